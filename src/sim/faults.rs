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
}

impl FaultKind {
    pub const ALL: [FaultKind; 8] = [
        FaultKind::WrongJoint,
        FaultKind::SeamDropout,
        FaultKind::Clamp,
        FaultKind::TackWelds,
        FaultKind::Spatter,
        FaultKind::SpecularStreaks,
        FaultKind::BarelyInView,
        FaultKind::TouchingPart,
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
    "unknown fault {0:?}: one of wrong-joint, seam-dropout, clamp, tack-welds, spatter, streaks, barely-in-view, touching-part"
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
        }
        Ok(())
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

/// The solids the faults add to the scene, in the workpiece frame.
pub fn fault_solids(spec: &SceneSpec) -> Vec<ConvexSolid> {
    let mut solids = Vec::new();
    for fault in &spec.faults {
        match *fault {
            Fault::Clamp { centre_mm, width_mm, height_mm, half_reach_mm } => {
                let top = spec.joint.top_z(-1.0).max(spec.joint.top_z(1.0));
                solids.extend(ConvexSolid::cuboid(
                    SurfaceKind::Clutter,
                    Vec3::new(-half_reach_mm, centre_mm - width_mm / 2.0, top),
                    Vec3::new(half_reach_mm, centre_mm + width_mm / 2.0, top + height_mm),
                ));
            }
            Fault::TackWelds { first_mm, pitch_mm, length_mm, crown_mm, spread_mm } => {
                let profile = tack_profile(&spec.joint, crown_mm, spread_mm);
                let [y0, y1] = spec.seam_range();
                let mut centre = first_mm;
                while centre - length_mm / 2.0 < y1 {
                    let span = [(centre - length_mm / 2.0).max(y0), (centre + length_mm / 2.0).min(y1)];
                    solids.extend(ConvexSolid::extruded(SurfaceKind::Weld, &profile, span));
                    centre += pitch_mm;
                }
            }
            Fault::Spatter { seed, count, radius_mm, spread_mm } => {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(FaultKind::Spatter as u64);
                let [y0, y1] = spec.seam_range();
                let nearest = spec.joint.seam_edge_half_width() + radius_mm;
                for _ in 0..count {
                    let side = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
                    let x = side * uniform(&mut rng, nearest, spread_mm);
                    let y = uniform(&mut rng, y0, y1);
                    let z = spec.joint.top_z(x);
                    let octagon: Vec<[f64; 2]> = (0..BEAD_CORNERS)
                        .map(|k| {
                            let a = std::f64::consts::TAU * k as f64 / BEAD_CORNERS as f64;
                            [x + radius_mm * a.cos(), z + radius_mm * a.sin()]
                        })
                        .collect();
                    solids.extend(ConvexSolid::extruded(SurfaceKind::Weld, &octagon, [y - radius_mm, y + radius_mm]));
                }
            }
            Fault::TouchingPart { plate, width_mm, step_mm } => {
                let [top, bottom] = plate_top_and_bottom(&spec.joint, plate);
                let (extent, x0, x1) = match plate {
                    PlateSide::A => (&spec.plate_a, -spec.plate_a.width_mm - width_mm, -spec.plate_a.width_mm),
                    PlateSide::B => (&spec.plate_b, spec.plate_b.width_mm, spec.plate_b.width_mm + width_mm),
                };
                solids.extend(ConvexSolid::cuboid(
                    SurfaceKind::Plate,
                    Vec3::new(x0, extent.offset_mm, bottom),
                    Vec3::new(x1, extent.offset_mm + extent.length_mm, top + step_mm),
                ));
            }
            Fault::WrongJoint { .. }
            | Fault::SeamDropout { .. }
            | Fault::SpecularStreaks { .. }
            | Fault::BarelyInView { .. } => {}
        }
    }
    solids
}

/// A tack's cross-section (convex, in xz): it fills the gap or the groove
/// from its root up and crowns above the top, `spread` wider than the
/// opening either side; for a lap, a fillet in the corner.
fn tack_profile(joint: &JointGeometry, crown: f64, spread: f64) -> Vec<[f64; 2]> {
    let crowned = |bottom: [[f64; 2]; 2], top_z: f64, half_top: f64| {
        vec![
            bottom[0],
            bottom[1],
            [half_top, top_z],
            [0.5 * half_top, top_z + crown],
            [-0.5 * half_top, top_z + crown],
            [-half_top, top_z],
        ]
    };
    match *joint {
        JointGeometry::IButt { thickness_mm: t, gap_mm } => {
            let h = gap_mm / 2.0;
            crowned([[-h, 0.0], [h, 0.0]], t, h + spread)
        }
        JointGeometry::VButt { thickness_mm: t, groove_depth_mm: d, root_gap_mm: r, .. } => {
            let top = joint.seam_edge_half_width() + spread;
            crowned([[-r / 2.0, t - d], [r / 2.0, t - d]], t, top)
        }
        JointGeometry::Lap { lower_thickness_mm: t1, upper_thickness_mm: t2, .. } => {
            let leg = spread + crown;
            vec![[-0.5, t1], [leg, t1], [-0.5, t1 + leg.min(t2)]]
        }
        // A tack in the -x root's corner (faults are not drawn on tees yet:
        // [`Fault::validate`] refuses them; this keeps the profile total).
        JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h } => {
            let (leg, root) = (spread + crown, -w / 2.0);
            vec![[root + 0.5, f], [root - leg, f], [root + 0.5, f + leg.min(h)]]
        }
        // A tack on the corner's weld line (refused on corners likewise).
        JointGeometry::Corner { flange_thickness_mm: f, .. } => {
            let leg = spread + crown;
            vec![[-0.5, f], [leg, f], [-0.5, f + leg]]
        }
    }
}

