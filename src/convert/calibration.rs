//! Hand-eye calibration's files in the library's form and back: a capture
//! file's numbers checked into poses (each error naming the capture and
//! the field), a result as the report `calibrate --json` prints, and a
//! simulated set as a capture file and its truth.

use nalgebra::Isometry3;
use weldseam_proto::calibration as proto;

use crate::calibration::{Calibration, Mount, TargetCapture};
use crate::geometry::conventions::{AngleUnit, LengthUnit, PoseConvention, PoseError, RotationForm, UnknownConvention};
use crate::geometry::pose::{HandEyeError, hand_eye_from_rows};
use crate::sim::calibration::{CalibrationSet, CalibrationSpec};

/// A transform's 16 numbers, row-major.
pub fn rows(iso: &Isometry3<f64>) -> Vec<f64> {
    let h = iso.to_homogeneous();
    (0..16).map(|k| h[(k / 4, k % 4)]).collect()
}

/// Why a capture file's numbers are not a capture set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CaptureFileError {
    #[error("pose_convention: {0}")]
    Convention(#[from] UnknownConvention),
    #[error("{field}: {value:?} is not one of {expected}")]
    Unit { field: &'static str, value: String, expected: &'static str },
    #[error("capture {capture}: robot_pose: {source}")]
    Pose { capture: usize, source: PoseError },
    #[error("capture {capture}: camera_T_target needs 16 numbers (row-major 4x4, mm), got {got}")]
    TargetCount { capture: usize, got: usize },
    #[error("capture {capture}: camera_T_target: {source}")]
    Target { capture: usize, source: HandEyeError },
    #[error(
        "capture {capture}: give camera_T_target (a target pose) or cloud (a point cloud of spheres), and the same \
         kind in every capture"
    )]
    Kind { capture: usize },
    #[error("sphere clouds need sphere_radius_mm or sphere_radii_mm (not both)")]
    Radii,
    #[error("sphere_radius_mm and sphere_radii_mm are for clouds; the captures give camera_T_target")]
    RadiiWithoutClouds,
}

/// A capture set's observations, checked.
#[derive(Debug, Clone, PartialEq)]
pub enum Captures {
    Targets(Vec<TargetCapture>),
    /// Each capture's flange pose and cloud path (as written in the
    /// file), with the spheres' radii.
    Spheres {
        radii: Vec<f64>,
        /// The layout's distances, when the file gives them.
        distances: Option<Vec<f64>>,
        captures: Vec<(Isometry3<f64>, String)>,
    },
}

/// The convention a capture file's poses are written in; `default` when
/// it names none.
pub fn pose_convention(file: &proto::CaptureFile, default: PoseConvention) -> Result<PoseConvention, CaptureFileError> {
    let rotation = match &file.pose_convention {
        Some(name) => name.parse::<RotationForm>()?,
        None => default.rotation,
    };
    let unknown = |field, value: &str, expected| CaptureFileError::Unit { field, value: value.into(), expected };
    let length = match file.length_unit.as_deref() {
        None => default.length,
        Some(name) => LengthUnit::from_name(name).ok_or_else(|| unknown("length_unit", name, "mm, m"))?,
    };
    let angle = match file.angle_unit.as_deref() {
        None => default.angle,
        Some(name) => AngleUnit::from_name(name).ok_or_else(|| unknown("angle_unit", name, "deg, rad"))?,
    };
    Ok(PoseConvention { rotation, length, angle })
}

