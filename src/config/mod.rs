//! Configuration: parsed once from TOML, validated once, then carried as a
//! built [`Config`] whose values are known to be usable. Every error names
//! the key at fault.
//!
//! Defaults are the paper's camera (Table 1) and parameters wherever the
//! paper gives one (R = 1 mm, μ = 0.5, 2 mm clustering, 1 mm RANSAC), and
//! measured values for the robust method's own settings.

mod camera;
mod file;
mod planning;
pub mod procedure;
mod process;
mod quality;
mod records;
mod server;
#[cfg(test)]
mod tests;
mod text_link;

use std::path::Path;

use nalgebra::Isometry3;

use crate::calibration::gate::{CalibrationRecord, GateLimits};
use crate::camera::CameraModel;
use crate::geometry::pose::{EulerConvention, HandEyeError, hand_eye_from_rows};

pub use file::ConfigFile;
pub use planning::{Method, PaperParams, PipelineParams, PointDensity, RoiFrame, TrajectoryParams};
pub use process::{MAX_PLATE_THICKNESS_MM, ProcessParams};
pub use quality::QualityParams;
pub use records::RecordsParams;
pub use server::{DEFAULT_DEBUG_KEEP_LAST, DEFAULT_PLAN_TIMEOUT_MS, DebugParams, MAX_DEBUG_KEEP_LAST, ServerConfig};
pub use text_link::TextLinkConfig;

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
    /// The plan records' store.
    pub records: RecordsParams,
    /// The limits `weldseam calibrate` holds a calibration to.
    pub calibration: GateLimits,
    /// The record of the calibration that gave `hand_eye`, when the file
    /// has one.
    pub hand_eye_calibration: Option<CalibrationRecord>,
    /// The weld procedure the waypoints' parameters follow, if any.
    pub process: ProcessParams,
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
    /// A short fingerprint of every setting that shapes a plan (the
    /// camera, the robot, the pipeline, the trajectory, the quality gates
    /// and, where set, the weld process: the procedure and the plates'
    /// thickness; not the daemon's links and stores): FNV-1a, 64 bits, of
    /// their debug form, whose numbers are exact. A record keeps it, so a
    /// replay can tell whether it plans with the same settings. A config
    /// without a process hashes as it did before the process was counted,
    /// so the records it made still match.
    pub fn planning_hash(&self) -> String {
        let mut text = format!(
            "{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}",
            self.camera,
            self.euler,
            self.hand_eye,
            self.robot_limits,
            self.pipeline,
            self.paper,
            self.trajectory,
            self.quality
        );
        if self.process != ProcessParams::default() {
            text.push_str(&format!("{:?}", self.process));
        }
        let hash = text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
        format!("{hash:016x}")
    }

    /// Reads and validates a TOML config file.
    pub fn load(path: &Path) -> Result<Config, ConfigError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|cause| ConfigError::Io { path: shown.clone(), cause })?;
        let mut file: ConfigFile =
            toml::from_str(&text).map_err(|e| ConfigError::Parse { path: shown.clone(), message: e.to_string() })?;
        // A procedure named relative to the config is read beside it.
        file.process = file.process.resolved_against(path.parent());
        Config::from_file(file)
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

    /// [`Config::parse`] with `procedure` as the weld procedure instead of
    /// the file `[process] procedure` names (not read): a plan record's
    /// configuration with the procedure it kept.
    pub fn parse_with_procedure(
        text: &str,
        origin: &str,
        procedure: procedure::Procedure,
    ) -> Result<Config, ConfigError> {
        let mut file: ConfigFile = toml::from_str(text)
            .map_err(|e| ConfigError::Parse { path: origin.to_string(), message: e.to_string() })?;
        file.process.procedure = String::new();
        let mut config = Config::from_file(file)?;
        config.process.procedure = Some(procedure);
        Ok(config)
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
        f.records.validate()?;
        let process = f.process.validate()?;
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
            records: f.records,
            calibration: f.calibration,
            hand_eye_calibration: f.robot.hand_eye_calibration,
            process,
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
