//! Why the background stage found no workpiece: [`BackgroundError`],
//! one variant per finding, each answered by a rule of
//! [`crate::rules::background`] ([`BackgroundError::rule`]).

use crate::joint::JointType;
use crate::rules::{self, Rule};

/// Why no workpiece could be found among the plane clusters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BackgroundError {
    /// Fewer than two candidate planes remain.
    #[error("found {found} workpiece plane(s), need 2")]
    TooFewPlanes { found: usize },
    /// No two clusters lie in one plane nearer the camera than the rest.
    #[error(
        "found {found} planes but no two coplanar ones (offsets {offsets_mm:?} mm along the normal) for a butt joint"
    )]
    NoCoplanarPair { found: usize, offsets_mm: Vec<f64> },
    /// No two layers are one plate thickness apart.
    #[error(
        "found {found} planes but no two layers {min_mm} to {max_mm} mm apart (offsets {offsets_mm:?} mm) for a lap joint"
    )]
    NoLapStep { found: usize, offsets_mm: Vec<f64>, min_mm: f64, max_mm: f64 },
    /// A plane larger than either plate of the coplanar pair lies nearer
    /// the camera: the pair is more likely the table or a fixture seen on
    /// both sides of the workpiece, and the plane the two plates seen as
    /// one across a gap the cloud does not resolve.
    #[error(
        "a plane of {area_mm2:.0} mm² lies {above_mm:.1} mm nearer the camera than the only coplanar pair \
         (plates of {smaller_mm2:.0} mm² and more): the pair may be the table on both sides of a workpiece whose \
         plates are seen as one, across a gap narrower than the cloud resolves"
    )]
    PairUnderLargerPlane { area_mm2: f64, above_mm: f64, smaller_mm2: f64 },
    /// A butt joint was asked for, but the nearest plates lie in two
    /// layers one plate thickness apart, as a lap's do.
    #[error(
        "no two plates lie in one plane for a {joint} joint, but the nearest two lie {step_mm:.1} mm apart along \
         the normal, one over the other: this looks like a lap joint, not the {joint} joint requested"
    )]
    LooksLikeLap { joint: JointType, step_mm: f64 },
    /// A lap joint was asked for, but the upper layer holds two plates
    /// side by side, as butt plates lie.
    #[error(
        "the upper layer holds two plates side by side in one plane ({first_mm2:.0} and {second_mm2:.0} mm²), \
         coplanar within {tolerance_mm} mm: this looks like a butt joint, not the lap requested"
    )]
    LooksLikeButt { first_mm2: f64, second_mm2: f64, tolerance_mm: f64 },
    /// A nearer plane lies across the plane the plates were sought in,
    /// which is seen on both of its sides: a tee's web on its flange,
    /// or an object lying on the workpiece; not a plate of a butt or lap
    /// joint. The layers alone cannot tell the two apart.
    #[error(
        "a plane of {top_mm2:.0} mm², {above_mm:.1} mm nearer the camera, lies across the plane under it, \
         which is seen on both of its sides ({first_mm2:.0} and {second_mm2:.0} mm²): the web of a tee joint \
         standing on its flange, no taller than a lap's step (too low to be told from a bar), or an object lying on the workpiece (a clamp or a \
         bar) over the joint; a lap's upper plate ends on its lower plate, and butt plates are not one plane cut \
         in two; for a clamp, clear the joint or set a region of interest beside it"
    )]
    LiesAcross { top_mm2: f64, above_mm: f64, first_mm2: f64, second_mm2: f64 },
    /// A butt joint's layer holds a third plate as large as a plate, lying
    /// beside the pair across their seam rather than along it (a piece a
    /// clamp or a streak cut off a plate lies along it): three plates side
    /// by side meet at two joints, and the request names one.
    #[error(
        "three plates lie side by side in one plane ({first_mm2:.0}, {second_mm2:.0} and {third_mm2:.0} mm²), the \
         third beyond the pair across their seam: they meet at two joints and the {joint} joint requested is either; \
         set a region of interest round the one to weld"
    )]
    ThreeSideBySide { joint: JointType, first_mm2: f64, second_mm2: f64, third_mm2: f64 },
    /// The joint type was left to the planner, and the nearest layer holds
    /// a plate and a piece too small to be a plate beside it, over a lower
    /// plane one plate thickness behind: butt plates, one barely seen, or a
    /// lap's upper plate that a gap in the cloud cut in two.
    #[error(
        "the nearest layer holds a plate of {first_mm2:.0} mm² and a piece of {second_mm2:.0} mm² beside it, \
         {step_mm:.1} mm over a lower plane: two butt plates, one barely in view, or a lap's upper plate cut in two \
         by a gap in the cloud; the joint type cannot be told: name it in the request"
    )]
    Ambiguous { first_mm2: f64, second_mm2: f64, step_mm: f64 },
    /// A butt or lap joint was asked for, but a long narrow plane lies a
    /// web's height over a layer seen on both of its sides: a tee's web on
    /// its flange.
    #[error(
        "a long narrow plane of {top_mm2:.0} mm², about {width_mm:.0} mm wide, lies {height_mm:.1} mm over a plane \
         seen on both of its sides ({first_mm2:.0} and {second_mm2:.0} mm²): this looks like a tee joint (a web \
         standing on its flange), not the {joint} joint requested"
    )]
    LooksLikeTee { joint: JointType, top_mm2: f64, width_mm: f64, height_mm: f64, first_mm2: f64, second_mm2: f64 },
    /// A tee was asked for, and no long narrow plane lies a web's height
    /// over a plane beside it: more than `min_mm` or, shorter, at least
    /// `min_height_per_width` times its width, and at most `max_mm`; nor
    /// does a wider one stand more than `min_mm` over a plane with a face
    /// falling from it to that plane.
    #[error(
        "found {found} planes but no long narrow one (a web's top, at most {max_width_mm} mm wide) standing over a \
         plane beside it more than {min_mm} mm, or at least {min_height_per_width} times its width, and at most \
         {max_mm} mm, nor a wider one standing more than {min_mm} mm over a plane with a face seen falling to it \
         (offsets {offsets_mm:?} mm) for a tee joint"
    )]
    NoWeb { found: usize, offsets_mm: Vec<f64>, min_mm: f64, min_height_per_width: f64, max_mm: f64, max_width_mm: f64 },
    /// The joint type was left to the planner, and a long narrow plane
    /// lies a web's height over a plane seen on one of its sides only: a
    /// tee whose flange the web hides on its far side, or a bar standing
    /// at a plate's edge.
    #[error(
        "a long narrow plane of {top_mm2:.0} mm², about {width_mm:.0} mm wide, lies {height_mm:.1} mm over a plane \
         seen on one of its sides only ({beside_mm2:.0} mm²): a tee joint whose flange the web hides on its far \
         side, or a bar standing at a plate's edge; the joint type cannot be told: name it (t_fillet) in the request"
    )]
    OneSidedWeb { top_mm2: f64, width_mm: f64, height_mm: f64, beside_mm2: f64 },
    /// A plate stands at the end of the flange, with nothing at the
    /// flange's level beyond it and the table far below (or, beside an
    /// outside corner's edge in a cloud cropped round it, the plate's outer
    /// face going down, or nothing): a corner joint.
    /// An outside corner is refused under every request, an inside one
    /// under any request but `t_fillet` or `auto` (which plan its root).
    #[error("this looks like a corner joint ({kind} corner): {what}; {}", kind.advice())]
    LooksLikeCorner { kind: CornerKind, what: String },
    /// The joint type was left to the planner, and the layers fit neither
    /// layout.
    #[error("the joint type cannot be told from the plates: not a butt joint ({butt}); not a lap ({lap})")]
    Unrecognised { butt: Box<BackgroundError>, lap: Box<BackgroundError> },
}

