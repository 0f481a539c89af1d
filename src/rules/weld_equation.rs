//! The rules of the weld equation stage (`Stage::WeldEquation`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&FILLET_NOT_FROM_EDGES, &EDGES_IN_DIFFERENT_AXES];

pub static FILLET_NOT_FROM_EDGES: Rule = Rule {
    id: "joint.fillet_not_from_edges",
    stage: Stage::WeldEquation,
    effect: Effect::Refuses,
    gate: None,
    summary: "a tee's weld is placed at its fillet roots, never between two plates' edges",
    reason: "A tee's weld runs along the root where the web stands on the flange, found from the web's \
             faces and the flange; the midline of two plate edges (Eq. 32, 36) lies on no surface of a tee. \
             The rule guards the butt and lap path against a tee reaching it.",
    parameters: &[],
    fires: &["src/pipeline/context.rs::a_weld_is_placed_from_two_edges_of_one_seam_only"],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};

pub static EDGES_IN_DIFFERENT_AXES: Rule = Rule {
    id: "seam.edges_in_different_axes",
    stage: Stage::WeldEquation,
    effect: Effect::Refuses,
    gate: None,
    summary: "the two weld edges are fitted along the same seam axes, so their midline is defined",
    reason: "A butt joint's weld is the midline of its two edges (Eq. 32, 36), taken point by point along \
             the seam. Edges fitted along different axes (one along the camera's x, the other along its y, \
             in the paper's choice of axis) run different ways and have no common parameter, so no midline \
             lies between them: they are not the two sides of one seam.",
    parameters: &[],
    fires: &["src/pipeline/context.rs::a_weld_is_placed_from_two_edges_of_one_seam_only"],
    holds: &["tests/pipeline.rs::the_papers_method_stays_reachable_and_plans_a_frontal_scene"],
};
