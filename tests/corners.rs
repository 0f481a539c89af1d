//! Issue 15 item 2 and issue 12 item 6 through the planner: a corner joint
//! (inside or outside) is never planned as a butt, a lap or a tee, under
//! any request; it is refused by name with its own gate.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::names_a_corner;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::quality::Gate;
use weldseam::pipeline::{PlanRequest, Planner, Stage};
use weldseam::sim::{corner_suite, simulate};

/// Corner scenes of the suite's tuning part: two inside, two outside.
const CORNERS: [usize; 4] = [2, 3, 6, 9];

#[test]
fn a_corner_is_refused_by_name_under_every_request() {
    let suite = corner_suite();
    let planner = Planner::new(Config::default());
    let requests = [
        RequestedJoint::Auto,
        RequestedJoint::Type(JointType::TFillet),
        RequestedJoint::Type(JointType::VButt),
        RequestedJoint::Type(JointType::IButt),
        RequestedJoint::Type(JointType::Lap),
    ];
    for k in CORNERS {
        let (name, spec) = &suite[k];
        let sim = simulate(spec, &CameraModel::default());
        let kind = if name.starts_with("corner-inside") { "inside corner" } else { "outside corner" };
        for joint in requests {
            let depth = (joint == RequestedJoint::Type(JointType::VButt)).then_some(5.0);
            let refused = planner
                .plan(&sim.cloud, &PlanRequest::new(joint, depth, sim.pose))
                .map(|plan| plan.seams.len())
                .expect_err(&format!("{name} as {joint}: a corner is never planned"));
            assert_eq!(refused.gate, Some(Gate::CornerJoint), "{name} as {joint}: {refused}");
            assert_eq!(refused.stage, Stage::Background, "{name} as {joint}");
            let reason = refused.to_string();
            assert!(names_a_corner(&reason) && reason.contains(kind), "{name} as {joint}: {reason}");
        }
    }
}
