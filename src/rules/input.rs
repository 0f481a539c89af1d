//! The rules of the input stage (`Stage::Input`): what a frame must hold
//! before any geometry is read from it.

use super::{Effect, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&NO_VALID_POINT];

pub static NO_VALID_POINT: Rule = Rule {
    id: "frame.no_valid_point",
    stage: Stage::Input,
    effect: Effect::Refuses,
    gate: None,
    summary: "the frame holds at least one point the camera can measure",
    reason: "A structured-light camera measures only within its working volume: nearer than its minimum \
             depth the projector and the sensor no longer overlap, farther than its maximum the pattern \
             is too faint, and beyond its field of view no pixel looks. A point outside that volume, or \
             one with a coordinate that is not a number, is a decoding error or a frame in the wrong \
             units or frame, never a surface. A frame with no point left has nothing to plan from; the \
             refusal counts the points on each side of the volume, since a whole frame outside it is \
             most often a cloud in metres or in the robot's base frame.",
    parameters: &[
        Parameter {
            name: "min_depth_mm",
            unit: "mm",
            meaning: "nearest depth the camera measures",
            source: Source::Config("camera.min_depth_mm"),
        },
        Parameter {
            name: "max_depth_mm",
            unit: "mm",
            meaning: "farthest depth the camera measures",
            source: Source::Config("camera.max_depth_mm"),
        },
        Parameter {
            name: "max_off_axis_deg",
            unit: "°",
            meaning: "widest angle off the optical axis a point may lie at",
            source: Source::Config("camera.max_off_axis_deg"),
        },
    ],
    fires: &[
        "tests/pipeline.rs::bad_requests_are_refused_before_any_work",
        "tests/pipeline.rs::points_at_the_optical_centre_are_ignored_not_searched_forever",
    ],
    holds: &["tests/hostile_clouds.rs::one_absurd_point_neither_runs_away_nor_changes_the_plan"],
};
