//! Configuration: parsed once from TOML, validated once, then carried as a
//! built [`Config`] whose values are known to be usable. Every error names
//! the key at fault.
//!
//! Defaults are the paper's camera (Table 1) and parameters wherever the
//! paper gives one (R = 1 mm, μ = 0.5, 2 mm clustering, 1 mm RANSAC), and
//! measured values for the robust method's own settings.

mod file;
mod text_link;

use std::net::{IpAddr, SocketAddr};
use std::path::Path;
use std::time::Duration;

use nalgebra::Isometry3;
use serde::{Deserialize, Deserializer};

use crate::calibration::gate::{CalibrationRecord, GateLimits};
use crate::camera::{CameraModel, Distortion, Intrinsics};
use crate::geometry::pose::{EulerConvention, HandEyeError, hand_eye_from_rows};
use crate::pipeline::CloudFrame;
use crate::pipeline::roi::Roi;

pub use file::ConfigFile;
pub use text_link::TextLinkConfig;

/// Which variant of the pipeline runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// The paper's method made robust (the default).
    #[default]
    Robust,
    /// The paper's method exactly as written, for comparison.
    Paper,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Robust => "robust",
            Method::Paper => "paper",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "robust" => Some(Method::Robust),
            "paper" => Some(Method::Paper),
            _ => None,
        }
    }
}

/// Reads `pipeline.method` by name; the error names the key, as the
/// range checks' do.
fn method_by_name<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Method, D::Error> {
    let name = String::deserialize(deserializer)?;
    Method::from_name(&name).ok_or_else(|| {
        serde::de::Error::custom(format!(
            "config key `pipeline.method`: unknown method {name:?}; expected \"robust\" or \"paper\""
        ))
    })
}

/// Where the neighbour count a full plane gives comes from, against which
/// the plane and edge criteria measure each point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointDensity {
    /// The camera model for organized frames (a raw frame of the camera),
    /// the cloud's own measured spacing for any other cloud.
    #[default]
    Auto,
    /// Always the camera model (the paper's Eq. 4 to 14): for comparison.
    Camera,
    /// Always the cloud's measured spacing, organized frames too.
    Measured,
}

/// The frame a config's region of interest is given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoiFrame {
    /// The camera's optical frame.
    #[default]
    Camera,
    /// The robot base frame, through each request's pose and hand-eye.
    Base,
}

impl RoiFrame {
    pub fn cloud_frame(self) -> CloudFrame {
        match self {
            RoiFrame::Camera => CloudFrame::Camera,
            RoiFrame::Base => CloudFrame::Base,
        }
    }
}

/// Parameters of the seam pipeline's stages: the `[pipeline]` section.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineParams {
    #[serde(deserialize_with = "method_by_name")]
    pub method: Method,
    /// Neighbour search radius R, mm (paper: 1). For a cloud whose density
    /// is measured, the radius at which a full plane holds about 50 points
    /// when that is larger.
    pub neighbour_radius_mm: f64,
    /// Where the full-plane neighbour count comes from.
    pub point_density: PointDensity,
    /// Robust plane criterion: the least fraction of the neighbours a full
    /// plane would give at this point, tilt and pixel grid included.
    pub plane_min_neighbour_ratio: f64,
    /// Robust plane criterion: the largest angle between a point's local
    /// normal and the workpiece's dominant normal; rejects bevel and side
    /// faces, which the neighbour count cannot tell from plates.
    pub plane_max_normal_angle_deg: f64,
    /// Euclidean clustering tolerance, mm, for clouds without a pixel grid
    /// (organized clouds are clustered on the grid, which keeps sub-mm gaps).
    pub cluster_tolerance_mm: f64,
    /// Clusters smaller than this are noise, not planes.
    pub min_plane_area_mm2: f64,
    /// Two butt plates are coplanar when their planes' offsets differ by
    /// less than this.
    pub coplanar_tolerance_mm: f64,
    /// The range of plate thicknesses a lap step may have.
    pub lap_step_min_mm: f64,
    pub lap_step_max_mm: f64,
    /// A tee's web: its top lies more than `lap_step_max_mm` and at most
    /// this far over the flange, mm ...
    pub tee_web_height_max_mm: f64,
    /// ... and is at most this wide, mm (the web's thickness; a plate
    /// lying over the table is far wider).
    pub tee_web_thickness_max_mm: f64,
    /// Robust edge criterion: a plane point is an edge point when it has at
    /// most this fraction of its full-plane neighbour count (paper: 0.5).
    pub edge_max_neighbour_ratio: f64,
    /// RANSAC inlier distance, mm (paper: 1).
    pub ransac_distance_mm: f64,
    pub ransac_iterations: u32,
    /// A line needs at least this many inliers to count as an edge.
    pub ransac_min_line_points: u32,
    /// Stop segmenting when fewer edge points remain (section 3.4.2).
    pub ransac_min_remaining_points: u32,
    pub ransac_max_lines: u32,
    /// Seed of the RANSAC random generator, so results are reproducible.
    pub ransac_seed: u64,
    /// The two weld edges must be parallel within this angle.
    pub max_edge_angle_deg: f64,
    /// Half-width of the band around a coarse weld edge searched for the
    /// plate's true boundary, mm.
    pub boundary_band_mm: f64,
    /// A point lies on a plate's plane when within this distance of it.
    pub on_plane_tolerance_mm: f64,
    /// Degree n of the least-squares polynomial (Eq. 17); 1 for straight seams.
    pub fit_degree: u32,
    /// Boundary samples further than this many sigmas from the fit are
    /// dropped and the fit repeated (sigma: the median residual taken as a
    /// standard deviation, so a run of cut-short samples cannot widen it).
    pub fit_trim_sigma: f64,
    /// Region of interest of every plan whose request names none:
    /// `[xmin, ymin, zmin, xmax, ymax, zmax]`, mm; empty for the whole cloud.
    pub roi: Vec<f64>,
    /// The frame `roi` is given in.
    pub roi_frame: RoiFrame,
}

impl Default for PipelineParams {
    fn default() -> Self {
        PipelineParams {
            method: Method::Robust,
            neighbour_radius_mm: 1.0,
            point_density: PointDensity::Auto,
            plane_min_neighbour_ratio: 0.8,
            plane_max_normal_angle_deg: 20.0,
            cluster_tolerance_mm: 1.0,
            min_plane_area_mm2: 400.0,
            coplanar_tolerance_mm: 3.0,
            lap_step_min_mm: 1.0,
            lap_step_max_mm: 30.0,
            tee_web_height_max_mm: 250.0,
            tee_web_thickness_max_mm: 30.0,
            edge_max_neighbour_ratio: 0.75,
            ransac_distance_mm: 1.0,
            ransac_iterations: 400,
            ransac_min_line_points: 40,
            ransac_min_remaining_points: 40,
            ransac_max_lines: 12,
            ransac_seed: 42,
            max_edge_angle_deg: 10.0,
            boundary_band_mm: 3.0,
            on_plane_tolerance_mm: 0.4,
            fit_degree: 1,
            fit_trim_sigma: 3.0,
            roi: Vec::new(),
            roi_frame: RoiFrame::Camera,
        }
    }
}

/// The paper's own numbers where they differ from the robust method's:
/// the `[paper]` section.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PaperParams {
    /// μ of the plane edge criterion (Eq. 15).
    pub edge_ratio: f64,
    /// Euclidean clustering threshold (section 3.3).
    pub cluster_tolerance_mm: f64,
}

impl Default for PaperParams {
    fn default() -> Self {
        PaperParams { edge_ratio: 0.5, cluster_tolerance_mm: 2.0 }
    }
}

