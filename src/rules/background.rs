//! The rules of the background stage (`Stage::Background`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&JOINT_NOT_REQUESTED, &WEB_FACE_WITHOUT_TOP, &NO_WORKPIECE_IN_VIEW];

pub static JOINT_NOT_REQUESTED: Rule = Rule {
    id: "joint.not_requested",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "the joint the plates' layers show is one the request admits",
    reason: "How the plates lie decides the joint before any edge is read: side by side in one plane is a \
             butt joint, one on the other a plate thickness apart is a lap, a plate standing on another is a \
             tee. A workpiece whose layers show a joint the request does not name (one type, or a set of \
             types) is refused for what it shows: planned as the joint asked, the weld would lie where that \
             joint's weld would, not where this one's is.",
    parameters: &[
        Parameter {
            name: "coplanar_tolerance_mm",
            unit: "mm",
            meaning: "how far apart two plates of one layer may lie",
            source: Source::Config("pipeline.coplanar_tolerance_mm"),
        },
        Parameter {
            name: "lap_step_min_mm",
            unit: "mm",
            meaning: "least step of a lap's upper plate",
            source: Source::Config("pipeline.lap_step_min_mm"),
        },
        Parameter {
            name: "lap_step_max_mm",
            unit: "mm",
            meaning: "largest step of a lap's upper plate",
            source: Source::Config("pipeline.lap_step_max_mm"),
        },
    ],
    fires: &["tests/several_seams.rs::a_set_of_joint_types_plans_the_workpieces_of_those_types_and_names_the_others"],
    holds: &["tests/several_seams.rs::a_set_of_joint_types_plans_the_workpieces_of_those_types_and_names_the_others"],
};

pub static WEB_FACE_WITHOUT_TOP: Rule = Rule {
    id: "tee.web_face_without_top",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "under `auto`, a face standing on the nearest plane with no top in view is not taken for a tee",
    reason: "A tee's web cropped below its top shows one side face standing on the flange. An inside \
             corner's standing plate and a fixture's side look the same from one face, and their roots lie \
             elsewhere, so under `auto` the face is named and not planned; a request for `t_fillet` says \
             which it is and plans its root.",
    parameters: &[Parameter {
        name: "tee_web_height_max_mm",
        unit: "mm",
        meaning: "tallest web a face may belong to",
        source: Source::Config("pipeline.tee_web_height_max_mm"),
    }],
    fires: &["tests/several_seams.rs::a_tee_cropped_round_its_root_is_planned_from_its_face_alone"],
    holds: &["tests/several_seams.rs::a_tee_cropped_round_its_root_is_planned_from_its_face_alone"],
};

pub static NO_WORKPIECE_IN_VIEW: Rule = Rule {
    id: "workpiece.none_in_view",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "a frame planned holds at least one workpiece, planned or named",
    reason: "A plan answers for every workpiece in view: each seam planned, or each joint named with why \
             not. A frame in which the planner found no workpiece at all gives neither, and is refused \
             rather than answered with an empty plan a controller could take for a finished one.",
    parameters: &[],
    fires: &["src/pipeline/context.rs::a_weld_waits_for_its_joint_type_and_no_workpiece_is_a_refusal"],
    holds: &["tests/several_seams.rs::a_requested_joint_applies_to_every_workpiece"],
};
