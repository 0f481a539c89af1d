//! The rulebook: every decision that can refuse a seam, change a joint's
//! type, or move or cut a seam's end, as a [`Rule`] with a stable id.
//!
//! A rule is declared once, in the catalogue file of the stage it belongs
//! to (`request.rs` to `trajectory.rs`), with its reason in physical terms,
//! its parameters (a config key a user may change, or a named constant
//! beside the code that applies it) and the tests that show it firing and
//! holding. The code that applies a rule names it ([`crate::pipeline::PlanError::by`]),
//! so the id travels with the refusal or warning to every interface: the
//! library's errors, `plan --json`, the debug trace, both wire links, the
//! logs, the metrics and the eval tables.
//!
//! docs/RULES.md is this catalogue rendered ([`markdown`]); the test
//! `rules_document_is_current` fails when the two differ, and checks that
//! every parameter and test a rule names exists.
//!
//! Ids are `family.decision`, lower snake case, and never change once
//! released: a controller, a dashboard or an eval table may key on them.
//! A rule that no longer applies is removed, and its id is not reused.
//!
//! This module depends on nothing else in the crate, so the configuration,
//! the pipeline and the wire links can all name rules without a cycle.

mod document;
mod gate;
mod stage;

pub mod background;
pub mod clustering;
pub mod edge_points;
pub mod groove;
pub mod input;
pub mod neighbour_index;
pub mod orientation;
pub mod plane_points;
pub mod process;
pub mod quality;
pub mod ransac;
pub mod refit;
pub mod request;
pub mod trajectory;
mod web_face;
pub mod weld_edges;
pub mod weld_equation;

use std::fmt;

pub use document::markdown;
pub use gate::Gate;
pub use stage::Stage;

/// One decision of the planner.
pub struct Rule {
    /// Stable id, `family.decision`.
    pub id: &'static str,
    /// The stage whose code applies the rule.
    pub stage: Stage,
    /// What the rule does to a plan when it fires.
    pub effect: Effect,
    /// The protocol's refusal class, for a rule that refuses.
    pub gate: Option<Gate>,
    /// One line: what the rule checks.
    pub summary: &'static str,
    /// One paragraph: why, in physical terms (what in the cell or the
    /// camera makes the rule hold).
    pub reason: &'static str,
    /// What the rule's decision depends on.
    pub parameters: &'static [Parameter],
    /// Tests that make the rule fire, as `path::function`; each names the
    /// rule's id.
    pub fires: &'static [&'static str],
    /// Tests where the rule is checked and holds, as `path::function`.
    pub holds: &'static [&'static str],
}

/// What a rule does when it fires.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// The seam (or the frame) is refused.
    Refuses,
    /// A seam is planned with a warning (a gate `quality.warn_only` names).
    Warns,
    /// The joint is planned as another type than the plates first suggest.
    ChangesJoint,
    /// A seam's end is moved.
    MovesEnd,
    /// A stretch of a seam is cut out.
    CutsSeam,
    /// A joint in view is reported and not planned while others are.
    LeavesUnplanned,
}

impl Effect {
    pub fn name(self) -> &'static str {
        match self {
            Effect::Refuses => "refuses",
            Effect::Warns => "warns",
            Effect::ChangesJoint => "changes the joint",
            Effect::MovesEnd => "moves an end",
            Effect::CutsSeam => "cuts the seam",
            Effect::LeavesUnplanned => "leaves a joint unplanned",
        }
    }
}

/// A figure a rule's decision depends on.
pub struct Parameter {
    /// The name a user reads: the config key's last part or the constant.
    pub name: &'static str,
    /// The unit, or "" for a ratio or a count.
    pub unit: &'static str,
    /// What it bounds, in a few words.
    pub meaning: &'static str,
    pub source: Source,
}

/// Where a parameter is set.
pub enum Source {
    /// A key of the configuration file, dotted (`quality.max_gap_mm`).
    Config(&'static str),
    /// A named constant in a source file, fixed at build time.
    Constant { file: &'static str, name: &'static str },
}

impl PartialEq for Rule {
    fn eq(&self, other: &Rule) -> bool {
        self.id == other.id
    }
}

impl Eq for Rule {}

impl std::hash::Hash for Rule {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.id.hash(state);
    }
}

impl fmt::Debug for Rule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Rule({})", self.id)
    }
}

impl fmt::Display for Rule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id)
    }
}

/// Each stage's catalogue, in run order.
const CATALOGUES: [&[&Rule]; 15] = [
    request::RULES,
    input::RULES,
    neighbour_index::RULES,
    orientation::RULES,
    plane_points::RULES,
    clustering::RULES,
    background::RULES,
    edge_points::RULES,
    ransac::RULES,
    weld_edges::RULES,
    refit::RULES,
    groove::RULES,
    weld_equation::RULES,
    quality::RULES,
    trajectory::RULES,
];

/// Every rule, by stage in run order and in catalogue order within one.
pub fn all() -> impl Iterator<Item = &'static Rule> {
    CATALOGUES.into_iter().flatten().copied()
}

/// The rule with this id.
pub fn by_id(id: &str) -> Option<&'static Rule> {
    all().find(|r| r.id == id)
}

/// A rule's id: lower snake case words, a family and a decision joined by
/// one dot.
pub fn is_well_formed_id(id: &str) -> bool {
    let word = |w: &str| {
        !w.is_empty()
            && w.starts_with(|c: char| c.is_ascii_lowercase())
            && w.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
    };
    matches!(id.split_once('.'), Some((family, decision)) if word(family) && word(decision))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_well_formed() {
        let mut seen = std::collections::HashSet::new();
        for rule in all() {
            assert!(is_well_formed_id(rule.id), "{}: not family.decision in lower snake case", rule.id);
            assert!(seen.insert(rule.id), "{}: declared twice", rule.id);
            assert!(by_id(rule.id).is_some_and(|r| std::ptr::eq(r, rule)));
        }
    }

    #[test]
    fn each_rule_sits_in_its_stage_catalogue() {
        for (catalogue, stage) in CATALOGUES.iter().zip(Stage::ALL) {
            for rule in *catalogue {
                assert_eq!(rule.stage, stage, "{} is declared under {stage}", rule.id);
            }
        }
    }

    #[test]
    fn a_gate_class_only_on_a_rule_that_refuses_or_warns() {
        for rule in all() {
            if rule.gate.is_some() {
                assert!(
                    matches!(rule.effect, Effect::Refuses | Effect::Warns),
                    "{}: a gate on a rule that does not refuse",
                    rule.id
                );
            }
            if rule.effect == Effect::Warns {
                assert!(rule.gate.is_some_and(Gate::can_warn), "{}: warns without a gate warn_only can name", rule.id);
            }
        }
    }

    #[test]
    fn well_formed_ids() {
        assert!(is_well_formed_id("lap.upper_plate_ends_off_lower"));
        assert!(is_well_formed_id("frame.no_valid_point"));
        for bad in ["lap", "Lap.end", "lap.", ".end", "lap.end.off", "lap.end-off", "lap._end"] {
            assert!(!is_well_formed_id(bad), "{bad}");
        }
    }
}
