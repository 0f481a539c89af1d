//! The rules of the groove stage (`Stage::Groove`): what lies between a
//! butt joint's two weld edges, and what it makes of the joint.

use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &PLATE_STANDING_IN_GAP,
    &TYPE_FROM_GROOVE,
    &NO_BEVEL_FOR_V_BUTT,
    &BEVELS_IN_I_BUTT,
    &TYPE_UNCLEAR,
    &OPENING_OFF_DEPTH,
    &BUTT_NOT_REQUESTED,
    &GROOVE_DEPTH_UNMEASURED,
];

const MOD: &str = "src/pipeline/groove/mod.rs";
const PROFILE: &str = "src/pipeline/groove/profile.rs";
const FIT: &str = "src/pipeline/groove/fit.rs";

/// What makes a face between the edges a bevel, a wall, or no face: the
/// parameters every verdict on the joint's type reads.
const FACE_PARAMETERS: &[Parameter] = &[
    Parameter {
        name: "MIN_BEVEL_DEG",
        unit: "°",
        meaning: "a face steeper than this from the plate normal is a square gap's wall",
        source: Source::Constant { file: PROFILE, name: "MIN_BEVEL_DEG" },
    },
    Parameter {
        name: "MAX_BEVEL_DEG",
        unit: "°",
        meaning: "a face flatter than this from the plate normal is no bevel",
        source: Source::Constant { file: PROFILE, name: "MAX_BEVEL_DEG" },
    },
    Parameter {
        name: "MAX_FACE_RMS_SPACINGS",
        unit: "point spacings",
        meaning: "the largest RMS residual of a face fitted as a plane",
        source: Source::Constant { file: PROFILE, name: "MAX_FACE_RMS_SPACINGS" },
    },
    Parameter {
        name: "MIN_FACE_POINTS",
        unit: "",
        meaning: "the fewest points a face is fitted from",
        source: Source::Constant { file: PROFILE, name: "MIN_FACE_POINTS" },
    },
    Parameter {
        name: "MIN_STATION_SHARE",
        unit: "",
        meaning: "the least share of the seam's stations a face is seen at",
        source: Source::Constant { file: PROFILE, name: "MIN_STATION_SHARE" },
    },
    Parameter {
        name: "RAY_ALIGNED_DEG",
        unit: "°",
        meaning: "a face within this of the camera's rays is a veil of mixed pixels",
        source: Source::Constant { file: FIT, name: "RAY_ALIGNED_DEG" },
    },
];

pub static PLATE_STANDING_IN_GAP: Rule = Rule {
    id: "butt.plate_standing_in_gap",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "nothing taller than a tack stands between a butt joint's two weld edges along the seam",
    reason: "Between a butt joint's edges lies a gap or a groove, below the plates' top. A tack or a weld \
             bead stands 1 to 3 mm proud, in spots; a plate standing between two edges, well above them \
             and along much of the seam, is a tee joint's web on its flange, whose two flange halves the \
             layers took for a butt joint's plates. Planned as a butt joint, the torch would run into the \
             web; the seam is refused and the joint named for what it looks like.",
    parameters: &[
        Parameter {
            name: "STANDING_MIN_MM",
            unit: "mm",
            meaning: "the least height above the plates of something taken for a plate",
            source: Source::Constant { file: MOD, name: "STANDING_MIN_MM" },
        },
        Parameter {
            name: "STANDING_PROBE_MM",
            unit: "mm",
            meaning: "how far above the plates the probe looks",
            source: Source::Constant { file: MOD, name: "STANDING_PROBE_MM" },
        },
        Parameter {
            name: "MIN_FACE_POINTS",
            unit: "",
            meaning: "the fewest points of a standing plate",
            source: Source::Constant { file: PROFILE, name: "MIN_FACE_POINTS" },
        },
        Parameter {
            name: "MIN_STATION_SHARE",
            unit: "",
            meaning: "the least share of the seam's stations it is seen at",
            source: Source::Constant { file: PROFILE, name: "MIN_STATION_SHARE" },
        },
    ],
    fires: &["src/pipeline/groove/tests.rs::a_plate_standing_between_the_edges_is_seen"],
    holds: &[
        "src/pipeline/groove/tests.rs::a_v_groove_shows_two_bevels_its_angle_and_depth",
        "src/pipeline/groove/tests.rs::a_square_gap_shows_no_bevel",
    ],
};