/// Sampling and torch orientation of the trajectory: the `[trajectory]`
/// section, and what a request's own step and angles override.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrajectoryParams {
    /// Distance between waypoints along the seam, mm.
    pub step_mm: f64,
    /// Torch tilt about tool x, the travel direction, degrees.
    pub work_angle_deg: f64,
    /// Torch tilt about tool y, across the seam in the plate's plane
    /// (push positive), degrees.
    pub travel_angle_deg: f64,
    /// Tee joints: the torch axis's angle from the flange, degrees, in the
    /// plane across the root, leaning towards the web (45: the bisector of
    /// a square tee's corner). `work_angle_deg` tilts it further, as for
    /// every joint; a request's work angle overrides that, not this.
    pub fillet_work_angle_deg: f64,
}

impl Default for TrajectoryParams {
    fn default() -> Self {
        TrajectoryParams { step_mm: 5.0, work_angle_deg: 0.0, travel_angle_deg: 0.0, fillet_work_angle_deg: 45.0 }
    }
}

/// The limits a planned seam must meet (issue 12): the `[quality]` section.
/// A seam that breaks one is refused with the figure, its value and the
/// limit, unless the gate is named in `warn_only`; see
/// [`crate::pipeline::quality`] for how each figure is measured.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QualityParams {
    /// The largest RMS residual of a weld edge's fit, in point spacings at
    /// the seam (the boundary is sampled to about a third of one).
    pub max_edge_fit_rms_spacings: f64,
    /// The largest fraction of a weld edge's boundary samples that may lie
    /// beyond its fitted line towards the other plate (by more than the
    /// fit's trimming limit). A plate's points stop at its edge: beyond the
    /// line lies the edge itself where a dropout or a shadow cut the rest
    /// of it short.
    pub max_edge_samples_beyond: f64,
    /// The largest step between two runs of a weld edge's samples, each
    /// along a tenth of the edge at least, in point spacings at the seam:
    /// a plate's edge is one line, and two are an edge cut short along one
    /// of them. Read on the edges that place the weld: both of a butt
    /// joint, a lap's upper one.
    pub max_edge_step_spacings: f64,
    /// The least fraction of the seam each weld edge must be seen along.
    pub min_edge_coverage: f64,
    /// The least fraction of the visible joint (where both plates are seen
    /// beside it) the seam must span.
    pub min_joint_coverage: f64,
    /// The longest stretch, mm, beyond either end of the seam along which
    /// both plates are still seen beside the weld (issue 11: the seam
    /// covers the visible joint to within 2 mm of where both plates'
    /// evidence ends). Longer, an edge was lost there while its plate
    /// goes on: a streak or spatter over the edge. For a fillet root, how
    /// far the web's top and the flange up to the root may be seen past
    /// its ends, where its face is not seen down to the flange.
    pub max_joint_beyond_seam_mm: f64,
    /// Butt joints: the largest high-low misalignment of the plates, mm,
    /// and as a fraction of their thickness t (ISO 5817 quality level C:
    /// 0.15 t, at most 4 mm); the smaller limit applies. The camera sees
    /// only a ceiling on t, the depth to the surface the plates rest on,
    /// so the fraction applies to that when it is seen.
    pub max_misalignment_mm: f64,
    pub max_misalignment_of_thickness: f64,
    /// I-butt joints: the widest root gap, mm.
    pub max_gap_mm: f64,
    /// I-butt joints: the narrowest gap, at its widest along the seam, in
    /// point spacings at the seam. A gap under one spacing is below what
    /// the cloud resolves: the plates may touch, and two plates elsewhere
    /// with a gap as narrow are seen as one.
    pub min_gap_spacings: f64,
    /// The largest angle between the two plates' planes, degrees.
    pub max_plate_angle_deg: f64,
    /// Tee joints: how far the web's side face may lie off square to the
    /// flange, degrees (the `plate_angle` gate of a fillet root).
    pub max_web_tilt_deg: f64,
    /// The largest estimated position uncertainty (one sigma) of the seam,
    /// across it or along the normal, mm.
    pub max_position_uncertainty_mm: f64,
    /// V-butt joints: the largest difference between the groove depth a
    /// request gives and the one measured, mm (the weld lies at the depth
    /// given, Eq. 32).
    pub max_groove_depth_difference_mm: f64,
    /// Gates (by name) whose failure is a warning on the seam, not a
    /// refusal.
    pub warn_only: Vec<String>,
}

impl Default for QualityParams {
    fn default() -> Self {
        QualityParams {
            max_edge_fit_rms_spacings: 2.0,
            max_edge_samples_beyond: 0.1,
            max_edge_step_spacings: 2.0,
            min_edge_coverage: 0.5,
            min_joint_coverage: 0.8,
            max_joint_beyond_seam_mm: 2.0,
            max_misalignment_mm: 4.0,
            max_misalignment_of_thickness: 0.15,
            max_gap_mm: 4.0,
            min_gap_spacings: 1.0,
            max_plate_angle_deg: 5.0,
            max_web_tilt_deg: 10.0,
            max_position_uncertainty_mm: 0.5,
            max_groove_depth_difference_mm: 1.0,
            warn_only: Vec::new(),
        }
    }
}

impl QualityParams {
    /// Whether a failure of `gate` only warns.
    pub fn warns_only(&self, gate: crate::pipeline::quality::Gate) -> bool {
        self.warn_only.iter().any(|name| name == gate.name())
    }

    /// Checks the `[quality]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        use crate::pipeline::quality::Gate;
        in_range("quality.max_edge_fit_rms_spacings", self.max_edge_fit_rms_spacings, 0.05, 100.0)?;
        in_range("quality.max_edge_samples_beyond", self.max_edge_samples_beyond, 0.0, 1.0)?;
        in_range("quality.max_edge_step_spacings", self.max_edge_step_spacings, 0.5, 100.0)?;
        in_range("quality.min_edge_coverage", self.min_edge_coverage, 0.0, 1.0)?;
        in_range("quality.min_joint_coverage", self.min_joint_coverage, 0.0, 1.0)?;
        in_range("quality.max_joint_beyond_seam_mm", self.max_joint_beyond_seam_mm, 0.0, 1000.0)?;
        in_range("quality.max_misalignment_mm", self.max_misalignment_mm, 0.0, 50.0)?;
        in_range("quality.max_misalignment_of_thickness", self.max_misalignment_of_thickness, 0.0, 1.0)?;
        in_range("quality.max_gap_mm", self.max_gap_mm, 0.0, 50.0)?;
        in_range("quality.min_gap_spacings", self.min_gap_spacings, 0.0, 10.0)?;
        in_range("quality.max_plate_angle_deg", self.max_plate_angle_deg, 0.0, 90.0)?;
        in_range("quality.max_web_tilt_deg", self.max_web_tilt_deg, 0.0, 80.0)?;
        in_range("quality.max_position_uncertainty_mm", self.max_position_uncertainty_mm, 0.001, 100.0)?;
        in_range("quality.max_groove_depth_difference_mm", self.max_groove_depth_difference_mm, 0.0, 100.0)?;
        for name in &self.warn_only {
            check("quality.warn_only", Gate::from_name(name).is_some_and(Gate::can_warn), || {
                let names: Vec<&str> = Gate::ALL.iter().filter(|g| g.can_warn()).map(|g| g.name()).collect();
                format!("{name:?} is not a gate that can warn; those are {}", names.join(", "))
            })?;
        }
        Ok(())
    }
}

/// The pictures and figures of the daemon's last plans: the `[debug]`
/// section. Each plan's set (what `weldseam plan --debug DIR` writes: the
/// camera view, the cross-sections and `trace.json`) goes into a directory
/// of its own under `dir`, the oldest beyond `keep_last` deleted. An empty
/// `dir` keeps none.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DebugParams {
    pub dir: String,
    pub keep_last: u32,
}

/// How many plans' sets the daemon keeps by default: the last few minutes
/// of a busy cell, a few megabytes each.
pub const DEFAULT_DEBUG_KEEP_LAST: u32 = 20;

/// `server.plan_timeout_ms` unless configured: a 1920 x 1200 frame plans
/// in about 130 ms and under 300 ms under load (docs/PERFORMANCE.md), a
/// frame of several workpieces in a few times that, so a plan still
/// running after 5 s is stuck on a frame no camera's view gives.
pub const DEFAULT_PLAN_TIMEOUT_MS: u64 = 5_000;

