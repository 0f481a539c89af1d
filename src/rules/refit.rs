//! The rules of the refit stage (`Stage::Refit`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &SEAM_END_READ_FROM_PLATE_RIM,
    &TEE_WEB_NOT_OVER_FLANGE,
    &TEE_ROOT_HIDDEN_BY_WEB,
    &TEE_SIDE_FACE_IS_WEB_END,
    &TEE_SIDE_FACE_ALONG_CAMERA_RAYS,
    &TEE_FLANGE_EDGE_AT_SHADOW,
    &TEE_FLANGE_EDGE_PAST_WEB_TOP,
    &TEE_ROOT_NOT_SEEN,
    &TEE_ROOT_LONGEST_SEEN_RUN,
    &TEE_ROOT_ENDS_AT_IMAGE_BORDER,
    &TEE_ROOT_RUNS_PAST_CUT_FOOT,
    &TEE_SHORT_FACE_GIVES_WAY_TO_FLANGE_EDGE,
    &TEE_FLANGE_EDGE_READ_ALONG_ITSELF,
    &TEE_FLANGE_EDGE_ENDS_WITH_WEB_TOP,
    &TEE_NO_ROOT_SEEN,
    &SEAM_SAMPLES_NOT_ALONG_A_LINE,
    &EDGE_TOO_FEW_POINTS_TO_FIT,
    &SEAM_END_AT_IMAGE_BORDER,
    &SEAM_LONGEST_SEEN_STRETCH,
];

const RIM: &str = "src/pipeline/boundary/rim.rs";

pub static SEAM_END_READ_FROM_PLATE_RIM: Rule = Rule {
    id: "seam.end_read_from_plate_rim",
    stage: Stage::Refit,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "where the cloud's border cuts a plate beside the weld, the seam ends where the plate's rim ends",
    reason: "Without a pixel grid a plate's boundary is read in strips across the weld edge. Where the image's \
             border or a crop cuts the plate beside the weld obliquely, a strip there holds part of the plate \
             only: it misses the edge (the seam stops short) or takes the border for it (the seam runs on past \
             the plate). The plate's last rows, just inside the fitted edge, run exactly as far as the plate does, \
             and nothing beyond the edge lies in them, so the seam's end is read again along them, but only where \
             the cloud itself ends beyond them (where the table or a shadow lies past a plate's own end, the \
             strips read that end) and where the edge's fit is steady enough to place the rows.",
    parameters: &[
        Parameter {
            name: "RIM_ROWS_SPACINGS",
            unit: "point spacings",
            meaning: "the rows read, inside the fitted edge",
            source: Source::Constant { file: RIM, name: "RIM_ROWS_SPACINGS" },
        },
        Parameter {
            name: "RIM_BREAK_SPACINGS",
            unit: "point spacings",
            meaning: "longest step along the rim still one plate",
            source: Source::Constant { file: RIM, name: "RIM_BREAK_SPACINGS" },
        },
        Parameter {
            name: "RIM_AT_BORDER_SPACINGS",
            unit: "point spacings",
            meaning: "rows beyond the rim's end that must hold no point for the cloud to end there",
            source: Source::Constant { file: RIM, name: "RIM_AT_BORDER_SPACINGS" },
        },
        Parameter {
            name: "MAX_RIM_EDGE_RMS_SPACINGS",
            unit: "point spacings",
            meaning: "most scatter of the edge's fit that still places the rows",
            source: Source::Constant { file: RIM, name: "MAX_RIM_EDGE_RMS_SPACINGS" },
        },
    ],
    fires: &[
        "src/pipeline/boundary/tests.rs::the_rim_reaches_a_border_that_cuts_the_band_inside_the_plate",
        "src/pipeline/boundary/tests.rs::the_rim_stops_where_a_border_cuts_the_edge_away",
    ],
    holds: &[
        "src/pipeline/boundary/tests.rs::past_a_plate_end_where_the_table_is_seen_the_strips_keep_the_end",
        "src/pipeline/boundary/tests.rs::an_edge_fitted_to_noisy_samples_keeps_the_strips_ends",
    ],
};

const FILLET: &str = "src/pipeline/fillet/mod.rs";

const FILLET_FACE: &str = "src/pipeline/fillet/face.rs";

const FILLET_EDGE: &str = "src/pipeline/fillet/flange_edge.rs";

