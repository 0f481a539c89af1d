//! The rules of the quality stage (`Stage::Quality`): the gates a planned
//! seam's figures must pass (src/pipeline/quality/ measures them). Each
//! rule is one figure against one configured limit; `quality.warn_only`
//! may name the gate of any of them, which makes its failure a warning on
//! the seam instead of a refusal.

use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[
    &EDGE_SAMPLES_BEYOND_LINE,
    &EDGE_SAMPLES_ON_TWO_LINES,
    &EDGE_FIT_RESIDUAL,
    &EDGE_COVERAGE,
    &JOINT_COVERAGE,
    &STOPS_SHORT_OF_JOINT,
    &MISALIGNMENT,
    &GAP_WIDTH,
    &GAP_UNRESOLVED,
    &WEB_TILT,
    &PLATE_ANGLE,
    &GROOVE_DEPTH_DIFFERENCE,
    &POSITION_UNCERTAINTY,
];

/// The file whose code applies the stage's rules.
const APPLIED_IN: &str = "src/pipeline/quality/mod.rs";

/// The file that measures a root's straightness.
const STRAIGHTNESS_IN: &str = "src/pipeline/straightness.rs";

/// Where the gap and the misalignment are read along the seam.
const STATIONS: Parameter = Parameter {
    name: "STATIONS",
    unit: "",
    meaning: "stations along the seam the figure is read at",
    source: Source::Constant { file: APPLIED_IN, name: "STATIONS" },
};