/// The most sets `debug.keep_last` may ask for: about a gigabyte of
/// pictures, beyond which the directory is an archive, not a debug aid.
pub const MAX_DEBUG_KEEP_LAST: u32 = 1000;

impl Default for DebugParams {
    fn default() -> Self {
        DebugParams { dir: String::new(), keep_last: DEFAULT_DEBUG_KEEP_LAST }
    }
}

impl DebugParams {
    /// Where the sets go, when the daemon keeps them.
    pub fn directory(&self) -> Option<&Path> {
        (!self.dir.is_empty()).then(|| Path::new(&self.dir))
    }

    /// Checks the `[debug]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        count_in("debug.keep_last", self.keep_last.into(), 1, MAX_DEBUG_KEEP_LAST.into())?;
        check("debug.dir", !self.dir.contains('\0'), || "must not contain a NUL character".into())
    }
}

/// The cell daemon's network and scheduling settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// Where the camera (or its bridge) connects.
    pub camera_listen: SocketAddr,
    /// Where the robot controller connects.
    pub controller_listen: SocketAddr,
    /// Peers allowed on each link; empty allows any.
    pub camera_allow: Vec<IpAddr>,
    pub controller_allow: Vec<IpAddr>,
    /// Connections served at once per link; more wait to be accepted.
    pub max_camera_connections: usize,
    pub max_controller_connections: usize,
    /// A peer that sends nothing for this long in the middle of a message
    /// is dropped.
    pub stall_timeout: Duration,
    /// A connection must complete its Hello this soon after it is accepted.
    pub hello_timeout: Duration,
    /// Every message must arrive whole within this time from its first
    /// byte, plus its length at [`Self::min_transfer_bytes_per_s`]; a peer
    /// that trickles bytes is dropped even though it is never silent.
    pub message_timeout: Duration,
    /// The slowest transfer rate a large message (a frame) is allowed.
    pub min_transfer_bytes_per_s: u64,
    /// Connections per link that have not yet said Hello; a further one
    /// closes the oldest of the address that holds the most.
    pub max_pending_connections: usize,
    /// Connections from one address per link that have not yet said Hello;
    /// a further one closes that address's oldest.
    pub max_pending_per_address: usize,
    /// Where the Prometheus metrics are served over HTTP; None is off.
    pub metrics_listen: Option<SocketAddr>,
    /// The largest frame payload accepted, bytes.
    pub max_frame_bytes: u64,
    /// Plan jobs queued or running at once; a request beyond gets Busy.
    pub plan_queue_depth: usize,
    /// Threads of the pipeline's pool; 0 uses every core.
    pub pipeline_threads: usize,
    /// How long a request waits for a fresh frame unless it says otherwise.
    pub fresh_frame_timeout: Duration,
    /// How long shutdown waits for plans in flight.
    pub shutdown_grace: Duration,
    /// The longest one plan may run; a plan still running then is stopped
    /// and refused (`plan_timeout`), and the next plan starts.
    pub plan_timeout: Duration,
    /// Recent frames kept for requests that name a frame id.
    pub frame_history: usize,
    /// The most bytes of points the frame history holds; the oldest
    /// frames go first when a new one would exceed it.
    pub frame_history_bytes: u64,
    /// How far a frame's capture time may lie outside the fresh window
    /// (before its request, or after its upload began) on the daemon's
    /// clock: the clock skew allowed between camera and daemon.
    pub capture_time_tolerance: Duration,
    /// The longest frame wait a request may ask for; longer is refused.
    pub max_request_timeout: Duration,
    /// Requests one controller connection may have waiting or running.
    pub max_requests_per_connection: usize,
    /// After this long without frames or plans the daemon hands freed
    /// memory back to the system; zero never does.
    pub idle_trim: Duration,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            camera_listen: SocketAddr::from(([127, 0, 0, 1], 7301)),
            controller_listen: SocketAddr::from(([127, 0, 0, 1], 7302)),
            camera_allow: Vec::new(),
            controller_allow: Vec::new(),
            max_camera_connections: 2,
            max_controller_connections: 8,
            stall_timeout: Duration::from_millis(5_000),
            hello_timeout: Duration::from_millis(2_000),
            message_timeout: Duration::from_millis(10_000),
            min_transfer_bytes_per_s: 1 << 20,
            max_pending_connections: 64,
            max_pending_per_address: 4,
            metrics_listen: None,
            max_frame_bytes: weldseam_proto::frame::DEFAULT_MAX_FRAME_BYTES,
            plan_queue_depth: 4,
            pipeline_threads: 0,
            fresh_frame_timeout: Duration::from_millis(5_000),
            shutdown_grace: Duration::from_millis(10_000),
            plan_timeout: Duration::from_millis(DEFAULT_PLAN_TIMEOUT_MS),
            frame_history: 8,
            frame_history_bytes: 128 << 20,
            capture_time_tolerance: Duration::from_millis(200),
            max_request_timeout: Duration::from_millis(30_000),
            max_requests_per_connection: 2,
            idle_trim: Duration::from_millis(10_000),
        }
    }
}

/// What a pose or a hand-eye matrix may plausibly be in this cell. A
/// trajectory is a command to a robot: numbers beyond these are a fault
/// upstream (a unit mix-up, a corrupt message), never a place to weld.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotLimits {
    /// The farthest a flange pose or a waypoint may be from the base
    /// frame's origin, mm: the robot's reach (plus any track or gantry).
    pub max_reach_mm: f64,
    /// The longest translation of `End_T_Camera`, mm: how far the camera
    /// can sit from the flange on its bracket.
    pub max_hand_eye_translation_mm: f64,
}

impl Default for RobotLimits {
    fn default() -> Self {
        RobotLimits { max_reach_mm: 3_500.0, max_hand_eye_translation_mm: 1_000.0 }
    }
}

/// The largest magnitude of a pose angle, degrees. Controllers report
/// angles within one turn (Euler angles within ±180°, a rotation vector
/// within 180°); a value beyond two turns is a unit or wiring fault.
pub const MAX_POSE_ANGLE_DEG: f64 = 720.0;

/// The waypoint spacing's range, mm, in the config and in requests: below
/// 0.1 mm the samples are finer than any camera resolves; above a metre
/// a seam gets no interior waypoint at all.
pub const MIN_STEP_MM: f64 = 0.1;
pub const MAX_STEP_MM: f64 = 1_000.0;

/// The largest work or travel angle, degrees, in the config and in
/// requests: beyond it the torch would lie nearly flat on the plate.
pub const MAX_TORCH_ANGLE_DEG: f64 = 80.0;

/// The least angle of a fillet torch from the flange or the web, degrees:
/// nearer either it would lie along that face.
pub const MIN_FILLET_WORK_ANGLE_DEG: f64 = 10.0;

/// The validated configuration.
#[derive(Debug, Clone)]
pub struct Config {
    pub camera: CameraModel,
    pub euler: EulerConvention,
    /// `End_T_Camera`, validated rigid.
    pub hand_eye: Isometry3<f64>,
    pub robot_limits: RobotLimits,
    pub pipeline: PipelineParams,
    pub paper: PaperParams,
    pub trajectory: TrajectoryParams,
    pub quality: QualityParams,
    pub server: ServerConfig,
    /// The text controller link robot programs speak directly.
    pub text_link: TextLinkConfig,
    pub debug: DebugParams,
    /// The limits `weldseam calibrate` holds a calibration to.
    pub calibration: GateLimits,
    /// The record of the calibration that gave `hand_eye`, when the file
    /// has one.
    pub hand_eye_calibration: Option<CalibrationRecord>,
}

impl Default for Config {
    fn default() -> Self {
        Config::from_file(ConfigFile::default()).expect("the built-in defaults are valid")
    }
}