/// The capture file's captures in the library's form.
pub fn captures(file: &proto::CaptureFile, default: PoseConvention) -> Result<Captures, CaptureFileError> {
    let convention = pose_convention(file, default)?;
    let clouds = file.captures.first().is_some_and(|c| c.cloud.is_some());
    let radii = match (file.sphere_radius_mm, &file.sphere_radii_mm) {
        (Some(r), None) => Some(vec![r]),
        (None, Some(r)) => Some(r.clone()),
        (None, None) => None,
        (Some(_), Some(_)) => return Err(CaptureFileError::Radii),
    };
    let mut targets = Vec::new();
    let mut spheres = Vec::new();
    for (capture, c) in file.captures.iter().enumerate() {
        let base_t_end =
            convention.to_isometry(&c.robot_pose).map_err(|source| CaptureFileError::Pose { capture, source })?;
        match (&c.camera_t_target, &c.cloud, clouds) {
            (Some(m), None, false) => {
                let m: [f64; 16] =
                    m.as_slice().try_into().map_err(|_| CaptureFileError::TargetCount { capture, got: m.len() })?;
                let camera_t_target =
                    hand_eye_from_rows(&m).map_err(|source| CaptureFileError::Target { capture, source })?;
                targets.push(TargetCapture { base_t_end, camera_t_target });
            }
            (None, Some(path), true) => spheres.push((base_t_end, path.clone())),
            _ => return Err(CaptureFileError::Kind { capture }),
        }
    }
    match (clouds, radii) {
        (true, Some(radii)) => {
            Ok(Captures::Spheres { radii, distances: file.sphere_distances_mm.clone(), captures: spheres })
        }
        (true, None) => Err(CaptureFileError::Radii),
        (false, Some(_)) => Err(CaptureFileError::RadiiWithoutClouds),
        (false, None) => Ok(Captures::Targets(targets)),
    }
}

/// A calibration as `calibrate --json` prints it; `spheres_found` for
/// sphere sets.
pub fn report(c: &Calibration, spheres_found: Option<Vec<usize>>) -> proto::CalibrationReport {
    proto::CalibrationReport {
        hand_eye: rows(&c.hand_eye),
        solved_for: c.mount.solved_for().to_string(),
        method: c.method.clone(),
        residuals: c
            .residuals
            .iter()
            .map(|r| proto::CaptureResidual {
                capture: r.capture,
                translation_mm: r.translation_mm,
                rotation_deg: r.rotation_deg,
            })
            .collect(),
        outliers: c.outliers.clone(),
        warnings: c.warnings.clone(),
        expected_error_mm: c.expected_error_mm,
        working_distance_mm: c.working_distance_mm,
        translation_sigma_mm: c.translation_sigma_mm,
        rotation_sigma_deg: c.rotation_sigma_deg,
        hand_eye_with_outliers: c.hand_eye_with_outliers.as_ref().map(rows),
        closed_forms: c
            .closed_forms
            .iter()
            .map(|(name, x)| proto::ClosedFormResult {
                name: name.to_string(),
                hand_eye: rows(x),
                translation_from_result_mm: (x.translation.vector - c.hand_eye.translation.vector).norm(),
                rotation_from_result_deg: x.rotation.angle_to(&c.hand_eye.rotation).to_degrees(),
            })
            .collect(),
        spheres_found,
        spheres_unnamed: Vec::new(),
        spheres_named_by_layout: Vec::new(),
        spheres_named_by_prediction: Vec::new(),
        sphere_prediction_tolerance_mm: None,
        sphere_distances_mm: None,
        gate: proto::GateReport::default(),
    }
}

/// A simulated set's capture file: poses in `convention`, target poses
/// row-major, or the cloud paths given (one per capture).
pub fn capture_file(
    set: &CalibrationSet,
    convention: &PoseConvention,
    convention_name: &str,
    radii: Option<&[f64]>,
    cloud_paths: &[String],
) -> proto::CaptureFile {
    let captures = set
        .captures
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let robot_pose = convention.numbers(&c.base_t_end)[..convention.numbers_len()].to_vec();
            let camera_t_target = match &c.observation {
                crate::sim::calibration::SimObservation::TargetPose(b) => Some(rows(b)),
                crate::sim::calibration::SimObservation::Cloud(_) => None,
            };
            proto::Capture { robot_pose, camera_t_target, cloud: cloud_paths.get(i).cloned() }
        })
        .collect();
    proto::CaptureFile {
        pose_convention: Some(convention_name.to_string()),
        length_unit: Some(convention.length.name().to_string()),
        angle_unit: Some(convention.angle.name().to_string()),
        sphere_radius_mm: None,
        sphere_radii_mm: radii.map(<[f64]>::to_vec),
        sphere_distances_mm: None,
        captures,
    }
}

