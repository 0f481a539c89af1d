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
    /// How much of the visible joint the seam spans and how much of the
    /// seam its edges were seen along; absent from the paper's method.
    pub coverage: Option<SeamCoverage>,
}

/// A seam's coverage of the joint the camera saw.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SeamCoverage {
    /// The fraction of the seam's length each weld edge was seen along.
    pub edge: [f64; 2],
    /// The fraction of the visible joint (where both plates are seen
    /// beside the seam) the seam spans.
    pub joint: f64,
    /// The visible joint's length, mm.
    pub visible_joint_mm: f64,
    /// How much of the seam runs beyond the visible joint, mm.
    pub beyond_mm: f64,
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
