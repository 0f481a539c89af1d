//! The rules of the background stage (`Stage::Background`): which plane
//! clusters are a joint's plates, how they lie (side by side, one on the
//! other, a web on its flange, a corner), and when the clusters show no
//! joint the request can be planned as.

use super::web_face::WEB_FACE;
pub use super::web_face::{
    TEE_FACE_FOOT_ABOVE_FLANGE, TEE_NO_FACE_STANDS_ON_FLANGE, TEE_NOTHING_STANDS_ON_FLANGE, TEE_STANDING_FACE_TOO_LOW,
    TEE_STANDING_FACE_TOO_SPARSE,
};
#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &CORNER_OUTSIDE_NOT_PLANNED,
    &CORNER_INSIDE_NEEDS_FILLET_REQUEST,
    &CORNER_INSIDE_PLANNED_AS_TEE_ROOT,
    &TOO_FEW_PLANES,
    &TEE_NO_WEB_TOP,
    &LOOKS_LIKE_TEE,
    &BUTT_NO_COPLANAR_PAIR,
    &LOOKS_LIKE_LAP,
    &BUTT_PAIR_UNDER_LARGER_PLANE,
    &BUTT_THIRD_PLATE_BEYOND_PAIR,
    &LAP_NO_PLATE_STEP,
    &LOOKS_LIKE_BUTT,
    &LAP_UPPER_PLANE_LIES_ACROSS_LOWER,
    &PLATE_AND_PIECE_OVER_LOWER_PLANE,
    &TEE_WEB_SEEN_ON_ONE_SIDE,
    &NO_LAYOUT_FITS,
    &TEE_NOTHING_STANDS_ON_FLANGE,
    &TEE_NO_FACE_STANDS_ON_FLANGE,
    &TEE_FACE_FOOT_ABOVE_FLANGE,
    &TEE_STANDING_FACE_TOO_SPARSE,
    &TEE_STANDING_FACE_TOO_LOW,
    &JOINT_NOT_REQUESTED,
    &WEB_FACE_WITHOUT_TOP,
    &NO_WORKPIECE_IN_VIEW,
    &LAP_NEARER_THAN_BUTT_PAIR,
];

const BACKGROUND: &str = "src/pipeline/background/placement.rs";
const CORNER: &str = "src/pipeline/background/corner.rs";
const LAYERS: &str = "src/pipeline/background/layers.rs";
const IMAGE_BREAK: &str = "src/pipeline/background/image_break.rs";

const COPLANAR_TOLERANCE: Parameter = Parameter {
    name: "coplanar_tolerance_mm",
    unit: "mm",
    meaning: "planes whose offsets along the normal agree within this are one layer",
    source: Source::Config("pipeline.coplanar_tolerance_mm"),
};
const LAP_STEP_MIN: Parameter = Parameter {
    name: "lap_step_min_mm",
    unit: "mm",
    meaning: "thinnest upper plate of a lap",
    source: Source::Config("pipeline.lap_step_min_mm"),
};
const LAP_STEP_MAX: Parameter = Parameter {
    name: "lap_step_max_mm",
    unit: "mm",
    meaning: "thickest upper plate of a lap; a web's top stands higher",
    source: Source::Config("pipeline.lap_step_max_mm"),
};
const WEB_HEIGHT_MAX: Parameter = Parameter {
    name: "tee_web_height_max_mm",
    unit: "mm",
    meaning: "tallest web over its flange",
    source: Source::Config("pipeline.tee_web_height_max_mm"),
};
const WEB_THICKNESS_MAX: Parameter = Parameter {
    name: "tee_web_thickness_max_mm",
    unit: "mm",
    meaning: "widest web's top",
    source: Source::Config("pipeline.tee_web_thickness_max_mm"),
};
const WEB_MIN_HEIGHT_PER_WIDTH: Parameter = Parameter {
    name: "WEB_MIN_HEIGHT_PER_WIDTH",
    unit: "",
    meaning: "least height over width of a web's top no higher than a lap step",
    source: Source::Constant { file: LAYERS, name: "WEB_MIN_HEIGHT_PER_WIDTH" },
};
const FACING_ANGLE_MAX: Parameter = Parameter {
    name: "plane_max_normal_angle_deg",
    unit: "°",
    meaning: "a plane further than this from the workpiece's normal is no plate",
    source: Source::Config("pipeline.plane_max_normal_angle_deg"),
};
const SIDE_BY_SIDE_AREA_RATIO: Parameter = Parameter {
    name: "SIDE_BY_SIDE_AREA_RATIO",
    unit: "",
    meaning: "least area of a second plate against the first, for a plate rather than a piece",
    source: Source::Constant { file: BACKGROUND, name: "SIDE_BY_SIDE_AREA_RATIO" },
};
const IMAGE_BREAK_MAX: Parameter = Parameter {
    name: "IMAGE_BREAK_MAX_MM",
    unit: "mm",
    meaning: "widest break between two coplanar pieces read as a break in the image (a streak, a dropout)",
    source: Source::Constant { file: IMAGE_BREAK, name: "IMAGE_BREAK_MAX_MM" },
};
const IMAGE_BREAK_RUN_ON: Parameter = Parameter {
    name: "RUN_ON_MIN_MM",
    unit: "mm",
    meaning: "how far such a break must run on, in line in the image, across the surface behind the pieces",
    source: Source::Constant { file: IMAGE_BREAK, name: "RUN_ON_MIN_MM" },
};
/// What tells a second plate of a layer from a piece of the first, over
/// a plane a lap's step behind: its area, and a break in the image
/// between them.
const PLATE_OR_PIECE_PARAMETERS: &[Parameter] =
    &[SIDE_BY_SIDE_AREA_RATIO, COPLANAR_TOLERANCE, LAP_STEP_MIN, LAP_STEP_MAX, IMAGE_BREAK_MAX, IMAGE_BREAK_RUN_ON];
