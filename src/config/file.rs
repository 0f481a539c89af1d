//! The on-disk schema of config/weldseam.toml. Sections whose values keep
//! their type (camera, pipeline, paper, trajectory, quality, debug, records, calibration) are the library's own
//! parameter structs, deserialized directly; only the three whose type
//! changes on the way in have a schema of their own here: `[camera]` (the
//! field of view or the intrinsics, either of which may be left out),
//! `[robot]` (an Euler convention by name, the hand-eye as 16 numbers) and
//! `[server]` and `[text_link]` (addresses as text, durations in ms). Every struct denies unknown keys,
//! so a misspelt key is an error rather than a silently ignored setting.
//! Nothing here is validated; see [`super::Config::from_file`] for that.

use serde::Deserialize;

use super::process::ProcessSection;
use super::text_link::TextLinkConfig;
use super::{
    DebugParams, PaperParams, PipelineParams, QualityParams, RecordsParams, RobotLimits, ServerConfig, TrajectoryParams,
};
use crate::calibration::gate::{CalibrationRecord, GateLimits};
use crate::camera::CameraModel;
use crate::geometry::pose::{EulerConvention, PAPER_HAND_EYE};

#[derive(Debug, Clone, Deserialize, Default, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ConfigFile {
    pub camera: CameraSection,
    pub robot: RobotSection,
    pub pipeline: PipelineParams,
    pub paper: PaperParams,
    pub trajectory: TrajectoryParams,
    pub quality: QualityParams,
    pub server: ServerSection,
    pub text_link: TextLinkSection,
    pub debug: DebugParams,
    pub records: RecordsParams,
    pub calibration: GateLimits,
    pub process: ProcessSection,
}

/// `[camera]`: the camera model's keys, with the field of view and the
/// intrinsics each optional (a key left out is `None`; the defaults the
/// shipped file shows are the paper's field of view and no intrinsics).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSection {
    pub width_px: u32,
    pub height_px: u32,
    #[serde(default)]
    pub fov_width_mm: Option<f64>,
    #[serde(default)]
    pub fov_height_mm: Option<f64>,
    pub fov_distance_mm: f64,
    #[serde(default)]
    pub fx: Option<f64>,
    #[serde(default)]
    pub fy: Option<f64>,
    #[serde(default)]
    pub cx: Option<f64>,
    #[serde(default)]
    pub cy: Option<f64>,
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
    pub k3: f64,
    pub baseline_mm: f64,
    pub nominal_accuracy_mm: f64,
    pub min_depth_mm: f64,
    pub max_depth_mm: f64,
    pub max_off_axis_deg: f64,
    pub fov_margin_px: f64,
}

impl Default for CameraSection {
    /// The paper's camera (Table 1), in the field-of-view form.
    fn default() -> Self {
        let c = CameraModel::default();
        CameraSection {
            width_px: c.width_px,
            height_px: c.height_px,
            fov_width_mm: Some(c.fov_width_mm),
            fov_height_mm: Some(c.fov_height_mm),
            fov_distance_mm: c.fov_distance_mm,
            fx: None,
            fy: None,
            cx: None,
            cy: None,
            k1: c.distortion.k1,
            k2: c.distortion.k2,
            p1: c.distortion.p1,
            p2: c.distortion.p2,
            k3: c.distortion.k3,
            baseline_mm: c.baseline_mm,
            nominal_accuracy_mm: c.nominal_accuracy_mm,
            min_depth_mm: c.min_depth_mm,
            max_depth_mm: c.max_depth_mm,
            max_off_axis_deg: c.max_off_axis_deg,
            fov_margin_px: c.fov_margin_px,
        }
    }
}

/// `[robot]`: the convention is named, the hand-eye a row-major 4x4 list.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSection {
    pub euler_convention: String,
    pub hand_eye: Vec<f64>,
    pub max_reach_mm: f64,
    pub max_hand_eye_translation_mm: f64,
    /// The figures of the calibration that gave `hand_eye`, as `weldseam
    /// calibrate --write-config` records them.
    #[serde(default)]
    pub hand_eye_calibration: Option<CalibrationRecord>,
}

impl Default for RobotSection {
    fn default() -> Self {
        let limits = RobotLimits::default();
        RobotSection {
            euler_convention: EulerConvention::default().name().into(),
            hand_eye: PAPER_HAND_EYE.to_vec(),
            max_reach_mm: limits.max_reach_mm,
            max_hand_eye_translation_mm: limits.max_hand_eye_translation_mm,
            hand_eye_calibration: None,
        }
    }
}

