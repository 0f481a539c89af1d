//! Placeholders for refusals not yet given a rule of their own: one per
//! stage, `pending.<stage>`. A refusal built with
//! [`crate::pipeline::PlanError::at`] carries its stage's placeholder, so
//! every refusal has an id while the catalogue is being filled; each one
//! still here is listed in docs/RULES.md as a decision without its own rule.

use super::{Effect, Rule, Stage};

const fn placeholder(id: &'static str, stage: Stage) -> Rule {
    Rule {
        id,
        stage,
        effect: Effect::Refuses,
        gate: None,
        summary: "a refusal of this stage not yet given a rule of its own",
        reason: "",
        parameters: &[],
        fires: &[],
        holds: &[],
    }
}

/// One placeholder per stage, in [`Stage::ALL`]'s order.
pub static ALL: [Rule; 15] = [
    placeholder("pending.request", Stage::Request),
    placeholder("pending.input", Stage::Input),
    placeholder("pending.neighbour_index", Stage::NeighbourIndex),
    placeholder("pending.orientation", Stage::Orientation),
    placeholder("pending.plane_points", Stage::PlanePoints),
    placeholder("pending.clustering", Stage::Clustering),
    placeholder("pending.background", Stage::Background),
    placeholder("pending.edge_points", Stage::EdgePoints),
    placeholder("pending.ransac", Stage::Ransac),
    placeholder("pending.weld_edges", Stage::WeldEdges),
    placeholder("pending.refit", Stage::Refit),
    placeholder("pending.groove", Stage::Groove),
    placeholder("pending.weld_equation", Stage::WeldEquation),
    placeholder("pending.quality", Stage::Quality),
    placeholder("pending.trajectory", Stage::Trajectory),
];

/// The placeholder of a stage.
pub fn for_stage(stage: Stage) -> &'static Rule {
    // `Stage` is declared in `Stage::ALL`'s order (checked below).
    &ALL[stage as usize]
}

/// Whether a rule is a placeholder.
pub fn is_pending(rule: &Rule) -> bool {
    ALL.iter().any(|p| std::ptr::eq(p, rule))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_stage_has_its_placeholder() {
        for stage in Stage::ALL {
            assert_eq!(for_stage(stage).stage, stage);
            assert_eq!(for_stage(stage).id, format!("pending.{stage}"));
            assert!(is_pending(for_stage(stage)));
        }
    }
}
