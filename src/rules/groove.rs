//! The rules of the groove stage (`Stage::Groove`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&BUTT_NOT_REQUESTED];

pub static BUTT_NOT_REQUESTED: Rule = Rule {
    id: "butt.groove_not_requested",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "the butt joint the groove shows (V or I) is one the request admits",
    reason: "Between a butt joint's edges the camera sees a V-groove's bevels or a square gap, and that \
             decides the type: a V-groove's weld lies at its root, an I-butt's at the plates' top. Under a \
             set of types that leaves out the one the groove shows, the workpiece is refused for what it \
             shows rather than welded at the other type's height.",
    parameters: &[],
    fires: &["tests/several_seams.rs::a_set_of_joint_types_plans_the_workpieces_of_those_types_and_names_the_others"],
    holds: &["tests/several_seams.rs::a_set_of_joint_types_plans_the_workpieces_of_those_types_and_names_the_others"],
};

pub static GROOVE_DEPTH_UNMEASURED: Rule = Rule {
    id: "butt.groove_depth_unmeasured",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: None,
    summary: "a V-groove's depth is given, or measured where a bevel face is seen down to its root",
    reason: "A V-groove's weld lies at its root, the groove depth below the plates' top (Eq. 32). The robust \
             method measures the depth along a bevel face seen down to the root; where no bevel is seen that \
             far (bevels cut through the whole plate, a shadow, a steep view) and no depth was given, the \
             weld's height is unknown.",
    parameters: &[],
    fires: &["tests/consumer_camera.rs::a_v_groove_whose_root_is_hidden_needs_its_depth"],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};