pub static TYPE_FROM_GROOVE: Rule = Rule {
    id: "butt.type_from_groove",
    stage: Stage::Groove,
    effect: Effect::ChangesJoint,
    gate: None,
    summary: "a butt joint left to the planner is a V-butt where bevel faces lie between its edges, an I-butt \
              where none do",
    reason: "A V-groove's two bevel faces slope down from the plates' top at half the groove angle from the \
             plate normal, 15 to 45 degrees a side; a square gap's walls stand along the normal, or are not \
             seen at all where the gap is narrower than the point spacing. So a face fitted between the edges \
             at a groove's angle, as flat as a plate and seen along the seam, makes the joint a V-butt, and \
             no face but walls, veils along the camera's rays or too few points makes it an I-butt. The \
             type decides where the torch goes: at the groove's depth below the edges' midline, or on it.",
    parameters: FACE_PARAMETERS,
    fires: &[
        "tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar",
        "src/pipeline/groove/tests.rs::a_v_groove_shows_two_bevels_its_angle_and_depth",
        "src/pipeline/groove/tests.rs::a_square_gap_shows_no_bevel",
    ],
    holds: &[],
};

pub static NO_BEVEL_FOR_V_BUTT: Rule = Rule {
    id: "groove.no_bevel_for_v_butt",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "a V-butt joint requested shows a bevel face between its edges",
    reason: "A V-butt's weld lies at the groove's depth below the edges' midline; planned on a square gap, \
             the torch sinks into a gap that has no groove by that depth. A V-groove's bevels are wide \
             sloped faces that face the camera and are seen along the whole seam; where none is seen \
             between the edges, the joint is not the one requested.",
    parameters: FACE_PARAMETERS,
    fires: &[
        "tests/joints.rs::the_wrong_joint_is_refused_for_what_the_frame_shows",
        "src/pipeline/groove/tests.rs::a_square_gap_shows_no_bevel",
    ],
    holds: &["src/pipeline/groove/tests.rs::a_v_groove_shows_two_bevels_its_angle_and_depth"],
};

pub static BEVELS_IN_I_BUTT: Rule = Rule {
    id: "groove.bevels_in_i_butt",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "an I-butt joint requested shows no bevel face between its edges",
    reason: "An I-butt's weld lies on the edges' midline, at the plates' top; a V-groove's root lies below \
             it by the groove's depth, and a seam planned at the top leaves the root unwelded. Bevel faces \
             between the edges are a V-groove's, so the joint is not the one requested.",
    parameters: FACE_PARAMETERS,
    fires: &[
        "tests/joints.rs::the_wrong_joint_is_refused_for_what_the_frame_shows",
        "src/pipeline/groove/tests.rs::a_v_groove_shows_two_bevels_its_angle_and_depth",
    ],
    holds: &["src/pipeline/groove/tests.rs::a_square_gap_shows_no_bevel"],
};

pub static TYPE_UNCLEAR: Rule = Rule {
    id: "groove.type_unclear",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "a butt joint left to the planner shows either bevels or a square gap between its edges",
    reason: "Faces between the edges that are seen along the seam but are neither a bevel nor a wall (too \
             flat for a groove, too rough for a plane face) say neither V nor I. The two types put the torch \
             at different heights, so under `auto` the joint is refused as not told; a request that names \
             the type is planned as named.",
    parameters: FACE_PARAMETERS,
    fires: &["src/pipeline/groove/tests.rs::a_face_too_flat_for_a_bevel_tells_neither_joint"],
    holds: &[
        "src/pipeline/groove/tests.rs::a_v_groove_shows_two_bevels_its_angle_and_depth",
        "src/pipeline/groove/tests.rs::a_square_gap_shows_no_bevel",
    ],
};

