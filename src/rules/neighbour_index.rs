//! The rules of the neighbour index stage (`Stage::NeighbourIndex`).

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] = &[&DENSITY_UNMEASURABLE];

pub static DENSITY_UNMEASURABLE: Rule = Rule {
    id: "frame.density_unmeasurable",
    stage: Stage::NeighbourIndex,
    effect: Effect::Refuses,
    gate: None,
    summary: "a cloud without the camera's grid is dense enough for its point spacing to be measured",
    reason: "Every count criterion (Eq. 6 to 15) compares a point's neighbours with what a plane at its \
             spacing would hold. A cloud not on the camera's grid has its own spacing, measured from its \
             points' neighbours; where most points have too few neighbours even in a wide radius, the cloud \
             is too sparse to show a plate's surface, let alone its edge.",
    parameters: &[
        Parameter {
            name: "MIN_MEASURED_COUNT",
            unit: "",
            meaning: "fewest neighbours a spacing is measured from",
            source: Source::Constant { file: "src/pipeline/scale.rs", name: "MIN_MEASURED_COUNT" },
        },
        Parameter {
            name: "MAX_MEASURING_RADIUS_MM",
            unit: "mm",
            meaning: "widest radius the neighbours are looked for in",
            source: Source::Constant { file: "src/pipeline/scale.rs", name: "MAX_MEASURING_RADIUS_MM" },
        },
        Parameter {
            name: "point_density",
            unit: "",
            meaning: "whether the density is the camera's or measured",
            source: Source::Config("pipeline.point_density"),
        },
    ],
    fires: &["tests/pipeline.rs::frames_no_camera_makes_are_refused_by_their_rule"],
    holds: &["tests/unorganized.rs::a_v_butt_seam_is_planned_from_an_unorganized_cloud_and_its_ply_file"],
};
