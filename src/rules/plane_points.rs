//! The rules of the plane points stage (`Stage::PlanePoints`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&NO_PLANE_POINT];

pub static NO_PLANE_POINT: Rule = Rule {
    id: "plane.no_plane_point",
    stage: Stage::PlanePoints,
    effect: Effect::Refuses,
    gate: None,
    summary: "some points have the neighbour count of a plane at their depth (Eq. 14)",
    reason: "A point on a flat plate has about as many neighbours within the radius as a plane at its depth \
             and tilt holds (Eq. 6 and 14). Where no point reaches that share, the frame shows no flat \
             surface at the scale the criterion reads (a cloud sparser than the camera's, or noise), and no \
             plate can be found.",
    parameters: &[
        Parameter {
            name: "plane_min_neighbour_ratio",
            unit: "",
            meaning: "least share of a plane's count a plane point has",
            source: Source::Config("pipeline.plane_min_neighbour_ratio"),
        },
        Parameter {
            name: "plane_max_normal_angle_deg",
            unit: "°",
            meaning: "largest tilt of a plane point's normal from the dominant one",
            source: Source::Config("pipeline.plane_max_normal_angle_deg"),
        },
    ],
    fires: &["tests/pipeline.rs::frames_no_camera_makes_are_refused_by_their_rule"],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};