const FILLET_STRETCH: &str = "src/pipeline/fillet/stretch.rs";

const MIN_FACE_POINTS: Parameter = Parameter {
    name: "MIN_FACE_POINTS",
    unit: "",
    meaning: "fewest points that make a face, or a flange seen on one side of the web",
    source: Source::Constant { file: FILLET, name: "MIN_FACE_POINTS" },
};

const STATION_SPACINGS: Parameter = Parameter {
    name: "STATION_SPACINGS",
    unit: "point spacings",
    meaning: "length of a station along the root",
    source: Source::Constant { file: FILLET_STRETCH, name: "STATION_SPACINGS" },
};

const JOINT_BREAK_SPACINGS: Parameter = Parameter {
    name: "JOINT_BREAK_SPACINGS",
    unit: "point spacings",
    meaning: "longest break along the root bridged as the same root",
    source: Source::Constant { file: "src/pipeline/boundary/ends.rs", name: "JOINT_BREAK_SPACINGS" },
};

const BORDER_REACH_SPACINGS: Parameter = Parameter {
    name: "BORDER_REACH_SPACINGS",
    unit: "point spacings",
    meaning: "evidence this near the image's border reaches it",
    source: Source::Constant { file: "src/pipeline/view_border.rs", name: "BORDER_REACH_SPACINGS" },
};

const MAX_JOINT_BEYOND_SEAM_MM: Parameter = Parameter {
    name: "max_joint_beyond_seam_mm",
    unit: "mm",
    meaning: "how far the joint may be seen past the root's ends",
    source: Source::Config("quality.max_joint_beyond_seam_mm"),
};

pub static TEE_WEB_NOT_OVER_FLANGE: Rule = Rule {
    id: "tee.web_not_over_flange",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "the web's top stands over the flange's plane, along a direction the flange's plane holds",
    reason: "A fillet root lies where a web standing on a flange meets it, and is read in the web's frame: the \
             flange's normal, the web's long axis laid in the flange's plane and the direction across it. \
             Where the flange's points span no plane, the web's top runs along the flange's normal, its points \
             are too few to place its edges, or it lies on the far side of the flange from the camera, no web \
             stands on that flange, and no root is read on either side.",
    parameters: &[],
    fires: &["src/pipeline/fillet/tests.rs::a_web_top_under_the_flange_gives_no_root"],
    holds: &["src/pipeline/fillet/tests.rs::the_root_is_where_the_face_meets_the_flange_and_runs_where_both_are_seen"],
};

pub static TEE_ROOT_HIDDEN_BY_WEB: Rule = Rule {
    id: "tee.root_hidden_by_web",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "a root is read only on a side of the web the camera sees: the flange seen beside the web there, and, \
              with the web's top out of view, the side of the face seen",
    reason: "A web stands steeply on its flange, so from one viewpoint it hides its far face and the flange \
             beside it, from the camera or from the projector. Where fewer than a face's worth of flange points \
             lie beyond the web's edge on one side, nothing shows where that root is. Where the web's top is out \
             of view (a crop round one root), the one side face seen places the web; the other face, behind it, \
             is neither seen nor placed. A member standing with every side a root (a block, wider than a web is \
             thick) shows a side face only to a camera outside that face: from over its top or beyond it the \
             face is seen from behind its plane, and the flange's edge beside it is where the member hides the \
             flange, not its root. Such a root is named as not planned, never invented.",
    parameters: &[MIN_FACE_POINTS],
    fires: &[
        "src/pipeline/fillet/tests.rs::a_web_seen_by_one_face_only_gives_that_face_s_root_and_names_the_other",
        "src/pipeline/fillet/tests.rs::a_flange_seen_on_one_side_only_gives_no_root_on_the_other",
    ],
    holds: &["src/pipeline/fillet/tests.rs::a_flange_in_one_piece_round_the_webs_end_is_seen_on_both_sides"],
};

