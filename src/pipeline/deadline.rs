//! A plan's time limit. The caller (the daemon, `server.plan_timeout_ms`)
//! gives the instant by which a plan must end; the pipeline checks it at
//! every stage's end, where the stage clock laps, and after each step of
//! the input stage, and gives up with a refusal that says so
//! ([`PlanError::out_of_time`]). The check is cooperative: the
//! plan stops at its next check and frees the pool's threads, so the next
//! plan starts at once rather than beside a computation nobody waits for.
//! Only a plan with a limit is affected; the library's and the command
//! line's plans have none.

use std::time::{Duration, Instant};

use super::{PlanError, Stage};
use crate::rules;

/// The instant a plan must end by, or none.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Deadline {
    at: Option<Instant>,
    limit: Duration,
}

impl Deadline {
    /// No limit: the plan runs to its end.
    pub const NONE: Deadline = Deadline { at: None, limit: Duration::ZERO };

    /// A limit of `limit` from now.
    pub fn after(limit: Duration) -> Self {
        Deadline { at: Instant::now().checked_add(limit), limit }
    }

    /// True once the limit has passed.
    #[inline]
    pub fn passed(&self) -> bool {
        self.at.is_some_and(|at| Instant::now() >= at)
    }

    /// The refusal of a plan stopped in `stage` because its time ran out,
    /// or Ok while there is time left.
    pub fn check(&self, stage: Stage) -> Result<(), PlanError> {
        if !self.passed() {
            return Ok(());
        }
        // One rule wherever the plan stops: the refusal's stage says where.
        Err(PlanError {
            out_of_time: true,
            ..PlanError::by_in(
                &rules::request::TIME_LIMIT,
                stage,
                format!(
                    "the plan ran past its time limit of {} ms and was stopped in the {} stage",
                    self.limit.as_millis(),
                    stage.name()
                ),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_passed_limit_refuses_and_names_it_and_no_limit_never_does() {
        assert_eq!(Deadline::NONE.check(Stage::Clustering), Ok(()));
        assert_eq!(Deadline::after(Duration::from_secs(3600)).check(Stage::Clustering), Ok(()));
        let e = Deadline::after(Duration::ZERO).check(Stage::Clustering).unwrap_err();
        assert!(e.out_of_time && e.stage == Stage::Clustering, "{e:?}");
        assert_eq!(e.rule.id, "plan.time_limit");
        assert!(e.reason.contains("time limit of 0 ms") && e.reason.contains("clustering"), "{}", e.reason);
    }
}
