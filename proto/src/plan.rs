//! A planning result: seams with base-frame waypoints, quality figures and
//! per-stage timings. The JSON form is a contract for scripts calling
//! `weldseam plan --json`; field names only ever get added, never renamed.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A plane weld joint type; JSON and wire names are `v_butt`, `i_butt`,
/// `lap`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Joint {
    VButt,
    IButt,
    Lap,
}

/// One waypoint in the robot base frame: position in mm, torch
/// orientation as the configured Euler angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    pub xyz: [f64; 3],
    pub rpy_deg: [f64; 3],
}

/// One planned seam.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Seam {
    pub joint: Joint,
    /// Ordered along the seam, base frame.
    pub waypoints: Vec<Waypoint>,
    /// The seam's ends and the plate normal (into the workpiece), camera frame.
    pub start_camera: [f64; 3],
    pub end_camera: [f64; 3],
    pub normal_camera: [f64; 3],
    pub length_mm: f64,
    /// RMS residual of each weld edge's least-squares fit, mm.
    pub edge_fit_rms_mm: [f64; 2],
    /// Samples each edge fit used, and how many outliers it dropped.
    pub edge_samples: [u32; 2],
    pub edge_samples_dropped: [u32; 2],
}

/// Point counts through the pipeline.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCounts {
    pub valid: u64,
    pub plane: u64,
    pub clusters: u32,
    pub plates: [u64; 2],
    pub edges: [u64; 2],
    pub edge_lines: u32,
}

/// The result of planning one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanResult {
    pub seams: Vec<Seam>,
    /// Milliseconds per pipeline stage, plus `total`.
    pub timing_ms: BTreeMap<String, f64>,
    /// `robust` or `paper`.
    pub method: String,
    /// The Euler convention of every `rpy_deg`.
    pub euler_convention: String,
    pub points: PointCounts,
}