/// Why a configuration was refused. Every variant names the key.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read (the I/O error is part of the message).
    #[error("cannot read config {path}: {cause}")]
    Io { path: String, cause: std::io::Error },
    /// The TOML is malformed, has an unknown key or a value of the wrong type.
    #[error("config {path}: {message}")]
    Parse { path: String, message: String },
    /// A value is out of its allowed range.
    #[error("config key `{key}`: {message}")]
    Invalid { key: &'static str, message: String },
    /// The hand-eye matrix is not a rigid transform. The cause is part of
    /// the message, not a separate source, so it is printed once.
    #[error("config key `robot.hand_eye`: {0}")]
    HandEye(HandEyeError),
}

/// The widest sensor side a camera may have, pixels.
const MAX_SENSOR_PX: u32 = 32_768;
/// The shortest field-of-view size or distance, mm.
const MIN_LENGTH_MM: f64 = 1e-3;
/// The longest camera length (field of view, its distance, depth), mm:
/// 100 m, far beyond what a cell's camera sees.
const MAX_CAMERA_MM: f64 = 100_000.0;

fn check(key: &'static str, ok: bool, message: impl FnOnce() -> String) -> Result<(), ConfigError> {
    if ok { Ok(()) } else { Err(ConfigError::Invalid { key, message: message() }) }
}

fn in_range(key: &'static str, v: f64, lo: f64, hi: f64) -> Result<(), ConfigError> {
    check(key, v.is_finite() && (lo..=hi).contains(&v), || format!("must lie in [{lo}, {hi}], got {v}"))
}

fn count_in(key: &'static str, v: u64, lo: u64, hi: u64) -> Result<(), ConfigError> {
    check(key, (lo..=hi).contains(&v), || format!("must lie in [{lo}, {hi}], got {v}"))
}

impl Config {
    /// Reads and validates a TOML config file.
    pub fn load(path: &Path) -> Result<Config, ConfigError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|cause| ConfigError::Io { path: shown.clone(), cause })?;
        Config::parse(&text, &shown)
    }

    /// Reads and validates the config file at `path`, or gives the
    /// built-in defaults when there is none.
    pub fn load_or_default(path: Option<&Path>) -> Result<Config, ConfigError> {
        path.map_or_else(|| Ok(Config::default()), Config::load)
    }

    /// Parses and validates TOML text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Config, ConfigError> {
        let file: ConfigFile = toml::from_str(text)
            .map_err(|e| ConfigError::Parse { path: origin.to_string(), message: e.to_string() })?;
        Config::from_file(file)
    }

    /// Validates the schema's values into a built config.
    pub fn from_file(f: ConfigFile) -> Result<Config, ConfigError> {
        let camera = f.camera.validate()?;
        let (euler, hand_eye, robot_limits) = f.robot.validate()?;
        f.pipeline.validate()?;
        f.paper.validate()?;
        f.trajectory.validate()?;
        f.quality.validate()?;
        let server = f.server.validate()?;
        let text_link = f.text_link.validate()?;
        f.debug.validate()?;
        validate_gate(&f.calibration)?;
        if let Some(record) = &f.robot.hand_eye_calibration {
            validate_record(record)?;
        }
        Ok(Config {
            camera,
            euler,
            hand_eye,
            robot_limits,
            pipeline: f.pipeline,
            paper: f.paper,
            trajectory: f.trajectory,
            quality: f.quality,
            server,
            text_link,
            debug: f.debug,
            calibration: f.calibration,
            hand_eye_calibration: f.robot.hand_eye_calibration,
        })
    }
}

/// Checks the `[calibration]` section.
fn validate_gate(g: &GateLimits) -> Result<(), ConfigError> {
    in_range("calibration.max_expected_error_mm", g.max_expected_error_mm, 0.001, 100.0)?;
    in_range("calibration.max_translation_sigma_mm", g.max_translation_sigma_mm, 0.001, 100.0)?;
    in_range("calibration.max_rotation_sigma_deg", g.max_rotation_sigma_deg, 0.0001, 10.0)?;
    in_range("calibration.max_residual_mm", g.max_residual_mm, 0.001, 100.0)?;
    in_range("calibration.max_residual_deg", g.max_residual_deg, 0.0001, 10.0)?;
    in_range("calibration.min_rotation_deg", g.min_rotation_deg, 0.0, 180.0)?;
    in_range("calibration.min_axis_spread_deg", g.min_axis_spread_deg, 0.0, 45.0)
}

/// Checks `robot.hand_eye_calibration`: its figures are numbers a
/// calibration can give.
fn validate_record(r: &CalibrationRecord) -> Result<(), ConfigError> {
    let figures = [r.expected_error_mm, r.translation_sigma_mm, r.rotation_sigma_deg, r.worst_residual_deg];
    let plausible = |v: f64| v.is_finite() && v >= 0.0;
    check("robot.hand_eye_calibration", figures.iter().flatten().all(|v| plausible(*v)), || {
        "its figures must be finite and not negative".to_string()
    })?;
    check(
        "robot.hand_eye_calibration",
        plausible(r.worst_residual_mm) && plausible(r.working_distance_mm) && r.captures_used <= r.captures,
        || "its residual and working distance must be finite and not negative, captures_used at most captures".into(),
    )?;
    check("robot.hand_eye_calibration", r.passed == r.failures.is_empty(), || {
        "passed must be true exactly when failures is empty".to_string()
    })
}

// Every number has a floor and a ceiling: a value outside them is a typo
// or a unit mix-up, and an unbounded one (a billion RANSAC iterations, a
// tolerance of 1e-30 mm) would hang or silently break the planner rather
// than fail at start.

/// How far the configured intrinsics and field of view may disagree, as a
/// fraction of the focal length, when both are given: the two forms are
/// the same numbers written twice, so anything beyond rounding in the
/// datasheet (a few parts in ten thousand) is a typo or two cameras' values.
const INTRINSICS_AGREEMENT: f64 = 1e-3;

/// The largest lens distortion coefficient, in magnitude: measurement
/// cameras' are below 1, fisheyes' a few; beyond 10 the model is not
/// Brown-Conrady's any more.
const MAX_DISTORTION: f64 = 10.0;

