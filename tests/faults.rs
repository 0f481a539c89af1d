//! Faults that once gave a confident wrong seam (issue 12, item 8), each
//! now answered by the check it taught: a clamp lying across a lap's plate
//! and a part abutting a V-butt plate are refused for what they are, a lap
//! whose upper plate a specular streak cut in two is refused for covering
//! part of the joint (and not taken for an I-butt under `auto`), or,
//! where the streak runs on across the plate under it, planned along both
//! pieces as one plate (cropped round the seam, where the pieces are each
//! large enough to be a butt plate), and a
//! V-groove leaving the image at a grazing angle is planned to the border,
//! and an I-butt whose edge a streak hides over the joint's last stretch is
//! refused for stopping short of where both plates are still seen.
//! Dropout bands wider than the suite's, over 30 to 90 % of a seam, are
//! either fitted on the edge that is left or refused (the `edge_cut_short`
//! gate) for the samples left beyond the line the rest fit, or for samples
//! on two lines.
//! A seam an image border crosses at a shallow angle, cropped in voxels,
//! runs to where it leaves the image.
//! Two came from fresh draws of the suite (`eval --fresh`): a part
//! abutting an I-butt plate, larger in view than the other plate, and a
//! clamp whose end over a lap's upper plate was planned as the lap's edge;
//! both are refused for what the layers and the edges cannot decide. A
//! third, a part touching a lap's lower plate a little lower, put the
//! root under that plate's top, and is now planned on the plate the upper
//! plate stands beside.
//! Each scene is planned as `weldseam eval --suite faults` plans it.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::{EvalRequest, JointAsk, SceneOutcome, Verdict, evaluate_variant};
use weldseam::pipeline::Planner;
use weldseam::pipeline::quality::Gate;
use weldseam::sim::variants::Variant;
use weldseam::sim::{Draw, Fault, fault_suite, hard_suite};

use crate::scenes;

fn planned(name: &str, joint: JointAsk) -> SceneOutcome {
    planned_as(name, joint, "raw")
}

/// `name` made into `variant` and planned as `eval --variant` plans it.
fn planned_as(name: &str, joint: JointAsk, variant: &str) -> SceneOutcome {
    let (_, spec) = fault_suite(Draw::of_scene(name))
        .into_iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no scene {name}"));
    let request = EvalRequest { joint, ..EvalRequest::default() };
    let variant = Variant::parse(variant).expect("a variant");
    // The capture made into the variant, as `eval` makes it.
    let sim = scenes::as_variant(&spec, &CameraModel::default(), &variant);
    evaluate_variant(&Planner::new(Config::default()), name, &spec, sim, &variant, &request)
}

/// A seam-dropout scene of the fault suite with its band widened to
/// `fraction` of the seam, starting `at` of the way along what is left.
fn planned_with_band(name: &str, fraction: f64, at: f64) -> SceneOutcome {
    planned_with_band_by(&Planner::new(Config::default()), name, fraction, at)
}

fn planned_with_band_by(planner: &Planner, name: &str, fraction: f64, at: f64) -> SceneOutcome {
    let (_, mut spec) =
        fault_suite(Draw::Documented).into_iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no scene {name}"));
    let [y0, y1] = spec.seam_range();
    let start = y0 + at * (1.0 - fraction) * (y1 - y0);
    spec.faults = vec![Fault::SeamDropout { along_mm: [start, start + fraction * (y1 - y0)], margin_mm: 2.0 }];
    let sim = scenes::by_default_camera(&spec);
    let request = EvalRequest { joint: JointAsk::AsScene, ..EvalRequest::default() };
    let name = format!("{name} with a dropout over {:.0} % of its seam", 100.0 * fraction);
    evaluate_variant(planner, &name, &spec, sim, &Variant::default(), &request)
}

/// The id of the rule that refused `outcome`.
fn refused_by(outcome: &SceneOutcome) -> &'static str {
    match &outcome.result {
        Err(e) => e.rule.id,
        Ok((err, _)) => panic!("{}: planned {:.1} mm off", outcome.name, err.max_mm),
    }
}

