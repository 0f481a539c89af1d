//! The quality gates: the classes of refusal the protocol carries as a
//! code. Each gate is the family of one or more rules ([`super::Rule`]);
//! a rule's id says which decision refused, its gate which class of
//! refusal it is, for a controller that branches on the class.

use std::fmt;

/// A limit a seam must meet. The names and numbers are stable: the
/// protocol and `plan --json` carry them, and `quality.warn_only` names
/// them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Gate {
    /// More of a weld edge's boundary samples than
    /// `quality.max_edge_samples_beyond` lie beyond its fitted line towards
    /// the other plate, or its samples run on two lines further apart than
    /// `quality.max_edge_step_spacings`: the edge was cut short along
    /// much of its length.
    EdgeCutShort,
    /// A weld edge's fit residual is above `quality.max_edge_fit_rms_spacings`.
    EdgeFitResidual,
    /// A weld edge was seen along less of the seam than `quality.min_edge_coverage`.
    EdgeCoverage,
    /// The seam spans less of the visible joint than `quality.min_joint_coverage`.
    JointCoverage,
    /// The butt plates' high-low misalignment exceeds its limit.
    Misalignment,
    /// An I-butt joint's gap is wider than `quality.max_gap_mm`.
    GapWidth,
    /// An I-butt joint's gap, at its widest, is narrower than
    /// `quality.min_gap_spacings` point spacings: narrower than the cloud
    /// resolves, so the cloud cannot show where plates part, here or
    /// across a plate it sees whole.
    GapUnresolved,
    /// The two plates' planes meet at more than `quality.max_plate_angle_deg`.
    PlateAngle,
    /// The seam's position is known less well than `quality.max_position_uncertainty_mm`.
    PositionUncertainty,
    /// The groove depth given differs from the one measured by more than
    /// `quality.max_groove_depth_difference_mm`.
    GrooveDepth,
    /// The plates seen are not those of the joint requested (a lap's step
    /// where a butt joint was asked for, butt plates for a lap, a square
    /// gap for a V-groove or bevels for an I-butt joint, a plate standing
    /// between the edges). Not a figure of a seam, so it cannot be only a
    /// warning.
    JointMismatch,
    /// `auto` was asked for and the geometry does not say which joint it is.
    JointUnknown,
    /// The plates are a corner joint's (a plate standing at the flange's
    /// end): an outside corner, or an inside one under a butt or lap
    /// request.
    CornerJoint,
}

impl Gate {
    pub const ALL: [Gate; 13] = [
        Gate::EdgeCutShort,
        Gate::EdgeFitResidual,
        Gate::EdgeCoverage,
        Gate::JointCoverage,
        Gate::Misalignment,
        Gate::GapWidth,
        Gate::GapUnresolved,
        Gate::PlateAngle,
        Gate::PositionUncertainty,
        Gate::GrooveDepth,
        Gate::JointMismatch,
        Gate::JointUnknown,
        Gate::CornerJoint,
    ];

    /// Whether `quality.warn_only` may name the gate: every gate read from
    /// a planned seam's figures.
    pub fn can_warn(self) -> bool {
        !matches!(self, Gate::JointMismatch | Gate::JointUnknown | Gate::CornerJoint)
    }

    /// The gate's snake_case name, as config, logs and JSON write it.
    pub fn name(self) -> &'static str {
        match self {
            Gate::EdgeCutShort => "edge_cut_short",
            Gate::EdgeFitResidual => "edge_fit_residual",
            Gate::EdgeCoverage => "edge_coverage",
            Gate::JointCoverage => "joint_coverage",
            Gate::Misalignment => "misalignment",
            Gate::GapWidth => "gap_width",
            Gate::GapUnresolved => "gap_unresolved",
            Gate::PlateAngle => "plate_angle",
            Gate::PositionUncertainty => "position_uncertainty",
            Gate::GrooveDepth => "groove_depth",
            Gate::JointMismatch => "joint_mismatch",
            Gate::JointUnknown => "joint_unknown",
            Gate::CornerJoint => "corner_joint",
        }
    }

    pub fn from_name(name: &str) -> Option<Gate> {
        Gate::ALL.into_iter().find(|g| g.name() == name)
    }
}

impl fmt::Display for Gate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