pub static TEE_SIDE_FACE_IS_WEB_END: Rule = Rule {
    id: "tee.side_face_is_web_end",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "the points standing on one side of the web run along the web's top, as its side face does; a face \
              seen without the web's top runs longer than the thickest web",
    reason: "A web's side face runs the web's length, its foot along the top's long axis whether the web stands \
             square or leans. Where the side face is turned edge-on to the camera it returns nothing, and what \
             stands on that side of the web's middle may be the web's end face, across the web: its foot is a \
             few millimetres of the web's thickness, not the root. Points whose foot turns further from the \
             top's long axis than the axis's own uncertainty and a lean allow are not the side face; the root \
             is then read from the flange's edge, and left unplanned when that does not show it either. With \
             the web's top out of view there is no long axis to turn from, and a web's end stands on the \
             flange as a side face does: a face whose root is seen no longer than the thickest web is not \
             taken for a side face.",
    parameters: &[
        Parameter {
            name: "MAX_ROOT_SKEW_DEG",
            unit: "°",
            meaning: "most a face's foot may turn from the web top's long axis",
            source: Source::Constant { file: FILLET_FACE, name: "MAX_ROOT_SKEW_DEG" },
        },
        Parameter {
            name: "tee_web_thickness_max_mm",
            unit: "mm",
            meaning: "with the web's top out of view, a face's root must be seen longer than this",
            source: Source::Config("pipeline.tee_web_thickness_max_mm"),
        },
    ],
    fires: &[
        "src/pipeline/fillet/tests.rs::the_webs_end_face_is_no_side_face_and_the_root_runs_to_the_webs_end",
        "src/pipeline/fillet/tests.rs::a_face_seen_without_the_web_s_top_no_longer_than_a_web_is_thick_may_be_its_end",
    ],
    holds: &[
        "src/pipeline/fillet/tests.rs::a_face_seen_higher_up_along_the_web_gives_its_root_all_along",
        "src/pipeline/fillet/tests.rs::a_face_seen_without_the_web_s_top_no_longer_than_a_web_is_thick_may_be_its_end",
    ],
};

pub static TEE_SIDE_FACE_ALONG_CAMERA_RAYS: Rule = Rule {
    id: "tee.side_face_along_camera_rays",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "the web's side face is turned towards the camera by more than a few degrees",
    reason: "A structured-light camera samples a surface only where it is turned towards the camera's rays; a \
             depth jump at the web's edge instead leaves a veil of mixed returns hanging along the rays, from \
             the web's top down to whatever lies behind. Points between the flange and the web's top that lie \
             along the rays are that veil, not the web's face, and their root would be invented. The root is \
             then read from the flange's edge, and left unplanned when that does not show it either.",
    parameters: &[Parameter {
        name: "MIN_FACE_VIEW_DEG",
        unit: "°",
        meaning: "least angle between a face and the camera's ray to it",
        source: Source::Constant { file: FILLET_FACE, name: "MIN_FACE_VIEW_DEG" },
    }],
    fires: &["src/pipeline/fillet/tests.rs::mixed_returns_along_the_rays_are_no_side_face"],
    holds: &["src/pipeline/fillet/tests.rs::a_face_seen_higher_up_along_the_web_gives_its_root_all_along"],
};

pub static TEE_FLANGE_EDGE_AT_SHADOW: Rule = Rule {
    id: "tee.flange_edge_at_shadow",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "a root read from the flange's edge implies a face turned towards both the camera and the projector",
    reason: "A face turned edge-on returns no points while its root is in plain view, and the flange's edge \
             against the web then shows the root. A flange also ends at the edge of the web's shadow, from the \
             camera or from the projector: there the face from the flange's edge up to the web top's edge holds \
             the ray that grazes the top's edge, turned from the shadowing eye by nothing. Each edge's sampling \
             may move that implied face by a spacing, so the root is taken only when the face is turned towards \
             both eyes by more than a few spacings over the web's height; otherwise the edge may be a shadow's, \
             and the root is not planned.",
    parameters: &[Parameter {
        name: "EDGE_VIEW_SPACINGS",
        unit: "point spacings",
        meaning: "how far, over the web's height, the implied face must turn towards both eyes",
        source: Source::Constant { file: FILLET_EDGE, name: "EDGE_VIEW_SPACINGS" },
    }],
    fires: &[
        "tests/several_seams.rs::a_tee_s_seen_root_is_planned_within_the_fillet_bar_and_the_hidden_one_named",
        "src/pipeline/fillet/tests.rs::a_face_edge_on_to_the_camera_gives_its_root_from_the_flange_edge_and_a_shadow_edge_gives_none",
        "src/pipeline/fillet/tests.rs::a_flange_ending_at_the_projectors_shadow_gives_no_root",
        "tests/several_seams.rs::an_edge_on_face_gives_its_root_from_the_flange_edge_and_a_shadow_edge_none",
    ],
    holds: &["src/pipeline/fillet/tests.rs::a_web_top_seen_all_along_the_root_covers_it_whatever_its_stations"],
};