const BAR_ELONGATION: Parameter = Parameter {
    name: "BAR_ELONGATION",
    unit: "",
    meaning: "least length over width of a plane that can lie across another",
    source: Source::Constant { file: BACKGROUND, name: "BAR_ELONGATION" },
};
const FALL_HEIGHT_BANDS: Parameter = Parameter {
    name: "FALL_HEIGHT_BANDS",
    unit: "",
    meaning: "a face falls from a wide top when the points round one side of its outline fill this many bands of \
              height between it and the plane under it",
    source: Source::Constant { file: BACKGROUND, name: "FALL_HEIGHT_BANDS" },
};
const FALL_MIN_POINTS: Parameter = Parameter {
    name: "FALL_MIN_POINTS",
    unit: "",
    meaning: "fewest points between a wide top and the plane under it that show a face falling from it",
    source: Source::Constant { file: BACKGROUND, name: "FALL_MIN_POINTS" },
};
const CORNER_WEB_WIDTH_MAX: Parameter = Parameter {
    name: "CORNER_WEB_WIDTH_MAX_MM",
    unit: "mm",
    meaning: "widest plate edge taken for a corner's standing plate",
    source: Source::Constant { file: CORNER, name: "CORNER_WEB_WIDTH_MAX_MM" },
};
const CORNER_LEVEL_SHARE_MAX: Parameter = Parameter {
    name: "CORNER_LEVEL_SHARE_MAX",
    unit: "",
    meaning: "most share of returns at the plates' level beyond the edge",
    source: Source::Constant { file: CORNER, name: "CORNER_LEVEL_SHARE_MAX" },
};
const CORNER_DEEP_RETURNS_MIN: Parameter = Parameter {
    name: "CORNER_DEEP_RETURNS_MIN",
    unit: "",
    meaning: "fewest returns far below beyond the edge that show a drop",
    source: Source::Constant { file: CORNER, name: "CORNER_DEEP_RETURNS_MIN" },
};
const FACE_SHARE_MIN: Parameter = Parameter {
    name: "FACE_SHARE_MIN",
    unit: "",
    meaning: "least share of the returns below the edge on a face going down from it",
    source: Source::Constant { file: CORNER, name: "FACE_SHARE_MIN" },
};
const MIN_BESIDE_SHARE: Parameter = Parameter {
    name: "MIN_BESIDE_SHARE",
    unit: "",
    meaning: "least share of the edge's length along which the larger plane is seen beside it",
    source: Source::Constant { file: CORNER, name: "MIN_BESIDE_SHARE" },
};

/// The corner parameters: the shape of the standing plate's edge and what
/// must lie beyond it.
const CORNER_PARAMETERS: &[Parameter] = &[
    WEB_THICKNESS_MAX,
    CORNER_WEB_WIDTH_MAX,
    BAR_ELONGATION,
    COPLANAR_TOLERANCE,
    LAP_STEP_MAX,
    WEB_HEIGHT_MAX,
    SIDE_BY_SIDE_AREA_RATIO,
    CORNER_LEVEL_SHARE_MAX,
    CORNER_DEEP_RETURNS_MIN,
    FACE_SHARE_MIN,
    MIN_BESIDE_SHARE,
];