impl file::CameraSection {
    /// Checks the `[camera]` section and builds the camera model: the field
    /// of view or the intrinsics (all four), or both when they agree.
    pub fn validate(&self) -> Result<CameraModel, ConfigError> {
        let c = self;
        // A sensor of 32768 pixels a side is beyond any camera; the tile
        // keys of the full-plane counts hold 16-bit tile indices.
        for (key, px) in [("camera.width_px", c.width_px), ("camera.height_px", c.height_px)] {
            check(key, (1..=MAX_SENSOR_PX).contains(&px), || format!("must lie in [1, {MAX_SENSOR_PX}], got {px}"))?;
        }
        in_range("camera.fov_distance_mm", c.fov_distance_mm, MIN_LENGTH_MM, MAX_CAMERA_MM)?;
        let (w, h) = (f64::from(c.width_px), f64::from(c.height_px));
        // Focal lengths from a tenth of the sensor (a 157° view) to a
        // thousand times it; the principal point within a sensor's width
        // of the sensor.
        let given = [("camera.fx", c.fx), ("camera.fy", c.fy), ("camera.cx", c.cx), ("camera.cy", c.cy)];
        let intrinsics = match (c.fx, c.fy, c.cx, c.cy) {
            (Some(fx), Some(fy), Some(cx), Some(cy)) => {
                in_range("camera.fx", fx, 0.1 * w, 1000.0 * w)?;
                in_range("camera.fy", fy, 0.1 * h, 1000.0 * h)?;
                in_range("camera.cx", cx, -w, 2.0 * w)?;
                in_range("camera.cy", cy, -h, 2.0 * h)?;
                Some(Intrinsics { fx, fy, cx, cy })
            }
            (None, None, None, None) => None,
            _ => {
                let (set, unset): (Vec<&(&'static str, Option<f64>)>, Vec<_>) =
                    given.iter().partition(|(_, v)| v.is_some());
                let names = |keys: &[&(&'static str, Option<f64>)]| {
                    keys.iter().map(|(k, _)| k.trim_start_matches("camera.")).collect::<Vec<_>>().join(", ")
                };
                return Err(ConfigError::Invalid {
                    key: unset[0].0,
                    message: format!(
                        "the intrinsics need all of fx, fy, cx and cy; {} given but not {}",
                        names(&set),
                        names(&unset)
                    ),
                });
            }
        };
        // Each side of the field of view: as given (and then held to agree
        // with the intrinsics, if any), else implied by the intrinsics,
        // else the paper's.
        let paper = CameraModel::default();
        let sides = [
            ("camera.fov_width_mm", c.fov_width_mm, w, intrinsics.map(|i| i.fx), paper.fov_width_mm),
            ("camera.fov_height_mm", c.fov_height_mm, h, intrinsics.map(|i| i.fy), paper.fov_height_mm),
        ];
        let mut fov = [0.0; 2];
        for (side, (key, given, px, focal, default)) in fov.iter_mut().zip(sides) {
            *side = match (given, focal) {
                (Some(mm), focal) => {
                    in_range(key, mm, MIN_LENGTH_MM, MAX_CAMERA_MM)?;
                    if let Some(f) = focal {
                        let implied = px * c.fov_distance_mm / mm;
                        let focal_key = if key.ends_with("width_mm") { "camera.fx" } else { "camera.fy" };
                        check(focal_key, ((implied - f) / f).abs() <= INTRINSICS_AGREEMENT, || {
                            format!(
                                "{f} px disagrees with {key} ({mm} mm), which implies {implied:.3} px; \
                                 must agree within {}%: give the intrinsics or the field of view, not both",
                                INTRINSICS_AGREEMENT * 100.0
                            )
                        })?;
                    }
                    mm
                }
                (None, Some(f)) => px * c.fov_distance_mm / f,
                (None, None) => default,
            };
        }
        let [fov_width_mm, fov_height_mm] = fov;
        in_range("camera.baseline_mm", c.baseline_mm, 0.0, 10_000.0)?;
        in_range("camera.nominal_accuracy_mm", c.nominal_accuracy_mm, 1e-6, 100.0)?;
        in_range("camera.min_depth_mm", c.min_depth_mm, 1.0, c.fov_distance_mm)?;
        in_range("camera.max_depth_mm", c.max_depth_mm, c.fov_distance_mm, MAX_CAMERA_MM)?;
        // Up to 89°: the off-axis limit bounds every coordinate by a
        // multiple of the depth, which a limit of 90° would not.
        in_range("camera.max_off_axis_deg", c.max_off_axis_deg, 1.0, 89.0)?;
        in_range("camera.fov_margin_px", c.fov_margin_px, 0.0, f64::from(MAX_SENSOR_PX))?;
        for (key, k) in
            [("camera.k1", c.k1), ("camera.k2", c.k2), ("camera.p1", c.p1), ("camera.p2", c.p2), ("camera.k3", c.k3)]
        {
            in_range(key, k, -MAX_DISTORTION, MAX_DISTORTION)?;
        }
        Ok(CameraModel {
            width_px: c.width_px,
            height_px: c.height_px,
            fov_width_mm,
            fov_height_mm,
            fov_distance_mm: c.fov_distance_mm,
            baseline_mm: c.baseline_mm,
            nominal_accuracy_mm: c.nominal_accuracy_mm,
            min_depth_mm: c.min_depth_mm,
            max_depth_mm: c.max_depth_mm,
            max_off_axis_deg: c.max_off_axis_deg,
            fov_margin_px: c.fov_margin_px,
            intrinsics,
            distortion: Distortion { k1: c.k1, k2: c.k2, p1: c.p1, p2: c.p2, k3: c.k3 },
        })
    }
}

impl file::RobotSection {
    /// Checks the `[robot]` section and builds its typed values.
    pub fn validate(&self) -> Result<(EulerConvention, Isometry3<f64>, RobotLimits), ConfigError> {
        let r = self;
        let euler = EulerConvention::from_name(&r.euler_convention).ok_or_else(|| ConfigError::Invalid {
            key: "robot.euler_convention",
            message: format!(
                "unknown convention {:?}; expected one of {:?}",
                r.euler_convention,
                EulerConvention::NAMES
            ),
        })?;
        in_range("robot.max_reach_mm", r.max_reach_mm, 100.0, 100_000.0)?;
        in_range("robot.max_hand_eye_translation_mm", r.max_hand_eye_translation_mm, 1.0, 10_000.0)?;
        let robot_limits =
            RobotLimits { max_reach_mm: r.max_reach_mm, max_hand_eye_translation_mm: r.max_hand_eye_translation_mm };
        let rows: [f64; 16] = r.hand_eye.as_slice().try_into().map_err(|_| ConfigError::Invalid {
            key: "robot.hand_eye",
            message: format!("needs 16 numbers (row-major 4x4), got {}", r.hand_eye.len()),
        })?;
        let hand_eye = hand_eye_from_rows(&rows).map_err(ConfigError::HandEye)?;
        let offset = hand_eye.translation.vector.norm();
        check("robot.hand_eye", offset <= robot_limits.max_hand_eye_translation_mm, || {
            format!(
                "its translation is {offset:.1} mm long, beyond robot.max_hand_eye_translation_mm ({} mm); \
                 is it in millimetres?",
                robot_limits.max_hand_eye_translation_mm
            )
        })?;
        Ok((euler, hand_eye, robot_limits))
    }
}

impl PipelineParams {
    /// Checks the `[pipeline]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let p = self;
        in_range("pipeline.neighbour_radius_mm", p.neighbour_radius_mm, 0.05, 10.0)?;
        in_range("pipeline.plane_min_neighbour_ratio", p.plane_min_neighbour_ratio, 0.05, 1.0)?;
        in_range("pipeline.plane_max_normal_angle_deg", p.plane_max_normal_angle_deg, 1.0, 89.0)?;
        in_range("pipeline.cluster_tolerance_mm", p.cluster_tolerance_mm, 0.05, 20.0)?;
        in_range("pipeline.min_plane_area_mm2", p.min_plane_area_mm2, 0.0, 1e7)?;
        in_range("pipeline.coplanar_tolerance_mm", p.coplanar_tolerance_mm, 0.05, 50.0)?;
        in_range("pipeline.lap_step_min_mm", p.lap_step_min_mm, 0.1, 100.0)?;
        in_range("pipeline.lap_step_max_mm", p.lap_step_max_mm, 0.1, 200.0)?;
        check("pipeline.lap_step_max_mm", p.lap_step_max_mm > p.lap_step_min_mm, || {
            format!("must exceed lap_step_min_mm ({}), got {}", p.lap_step_min_mm, p.lap_step_max_mm)
        })?;
        in_range("pipeline.tee_web_height_max_mm", p.tee_web_height_max_mm, 1.0, 2000.0)?;
        check("pipeline.tee_web_height_max_mm", p.tee_web_height_max_mm > p.lap_step_max_mm, || {
            format!(
                "must exceed lap_step_max_mm ({}): a web is taller than a lap's step, got {}",
                p.lap_step_max_mm, p.tee_web_height_max_mm
            )
        })?;
        in_range("pipeline.tee_web_thickness_max_mm", p.tee_web_thickness_max_mm, 0.5, 500.0)?;
        in_range("pipeline.edge_max_neighbour_ratio", p.edge_max_neighbour_ratio, 0.05, 0.99)?;
        check("pipeline.edge_max_neighbour_ratio", p.edge_max_neighbour_ratio < p.plane_min_neighbour_ratio, || {
            format!(
                "must be below plane_min_neighbour_ratio ({}), or every plane point is an edge point",
                p.plane_min_neighbour_ratio
            )
        })?;
        in_range("pipeline.ransac_distance_mm", p.ransac_distance_mm, 0.01, 20.0)?;
        count_in("pipeline.ransac_iterations", p.ransac_iterations.into(), 1, 100_000)?;
        count_in("pipeline.ransac_min_line_points", p.ransac_min_line_points.into(), 2, 1_000_000)?;
        count_in("pipeline.ransac_min_remaining_points", p.ransac_min_remaining_points.into(), 2, 1_000_000)?;
        count_in("pipeline.ransac_max_lines", p.ransac_max_lines.into(), 1, 100)?;
        in_range("pipeline.max_edge_angle_deg", p.max_edge_angle_deg, 0.1, 45.0)?;
        in_range("pipeline.boundary_band_mm", p.boundary_band_mm, 0.1, 50.0)?;
        in_range("pipeline.on_plane_tolerance_mm", p.on_plane_tolerance_mm, 0.01, 10.0)?;
        check("pipeline.fit_degree", (1..=5).contains(&p.fit_degree), || {
            format!("must be 1 (straight seams) to 5, got {}", p.fit_degree)
        })?;
        in_range("pipeline.fit_trim_sigma", p.fit_trim_sigma, 1.0, 100.0)?;
        self.region_of_interest().map(|_| ())
    }

    /// The configured region of interest, or None for the whole cloud;
    /// the error names `pipeline.roi` and the limit it breaks.
    pub fn region_of_interest(&self) -> Result<Option<Roi>, ConfigError> {
        let bounds: [f64; 6] = match self.roi.as_slice().try_into() {
            Ok(bounds) => bounds,
            Err(_) if self.roi.is_empty() => return Ok(None),
            Err(_) => {
                return Err(ConfigError::Invalid {
                    key: "pipeline.roi",
                    message: format!(
                        "must be [] or 6 numbers [xmin, ymin, zmin, xmax, ymax, zmax], got {}",
                        self.roi.len()
                    ),
                });
            }
        };
        Roi::from_bounds(bounds, self.roi_frame.cloud_frame())
            .map(Some)
            .map_err(|e| ConfigError::Invalid { key: "pipeline.roi", message: format!("must be a box: {e}") })
    }
}

impl PaperParams {
    /// Checks the `[paper]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("paper.edge_ratio", self.edge_ratio, 0.01, 1.0)?;
        in_range("paper.cluster_tolerance_mm", self.cluster_tolerance_mm, 0.05, 20.0)
    }
}

impl TrajectoryParams {
    /// Checks the `[trajectory]` section, against the same limits a
    /// request's own step and angles are held to.
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("trajectory.step_mm", self.step_mm, MIN_STEP_MM, MAX_STEP_MM)?;
        in_range("trajectory.work_angle_deg", self.work_angle_deg, -MAX_TORCH_ANGLE_DEG, MAX_TORCH_ANGLE_DEG)?;
        in_range("trajectory.travel_angle_deg", self.travel_angle_deg, -MAX_TORCH_ANGLE_DEG, MAX_TORCH_ANGLE_DEG)?;
        // The torch must lean between the flange and the web, never along
        // either.
        let (least, most) = (MIN_FILLET_WORK_ANGLE_DEG, 90.0 - MIN_FILLET_WORK_ANGLE_DEG);
        in_range("trajectory.fillet_work_angle_deg", self.fillet_work_angle_deg, least, most)
    }
}