fn refusal(outcome: &SceneOutcome) -> &str {
    match &outcome.verdict {
        Verdict::Refused { reason } => reason,
        other => panic!("{}: {other:?}", outcome.name),
    }
}

/// The id of the rule that refused `outcome`.
fn refusing_rule_id(outcome: &SceneOutcome) -> &'static str {
    match &outcome.result {
        Err(e) => e.rule.id,
        Ok(_) => panic!("{}: planned, not refused", outcome.name),
    }
}

/// Asserts that `name`, planned as its scene's joint, is refused for a
/// plane lying across the plate under it, named a clamp among its causes.
fn assert_refused_as_lying_across(name: &str, variant: &str) {
    let outcome = planned_as(name, JointAsk::AsScene, variant);
    let reason = refusal(&outcome).to_string();
    let rule = outcome.result.as_ref().err().map(|e| e.rule.id);
    assert_eq!(rule, Some("lap.upper_plane_lies_across_lower"), "{variant}: {reason}");
    assert!(reason.contains("clamp"), "{variant}: {reason}");
}

#[test]
fn a_clamp_lying_across_a_laps_plate_is_refused_as_an_object_on_the_workpiece() {
    // Cropped 35 mm round the seam, the clamp's pad is cut to 1.9 times
    // longer than wide, no bar: its top over the upper plate was planned
    // as the lap, 129 mm off, until the pad's footprint was read.
    for variant in ["raw", "cropped:35"] {
        assert_refused_as_lying_across("fault-clamp-lap-02-d500-t20", variant);
    }
}

#[test]
fn a_part_abutting_a_v_butt_plate_is_refused_for_an_opening_the_groove_cannot_have() {
    let outcome = planned("fault-touching-part-v-butt-00-d1000-t30", JointAsk::AsScene);
    assert_eq!(refused_by(&outcome), "groove.opening_off_depth", "{}", refusal(&outcome));
}

#[test]
fn a_part_abutting_an_i_butt_plate_larger_than_the_other_plate_is_refused_as_a_third_plate() {
    let outcome = planned("fault-touching-part-i-butt-00-d667-t0-fresh1", JointAsk::AsScene);
    let reason = refusal(&outcome).to_string();
    let rule = outcome.result.as_ref().err().map(|e| e.rule.id);
    assert_eq!(rule, Some("butt.third_plate_beyond_pair"), "{reason}");
    assert!(reason.contains("region of interest"), "{reason}");
}

#[test]
fn a_part_touching_a_laps_lower_plate_a_little_lower_is_not_taken_for_that_plate() {
    // Fresh draw 7: the part, 78 mm wide and 1.79 mm under the lower
    // plate's top, lies in the lower plate's layer and was the larger of
    // the two. Taken for the lower plate, it put the root 1.79 mm under
    // the lower plate's top all along the seam. The lower plate is the one
    // the upper plate stands beside.
    for variant in ["raw", "voxel:1"] {
        let outcome = planned_as("fault-touching-part-lap-00-d1000-t10-fresh7", JointAsk::AsScene, variant);
        let (err, plan) = outcome.result.as_ref().unwrap_or_else(|e| panic!("{variant}: refused: {e:?}"));
        assert_eq!(outcome.verdict, Verdict::WithinBar, "{variant}: {err:?}");
        // The plate under the upper one is 4.06 mm thick (the truth's).
        let step = plan.seams[0].quality.as_ref().and_then(|q| q.lap_step_mm).expect("a lap's step");
        assert!((step - 4.06).abs() < 0.1, "{variant}: lap step {step:.2} mm");
    }
}