pub static CORNER_OUTSIDE_NOT_PLANNED: Rule = Rule {
    id: "corner.outside_not_planned",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::CornerJoint),
    summary: "no plate's edge stands flush with or just proud of a larger plane beside it with nothing beyond it",
    reason: "At an outside corner one plate's end face meets the other plate's edge, so from above the camera \
             sees a narrow strip (the standing plate's edge, a plate thickness wide) flush with or a little proud \
             of a larger plane seen on one of its sides only, and beyond the strip nothing at their level: the \
             table far below, the standing plate's outer face going down, or no return at all. Its plates pass \
             for butt plates with a square gap, or for a lap whose upper plate is its edge, and a path planned \
             so would weld the wrong place; the corner's own weld runs along the outside of the corner, which \
             the planner does not plan. Where nothing is seen beyond the strip, an edge along the view's border \
             is a plate the image cuts, not a corner. The two plates meet along the whole joint, so the larger \
             plane is seen beside the strip along most of its length; a strip with the larger plane off its end \
             (a beam's top seen as a sliver in front of a tube standing near the beam's edge) is a piece of that \
             plane, not a corner's edge. And the strip touches the larger plane (they lie apart by no more \
             than the two clusters' rims): a tee's flange ending just past its web shows a sliver as narrow, flush \
             with the flange on the web's other side, but a web's thickness off it.",
    parameters: CORNER_PARAMETERS,
    fires: &[
        "tests/corners.rs::a_cropped_outside_corner_is_refused_by_name_under_every_request",
        "src/pipeline/background/tests.rs::a_plates_edge_flush_or_proud_beside_a_flange_with_a_drop_beyond_is_an_outside_corner",
        "src/pipeline/background/tests.rs::an_edge_with_its_outer_face_going_down_to_where_the_cloud_ends_is_an_outside_corner",
        "src/pipeline/background/tests.rs::an_edge_with_nothing_beyond_inside_the_view_or_in_a_cloud_without_a_grid_is_refused",
        "tests/corners.rs::an_outside_corner_is_refused_by_name_under_every_request",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::a_sliver_cut_by_the_image_border_is_no_corner",
        "src/pipeline/background/tests.rs::a_sliver_continuing_a_plate_off_its_end_is_no_corner",
        "src/pipeline/background/tests.rs::a_sliver_of_flange_beyond_a_web_near_its_edge_is_no_corner",
        "src/eval/web_near_edge.rs::no_root_is_confident_wrong_on_the_documented_seeds",
        "src/pipeline/background/tests.rs::returns_at_the_flanges_level_beyond_make_it_no_corner",
        "src/pipeline/background/tests.rs::a_drop_no_deeper_than_a_lap_step_is_no_corner",
    ],
};

pub static CORNER_INSIDE_NEEDS_FILLET_REQUEST: Rule = Rule {
    id: "corner.inside_root_needs_fillet_request",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::CornerJoint),
    summary: "under a butt or lap request, no plate stands a web's height tall at the end of a larger plane",
    reason: "At an inside corner one plate stands on the other's end: from above, a narrow strip (its edge) a \
             web's height over a larger plane seen on one of its sides only, and beyond it the cloud drops to \
             the table. Its weld is a fillet in the root between the two, as a tee's with a flange on one side; \
             a butt joint's or a lap's path through it would weld the wrong place, so under those requests it is \
             refused with the advice to ask for a fillet.",
    parameters: CORNER_PARAMETERS,
    fires: &[
        "src/pipeline/background/tests.rs::a_web_a_web_height_over_a_flange_with_a_drop_beyond_is_an_inside_corner",
        "tests/corners.rs::an_inside_corner_s_root_is_planned_as_a_fillet_and_refused_as_a_butt_or_lap",
    ],
    holds: &["src/pipeline/background/tests.rs::a_drop_no_deeper_than_a_lap_step_is_no_corner"],
};

pub static CORNER_INSIDE_PLANNED_AS_TEE_ROOT: Rule = Rule {
    id: "corner.inside_planned_as_tee_root",
    stage: Stage::Background,
    effect: Effect::ChangesJoint,
    gate: None,
    summary: "an inside corner under `t_fillet` or `auto` is planned as a tee's root with its flange on one side",
    reason: "An inside corner's fillet root lies where the standing plate's face meets the plate it stands on, as \
             a tee web's root does; only the flange beyond the web is missing. Under a request that admits a \
             fillet its one root is planned as a tee's, from the standing plate's edge and the plane beside it, \
             and no second root is named.",
    parameters: CORNER_PARAMETERS,
    fires: &[
        "src/pipeline/background/tests.rs::a_web_a_web_height_over_a_flange_with_a_drop_beyond_is_an_inside_corner",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::a_plates_edge_flush_or_proud_beside_a_flange_with_a_drop_beyond_is_an_outside_corner",
    ],
};

