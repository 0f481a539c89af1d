//! The rules of the trajectory stage (`Stage::Trajectory`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply: the reach, then the weld
/// process's cuts (declared in `process.rs`).
pub(super) static RULES: &[&Rule] = &[
    &WAYPOINT_BEYOND_ROBOT,
    &super::process::FIGURES_UNMEASURED,
    &super::process::OUTSIDE_PROCEDURE,
    &super::process::TORCH_BLOCKED,
];

pub static WAYPOINT_BEYOND_ROBOT: Rule = Rule {
    id: "reach.waypoint_beyond_robot",
    stage: Stage::Trajectory,
    effect: Effect::Refuses,
    gate: None,
    summary: "every waypoint is finite and within the robot's reach",
    reason: "The waypoints are the seam moved into the robot's base frame by the pose and the hand-eye \
             transform (Eq. 42). A waypoint the arm cannot reach means one of them, or the cloud's units, is \
             wrong; the seam it belongs to would be welded somewhere else, so none of its waypoints are sent.",
    parameters: &[Parameter {
        name: "max_reach_mm",
        unit: "mm",
        meaning: "farthest the robot reaches from its base origin",
        source: Source::Config("robot.max_reach_mm"),
    }],
    fires: &["tests/requests.rs::waypoints_beyond_the_robots_reach_are_refused"],
    holds: &["tests/requests.rs::waypoints_beyond_the_robots_reach_are_refused"],
};
