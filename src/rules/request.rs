//! The rules of the request stage (`Stage::Request`): what a plan request
//! must hold before a frame is read for it, and the plan's time limit.

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &POSE_BEYOND_ROBOT,
    &HAND_EYE_BEYOND_LIMIT,
    &START_BEYOND_ROBOT,
    &JOINT_BEYOND_METHOD,
    &GROOVE_DEPTH_NOT_GIVEN,
    &GROOVE_DEPTH_OUT_OF_RANGE,
    &STEP_OUT_OF_RANGE,
    &TORCH_ANGLE_OUT_OF_RANGE,
    &REGION_OF_INTEREST_INVALID,
    &GROOVE_DEEPER_THAN_PLATES,
    &JOINT_UNDECIDED,
    &TIME_LIMIT,
];

const MAX_REACH: Parameter = Parameter {
    name: "max_reach_mm",
    unit: "mm",
    meaning: "farthest the robot reaches from its base origin",
    source: Source::Config("robot.max_reach_mm"),
};

pub static POSE_BEYOND_ROBOT: Rule = Rule {
    id: "reach.pose_beyond_robot",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "the flange pose at capture is finite, within the robot's reach, with angles within two turns",
    reason: "Every waypoint is placed through the flange pose the frame was captured at (Eq. 42). A pose the \
             robot cannot take, farther from its base than its arm reaches, with a coordinate that is not a \
             number or an angle of several turns, is a pose in the wrong units (metres, radians) or read from \
             the wrong register; a trajectory built on it would send the torch somewhere nobody meant.",
    parameters: &[
        MAX_REACH,
        Parameter {
            name: "MAX_POSE_ANGLE_DEG",
            unit: "°",
            meaning: "largest magnitude of a pose angle",
            source: Source::Constant { file: "src/config/mod.rs", name: "MAX_POSE_ANGLE_DEG" },
        },
    ],
    fires: &[
        "tests/requests.rs::poses_beyond_the_robots_reach_or_with_absurd_angles_are_refused",
        "tests/pipeline.rs::bad_requests_are_refused_before_any_work",
    ],
    holds: &["tests/requests.rs::poses_beyond_the_robots_reach_or_with_absurd_angles_are_refused"],
};

pub static HAND_EYE_BEYOND_LIMIT: Rule = Rule {
    id: "reach.hand_eye_beyond_limit",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a hand-eye transform given with the request places the camera within reach of the flange",
    reason: "The camera is bolted to the robot's wrist, a hand's breadth or two from the flange. A hand-eye \
             transform that places it farther is a matrix in metres, inverted, or another cell's; every \
             waypoint would be off by its error.",
    parameters: &[Parameter {
        name: "max_hand_eye_translation_mm",
        unit: "mm",
        meaning: "longest camera offset from the flange",
        source: Source::Config("robot.max_hand_eye_translation_mm"),
    }],
    fires: &["tests/requests.rs::a_hand_eye_translation_beyond_the_configured_maximum_is_refused"],
    holds: &["tests/requests.rs::a_hand_eye_translation_beyond_the_configured_maximum_is_refused"],
};

pub static START_BEYOND_ROBOT: Rule = Rule {
    id: "reach.start_beyond_robot",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "the point the seams should start near is finite and within the robot's reach",
    reason: "The start point orders the seams and picks each one's first end, in the robot's base frame. A \
             point beyond the arm's reach is one in the wrong units or frame, and an order read from it would \
             be arbitrary.",
    parameters: &[MAX_REACH],
    fires: &["tests/requests.rs::poses_beyond_the_robots_reach_or_with_absurd_angles_are_refused"],
    holds: &["tests/several_seams.rs::workpieces_planned_side_by_side_plan_as_on_one_thread"],
};