pub static TOO_FEW_PLANES: Rule = Rule {
    id: "workpiece.fewer_than_two_planes",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "at least two plane surfaces face the camera as the workpiece does",
    reason: "Every joint planned is read from two plane surfaces seen from the camera's side: two plates, one \
             over the other, or a web's top over its flange. A surface turned further from the workpiece's \
             normal than the camera can see a plate at (a plate's side face, a fixture's wall) is none of them. \
             With fewer than two facing surfaces the frame shows at most one plate, or one surface where the \
             plates lie closer than the cloud resolves. The refusal says what rises beside the lone plane, read \
             on the facet holding the most of it that comes down to the plane (a block's two faces are no one \
             plane, and a plane through both would lie near the plate's own), or where no facet holds a \
             face's worth of points, on the plane through most of it: two faces meeting in a valley wider than a web stands on its flange, or obtuse and seen down its middle \
             (both faces turned about as far from the rays), are a groove's two flanks with no plate top in view, \
             and no tee is tried under `auto`; two faces within a few degrees of one plane are one surface, \
             one plate or a butt's plates seen as one.",
    parameters: &[
        FACING_ANGLE_MAX,
        Parameter {
            name: "VALLEY_MIDDLE_SLANT_DEG",
            unit: "°",
            meaning: "most two faces' slants from the rays differ for the camera to look down a valley's middle",
            source: Source::Constant { file: WEB_FACE, name: "VALLEY_MIDDLE_SLANT_DEG" },
        },
        Parameter {
            name: "ONE_SURFACE_MIN_OPENING_DEG",
            unit: "°",
            meaning: "the valley two faces open above which they are told as one surface, not a groove's flanks",
            source: Source::Constant { file: WEB_FACE, name: "ONE_SURFACE_MIN_OPENING_DEG" },
        },
    ],
    fires: &[
        "src/pipeline/background/tests.rs::failures_say_what_was_found",
        "tests/pipeline.rs::a_frame_without_the_workpiece_names_the_failing_stage",
    ],
    holds: &["src/pipeline/background/tests.rs::plates_filling_the_view_are_both_kept"],
};

pub static TEE_NO_WEB_TOP: Rule = Rule {
    id: "tee.no_web_top",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "under a tee request, a member's top stands a web's height over a plane beside it",
    reason: "A tee's web stands on its flange: from the camera's side its top is a plane no higher over the flange \
             than a web stands, with the flange seen beside it, and it stands as a member does: either a long \
             narrow top, no wider than a web is thick, higher than any lap's upper plate is thick or, a short \
             web, several times as tall as its top is wide; or a top of any width or shape higher than any lap's \
             upper plate is thick with a face seen falling from its edges to the plane under it (a block or a \
             box standing on a plate, every side of it a root). A narrow strip no higher than a lap step and \
             about as wide as it is tall, or wider, is a bar or a clamp lying on a plate; a narrow plane under a \
             larger one is a V-groove's root land below the workpiece's top, not a web's top; a wide plane over \
             another with no face between them is held over it, not standing on it. (A short strip standing \
             taller than it is wide is read as a web only under the tee's request: a bar or clamp standing on \
             edge across a butt or lap joint's plates shows the same layers.)",
    parameters: &[
        WEB_THICKNESS_MAX,
        BAR_ELONGATION,
        LAP_STEP_MAX,
        WEB_MIN_HEIGHT_PER_WIDTH,
        WEB_HEIGHT_MAX,
        COPLANAR_TOLERANCE,
        FALL_MIN_POINTS,
        FALL_HEIGHT_BANDS,
    ],
    fires: &[
        "src/pipeline/background/tests.rs::a_bar_lying_on_the_plates_or_too_wide_is_no_web",
        "src/pipeline/background/tests.rs::a_v_groove_s_root_land_under_its_plates_is_no_web_s_top",
        "src/pipeline/background/standing_tests.rs::a_wide_top_with_no_face_falling_to_the_plate_or_no_higher_than_a_lap_step_is_no_web",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::a_web_a_web_height_over_its_flange_seen_on_both_sides_is_a_tee",
        "src/pipeline/background/tests.rs::a_web_shorter_than_a_lap_step_standing_taller_than_it_is_thick_is_a_tee",
        "src/pipeline/background/standing_tests.rs::a_block_standing_on_a_plate_is_a_tee_by_the_face_falling_from_its_top",
    ],
};

