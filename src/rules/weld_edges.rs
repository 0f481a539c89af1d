//! The rules of the weld-edge stage (`Stage::WeldEdges`): which two edge
//! lines are the joint's, and for a lap, whether the upper plate's edge
//! chosen is where it ends on its lower plate.

use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &NO_LINE_BETWEEN_PLATES,
    &NO_PARALLEL_PAIR,
    &TWO_FACING_EDGES,
    &LOWER_PLATE_BESIDE_OTHER_EDGE,
    &UPPER_PLATE_NOT_PAST_LOWER,
    &UPPER_PLATE_WITHIN_LOWER_LAYER,
    &UPPER_PLATE_ENDS_OFF_LOWER,
];

const WELD_EDGES: &str = "src/pipeline/weld_edges.rs";

const OTHER_EDGE_MIN_ANGLE: Parameter = Parameter {
    name: "OTHER_EDGE_MIN_ANGLE_DEG",
    unit: "°",
    meaning: "how far an edge turns from the chosen one to be another edge of the plate",
    source: Source::Constant { file: WELD_EDGES, name: "OTHER_EDGE_MIN_ANGLE_DEG" },
};

const MIN_SHARED_SPAN: Parameter = Parameter {
    name: "MIN_SHARED_SPAN",
    unit: "",
    meaning: "the least share of the shorter edge two facing edges run side by side along",
    source: Source::Constant { file: WELD_EDGES, name: "MIN_SHARED_SPAN" },
};

pub static NO_LINE_BETWEEN_PLATES: Rule = Rule {
    id: "edge.no_line_between_plates",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: None,
    summary: "each plate has an edge line with the two plates' centroids on either side of it (Eq. 16)",
    reason: "The two plates of a joint lie on either side of the joint, so each plate's edge along it \
             separates the plates' centroids: the centroids lie on opposite sides of its line in the plates' \
             plane. Where a plate has no such line, its edge along the joint was not segmented (too few edge \
             points along it, out of view or under a dropout), and no line of it can stand for the seam.",
    parameters: &[],
    fires: &["src/pipeline/weld_edges.rs::paper_selection_needs_two_separating_lines"],
    holds: &["src/pipeline/weld_edges.rs::centroid_test_picks_the_facing_edges"],
};

pub static NO_PARALLEL_PAIR: Rule = Rule {
    id: "edge.no_parallel_pair",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: None,
    summary: "a separating edge line of one plate runs parallel to, and side by side with, one of the other's",
    reason: "A joint's two weld edges face each other across the gap: they run parallel, within what the \
             plates' cutting and the lines' fit leave, and side by side along most of their length. Edge \
             lines that separate the centroids but meet at an angle, or that lie end to end (two plates' \
             outer edges meeting at a corner), are no joint's pair.",
    parameters: &[
        Parameter {
            name: "max_edge_angle_deg",
            unit: "°",
            meaning: "the largest angle between the two weld edges",
            source: Source::Config("pipeline.max_edge_angle_deg"),
        },
        MIN_SHARED_SPAN,
    ],
    fires: &["src/pipeline/weld_edges.rs::separating_lines_at_right_angles_are_no_pair"],
    holds: &[
        "src/pipeline/weld_edges.rs::centroid_test_picks_the_facing_edges",
        "src/pipeline/weld_edges.rs::edges_meeting_end_to_end_are_not_a_facing_pair",
    ],
};

pub static TWO_FACING_EDGES: Rule = Rule {
    id: "edge.two_facing_edges",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: None,
    summary: "the nearest facing pair of edges is the plates' longest: no other pair, turned from it as a \
              part's end from its side, faces along a longer stretch",
    reason: "Two plates of a joint face each other along one edge. Where they also face each other along \
             another, turned from the first as a part's end is from its side, for a longer stretch, the \
             nearest pair is no answer: an object lying on a plate (a clamp) faces the plane under it along \
             its end and along its sides, and a lap's upper plate may end on its lower plate. Which edge is \
             the joint is not clear, and the seam is refused rather than planned along the wrong one.",
    parameters: &[OTHER_EDGE_MIN_ANGLE, MIN_SHARED_SPAN],
    fires: &["src/pipeline/weld_edges.rs::a_longer_facing_stretch_along_another_edge_is_refused"],
    holds: &["src/pipeline/weld_edges.rs::centroid_test_picks_the_facing_edges"],
};

pub static LOWER_PLATE_BESIDE_OTHER_EDGE: Rule = Rule {
    id: "lap.lower_plate_beside_other_edge",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: None,
    summary: "a lap's lower plate is seen beside the upper plate's chosen edge for longer than beside any \
              edge turned from it",
    reason: "A lap's lower plate runs along its upper plate's side, the joint; it is seen beside the upper \
             plate's end only where the two overlap. Where it is seen beside an end for longer than beside \
             the chosen side, the upper plate may end on the lower plate, or the lower plate may show only as \
             a sliver along the joint (barely in view, its lines separating no centroids) and the end's pair \
             was the only candidate: which edge is the joint is not clear.",
    parameters: &[OTHER_EDGE_MIN_ANGLE],
    fires: &[
        "src/pipeline/weld_edges.rs::a_lap_s_lower_plate_seen_longer_beside_another_edge_is_refused",
        "tests/faults.rs::a_laps_lower_plate_seen_past_the_upper_plates_end_and_as_a_sliver_beside_it_is_refused",
    ],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};