pub static JOINT_BEYOND_METHOD: Rule = Rule {
    id: "plan.joint_beyond_method",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "the paper's method is asked for one joint type it plans (butt or lap)",
    reason: "The paper's method plans the joint it is told, from two plates' edges: it has no fillet for a \
             tee's root and no way to tell the joint from the frame. A tee, `auto` or a set of types asked of \
             it could only be guessed at; the robust method plans them.",
    parameters: &[Parameter {
        name: "method",
        unit: "",
        meaning: "which method plans",
        source: Source::Config("pipeline.method"),
    }],
    fires: &["tests/joints.rs::the_paper_method_is_told_the_joint_and_the_depth"],
    holds: &["tests/pipeline.rs::bad_requests_are_refused_before_any_work"],
};

pub static GROOVE_DEPTH_NOT_GIVEN: Rule = Rule {
    id: "groove.depth_not_given",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "the paper's method is given a V-butt joint's groove depth",
    reason: "A V-groove's weld lies at its root, the groove depth below the plates' top (Eq. 32). The paper's \
             method sees only the top edges and cannot measure the depth, so without it the weld's height is \
             unknown.",
    parameters: &[Parameter {
        name: "method",
        unit: "",
        meaning: "which method plans",
        source: Source::Config("pipeline.method"),
    }],
    fires: &["tests/joints.rs::the_paper_method_is_told_the_joint_and_the_depth"],
    holds: &["tests/requests.rs::groove_depth_step_and_angles_have_limits_named_in_the_error"],
};

pub static GROOVE_DEPTH_OUT_OF_RANGE: Rule = Rule {
    id: "groove.depth_out_of_range",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a groove depth given lies between zero and the deepest a single-sided groove is cut",
    reason: "Single-sided V-butt welds join plates rarely thicker than 50 mm; a depth below zero or of many \
             centimetres is a value in the wrong unit or field, and would move every waypoint by it.",
    parameters: &[Parameter {
        name: "MAX_GROOVE_DEPTH_MM",
        unit: "mm",
        meaning: "deepest groove a request may name",
        source: Source::Constant { file: "src/pipeline/mod.rs", name: "MAX_GROOVE_DEPTH_MM" },
    }],
    fires: &[
        "tests/requests.rs::groove_depth_step_and_angles_have_limits_named_in_the_error",
        "tests/pipeline.rs::bad_requests_are_refused_before_any_work",
    ],
    holds: &["tests/requests.rs::a_groove_deeper_than_the_measured_plates_is_refused"],
};

pub static STEP_OUT_OF_RANGE: Rule = Rule {
    id: "plan.step_out_of_range",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a waypoint step given lies between what a camera resolves and a metre",
    reason: "Waypoints finer than the camera resolves carry no information and flood the controller; a step \
             longer than a metre leaves a seam without an interior waypoint, so the torch would cut straight \
             across whatever the seam does between its ends.",
    parameters: &[
        Parameter {
            name: "MIN_STEP_MM",
            unit: "mm",
            meaning: "finest waypoint step",
            source: Source::Constant { file: "src/config/mod.rs", name: "MIN_STEP_MM" },
        },
        Parameter {
            name: "MAX_STEP_MM",
            unit: "mm",
            meaning: "coarsest waypoint step",
            source: Source::Constant { file: "src/config/mod.rs", name: "MAX_STEP_MM" },
        },
    ],
    fires: &["tests/requests.rs::groove_depth_step_and_angles_have_limits_named_in_the_error"],
    holds: &["tests/requests.rs::poses_beyond_the_robots_reach_or_with_absurd_angles_are_refused"],
};