pub static LOOKS_LIKE_TEE: Rule = Rule {
    id: "joint.looks_like_tee",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "under a butt or lap request, no web stands on a flange seen on both of its sides",
    reason: "A long narrow plane a web's height over a plane seen on both of its long sides is a tee's web \
             standing on its flange: too tall for a lap's upper plate, and butt plates are one plane. Planning \
             it as the butt joint or lap requested would take the web's top edges for plate edges.",
    parameters: &[WEB_THICKNESS_MAX, BAR_ELONGATION, LAP_STEP_MAX, WEB_HEIGHT_MAX, COPLANAR_TOLERANCE],
    fires: &[
        "tests/several_seams.rs::a_tee_requested_as_a_butt_or_lap_joint_is_refused_by_name",
        "src/pipeline/background/tests.rs::a_web_a_web_height_over_its_flange_seen_on_both_sides_is_a_tee",
    ],
    holds: &["src/pipeline/background/tests.rs::a_bar_lying_on_the_plates_or_too_wide_is_no_web"],
};

pub static BUTT_NO_COPLANAR_PAIR: Rule = Rule {
    id: "butt.no_coplanar_pair",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "under a butt request, two plates lie side by side in one plane",
    reason: "Butt plates are laid flat side by side on one support, so their top faces lie in one plane, within \
             what the fixture and the cloud's depth noise allow. With no two facing planes that near to each \
             other along the normal, the frame holds no butt joint; the refusal lists the planes' offsets. Two \
             pieces of one plane whose narrow break runs on, in line in the image, across the surface behind \
             them are one plate a streak or a dropout cut, not two: a gap between plates ends where they do.",
    parameters: &[COPLANAR_TOLERANCE, FACING_ANGLE_MAX, IMAGE_BREAK_MAX, IMAGE_BREAK_RUN_ON],
    fires: &["src/pipeline/background/tests.rs::failures_say_what_was_found"],
    holds: &["src/pipeline/background/tests.rs::plates_filling_the_view_are_both_kept"],
};

pub static LOOKS_LIKE_LAP: Rule = Rule {
    id: "joint.looks_like_lap",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "under a butt request, the nearest two plates do not lie one plate thickness apart with none beside",
    reason: "Where no two plates lie in one plane but the nearest two lie a plate's thickness apart along the \
             normal, one over the other, the plates are a lap's. Planning them as butt plates would take the \
             upper plate's edge and the lower plate's edge for the two sides of a gap.",
    parameters: &[COPLANAR_TOLERANCE, LAP_STEP_MIN, LAP_STEP_MAX],
    fires: &[
        "tests/cli.rs::failures_exit_non_zero_and_say_why",
        "src/pipeline/background/tests.rs::the_wrong_joint_requested_is_named_for_what_it_looks_like",
        "tests/joints.rs::the_wrong_joint_is_refused_for_what_the_frame_shows",
    ],
    holds: &["src/pipeline/background/tests.rs::plates_filling_the_view_are_both_kept"],
};

pub static BUTT_PAIR_UNDER_LARGER_PLANE: Rule = Rule {
    id: "butt.pair_under_larger_plane",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "no plane larger than either plate of the butt pair lies nearer the camera",
    reason: "Butt plates are the workpiece's top. A plane nearer the camera and larger than either plate of the \
             only coplanar pair is more likely the workpiece itself, its two plates seen as one across a gap \
             narrower than the cloud resolves, and the pair the table or fixture seen on both sides of it. \
             Planning the pair would weld the table.",
    parameters: &[COPLANAR_TOLERANCE],
    fires: &[
        "tests/measured_clouds.rs::voxel_clouds_plan_their_seam_where_it_is_or_say_why_not",
        "src/pipeline/background/tests.rs::table_pieces_under_plates_seen_as_one_are_refused",
    ],
    holds: &["src/pipeline/background/tests.rs::a_split_table_is_not_taken_for_a_plate"],
};

