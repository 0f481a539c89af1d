//! The figures of one plan's trace, stage by stage: what `weldseam plan
//! --debug DIR` writes as `trace.json` beside its pictures, and what the
//! daemon keeps for its last plans (`[debug]`). Points are in the camera
//! frame, millimetres. Field names only ever get added, never renamed.

use serde::{Deserialize, Serialize};

use crate::plan::{Joint, PlanResult, Refusal, SeamQuality};

/// What one plan found at each stage; a stage that did not run leaves its
/// fields empty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanTrace {
    /// The joint planned: the one requested, or the one `auto` found;
    /// absent when `auto` was refused before deciding.
    pub joint: Option<Joint>,
    pub groove_depth_mm: Option<f64>,
    /// `robust` or `paper`.
    pub method: String,
    /// The plan exactly as `plan --json` prints it, when there is one.
    pub plan: Option<PlanResult>,
    /// Why the plan was refused, exactly as `plan --json` prints it.
    pub error: Option<Refusal>,
    pub points: TracePoints,
    /// The workpiece's dominant normal (robust method).
    pub dominant_normal: Option<[f64; 3]>,
    /// The plane clusters large enough to be a plate.
    pub planes: Vec<TracePlane>,
    /// The RANSAC edge lines, per plate in the order found.
    pub edge_lines: Vec<TraceLine>,
    /// The two refitted weld edges.
    pub weld_edges: Vec<TraceEdge>,
    /// The weld curve's planned stretch.
    pub weld: Option<TraceWeld>,
    /// The waypoints in the camera frame, in travel order.
    pub waypoints_camera: Vec<[f64; 3]>,
    /// The seam's quality figures, also when a gate refused it.
    pub quality: Option<SeamQuality>,
}

/// Point counts through the stages.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TracePoints {
    /// Valid points of the frame the stages saw.
    pub valid: u64,
    /// Points that passed the plane point criterion.
    pub plane: u64,
    /// Each plate's points, once the plates are chosen.
    pub plates: Option<[u64; 2]>,
    /// Each plate's edge points.
    pub edges: [u64; 2],
    /// The samples each weld edge was fitted to.
    pub fit_samples: [u64; 2],
}

/// A plane cluster.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TracePlane {
    pub label: u32,
    pub points: u64,
    pub area_mm2: f64,
    /// Unit normal and offset of its least-squares plane `n·p = offset`.
    pub normal: [f64; 3],
    pub offset_mm: f64,
    pub centroid: [f64; 3],
    /// 1 or 2 when it is chosen as that plate.
    pub plate: Option<u8>,
}

/// A RANSAC edge line as the segment its inliers span.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceLine {
    /// 1 or 2: the plate whose edge points it was found among.
    pub plate: u8,
    /// Its place in the order its run found the lines.
    pub rank: u32,
    pub inliers: u64,
    pub ends: [[f64; 3]; 2],
    /// Chosen as a weld edge.
    pub picked: bool,
}

/// A refitted weld edge.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceEdge {
    pub rms_mm: f64,
    pub samples: u64,
    pub dropped: u64,
    /// The fitted curve's ends.
    pub ends: [[f64; 3]; 2],
}

/// The weld curve over the stretch planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceWeld {
    pub ends: [[f64; 3]; 2],
    /// The plate normal, into the workpiece.
    pub normal: [f64; 3],
    pub length_mm: f64,
}
