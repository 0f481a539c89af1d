//! Faults a real cell puts in front of the camera, as parts of a
//! [`SceneSpec`]: each is seeded, validated with the scene, rendered into
//! the frame by the scene (solids), the renderer's depth pass (bands of
//! missing points) or after the sensor noise (streaks), and leaves the
//! ground truth where it was: the seam between plates A and B.
//!
//! The faults, and what the right answer to each is
//! ([`right_answer`], scored by `eval`):
//!
//! | fault | what the frame shows | right answer |
//! |---|---|---|
//! | [`Fault::WrongJoint`] | the scene's joint; the request names another | a refusal, always: any seam is a confident wrong one |
//! | [`Fault::SeamDropout`] | a band of missing points over the seam along part of it, as a specular groove gives | the whole seam within the bar, or a piece of it |
//! | [`Fault::Clamp`] | a bar lying across both plates over the seam | the whole seam, or a piece beside the clamp |
//! | [`Fault::TackWelds`] | short blobs filling the gap or groove (or the lap's corner) every so many mm | the whole seam, or a piece between tacks |
//! | [`Fault::Spatter`] | small beads on the plates near the seam | the whole seam |
//! | [`Fault::EdgeGlare`] | no returns in runs along the plates' bright seam-side edges, as a polished or freshly cut arris saturates the sensor | the whole seam, or a piece where neither edge glares |
//! | [`Fault::SpecularStreaks`] | lines of outlier depths, as saturated structured light gives | the whole seam |
//! | [`Fault::BarelyInView`] | the seam near the image border: a sliver of one plate in view | the whole seam |
//! | [`Fault::TouchingPart`] | a second plate abutting one plate's outer edge | the whole seam |
//!
//! Every answer but the wrong joint's may also be a refusal: a refusal is
//! never a confident wrong seam. "Within the bar" is `SeamError::passes`
//! (max < 1 mm, both ends within 2 mm) against the seam the frame shows.
//!
//! Where a fault hides part of the seam, the choice is:
//! - *A piece* is a stretch of the observed seam along which neither seam
//!   edge is hidden by the fault (from the camera or the projector) and no
//!   dropout band lies ([`visible_pieces`]); a seam returned for a piece
//!   must meet the bar against that piece, its ends within 2 mm of the
//!   piece's. Pieces shorter than [`MIN_PIECE_MM`] are not answers.
//! - Under every such fault the whole seam within the bar is right, and
//!   so is a piece: the seam is still there under a dropout band (only
//!   data is missing), under tacks (a welder welds over them) and under a
//!   clamp, and stopping where the evidence stops is incomplete, not
//!   wrong. A seam bridging a clamp is counted within the bar because
//!   issue 12's confident wrong seam is one off by more than the bar, and
//!   this one is where the seam is; whether the torch may pass the clamp
//!   is the cell's collision check's to say, which sees the clamp too.
//!
//! [`FaultKind::BarelyInView`] is not drawn: it is where the camera looks,
//! set by [`frame_barely_in_view`] when the scene is made, and recorded in
//! the spec so the suite and a reader know why the view is so tight.

use std::fmt;
use std::str::FromStr;

use nalgebra::Isometry3;
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use rayon::prelude::*;

mod render;
#[cfg(test)]
mod tests;

pub use render::{draw_streaks, erase_dropout_bands, fault_solids, frame_barely_in_view};

use super::scene::{ConvexSolid, SurfaceKind};
use super::suite::{MIN_PLATE_IN_VIEW_MM, plates_in_view, uniform};
use super::truth::{LineOfSight, observed_seam_range, unhidden_stretches};
use super::{InvalidScene, JointGeometry, SceneSpec};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::joint::JointType;

/// Pieces of seam shorter than this are no answer a planner is asked for.
pub const MIN_PIECE_MM: f64 = 5.0;
/// Corners of the octagon a spatter bead's cross-section is.
const BEAD_CORNERS: usize = 8;

/// The kinds of fault, for naming scenes, choosing from the command line
/// and counting per fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FaultKind {
    WrongJoint,
    SeamDropout,
    Clamp,
    TackWelds,
    Spatter,
    SpecularStreaks,
    BarelyInView,
    TouchingPart,
    EdgeGlare,
}