pub static BUTT_THIRD_PLATE_BEYOND_PAIR: Rule = Rule {
    id: "butt.third_plate_beyond_pair",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "the butt pair's plane holds no third plate beside the pair across their seam",
    reason: "Three plates side by side in one plane meet at two joints, and the request names one. A third plane \
             as large as a plate whose centre lies beyond the pair across their seam is such a plate; a piece of \
             one of the pair (cut off by something lying over it, or by a gap in the cloud) runs on along the seam \
             instead, and a small plane is a tack or a bead. The user sets a region of interest round the joint \
             to weld.",
    parameters: &[
        COPLANAR_TOLERANCE,
        SIDE_BY_SIDE_AREA_RATIO,
        Parameter {
            name: "BEYOND_PAIR_SPACINGS",
            unit: "",
            meaning: "how far outside the pair, in pair spacings, a third plate's centre lies",
            source: Source::Constant { file: BACKGROUND, name: "BEYOND_PAIR_SPACINGS" },
        },
    ],
    fires: &[
        "src/pipeline/background/tests.rs::a_third_plate_beside_a_butt_pair_is_refused_and_a_piece_along_it_is_not",
        "tests/faults.rs::a_part_abutting_an_i_butt_plate_larger_than_the_other_plate_is_refused_as_a_third_plate",
        "tests/faults.rs::a_part_touching_an_i_butt_whose_gap_voxels_close_is_not_taken_for_its_second_plate",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::a_third_plate_beside_a_butt_pair_is_refused_and_a_piece_along_it_is_not",
    ],
};

pub static LAP_NO_PLATE_STEP: Rule = Rule {
    id: "lap.no_plate_step",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "under a lap request, two layers of planes lie one plate thickness apart",
    reason: "A lap's upper plate lies on its lower plate, so their top faces are parallel and one upper plate's \
             thickness apart along the normal, within the thickness range of the plates welded. With no two \
             layers that far apart the frame holds no lap; the refusal lists the planes' offsets.",
    parameters: &[LAP_STEP_MIN, LAP_STEP_MAX, COPLANAR_TOLERANCE],
    fires: &[
        "tests/several_seams.rs::a_requested_joint_applies_to_every_workpiece",
        "src/pipeline/background/tests.rs::failures_say_what_was_found",
        "tests/joints.rs::the_wrong_joint_is_refused_for_what_the_frame_shows",
    ],
    holds: &["src/pipeline/background/tests.rs::lap_takes_the_nearest_layers_one_thickness_apart_upper_first"],
};

pub static LOOKS_LIKE_BUTT: Rule = Rule {
    id: "joint.looks_like_butt",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointMismatch),
    summary: "under a lap request, the upper layer holds no two plates side by side",
    reason: "A lap's upper layer is one plate. Two plates side by side in it, the second as large as a plate \
             rather than a piece, lie as butt plates do, and the layer under them is what they rest on; planning \
             a lap would weld one butt plate's edge to the table. Two pieces whose narrow break runs on, in line \
             in the image, across the plate under them are one upper plate a streak or a dropout cut: the lap \
             is planned along both.",
    parameters: PLATE_OR_PIECE_PARAMETERS,
    fires: &["src/pipeline/background/tests.rs::the_wrong_joint_requested_is_named_for_what_it_looks_like"],
    holds: &[
        "src/pipeline/background/tests.rs::lap_takes_the_nearest_layers_one_thickness_apart_upper_first",
        "tests/faults.rs::a_lap_plate_cut_by_a_streak_running_on_across_the_plate_under_it_is_one_plate",
    ],
};

pub static LAP_UPPER_PLANE_LIES_ACROSS_LOWER: Rule = Rule {
    id: "lap.upper_plane_lies_across_lower",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "the lap's upper plate ends on its lower plate, which is seen on one side of it only",
    reason: "A lap's upper plate ends on the lower one: the lower plate is seen beside the upper plate's weld edge \
             and not past its far side. A plane a lap step over a plane seen on both of its sides lies across that \
             plane instead: an object lying on the workpiece (a bar, a clamp's jaw) or a web too low to be told \
             from one. A long narrow plane has the plane under it on both of its long sides; one no longer than a \
             bar (a clamp's pad the view cuts short round the seam) has the line between two pieces of the plane \
             under it pass through it. Its sides are no plate edges, and a path along one would weld beside the \
             joint.",
    parameters: &[BAR_ELONGATION, SIDE_BY_SIDE_AREA_RATIO, LAP_STEP_MIN, LAP_STEP_MAX],
    fires: &[
        "src/pipeline/background/tests.rs::a_bar_lying_across_a_plate_is_no_lap",
        "src/pipeline/background/tests.rs::a_clamp_cut_short_by_a_crop_round_the_seam_is_no_lap_s_upper_plate",
        "src/pipeline/background/tests.rs::a_bar_across_a_plate_seen_round_its_end_is_no_lap",
        "src/pipeline/background/tests.rs::a_bar_across_a_small_plate_beside_a_large_one_is_no_lap",
        "tests/faults.rs::a_clamp_lying_across_a_laps_plate_is_refused_as_an_object_on_the_workpiece",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::a_lap_whose_lower_plate_runs_on_past_the_upper_plates_end_is_kept",
        "src/pipeline/background/tests.rs::a_lap_whose_lower_plate_is_seen_on_one_side_only_is_kept",
    ],
};