/// `[server]`: addresses as text, durations in whole milliseconds.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ServerSection {
    pub camera_listen: String,
    pub controller_listen: String,
    pub camera_allow: Vec<String>,
    pub controller_allow: Vec<String>,
    pub max_camera_connections: u32,
    pub max_controller_connections: u32,
    pub stall_timeout_ms: u64,
    pub hello_timeout_ms: u64,
    pub message_timeout_ms: u64,
    pub min_transfer_bytes_per_s: u64,
    pub max_pending_connections: u32,
    pub max_pending_per_address: u32,
    pub metrics_listen: String,
    pub http_token: String,
    pub page_plans: u32,
    pub max_frame_bytes: u64,
    pub plan_queue_depth: u32,
    pub pipeline_threads: u32,
    pub fresh_frame_timeout_ms: u64,
    pub shutdown_grace_ms: u64,
    pub plan_timeout_ms: u64,
    pub frame_history: u32,
    pub frame_history_bytes: u64,
    pub capture_time_tolerance_ms: u64,
    pub max_request_timeout_ms: u64,
    pub max_requests_per_connection: u32,
    pub idle_trim_ms: u64,
}

impl Default for ServerSection {
    /// [`ServerConfig::default`] written the file's way, so the defaults
    /// are stated once.
    fn default() -> Self {
        let s = ServerConfig::default();
        let ms = |d: std::time::Duration| d.as_millis() as u64;
        let list = |ips: &[std::net::IpAddr]| ips.iter().map(ToString::to_string).collect();
        ServerSection {
            camera_listen: s.camera_listen.to_string(),
            controller_listen: s.controller_listen.to_string(),
            camera_allow: list(&s.camera_allow),
            controller_allow: list(&s.controller_allow),
            max_camera_connections: s.max_camera_connections as u32,
            max_controller_connections: s.max_controller_connections as u32,
            stall_timeout_ms: ms(s.stall_timeout),
            hello_timeout_ms: ms(s.hello_timeout),
            message_timeout_ms: ms(s.message_timeout),
            min_transfer_bytes_per_s: s.min_transfer_bytes_per_s,
            max_pending_connections: s.max_pending_connections as u32,
            max_pending_per_address: s.max_pending_per_address as u32,
            metrics_listen: s.metrics_listen.map(|a| a.to_string()).unwrap_or_default(),
            http_token: s.http_token.clone().unwrap_or_default(),
            page_plans: s.page_plans as u32,
            max_frame_bytes: s.max_frame_bytes,
            plan_queue_depth: s.plan_queue_depth as u32,
            pipeline_threads: s.pipeline_threads as u32,
            fresh_frame_timeout_ms: ms(s.fresh_frame_timeout),
            shutdown_grace_ms: ms(s.shutdown_grace),
            plan_timeout_ms: ms(s.plan_timeout),
            frame_history: s.frame_history as u32,
            frame_history_bytes: s.frame_history_bytes,
            capture_time_tolerance_ms: ms(s.capture_time_tolerance),
            max_request_timeout_ms: ms(s.max_request_timeout),
            max_requests_per_connection: s.max_requests_per_connection as u32,
            idle_trim_ms: ms(s.idle_trim),
        }
    }
}

/// `[text_link]`: the address as text (empty is off), the dialect by name
/// (empty: the robot names it), durations in whole milliseconds.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct TextLinkSection {
    pub listen: String,
    pub allow: Vec<String>,
    pub max_connections: u32,
    pub dialect: String,
    pub max_line_bytes: u64,
    pub line_timeout_ms: u64,
    pub idle_timeout_ms: u64,
    pub approach_offset_mm: f64,
}

impl Default for TextLinkSection {
    /// [`TextLinkConfig::default`] written the file's way.
    fn default() -> Self {
        let t = TextLinkConfig::default();
        let ms = |d: std::time::Duration| d.as_millis() as u64;
        TextLinkSection {
            listen: t.listen.map(|a| a.to_string()).unwrap_or_default(),
            allow: t.allow.iter().map(ToString::to_string).collect(),
            max_connections: t.max_connections as u32,
            dialect: t.dialect.map(|d| d.name().to_string()).unwrap_or_default(),
            max_line_bytes: t.max_line_bytes as u64,
            line_timeout_ms: ms(t.line_timeout),
            idle_timeout_ms: ms(t.idle_timeout),
            approach_offset_mm: t.approach_offset_mm,
        }
    }
}