fn socket_addr(key: &'static str, text: &str) -> Result<SocketAddr, ConfigError> {
    text.parse().map_err(|_| ConfigError::Invalid {
        key,
        message: format!("{text:?} is not an address with a port, such as \"127.0.0.1:7301\""),
    })
}

fn ip_list(key: &'static str, list: &[String]) -> Result<Vec<IpAddr>, ConfigError> {
    list.iter()
        .map(|t| {
            t.parse().map_err(|_| ConfigError::Invalid {
                key,
                message: format!("{t:?} is not an IP address, such as \"192.168.0.10\""),
            })
        })
        .collect()
}

impl file::ServerSection {
    /// Checks the `[server]` section and builds its typed values.
    pub fn validate(&self) -> Result<ServerConfig, ConfigError> {
        let s = self;
        const MAX_CONNECTIONS: u32 = 1024;
        check("server.max_camera_connections", (1..=MAX_CONNECTIONS).contains(&s.max_camera_connections), || {
            format!("must lie in [1, {MAX_CONNECTIONS}], got {}", s.max_camera_connections)
        })?;
        check(
            "server.max_controller_connections",
            (1..=MAX_CONNECTIONS).contains(&s.max_controller_connections),
            || format!("must lie in [1, {MAX_CONNECTIONS}], got {}", s.max_controller_connections),
        )?;
        check("server.stall_timeout_ms", (10..=3_600_000).contains(&s.stall_timeout_ms), || {
            format!("must lie in [10, 3600000] ms, got {}", s.stall_timeout_ms)
        })?;
        check("server.hello_timeout_ms", (10..=60_000).contains(&s.hello_timeout_ms), || {
            format!("must lie in [10, 60000] ms, got {}", s.hello_timeout_ms)
        })?;
        check("server.message_timeout_ms", (10..=3_600_000).contains(&s.message_timeout_ms), || {
            format!("must lie in [10, 3600000] ms, got {}", s.message_timeout_ms)
        })?;
        const MIN_RATE: u64 = 1 << 10;
        const MAX_RATE: u64 = 1 << 30;
        check("server.min_transfer_bytes_per_s", (MIN_RATE..=MAX_RATE).contains(&s.min_transfer_bytes_per_s), || {
            format!("must lie in [{MIN_RATE}, {MAX_RATE}] bytes per second, got {}", s.min_transfer_bytes_per_s)
        })?;
        const MAX_PENDING: u32 = 4096;
        check("server.max_pending_connections", (1..=MAX_PENDING).contains(&s.max_pending_connections), || {
            format!("must lie in [1, {MAX_PENDING}], got {}", s.max_pending_connections)
        })?;
        check(
            "server.max_pending_per_address",
            (1..=s.max_pending_connections).contains(&s.max_pending_per_address),
            || {
                format!(
                    "must lie in [1, server.max_pending_connections = {}], got {}",
                    s.max_pending_connections, s.max_pending_per_address
                )
            },
        )?;
        let metrics_listen = match s.metrics_listen.as_str() {
            "" => None,
            text => Some(socket_addr("server.metrics_listen", text)?),
        };
        const MIN_FRAME: u64 = 1 << 10;
        const MAX_FRAME: u64 = 4 << 30;
        check("server.max_frame_bytes", (MIN_FRAME..=MAX_FRAME).contains(&s.max_frame_bytes), || {
            format!("must lie in [{MIN_FRAME}, {MAX_FRAME}] bytes, got {}", s.max_frame_bytes)
        })?;
        check("server.plan_queue_depth", (1..=1024).contains(&s.plan_queue_depth), || {
            format!("must lie in [1, 1024], got {}", s.plan_queue_depth)
        })?;
        check("server.pipeline_threads", s.pipeline_threads <= 1024, || {
            format!("must be 0 (every core) to 1024, got {}", s.pipeline_threads)
        })?;
        check("server.fresh_frame_timeout_ms", (1..=600_000).contains(&s.fresh_frame_timeout_ms), || {
            format!("must lie in [1, 600000] ms, got {}", s.fresh_frame_timeout_ms)
        })?;
        check("server.shutdown_grace_ms", s.shutdown_grace_ms <= 3_600_000, || {
            format!("must be at most 3600000 ms, got {}", s.shutdown_grace_ms)
        })?;
        check("server.plan_timeout_ms", (1..=600_000).contains(&s.plan_timeout_ms), || {
            format!("must lie in [1, 600000] ms, got {}", s.plan_timeout_ms)
        })?;
        check("server.frame_history", (1..=1024).contains(&s.frame_history), || {
            format!("must lie in [1, 1024] frames, got {}", s.frame_history)
        })?;
        const MAX_HISTORY_BYTES: u64 = 64 << 30;
        check(
            "server.frame_history_bytes",
            (s.max_frame_bytes..=MAX_HISTORY_BYTES).contains(&s.frame_history_bytes),
            || {
                format!(
                    "must lie in [server.max_frame_bytes = {}, {MAX_HISTORY_BYTES}] bytes, so the newest frame always fits, got {}",
                    s.max_frame_bytes, s.frame_history_bytes
                )
            },
        )?;
        check("server.capture_time_tolerance_ms", s.capture_time_tolerance_ms <= 5_000, || {
            format!("must lie in [0, 5000] ms, got {}", s.capture_time_tolerance_ms)
        })?;
        check("server.max_request_timeout_ms", (1..=600_000).contains(&s.max_request_timeout_ms), || {
            format!("must lie in [1, 600000] ms, got {}", s.max_request_timeout_ms)
        })?;
        check("server.fresh_frame_timeout_ms", s.fresh_frame_timeout_ms <= s.max_request_timeout_ms, || {
            format!(
                "must not exceed server.max_request_timeout_ms ({}), got {}",
                s.max_request_timeout_ms, s.fresh_frame_timeout_ms
            )
        })?;
        check(
            "server.max_requests_per_connection",
            (1..=s.plan_queue_depth).contains(&s.max_requests_per_connection),
            || {
                format!(
                    "must lie in [1, server.plan_queue_depth = {}], got {}",
                    s.plan_queue_depth, s.max_requests_per_connection
                )
            },
        )?;
        check("server.idle_trim_ms", s.idle_trim_ms <= 86_400_000, || {
            format!("must lie in [0 (never), 86400000] ms, got {}", s.idle_trim_ms)
        })?;
        Ok(ServerConfig {
            camera_listen: socket_addr("server.camera_listen", &s.camera_listen)?,
            controller_listen: socket_addr("server.controller_listen", &s.controller_listen)?,
            camera_allow: ip_list("server.camera_allow", &s.camera_allow)?,
            controller_allow: ip_list("server.controller_allow", &s.controller_allow)?,
            max_camera_connections: s.max_camera_connections as usize,
            max_controller_connections: s.max_controller_connections as usize,
            stall_timeout: Duration::from_millis(s.stall_timeout_ms),
            hello_timeout: Duration::from_millis(s.hello_timeout_ms),
            message_timeout: Duration::from_millis(s.message_timeout_ms),
            min_transfer_bytes_per_s: s.min_transfer_bytes_per_s,
            max_pending_connections: s.max_pending_connections as usize,
            max_pending_per_address: s.max_pending_per_address as usize,
            metrics_listen,
            max_frame_bytes: s.max_frame_bytes,
            plan_queue_depth: s.plan_queue_depth as usize,
            pipeline_threads: s.pipeline_threads as usize,
            fresh_frame_timeout: Duration::from_millis(s.fresh_frame_timeout_ms),
            shutdown_grace: Duration::from_millis(s.shutdown_grace_ms),
            plan_timeout: Duration::from_millis(s.plan_timeout_ms),
            frame_history: s.frame_history as usize,
            frame_history_bytes: s.frame_history_bytes,
            capture_time_tolerance: Duration::from_millis(s.capture_time_tolerance_ms),
            max_request_timeout: Duration::from_millis(s.max_request_timeout_ms),
            max_requests_per_connection: s.max_requests_per_connection as usize,
            idle_trim: Duration::from_millis(s.idle_trim_ms),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_file_gives_the_defaults() {
        let c = Config::parse("", "empty").unwrap();
        assert_eq!(c.pipeline, PipelineParams::default());
        assert_eq!(c.camera, CameraModel::default());
        assert_eq!(c.euler, EulerConvention::Zyx);
    }

    #[test]
    fn unknown_keys_are_refused_with_their_name() {
        let e = Config::parse("[pipeline]\nneighbour_radius = 1.0\n", "x.toml").unwrap_err().to_string();
        assert!(e.contains("neighbour_radius") && e.contains("x.toml"), "{e}");
    }

    #[test]
    fn bad_values_name_their_key() {
        let cases = [
            ("[pipeline]\nneighbour_radius_mm = -1.0\n", "pipeline.neighbour_radius_mm"),
            ("[camera]\nmin_depth_mm = 0.0\n", "camera.min_depth_mm"),
            ("[pipeline]\nmethod = \"fast\"\n", "pipeline.method"),
            ("[trajectory]\nstep_mm = 0.0\n", "trajectory.step_mm"),
            ("[robot]\neuler_convention = \"zxz\"\n", "robot.euler_convention"),
            ("[robot]\nhand_eye = [1.0, 0.0]\n", "robot.hand_eye"),
            ("[pipeline]\nedge_max_neighbour_ratio = 0.9\n", "pipeline.edge_max_neighbour_ratio"),
            ("[server]\ncamera_listen = \"localhost\"\n", "server.camera_listen"),
            ("[server]\ncontroller_allow = [\"10.0.0.x\"]\n", "server.controller_allow"),
            ("[server]\nplan_queue_depth = 0\n", "server.plan_queue_depth"),
            ("[server]\nmax_frame_bytes = 12\n", "server.max_frame_bytes"),
            ("[server]\nstall_timeout_ms = 0\n", "server.stall_timeout_ms"),
            ("[server]\nframe_history_bytes = 1024\n", "server.frame_history_bytes"),
            ("[server]\ncapture_time_tolerance_ms = 60000\n", "server.capture_time_tolerance_ms"),
            ("[server]\nmax_request_timeout_ms = 4294967295\n", "server.max_request_timeout_ms"),
            ("[server]\nmax_request_timeout_ms = 100\n", "server.fresh_frame_timeout_ms"),
            ("[server]\nmax_requests_per_connection = 5\n", "server.max_requests_per_connection"),
            ("[server]\nidle_trim_ms = 100000000\n", "server.idle_trim_ms"),
            ("[server]\nhello_timeout_ms = 0\n", "server.hello_timeout_ms"),
            ("[server]\nhello_timeout_ms = 3600000\n", "server.hello_timeout_ms"),
            ("[server]\nmessage_timeout_ms = 4000000\n", "server.message_timeout_ms"),
            ("[server]\nmin_transfer_bytes_per_s = 10\n", "server.min_transfer_bytes_per_s"),
            ("[server]\nmax_pending_connections = 0\n", "server.max_pending_connections"),
            ("[server]\nmax_pending_connections = 100000\n", "server.max_pending_connections"),
            ("[server]\nmax_pending_per_address = 65\n", "server.max_pending_per_address"),
            ("[server]\nmetrics_listen = \"9100\"\n", "server.metrics_listen"),
            ("[pipeline]\nroi = [1.0, 2.0]\n", "pipeline.roi"),
            ("[pipeline]\nroi = [0.0, 0.0, 600.0, 10.0, 10.0, 500.0]\n", "pipeline.roi"),
            ("[pipeline]\nroi_frame = \"tool\"\n", "roi_frame"),
            ("[debug]\nkeep_last = 0\n", "debug.keep_last"),
            ("[debug]\nkeep = 3\n", "keep"),
        ];
        for (text, key) in cases {
            let e = Config::parse(text, "c.toml").unwrap_err().to_string();
            assert!(e.contains(key), "{text:?} gave {e}");
        }
    }

    /// Every numeric key of the shipped file, with its section.
    fn numeric_keys() -> Vec<(String, String, toml::Value)> {
        let text = include_str!("../../config/weldseam.toml");
        let doc: toml::Table = toml::from_str(text).unwrap();
        let mut keys = Vec::new();
        for (section, table) in &doc {
            for (key, value) in table.as_table().unwrap() {
                if value.is_integer() || value.is_float() {
                    keys.push((section.clone(), key.clone(), value.clone()));
                }
            }
        }
        keys
    }

    #[test]
    fn every_number_has_a_ceiling_named_in_its_error() {
        // The seed may be any number; every other value has a limit, so a
        // unit mix-up or a typo cannot hang or silently break the planner.
        let keys = numeric_keys();
        assert!(keys.len() > 40, "found {} numeric keys", keys.len());
        for (section, key, value) in keys.into_iter().filter(|(_, k, _)| k != "ransac_seed") {
            // The largest u32 for counts; for 64-bit keys whose ceiling lies
            // above that (a frame of over 4 GB), the largest TOML integer.
            let huge: &[&str] = if value.is_integer() { &["4294967295", "9223372036854775807"] } else { &["1e300"] };
            let refused = huge.iter().find_map(|h| {
                let text = format!("[{section}]\n{key} = {h}\n");
                // A huge value may first break a rule between two keys (a
                // frame larger than the history); the next one must meet
                // the key's own ceiling.
                match Config::parse(&text, "c.toml") {
                    Err(ConfigError::Invalid { key: named, message }) if named == format!("{section}.{key}") => {
                        Some((text, message))
                    }
                    _ => None,
                }
            });
            let (text, message) = refused.unwrap_or_else(|| panic!("{section}.{key} has no ceiling"));
            assert!(message.contains("must"), "{text:?} gave {message}");
        }
    }

    #[test]
    fn tolerances_of_nothing_are_refused() {
        for key in ["cluster_tolerance_mm", "coplanar_tolerance_mm", "ransac_distance_mm", "on_plane_tolerance_mm"] {
            let text = format!("[pipeline]\n{key} = 1e-30\n");
            let e = Config::parse(&text, "c.toml").unwrap_err().to_string();
            assert!(e.contains(&format!("pipeline.{key}")) && e.contains("must lie in"), "{e}");
        }
    }

    #[test]
    fn a_hand_eye_with_a_camera_a_kilometre_away_is_refused() {
        let mut rows = crate::geometry::pose::PAPER_HAND_EYE;
        rows[3] = 1e6;
        let text = format!("[robot]\nhand_eye = {rows:?}\n");
        let e = Config::parse(&text, "c.toml").unwrap_err().to_string();
        assert!(e.contains("robot.hand_eye") && e.contains("max_hand_eye_translation_mm (1000 mm)"), "{e}");
    }

    #[test]
    fn camera_values_out_of_range_name_their_key_and_limit() {
        let cases = [
            ("width_px = 0", "camera.width_px", "[1, 32768]"),
            ("height_px = 100000", "camera.height_px", "[1, 32768]"),
            ("fov_width_mm = 1e300", "camera.fov_width_mm", "100000"),
            ("nominal_accuracy_mm = 0.0", "camera.nominal_accuracy_mm", "[0.000001, 100]"),
            ("max_depth_mm = 500.0", "camera.max_depth_mm", "[1000, 100000]"),
            ("max_depth_mm = inf", "camera.max_depth_mm", "[1000, 100000]"),
            ("max_off_axis_deg = 90.0", "camera.max_off_axis_deg", "[1, 89]"),
            ("fov_margin_px = -1.0", "camera.fov_margin_px", "[0, 32768]"),
            ("fov_margin_px = nan", "camera.fov_margin_px", "[0, 32768]"),
        ];
        for (line, key, limit) in cases {
            let e = Config::parse(&format!("[camera]\n{line}\n"), "c.toml").unwrap_err().to_string();
            assert!(e.contains(key) && e.contains(limit), "{line:?} gave {e}");
        }
        let c = Config::parse("[camera]\nmax_depth_mm = 2000.0\nfov_margin_px = 0.0\n", "c.toml").unwrap();
        assert_eq!((c.camera.max_depth_mm, c.camera.fov_margin_px), (2000.0, 0.0));
    }

    #[test]
    fn the_papers_printed_hand_eye_typo_is_refused() {
        let mut rows = crate::geometry::pose::PAPER_HAND_EYE;
        rows[4] = -0.353;
        let text = format!("[robot]\nhand_eye = {rows:?}\n");
        let e = Config::parse(&text, "c.toml").unwrap_err().to_string();
        assert!(e.contains("robot.hand_eye") && e.contains("orthonormal"), "{e}");
    }

    #[test]
    fn intrinsics_replace_or_agree_with_the_field_of_view() {
        let paper = CameraModel::default();
        let only = "[camera]\nfx = 2000.0\nfy = 2010.0\ncx = 950.25\ncy = 601.75\n";
        let c = Config::parse(only, "c.toml").unwrap().camera;
        assert_eq!((c.fx(), c.fy(), c.cx(), c.cy()), (2000.0, 2010.0, 950.25, 601.75));
        assert!((c.fov_width_mm - 1920.0 * 1000.0 / 2000.0).abs() < 1e-9, "the fov they imply: {c:?}");
        // Both forms, agreeing: the paper's camera with its principal point moved.
        let both = format!(
            "[camera]\nfov_width_mm = 700.0\nfov_height_mm = 440.0\nfx = {}\nfy = {}\ncx = 958.0\ncy = 600.0\n",
            paper.fx(),
            paper.fy()
        );
        let c = Config::parse(&both, "c.toml").unwrap().camera;
        assert_eq!((c.fx(), c.cx()), (paper.fx(), 958.0));
        let cases = [
            ("fov_width_mm = 700.0\nfx = 2000.0\nfy = 2727.0\ncx = 959.5\ncy = 599.5", "camera.fx", "not both"),
            ("fx = 2000.0\nfy = 2000.0", "camera.cx", "fx, fy given but not cx, cy"),
            ("fx = 1.0\nfy = 2000.0\ncx = 959.5\ncy = 599.5", "camera.fx", "must lie in"),
            ("k1 = 50.0", "camera.k1", "[-10, 10]"),
        ];
        for (lines, key, text) in cases {
            let e = Config::parse(&format!("[camera]\n{lines}\n"), "c.toml").unwrap_err().to_string();
            assert!(e.contains(key) && e.contains(text), "{lines:?} gave {e}");
        }
        let c = Config::parse("[camera]\nk1 = -0.1\np2 = 0.001\n", "c.toml").unwrap().camera;
        assert_eq!((c.distortion.k1, c.distortion.p2, c.fx()), (-0.1, 0.001, paper.fx()));
    }

    #[test]
    fn shipped_config_file_is_valid_and_equals_the_defaults() {
        let text = include_str!("../../config/weldseam.toml");
        Config::parse(text, "config/weldseam.toml").unwrap();
        // The whole file, section by section: [robot]'s convention and
        // hand-eye and [paper] included, not only what a built config holds.
        let file: ConfigFile = toml::from_str(text).unwrap();
        assert_eq!(file, ConfigFile::default());
    }

    #[test]
    fn a_request_and_the_config_share_the_step_and_angle_limits() {
        use crate::geometry::pose::RobotPose;
        use crate::joint::JointType;
        use crate::pipeline::{PlanRequest, Planner};
        let planner = Planner::new(Config::default());
        let pose = RobotPose { xyz_mm: [500.0, 0.0, 500.0], angles_deg: [180.0, 0.0, 0.0] };
        let request = |step: f64, angle: f64| PlanRequest {
            step_mm: Some(step),
            travel_angle_deg: Some(angle),
            ..PlanRequest::new(JointType::IButt, None, pose)
        };
        let config = |step: f64, angle: f64| {
            Config::parse(&format!("[trajectory]\nstep_mm = {step}\ntravel_angle_deg = {angle}\n"), "c.toml")
        };
        // At the limits both accept; just beyond, both refuse.
        for (step, angle) in [(MIN_STEP_MM, -MAX_TORCH_ANGLE_DEG), (MAX_STEP_MM, MAX_TORCH_ANGLE_DEG)] {
            assert!(planner.check_request(&request(step, angle)).is_ok(), "request {step} {angle}");
            assert!(config(step, angle).is_ok(), "config {step} {angle}");
        }
        for (step, angle) in [(MIN_STEP_MM * 0.99, 0.0), (MAX_STEP_MM * 1.01, 0.0), (5.0, MAX_TORCH_ANGLE_DEG + 0.1)] {
            assert!(planner.check_request(&request(step, angle)).is_err(), "request {step} {angle}");
            assert!(config(step, angle).is_err(), "config {step} {angle}");
        }
    }
}