pub static TEE_FLANGE_EDGE_PAST_WEB_TOP: Rule = Rule {
    id: "tee.flange_edge_past_web_top",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "a root read from the flange's edge runs no further past the web's top seen than the coverage gate \
              allows, unless the image's border cut the top there",
    reason: "The flange's edge runs on nearly straight past the web's end (the web's end hides the flange behind \
             it a little more at each step), so a root read from it is clipped to where the web's top is seen. \
             Where the edge runs on further than the coverage gate allows and neither the camera's pixel grid \
             nor the cloud's rays show where the image ends, the web may end there or the image may have cut \
             its top: the root's end cannot be told, and the root is not planned.",
    parameters: &[MAX_JOINT_BEYOND_SEAM_MM],
    fires: &["src/pipeline/fillet/tests.rs::a_flange_edge_running_past_the_web_top_with_no_border_gives_no_root"],
    holds: &["src/pipeline/fillet/tests.rs::the_webs_end_face_is_no_side_face_and_the_root_runs_to_the_webs_end"],
};

pub static TEE_ROOT_NOT_SEEN: Rule = Rule {
    id: "tee.root_not_seen",
    stage: Stage::Refit,
    effect: Effect::LeavesUnplanned,
    gate: None,
    summary: "a root is seen: the web's side face down to its foot and the flange up to it together somewhere \
              along the root, or the flange's edge under the web top's edge",
    reason: "A fillet root is the line where the web's side face meets the flange, and is read only where both \
             are seen: the face's foot (its lowest band at each station along the root) and flange points a few \
             spacings outward of the root, in the same station. A face turned edge-on returns nothing, and then \
             the flange's edge against the web, seen at enough stations, stands in for it under the web top's \
             edge. Where neither shows the root (the face too sparse to fit, seen nowhere down to the flange, the \
             flange not seen up to it, or the edges seen at too few stations) the root is not planned.",
    parameters: &[
        MIN_FACE_POINTS,
        STATION_SPACINGS,
        Parameter {
            name: "MIN_EDGE_STATIONS",
            unit: "",
            meaning: "fewest stations that make an edge's line",
            source: Source::Constant { file: FILLET_EDGE, name: "MIN_EDGE_STATIONS" },
        },
        Parameter {
            name: "FLANGE_REACH_SPACINGS",
            unit: "point spacings",
            meaning: "how far outward of the root a flange point shows the flange seen up to it",
            source: Source::Constant { file: FILLET_FACE, name: "FLANGE_REACH_SPACINGS" },
        },
    ],
    fires: &["src/pipeline/fillet/tests.rs::a_face_whose_flange_is_not_seen_up_to_it_gives_no_root"],
    holds: &["src/pipeline/fillet/tests.rs::a_flange_in_one_piece_round_the_webs_end_is_seen_on_both_sides"],
};

pub static TEE_NO_ROOT_SEEN: Rule = Rule {
    id: "tee.no_root_seen",
    stage: Stage::Refit,
    effect: Effect::Refuses,
    gate: None,
    summary: "at least one root of a tee (or of an inside corner) is read and passes the gates",
    reason: "One view sees at most one root of a tee well, and sometimes none: the web hides its far side, its \
             near face may be edge-on to the camera with its flange ending at a shadow. A tee with no root \
             planned is refused, by the gate that refused a root seen where one did, else saying why each root \
             was not read; nothing is welded on a guess.",
    parameters: &[],
    fires: &["tests/several_seams.rs::a_tee_whose_roots_are_not_seen_is_refused_saying_why"],
    holds: &["tests/several_seams.rs::a_tee_s_seen_root_is_planned_within_the_fillet_bar_and_the_hidden_one_named"],
};