#[test]
fn a_part_touching_an_i_butt_whose_gap_voxels_close_is_not_taken_for_its_second_plate() {
    // Fresh draw 13 at 1 mm voxels: the I-butt's gap (0.53 mm) is under
    // two voxels, so its two plates are one cluster, and the part touching
    // plate B, 1.54 mm proud of it, was taken for the second plate: a seam
    // planned 102 mm off, its gap "measured" at 0.29 to 0.37 mm with the
    // points 0.84 mm apart. A gap under a point spacing is not resolved;
    // the seam is refused for it. At the raw frame's spacing the gap is
    // seen, and so are the three plates in a row, refused as such.
    let name = "fault-touching-part-i-butt-00-d667-t0-fresh13";
    let voxels = planned_as(name, JointAsk::AsScene, "voxel:1");
    let (gate, reason) = match &voxels.result {
        Err(e) => (e.gate, e.reason.clone()),
        Ok((_, plan)) => panic!("voxel:1: planned {:?}", plan.seams.first().map(|s| s.start_camera)),
    };
    assert_eq!(voxels.result.as_ref().err().map(|e| e.rule.id), Some("butt.gap_unresolved"), "{reason}");
    assert_eq!(gate, Some(Gate::GapUnresolved), "{reason}");
    assert!(reason.contains("0.84 mm point spacing"), "{reason}");
    let raw = planned_as(name, JointAsk::AsScene, "raw");
    let rule = raw.result.as_ref().err().map(|e| e.rule.id);
    assert_eq!(rule, Some("butt.third_plate_beyond_pair"), "raw: {}", refusal(&raw));
}

#[test]
fn a_laps_seam_ends_where_its_lower_plate_ends_not_where_its_upper_plate_does() {
    // Hard draw 13: a lap seen at 41° whose upper plate runs on past the
    // lower plate's end, over the table. The foot of the upper plate's side
    // face lies in the lower plate's plane and was taken for the lower
    // plate's edge 9.9 mm past its end: the seam started 9.32 mm early.
    // Beside that stretch the pixels just inside the lower edge, in view,
    // see no lower plate (its shadow on the table, far below), and the
    // seam ends where the lower plate was last seen
    // (`lap.seam_ends_where_lower_plate_ends`).
    let name = "hard-lap-01-d524-t41-fill-lower-side-s0.11-dr1.4-fresh13";
    let (_, spec) =
        hard_suite(Draw::of_scene(name)).into_iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no {name}"));
    let sim = scenes::by_default_camera(&spec);
    let planner = Planner::new(Config::default());
    let outcome = evaluate_variant(&planner, name, &spec, sim, &Variant::default(), &EvalRequest::default());
    let (err, _) = outcome.result.as_ref().unwrap_or_else(|e| panic!("refused: {e}"));
    assert_eq!(outcome.verdict, Verdict::WithinBar, "{err:?}");
    assert!(err.start_mm < 0.5 && err.end_mm < 0.5, "{err:?}");
}

#[test]
fn a_clamps_end_over_a_laps_upper_plate_is_refused_as_lying_across_it() {
    // Its end was planned as the lap's edge, 125 mm off. The weld-edge
    // stage refuses it too (its side faces the plate for longer than its
    // end); the background stage, which sees the plate on both of its
    // sides, says so first.
    assert_refused_as_lying_across("fault-clamp-lap-00-d833-t0-fresh1", "raw");
}

#[test]
fn a_clamp_over_a_laps_plate_seen_round_its_end_is_refused_as_lying_across_it() {
    // The plate the clamp lies on is one cluster round the clamp's end,
    // and the clamp's side was planned as a lap's edge, 164 mm off.
    assert_refused_as_lying_across("fault-clamp-lap-00-d833-t0-fresh2", "raw");
}

#[test]
fn a_laps_lower_plate_seen_past_the_upper_plates_end_and_as_a_sliver_beside_it_is_refused() {
    // The sliver's lines separate no centroids, and the upper plate's end
    // was planned as the lap's edge, 91 mm off.
    let outcome = planned("fault-barely-in-view-lap-02-d500-t20-fresh2", JointAsk::AsScene);
    assert_eq!(refused_by(&outcome), "lap.lower_plate_beside_other_edge", "{}", refusal(&outcome));
}

