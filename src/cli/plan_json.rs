//! What `plan --json` prints of a seam beyond the protocol's seam:
//!
//! `along_seam`: the joint's figures at every waypoint, one object per
//! waypoint in the waypoints' order, each figure `{"value", "sigma"}` (its
//! standard error) or null where the points near the waypoint do not give
//! it; empty for a seam whose joint is not measured along it.
//!
//! The binary link does not carry it yet. The protocol's fields keep
//! their names and order; the new ones follow them.

use std::collections::BTreeMap;

use serde::Serialize;
use weldseam::pipeline::Plan;
use weldseam::pipeline::along_seam::{JointFigures, Measured};
use weldseam_proto::plan::{PlanResult, PointCounts, Seam, UnplannedJoint};

/// [`PlanResult`] as `plan --json` prints it.
#[derive(Serialize)]
pub struct PlanJson<'a> {
    seams: Vec<SeamJson<'a>>,
    unplanned: &'a [UnplannedJoint],
    timing_ms: &'a BTreeMap<String, f64>,
    method: &'a str,
    euler_convention: &'a str,
    points: &'a PointCounts,
}

#[derive(Serialize)]
struct SeamJson<'a> {
    #[serde(flatten)]
    seam: &'a Seam,
    along_seam: Vec<FiguresJson>,
}

#[derive(Serialize)]
struct FiguresJson {
    gap_mm: Option<MeasuredJson>,
    high_low_mm: Option<MeasuredJson>,
    groove_area_mm2: Option<MeasuredJson>,
    groove_angle_deg: Option<f64>,
    groove_depth_mm: Option<f64>,
    lap_step_mm: Option<MeasuredJson>,
}

#[derive(Serialize)]
struct MeasuredJson {
    value: f64,
    sigma: f64,
}

/// The report of `plan`, each seam with its figures along the seam.
pub fn plan_json<'a>(report: &'a PlanResult, plan: &'a Plan) -> PlanJson<'a> {
    let measured = |m: Option<Measured>| m.map(|m| MeasuredJson { value: m.value, sigma: m.sigma });
    let figures = |f: &JointFigures| FiguresJson {
        gap_mm: measured(f.gap_mm),
        high_low_mm: measured(f.high_low_mm),
        groove_area_mm2: measured(f.groove_area_mm2),
        groove_angle_deg: f.groove_angle_deg,
        groove_depth_mm: f.groove_depth_mm,
        lap_step_mm: measured(f.lap_step_mm),
    };
    PlanJson {
        seams: report
            .seams
            .iter()
            .zip(&plan.seams)
            .map(|(seam, planned)| SeamJson { seam, along_seam: planned.along_seam.iter().map(figures).collect() })
            .collect(),
        unplanned: &report.unplanned,
        timing_ms: &report.timing_ms,
        method: &report.method,
        euler_convention: &report.euler_convention,
        points: &report.points,
    }
}