pub static TORCH_ANGLE_OUT_OF_RANGE: Rule = Rule {
    id: "plan.torch_angle_out_of_range",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a work or travel angle given tilts the torch less than it takes to lie flat on the plate",
    reason: "Beyond a steep tilt the torch's nozzle lies nearly flat on the plate and hits it or the other \
             plate before the wire reaches the joint; such an angle is a value in radians or a typing error.",
    parameters: &[Parameter {
        name: "MAX_TORCH_ANGLE_DEG",
        unit: "°",
        meaning: "largest work or travel angle",
        source: Source::Constant { file: "src/config/mod.rs", name: "MAX_TORCH_ANGLE_DEG" },
    }],
    fires: &["tests/requests.rs::groove_depth_step_and_angles_have_limits_named_in_the_error"],
    holds: &["tests/requests.rs::poses_beyond_the_robots_reach_or_with_absurd_angles_are_refused"],
};

pub static REGION_OF_INTEREST_INVALID: Rule = Rule {
    id: "frame.region_of_interest_invalid",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "the configured region of interest is none or a box of six finite bounds",
    reason: "The region of interest says where in the cell the workpieces lie; a box that is not one (too \
             few bounds, empty, inverted or beyond any cell) would crop the frame arbitrarily, so the plan is \
             refused naming the key rather than planned from a guess at what was meant.",
    parameters: &[Parameter {
        name: "roi",
        unit: "mm",
        meaning: "the box's bounds",
        source: Source::Config("pipeline.roi"),
    }],
    fires: &["tests/roi.rs::the_configured_box_applies_unless_the_request_brings_its_own"],
    holds: &["tests/roi.rs::the_configured_box_applies_unless_the_request_brings_its_own"],
};

pub static GROOVE_DEEPER_THAN_PLATES: Rule = Rule {
    id: "groove.deeper_than_plates",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a V-groove depth given is no deeper than the plates, where the surface under them is seen",
    reason: "A groove is cut into the plates and cannot reach below them. Where the table or fixture the \
             plates rest on is seen beside them, the depth from their top to it bounds the groove; a depth \
             given beyond it would put every waypoint under the workpiece. A surface seen only between the \
             plates is the joint's own floor and bounds nothing.",
    parameters: &[Parameter {
        name: "GROOVE_DEPTH_TOLERANCE_MM",
        unit: "mm",
        meaning: "fit noise allowed past the plates' depth",
        source: Source::Constant { file: "src/pipeline/context.rs", name: "GROOVE_DEPTH_TOLERANCE_MM" },
    }],
    fires: &["tests/requests.rs::a_groove_deeper_than_the_measured_plates_is_refused"],
    holds: &["tests/requests.rs::a_groove_deeper_than_the_measured_plates_is_refused"],
};

pub static JOINT_UNDECIDED: Rule = Rule {
    id: "joint.undecided",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a weld is placed only once the joint type is known: requested, or decided from the frame",
    reason: "Each joint type places its weld differently (Eq. 32, 36, 38, a fillet's root), so a weld \
             placed before the type is known would be one type's guess. The robust method decides it from \
             the plates' layers and the groove before any weld is placed; the rule guards that order.",
    parameters: &[],
    fires: &["src/pipeline/context.rs::a_weld_waits_for_its_joint_type_and_no_workpiece_is_a_refusal"],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};

pub static TIME_LIMIT: Rule = Rule {
    id: "plan.time_limit",
    stage: Stage::Request,
    effect: Effect::Refuses,
    gate: None,
    summary: "a plan ends within the time limit its caller gives",
    reason: "A robot waits for its trajectory, and the frame behind it waits in the queue. A plan still \
             running past its limit is stopped at the end of the stage it is in and refused, so the next plan \
             starts at once; it says nothing about the frame, which may plan within a longer limit. The rule \
             is checked at every stage's end: the refusal's stage is the one the plan stopped in.",
    parameters: &[Parameter {
        name: "plan_timeout_ms",
        unit: "ms",
        meaning: "longest a daemon's plan may run",
        source: Source::Config("server.plan_timeout_ms"),
    }],
    fires: &["src/pipeline/deadline.rs::a_passed_limit_refuses_and_names_it_and_no_limit_never_does"],
    holds: &["src/pipeline/deadline.rs::a_passed_limit_refuses_and_names_it_and_no_limit_never_does"],
};
