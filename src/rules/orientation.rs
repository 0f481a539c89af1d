//! The rules of the orientation stage (`Stage::Orientation`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&NO_DOMINANT_NORMAL];

pub static NO_DOMINANT_NORMAL: Rule = Rule {
    id: "plane.no_dominant_normal",
    stage: Stage::Orientation,
    effect: Effect::Refuses,
    gate: None,
    summary: "enough of the frame's sampled points have a local normal for the plates' common normal to be read",
    reason: "Plates, table and fixture lie parallel, and the robust method reads every later criterion \
             against their common normal. A point's normal is fitted to its neighbours within the search \
             radius; where no sampled point has enough of them (a cloud far sparser than the radius \
             assumes), no surface is seen and nothing can be planned.",
    parameters: &[
        Parameter {
            name: "neighbour_radius_mm",
            unit: "mm",
            meaning: "radius the neighbours are counted in",
            source: Source::Config("pipeline.neighbour_radius_mm"),
        },
        Parameter {
            name: "DOMINANT_NORMAL_AGREEMENT_DEG",
            unit: "°",
            meaning: "how far a normal may lie from the most common one and be averaged into it",
            source: Source::Constant { file: "src/pipeline/robust.rs", name: "DOMINANT_NORMAL_AGREEMENT_DEG" },
        },
    ],
    fires: &["tests/pipeline.rs::frames_no_camera_makes_are_refused_by_their_rule"],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};