#[test]
fn a_lap_plate_cut_by_a_streak_is_refused_for_coverage_and_not_found_as_a_butt_joint() {
    let name = "fault-streaks-lap-01-d833-t20";
    let outcome = planned(name, JointAsk::AsScene);
    assert_eq!(refusing_rule_id(&outcome), "seam.joint_coverage", "{}", refusal(&outcome));
    // Under `auto` the piece the streak cut off the upper plate, beside
    // it, leaves the joint type open: a butt pair or a lap cut in two.
    let auto = planned(name, JointAsk::Auto);
    assert_eq!(refusing_rule_id(&auto), "joint.plate_and_piece_over_lower_plane", "{}", refusal(&auto));
    assert_eq!(auto.result.as_ref().err().and_then(|e| e.gate), Some(Gate::JointUnknown), "{}", refusal(&auto));
}

#[test]
fn a_lap_plate_cut_by_a_streak_running_on_across_the_plate_under_it_is_one_plate() {
    // Fresh draw 1, cropped 25 mm round the seam: the streak cuts the
    // upper plate into two pieces, each large enough to be a plate, and
    // runs on across the lower plate. Read as two butt plates, `auto`
    // planned the 0.7 mm break as an I-butt's gap, 275 mm off the lap; a
    // gap between plates ends where they do, a break in the image does
    // not, so both requests plan the lap along both pieces.
    for joint in [JointAsk::AsScene, JointAsk::Auto] {
        let outcome = planned_as("fault-streaks-lap-01-d833-t20-fresh1", joint, "cropped:25");
        assert_eq!(outcome.verdict, Verdict::WithinBar, "{joint:?}: {:?}", outcome.result.as_ref().map(|(e, _)| e));
    }
}

#[test]
fn a_groove_leaving_the_image_at_a_grazing_angle_is_planned_to_the_border() {
    // `seam.end_at_image_border` carries the edges to the border, where
    // the strips stop a rim's depth short of it.
    let outcome = planned("fault-barely-in-view-v-butt-01-d1000-t10", JointAsk::AsScene);
    assert_eq!(outcome.verdict, Verdict::WithinBar, "{:?}", outcome.result.as_ref().map(|(e, _)| e));
}

#[test]
fn a_lap_leaving_the_image_obliquely_is_planned_to_where_its_joint_leaves_it() {
    // Fresh draw 1, cropped round the seam. The lower plate barely in
    // view: its edge, read where its points stop beside the root, leaves
    // the image 6.8 mm before the root does, and the seam stopped 6.4 mm
    // short. Streaks across the plates: the rows read inside the upper
    // plate's edge run 5 mm past where that edge leaves the image, so the
    // root must not be carried to them.
    for name in ["fault-barely-in-view-lap-02-d500-t20-fresh1", "fault-streaks-lap-01-d833-t20-fresh1"] {
        let outcome = planned_as(name, JointAsk::AsScene, "cropped:35");
        assert_eq!(outcome.verdict, Verdict::WithinBar, "{name}: {:?}", outcome.result.as_ref().map(|(e, _)| e));
    }
}

#[test]
fn a_seam_an_image_border_crosses_at_a_shallow_angle_is_planned_to_where_it_leaves_the_image() {
    // Cropped round the seam in 1 mm voxels, the plate barely in view
    // thins to nothing beside its edge along a border crossing the seam
    // at a shallow angle (a sine of 0.19 and 0.18 on the first two): its
    // rim's rows end 3.8 mm (i-butt-01) short of where the edge leaves
    // the view, and the seams stopped 2.6,
    // 2.0 and 9.2 mm short. An end moves to a border that lies a few
    // spacings from it across the border, however far along the edge.
    for name in [
        "fault-barely-in-view-i-butt-01-d667-t20",
        "fault-barely-in-view-lap-01-d1000-t30",
        "fault-barely-in-view-lap-02-d500-t20-fresh1",
    ] {
        let outcome = planned_as(name, JointAsk::AsScene, "cropped:35,voxel:1,metres");
        assert_eq!(outcome.verdict, Verdict::WithinBar, "{name}: {:?}", outcome.result.as_ref().map(|(e, _)| e));
    }
}

