//! Why the joint between a butt joint's edges is refused: not the one
//! requested, not one the planner can name, or edges that are not the
//! groove's. Each refusal is a rule of [`crate::rules::groove`].

use crate::rules::{self, Rule};

/// Why the joint between the edges is not the one requested, or cannot be
/// told.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GrooveError {
    #[error(
        "a plate stands between the two plates' edges, up to {height_mm:.0} mm above them along {share:.0} % of the \
         seam: this looks like a tee joint (a web standing on a flange), which is not planned; {profile}"
    )]
    LooksLikeTee { height_mm: f64, share: f64, profile: String },
    #[error(
        "no groove faces between the weld edges ({profile}): this looks like an I-butt joint, not the V-butt requested"
    )]
    LooksLikeIButt { profile: String },
    #[error(
        "groove faces between the weld edges ({profile}): this looks like a V-butt joint, not the I-butt requested"
    )]
    LooksLikeVButt { profile: String },
    #[error(
        "the points between the weld edges are neither a V-groove's faces nor a square gap ({profile}): the joint \
         type cannot be told; name it in the request"
    )]
    Unclear { profile: String },
    #[error(
        "the weld edges are {opening_mm:.1} mm apart, but a V-groove {depth_mm:.1} mm deep with the bevels seen \
         opens {least_mm:.1} to {most_mm:.1} mm at its top ({profile}): the edges found are not this groove's \
         (another part beside the joint, or something in the groove), or the groove depth is wrong"
    )]
    OpeningMismatch { opening_mm: f64, depth_mm: f64, least_mm: f64, most_mm: f64, profile: String },
}

impl GrooveError {
    /// Whether the type was left to the planner and could not be told
    /// (every other error names what the joint looks like).
    pub fn is_unknown(&self) -> bool {
        matches!(self, GrooveError::Unclear { .. })
    }

    /// The rule that refused.
    pub fn rule(&self) -> &'static Rule {
        match self {
            GrooveError::LooksLikeTee { .. } => &rules::groove::PLATE_STANDING_IN_GAP,
            GrooveError::LooksLikeIButt { .. } => &rules::groove::NO_BEVEL_FOR_V_BUTT,
            GrooveError::LooksLikeVButt { .. } => &rules::groove::BEVELS_IN_I_BUTT,
            GrooveError::Unclear { .. } => &rules::groove::TYPE_UNCLEAR,
            GrooveError::OpeningMismatch { .. } => &rules::groove::OPENING_OFF_DEPTH,
        }
    }
}
