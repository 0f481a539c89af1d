//! The rules of the refit stage (`Stage::Refit`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&SEAM_END_READ_FROM_PLATE_RIM];

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