/// A simulated set's truth, with the spec that made it.
pub fn truth(set: &CalibrationSet, spec: &CalibrationSpec) -> proto::CalibrationTruth {
    proto::CalibrationTruth {
        hand_eye: rows(&set.hand_eye),
        mount: match spec.mount {
            Mount::EyeInHand => "eye_in_hand",
            Mount::EyeToHand => "eye_to_hand",
        }
        .into(),
        target_pose: rows(&set.target_pose),
        sphere_centres_mm: set.sphere_centres.iter().map(|c| [c.x, c.y, c.z]).collect(),
        wrong_pairing: spec.wrong_pairing,
        parallel_axes: spec.parallel_axes,
        small_rotations: spec.small_rotations,
        seed: spec.seed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose::EulerConvention;

    fn file(captures: Vec<proto::Capture>) -> proto::CaptureFile {
        proto::CaptureFile {
            pose_convention: Some("zyx".into()),
            length_unit: None,
            angle_unit: None,
            sphere_radius_mm: None,
            sphere_radii_mm: None,
            sphere_distances_mm: None,
            captures,
        }
    }

    fn identity() -> Vec<f64> {
        rows(&Isometry3::identity())
    }

    #[test]
    fn errors_name_the_capture_and_the_field() {
        let default = PoseConvention::config(EulerConvention::Zyx);
        let good = proto::Capture { robot_pose: vec![0.0; 6], camera_t_target: Some(identity()), cloud: None };
        let short = proto::Capture { robot_pose: vec![0.0; 5], ..good.clone() };
        let e = captures(&file(vec![good.clone(), short]), default).unwrap_err().to_string();
        assert!(e.starts_with("capture 1: robot_pose") && e.contains("6 numbers, got 5"), "{e}");
        let mut bad = identity();
        bad[1] = 0.5;
        let skewed = proto::Capture { camera_t_target: Some(bad), ..good.clone() };
        let e = captures(&file(vec![good.clone(), good.clone(), skewed]), default).unwrap_err().to_string();
        assert!(e.starts_with("capture 2: camera_T_target") && e.contains("orthonormal"), "{e}");
        let mixed = proto::Capture { camera_t_target: None, cloud: Some("a.pcd".into()), ..good.clone() };
        let e = captures(&file(vec![good.clone(), mixed]), default).unwrap_err().to_string();
        assert!(e.starts_with("capture 1: give camera_T_target"), "{e}");
        let mut f = file(vec![good.clone()]);
        f.pose_convention = Some("zxz".into());
        assert!(captures(&f, default).unwrap_err().to_string().contains("unknown pose convention"));
        f.pose_convention = None;
        f.length_unit = Some("inch".into());
        assert!(captures(&f, default).unwrap_err().to_string().starts_with("length_unit: \"inch\""));
    }

    #[test]
    fn a_ur_pose_in_metres_and_radians_is_read_as_such() {
        let mut f = file(vec![proto::Capture {
            robot_pose: vec![0.5, 0.0, 0.25, 0.0, 0.0, std::f64::consts::FRAC_PI_2],
            camera_t_target: Some(identity()),
            cloud: None,
        }]);
        f.pose_convention = Some("rotation_vector".into());
        f.length_unit = Some("m".into());
        f.angle_unit = Some("rad".into());
        let Captures::Targets(t) = captures(&f, PoseConvention::config(EulerConvention::Zyx)).unwrap() else {
            panic!("targets")
        };
        assert!((t[0].base_t_end.translation.vector.x - 500.0).abs() < 1e-9);
        assert!((t[0].base_t_end.rotation.angle().to_degrees() - 90.0).abs() < 1e-9);
    }
}
