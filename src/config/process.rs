//! The `[process]` section: the weld procedure whose parameters the plan's
//! waypoints carry, read and validated once when the config is loaded,
//! and the plates' thickness that picks the procedure's entry.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::procedure::Procedure;
use super::{ConfigError, check};

/// The thickest plate the key takes, mm: beyond any single-sided weld.
pub const MAX_PLATE_THICKNESS_MM: f64 = 200.0;

/// `[process]` as the file writes it.
#[derive(Debug, Clone, Deserialize, Default, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ProcessSection {
    /// The procedure's TOML file; empty leaves the process out of the plan.
    pub procedure: String,
    /// The plates' thickness, mm; 0 takes it from the joint where the
    /// cloud shows it.
    pub plate_thickness_mm: f64,
}

/// The process settings, validated.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProcessParams {
    /// The procedure, read and validated; None: off.
    pub procedure: Option<Procedure>,
    /// The plates' thickness when configured, mm.
    pub plate_thickness_mm: Option<f64>,
}

impl ProcessSection {
    /// The procedure's path read relative to `dir` (the config file's
    /// directory) when it is relative.
    pub fn resolved_against(mut self, dir: Option<&Path>) -> ProcessSection {
        let path = PathBuf::from(&self.procedure);
        if let Some(dir) = dir.filter(|_| !self.procedure.is_empty() && path.is_relative()) {
            self.procedure = dir.join(path).display().to_string();
        }
        self
    }

    /// Reads the procedure and checks the thickness.
    pub fn validate(&self) -> Result<ProcessParams, ConfigError> {
        let t = self.plate_thickness_mm;
        check("process.plate_thickness_mm", t.is_finite() && (0.0..=MAX_PLATE_THICKNESS_MM).contains(&t), || {
            format!("must lie in [0, {MAX_PLATE_THICKNESS_MM}] (0: from the joint), got {t}")
        })?;
        let procedure = if self.procedure.is_empty() {
            None
        } else {
            let text = std::fs::read_to_string(&self.procedure).map_err(|e| ConfigError::Invalid {
                key: "process.procedure",
                message: format!("cannot read {}: {e}", self.procedure),
            })?;
            let procedure = Procedure::from_toml(&text).map_err(|e| ConfigError::Invalid {
                key: "process.procedure",
                message: format!("{}: {e}", self.procedure),
            })?;
            Some(procedure)
        };
        Ok(ProcessParams { procedure, plate_thickness_mm: (t > 0.0).then_some(t) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn procedures_dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("config/procedures")
    }

    #[test]
    fn a_procedure_named_beside_the_config_is_read_once_and_validated() {
        let section = ProcessSection { procedure: "gmaw-mild-steel.toml".into(), plate_thickness_mm: 6.0 };
        let params = section.resolved_against(Some(&procedures_dir())).validate().expect("the shipped procedure");
        let procedure = params.procedure.expect("read");
        assert_eq!(procedure, Procedure::example(), "the shipped file is the example the tests use");
        assert_eq!(params.plate_thickness_mm, Some(6.0));
        // Empty: no process, and a thickness of 0 is taken from the joint.
        let off = ProcessSection::default().resolved_against(Some(&procedures_dir())).validate().unwrap();
        assert_eq!(off, ProcessParams::default());
    }

    #[test]
    fn a_missing_procedure_or_a_thickness_out_of_range_names_its_key() {
        let missing = ProcessSection { procedure: "no-such-procedure.toml".into(), plate_thickness_mm: 0.0 };
        let err = missing.resolved_against(Some(&procedures_dir())).validate().unwrap_err();
        assert!(matches!(err, ConfigError::Invalid { key: "process.procedure", .. }), "{err:?}");
        for t in [-1.0, MAX_PLATE_THICKNESS_MM + 1.0, f64::NAN] {
            let err = ProcessSection { procedure: String::new(), plate_thickness_mm: t }.validate().unwrap_err();
            assert!(matches!(err, ConfigError::Invalid { key: "process.plate_thickness_mm", .. }), "{err:?}");
        }
    }
}