impl FaultKind {
    /// Every kind, in the order the fault suite draws them; a new kind
    /// goes last so the scenes of the others keep their random streams.
    pub const ALL: [FaultKind; 9] = [
        FaultKind::WrongJoint,
        FaultKind::SeamDropout,
        FaultKind::Clamp,
        FaultKind::TackWelds,
        FaultKind::Spatter,
        FaultKind::SpecularStreaks,
        FaultKind::BarelyInView,
        FaultKind::TouchingPart,
        FaultKind::EdgeGlare,
    ];

    /// The name in scene names and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::WrongJoint => "wrong-joint",
            FaultKind::SeamDropout => "seam-dropout",
            FaultKind::Clamp => "clamp",
            FaultKind::TackWelds => "tack-welds",
            FaultKind::Spatter => "spatter",
            FaultKind::SpecularStreaks => "streaks",
            FaultKind::BarelyInView => "barely-in-view",
            FaultKind::TouchingPart => "touching-part",
            FaultKind::EdgeGlare => "edge-glare",
        }
    }
}

impl fmt::Display for FaultKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A fault name that is none of [`FaultKind::ALL`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "unknown fault {0:?}: one of wrong-joint, seam-dropout, clamp, tack-welds, spatter, streaks, barely-in-view, touching-part, \
     edge-glare"
)]
pub struct UnknownFault(pub String);

impl FromStr for FaultKind {
    type Err = UnknownFault;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key = s.trim().to_ascii_lowercase().replace('_', "-");
        FaultKind::ALL.into_iter().find(|k| k.name() == key).ok_or_else(|| UnknownFault(s.to_string()))
    }
}

/// One of the two plates of the joint (A on the -x side, the lap's upper).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlateSide {
    A,
    B,
}

/// One fault in a scene. Lengths in mm, positions `along` the seam are
/// workpiece y (the seam runs along y at x = 0).
#[derive(Debug, Clone, PartialEq)]
pub enum Fault {
    /// The request names `requested`, not the scene's joint.
    WrongJoint { requested: JointType },
    /// No return from a band over the seam between `along_mm[0]` and
    /// `along_mm[1]`, reaching `margin_mm` beyond the seam-side edges onto
    /// both plates.
    SeamDropout { along_mm: [f64; 2], margin_mm: f64 },
    /// A bar `width_mm` wide along the seam, centred at `centre_mm`, lying
    /// on the plates across the seam, `half_reach_mm` either side of it and
    /// `height_mm` tall.
    Clamp { centre_mm: f64, width_mm: f64, height_mm: f64, half_reach_mm: f64 },
    /// Tacks `length_mm` long every `pitch_mm` from `first_mm`, filling the
    /// gap or groove, spreading `spread_mm` onto the plates beside it and
    /// standing `crown_mm` proud of the top (for a lap, a fillet in the
    /// corner with legs of `spread_mm + crown_mm`).
    TackWelds { first_mm: f64, pitch_mm: f64, length_mm: f64, crown_mm: f64, spread_mm: f64 },
    /// `count` beads of `radius_mm` on the plates' tops, beside the seam
    /// within `spread_mm` of it, placed from `seed`.
    Spatter { seed: u64, count: usize, radius_mm: f64, spread_mm: f64 },
    /// `count` straight streaks `length_mm` long and `width_px` wide in the
    /// image, each through a point near the seam, whose depths are off by
    /// `offset_mm` (either way, up to half again, from `seed`).
    SpecularStreaks { seed: u64, count: usize, length_mm: f64, width_px: f64, offset_mm: f64 },
    /// Only `in_view_mm` of `plate`'s top is in view beside the seam (the
    /// camera's aim is set by [`frame_barely_in_view`]).
    BarelyInView { plate: PlateSide, in_view_mm: f64 },
    /// A second plate `width_mm` wide abutting `plate`'s outer edge along
    /// its whole length, its top `step_mm` above that plate's.
    TouchingPart { plate: PlateSide, width_mm: f64, step_mm: f64 },
    /// Each seam-side edge of the plates (the arris where a plate's top
    /// meets its bevel, face or gap) returns no depth within `band_mm` of
    /// it, in runs `run_mm[0]` to `run_mm[1]` long that cover about `share`
    /// of its length, placed from `seed` for each edge on its own
    /// ([`Fault::glare_runs`]).
    EdgeGlare { seed: u64, band_mm: f64, run_mm: [f64; 2], share: f64 },
}