/// The two corner joints [`super::find_corner`] recognises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CornerKind {
    /// A web standing on the flange's end, its outer face flush with the
    /// flange's end face (the L seen from inside).
    Inside,
    /// A web beside the flange's end, its top flush with the flange's top
    /// or a little proud of it (the L seen from outside).
    Outside,
}

impl CornerKind {
    /// What is planned of such a corner, for its refusal.
    pub fn advice(self) -> &'static str {
        match self {
            CornerKind::Inside => {
                "its fillet root is planned as a tee's (request t_fillet or auto), not as a butt joint or a lap"
            }
            CornerKind::Outside => "an outside corner's weld is not planned",
        }
    }
}

impl std::fmt::Display for CornerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CornerKind::Inside => "inside",
            CornerKind::Outside => "outside",
        })
    }
}

impl BackgroundError {
    /// The rule that found no workpiece (`crate::rules::background`).
    pub fn rule(&self) -> &'static Rule {
        use rules::background as r;
        match self {
            BackgroundError::TooFewPlanes { .. } => &r::TOO_FEW_PLANES,
            BackgroundError::NoCoplanarPair { .. } => &r::BUTT_NO_COPLANAR_PAIR,
            BackgroundError::NoLapStep { .. } => &r::LAP_NO_PLATE_STEP,
            BackgroundError::PairUnderLargerPlane { .. } => &r::BUTT_PAIR_UNDER_LARGER_PLANE,
            BackgroundError::LooksLikeLap { .. } => &r::LOOKS_LIKE_LAP,
            BackgroundError::LooksLikeButt { .. } => &r::LOOKS_LIKE_BUTT,
            BackgroundError::LiesAcross { .. } => &r::LAP_UPPER_PLANE_LIES_ACROSS_LOWER,
            BackgroundError::ThreeSideBySide { .. } => &r::BUTT_THIRD_PLATE_BEYOND_PAIR,
            BackgroundError::Ambiguous { .. } => &r::PLATE_AND_PIECE_OVER_LOWER_PLANE,
            BackgroundError::LooksLikeTee { .. } => &r::LOOKS_LIKE_TEE,
            BackgroundError::NoWeb { .. } => &r::TEE_NO_WEB_TOP,
            BackgroundError::OneSidedWeb { .. } => &r::TEE_WEB_SEEN_ON_ONE_SIDE,
            BackgroundError::LooksLikeCorner { kind: CornerKind::Outside, .. } => &r::CORNER_OUTSIDE_NOT_PLANNED,
            BackgroundError::LooksLikeCorner { kind: CornerKind::Inside, .. } => &r::CORNER_INSIDE_NEEDS_FILLET_REQUEST,
            BackgroundError::Unrecognised { .. } => &r::NO_LAYOUT_FITS,
        }
    }

    /// Whether the error says the joint seen is not the joint requested.
    pub fn is_joint_mismatch(&self) -> bool {
        matches!(
            self,
            BackgroundError::LooksLikeLap { .. }
                | BackgroundError::LooksLikeButt { .. }
                | BackgroundError::LooksLikeTee { .. }
        )
    }

    /// Whether the joint type was left to the planner and could not be told.
    pub fn is_unrecognised(&self) -> bool {
        matches!(
            self,
            BackgroundError::Unrecognised { .. }
                | BackgroundError::Ambiguous { .. }
                | BackgroundError::OneSidedWeb { .. }
        )
    }
}