#[test]
fn plates_seen_past_where_a_seam_leaves_the_image_do_not_refuse_it_as_cut_short() {
    // Fresh draw 2: the image's border crosses a lap's seam obliquely. The
    // upper edge ran on 2.2 mm past where its line leaves the image (the
    // seam planned 2.15 mm past the joint in view); held to the view, the
    // plates' pixels just inside the edges, still in view past it, were
    // read as the joint going on, and `seam.stops_short_of_joint` refused.
    let outcome = planned("fault-touching-part-lap-03-d833-t20-fresh2", JointAsk::AsScene);
    assert_eq!(outcome.verdict, Verdict::WithinBar, "{:?}", outcome.result.as_ref().map(|(e, _)| e));
}

#[test]
fn an_edge_lost_under_a_streak_while_both_plates_go_on_is_refused_not_cut_short() {
    let outcome = planned("fault-streaks-i-butt-00-d1000-t20", JointAsk::AsScene);
    assert_eq!(refusing_rule_id(&outcome), "seam.stops_short_of_joint", "{}", refusal(&outcome));
}

#[test]
fn a_lap_whose_edge_a_dropout_cuts_short_along_most_of_its_seam_is_refused_not_planned_2_mm_off() {
    // The upper plate's edge 2 mm short along 70 to 80 % of the seam: its
    // samples lie on the receded line mostly. Least squares planned the
    // first 2.7 mm off (its residual refused the others); a fit that trims
    // the minority planned all three 2.0 to 2.7 mm off.
    for (name, fraction, at) in [
        ("fault-seam-dropout-lap-02-d1000-t10", 0.7, 0.0),
        ("fault-seam-dropout-lap-01-d833-t20", 0.7, 0.5),
        ("fault-seam-dropout-lap-00-d667-t30", 0.8, 0.0),
    ] {
        let outcome = planned_with_band(name, fraction, at);
        let reason = refusal(&outcome);
        assert_eq!(refusing_rule_id(&outcome), "edge.samples_beyond_line", "{}: {reason}", outcome.name);
        let gate = outcome.result.as_ref().err().and_then(|e| e.gate);
        assert_eq!(gate, Some(Gate::EdgeCutShort), "{}: {reason}", outcome.name);
    }
}

#[test]
fn a_cut_short_edge_named_in_warn_only_is_planned_with_the_warning_on_its_seam() {
    // The gate is a figure of the seam like the others: a cell that would
    // rather have the seam and a warning can say so, and the warning
    // carries the share and the limit.
    let mut config = Config::default();
    config.quality.warn_only = vec!["edge_cut_short".into()];
    let outcome = planned_with_band_by(&Planner::new(config), "fault-seam-dropout-lap-02-d1000-t10", 0.7, 0.0);
    let (_, plan) = outcome.result.as_ref().unwrap_or_else(|e| panic!("{}: {e}", outcome.name));
    let warnings: Vec<_> = plan.seams.iter().flat_map(|s| &s.warnings).collect();
    assert_eq!(warnings.iter().map(|w| w.rule.id).collect::<Vec<_>>(), ["edge.samples_beyond_line"], "{warnings:?}");
    assert_eq!(warnings[0].gate, Gate::EdgeCutShort);
    assert!(warnings[0].value > warnings[0].limit && warnings[0].limit == 0.1, "{warnings:?}");
}

#[test]
fn a_dropout_over_a_third_of_a_seam_is_fitted_on_the_edge_left() {
    // Least squares averaged the cut-short third in and the residual gate
    // refused both.
    for (name, at) in [("fault-seam-dropout-lap-00-d667-t30", 0.0), ("fault-seam-dropout-v-butt-01-d833-t0", 0.5)] {
        let outcome = planned_with_band(name, 0.3, at);
        assert_eq!(
            outcome.verdict,
            Verdict::WithinBar,
            "{}: {:?}",
            outcome.name,
            outcome.result.as_ref().map(|(e, _)| e)
        );
    }
}

