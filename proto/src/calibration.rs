//! Hand-eye calibration's files: the capture set `weldseam calibrate`
//! reads (and `weldseam simulate --calibration` writes), the report
//! `calibrate --json` prints, and a simulated set's truth. Field names
//! only ever get added, never renamed.

use serde::{Deserialize, Serialize};

/// A capture set: the robot pose of each capture and what the camera saw
/// there, either a target's pose or a point cloud of calibration spheres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureFile {
    /// How `robot_pose` is written: any name of the pose conventions
    /// (`zyx`, `xyz`, `rotation_vector`, `kuka_abc`, `fanuc_wpr`,
    /// `intrinsic_zyx`, `quaternion_wxyz`, ...); the config's
    /// `robot.euler_convention` when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose_convention: Option<String>,
    /// `mm` (the default) or `m`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_unit: Option<String>,
    /// `deg` (the default) or `rad`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_unit: Option<String>,
    /// One sphere's radius, for clouds of one sphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere_radius_mm: Option<f64>,
    /// Several spheres' radii, for clouds of several.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere_radii_mm: Option<Vec<f64>>,
    /// The rig's layout: the distances between the sphere centres, mm, in
    /// the order (0,1), (0,2), ..., (0,n-1), (1,2), ...; found from the
    /// captures when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere_distances_mm: Option<Vec<f64>>,
    pub captures: Vec<Capture>,
}

/// One capture.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Capture {
    /// The flange pose the controller reported, in `pose_convention`.
    pub robot_pose: Vec<f64>,
    /// The target's pose in the camera frame, 16 numbers row-major, mm.
    #[serde(rename = "camera_T_target", default, skip_serializing_if = "Option::is_none")]
    pub camera_t_target: Option<Vec<f64>>,
    /// A point cloud file (PCD or PLY, camera frame), relative to the
    /// capture file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cloud: Option<String>,
}

/// What `weldseam calibrate --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationReport {
    /// `End_T_Camera` (or `Base_T_Camera` for a camera fixed in the
    /// cell), 16 numbers row-major, mm; computed without the outliers.
    pub hand_eye: Vec<f64>,
    /// `End_T_Camera` or `Base_T_Camera`.
    pub solved_for: String,
    pub method: String,
    /// Every capture's residual against `hand_eye`.
    pub residuals: Vec<CaptureResidual>,
    /// The captures left out of `hand_eye`.
    pub outliers: Vec<usize>,
    pub warnings: Vec<String>,
    /// One-sigma RMS error of a point at the working distance, mm; null
    /// when the captures do not determine the hand-eye.
    pub expected_error_mm: Option<f64>,
    pub working_distance_mm: f64,
    /// One-sigma uncertainty of `hand_eye`'s translation and rotation.
    pub translation_sigma_mm: Option<f64>,
    pub rotation_sigma_deg: Option<f64>,
    /// The result with every capture, when outliers were left out.
    pub hand_eye_with_outliers: Option<Vec<f64>>,
    /// The closed forms' answers on the captures used.
    pub closed_forms: Vec<ClosedFormResult>,
    /// Sphere sets: the spheres found in each capture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spheres_found: Option<Vec<usize>>,
    /// Sphere sets: the captures left out because their spheres could not
    /// be named, each with the reason.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spheres_unnamed: Vec<UnnamedCapture>,
    /// Sphere sets: the captures whose spheres the layout's distances (or
    /// their radii) named.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spheres_named_by_layout: Vec<usize>,
    /// Sphere sets: the captures the layout could not name whose spheres
    /// were named by where the first solution (on the captures the layout
    /// named) predicts each ball, within `sphere_prediction_tolerance_mm`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spheres_named_by_prediction: Vec<usize>,
    /// Sphere sets: the tolerance of that prediction, mm, when one was made.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere_prediction_tolerance_mm: Option<f64>,
    /// Sphere sets: the layout the spheres were named by (distances as in
    /// the capture file's `sphere_distances_mm`), when distances named them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere_distances_mm: Option<Vec<f64>>,
    /// The gate: whether the calibration may be written, and each limit it
    /// failed.
    #[serde(default)]
    pub gate: GateReport,
}

/// A sphere capture left out of the solution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnnamedCapture {
    pub capture: usize,
    pub reason: String,
}

/// The trust gate's verdict on a calibration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct GateReport {
    pub passed: bool,
    /// Each failed limit, as a sentence naming the figure and the limit.
    pub failures: Vec<String>,
    /// Written with `--force` despite the failures.
    pub forced: bool,
}

/// One capture's residual.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CaptureResidual {
    pub capture: usize,
    pub translation_mm: f64,
    /// Null for a sphere capture that saw fewer than three spheres.
    pub rotation_deg: Option<f64>,
}

/// A closed form's answer and how far the result is from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClosedFormResult {
    pub name: String,
    pub hand_eye: Vec<f64>,
    pub translation_from_result_mm: f64,
    pub rotation_from_result_deg: f64,
}

/// The truth of a simulated capture set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationTruth {
    /// The true `End_T_Camera` (or `Base_T_Camera`), 16 numbers row-major.
    pub hand_eye: Vec<f64>,
    /// `eye_in_hand` or `eye_to_hand`.
    pub mount: String,
    /// `Base_T_Target` (or `End_T_Target`), 16 numbers row-major.
    pub target_pose: Vec<f64>,
    /// The spheres' centres in the target frame, mm.
    pub sphere_centres_mm: Vec<[f64; 3]>,
    /// The capture whose observation belongs to another pose.
    pub wrong_pairing: Option<usize>,
    pub parallel_axes: bool,
    pub small_rotations: bool,
    pub seed: u64,
}
