//! Under `auto`, a workpiece every proposed reading refused is read as a
//! tee's request reads it (src/pipeline/robust/tee_reading.rs), for its
//! refusal, never for a plan. Each test holds one branch of that weighing
//! on a documented simulated scene.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::{Plan, PlanError, PlanRequest, Planner};
use weldseam::sim::{Draw, FaultKind, ProcessCase, SceneSpec, fault_suite, process_suite, tee_suite};

use crate::scenes;

fn plan(spec: &SceneSpec, joint: RequestedJoint) -> Result<Plan, PlanError> {
    let sim = scenes::by_default_camera(spec);
    Planner::new(Config::default()).plan(&sim.cloud, &PlanRequest::new(joint, None, sim.pose))
}

#[test]
fn a_short_web_the_butt_pair_s_groove_finds_standing_is_named_and_left_to_the_request() {
    // The process family's short webs (15 to 25 mm, no taller than a
    // lap's upper plate is thick): their flange's halves read as a butt
    // pair, refused by the probe that finds the web standing between them.
    // A clamp standing along a seam is refused so too, so `auto` plans
    // neither; the refusal says a tee's request plans the root, and it
    // does.
    let webs: Vec<_> = process_suite(Draw::Documented)
        .into_iter()
        .filter(|s| s.case == ProcessCase::ShortWebTee && !s.name.ends_with("-holdout"))
        .collect();
    assert!(webs.len() >= 2);
    let camera = CameraModel::default();
    let planner = Planner::new(Config::default());
    for scene in webs.iter().take(2) {
        let name = &scene.name;
        let sim = scene.simulate(&camera);
        let plan_as = |joint: RequestedJoint| planner.plan(&sim.cloud, &PlanRequest::new(joint, None, sim.pose));
        let err = plan_as(RequestedJoint::Auto).map(|p| format!("{} seams", p.seams.len())).unwrap_err();
        assert_eq!(err.rule.id, "butt.plate_standing_in_gap", "{name}: {err}");
        assert!(err.reason.contains("pass every gate") && err.reason.contains("request t_fillet"), "{name}: {err}");
        let typed = plan_as(JointType::TFillet.into()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(typed.seams.iter().map(|s| s.joint).collect::<Vec<_>>(), [JointType::TFillet], "{name}");
    }
}

#[test]
fn a_clamp_standing_along_a_lap_s_seam_is_not_welded_as_a_tee() {
    // The fault suite's clamp over a lap at 1 mm voxels (33 mm wide, 35 mm
    // tall, along the whole seam): its plates read as a butt pair with the
    // clamp standing between their edges, and read as a tee, its foot
    // passes every gate. `auto` refuses it.
    let (name, spec) = fault_suite(Draw::Documented)
        .into_iter()
        .find(|(name, _)| name.starts_with("fault-clamp-lap-01"))
        .expect("the fault suite's clamp over a lap");
    let sim = scenes::as_named_variant(&spec, &CameraModel::default(), "voxel:1");
    let err = Planner::new(Config::default())
        .plan(&sim.cloud, &PlanRequest::new(RequestedJoint::Auto, None, sim.pose))
        .map(|p| format!("{} seams", p.seams.len()))
        .unwrap_err();
    assert_eq!(err.rule.id, "butt.plate_standing_in_gap", "{name}: {err}");
}

#[test]
fn a_clamp_no_tee_s_reading_passes_keeps_the_butt_pair_s_refusal() {
    // A clamp over a lap, its plates read as a butt pair with the clamp
    // standing between their edges: read as a tee, nothing stands on a
    // flange, so the groove probe's refusal stands and nothing is planned.
    let (name, spec) = fault_suite(Draw::Documented)
        .into_iter()
        .find(|(name, s)| s.fault_kind() == Some(FaultKind::Clamp) && name.starts_with("fault-clamp-lap-02"))
        .expect("the fault suite's second clamp over a lap");
    let err = plan(&spec, RequestedJoint::Auto).map(|p| format!("{} seams", p.seams.len())).unwrap_err();
    assert_eq!(err.rule.id, "butt.plate_standing_in_gap", "{name}: {err}");
    assert!(!err.reason.contains("read as a tee"), "{name}: {err}");
}

#[test]
fn a_web_seen_over_one_side_whose_root_passes_is_named_not_planned() {
    // Suite tee 4, its web's top clipped by the image: its flange is seen
    // on one side of the web only. A tee's request plans its root; `auto` refuses, as
    // a bar at a plate's edge looks the same, and says the root passes.
    let (name, spec) = &tee_suite(Draw::Documented)[4];
    let err = plan(spec, RequestedJoint::Auto).map(|p| format!("{} seams", p.seams.len())).unwrap_err();
    assert_eq!(err.rule.id, "tee.web_seen_on_one_side", "{name}: {err}");
    assert!(err.reason.contains("pass every gate") && err.reason.contains("request t_fillet"), "{name}: {err}");
    let typed = plan(spec, JointType::TFillet.into()).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(!typed.seams.is_empty(), "{name}");
}

#[test]
fn a_tee_s_reading_that_gets_further_gives_the_refusal_and_the_layers_follow() {
    // Suite tee 10: under `auto`, its top seen over one side of the flange
    // was refused at the background stage; read as a tee, its roots are
    // found hidden or turned from the camera at the refit stage, which says
    // more of the cloud, and the layers' reason follows it.
    let (name, spec) = &tee_suite(Draw::Documented)[10];
    let err = plan(spec, RequestedJoint::Auto).map(|p| format!("{} seams", p.seams.len())).unwrap_err();
    assert_eq!(err.rule.id, "tee.no_root_seen", "{name}: {err}");
    assert!(
        err.reason.contains("as the layers read it") && err.reason.contains("one of its sides only"),
        "{name}: {err}"
    );
}