pub static EDGE_SAMPLES_BEYOND_LINE: Rule = Rule {
    id: "edge.samples_beyond_line",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::EdgeCutShort),
    summary: "few of a weld edge's boundary samples lie beyond the line the rest fit, towards the other plate",
    reason: "A plate's points stop at its edge, so no boundary sample of a whole edge lies beyond the line \
             through the others towards the other plate. Where a dropout, a shadow or a reflection over the \
             joint cut the edge short along most of its length, the samples that remain on the true edge are \
             the minority beyond the line, and a fit that trims them follows the receded edge: the seam would \
             be welded millimetres off. Which line is the plate's edge is then not clear from the cloud, so the \
             seam is refused, with the share and how far beyond the samples lie. `quality.warn_only` may name \
             the gate (`edge_cut_short`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "max_edge_samples_beyond",
        unit: "",
        meaning: "largest share of an edge's samples beyond its fitted line",
        source: Source::Config("quality.max_edge_samples_beyond"),
    }],
    fires: &[
        "src/pipeline/quality/tests.rs::an_edge_cut_short_is_refused_by_its_samples_beyond_or_on_two_lines",
        "tests/faults.rs::a_lap_whose_edge_a_dropout_cuts_short_along_most_of_its_seam_is_refused_not_planned_2_mm_off",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static EDGE_SAMPLES_ON_TWO_LINES: Rule = Rule {
    id: "edge.samples_on_two_lines",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::EdgeCutShort),
    summary: "a weld edge's boundary samples lie on one line, not on two runs a step apart",
    reason: "A plate's edge is one straight line (or a gentle curve). Boundary samples that fall into two runs, \
             each along a good part of the edge and a few point spacings apart across it, are an edge cut short \
             along one of them by a dropout or a shadow: a fit runs between the two, its residual still small, \
             or follows the cut-short run with the true edge's samples too few to count as beyond it. Read on \
             the edges that place the weld (both of a butt joint, a lap's upper one), or for a V-groove welded \
             on its root (`groove.weld_on_bevel_midline`) on the root's samples, one a station, where a step \
             says a flank's foot was cut short along one run. `quality.warn_only` may name the gate \
             (`edge_cut_short`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "max_edge_step_spacings",
        unit: "point spacings",
        meaning: "largest step between two runs of an edge's samples",
        source: Source::Config("quality.max_edge_step_spacings"),
    }],
    fires: &[
        "src/pipeline/quality/tests.rs::an_edge_cut_short_is_refused_by_its_samples_beyond_or_on_two_lines",
        "tests/faults.rs::a_lap_edge_on_two_lines_is_refused_whether_the_fit_runs_between_them_or_follows_one",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static EDGE_FIT_RESIDUAL: Rule = Rule {
    id: "seam.edge_fit_residual",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::EdgeFitResidual),
    summary: "each of the seam's two fits leaves a residual of at most a few point spacings, and its samples \
              follow the straight root station by station",
    reason: "The camera samples a plate's boundary to about a third of a point spacing, so the samples of a \
             straight edge scatter about their fitted line by well under a spacing, and the points of a flat \
             face about their plane as little. A residual of several spacings says the samples are not one \
             edge (or the points not one face): spatter, a burr, a second edge or a fixture mixed in, and the \
             line through them is not where the plate ends. For a fillet root the two fits are the web's side \
             face (or the flange's edge against the web) and the flange beside the root. A curved member (a \
             round tube on a plate or a cylinder, a plate bent along the joint) leaves a residual of only the \
             camera's noise on a coarse cloud, yet its root is not a line: the samples that show the root (a \
             face's foot, the flange beside it, a plate's boundary samples), averaged a few spacings along \
             the root at a time, follow a curve off the straight seam, where noise scatters the averages \
             about it. Where that trend leaves the straight root by more than three standard errors of the \
             averages' own scatter and more than a point spacing, the root bends: not a plane weld, and a \
             straight seam would be welded millimetres off it. For a V-groove welded on its root \
             (`groove.weld_on_bevel_midline`), the fit is the root line through the root's samples, one a \
             station, and they are what bends. A root seen over fewer than the fewest stations of a point \
             spacing each cannot show a curve at all, and planned it would be a chord of whatever the joint \
             is (a round tube's foot where both faces are seen together over a few millimetres): it is \
             refused as unchecked. `quality.warn_only` may name the gate (`edge_fit_residual`) to plan the \
             seam with a warning instead.",
    parameters: &[
        Parameter {
            name: "max_edge_fit_rms_spacings",
            unit: "point spacings",
            meaning: "largest RMS residual of either fit",
            source: Source::Config("quality.max_edge_fit_rms_spacings"),
        },
        Parameter {
            name: "NOISE_SIGMAS",
            unit: "standard errors",
            meaning: "the root samples' trend off the straight root that the noise explains",
            source: Source::Constant { file: STRAIGHTNESS_IN, name: "NOISE_SIGMAS" },
        },
        Parameter {
            name: "RESOLUTION_SPACINGS",
            unit: "point spacings",
            meaning: "the trend off the straight root that the cloud's resolution explains",
            source: Source::Constant { file: STRAIGHTNESS_IN, name: "RESOLUTION_SPACINGS" },
        },
        Parameter {
            name: "STATION_SPACINGS",
            unit: "point spacings",
            meaning: "the longest stretch of root samples averaged together",
            source: Source::Constant { file: STRAIGHTNESS_IN, name: "STATION_SPACINGS" },
        },
        Parameter {
            name: "MIN_STATIONS",
            unit: "stations",
            meaning: "the fewest stations, a point spacing long at least, over which a root's straightness is \
                      told; a seam shorter than that many spacings is refused",
            source: Source::Constant { file: STRAIGHTNESS_IN, name: "MIN_STATIONS" },
        },
    ],
    fires: &[
        "src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit",
        "src/pipeline/quality/tests.rs::a_bent_root_is_refused_by_its_sagitta_not_its_residual",
        "src/pipeline/quality/tests.rs::a_root_too_short_to_show_a_bend_is_refused_as_unchecked",
        "src/sim/curved.rs::no_curved_root_is_planned_on_the_documented_seeds",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "src/sim/curved.rs::the_same_tees_unbent_are_planned",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static EDGE_COVERAGE: Rule = Rule {
    id: "edge.coverage",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::EdgeCoverage),
    summary: "each weld edge is seen along most of the seam planned",
    reason: "A weld edge is evidence for the seam only where its samples are: along a stretch where one edge \
             has none (a gap narrower than about two point spacings, a shadow, a reflection), the seam is \
             extrapolated from the rest, and a plate that bends or a gap that opens there is not seen. Read on \
             the robust method's edges; for a fillet root, on the web's face down to the flange (or the web \
             top's edge) and the flange up to the web; for a V-groove welded on its root \
             (`groove.weld_on_bevel_midline`), on the stations where both flanks show the root. \
             `quality.warn_only` may name the gate (`edge_coverage`) \
             to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "min_edge_coverage",
        unit: "",
        meaning: "least share of the seam each edge is seen along",
        source: Source::Config("quality.min_edge_coverage"),
    }],
    fires: &["src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit"],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static JOINT_COVERAGE: Rule = Rule {
    id: "seam.joint_coverage",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::JointCoverage),
    summary: "the seam spans most of the joint along which both plates are seen beside it",
    reason: "Where both plates are seen side by side, the joint runs between them whether or not their edges \
             were found there. A seam that spans only part of that stretch had its edges found along part of \
             the joint only (a streak or a shadow over the rest), so it would leave the rest unwelded, or its \
             edges belong to something else than the joint. For a fillet root the visible joint is where the \
             web's face and the flange up to it are seen together, each stretch of it measured as the root is, \
             from where both are seen to where either ends; for a member standing on a plate with every \
             side a root (a block), at least as long as its top's edge over that side is seen, as the joint runs \
             the whole side. `quality.warn_only` may name the gate \
             (`joint_coverage`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "min_joint_coverage",
        unit: "",
        meaning: "least share of the visible joint the seam spans",
        source: Source::Config("quality.min_joint_coverage"),
    }],
    fires: &[
        "src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit",
        "tests/faults.rs::a_lap_plate_cut_by_a_streak_is_refused_for_coverage_and_not_found_as_a_butt_joint",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static STOPS_SHORT_OF_JOINT: Rule = Rule {
    id: "seam.stops_short_of_joint",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::JointCoverage),
    summary: "both plates are not seen beside the joint for more than a little beyond either end of the seam",
    reason: "A seam ends where its joint ends: where one plate stops, or where the camera stops seeing them \
             (where a weld edge leaves the image, though pixels inside the plates, across an oblique border, \
             are still in view). Where both plates are still seen side by side well past the seam's end, the joint goes on and a \
             weld edge was lost there while its plate goes on (a streak, spatter or a reflection over the \
             edge), so the weld would stop short of the joint. For a fillet root, the web's top and the flange \
             seen past the root's end where the web's side face is not seen down to the flange (turned \
             edge-on to the camera or the projector, or covered). `quality.warn_only` may name the gate \
             (`joint_coverage`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "max_joint_beyond_seam_mm",
        unit: "mm",
        meaning: "longest stretch both plates are seen past either end",
        source: Source::Config("quality.max_joint_beyond_seam_mm"),
    }],
    fires: &[
        "tests/consumer_camera.rs::a_far_i_butt_strip_whose_edge_is_lost_short_of_an_end_is_refused_not_cut_short",
        "src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit",
        "tests/faults.rs::an_edge_lost_under_a_streak_while_both_plates_go_on_is_refused_not_cut_short",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
        "tests/faults.rs::plates_seen_past_where_a_seam_leaves_the_image_do_not_refuse_it_as_cut_short",
    ],
};

