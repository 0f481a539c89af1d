//! Faults that once gave a confident wrong seam (issue 12, item 8), each
//! now answered by the check it taught: a clamp lying across a lap's plate
//! and a part abutting a V-butt plate are refused for what they are, a lap
//! whose upper plate a specular streak cut in two is refused for covering
//! part of the joint (and not taken for an I-butt under `auto`), and a
//! V-groove leaving the image at a grazing angle is planned to the border,
//! and an I-butt whose edge a streak hides over the joint's last stretch is
//! refused for stopping short of where both plates are still seen.
//! Each scene is planned as `weldseam eval --suite faults` plans it.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::{EvalRequest, JointAsk, SceneOutcome, Verdict, evaluate_variant};
use weldseam::pipeline::Planner;
use weldseam::sim::variants::Variant;
use weldseam::sim::{fault_suite, simulate};

fn planned(name: &str, joint: JointAsk) -> SceneOutcome {
    let (_, spec) = fault_suite().into_iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no scene {name}"));
    let sim = simulate(&spec, &CameraModel::default());
    let request = EvalRequest { joint, ..EvalRequest::default() };
    evaluate_variant(&Planner::new(Config::default()), name, &spec, &sim, &Variant::default(), &request)
}

fn refusal(outcome: &SceneOutcome) -> &str {
    match &outcome.verdict {
        Verdict::Refused { reason } => reason,
        other => panic!("{}: {other:?}", outcome.name),
    }
}

#[test]
fn a_clamp_lying_across_a_laps_plate_is_refused_as_an_object_on_the_workpiece() {
    let reason = refusal(&planned("fault-clamp-lap-02-d500-t20", JointAsk::AsScene)).to_string();
    assert!(reason.contains("lies across the plane under it") && reason.contains("clamp"), "{reason}");
}

#[test]
fn a_part_abutting_a_v_butt_plate_is_refused_for_an_opening_the_groove_cannot_have() {
    let reason = refusal(&planned("fault-touching-part-v-butt-00-d1000-t30", JointAsk::AsScene)).to_string();
    assert!(reason.contains("mm apart, but a V-groove") && reason.contains("not this groove's"), "{reason}");
}

#[test]
fn a_lap_plate_cut_by_a_streak_is_refused_for_coverage_and_not_found_as_a_butt_joint() {
    let name = "fault-streaks-lap-01-d833-t20";
    let reason = refusal(&planned(name, JointAsk::AsScene)).to_string();
    assert!(reason.contains("of joint both plates are seen beside"), "{reason}");
    let reason = refusal(&planned(name, JointAsk::Auto)).to_string();
    assert!(reason.contains("cannot be told"), "{reason}");
}

#[test]
fn a_groove_leaving_the_image_at_a_grazing_angle_is_planned_to_the_border() {
    let outcome = planned("fault-barely-in-view-v-butt-01-d1000-t10", JointAsk::AsScene);
    assert_eq!(outcome.verdict, Verdict::WithinBar, "{:?}", outcome.result.as_ref().map(|(e, _)| e));
}

#[test]
fn an_edge_lost_under_a_streak_while_both_plates_go_on_is_refused_not_cut_short() {
    let reason = refusal(&planned("fault-streaks-i-butt-00-d1000-t20", JointAsk::AsScene)).to_string();
    assert!(reason.contains("beyond the seam's") && reason.contains("a weld edge was lost there"), "{reason}");
}