pub static TEE_ROOT_LONGEST_SEEN_RUN: Rule = Rule {
    id: "tee.root_longest_seen_run",
    stage: Stage::Refit,
    effect: Effect::CutsSeam,
    gate: None,
    summary: "the root planned is the longest run of stations where it is seen, across short breaks",
    reason: "A root is planned only where its evidence is seen together, station by station. A break no longer \
             than a dropout or a narrow streak across the joint is bridged; beyond a longer one the root may \
             not go on (the web ends, something stands on the flange), so only the longest run seen is planned \
             and the rest is cut off, its share of the root reported for the coverage gate.",
    parameters: &[STATION_SPACINGS, JOINT_BREAK_SPACINGS],
    fires: &["src/pipeline/fillet/tests.rs::a_face_seen_past_a_long_break_gives_its_longest_run"],
    holds: &["src/pipeline/fillet/tests.rs::the_run_seen_bridges_short_breaks_and_not_long_ones"],
};

pub static TEE_ROOT_ENDS_AT_IMAGE_BORDER: Rule = Rule {
    id: "tee.root_ends_at_image_border",
    stage: Stage::Refit,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "where a root's evidence runs up to the image's border, the root ends where the border crosses the \
              root itself",
    reason: "The face's foot and the flange beside the root lie a spacing or more off the root, so an image \
             border crossing the root obliquely cuts them before or after it cuts the root. Where both run up \
             to the border within the last station, the root's end is moved, by at most a station, to where \
             the border crosses the root line; an end the evidence does not carry to the border stays where the \
             evidence puts it.",
    parameters: &[STATION_SPACINGS, BORDER_REACH_SPACINGS],
    fires: &[
        "src/pipeline/fillet/tests.rs::a_root_whose_evidence_reaches_the_image_border_ends_where_the_border_crosses_it",
    ],
    holds: &["src/pipeline/fillet/tests.rs::the_root_is_where_the_face_meets_the_flange_and_runs_where_both_are_seen"],
};

pub static TEE_ROOT_RUNS_PAST_CUT_FOOT: Rule = Rule {
    id: "tee.root_runs_past_cut_foot",
    stage: Stage::Refit,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "where the image's border, not the web, ends a face's foot seen well up the face, the root runs on \
              along the flange seen up to it",
    reason: "A face turned nearly edge-on is seen only well above the flange, and a tilted camera sees what \
             stands higher further in: where the image's border crosses the web, that foot leaves the view \
             before the root does. When the foot's last point lies at the border, the root runs on as far as \
             the flange is seen up to it (across short breaks, short of any flange seen under where the web \
             would stand), and never out of view.",
    parameters: &[STATION_SPACINGS, JOINT_BREAK_SPACINGS, BORDER_REACH_SPACINGS],
    fires: &["src/pipeline/fillet/tests.rs::a_root_runs_to_the_image_border_past_where_the_border_cuts_its_face"],
    holds: &["src/pipeline/fillet/tests.rs::a_face_seen_higher_up_along_the_web_gives_its_root_all_along"],
};

pub static TEE_SHORT_FACE_GIVES_WAY_TO_FLANGE_EDGE: Rule = Rule {
    id: "tee.short_face_gives_way_to_flange_edge",
    stage: Stage::Refit,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "a root read from a face seen along part of the web gives way to the flange's edge where that shows \
              a longer root",
    reason: "A face turned nearly edge-on returns points along part of the web only (where a gap lets the camera \
             see it, or where it turns a little less), and its root, read over that stretch, stops short of a \
             joint that goes on. Where the face's root runs less than half the web's top, or the web's top and \
             the flange up to the root are seen past its ends further than the coverage gate allows, the \
             flange's edge beside the same face is read, and its root taken when it is the longer.",
    parameters: &[
        Parameter {
            name: "MIN_FACE_RUN_SHARE",
            unit: "",
            meaning: "least share of the web top's length a face's root must run",
            source: Source::Constant { file: FILLET, name: "MIN_FACE_RUN_SHARE" },
        },
        MAX_JOINT_BEYOND_SEAM_MM,
    ],
    fires: &["src/pipeline/fillet/tests.rs::a_face_seen_along_part_of_the_web_gives_way_to_the_flanges_edge"],
    holds: &["src/pipeline/fillet/tests.rs::a_face_seen_higher_up_along_the_web_gives_its_root_all_along"],
};