pub static OPENING_OFF_DEPTH: Rule = Rule {
    id: "groove.opening_off_depth",
    stage: Stage::Groove,
    effect: Effect::Refuses,
    gate: None,
    summary: "a V-groove's weld edges lie as far apart as its bevels and its depth open it at the top",
    reason: "A V-groove `d` deep whose bevels stand at `α1` and `α2` from the normal opens `g + d (tan α1 + \
             tan α2)` at its top, for a root gap `g` of a few millimetres at most. Weld edges much further \
             apart than that are not the groove's: another part abutting a plate gives an edge beside the \
             groove, with the true groove between the edges found. Much nearer, they are something inside \
             the groove. A groove depth given that the bevels do not fit is caught here too, where the \
             camera cannot see the root to measure it. A root land seen at the bevels' feet widens the \
             bottom as a root gap does, by its own width.",
    parameters: &[
        Parameter {
            name: "OPENING_SLACK_MM",
            unit: "mm",
            meaning: "how far the edges' distance may stray from the opening, besides the share below",
            source: Source::Constant { file: PROFILE, name: "OPENING_SLACK_MM" },
        },
        Parameter {
            name: "OPENING_SLACK_SHARE",
            unit: "",
            meaning: "how far it may stray, as a share of the widest opening",
            source: Source::Constant { file: PROFILE, name: "OPENING_SLACK_SHARE" },
        },
        Parameter {
            name: "MAX_ROOT_GAP_MM",
            unit: "mm",
            meaning: "the widest root gap a V-groove has",
            source: Source::Constant { file: PROFILE, name: "MAX_ROOT_GAP_MM" },
        },
        Parameter {
            name: "MIN_BEVEL_DEG",
            unit: "°",
            meaning: "the steepest bevel assumed on a side whose bevel is not seen",
            source: Source::Constant { file: PROFILE, name: "MIN_BEVEL_DEG" },
        },
        Parameter {
            name: "MAX_BEVEL_DEG",
            unit: "°",
            meaning: "the flattest bevel assumed on a side whose bevel is not seen",
            source: Source::Constant { file: PROFILE, name: "MAX_BEVEL_DEG" },
        },
    ],
    fires: &[
        "tests/faults.rs::a_part_abutting_a_v_butt_plate_is_refused_for_an_opening_the_groove_cannot_have",
        "src/pipeline/groove/tests.rs::a_v_groove_shows_two_bevels_its_angle_and_depth",
    ],
    holds: &[
        "tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar",
        "src/pipeline/groove/tests.rs::a_groove_ending_in_a_root_land_shows_its_root_at_the_land",
    ],
};

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
             weld's height is unknown. A groove that ends in a flat root land shows its root where the bevels \
             run down onto the land: a surface seen only between the plates is the groove's own floor, not \
             what the plates rest on, and the depth is the land's, provided the land is narrow beside the \
             groove's opening (a floor as wide as the groove is a trough's, whose root its walls do not place).",
    parameters: &[
        Parameter {
            name: "MAX_ROOT_GAP_MM",
            unit: "mm",
            meaning: "a bevel's foot within half of this of the midline shows the root",
            source: Source::Constant { file: PROFILE, name: "MAX_ROOT_GAP_MM" },
        },
        Parameter {
            name: "MAX_LAND_SHARE",
            unit: "",
            meaning: "the widest root land, as a share of the groove's opening, whose bevels' feet show the root",
            source: Source::Constant { file: PROFILE, name: "MAX_LAND_SHARE" },
        },
    ],
    fires: &["tests/faults.rs::a_v_groove_whose_bevels_are_not_seen_down_to_its_root_needs_its_depth"],
    holds: &[
        "tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar",
        "tests/consumer_camera.rs::a_v_groove_cut_through_the_plate_has_its_root_where_the_plates_rest",
        "src/pipeline/groove/tests.rs::a_groove_ending_in_a_root_land_shows_its_root_at_the_land",
    ],
};
