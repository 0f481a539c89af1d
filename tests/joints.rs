//! The joint checked or found, and the groove measured (issue 12, items 3
//! to 5): `auto` names each joint from the frame and says why, the wrong
//! joint is refused for what the frame shows, a V-groove's depth is
//! measured where it is not given and checked where it is, in the library
//! and in `plan --json`.

use std::process::Command;

use weldseam::config::Config;
use weldseam::eval::seam_error;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::quality::Gate;
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::sim::{JointGeometry, SceneSpec, Simulation, demo_scene};

use crate::scenes;

fn rendered(joint: JointType) -> (SceneSpec, &'static Simulation) {
    let spec = demo_scene(joint);
    let sim = scenes::by_default_camera(&spec);
    (spec, sim)
}

#[test]
fn auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar() {
    // A butt joint's type is named by `butt.type_from_groove`: a V-butt
    // for its bevels, an I-butt for its square gap.
    for joint in JointType::ALL {
        let (spec, sim) = rendered(joint);
        let plan = Planner::new(Config::default())
            .plan(&sim.cloud, &PlanRequest::new(RequestedJoint::Auto, None, sim.pose))
            .unwrap_or_else(|e| panic!("{joint}: {e}"));
        let seam = &plan.seams[0];
        assert_eq!(seam.joint, joint);
        let evidence = seam.joint_evidence.as_deref().unwrap_or_default();
        let error = seam_error(&sim.truth, seam).unwrap();
        assert!(error.passes(), "{joint}: {error:?}");
        let q = seam.quality.unwrap();
        match spec.joint {
            JointGeometry::VButt { groove_depth_mm, groove_angle_deg, .. } => {
                assert!(evidence.contains("a V-groove"), "{evidence}");
                let depth = q.groove_depth_mm.expect("the demo groove's root is in view");
                assert!((depth - groove_depth_mm).abs() < 0.3, "depth {depth} against {groove_depth_mm}");
                let angle = q.groove_angle_deg.unwrap();
                assert!((angle - groove_angle_deg).abs() < 2.0, "angle {angle} against {groove_angle_deg}");
            }
            JointGeometry::IButt { .. } => {
                assert!(evidence.contains("a square gap"), "{evidence}");
                assert_eq!((q.groove_depth_mm, q.groove_angle_deg), (None, None));
            }
            JointGeometry::Lap { .. } => assert!(evidence.contains("an upper plate"), "{evidence}"),
            JointGeometry::Tee { .. } | JointGeometry::Corner { .. } => {
                unreachable!("only the planned joints are planned here")
            }
        }
    }
}

#[test]
fn the_wrong_joint_is_refused_for_what_the_frame_shows() {
    let planner = Planner::new(Config::default());
    // Each refusal by the rule that made it: the groove probe's for a
    // butt joint of the other type, the layers' for a lap or a butt.
    for (seen, asked, rule) in [
        (JointType::VButt, JointType::IButt, "groove.bevels_in_i_butt"),
        (JointType::IButt, JointType::VButt, "groove.no_bevel_for_v_butt"),
        (JointType::Lap, JointType::VButt, "joint.looks_like_lap"),
        (JointType::VButt, JointType::Lap, "lap.no_plate_step"),
    ] {
        let (_, sim) = rendered(seen);
        let refused = planner.plan(&sim.cloud, &PlanRequest::new(asked, Some(5.0), sim.pose)).unwrap_err();
        assert_eq!(refused.rule.id, rule, "{seen} asked as {asked}: {refused}");
        if asked != JointType::Lap {
            assert_eq!(refused.gate, Some(Gate::JointMismatch), "{seen} asked as {asked}: {refused}");
        }
    }
}

#[test]
fn a_groove_depth_given_is_checked_against_the_one_measured() {
    let (spec, sim) = rendered(JointType::VButt);
    let truth = spec.joint.groove_depth_mm().unwrap();
    let planner = Planner::new(Config::default());
    // Near the truth: planned at the depth given.
    let plan = planner.plan(&sim.cloud, &PlanRequest::new(JointType::VButt, Some(truth + 0.2), sim.pose)).unwrap();
    assert!(plan.seams[0].warnings.is_empty());
    // Three millimetres off: refused, with both figures and the limit.
    let refused =
        planner.plan(&sim.cloud, &PlanRequest::new(JointType::VButt, Some(truth - 3.0), sim.pose)).unwrap_err();
    assert_eq!((refused.rule.id, refused.gate), ("butt.groove_depth_difference", Some(Gate::GrooveDepth)), "{refused}");
    assert!(refused.reason.contains("measured") && refused.reason.contains("above 1.00 mm"), "{refused}");
    // Made a warning, the seam keeps the depth given.
    let mut config = Config::default();
    config.quality.warn_only = vec!["groove_depth".into()];
    let plan = Planner::new(config)
        .plan(&sim.cloud, &PlanRequest::new(JointType::VButt, Some(truth - 3.0), sim.pose))
        .unwrap();
    let warned: Vec<_> = plan.seams[0].warnings.iter().map(|w| (w.rule.id, w.gate)).collect();
    assert_eq!(warned, [("butt.groove_depth_difference", Gate::GrooveDepth)]);
    let error = seam_error(&sim.truth, &plan.seams[0]).unwrap();
    assert!(error.mean_mm > 2.5, "the weld lies at the depth given: {error:?}");
}

#[test]
fn the_paper_method_is_told_the_joint_and_the_depth() {
    let (_, sim) = rendered(JointType::VButt);
    let mut config = Config::default();
    config.pipeline.method = weldseam::config::Method::Paper;
    let planner = Planner::new(config);
    let auto = planner.check_request(&PlanRequest::new(RequestedJoint::Auto, None, sim.pose)).unwrap_err();
    assert_eq!(auto.rule.id, "plan.joint_beyond_method", "{auto}");
    assert!(auto.reason.contains("`auto` needs pipeline.method"), "{auto}");
    let set = planner
        .check_request(&PlanRequest::new("v-butt+lap".parse::<RequestedJoint>().unwrap(), None, sim.pose))
        .unwrap_err();
    assert_eq!(set.rule.id, "plan.joint_beyond_method", "{set}");
    assert!(set.reason.contains("`v_butt+lap` needs pipeline.method"), "{set}");
    let no_depth = planner.check_request(&PlanRequest::new(JointType::VButt, None, sim.pose)).unwrap_err();
    assert_eq!(no_depth.rule.id, "groove.depth_not_given", "{no_depth}");
    assert!(no_depth.reason.contains("groove depth"), "{no_depth}");
}

#[test]
fn plan_json_says_which_joint_it_found_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("v-butt.pcd");
    let truth = dir.path().join("v-butt.json");
    let status = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["simulate", "--joint", "v-butt", "--out", cloud.to_str().unwrap(), "--truth", truth.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(status.success());
    let truth: serde_json::Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
    let pose = truth["plan_args"].as_str().unwrap().split_whitespace().find(|a| a.starts_with("--pose=")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["plan", "--cloud", cloud.to_str().unwrap(), "--joint", "auto", pose, "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let reply: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let seam = &reply["seams"][0];
    assert_eq!(seam["joint"], "v_butt");
    assert!(seam["joint_evidence"].as_str().unwrap().contains("V-groove"), "{seam}");
    let depth = seam["quality"]["groove_depth_mm"].as_f64().unwrap();
    let true_depth = truth["truth"]["groove_depth_mm"].as_f64().unwrap();
    assert!((depth - true_depth).abs() < 0.3, "{depth} against {true_depth}");
}