pub static TEE_FLANGE_EDGE_READ_ALONG_ITSELF: Rule = Rule {
    id: "tee.flange_edge_read_along_itself",
    stage: Stage::Refit,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "a flange's edge turned from the web's axis by more than a degree is read again along its own line",
    reason: "The web's long axis comes from its top's spread, and lies off the web where the image's border cuts \
             the top obliquely. The flange's edge, looked for outward of the web's middle line along that axis, \
             then runs into the search's bound before the web ends, and the root would stop short. An edge \
             turned from the axis by more than a degree (a spacing every few centimetres) is read again in the \
             web's frame turned along the edge.",
    parameters: &[Parameter {
        name: "MAX_AXIS_TURN_DEG",
        unit: "°",
        meaning: "most the flange's edge may turn from the web's axis before it is read along itself",
        source: Source::Constant { file: FILLET_EDGE, name: "MAX_AXIS_TURN_DEG" },
    }],
    fires: &["src/pipeline/fillet/tests.rs::a_web_axis_off_the_web_is_read_again_along_the_flange_s_edge"],
    holds: &[
        "src/pipeline/fillet/tests.rs::a_face_edge_on_to_the_camera_gives_its_root_from_the_flange_edge_and_a_shadow_edge_gives_none",
    ],
};

pub static TEE_FLANGE_EDGE_ENDS_WITH_WEB_TOP: Rule = Rule {
    id: "tee.flange_edge_ends_with_web_top",
    stage: Stage::Refit,
    effect: Effect::CutsSeam,
    gate: None,
    summary: "a root read from the flange's edge ends where the web's top is seen, unless the image's border cut \
              the top there",
    reason: "Past the web's end the flange's edge runs on nearly straight, the web's end hiding the flange \
             behind it a little more at each step, so the edge alone does not show where the web ends: the root \
             is cut where the web's top ends. Where the image's border (the camera's grid, or the cloud's rays) \
             cut the top instead, the top, nearer the camera, left the image before the root did, and the root \
             runs on where the flange's edge does.",
    parameters: &[STATION_SPACINGS, BORDER_REACH_SPACINGS],
    fires: &["src/pipeline/fillet/tests.rs::the_webs_end_face_is_no_side_face_and_the_root_runs_to_the_webs_end"],
    holds: &["src/pipeline/fillet/tests.rs::a_web_axis_off_the_web_is_read_again_along_the_flange_s_edge"],
};

pub static SEAM_SAMPLES_NOT_ALONG_A_LINE: Rule = Rule {
    id: "seam.samples_not_along_a_line",
    stage: Stage::Refit,
    effect: Effect::Refuses,
    gate: None,
    summary: "the two weld edges' boundary samples spread along a line that lies across the plates' normal",
    reason: "The seam's axis, along which both edges are refitted and the weld is sampled, is the direction \
             the boundary samples of both edges spread along, laid in the plates' plane. Samples that spread \
             along no direction (none, or all at one place) or only along the plates' normal (a face seen \
             edge-on, not a plate's edge) give the seam no direction: there is no edge to follow.",
    parameters: &[],
    fires: &["src/pipeline/robust/plates/tests.rs::edge_samples_without_a_direction_in_the_plates_give_no_seam"],
    holds: &["tests/pipeline.rs::each_joint_type_is_planned_within_a_millimetre"],
};

pub static EDGE_TOO_FEW_POINTS_TO_FIT: Rule = Rule {
    id: "edge.too_few_points_to_fit",
    stage: Stage::Refit,
    effect: Effect::Refuses,
    gate: None,
    summary: "each weld edge has more points, spread along the seam, than its fitted curve has coefficients",
    reason: "Each weld edge is refitted as a polynomial along the seam (Eq. 17 to 25): a line needs two points \
             apart along it, and a curve of higher degree one more per degree, before a residual says anything \
             about how well the edge is placed. An edge with fewer (its plate seen as a sliver at the joint, its \
             boundary samples or line inliers all at one station) is not seen well enough to place a weld on.",
    parameters: &[Parameter {
        name: "fit_degree",
        unit: "",
        meaning: "degree of the polynomial each edge is fitted with",
        source: Source::Config("pipeline.fit_degree"),
    }],
    fires: &["src/pipeline/paper.rs::an_edge_of_too_few_points_or_collinear_edges_are_refused_by_rule"],
    holds: &["tests/pipeline.rs::the_papers_method_stays_reachable_and_plans_a_frontal_scene"],
};