pub static MISALIGNMENT: Rule = Rule {
    id: "butt.misalignment",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::Misalignment),
    summary: "a butt joint's plates lie level within the high-low misalignment a butt weld allows",
    reason: "Butt plates whose edges stand at different heights (high-low) cannot be joined by one bead \
             placed between the edges: the root on the high side is not reached, and ISO 5817 limits the \
             linear misalignment of butt welds at quality level C to 0.15 of the thickness and 4 mm at most. \
             The camera sees only a ceiling on the thickness, the depth to the surface the plates rest on \
             (they may lie on spacers), so the fraction applies to that when it is seen and is never stricter \
             than the real thickness would be. The height difference is read along the plate normal at \
             stations along the seam. `quality.warn_only` may name the gate (`misalignment`) to plan the seam \
             with a warning instead.",
    parameters: &[
        Parameter {
            name: "max_misalignment_mm",
            unit: "mm",
            meaning: "largest height difference between the edges",
            source: Source::Config("quality.max_misalignment_mm"),
        },
        Parameter {
            name: "max_misalignment_of_thickness",
            unit: "",
            meaning: "largest height difference, as a share of the depth to the support",
            source: Source::Config("quality.max_misalignment_of_thickness"),
        },
        STATIONS,
    ],
    fires: &["src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit"],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static GAP_WIDTH: Rule = Rule {
    id: "butt.gap_width",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::GapWidth),
    summary: "an I-butt joint's root gap is no wider than the weld procedure bridges",
    reason: "A square butt joint is welded across its root gap; a gap wider than the procedure is qualified \
             for burns through or leaves the root unfused, and a gap far wider than the parts' tolerance says \
             the plates are not where the fixture should hold them. The gap is read across the seam between \
             the two fitted weld edges at stations along it, and its widest counts. `quality.warn_only` may \
             name the gate (`gap_width`) to plan the seam with a warning instead.",
    parameters: &[
        Parameter {
            name: "max_gap_mm",
            unit: "mm",
            meaning: "widest root gap",
            source: Source::Config("quality.max_gap_mm"),
        },
        STATIONS,
    ],
    fires: &[
        "tests/measured_clouds.rs::a_part_touching_a_plate_is_no_joint_where_the_plates_merged",
        "src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit",
        "tests/quality.rs::a_seam_that_fails_a_gate_is_refused_with_the_figure_its_value_and_the_limit",
        "tests/quality.rs::a_gate_named_in_warn_only_warns_on_the_seam_instead",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static GAP_UNRESOLVED: Rule = Rule {
    id: "butt.gap_unresolved",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::GapUnresolved),
    summary: "an I-butt joint's gap, at its widest, is at least as wide as the cloud resolves",
    reason: "A gap is measured between two fitted edges, each a plate's last points, a point spacing or so \
             short of where the plate ends. A gap under one spacing is not measured but guessed (plates that \
             touch measure a few tenths), and a joint as narrow elsewhere in the frame leaves its two plates \
             one surface, so the plates paired here may not be the joint's: the cloud cannot show where the \
             plates part. A finer cloud (voxels under half the narrowest gap) resolves it. `quality.warn_only` \
             may name the gate (`gap_unresolved`) to plan the seam with a warning instead.",
    parameters: &[
        Parameter {
            name: "min_gap_spacings",
            unit: "point spacings",
            meaning: "narrowest gap at its widest; 0 turns the rule off",
            source: Source::Config("quality.min_gap_spacings"),
        },
        STATIONS,
    ],
    fires: &[
        "src/pipeline/quality/tests.rs::an_i_butt_gap_under_a_point_spacing_is_not_resolved",
        "tests/faults.rs::a_part_touching_an_i_butt_whose_gap_voxels_close_is_not_taken_for_its_second_plate",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::an_i_butt_gap_under_a_point_spacing_is_not_resolved",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static WEB_TILT: Rule = Rule {
    id: "tee.web_tilt",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::PlateAngle),
    summary: "a tee's web side face stands square to the flange, within a few degrees",
    reason: "A tee's web stands on the flange at a right angle; the fillet's torch angles and its root are \
             placed from the web's side face and the flange. A face fitted at a clearly other angle is not a \
             web standing on the flange (a bevelled part, a fixture's face, the web's top or end taken for its \
             side), and the root placed from it would be off. `quality.warn_only` may name the gate \
             (`plate_angle`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "max_web_tilt_deg",
        unit: "°",
        meaning: "largest angle the web's face lies off square to the flange",
        source: Source::Config("quality.max_web_tilt_deg"),
    }],
    fires: &["src/pipeline/quality/tests.rs::a_fillet_roots_web_is_square_to_its_flange"],
    holds: &["src/pipeline/quality/tests.rs::a_fillet_roots_web_is_square_to_its_flange"],
};

