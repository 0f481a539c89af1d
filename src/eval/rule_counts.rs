//! How often each rule of the planner refused or warned over a suite's
//! outcomes: the eval report's per-rule table. A refusal is a plan refused
//! or a joint left unplanned beside the seams planned; a warning is a
//! quality gate `quality.warn_only` turned into one on a planned seam.
//! Rules are told apart by their ids, never by their sentences.

use std::collections::BTreeMap;

use super::SceneOutcome;
use crate::pipeline::{Plan, PlanError};

/// Refusals and warnings per rule id, in id order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RuleCounts {
    pub refusals: BTreeMap<&'static str, usize>,
    pub warnings: BTreeMap<&'static str, usize>,
}

impl RuleCounts {
    /// Every rule counted, in id order, with its refusals and warnings.
    pub fn rows(&self) -> Vec<(&'static str, usize, usize)> {
        let ids: std::collections::BTreeSet<&'static str> =
            self.refusals.keys().chain(self.warnings.keys()).copied().collect();
        ids.into_iter()
            .map(|id| (id, self.refusals.get(id).copied().unwrap_or(0), self.warnings.get(id).copied().unwrap_or(0)))
            .collect()
    }

    fn count(&mut self, result: Result<&Plan, &PlanError>) {
        match result {
            Err(e) => *self.refusals.entry(e.rule.id).or_default() += 1,
            Ok(plan) => {
                for unplanned in &plan.unplanned {
                    *self.refusals.entry(unplanned.reason.rule.id).or_default() += 1;
                }
                for warning in plan.seams.iter().flat_map(|s| &s.warnings) {
                    *self.warnings.entry(warning.rule.id).or_default() += 1;
                }
            }
        }
    }
}

/// Counts the refusals and warnings of `outcomes` by rule.
pub fn count_rules<'a>(outcomes: impl IntoIterator<Item = &'a SceneOutcome>) -> RuleCounts {
    let mut counts = RuleCounts::default();
    for o in outcomes {
        counts.count(o.result.as_ref().map(|(_, plan)| plan));
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules;

    #[test]
    fn refusals_and_warnings_are_counted_by_rule_id() {
        let mut counts = RuleCounts::default();
        let refused = PlanError::by(&rules::input::NO_VALID_POINT, "no point");
        counts.count(Err(&refused));
        counts.count(Err(&refused));
        counts.count(Err(&PlanError::by(&rules::refit::TEE_NO_ROOT_SEEN, "no root")));
        assert_eq!(
            counts.rows(),
            vec![("frame.no_valid_point", 2, 0), ("tee.no_root_seen", 1, 0)],
            "in id order, a rule's refusals and warnings side by side"
        );
    }
}
