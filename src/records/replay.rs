//! Plans a recorded frame again, with the recorded request and
//! configuration, as the daemon did, and says whether today's build gives
//! the same plan ([`super::compare`]): every field the record keeps, each
//! seam's figures along it and its process included (a format 1 record,
//! which did not keep those, is compared without them).

use weldseam_proto::plan::PlanResult;

use super::compare::{Changes, compare};
use super::{FormatError, Outcome, Record};
use crate::config::procedure::{Procedure, ProcedureError};
use crate::config::{Config, ConfigError};
use crate::convert::from_proto::{self, RequestError};
use crate::convert::to_proto::{add_along_seam, plan_error_code, plan_result};
use crate::pipeline::Planner;

/// Why a record could not be planned again.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error("the recorded configuration does not load in this build: {0}")]
    Config(#[from] ConfigError),
    #[error("the recorded request does not convert in this build: {0}")]
    Request(#[from] RequestError),
    #[error(transparent)]
    Frame(#[from] FormatError),
    #[error("the recorded weld procedure does not load in this build: {0}")]
    Procedure(ProcedureError),
}

/// A record planned again.
#[derive(Debug, Clone)]
pub struct Replayed {
    pub outcome: Outcome,
    /// What changed from the recorded outcome; empty when it is the same.
    pub changes: Changes,
    /// The planning hash of the configuration used now; the record's
    /// differs when this build reads the recorded settings (or its
    /// defaults) differently.
    pub config_hash: String,
}

impl Replayed {
    pub fn same(&self) -> bool {
        self.changes.is_empty()
    }
}

/// The outcome as a record of `format` holds it (format 1 kept the plan
/// in the binary link's layout only), its stage times cleared, which are
/// the machine's.
fn timeless(outcome: &Outcome, format: u32) -> Outcome {
    let stored = if format < 2 { Record::as_format_1(outcome) } else { outcome.clone() };
    match stored {
        Outcome::Planned(result) => Outcome::Planned(PlanResult { timing_ms: Default::default(), ..result }),
        other => other,
    }
}

/// Plans `record`'s frame again with its request and configuration (the
/// recorded file, or this build's defaults when the daemon had none) and
/// the weld procedure it kept.
pub fn replay(record: &Record) -> Result<Replayed, ReplayError> {
    let origin = "the recorded configuration";
    let procedure = match &record.procedure_text {
        Some(text) => Some(Procedure::from_toml(text).map_err(ReplayError::Procedure)?),
        None => None,
    };
    let config = match (&record.config_text, procedure) {
        (Some(text), Some(procedure)) => Config::parse_with_procedure(text, origin, procedure)?,
        (Some(text), None) => Config::parse(text, origin)?,
        (None, procedure) => {
            let mut config = Config::default();
            config.process.procedure = procedure;
            config
        }
    };
    let config_hash = config.planning_hash();
    let (cloud, input) = record.cloud()?;
    let mut request = from_proto::plan_request(&record.request, config.euler)?;
    // As the daemon does: the frame says which units and frame its points are in.
    (request.units, request.cloud_frame) = (input.units, input.cloud_frame);
    let euler = config.euler;
    let outcome = match Planner::new(config).plan(&cloud, &request) {
        Ok(plan) => {
            // As the daemon records it: with each seam's figures along it
            // and its process.
            let mut result = plan_result(&plan, euler);
            add_along_seam(&mut result, &plan);
            Outcome::Planned(result)
        }
        Err(e) => Outcome::Refused {
            code: plan_error_code(&e).name().to_string(),
            rule: Some(e.rule.id.to_string()),
            reason: format!("frame {}: {e}", record.frame.frame_id),
        },
    };
    let (before, after) = (timeless(&record.outcome, record.format), timeless(&outcome, record.format));
    let mut changes = compare(&before, &after);
    if changes.is_empty() && !same_bits(&before, &after) {
        // JSON cannot tell NaN from null, nor -0 from 0.
        changes.listed.push("a figure differs in its bits (a NaN or a signed zero)".into());
    }
    Ok(Replayed { outcome, changes, config_hash })
}

/// Whether two outcomes encode to the same bytes, every field the record
/// keeps included.
fn same_bits(a: &Outcome, b: &Outcome) -> bool {
    Record::outcome_bytes(a) == Record::outcome_bytes(b)
}
