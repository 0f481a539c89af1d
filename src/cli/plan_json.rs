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
//! The binary link does not carry them yet. The protocol's fields keep
//! their names and order; the new ones follow them.

use std::collections::BTreeMap;

use serde::Serialize;
use weldseam::config::procedure::WeavePattern;
use weldseam::pipeline::Plan;
use weldseam::pipeline::along_seam::{JointFigures, Measured};
use weldseam::pipeline::seam_process::{SeamProcess, WaypointProcess};
use weldseam::process::{Pass, PassKind};
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
    process: Option<ProcessJson<'a>>,
}

#[derive(Serialize)]
struct ProcessJson<'a> {
    procedure: &'a str,
    waypoints: Vec<Option<WaypointJson>>,
    cut: Vec<CutJson<'a>>,
}

#[derive(Serialize)]
struct WaypointJson {
    thickness_mm: f64,
    joint_area_mm2: f64,
    crown_area_mm2: f64,
    work_angle_deg: f64,
    travel_angle_deg: f64,
    re_angled: bool,
    passes: Vec<PassJson>,
}

#[derive(Serialize)]
struct PassJson {
    kind: &'static str,
    layer: usize,
    bead: usize,
    lateral_mm: f64,
    height_mm: f64,
    work_angle_deg: f64,
    travel_speed_mm_s: f64,
    wire_feed_m_min: f64,
    voltage_v: f64,
    current_a: f64,
    target_area_mm2: f64,
    deposited_area_mm2: f64,
    weave: Option<WeaveJson>,
}

#[derive(Serialize)]
struct WeaveJson {
    pattern: &'static str,
    amplitude_mm: f64,
    wavelength_mm: f64,
    dwell_mm: f64,
    frequency_hz: f64,
}

#[derive(Serialize)]
struct CutJson<'a> {
    first: usize,
    last: usize,
    rule: &'static str,
    reason: &'a str,
    contact_camera_mm: Option<[f64; 3]>,
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
            .map(|(seam, planned)| SeamJson {
                seam,
                along_seam: planned.along_seam.iter().map(figures).collect(),
                process: planned.process.as_ref().map(process),
            })
            .collect(),
        unplanned: &report.unplanned,
        timing_ms: &report.timing_ms,
        method: &report.method,
        euler_convention: &report.euler_convention,
        points: &report.points,
    }
}

fn process(p: &SeamProcess) -> ProcessJson<'_> {
    ProcessJson {
        procedure: &p.procedure,
        waypoints: p.waypoints.iter().map(|w| w.as_ref().map(waypoint)).collect(),
        cut: p
            .cut
            .iter()
            .map(|c| CutJson {
                first: c.first,
                last: c.last,
                rule: c.rule.id,
                reason: &c.reason,
                contact_camera_mm: c.contact_camera.map(|v| [v.x, v.y, v.z]),
            })
            .collect(),
    }
}

fn waypoint(w: &WaypointProcess) -> WaypointJson {
    WaypointJson {
        thickness_mm: w.thickness_mm,
        joint_area_mm2: w.layout.joint_area_mm2,
        crown_area_mm2: w.layout.crown_area_mm2,
        work_angle_deg: w.work_angle_deg,
        travel_angle_deg: w.travel_angle_deg,
        re_angled: w.re_angled,
        passes: w.layout.passes.iter().map(pass).collect(),
    }
}

fn pass(p: &Pass) -> PassJson {
    let s = p.settings;
    PassJson {
        kind: match p.kind {
            PassKind::Root => "root",
            PassKind::Fill => "fill",
            PassKind::Cap => "cap",
            PassKind::Single => "single",
        },
        layer: p.layer,
        bead: p.bead,
        lateral_mm: p.lateral_mm,
        height_mm: p.height_mm,
        work_angle_deg: p.work_angle_deg,
        travel_speed_mm_s: s.travel_speed_mm_s,
        wire_feed_m_min: s.wire_feed_m_min,
        voltage_v: s.voltage_v,
        current_a: s.current_a,
        target_area_mm2: s.target_area_mm2,
        deposited_area_mm2: s.deposited_area_mm2,
        weave: p.weave.map(|w| WeaveJson {
            pattern: match w.pattern {
                WeavePattern::Triangle => "triangle",
                WeavePattern::Sine => "sine",
                WeavePattern::Trapezoid => "trapezoid",
            },
            amplitude_mm: w.amplitude_mm,
            wavelength_mm: w.wavelength_mm,
            dwell_mm: w.dwell_mm,
            frequency_hz: w.frequency_hz(s.travel_speed_mm_s),
        }),
    }
}