/// Removes the returns of the dropout bands from noise-free depths
/// (row-major, camera frame); nothing changes without such a fault.
pub fn erase_dropout_bands(depths: &mut [f64], spec: &SceneSpec, camera: &CameraModel) {
    let bands: Vec<([f64; 2], f64)> = spec
        .faults
        .iter()
        .filter_map(|f| match *f {
            Fault::SeamDropout { along_mm, margin_mm } => {
                Some((along_mm, spec.joint.seam_edge_half_width() + margin_mm))
            }
            _ => None,
        })
        .collect();
    if bands.is_empty() {
        return;
    }
    let workpiece_from_camera = spec.workpiece_from_camera();
    let width = (camera.width_px as usize).max(1);
    depths.par_chunks_mut(width).enumerate().for_each(|(row, out)| {
        for (col, z) in out.iter_mut().enumerate() {
            if !z.is_finite() {
                continue;
            }
            let [rx, ry, _] = camera.ray(col as f64, row as f64);
            let w = workpiece_from_camera.transform_point(&Vec3::new(rx * *z, ry * *z, *z).into()).coords;
            if bands.iter().any(|([a, b], half)| (*a..=*b).contains(&w.y) && w.x.abs() <= *half) {
                *z = f64::NAN;
            }
        }
    });
}