impl Fault {
    pub fn kind(&self) -> FaultKind {
        match self {
            Fault::WrongJoint { .. } => FaultKind::WrongJoint,
            Fault::SeamDropout { .. } => FaultKind::SeamDropout,
            Fault::Clamp { .. } => FaultKind::Clamp,
            Fault::TackWelds { .. } => FaultKind::TackWelds,
            Fault::Spatter { .. } => FaultKind::Spatter,
            Fault::SpecularStreaks { .. } => FaultKind::SpecularStreaks,
            Fault::BarelyInView { .. } => FaultKind::BarelyInView,
            Fault::TouchingPart { .. } => FaultKind::TouchingPart,
            Fault::EdgeGlare { .. } => FaultKind::EdgeGlare,
        }
    }

    /// A typical instance of `kind` on `spec`'s seam (its middle, its
    /// joint), for `simulate --fault` and the tests. Apply
    /// [`frame_barely_in_view`] after adding a [`Fault::BarelyInView`].
    pub fn example(kind: FaultKind, spec: &SceneSpec) -> Fault {
        let [y0, y1] = spec.seam_range();
        let middle = (y0 + y1) / 2.0;
        match kind {
            FaultKind::WrongJoint => Fault::WrongJoint {
                requested: match spec.joint.joint_type() {
                    JointType::Lap => JointType::IButt,
                    _ => JointType::Lap,
                },
            },
            FaultKind::SeamDropout => Fault::SeamDropout { along_mm: [middle - 20.0, middle + 20.0], margin_mm: 2.0 },
            FaultKind::Clamp => {
                Fault::Clamp { centre_mm: middle, width_mm: 30.0, height_mm: 25.0, half_reach_mm: 80.0 }
            }
            FaultKind::TackWelds => {
                Fault::TackWelds { first_mm: y0 + 20.0, pitch_mm: 50.0, length_mm: 6.0, crown_mm: 1.5, spread_mm: 2.0 }
            }
            FaultKind::Spatter => Fault::Spatter { seed: spec.seed, count: 60, radius_mm: 0.8, spread_mm: 20.0 },
            FaultKind::SpecularStreaks => {
                Fault::SpecularStreaks { seed: spec.seed, count: 3, length_mm: 80.0, width_px: 3.0, offset_mm: 8.0 }
            }
            FaultKind::BarelyInView => Fault::BarelyInView { plate: PlateSide::B, in_view_mm: 12.0 },
            FaultKind::TouchingPart => Fault::TouchingPart { plate: PlateSide::B, width_mm: 80.0, step_mm: 1.5 },
            FaultKind::EdgeGlare => Fault::EdgeGlare { seed: spec.seed, band_mm: 1.5, run_mm: [5.0, 20.0], share: 0.3 },
        }
    }

