//! The trust gate of a calibration: the figures the report gives,
//! measured against configured limits (the config's `[calibration]`
//! section), and the record of the verdict written beside
//! `robot.hand_eye`. A calibration that fails is not written (unless the
//! operator forces it, and then the record says so), and the daemon
//! refuses to start with a hand-eye whose record says it failed.

use serde::{Deserialize, Serialize};

use super::Calibration;

/// The largest expected error at the working distance, mm (one sigma):
/// the calibration adds it to every weld; half a millimetre is a fifth of
/// a typical fillet's leg tolerance.
pub const MAX_EXPECTED_ERROR_MM: f64 = 0.5;
/// The largest one-sigma uncertainty of the hand-eye's translation, mm.
pub const MAX_TRANSLATION_SIGMA_MM: f64 = 0.5;
/// The largest one-sigma uncertainty of the hand-eye's rotation, degrees:
/// 0.1 degree moves a point at 500 mm by 0.9 mm.
pub const MAX_ROTATION_SIGMA_DEG: f64 = 0.1;
/// The largest residual of a capture used, mm: a robot and a camera that
/// agree give a tenth of a millimetre or two; a loose target, a wrong
/// pose convention or a sphere misnamed give millimetres.
pub const MAX_RESIDUAL_MM: f64 = 1.0;
/// The largest rotation residual of a capture used, degrees.
pub const MAX_RESIDUAL_DEG: f64 = 0.3;
/// The pose set's largest rotation between two captures must be at least
/// this, degrees (the conditioning).
pub const MIN_ROTATION_DEG: f64 = 15.0;
/// The spread of the rotation axes must be at least this, degrees.
pub const MIN_AXIS_SPREAD_DEG: f64 = 8.0;

/// `[calibration]`: the limits a calibration must meet to be written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GateLimits {
    pub max_expected_error_mm: f64,
    pub max_translation_sigma_mm: f64,
    pub max_rotation_sigma_deg: f64,
    pub max_residual_mm: f64,
    pub max_residual_deg: f64,
    pub min_rotation_deg: f64,
    pub min_axis_spread_deg: f64,
}

impl Default for GateLimits {
    fn default() -> Self {
        GateLimits {
            max_expected_error_mm: MAX_EXPECTED_ERROR_MM,
            max_translation_sigma_mm: MAX_TRANSLATION_SIGMA_MM,
            max_rotation_sigma_deg: MAX_ROTATION_SIGMA_DEG,
            max_residual_mm: MAX_RESIDUAL_MM,
            max_residual_deg: MAX_RESIDUAL_DEG,
            min_rotation_deg: MIN_ROTATION_DEG,
            min_axis_spread_deg: MIN_AXIS_SPREAD_DEG,
        }
    }
}

/// A calibration's figures and the gate's verdict, as the config file
/// records them beside `robot.hand_eye` (`robot.hand_eye_calibration`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationRecord {
    /// Whether every limit was met.
    pub passed: bool,
    /// Written with `calibrate --force` although it failed.
    #[serde(default)]
    pub forced: bool,
    /// Each limit failed, as the report words it.
    #[serde(default)]
    pub failures: Vec<String>,
    /// The expected error at the working distance, mm (one sigma); absent
    /// when the captures do not determine it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected_error_mm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translation_sigma_mm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_sigma_deg: Option<f64>,
    /// The largest residual of the captures used, mm and degrees.
    pub worst_residual_mm: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub worst_residual_deg: Option<f64>,
    pub working_distance_mm: f64,
    /// The captures in the set and those the result used.
    pub captures: u32,
    pub captures_used: u32,
}

