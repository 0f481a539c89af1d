//! The rules of the weld equation stage (`Stage::WeldEquation`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &FILLET_NOT_FROM_EDGES,
    &EDGES_IN_DIFFERENT_AXES,
    &EDGES_COLLINEAR,
    &LAP_NO_STEP_ALONG_NORMAL,
    &EDGES_DO_NOT_OVERLAP,
    &WELD_ON_BEVEL_MIDLINE,
    &LAP_SEAM_ENDS_WHERE_LOWER_PLATE_ENDS,
];

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

pub static EDGES_COLLINEAR: Rule = Rule {
    id: "seam.edges_collinear",
    stage: Stage::WeldEquation,
    effect: Effect::Refuses,
    gate: None,
    summary: "in the paper's method, the two weld edges' ends span a plane, so the plate normal is defined",
    reason: "The paper's method takes the plates' normal from the weld edges' end points (Eq. 33, 34): the \
             cross product of one edge's direction with the step to the other. Two edges that lie on one line \
             (the same edge found twice, or two plates' edges meeting end to end) span no plane, so no normal \
             says where the torch stands or which way a groove's depth runs.",
    parameters: &[],
    fires: &["src/pipeline/paper.rs::an_edge_of_too_few_points_or_collinear_edges_are_refused_by_rule"],
    holds: &["tests/pipeline.rs::the_papers_method_stays_reachable_and_plans_a_frontal_scene"],
};

pub static LAP_NO_STEP_ALONG_NORMAL: Rule = Rule {
    id: "lap.no_step_along_normal",
    stage: Stage::WeldEquation,
    effect: Effect::Refuses,
    gate: None,
    summary: "a lap's lower plate faces along the plates' normal, so the step down to its root is measured along it",
    reason: "A lap's weld lies at the root, the upper plate's edge moved down the step to the lower plate's \
             surface along the plates' normal (Eq. 38). A lower plate turned nearly square to that normal \
             (more than about 84 degrees) is met by the normal far from the edge or never, so the step and the \
             root it places mean nothing; such plates are no lap.",
    parameters: &[Parameter {
        name: "MIN_STEP_COSINE",
        unit: "",
        meaning: "least cosine between the plates' normal and the lower plate's",
        source: Source::Constant { file: "src/pipeline/weld_equation.rs", name: "MIN_STEP_COSINE" },
    }],
    fires: &[
        "src/pipeline/robust/plates/tests.rs::a_lap_without_a_step_or_edges_that_do_not_overlap_are_refused_by_rule",
    ],
    holds: &["tests/pipeline.rs::lap_is_planned_at_the_root_from_either_side"],
};

pub static EDGES_DO_NOT_OVERLAP: Rule = Rule {
    id: "seam.edges_do_not_overlap",
    stage: Stage::WeldEquation,
    effect: Effect::Refuses,
    gate: None,
    summary: "the two weld edges are seen side by side along some stretch of the seam",
    reason: "The weld is planned only where both edges were seen, the stretch along the seam where their \
             extents overlap (for a lap, also where the root is in view). Two edges seen at different places \
             along the seam, one ending before the other begins, show two plates' edges but no joint between \
             them: nowhere is the gap, the groove or the step seen from both sides.",
    parameters: &[],
    fires: &[
        "src/pipeline/robust/plates/tests.rs::a_lap_without_a_step_or_edges_that_do_not_overlap_are_refused_by_rule",
    ],
    holds: &["tests/pipeline.rs::each_joint_type_is_planned_within_a_millimetre"],
};

pub static WELD_ON_BEVEL_MIDLINE: Rule = Rule {
    id: "groove.weld_on_bevel_midline",
    stage: Stage::WeldEquation,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "a V-groove's weld line, ends and all, lies on the midline of its edges as its two bevels place them",
    reason: "A V-groove's weld edges are read where the plates' points stop, and the boundary strips walk some \
             way down each bevel before leaving the plate's plane: a bevel 30 degrees off the plates stays within \
             the on-plane tolerance for most of a millimetre, more under noise, and the bevel turned to the camera, \
             seen more densely, loses more. Each bevel's fitted line carried up to the plates' top meets it at the \
             groove's true edge, so where both sides show a sloped face the weld line (Eq. 32) is moved onto the \
             midline of those two edges; with no bevel on either side it stays on the weld edges' midline. \
             A groove cut by hand or by a torch has ragged top edges, or one cut back along part of the seam, \
             while its flanks run clean to a root that did not move: where the weld so placed fails a gate that \
             reads the top edges (samples beyond or on two lines, a fit residual, the joint's coverage, the \
             plates seen past the seam's ends) and both sides show a sloped plane face down to the root, the \
             weld is placed on the root itself, midway between the two flanks' feet at the groove's depth, \
             station by station along every stretch either edge was seen, its ends where both flanks show it; \
             the same gates then read the root's own samples in place of the edges'.",
    parameters: &[Parameter {
        name: "MAX_FLANK_RMS_SPACINGS",
        unit: "point spacings",
        meaning: "largest RMS of a flank about its own stations' lines for the root to be read from it",
        source: Source::Constant { file: "src/pipeline/groove/root.rs", name: "MAX_FLANK_RMS_SPACINGS" },
    }],
    fires: &[
        "src/pipeline/groove/tests.rs::a_v_groove_s_bevels_place_its_edges_where_the_edges_given_are_read_inside_it",
        "src/sim/groove_width.rs::a_groove_cut_back_along_part_of_its_seam_is_welded_on_its_root",
    ],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};

pub static LAP_SEAM_ENDS_WHERE_LOWER_PLATE_ENDS: Rule = Rule {
    id: "lap.seam_ends_where_lower_plate_ends",
    stage: Stage::WeldEquation,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "a lap's seam ends where its lower plate is last seen inside its edge, not where the upper plate's \
              face runs on",
    reason: "Where a lap's upper plate runs on past the lower plate's end, the foot of the upper plate's side face \
             lies in the lower plate's plane and is taken for the lower plate's edge, running on past where the \
             plate ends. Along that stretch the pixels just inside the lower edge, in view, see no lower plate (its \
             shadow, or the table far below); the lower plate has ended there, the root with it, and the seam's \
             end is moved back to where the lower plate was last seen beside the weld.",
    parameters: &[
        Parameter {
            name: "SURFACE_INSET_SPACINGS",
            unit: "point spacings",
            meaning: "how far inside the lower edge the plate is looked for",
            source: Source::Constant { file: "src/pipeline/boundary/ends.rs", name: "SURFACE_INSET_SPACINGS" },
        },
        Parameter {
            name: "MIN_STATIONS_UNSEEN",
            unit: "",
            meaning: "fewest stations in view, without the plate, that show it ended",
            source: Source::Constant { file: "src/pipeline/boundary/ends.rs", name: "MIN_STATIONS_UNSEEN" },
        },
    ],
    fires: &["tests/faults.rs::a_laps_seam_ends_where_its_lower_plate_ends_not_where_its_upper_plate_does"],
    holds: &["tests/pipeline.rs::lap_is_planned_at_the_root_from_either_side"],
};