    /// Checks the fault's numbers against the scene it is in.
    pub fn validate(&self, spec: &SceneSpec) -> Result<(), InvalidScene> {
        let fail = |what: String| Err(InvalidScene(format!("{}: {what}", self.kind())));
        let positive = |v: f64| v > 0.0 && v.is_finite();
        let [y0, y1] = spec.seam_range();
        if matches!(spec.joint, JointGeometry::Tee { .. } | JointGeometry::Corner { .. }) || !spec.others.is_empty() {
            return fail("faults are drawn on one butt or lap joint per frame only".into());
        }
        match *self {
            Fault::WrongJoint { requested } => {
                if requested == spec.joint.joint_type() {
                    return fail(format!("the request must name another joint than the scene's {requested}"));
                }
            }
            Fault::SeamDropout { along_mm: [a, b], margin_mm } => {
                if !(a.is_finite() && b.is_finite() && a < b && b > y0 && a < y1) {
                    return fail(format!("the band {a}..{b} must be an interval overlapping the seam {y0}..{y1}"));
                }
                if !(0.0..=50.0).contains(&margin_mm) {
                    return fail("the margin must be between 0 and 50 mm".into());
                }
            }
            Fault::Clamp { centre_mm, width_mm, height_mm, half_reach_mm } => {
                if !(centre_mm.is_finite() && positive(width_mm) && positive(height_mm) && positive(half_reach_mm)) {
                    return fail("the clamp needs a finite place and positive sizes".into());
                }
                if half_reach_mm <= spec.joint.seam_edge_half_width() + 1.0 {
                    return fail("the clamp must reach over both seam edges".into());
                }
            }
            Fault::TackWelds { first_mm, pitch_mm, length_mm, crown_mm, spread_mm } => {
                if !(first_mm.is_finite() && positive(pitch_mm) && positive(length_mm) && positive(spread_mm)) {
                    return fail("tacks need a finite start and positive pitch, length and spread".into());
                }
                if !(length_mm < pitch_mm && (0.0..=10.0).contains(&crown_mm) && spread_mm <= 20.0) {
                    return fail(
                        "tacks must be shorter than their pitch, crowns 0 to 10 mm, spread at most 20 mm".into(),
                    );
                }
            }
            Fault::Spatter { count, radius_mm, spread_mm, .. } => {
                let edge = spec.joint.seam_edge_half_width();
                if !(count <= 10_000 && positive(radius_mm) && radius_mm <= 5.0) {
                    return fail("at most 10000 beads of radius 0 to 5 mm".into());
                }
                if !(spread_mm > edge + 2.0 * radius_mm && spread_mm.is_finite()) {
                    return fail(format!("the spread must reach past the seam edge ({edge:.2} mm) by a bead"));
                }
            }
            Fault::SpecularStreaks { count, length_mm, width_px, offset_mm, .. } => {
                if !(count <= 100 && positive(length_mm) && length_mm <= 2000.0) {
                    return fail("at most 100 streaks of 0 to 2000 mm".into());
                }
                if !(positive(width_px) && width_px <= 50.0 && positive(offset_mm) && offset_mm <= 500.0) {
                    return fail("streaks 0 to 50 px wide, their depths off by 0 to 500 mm".into());
                }
            }
            Fault::BarelyInView { in_view_mm, .. } => {
                if !(positive(in_view_mm) && in_view_mm < MIN_PLATE_IN_VIEW_MM) {
                    return fail(format!("a plate barely in view shows less than {} mm", MIN_PLATE_IN_VIEW_MM));
                }
            }
            Fault::TouchingPart { width_mm, step_mm, plate } => {
                let thickness = plate_top_and_bottom(&spec.joint, plate);
                if !(positive(width_mm) && step_mm.is_finite() && thickness[0] + step_mm > thickness[1] + 1.0) {
                    return fail("the part needs a positive width and a top above its bottom".into());
                }
            }
            Fault::EdgeGlare { band_mm, run_mm: [shortest, longest], share, .. } => {
                if !(positive(band_mm) && band_mm <= 10.0) {
                    return fail("the glare reaches 0 to 10 mm from the edge".into());
                }
                if !(positive(shortest) && shortest <= longest && longest <= 500.0) {
                    return fail("glare runs from a positive length up to at most 500 mm".into());
                }
                if !(share > 0.0 && share < 1.0) {
                    return fail("the glare covers a share of each edge between 0 and 1".into());
                }
            }
        }
        Ok(())
    }

    /// The stretches of the seam (workpiece y ranges) along which each of
    /// the two seam-side edges of [`JointGeometry::seam_edges_xz`] glares,
    /// for a [`Fault::EdgeGlare`]; none for any other fault. Runs and the
    /// lit stretches between them alternate from the seam's start, their
    /// lengths drawn uniformly, the lit ones scaled so the runs cover about
    /// the fault's share.
    pub fn glare_runs(&self, spec: &SceneSpec) -> [Vec<[f64; 2]>; 2] {
        let Fault::EdgeGlare { seed, run_mm: [shortest, longest], share, .. } = *self else {
            return [Vec::new(), Vec::new()];
        };
        let [y0, y1] = spec.seam_range();
        let lit_scale = (1.0 - share) / share;
        [0u64, 1].map(|edge| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(FaultKind::EdgeGlare as u64 * 2 + edge);
            let mut runs = Vec::new();
            let mut y = y0 + lit_scale * uniform(&mut rng, shortest, longest) * uniform(&mut rng, 0.0, 1.0);
            while y < y1 {
                let end = (y + uniform(&mut rng, shortest, longest)).min(y1);
                runs.push([y, end]);
                y = end + lit_scale * uniform(&mut rng, shortest, longest);
            }
            runs
        })
    }
}