impl CalibrationRecord {
    /// The figures as one line for a log or an error.
    pub fn summary(&self) -> String {
        let or_none = |v: Option<f64>, digits: usize| v.map_or("undetermined".to_string(), |v| format!("{v:.digits$}"));
        format!(
            "{} ({}expected error {} mm, translation sigma {} mm, rotation sigma {} deg, worst residual {:.3} mm, \
             {} of {} captures used)",
            if self.passed { "passed its gate" } else { "FAILED its gate" },
            if self.forced { "written with --force, " } else { "" },
            or_none(self.expected_error_mm, 3),
            or_none(self.translation_sigma_mm, 3),
            or_none(self.rotation_sigma_deg, 4),
            self.worst_residual_mm,
            self.captures_used,
            self.captures,
        )
    }
}

/// Every limit the calibration fails, as a sentence naming the figure,
/// its value and the limit (empty when it passes).
pub fn failures(c: &Calibration, limits: &GateLimits) -> Vec<String> {
    let mut out = Vec::new();
    let mut over = |what: &str, key: &str, value: Option<f64>, limit: f64, unit: &str| match value {
        Some(v) if v <= limit => {}
        Some(v) => out.push(format!("{what} {v:.4} {unit} is above calibration.{key} ({limit} {unit})")),
        None => out.push(format!("{what} is undetermined (the captures do not fix the hand-eye)")),
    };
    over(
        "the expected error at the working distance",
        "max_expected_error_mm",
        c.expected_error_mm,
        limits.max_expected_error_mm,
        "mm",
    );
    over(
        "the translation's uncertainty",
        "max_translation_sigma_mm",
        c.translation_sigma_mm,
        limits.max_translation_sigma_mm,
        "mm",
    );
    over(
        "the rotation's uncertainty",
        "max_rotation_sigma_deg",
        c.rotation_sigma_deg,
        limits.max_rotation_sigma_deg,
        "deg",
    );
    let (worst_mm, worst_deg) = worst_residuals(c);
    over("the worst residual of a capture used", "max_residual_mm", Some(worst_mm), limits.max_residual_mm, "mm");
    if let Some(deg) = worst_deg {
        over(
            "the worst rotation residual of a capture used",
            "max_residual_deg",
            Some(deg),
            limits.max_residual_deg,
            "deg",
        );
    }
    let conditioning = &c.conditioning;
    if conditioning.largest_rotation_deg < limits.min_rotation_deg {
        out.push(format!(
            "the largest rotation between captures, {:.1} deg, is below calibration.min_rotation_deg ({} deg)",
            conditioning.largest_rotation_deg, limits.min_rotation_deg
        ));
    }
    if conditioning.axis_spread_deg < limits.min_axis_spread_deg {
        out.push(format!(
            "the spread of the rotation axes, {:.1} deg, is below calibration.min_axis_spread_deg ({} deg)",
            conditioning.axis_spread_deg, limits.min_axis_spread_deg
        ));
    }
    out
}

/// The largest residuals, mm and degrees, of the captures the result used.
fn worst_residuals(c: &Calibration) -> (f64, Option<f64>) {
    let used = c.residuals.iter().filter(|r| !c.outliers.contains(&r.capture));
    used.fold((0.0f64, None::<f64>), |(mm, deg), r| {
        (
            mm.max(r.translation_mm),
            match (deg, r.rotation_deg) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            },
        )
    })
}

/// The record of `c` with the gate's `failures`.
pub fn record(c: &Calibration, failures: &[String], forced: bool) -> CalibrationRecord {
    let (worst_residual_mm, worst_residual_deg) = worst_residuals(c);
    CalibrationRecord {
        passed: failures.is_empty(),
        forced: forced && !failures.is_empty(),
        failures: failures.to_vec(),
        expected_error_mm: c.expected_error_mm,
        translation_sigma_mm: c.translation_sigma_mm,
        rotation_sigma_deg: c.rotation_sigma_deg,
        worst_residual_mm,
        worst_residual_deg,
        working_distance_mm: c.working_distance_mm,
        captures: c.residuals.len() as u32,
        captures_used: (c.residuals.len() - c.outliers.len()) as u32,
    }
}