/// Draws the specular streaks into a frame's depths (after the sensor's
/// noise: a streak is the sensor's error, not a surface).
pub fn draw_streaks(depths: &mut [f64], spec: &SceneSpec, camera: &CameraModel) {
    let camera_from_workpiece = spec.workpiece_from_camera().inverse();
    let (width, height) = (camera.width_px as usize, camera.height_px as usize);
    for fault in &spec.faults {
        let Fault::SpecularStreaks { seed, count, length_mm, width_px, offset_mm } = *fault else {
            continue;
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(FaultKind::SpecularStreaks as u64);
        let [y0, y1] = spec.seam_range();
        for _ in 0..count {
            let x = uniform(&mut rng, -20.0, 20.0);
            let y = uniform(&mut rng, y0, y1);
            let angle = uniform(&mut rng, 0.0, std::f64::consts::PI);
            let sign = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
            let half = Vec3::new(angle.cos(), angle.sin(), 0.0) * (length_mm / 2.0);
            let centre = Vec3::new(x, y, spec.joint.top_z(x));
            let ends = [centre - half, centre + half]
                .map(|p| camera.project(&camera_from_workpiece.transform_point(&p.into()).coords));
            let [Some(a), Some(b)] = ends else { continue };
            let reach = width_px / 2.0;
            let (u_lo, u_hi) = (a.0.min(b.0) - reach, a.0.max(b.0) + reach);
            let (v_lo, v_hi) = (a.1.min(b.1) - reach, a.1.max(b.1) + reach);
            let clamp_px = |v: f64, n: usize| v.clamp(0.0, n.saturating_sub(1) as f64) as usize;
            for row in clamp_px(v_lo.floor(), height)..=clamp_px(v_hi.ceil(), height) {
                for col in clamp_px(u_lo.floor(), width)..=clamp_px(u_hi.ceil(), width) {
                    let z = &mut depths[row * width + col];
                    if z.is_finite() && distance_to_segment_px((col as f64, row as f64), a, b) <= reach {
                        let off = sign * offset_mm * (1.0 + 0.5 * uniform(&mut rng, -1.0, 1.0));
                        *z = (*z + off).max(f64::MIN_POSITIVE);
                    }
                }
            }
        }
    }
}

fn distance_to_segment_px(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let length2 = dx * dx + dy * dy;
    let t = if length2 > 0.0 { (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / length2).clamp(0.0, 1.0) } else { 0.0 };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

/// Sets the camera's aim across the seam so that only `in_view_mm` of the
/// plate a [`Fault::BarelyInView`] names is in view (at the middle of the
/// observed seam); no change without that fault.
pub fn frame_barely_in_view(spec: &mut SceneSpec, camera: &CameraModel) -> Result<(), InvalidScene> {
    let Some((plate, wanted)) = spec.faults.iter().find_map(|f| match *f {
        Fault::BarelyInView { plate, in_view_mm } => Some((plate, in_view_mm)),
        _ => None,
    }) else {
        return Ok(());
    };
    let index = match plate {
        PlateSide::A => 0,
        PlateSide::B => 1,
    };
    let shown = |spec: &SceneSpec, across: f64| -> Option<f64> {
        let mut moved = spec.clone();
        moved.placement.target_offset_mm[0] = across;
        let [y0, y1] = observed_seam_range(&moved, camera)?;
        Some(plates_in_view(&moved, camera, (y0 + y1) / 2.0)[index])
    };
    // Aiming away from the plate shows less of it: walk away until
    // less than wanted shows, then halve the step.
    let away = if index == 0 { 1.0 } else { -1.0 };
    let start = spec.placement.target_offset_mm[0];
    let mut near = start - away * 300.0;
    let mut far = None;
    let mut across = near;
    while (across - start).abs() <= 300.0 {
        match shown(spec, across) {
            Some(w) if w < wanted => {
                far = Some(across);
                break;
            }
            Some(_) => near = across,
            None => {}
        }
        across += away * 2.0;
    }
    let Some(mut far) = far else {
        return Err(InvalidScene(format!("no aim shows only {wanted} mm of plate {plate:?}")));
    };
    for _ in 0..40 {
        let middle = (near + far) / 2.0;
        match shown(spec, middle) {
            Some(w) if w >= wanted => near = middle,
            _ => far = middle,
        }
    }
    spec.placement.target_offset_mm[0] = near;
    Ok(())
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
    let hides = kinds.iter().any(|k| matches!(k, FaultKind::SeamDropout | FaultKind::Clamp | FaultKind::TackWelds));
    RightAnswer {
        refuse,
        whole_seam: !refuse,
        pieces_mm: if hides && !refuse { visible_pieces(spec, camera) } else { Vec::new() },
    }
}

/// The stretches of the observed seam that no fault hides: no dropout
/// band over them, and neither seam edge behind or inside a fault's solid
/// as the camera and the projector see it. At least [`MIN_PIECE_MM`] long.
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
    let sight = LineOfSight::new(solids, camera);
    let hidden =
        |y: f64| {
            bands.iter().any(|[a, b]| (*a..=*b).contains(&y))
                || spec.joint.seam_edges_xz().iter().any(|[x, z]| {
                    sight.hides(&camera_from_workpiece.transform_point(&Vec3::new(*x, y, *z).into()).coords)
                })
        };
    unhidden_stretches([y0, y1], hidden, MIN_PIECE_MM)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;
    use crate::sim::{CameraPlacement, NoiseSpec, demo_scene, simulate};

    fn small_camera() -> CameraModel {
        CameraModel { width_px: 480, height_px: 300, ..CameraModel::default() }
    }

    /// A noise-free demo scene of `joint` seen from 600 mm at 15 degrees.
    fn clean(joint: JointType) -> SceneSpec {
        let mut spec = demo_scene(joint);
        spec.noise = NoiseSpec::none();
        spec.placement = CameraPlacement { tilt_azimuth_deg: 40.0, ..CameraPlacement::straight(600.0, 15.0) };
        spec
    }

    /// The pixels a fault changes: `(clean point, faulted point)` in the
    /// workpiece frame, either absent where that frame has no return.
    fn changes(spec: &SceneSpec, fault: Fault) -> Vec<(Option<Vec3>, Option<Vec3>)> {
        let camera = small_camera();
        let mut faulted = spec.clone();
        faulted.faults.push(fault);
        assert_eq!(faulted.validate(), Ok(()));
        let workpiece_from_camera = spec.workpiece_from_camera();
        let to_workpiece = |p: &crate::cloud::Point| {
            p[0].is_finite().then(|| workpiece_from_camera.transform_point(&vec3(p).into()).coords)
        };
        let (a, b) = (simulate(spec, &camera), simulate(&faulted, &camera));
        a.cloud
            .points()
            .iter()
            .zip(b.cloud.points())
            .filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits))
            .map(|(p, q)| (to_workpiece(p), to_workpiece(q)))
            .collect()
    }

    #[test]
    fn a_dropout_band_removes_the_returns_over_the_seam_and_nothing_else() {
        for joint in JointType::ALL {
            let spec = clean(joint);
            let half = spec.joint.seam_edge_half_width() + 2.0;
            let changed = changes(&spec, Fault::SeamDropout { along_mm: [100.0, 140.0], margin_mm: 2.0 });
            assert!(changed.len() > 20, "{joint}: {} pixels", changed.len());
            for (before, after) in changed {
                let p = before.expect("a band only removes returns");
                assert!(after.is_none(), "{joint}: a return kept");
                assert!((100.0..=140.0).contains(&p.y) && p.x.abs() <= half + 1e-6, "{joint}: {p:?}");
            }
        }
    }

    #[test]
    fn a_clamp_covers_the_seam_where_it_lies_and_shadows_beside_it() {
        for joint in JointType::ALL {
            let spec = clean(joint);
            let top = spec.joint.top_z(-1.0).max(spec.joint.top_z(1.0));
            let clamp = Fault::Clamp { centre_mm: 120.0, width_mm: 30.0, height_mm: 20.0, half_reach_mm: 60.0 };
            let changed = changes(&spec, clamp.clone());
            let on_clamp = changed.iter().filter(|(_, q)| q.is_some_and(|q| (q.z - top - 20.0).abs() < 1e-3)).count();
            assert!(on_clamp > 100, "{joint}: {on_clamp} returns on the clamp's top");
            // Hidden behind it or in its shadow: within a few heights of it.
            for (before, after) in &changed {
                let p = before.or(*after).unwrap();
                assert!((p.y - 120.0).abs() <= 15.0 + 3.0 * 20.0 && p.x.abs() <= 60.0 + 3.0 * 20.0, "{joint}: {p:?}");
            }
            let mut faulted = spec.clone();
            faulted.faults.push(clamp);
            let pieces = visible_pieces(&faulted, &small_camera());
            assert_eq!(pieces.len(), 2, "{joint}: {pieces:?}");
            assert!(pieces[0][1] <= 105.0 && pieces[1][0] >= 135.0, "{joint}: {pieces:?}");
            assert!(pieces[0][0] < 1.0 && pieces[1][1] > 239.0, "{joint}: {pieces:?}");
        }
    }

    #[test]
    fn tack_welds_fill_the_seam_at_their_pitch() {
        for joint in JointType::ALL {
            let spec = clean(joint);
            let tacks =
                Fault::TackWelds { first_mm: 30.0, pitch_mm: 60.0, length_mm: 8.0, crown_mm: 1.5, spread_mm: 2.0 };
            let reach = spec.joint.seam_edge_half_width() + 2.0 + 1.5 + 1.0;
            let changed = changes(&spec, tacks.clone());
            assert!(changed.len() > 20, "{joint}: {} pixels", changed.len());
            for (before, after) in &changed {
                let p = after.or(*before).unwrap();
                let to_tack = ((p.y - 30.0).rem_euclid(60.0)).min(60.0 - (p.y - 30.0).rem_euclid(60.0));
                // The tack itself, or its shadow a few mm beside it.
                assert!(to_tack <= 4.0 + 6.0 && p.x.abs() <= reach + 6.0, "{joint}: {p:?}");
            }
            let mut faulted = spec.clone();
            faulted.faults.push(tacks);
            let pieces = visible_pieces(&faulted, &small_camera());
            // Tacks at 30, 90, 150 and 210 mm of a 240 mm seam.
            assert_eq!(pieces.len(), 5, "{joint}: {pieces:?}");
        }
    }

    #[test]
    fn spatter_lands_beside_the_seam() {
        let spec = clean(JointType::VButt);
        let spread = spec.joint.seam_edge_half_width() + 15.0;
        let changed = changes(&spec, Fault::Spatter { seed: 3, count: 40, radius_mm: 2.0, spread_mm: spread });
        assert!(changed.len() > 40, "{} pixels", changed.len());
        for (before, after) in changed {
            let p = after.or(before).unwrap();
            assert!(p.x.abs() <= spread + 2.0 + 8.0, "{p:?}");
        }
    }

    #[test]
    fn streaks_move_depths_along_lines_by_their_offset() {
        let spec = clean(JointType::Lap);
        let streaks = Fault::SpecularStreaks { seed: 5, count: 2, length_mm: 60.0, width_px: 2.0, offset_mm: 10.0 };
        let camera = small_camera();
        let mut faulted = spec.clone();
        faulted.faults.push(streaks);
        let (a, b) = (simulate(&spec, &camera), simulate(&faulted, &camera));
        let moved: Vec<f32> = a
            .cloud
            .points()
            .iter()
            .zip(b.cloud.points())
            .filter(|(p, q)| p[2].to_bits() != q[2].to_bits())
            .map(|(p, q)| (q[2] - p[2]).abs())
            .collect();
        // Two streaks about 60 mm (some 40 px here) long and 2 px wide.
        assert!((60..=400).contains(&moved.len()), "{} pixels", moved.len());
        assert!(moved.iter().all(|d| (4.9..=15.1).contains(d)), "{moved:?}");
    }

    #[test]
    fn a_touching_part_abuts_the_plates_outer_edge() {
        let spec = clean(JointType::IButt);
        let width_b = spec.plate_b.width_mm;
        let changed = changes(&spec, Fault::TouchingPart { plate: PlateSide::B, width_mm: 60.0, step_mm: 2.0 });
        assert!(changed.len() > 500, "{} pixels", changed.len());
        for (before, after) in changed {
            let p = after.or(before).unwrap();
            assert!(p.x >= width_b - 10.0 && p.x <= width_b + 60.0 + 1e-6, "{p:?}");
        }
    }

    #[test]
    fn a_plate_barely_in_view_shows_the_sliver_asked_for() {
        let camera = CameraModel::default();
        for (joint, plate) in [(JointType::VButt, PlateSide::A), (JointType::Lap, PlateSide::B)] {
            let mut spec = demo_scene(joint);
            spec.faults.push(Fault::BarelyInView { plate, in_view_mm: 10.0 });
            frame_barely_in_view(&mut spec, &camera).unwrap();
            assert_eq!(spec.validate(), Ok(()));
            let f = crate::sim::framing(&spec, &camera);
            let index = usize::from(plate == PlateSide::B);
            assert!((f.plate_in_view_mm[index] - 10.0).abs() < 0.5, "{joint}: {f:?}");
            assert!(f.plate_in_view_mm[1 - index] > 40.0 && f.observed_seam_mm > 80.0, "{joint}: {f:?}");
        }
    }

    #[test]
    fn a_wrong_joint_changes_the_request_not_the_frame() {
        let spec = clean(JointType::IButt);
        assert!(changes(&spec, Fault::WrongJoint { requested: JointType::VButt }).is_empty());
        let mut wrong = spec.clone();
        wrong.faults.push(Fault::WrongJoint { requested: JointType::VButt });
        assert_eq!((wrong.requested_joint(), wrong.requested_groove_depth_mm()), (JointType::VButt, Some(3.0)));
        let answer = right_answer(&wrong, &small_camera());
        assert!(answer.refuse && !answer.whole_seam && answer.pieces_mm.is_empty());
        wrong.faults = vec![Fault::WrongJoint { requested: JointType::IButt }];
        assert!(wrong.validate().unwrap_err().to_string().contains("another joint"));
    }

    #[test]
    fn faults_are_validated_with_the_reason() {
        let mut spec = clean(JointType::VButt);
        spec.faults = vec![Fault::Clamp { centre_mm: 100.0, width_mm: 20.0, height_mm: 10.0, half_reach_mm: 2.0 }];
        assert!(spec.validate().unwrap_err().to_string().contains("clamp: the clamp must reach"));
        spec.faults = vec![Fault::SeamDropout { along_mm: [400.0, 450.0], margin_mm: 1.0 }];
        assert!(spec.validate().unwrap_err().to_string().contains("overlapping the seam"));
        spec.faults = vec![Fault::BarelyInView { plate: PlateSide::A, in_view_mm: 60.0 }];
        assert!(spec.validate().unwrap_err().to_string().contains("less than 40 mm"));
        assert_eq!("tack_welds".parse::<FaultKind>(), Ok(FaultKind::TackWelds));
        assert!("rust".parse::<FaultKind>().is_err());
        for kind in FaultKind::ALL {
            let mut spec = clean(JointType::Lap);
            spec.faults.push(Fault::example(kind, &spec));
            frame_barely_in_view(&mut spec, &CameraModel::default()).unwrap();
            assert_eq!(spec.validate(), Ok(()), "{kind}");
            assert_eq!(spec.fault_kind(), Some(kind));
        }
    }
}