pub static UPPER_PLATE_NOT_PAST_LOWER: Rule = Rule {
    id: "lap.upper_plate_not_past_lower",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: None,
    summary: "a lap's upper plate reaches past its lower plate's edge somewhere along each of its ends in view",
    reason: "A lap's lower plate ends under its upper plate, so beside the upper plate's end it is seen only \
             as far as the two overlap: at most about half of the end on laps of every simulated suite. A \
             plate lying on the table, its far edge out of view, shows the same two layers as a lap (butt \
             plates the cloud sees as one across a gap it does not resolve, for one), with the table seen \
             beside all of each end. The upper plate must reach past the plane under it along part of an end.",
    parameters: &[
        Parameter {
            name: "LOWER_PLATE_ALONG_END_SHARE",
            unit: "",
            meaning: "the share of an end beside which the lower plate shows the plate lying on it",
            source: Source::Constant { file: WELD_EDGES, name: "LOWER_PLATE_ALONG_END_SHARE" },
        },
        OTHER_EDGE_MIN_ANGLE,
    ],
    fires: &[
        "src/pipeline/weld_edges.rs::a_lap_s_upper_plate_must_reach_past_its_lower_plate_somewhere",
        "tests/measured_clouds.rs::plates_seen_as_one_on_the_table_are_no_lap_s_upper_plate",
    ],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};

pub static UPPER_PLATE_WITHIN_LOWER_LAYER: Rule = Rule {
    id: "lap.upper_plate_within_lower_layer",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: None,
    summary: "the plane under a lap's upper plate is not seen beside most of the plate's far edge",
    reason: "A lap's lower plate ends under its upper plate, so beyond the upper plate's far edge (across the \
             plate from the weld edge) lies whatever the lower plate rests on, not the lower plate's layer. \
             Where that layer runs beside most of the far edge too, the upper plate lies on it whole: a part \
             on the table or on spacers (butt plates seen as one across a gap the cloud does not resolve), or \
             a plate lapped on a larger one all round, whose weld edge the frame does not tell.",
    parameters: &[Parameter {
        name: "LOWER_LAYER_BESIDE_FAR_EDGE_SHARE",
        unit: "",
        meaning: "the share of the far edge beside which the layer shows the plate lying on it whole",
        source: Source::Constant { file: WELD_EDGES, name: "LOWER_LAYER_BESIDE_FAR_EDGE_SHARE" },
    }],
    fires: &[
        "src/pipeline/weld_edges.rs::a_lap_s_upper_plate_must_not_lie_within_the_plane_under_it",
        "tests/measured_clouds.rs::plates_seen_as_one_with_the_table_all_round_are_no_lap_s_upper_plate",
    ],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};

pub static UPPER_PLATE_ENDS_OFF_LOWER: Rule = Rule {
    id: "lap.upper_plate_ends_off_lower",
    stage: Stage::WeldEdges,
    effect: Effect::Refuses,
    gate: Some(Gate::JointUnknown),
    summary: "where the request leaves a butt joint open, a lap's upper plate is seen to end off the plane \
              under it somewhere besides the weld edge",
    reason: "A step between two planes is what a lap's plates show, and also what a plate or a workpiece seen \
             as one shows lying on the table with its other edges out of view. A lap's lower plate ends under \
             its upper plate, so beyond the far edge, and beside an end past the overlap, the upper plate \
             ends off that plane; where no edge in view does (the others along the image's border, a slit \
             with the plate seen beyond, or the plane beside most of them), the frame does not tell a lap \
             from a plate on the table. Under `auto` that is refused as not told; a request for a lap says \
             what the lower plane is and is planned.",
    parameters: &[Parameter {
        name: "LOWER_PLANE_OFF_EDGE_SHARE",
        unit: "",
        meaning: "the share of an edge in view beside which the plane under it shows the plate lying on it",
        source: Source::Constant { file: WELD_EDGES, name: "LOWER_PLANE_OFF_EDGE_SHARE" },
    }],
    fires: &[
        "src/pipeline/weld_edges.rs::a_lap_s_upper_plate_must_be_seen_to_end_off_the_plane_under_it",
        "tests/measured_clouds.rs::a_step_across_the_view_and_nothing_else_is_named_by_the_request_not_by_auto",
    ],
    holds: &["tests/joints.rs::auto_names_each_joint_measures_the_groove_and_plans_it_within_the_bar"],
};