pub static SEAM_END_AT_IMAGE_BORDER: Rule = Rule {
    id: "seam.end_at_image_border",
    stage: Stage::Refit,
    effect: Effect::MovesEnd,
    gate: None,
    summary: "where a plate runs on to the image's border beside its weld edge, the edge, and the seam, run on to \
              the border too",
    reason: "The plane criterion trims a plate's rim along the image's border as along any edge, so a weld edge's \
             boundary samples stop a rim's depth inside the border; where the seam leaves the image at a grazing \
             angle that depth becomes millimetres along the seam, and the seam would stop short of a joint that \
             goes on out of view. Where the plate is seen just inside its edge all the way to the border (on the \
             camera's grid: most pixels between the end and the border on the plate's plane; without a grid: the \
             plate's rim within a voxel or so of the border the cloud's rays span), the edge's end is moved to \
             where the fitted edge leaves the image. Where the plate ends first, or nothing is seen beyond the \
             end, the end stays where the samples put it. No edge runs on past where its own line leaves the \
             image (a plate's rows inside its edge cross an oblique border before or after the edge does). A \
             lap's joint is its upper edge and its root: the lower plate's edge, read where that plate's points \
             stop beside the root, does not end the seam where it leaves the image, and the root runs on to \
             where it leaves the image itself or the upper edge ends.",
    parameters: &[
        Parameter {
            name: "MAX_BORDER_REACH_MM",
            unit: "mm",
            meaning: "farthest an end moves to the border, on the camera's grid",
            source: Source::Constant { file: "src/pipeline/boundary/ends.rs", name: "MAX_BORDER_REACH_MM" },
        },
        Parameter {
            name: "MIN_ON_PLATE_TO_BORDER",
            unit: "",
            meaning: "least share of the pixels inside the edge, up to the border, on the plate's plane",
            source: Source::Constant { file: "src/pipeline/boundary/ends.rs", name: "MIN_ON_PLATE_TO_BORDER" },
        },
        BORDER_REACH_SPACINGS,
        Parameter {
            name: "END_EVIDENCE_SPACINGS",
            unit: "point spacings",
            meaning: "the rim's points read at an end, and the farthest, across the border, an end moves to it, \
                      without a grid",
            source: Source::Constant { file: "src/pipeline/view_border.rs", name: "END_EVIDENCE_SPACINGS" },
        },
    ],
    fires: &[
        "src/pipeline/view_border.rs::an_edge_read_short_of_an_oblique_border_runs_on_to_it_where_its_plate_does",
        "src/pipeline/view_border.rs::an_edge_the_border_crosses_at_a_shallow_angle_runs_on_to_it_from_where_its_plate_thins_out",
        "tests/faults.rs::a_groove_leaving_the_image_at_a_grazing_angle_is_planned_to_the_border",
        "tests/faults.rs::a_lap_leaving_the_image_obliquely_is_planned_to_where_its_joint_leaves_it",
        "src/pipeline/boundary/tests.rs::an_edge_standing_in_for_the_root_ends_the_seam_only_inside_the_view",
    ],
    holds: &["src/pipeline/view_border.rs::an_end_is_not_moved_when_any_evidence_stops_short_of_the_border"],
};

pub static SEAM_LONGEST_SEEN_STRETCH: Rule = Rule {
    id: "seam.longest_seen_stretch",
    stage: Stage::Refit,
    effect: Effect::CutsSeam,
    gate: None,
    summary: "in a cloud without a pixel grid, a weld edge runs along its longest stretch of boundary strips \
              unbroken by more than a few empty ones",
    reason: "Without a pixel grid a plate's boundary is read in strips across the weld edge, and a plate seen at \
             all leaves a sample in nearly every strip; a few empty strips in a row are a glare spot or a tack \
             weld. A lone sample or a short run beyond a longer break (a chance hole in a sparse strip at the \
             cloud's border, a piece of another part) proves nothing about where the edge runs, so the edge's \
             extent is the longest stretch its strips show, and what lies beyond the break is cut off.",
    parameters: &[Parameter {
        name: "EXTENT_BREAK_LINES",
        unit: "strips",
        meaning: "most empty strips in a row still within one stretch",
        source: Source::Constant { file: "src/pipeline/boundary/mod.rs", name: "EXTENT_BREAK_LINES" },
    }],
    fires: &["src/pipeline/robust/plates/tests.rs::a_weld_edge_without_a_grid_runs_along_its_longest_unbroken_stretch"],
    holds: &["src/pipeline/robust/plates/tests.rs::a_weld_edge_without_a_grid_runs_along_its_longest_unbroken_stretch"],
};
