//! The quality gates' limits: the `[quality]` section, its defaults and
//! its checks.

use serde::Deserialize;

use super::{ConfigError, check, in_range};

/// The limits a planned seam must meet (issue 12): the `[quality]` section.
/// A seam that breaks one is refused with the figure, its value and the
/// limit, unless the gate is named in `warn_only`; see
/// [`crate::pipeline::quality`] for how each figure is measured.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QualityParams {
    /// The largest RMS residual of a weld edge's fit, in point spacings at
    /// the seam (the boundary is sampled to about a third of one).
    pub max_edge_fit_rms_spacings: f64,
    /// The largest fraction of a weld edge's boundary samples that may lie
    /// beyond its fitted line towards the other plate (by more than the
    /// fit's trimming limit). A plate's points stop at its edge: beyond the
    /// line lies the edge itself where a dropout or a shadow cut the rest
    /// of it short.
    pub max_edge_samples_beyond: f64,
    /// The largest step between two runs of a weld edge's samples, each
    /// along a tenth of the edge at least, in point spacings at the seam:
    /// a plate's edge is one line, and two are an edge cut short along one
    /// of them. Read on the edges that place the weld: both of a butt
    /// joint, a lap's upper one.
    pub max_edge_step_spacings: f64,
    /// The least fraction of the seam each weld edge must be seen along.
    pub min_edge_coverage: f64,
    /// The least fraction of the visible joint (where both plates are seen
    /// beside it) the seam must span.
    pub min_joint_coverage: f64,
    /// The longest stretch, mm, beyond either end of the seam along which
    /// both plates are still seen beside the weld (issue 11: the seam
    /// covers the visible joint to within 2 mm of where both plates'
    /// evidence ends). Longer, an edge was lost there while its plate
    /// goes on: a streak or spatter over the edge. For a fillet root, how
    /// far the web's top and the flange up to the root may be seen past
    /// its ends, where its face is not seen down to the flange.
    pub max_joint_beyond_seam_mm: f64,
    /// Butt joints: the largest high-low misalignment of the plates, mm,
    /// and as a fraction of their thickness t (ISO 5817 quality level C:
    /// 0.15 t, at most 4 mm); the smaller limit applies. The camera sees
    /// only a ceiling on t, the depth to the surface the plates rest on,
    /// so the fraction applies to that when it is seen.
    pub max_misalignment_mm: f64,
    pub max_misalignment_of_thickness: f64,
    /// I-butt joints: the widest root gap, mm.
    pub max_gap_mm: f64,
    /// I-butt joints: the narrowest gap, at its widest along the seam, in
    /// point spacings at the seam. A gap under one spacing is below what
    /// the cloud resolves: the plates may touch, and two plates elsewhere
    /// with a gap as narrow are seen as one.
    pub min_gap_spacings: f64,
    /// The largest angle between the two plates' planes, degrees.
    pub max_plate_angle_deg: f64,
    /// Tee joints: how far the web's side face may lie off square to the
    /// flange, degrees (the `plate_angle` gate of a fillet root).
    pub max_web_tilt_deg: f64,
    /// The largest estimated position uncertainty (one sigma) of the seam,
    /// across it or along the normal, mm.
    pub max_position_uncertainty_mm: f64,
    /// V-butt joints: the largest difference between the groove depth a
    /// request gives and the one measured, mm (the weld lies at the depth
    /// given, Eq. 32).
    pub max_groove_depth_difference_mm: f64,
    /// Gates (by name) whose failure is a warning on the seam, not a
    /// refusal.
    pub warn_only: Vec<String>,
}

impl Default for QualityParams {
    fn default() -> Self {
        QualityParams {
            max_edge_fit_rms_spacings: 2.0,
            max_edge_samples_beyond: 0.1,
            max_edge_step_spacings: 2.0,
            min_edge_coverage: 0.5,
            min_joint_coverage: 0.8,
            max_joint_beyond_seam_mm: 2.0,
            max_misalignment_mm: 4.0,
            max_misalignment_of_thickness: 0.15,
            max_gap_mm: 4.0,
            min_gap_spacings: 1.0,
            max_plate_angle_deg: 5.0,
            max_web_tilt_deg: 10.0,
            max_position_uncertainty_mm: 0.5,
            max_groove_depth_difference_mm: 1.0,
            warn_only: Vec::new(),
        }
    }
}

impl QualityParams {
    /// Whether a failure of `gate` only warns.
    pub fn warns_only(&self, gate: crate::rules::Gate) -> bool {
        self.warn_only.iter().any(|name| name == gate.name())
    }

    /// Checks the `[quality]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        use crate::rules::Gate;
        in_range("quality.max_edge_fit_rms_spacings", self.max_edge_fit_rms_spacings, 0.05, 100.0)?;
        in_range("quality.max_edge_samples_beyond", self.max_edge_samples_beyond, 0.0, 1.0)?;
        in_range("quality.max_edge_step_spacings", self.max_edge_step_spacings, 0.5, 100.0)?;
        in_range("quality.min_edge_coverage", self.min_edge_coverage, 0.0, 1.0)?;
        in_range("quality.min_joint_coverage", self.min_joint_coverage, 0.0, 1.0)?;
        in_range("quality.max_joint_beyond_seam_mm", self.max_joint_beyond_seam_mm, 0.0, 1000.0)?;
        in_range("quality.max_misalignment_mm", self.max_misalignment_mm, 0.0, 50.0)?;
        in_range("quality.max_misalignment_of_thickness", self.max_misalignment_of_thickness, 0.0, 1.0)?;
        in_range("quality.max_gap_mm", self.max_gap_mm, 0.0, 50.0)?;
        in_range("quality.min_gap_spacings", self.min_gap_spacings, 0.0, 10.0)?;
        in_range("quality.max_plate_angle_deg", self.max_plate_angle_deg, 0.0, 90.0)?;
        in_range("quality.max_web_tilt_deg", self.max_web_tilt_deg, 0.0, 80.0)?;
        in_range("quality.max_position_uncertainty_mm", self.max_position_uncertainty_mm, 0.001, 100.0)?;
        in_range("quality.max_groove_depth_difference_mm", self.max_groove_depth_difference_mm, 0.0, 100.0)?;
        for name in &self.warn_only {
            check("quality.warn_only", Gate::from_name(name).is_some_and(Gate::can_warn), || {
                let names: Vec<&str> = Gate::ALL.iter().filter(|g| g.can_warn()).map(|g| g.name()).collect();
                format!("{name:?} is not a gate that can warn; those are {}", names.join(", "))
            })?;
        }
        Ok(())
    }
}