/// The z of a plate's top and bottom, `[top, bottom]`.
fn plate_top_and_bottom(joint: &JointGeometry, plate: PlateSide) -> [f64; 2] {
    let x = match plate {
        PlateSide::A => -1.0,
        PlateSide::B => 1.0,
    };
    let bottom = match (*joint, plate) {
        (JointGeometry::Lap { lower_thickness_mm, .. }, PlateSide::A) => lower_thickness_mm,
        _ => 0.0,
    };
    [joint.top_z(x), bottom]
}

impl SceneSpec {
    /// The joint the request names: the scene's, unless a
    /// [`Fault::WrongJoint`] names another.
    pub fn requested_joint(&self) -> JointType {
        self.faults
            .iter()
            .find_map(|f| match f {
                Fault::WrongJoint { requested } => Some(*requested),
                _ => None,
            })
            .unwrap_or(self.joint.joint_type())
    }

    /// The groove depth the request gives: the scene's for its own
    /// V-butt; for a wrong V-butt request, half the plates' top height (a
    /// plausible figure a person would type).
    pub fn requested_groove_depth_mm(&self) -> Option<f64> {
        self.groove_depth_requested_as(self.requested_joint())
    }

    /// The groove depth a request for `joint` gives: the scene's for a
    /// V-butt request on its own V-butt, half the plates' top height for
    /// one on another joint, none for any other request.
    pub fn groove_depth_requested_as(&self, joint: JointType) -> Option<f64> {
        match (joint, self.joint.groove_depth_mm()) {
            (JointType::VButt, Some(depth)) => Some(depth),
            (JointType::VButt, None) => Some(self.joint.seam_z() / 2.0),
            _ => None,
        }
    }

    /// The kind of the scene's first fault, if it has one.
    pub fn fault_kind(&self) -> Option<FaultKind> {
        self.faults.first().map(Fault::kind)
    }
}

/// What the planner should answer on a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct RightAnswer {
    /// Only a refusal is right (the wrong joint was requested).
    pub refuse: bool,
    /// The whole observed seam within the bar is right.
    pub whole_seam: bool,
    /// Stretches of the seam (workpiece y ranges) a seam may be returned
    /// for instead; empty when the faults hide none of it.
    pub pieces_mm: Vec<[f64; 2]>,
}

/// The right answer to `spec` as `camera` sees it (see the module doc).
pub fn right_answer(spec: &SceneSpec, camera: &CameraModel) -> RightAnswer {
    let kinds: Vec<FaultKind> = spec.faults.iter().map(Fault::kind).collect();
    let refuse = kinds.contains(&FaultKind::WrongJoint);
    let hides = kinds
        .iter()
        .any(|k| matches!(k, FaultKind::SeamDropout | FaultKind::Clamp | FaultKind::TackWelds | FaultKind::EdgeGlare));
    RightAnswer {
        refuse,
        whole_seam: !refuse,
        pieces_mm: if hides && !refuse { visible_pieces(spec, camera) } else { Vec::new() },
    }
}

/// The stretches of the observed seam that no fault hides: no dropout
/// band over them, neither seam edge glaring, and neither seam edge behind
/// or inside a fault's solid as the camera and the projector see it. At
/// least [`MIN_PIECE_MM`] long.
pub fn visible_pieces(spec: &SceneSpec, camera: &CameraModel) -> Vec<[f64; 2]> {
    let Some([y0, y1]) = observed_seam_range(spec, camera) else {
        return Vec::new();
    };
    let camera_from_workpiece: Isometry3<f64> = spec.workpiece_from_camera().inverse();
    let solids: Vec<ConvexSolid> = fault_solids(spec).iter().map(|s| s.transformed(&camera_from_workpiece)).collect();
    let bands: Vec<[f64; 2]> = spec
        .faults
        .iter()
        .filter_map(|f| match *f {
            Fault::SeamDropout { along_mm, .. } => Some(along_mm),
            _ => None,
        })
        .collect();
    let glaring: Vec<[f64; 2]> = spec.faults.iter().flat_map(|f| f.glare_runs(spec).into_iter().flatten()).collect();
    let sight = LineOfSight::new(solids, camera);
    let hidden =
        |y: f64| {
            bands.iter().chain(&glaring).any(|[a, b]| (*a..=*b).contains(&y))
                || spec.joint.seam_edges_xz().iter().any(|[x, z]| {
                    sight.hides(&camera_from_workpiece.transform_point(&Vec3::new(*x, y, *z).into()).coords)
                })
        };
    unhidden_stretches([y0, y1], hidden, MIN_PIECE_MM)
}