pub static PLATE_AND_PIECE_OVER_LOWER_PLANE: Rule = Rule {
    id: "joint.plate_and_piece_over_lower_plane",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "under `auto`, the nearest layer does not hold a plate and a smaller piece over a plane a step below",
    reason: "A plate with a piece too small to be a plate beside it in one plane, over a lower plane one plate \
             thickness behind, is two butt plates with one barely in view, or a lap's upper plate that a gap in \
             the cloud cut in two. Where the break between them runs on, in line in the image, across the plane \
             behind, the cloud tells: a break in the image, one plate. Otherwise the two joints' seams lie in \
             different places and the frame cannot tell them apart, so the joint type must be named in the \
             request.",
    parameters: PLATE_OR_PIECE_PARAMETERS,
    fires: &[
        "tests/faults.rs::a_lap_plate_cut_by_a_streak_is_refused_for_coverage_and_not_found_as_a_butt_joint",
        "src/pipeline/background/tests.rs::with_no_type_given_the_layers_decide",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::with_no_type_given_the_layers_decide",
        "tests/faults.rs::a_lap_plate_cut_by_a_streak_running_on_across_the_plate_under_it_is_one_plate",
    ],
};

pub static TEE_WEB_SEEN_ON_ONE_SIDE: Rule = Rule {
    id: "tee.web_seen_on_one_side",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "under `auto`, a web's top is seen over its flange on both of its sides, or the joint is named",
    reason: "A long narrow plane a web's height over a plane seen on one of its sides only is a tee whose web hides \
             the flange on its far side, or a bar standing at a plate's edge. Neither the layers nor the planes \
             tell the two apart; the user names the tee (`t_fillet`) to plan its root.",
    parameters: &[WEB_THICKNESS_MAX, BAR_ELONGATION, LAP_STEP_MAX, WEB_HEIGHT_MAX],
    fires: &[
        "tests/several_seams.rs::a_webs_end_face_is_not_taken_for_its_side_face",
        "src/pipeline/background/tests.rs::a_web_over_a_flange_seen_on_one_side_is_planned_only_when_named",
    ],
    holds: &["src/pipeline/background/tests.rs::a_web_a_web_height_over_its_flange_seen_on_both_sides_is_a_tee"],
};

pub static NO_LAYOUT_FITS: Rule = Rule {
    id: "joint.no_layout_fits",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "under `auto`, the plates lie side by side in one plane, one on the other, or as a web on a flange",
    reason: "With no joint type named, the layers of planes decide it: two plates side by side in one plane are a \
             butt joint, two layers one plate thickness apart a lap, a web's top over its flange a tee; and where \
             neither a butt nor a lap fits, a wider top standing more than a lap step over a plane seen on both \
             of its sides, a face seen falling from its edges to that plane, is a member standing on a plate (a \
             block), a tee each of whose sides is a root. (A clamp or bar lying across a butt or lap joint stands \
             so too, which is why the butt's and the lap's layers are weighed first.) Where the planes fit none \
             of these, the frame shows no joint the planner can tell; the refusal says why each layout failed.",
    parameters: &[
        COPLANAR_TOLERANCE,
        LAP_STEP_MIN,
        LAP_STEP_MAX,
        SIDE_BY_SIDE_AREA_RATIO,
        WEB_HEIGHT_MAX,
        FALL_MIN_POINTS,
        FALL_HEIGHT_BANDS,
    ],
    fires: &[
        "src/pipeline/background/tests.rs::with_no_type_given_the_layers_decide",
        "src/pipeline/background/tests.rs::a_third_plate_beside_a_butt_pair_is_refused_and_a_piece_along_it_is_not",
        "tests/measured_clouds.rs::a_clamp_across_the_smaller_plate_is_no_lap_s_upper_plate",
        "src/pipeline/background/standing_tests.rs::a_wide_top_with_no_face_falling_to_the_plate_or_no_higher_than_a_lap_step_is_no_web",
    ],
    holds: &[
        "src/pipeline/background/tests.rs::with_no_type_given_the_layers_decide",
        "src/pipeline/background/standing_tests.rs::a_block_standing_on_a_plate_is_a_tee_by_the_face_falling_from_its_top",
    ],
};

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
    fires: &[
        "tests/cli.rs::failures_exit_non_zero_and_say_why",
        "tests/several_seams.rs::a_set_of_joint_types_plans_the_workpieces_of_those_types_and_names_the_others",
    ],
    holds: &["tests/several_seams.rs::a_set_of_joint_types_plans_the_workpieces_of_those_types_and_names_the_others"],
};

