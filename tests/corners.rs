//! Issue 15 item 2 and issue 12 item 6 through the planner: an outside
//! corner is never planned, under any request; it is refused by name with
//! its own gate. An inside corner is a tee with a flange on one side of the
//! web: under `t_fillet` or `auto` its one fillet root is planned within the
//! fillet's bar, under a butt or lap request it is refused by name, with the
//! advice to ask for a fillet.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::{TrueSeam, Verdict, classify_tee};
use weldseam::geometry::Vec3;
use weldseam::geometry::pose::RobotPose;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::input::Units;
use weldseam::pipeline::quality::Gate;
use weldseam::pipeline::{PlanRequest, Planner, Stage};
use weldseam::sim::variants::Variant;
use weldseam::sim::{Draw, SceneSpec, Simulation, corner_suite};

use crate::scenes;

/// Outside corners of the suite's tuning part.
const OUTSIDE: [usize; 2] = [3, 9];
/// Inside corners of the suite's tuning part.
const INSIDE: [usize; 2] = [2, 6];

const EVERY_REQUEST: [RequestedJoint; 5] = [
    RequestedJoint::Auto,
    RequestedJoint::Type(JointType::TFillet),
    RequestedJoint::Type(JointType::VButt),
    RequestedJoint::Type(JointType::IButt),
    RequestedJoint::Type(JointType::Lap),
];

/// The suite's scenes at `indices`, each checked to be of `kind`, with its
/// simulated frame.
fn corner_scenes(indices: [usize; 2], kind: &str) -> impl Iterator<Item = (String, SceneSpec, &'static Simulation)> {
    let suite = corner_suite(Draw::Documented);
    indices.into_iter().map(move |k| {
        let (name, spec) = suite[k].clone();
        assert!(name.starts_with(kind), "{name}");
        let sim = scenes::by_default_camera(&spec);
        (name, spec, sim)
    })
}

fn request(joint: RequestedJoint, pose: RobotPose) -> PlanRequest {
    let depth = (joint == RequestedJoint::Type(JointType::VButt)).then_some(5.0);
    PlanRequest::new(joint, depth, pose)
}

#[test]
fn an_outside_corner_is_refused_by_name_under_every_request() {
    let planner = Planner::new(Config::default());
    for (name, _, sim) in corner_scenes(OUTSIDE, "corner-outside") {
        for joint in EVERY_REQUEST {
            let refused = planner
                .plan(&sim.cloud, &request(joint, sim.pose))
                .map(|plan| plan.seams.len())
                .expect_err(&format!("{name} as {joint}: an outside corner is never planned"));
            assert_eq!(refused.gate, Some(Gate::CornerJoint), "{name} as {joint}: {refused}");
            assert_eq!(refused.stage, Stage::Background, "{name} as {joint}");
            assert_eq!(refused.rule.id, "corner.outside_not_planned", "{name} as {joint}: {refused}");
        }
    }
}

/// Cropped 25 mm round the weld, as a user crops a scan to its joint, the
/// table beyond an outside corner's plate is gone, and with it the drop
/// that names the corner in a full frame. These two were planned before as
/// an I-butt joint (-03: the plate's edge 2 mm proud of the flange beside
/// it, taken for a second plate with a square gap) and as a lap (-09:
/// 4 mm proud, taken for an upper plate) under `auto` and those requests.
/// Under `t_fillet` too the plate's edge is named as an outside corner's.
#[test]
fn a_cropped_outside_corner_is_refused_by_name_under_every_request() {
    let planner = Planner::new(Config::default());
    let variant = Variant::parse("cropped:25,voxel:1,metres").unwrap();
    for (name, spec, _) in corner_scenes(OUTSIDE, "corner-outside") {
        let sim = scenes::as_variant(&spec, &CameraModel::default(), &variant);
        for joint in EVERY_REQUEST {
            let mut request = request(joint, sim.pose);
            request.units = Units::Auto;
            let refused = planner
                .plan(&sim.cloud, &request)
                .map(|plan| plan.seams.iter().map(|s| s.joint).collect::<Vec<_>>())
                .expect_err(&format!("{name} cropped, as {joint}: an outside corner is never planned"));
            let reason = refused.to_string();
            assert_eq!(refused.rule.id, "corner.outside_not_planned", "{name} cropped, as {joint}: {reason}");
            assert_eq!(refused.gate, Some(Gate::CornerJoint), "{name} cropped, as {joint}: {reason}");
            // The refusal says how the crop hid the drop beyond the edge.
            assert!(reason.contains("crop"), "{name} as {joint}: {reason}");
        }
    }
}

#[test]
fn an_inside_corner_s_root_is_planned_as_a_fillet_and_refused_as_a_butt_or_lap() {
    let planner = Planner::new(Config::default());
    for (name, spec, sim) in corner_scenes(INSIDE, "corner-inside") {
        let roots: Vec<TrueSeam> = sim.seams.iter().map(|s| TrueSeam::of(&spec, s)).collect();
        for joint in EVERY_REQUEST {
            let planned = planner.plan(&sim.cloud, &request(joint, sim.pose));
            if matches!(joint, RequestedJoint::Auto | RequestedJoint::Type(JointType::TFillet)) {
                let plan = planned.unwrap_or_else(|e| panic!("{name} as {joint}: {e}"));
                assert_eq!(plan.seams.len(), 1, "{name} as {joint}");
                let seam = &plan.seams[0];
                assert_eq!(seam.joint, JointType::TFillet, "{name} as {joint}");
                assert!(
                    seam.joint_evidence.as_deref().is_some_and(|e| e.contains("inside corner")),
                    "{name} as {joint}: {:?}",
                    seam.joint_evidence
                );
                let path: Vec<Vec3> = seam.waypoints.iter().map(|w| w.position).collect();
                let verdict = classify_tee(&roots, Ok(std::slice::from_ref(&path)));
                assert_eq!(verdict, Verdict::WithinBar, "{name} as {joint}");
                // A corner has a flange on one side only: there is no
                // second root to name.
                assert!(
                    plan.unplanned.iter().all(|u| u.joint != Some(JointType::TFillet)),
                    "{name}: {:?}",
                    plan.unplanned
                );
            } else {
                let refused = planned.map(|plan| plan.seams.len()).expect_err(&format!("{name} as {joint}"));
                assert_eq!(refused.gate, Some(Gate::CornerJoint), "{name} as {joint}: {refused}");
                assert_eq!(refused.rule.id, "corner.inside_root_needs_fillet_request", "{name} as {joint}");
                // The refusal says what to ask for instead.
                assert!(refused.reason.contains("t_fillet"), "{name} as {joint}: {refused}");
            }
        }
    }
}
