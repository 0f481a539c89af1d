//! The joint's figures along each seam and its weld process in the
//! protocol's form (part of [`super::to_proto`]): what the binary link
//! carries behind the `along_seam` capability, what `plan --json` prints
//! beside each seam and what the debug set's profile picture is drawn
//! from. The figures change only their form here.

use weldseam_proto::along_seam as proto;
use weldseam_proto::plan::PlanResult;

use crate::config::procedure::WeavePattern;
use crate::pipeline::Plan;
use crate::pipeline::along_seam::{JointFigures, Measured};
use crate::pipeline::seam_process::{CutStretch, SeamProcess, WaypointProcess};
use crate::process::{Pass, PassKind};

/// Sets every seam's figures and process in `report`, the report of
/// `plan` ([`super::to_proto::plan_result`] keeps the plan's seams in
/// their order).
pub fn add_along_seam(report: &mut PlanResult, plan: &Plan) {
    for (seam, planned) in report.seams.iter_mut().zip(&plan.seams) {
        seam.along_seam = Some(planned.along_seam.iter().map(figures).collect());
        seam.process = planned.process.as_ref().map(process);
    }
}

fn measured(m: Option<Measured>) -> Option<proto::Measured> {
    m.map(|m| proto::Measured { value: m.value, sigma: m.sigma })
}

pub fn figures(f: &JointFigures) -> proto::JointFigures {
    proto::JointFigures {
        gap_mm: measured(f.gap_mm),
        high_low_mm: measured(f.high_low_mm),
        groove_area_mm2: measured(f.groove_area_mm2),
        groove_angle_deg: f.groove_angle_deg,
        groove_depth_mm: f.groove_depth_mm,
        lap_step_mm: measured(f.lap_step_mm),
    }
}

pub fn process(p: &SeamProcess) -> proto::SeamProcess {
    proto::SeamProcess {
        procedure: p.procedure.clone(),
        waypoints: p.waypoints.iter().map(|w| w.as_ref().map(waypoint)).collect(),
        cut: p.cut.iter().map(cut).collect(),
    }
}

fn cut(c: &CutStretch) -> proto::CutStretch {
    proto::CutStretch {
        first: c.first as u64,
        last: c.last as u64,
        rule: c.rule.id.into(),
        reason: c.reason.clone(),
        contact_camera_mm: c.contact_camera.map(|v| [v.x, v.y, v.z]),
    }
}

fn waypoint(w: &WaypointProcess) -> proto::WaypointProcess {
    proto::WaypointProcess {
        thickness_mm: w.thickness_mm,
        joint_area_mm2: w.layout.joint_area_mm2,
        crown_area_mm2: w.layout.crown_area_mm2,
        work_angle_deg: w.work_angle_deg,
        travel_angle_deg: w.travel_angle_deg,
        re_angled: w.re_angled,
        passes: w.layout.passes.iter().map(pass).collect(),
    }
}

fn pass(p: &Pass) -> proto::Pass {
    let s = p.settings;
    // A layout has a handful of layers and beads; a count past u32 is
    // not one the planner makes.
    let count = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
    proto::Pass {
        kind: match p.kind {
            PassKind::Root => proto::PassKind::Root,
            PassKind::Fill => proto::PassKind::Fill,
            PassKind::Cap => proto::PassKind::Cap,
            PassKind::Single => proto::PassKind::Single,
        },
        layer: count(p.layer),
        bead: count(p.bead),
        lateral_mm: p.lateral_mm,
        height_mm: p.height_mm,
        work_angle_deg: p.work_angle_deg,
        travel_speed_mm_s: s.travel_speed_mm_s,
        wire_feed_m_min: s.wire_feed_m_min,
        voltage_v: s.voltage_v,
        current_a: s.current_a,
        target_area_mm2: s.target_area_mm2,
        deposited_area_mm2: s.deposited_area_mm2,
        weave: p.weave.map(|w| proto::Weave {
            pattern: match w.pattern {
                WeavePattern::Triangle => proto::WeavePattern::Triangle,
                WeavePattern::Sine => proto::WeavePattern::Sine,
                WeavePattern::Trapezoid => proto::WeavePattern::Trapezoid,
            },
            amplitude_mm: w.amplitude_mm,
            wavelength_mm: w.wavelength_mm,
            dwell_mm: w.dwell_mm,
            frequency_hz: w.frequency_hz(s.travel_speed_mm_s),
        }),
    }
}