#[test]
fn a_lap_edge_on_two_lines_is_refused_whether_the_fit_runs_between_them_or_follows_one() {
    // The upper plate's edge 2 mm short along the first half of the seam:
    // the fit ran between the two runs, its residual under the gate's
    // limit, and planned the seam 2 mm off. Along 90 % of it from 5 %: the
    // fit followed the cut-short run, with the true edge's 5 % at each end
    // beyond it, 9 % in all, just inside the share the gate allows.
    for (fraction, at) in [(0.5, 0.0), (0.9, 0.5)] {
        let outcome = planned_with_band("fault-seam-dropout-lap-01-d833-t20", fraction, at);
        let reason = refusal(&outcome);
        assert_eq!(refusing_rule_id(&outcome), "edge.samples_on_two_lines", "{}: {reason}", outcome.name);
        let gate = outcome.result.as_ref().err().and_then(|e| e.gate);
        assert_eq!(gate, Some(Gate::EdgeCutShort), "{}: {reason}", outcome.name);
    }
}

/// Every seam-dropout tuning scene with its band widened to 30 to 90 % of
/// the seam, in the middle or from the start, planned from raw frames:
/// no confident wrong seam. Under a minute in release;
/// run with `cargo test --release --test tests faults::dropout_bands --
/// --ignored --nocapture`, which prints each outcome (docs/ACCURACY.md,
/// "Dropout bands wider than the suite's").
#[test]
#[ignore = "72 scenes: run in release by hand"]
fn dropout_bands_of_every_width_give_no_confident_wrong_seam() {
    let scenes = [
        "lap-00-d667-t30",
        "lap-01-d833-t20",
        "lap-02-d1000-t10",
        "v-butt-01-d833-t0",
        "i-butt-00-d1000-t20",
        "i-butt-01-d500-t10",
    ];
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_test_writer()
        .try_init();
    let mut wrong = Vec::new();
    for scene in scenes {
        let name = format!("fault-seam-dropout-{scene}");
        for fraction in [0.3, 0.5, 0.6, 0.7, 0.8, 0.9] {
            for at in [0.5, 0.0] {
                let outcome = planned_with_band(&name, fraction, at);
                println!("{} from {at}: {:?}", outcome.name, outcome.verdict);
                if matches!(outcome.verdict, Verdict::ConfidentWrong { .. }) {
                    wrong.push(outcome.name);
                }
            }
        }
    }
    assert!(wrong.is_empty(), "confident wrong: {wrong:?}");
}

#[test]
fn a_v_groove_whose_bevels_are_not_seen_down_to_its_root_needs_its_depth() {
    // A steep, noisy view of a plates-filling V-groove: the bevel faces
    // thin out before the groove's root, so no face shows where it is and,
    // under `auto` with no depth given, the weld's height is unknown. Given
    // the depth, the same frame plans within the bar.
    let name = "hard-v-butt-02-d548-t21-fill-s0.08-dr1.2";
    let (_, spec) =
        hard_suite(Draw::of_scene(name)).into_iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no {name}"));
    let sim = scenes::by_default_camera(&spec);
    let planner = Planner::new(Config::default());
    let auto = EvalRequest { joint: JointAsk::Auto, ..EvalRequest::default() };
    let outcome = evaluate_variant(&planner, name, &spec, sim, &Variant::default(), &auto);
    let err = outcome.result.as_ref().map(|(e, _)| e).unwrap_err();
    assert_eq!(err.rule.id, "butt.groove_depth_unmeasured", "{name}: {err}");
    let typed = evaluate_variant(&planner, name, &spec, sim, &Variant::default(), &EvalRequest::default());
    assert_eq!(typed.verdict, Verdict::WithinBar, "{name}: with its depth given: {:?}", typed.verdict);
}
