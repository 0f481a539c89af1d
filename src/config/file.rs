//! The on-disk schema of config/weldseam.toml: plain serde structs with
//! named defaults and `deny_unknown_fields`, so a misspelt key is an error
//! rather than a silently ignored setting. Nothing here is validated; see
//! [`super::Config::from_file`] for that.

use serde::Deserialize;

use crate::geometry::pose::PAPER_HAND_EYE;

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ConfigFile {
    pub camera: CameraSection,
    pub robot: RobotSection,
    pub pipeline: PipelineSection,
    pub paper: PaperSection,
    pub trajectory: TrajectorySection,
    pub server: ServerSection,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSection {
    pub width_px: u32,
    pub height_px: u32,
    pub fov_width_mm: f64,
    pub fov_height_mm: f64,
    pub fov_distance_mm: f64,
    pub baseline_mm: f64,
    pub nominal_accuracy_mm: f64,
    pub min_depth_mm: f64,
    pub max_depth_mm: f64,
    pub max_off_axis_deg: f64,
    pub fov_margin_px: f64,
}

impl Default for CameraSection {
    fn default() -> Self {
        let c = crate::camera::CameraModel::default();
        CameraSection {
            width_px: c.width_px,
            height_px: c.height_px,
            fov_width_mm: c.fov_width_mm,
            fov_height_mm: c.fov_height_mm,
            fov_distance_mm: c.fov_distance_mm,
            baseline_mm: c.baseline_mm,
            nominal_accuracy_mm: c.nominal_accuracy_mm,
            min_depth_mm: c.min_depth_mm,
            max_depth_mm: c.max_depth_mm,
            max_off_axis_deg: c.max_off_axis_deg,
            fov_margin_px: c.fov_margin_px,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSection {
    pub euler_convention: String,
    pub hand_eye: Vec<f64>,
    pub max_reach_mm: f64,
    pub max_hand_eye_translation_mm: f64,
}

impl Default for RobotSection {
    fn default() -> Self {
        let limits = super::RobotLimits::default();
        RobotSection {
            euler_convention: "zyx".into(),
            hand_eye: PAPER_HAND_EYE.to_vec(),
            max_reach_mm: limits.max_reach_mm,
            max_hand_eye_translation_mm: limits.max_hand_eye_translation_mm,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineSection {
    pub method: String,
    pub neighbour_radius_mm: f64,
    pub plane_min_neighbour_ratio: f64,
    pub plane_max_normal_angle_deg: f64,
    pub cluster_tolerance_mm: f64,
    pub min_plane_area_mm2: f64,
    pub coplanar_tolerance_mm: f64,
    pub lap_step_min_mm: f64,
    pub lap_step_max_mm: f64,
    pub edge_max_neighbour_ratio: f64,
    pub ransac_distance_mm: f64,
    pub ransac_iterations: u32,
    pub ransac_min_line_points: u32,
    pub ransac_min_remaining_points: u32,
    pub ransac_max_lines: u32,
    pub ransac_seed: u64,
    pub max_edge_angle_deg: f64,
    pub boundary_band_mm: f64,
    pub on_plane_tolerance_mm: f64,
    pub fit_degree: u32,
    pub fit_trim_sigma: f64,
}

impl Default for PipelineSection {
    fn default() -> Self {
        let p = super::PipelineParams::default();
        PipelineSection {
            method: p.method.name().into(),
            neighbour_radius_mm: p.neighbour_radius_mm,
            plane_min_neighbour_ratio: p.plane_min_neighbour_ratio,
            plane_max_normal_angle_deg: p.plane_max_normal_angle_deg,
            cluster_tolerance_mm: p.cluster_tolerance_mm,
            min_plane_area_mm2: p.min_plane_area_mm2,
            coplanar_tolerance_mm: p.coplanar_tolerance_mm,
            lap_step_min_mm: p.lap_step_min_mm,
            lap_step_max_mm: p.lap_step_max_mm,
            edge_max_neighbour_ratio: p.edge_max_neighbour_ratio,
            ransac_distance_mm: p.ransac_distance_mm,
            ransac_iterations: p.ransac_iterations,
            ransac_min_line_points: p.ransac_min_line_points,
            ransac_min_remaining_points: p.ransac_min_remaining_points,
            ransac_max_lines: p.ransac_max_lines,
            ransac_seed: p.ransac_seed,
            max_edge_angle_deg: p.max_edge_angle_deg,
            boundary_band_mm: p.boundary_band_mm,
            on_plane_tolerance_mm: p.on_plane_tolerance_mm,
            fit_degree: p.fit_degree,
            fit_trim_sigma: p.fit_trim_sigma,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PaperSection {
    pub edge_ratio: f64,
    pub cluster_tolerance_mm: f64,
}

impl Default for PaperSection {
    fn default() -> Self {
        let p = super::PaperParams::default();
        PaperSection { edge_ratio: p.edge_ratio, cluster_tolerance_mm: p.cluster_tolerance_mm }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrajectorySection {
    pub step_mm: f64,
    pub work_angle_deg: f64,
    pub travel_angle_deg: f64,
}

impl Default for TrajectorySection {
    fn default() -> Self {
        let t = super::TrajectoryParams::default();
        TrajectorySection { step_mm: t.step_mm, work_angle_deg: t.work_angle_deg, travel_angle_deg: t.travel_angle_deg }
    }
}

#[derive(Debug, Clone, Deserialize)]
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
    pub max_frame_bytes: u64,
    pub plan_queue_depth: u32,
    pub pipeline_threads: u32,
    pub fresh_frame_timeout_ms: u64,
    pub shutdown_grace_ms: u64,
    pub frame_history: u32,
    pub frame_history_bytes: u64,
    pub capture_time_tolerance_ms: u64,
    pub max_request_timeout_ms: u64,
    pub max_requests_per_connection: u32,
    pub idle_trim_ms: u64,
}

impl Default for ServerSection {
    fn default() -> Self {
        let s = super::ServerConfig::default();
        let ms = |d: std::time::Duration| d.as_millis() as u64;
        ServerSection {
            camera_listen: s.camera_listen.to_string(),
            controller_listen: s.controller_listen.to_string(),
            camera_allow: Vec::new(),
            controller_allow: Vec::new(),
            max_camera_connections: s.max_camera_connections as u32,
            max_controller_connections: s.max_controller_connections as u32,
            stall_timeout_ms: ms(s.stall_timeout),
            hello_timeout_ms: ms(s.hello_timeout),
            message_timeout_ms: ms(s.message_timeout),
            min_transfer_bytes_per_s: s.min_transfer_bytes_per_s,
            max_pending_connections: s.max_pending_connections as u32,
            max_pending_per_address: s.max_pending_per_address as u32,
            metrics_listen: s.metrics_listen.map(|a| a.to_string()).unwrap_or_default(),
            max_frame_bytes: s.max_frame_bytes,
            plan_queue_depth: s.plan_queue_depth as u32,
            pipeline_threads: s.pipeline_threads as u32,
            fresh_frame_timeout_ms: ms(s.fresh_frame_timeout),
            shutdown_grace_ms: ms(s.shutdown_grace),
            frame_history: s.frame_history as u32,
            frame_history_bytes: s.frame_history_bytes,
            capture_time_tolerance_ms: ms(s.capture_time_tolerance),
            max_request_timeout_ms: ms(s.max_request_timeout),
            max_requests_per_connection: s.max_requests_per_connection as u32,
            idle_trim_ms: ms(s.idle_trim),
        }
    }
}