pub static PLATE_ANGLE: Rule = Rule {
    id: "seam.plate_angle",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::PlateAngle),
    summary: "the two plates of a butt or lap joint lie parallel, within a few degrees",
    reason: "The butt and lap joints planned here join two plates lying in parallel planes; the weld equation \
             places the seam from both planes and the torch along their shared normal. Plates meeting at a \
             clear angle are another joint (a corner or a bent part), or one of the two planes is not a plate \
             of the joint, and a seam placed between them would not lie on the joint. `quality.warn_only` may \
             name the gate (`plate_angle`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "max_plate_angle_deg",
        unit: "°",
        meaning: "largest angle between the two plates' planes",
        source: Source::Config("quality.max_plate_angle_deg"),
    }],
    fires: &["src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit"],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

pub static GROOVE_DEPTH_DIFFERENCE: Rule = Rule {
    id: "butt.groove_depth_difference",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::GrooveDepth),
    summary: "a V-groove depth the request gives agrees with the one measured",
    reason: "A V-butt weld is placed at the groove depth the request gives (the weld equation puts the root \
             that far below the plates' top). Where a bevel face shows the root, the groove's depth is \
             measured; a depth given that differs from it by more than a millimetre or so is the wrong part \
             or drawing, and the weld would lie that far off the root. `quality.warn_only` may name the gate \
             (`groove_depth`) to plan the seam at the depth given with a warning instead.",
    parameters: &[Parameter {
        name: "max_groove_depth_difference_mm",
        unit: "mm",
        meaning: "largest difference between the depth given and the one measured",
        source: Source::Config("quality.max_groove_depth_difference_mm"),
    }],
    fires: &[
        "src/pipeline/quality/tests.rs::a_groove_depth_given_is_held_to_the_one_measured",
        "tests/joints.rs::a_groove_depth_given_is_checked_against_the_one_measured",
    ],
    holds: &[
        "src/pipeline/quality/tests.rs::a_groove_depth_given_is_held_to_the_one_measured",
        "tests/joints.rs::a_groove_depth_given_is_checked_against_the_one_measured",
    ],
};

