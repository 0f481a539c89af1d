//! What `plan --json` prints of a seam beyond the protocol's seam:
//!
//! - `along_seam`: the joint's figures at every waypoint, one object per
//!   waypoint in the waypoints' order, each figure `{"value", "sigma"}`
//!   (its standard error) or null where the points near the waypoint do
//!   not give it;
//! - `process`: with `process.procedure` configured, per waypoint the
//!   passes that weld it (each with its aim offset, work angle, arc
//!   settings and weave) and the torch's angles, null where the waypoint
//!   is cut; and the stretches cut, each with its rule, its reason and,
//!   for a torch blocked, the point of contact. Null without a procedure.
//!
//! Both are the protocol's types ([`weldseam_proto::along_seam`]), which
//! the binary link carries behind its `along_seam` capability; the report
//! must have them set ([`weldseam::convert::to_proto::add_along_seam`]).
//! The protocol's fields keep their names and order; these follow them.

use std::collections::BTreeMap;

use serde::Serialize;
use weldseam_proto::along_seam::{JointFigures, SeamProcess};
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
    along_seam: &'a [JointFigures],
    process: Option<&'a SeamProcess>,
}

/// The report of `plan`, each seam with its figures along the seam.
pub fn plan_json(report: &PlanResult) -> PlanJson<'_> {
    PlanJson {
        seams: report
            .seams
            .iter()
            .map(|seam| SeamJson {
                seam,
                along_seam: seam.along_seam.as_deref().unwrap_or_default(),
                process: seam.process.as_ref(),
            })
            .collect(),
        unplanned: &report.unplanned,
        timing_ms: &report.timing_ms,
        method: &report.method,
        euler_convention: &report.euler_convention,
        points: &report.points,
    }
}