pub static WEB_FACE_WITHOUT_TOP: Rule = Rule {
    id: "tee.web_face_without_top",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "a face standing on the nearest plane with no top in view is a tee's web, without a request, only \
              where it stands taller than a lap's upper plate and, beside a butt pair or a lap the layers read, \
              only where that reading fails; under a request that admits no tee it is named",
    reason: "A tee's web cropped below its top shows its side faces standing on the flange, and no top. Without \
             a request the same evidence decides whether the table behind is in view or not: the layers' \
             reading first where there are planes enough for a butt pair or a lap (a tube on a beam: the \
             beam's top in pieces either side of the tube, the table behind), and where it fails its gates, or \
             with a lone plane in view, the root of each face of the member standing there (a box section or a \
             block shows two, meeting along an edge) where it passes every gate of a tee; else the refusal of \
             the reading that got further. An inside corner's standing plate is welded along the same root. A \
             fixture's side is not taken for a web: its top is a plane nearer the camera than the plates, so \
             the nearest layer is its top and nothing stands on it; and a face seen no taller than a lap's \
             upper plate (as a clamp or a bar whose top goes unseen may stand) is not proposed but named, as \
             is every face under a request that admits no tee, saying to request `t_fillet`.",
    parameters: &[
        Parameter {
            name: "tee_web_height_max_mm",
            unit: "mm",
            meaning: "tallest web a face may belong to",
            source: Source::Config("pipeline.tee_web_height_max_mm"),
        },
        Parameter {
            name: "lap_step_max_mm",
            unit: "mm",
            meaning: "without a request, a face must be seen taller than this",
            source: Source::Config("pipeline.lap_step_max_mm"),
        },
    ],
    fires: &["tests/several_seams.rs::a_tee_cropped_round_its_root_is_planned_from_its_face_alone"],
    holds: &[
        "tests/several_seams.rs::a_tee_cropped_round_its_root_is_planned_from_its_face_alone",
        "tests/several_seams.rs::under_auto_a_face_standing_between_flange_pieces_is_planned_where_the_butt_pair_fails",
    ],
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

pub static LAP_NEARER_THAN_BUTT_PAIR: Rule = Rule {
    id: "joint.lap_nearer_than_butt_pair",
    stage: Stage::Background,
    effect: Effect::ChangesJoint,
    gate: None,
    summary: "under `auto`, where both a coplanar pair and a lap's two layers are found, a plate nearer the camera \
              than the pair, over a lower plate of its own, makes the joint a lap",
    reason: "A frame can hold two plates side by side in one plane and a plate lying one plate thickness over \
             another: a lap over a table whose pieces lie coplanar, or a clamp or a fixture lying across a butt \
             joint. The joint is the one nearest the camera, the camera being set up over the work: a plate \
             nearer than the pair, as large as a plate beside it and over a lower plate of its own (not lying \
             across the pair), is a lap's upper plate, and the joint is planned as a lap; otherwise the pair is \
             the butt joint and what lies over it is not a plate.",
    parameters: &[
        Parameter {
            name: "SIDE_BY_SIDE_AREA_RATIO",
            unit: "",
            meaning: "least area of the upper plate, as a share of the pair's second plate",
            source: Source::Constant { file: "src/pipeline/background/placement.rs", name: "SIDE_BY_SIDE_AREA_RATIO" },
        },
        Parameter {
            name: "lap_step_max_mm",
            unit: "mm",
            meaning: "thickest plate a lap's step may be",
            source: Source::Config("pipeline.lap_step_max_mm"),
        },
    ],
    fires: &["src/pipeline/background/tests.rs::with_no_type_given_the_layers_decide"],
    holds: &["src/pipeline/background/tests.rs::with_no_type_given_the_layers_decide"],
};
