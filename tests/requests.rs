//! Nonsense in a plan request is refused, not planned: a trajectory is a
//! command to a robot. Poses beyond the robot's reach or with absurd
//! angles, a hand-eye matrix placing the camera kilometres from the
//! flange, a groove deeper than the plates, a spacing of a kilometre: each
//! gets an error naming the value and the limit, before or instead of a
//! plan.

use nalgebra::{Isometry3, Vector3};
use weldseam::config::Config;
use weldseam::geometry::pose::RobotPose;
use weldseam::joint::JointType;
use weldseam::pipeline::{PlanError, PlanRequest, Planner, Stage};
use weldseam::sim::demo_scene;

use crate::scenes;

fn pose(xyz_mm: [f64; 3], angles_deg: [f64; 3]) -> RobotPose {
    RobotPose { xyz_mm, angles_deg }
}

fn refused(request: &PlanRequest) -> PlanError {
    let planner = Planner::new(Config::default());
    let checked = planner.check_request(request).expect_err("check_request refuses it");
    // Planning refuses it the same way, before touching the cloud.
    let cloud = weldseam::cloud::PointCloud::unorganized(vec![[0.0, 0.0, 500.0]]);
    let planned = planner.plan(&cloud, request).expect_err("plan refuses it");
    assert_eq!(checked, planned);
    assert_eq!(checked.stage, Stage::Request, "{checked}");
    checked
}

#[test]
fn poses_beyond_the_robots_reach_or_with_absurd_angles_are_refused() {
    let far = refused(&PlanRequest::new(JointType::Lap, None, pose([1e308, 0.0, 0.0], [0.0; 3])));
    assert_eq!(far.rule.id, "reach.pose_beyond_robot", "{far}");
    assert!(far.reason.contains("robot.max_reach_mm (3500 mm)"), "{far}");
    let just_beyond = refused(&PlanRequest::new(JointType::Lap, None, pose([3000.0, 2000.0, 0.0], [0.0; 3])));
    assert!(just_beyond.reason.contains("3606 mm from the base origin"), "{just_beyond}");
    let mut aimed = PlanRequest::new(JointType::Lap, None, pose([800.0, 0.0, 300.0], [0.0; 3]));
    aimed.start_near = Some(Vector3::new(0.0, 1e9, 0.0));
    let e = refused(&aimed);
    assert_eq!(e.rule.id, "reach.start_beyond_robot", "{e}");
    assert!(e.reason.contains("start_near") && e.reason.contains("robot.max_reach_mm"), "{e}");
    let spun = refused(&PlanRequest::new(JointType::Lap, None, pose([800.0, 0.0, 300.0], [1e300, 0.0, 0.0])));
    assert_eq!(spun.rule.id, "reach.pose_beyond_robot", "{spun}");
    assert!(spun.reason.contains("±720°"), "{spun}");
    let planner = Planner::new(Config::default());
    let fine = PlanRequest::new(JointType::Lap, None, pose([800.0, -200.0, 300.0], [-179.0, 2.0, 359.0]));
    assert_eq!(planner.check_request(&fine), Ok(()));
}

#[test]
fn a_hand_eye_translation_beyond_the_configured_maximum_is_refused() {
    let mut request = PlanRequest::new(JointType::Lap, None, pose([800.0, 0.0, 300.0], [180.0, 0.0, 0.0]));
    request.hand_eye = Some(Isometry3::translation(1e308, 0.0, 0.0));
    let e = refused(&request);
    assert_eq!(e.rule.id, "reach.hand_eye_beyond_limit", "{e}");
    assert!(e.reason.contains("robot.max_hand_eye_translation_mm (1000 mm)"), "{e}");
    request.hand_eye = Some(Isometry3::new(Vector3::new(76.0, -84.0, 100.0), Vector3::zeros()));
    assert_eq!(Planner::new(Config::default()).check_request(&request), Ok(()));
}

#[test]
fn groove_depth_step_and_angles_have_limits_named_in_the_error() {
    let at = pose([800.0, 0.0, 300.0], [180.0, 0.0, 0.0]);
    let deep = refused(&PlanRequest::new(JointType::VButt, Some(200.0), at));
    assert_eq!(deep.rule.id, "groove.depth_out_of_range", "{deep}");
    assert!(deep.reason.contains("groove depth 200 mm is outside 0 to 100 mm"), "{deep}");
    let negative = refused(&PlanRequest::new(JointType::VButt, Some(-1.0), at));
    assert_eq!(negative.rule.id, "groove.depth_out_of_range", "{negative}");
    assert!(negative.reason.contains("groove depth -1 mm"), "{negative}");
    let coarse = refused(&PlanRequest { step_mm: Some(1e9), ..PlanRequest::new(JointType::Lap, None, at) });
    assert_eq!(coarse.rule.id, "plan.step_out_of_range", "{coarse}");
    assert!(coarse.reason.contains("outside 0.1 to 1000 mm"), "{coarse}");
    let flat = refused(&PlanRequest { work_angle_deg: Some(89.0), ..PlanRequest::new(JointType::Lap, None, at) });
    assert_eq!(flat.rule.id, "plan.torch_angle_out_of_range", "{flat}");
    assert!(flat.reason.contains("±80°"), "{flat}");
}

#[test]
fn a_groove_deeper_than_the_measured_plates_is_refused() {
    // The demo V-butt plates are 8 mm thick on spacers: the table behind
    // them bounds any groove. 60 mm passes the request's own limits but
    // would put every waypoint far below the plates.
    let spec = demo_scene(JointType::VButt);
    let config = Config::default();
    let sim = scenes::rendered(&spec, &config.camera);
    let planner = Planner::new(config);
    let true_depth = spec.joint.groove_depth_mm().expect("a V-butt scene has a groove depth");
    let plan = planner.plan(&sim.cloud, &PlanRequest::new(JointType::VButt, Some(true_depth), sim.pose));
    assert!(plan.is_ok(), "the true depth plans: {plan:?}");
    let e = planner.plan(&sim.cloud, &PlanRequest::new(JointType::VButt, Some(60.0), sim.pose)).unwrap_err();
    assert_eq!((e.rule.id, e.stage), ("groove.deeper_than_plates", Stage::Request), "{e}");
    assert!(e.reason.contains("groove depth 60 mm is deeper than the plates"), "{e}");
}

#[test]
fn waypoints_beyond_the_robots_reach_are_refused() {
    // The same capture with the base frame moved to the flange: the pose
    // (at the origin) is within a 300 mm reach, the workpiece 700 mm below
    // the camera is not, and the plan must not hand out its waypoints.
    let spec = demo_scene(JointType::IButt);
    let mut config = Config::default();
    let sim = scenes::rendered(&spec, &config.camera);
    let at_flange = pose([0.0; 3], sim.pose.angles_deg);
    let planner = Planner::new(config.clone());
    assert!(planner.plan(&sim.cloud, &PlanRequest::new(JointType::IButt, None, at_flange)).is_ok());
    config.robot_limits.max_reach_mm = 300.0;
    let e = Planner::new(config).plan(&sim.cloud, &PlanRequest::new(JointType::IButt, None, at_flange)).unwrap_err();
    assert_eq!((e.rule.id, e.stage), ("reach.waypoint_beyond_robot", Stage::Trajectory), "{e}");
    assert!(e.reason.contains("beyond robot.max_reach_mm (300 mm)"), "{e}");
}