pub static POSITION_UNCERTAINTY: Rule = Rule {
    id: "seam.position_uncertainty",
    stage: Stage::Quality,
    effect: Effect::Refuses,
    gate: Some(Gate::PositionUncertainty),
    summary: "the seam's position is known, one sigma, to within the torch's tolerance",
    reason: "A cell has no tape measure: how well the seam is placed is read from the fits that place it. A \
             least-squares fit is worst at its ends, known there to its scatter times (degree + 1) over the \
             root of its sample count, and a plate's edge lies somewhere within a spacing past its last point, \
             which no number of samples averages away. A seam placed from few or scattered samples may lie off \
             by more than the torch and the wire tolerate. `quality.warn_only` may name the gate \
             (`position_uncertainty`) to plan the seam with a warning instead.",
    parameters: &[Parameter {
        name: "max_position_uncertainty_mm",
        unit: "mm",
        meaning: "largest one-sigma position uncertainty, across the seam or along the normal",
        source: Source::Config("quality.max_position_uncertainty_mm"),
    }],
    fires: &["src/pipeline/quality/tests.rs::each_gate_names_its_figure_value_and_limit"],
    holds: &[
        "src/pipeline/quality/tests.rs::a_good_seam_passes_every_gate",
        "tests/quality.rs::every_seam_carries_its_quality_figures",
    ],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_gate_rule_refuses_with_a_gate_warn_only_may_name() {
        for rule in RULES {
            assert_eq!(rule.effect, Effect::Refuses, "{}", rule.id);
            assert!(rule.gate.is_some_and(Gate::can_warn), "{}", rule.id);
            let gate = rule.gate.map(Gate::name).unwrap_or_default();
            assert!(rule.reason.contains(&format!("`quality.warn_only` may name the gate (`{gate}`)")), "{}", rule.id);
        }
    }
}
