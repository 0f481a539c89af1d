//! The web's frame: the flange's plane fitted to its pieces and how far
//! its points scatter about it, the web's long axis laid in it and the
//! direction across, where the web's middle and its top's edges lie
//! across it, how high the top stands, and which sides of the web the
//! flange is seen on. Read from the web's top, or, with the top out of
//! view, from the one side face seen standing on the flange.

use crate::cloud::PointCloud;
use crate::geometry::fit::{Moments, Plane};
use crate::geometry::{MAD_PER_SIGMA, Vec3, vec3};

use super::super::background::PlaneCluster;
use super::super::web_face::StandingFace;
use super::{MIN_FACE_POINTS, Side, TeeView, Web};

/// How far beyond the web top's trimmed edge a face point may lie, in
/// point spacings on top of the trimmed rim: depth noise and the face seen
/// at a grazing angle spread its points a little across.
pub(super) const FACE_REACH_SPACINGS: f64 = 6.0;

/// The margins, in point spacings (and at least the on-plane tolerance),
/// that keep the flange's and the web top's own points (and their noise)
/// out of the face, and the face's foot out of the flange beside it. No
/// wider: where an image border or a dropout crosses the root obliquely,
/// the evidence a margin off the root stops that much times the slant
/// before or after the root does (two spacings cost 1 to 2 mm at the ends
/// of 1 mm voxel clouds).
const HEIGHT_MARGIN_SPACINGS: f64 = 1.0;

/// How many of a flange piece's points are read to fit the flange's
/// plane and to tell which sides of the web it lies on.
const FLANGE_SAMPLES: usize = 20_000;

/// A point is on the flange within this many of the flange's own scatter
/// about its plane ([`WebFrame::flange_scatter_mm`]), when that is wider
/// than the configured on-plane tolerance: all but about one in a hundred
/// of a normally spread flange's points. A camera noisier than the one
/// the tolerance was set for, or a flange a millimetre off flat over its
/// length (a real plate, a block's top), otherwise loses the flange's
/// points beside a root wherever they stray past the tolerance, and the
/// root's evidence breaks there.
pub(super) const FLANGE_SCATTER_SIGMAS: f64 = 2.5;

/// The web's frame: where its top is and how the flange lies.
#[derive(Debug, Clone, Copy)]
pub(super) struct WebFrame {
    /// Into the workpiece.
    pub(super) n: Vec3,
    /// Along the web.
    pub(super) e: Vec3,
    /// Across the web.
    pub(super) u: Vec3,
    pub(super) origin: Vec3,
    /// The flange plane's offset along `n`.
    pub(super) flange_offset: f64,
    /// The web's middle and half its top's width across, mm from `origin`.
    pub(super) middle: f64,
    pub(super) half_width: f64,
    pub(super) height: f64,
    /// Whether the flange lies on the web's −u and +u sides.
    pub(super) flange_sides: [bool; 2],
    /// The side (`sign`) of the one face seen, when the web's top is not:
    /// `middle` and `half_width` then place that face, not the top.
    pub(super) face_only: Option<f64>,
    /// The flange's points' scatter about its plane, mm: the median
    /// distance over [`MAD_PER_SIGMA`], a sigma no stray point widens.
    pub(super) flange_scatter_mm: f64,
}

impl WebFrame {
    /// Whether the flange lies on the web's side `sign`.
    pub(super) fn flange_on(&self, sign: f64) -> bool {
        self.flange_sides[usize::from(sign > 0.0)]
    }

    pub(super) fn height_of(&self, p: &Vec3) -> f64 {
        self.flange_offset - self.n.dot(p)
    }

    /// How near its plane a point lies on the flange, mm: the on-plane
    /// tolerance, or [`FLANGE_SCATTER_SIGMAS`] of the flange's own scatter
    /// where that is wider.
    pub(super) fn on_flange_mm(&self, on_plane_mm: f64) -> f64 {
        on_plane_mm.max(FLANGE_SCATTER_SIGMAS * self.flange_scatter_mm)
    }

    pub(super) fn across(&self, p: &Vec3) -> f64 {
        (p - self.origin).dot(&self.u)
    }

    /// Where a face point on side `sign` may lie, outward of the web's
    /// middle, mm, and up to which height over the flange: from the web's
    /// middle to a little beyond the top's trimmed edge, below the top's
    /// own points (for a member with every side a root, from a little
    /// inside that edge); or round the one face seen, up to where it is
    /// seen.
    pub(super) fn face_band(&self, view: &TeeView, sign: f64, margin: f64) -> ((f64, f64), f64) {
        let spacing = view.point_spacing_mm;
        match self.face_only {
            Some(seen) if seen == sign => {
                let reach = FACE_REACH_SPACINGS * spacing;
                ((self.half_width - reach, self.half_width + reach), self.height)
            }
            // A member with every side a root: its ends' faces stand across
            // it, inside its top's edges, so only a band round the edge
            // is this side's face.
            _ if view.every_side => {
                let reach = FACE_REACH_SPACINGS * spacing;
                ((self.half_width - reach, self.half_width + view.rim_mm + reach), self.height - margin)
            }
            _ => ((0.0, self.half_width + view.rim_mm + FACE_REACH_SPACINGS * spacing), self.height - margin),
        }
    }
}

/// The flange's plane from all its pieces (one plate on both sides of the
/// web), fitted to a sample of their points ([`flange_samples`]), and
/// those points.
pub(in crate::pipeline) fn flange_plane(cloud: &PointCloud, pieces: &[&PlaneCluster]) -> Option<(Plane, Vec<Vec3>)> {
    let flange_points = flange_samples(cloud, pieces);
    let flange = flange_points.iter().collect::<Moments>().plane()?;
    Some((flange, flange_points))
}

/// A sample of the flange pieces' points, at most about [`FLANGE_SAMPLES`]
/// of each piece.
fn flange_samples(cloud: &PointCloud, pieces: &[&PlaneCluster]) -> Vec<Vec3> {
    let points = cloud.points();
    pieces
        .iter()
        .flat_map(|c| {
            let stride = (c.members.len() / FLANGE_SAMPLES).max(1);
            c.members.iter().step_by(stride).map(|&i| vec3(&points[i as usize]))
        })
        .collect()
}

/// The scatter of `heights` about nil, mm: their median magnitude over
/// [`MAD_PER_SIGMA`] (0 without any).
fn scatter_mm(heights: impl Iterator<Item = f64>) -> f64 {
    let mut magnitudes: Vec<f64> = heights.map(f64::abs).filter(|h| h.is_finite()).collect();
    if magnitudes.is_empty() {
        return 0.0;
    }
    let mid = magnitudes.len() / 2;
    *magnitudes.select_nth_unstable_by(mid, f64::total_cmp).1 / MAD_PER_SIGMA
}

/// The margin, mm, that keeps a plane's own points (and their noise) out
/// of a face standing on it: [`HEIGHT_MARGIN_SPACINGS`] spacings, and at
/// least the on-plane tolerance.
pub(in crate::pipeline) fn height_margin(on_plane_mm: f64, spacing: f64) -> f64 {
    on_plane_mm.max(HEIGHT_MARGIN_SPACINGS * spacing)
}

/// The cloud's valid points, read as they are needed: a frame of millions
/// of points is not copied.
pub(in crate::pipeline) fn valid_points(cloud: &PointCloud) -> impl Iterator<Item = Vec3> + '_ {
    cloud.points().iter().filter(|p| p.iter().all(|c| c.is_finite())).map(vec3)
}

/// The web's frame from the flange pieces and its top, or its one face
/// seen; `turned`, a member standing with every side a root
/// ([`TeeView::every_side`]), along its top's other side (its ends'
/// roots).
pub(super) fn web_frame(view: &TeeView, turned: bool) -> Option<WebFrame> {
    let flange_points = flange_samples(view.cloud, view.flange_pieces);
    let frame = match view.web {
        Web::Top(top) => {
            let flange = flange_points.iter().collect::<Moments>().plane()?;
            let frame = frame_from_top(view.cloud, top, &flange, view.every_side)?;
            if turned { frame_along(view.cloud, top, &frame, &frame.u)? } else { frame }
        }
        // The face search fitted the flange's plane to these same pieces.
        Web::Face(_) if turned => return None,
        Web::Face(face) => frame_from_face(face, &face.flange)?,
    };
    // Which sides of the web the flange lies on, from its points, not its
    // pieces' centroids: a web shorter than its flange has one flange
    // piece round its end, seen on both sides, its centroid on one.
    let rim = if frame.face_only.is_some() { 0.0 } else { view.rim_mm };
    let flange_on = |sign: f64| {
        let beyond_rim = |p: &&Vec3| sign * (frame.across(p) - frame.middle) > frame.half_width + rim;
        flange_points.iter().filter(beyond_rim).take(MIN_FACE_POINTS).count() >= MIN_FACE_POINTS
    };
    let flange_sides = [flange_on(-1.0), flange_on(1.0)];
    let flange_scatter_mm = scatter_mm(flange_points.iter().map(|p| frame.height_of(p)));
    (frame.height > 0.0).then_some(WebFrame { flange_sides, flange_scatter_mm, ..frame })
}

/// The web's frame from its top: along its long axis (or, for a member
/// with every side a root, `outlined`, along the sides of the rectangle
/// its top fills best, [`outline_axis`]), its middle and half width from
/// its points' spread across it.
fn frame_from_top(cloud: &PointCloud, top: &PlaneCluster, flange: &Plane, outlined: bool) -> Option<WebFrame> {
    let n = flange.normal;
    let axis = if outlined { outline_axis(cloud, top, &n)? } else { top.long_axis };
    let e = (axis - n * axis.dot(&n)).try_normalize(1e-9)?;
    let u = n.cross(&e);
    let origin = top.centroid;
    let (lo, hi) = top_edges_across(cloud, top, &origin, &u)?;
    Some(WebFrame {
        n,
        e,
        u,
        origin,
        flange_offset: flange.offset,
        middle: 0.5 * (lo + hi),
        half_width: 0.5 * (hi - lo),
        height: flange.offset - n.dot(&origin),
        flange_sides: [false; 2],
        face_only: None,
        flange_scatter_mm: 0.0,
    })
}

/// The web's frame from its one face seen: along the line where the face
/// meets the flange, the origin on the face (so `middle` and `half_width`
/// are nil), the face's side the sign of `u` along its normal out of the
/// web; the web's height the height the face is seen to.
fn frame_from_face(face: &StandingFace, flange: &Plane) -> Option<WebFrame> {
    let n = flange.normal;
    let e = n.cross(&face.plane.normal).try_normalize(1e-6)?;
    let u = n.cross(&e);
    let sign = if u.dot(&face.plane.normal) >= 0.0 { 1.0 } else { -1.0 };
    Some(WebFrame {
        n,
        e,
        u,
        origin: face.centroid,
        flange_offset: flange.offset,
        middle: 0.0,
        half_width: 0.0,
        height: face.seen_height_mm,
        flange_sides: [false; 2],
        face_only: Some(sign),
        flange_scatter_mm: 0.0,
    })
}

/// How many of a top's points [`outline_axis`] reads, at most.
const OUTLINE_SAMPLES: usize = 4_000;

/// The direction, in the plane across `n`, of one side of the rectangle
/// round `top`'s points that covers the least area
/// ([`crate::geometry::outline_axis`]): a block's top is square or nearly
/// so, and the spread of its points (its long axis) says nothing of where
/// its sides run, while its outline does.
fn outline_axis(cloud: &PointCloud, top: &PlaneCluster, n: &Vec3) -> Option<Vec3> {
    let points = cloud.points();
    let stride = (top.members.len() / OUTLINE_SAMPLES).max(1);
    let sample: Vec<Vec3> = top.members.iter().step_by(stride).map(|&i| vec3(&points[i as usize])).collect();
    crate::geometry::outline_axis(&sample, n)
}

/// Which side of the web `sign` is, as the camera (at the frame's origin)
/// sees it.
pub(super) fn side_seen(frame: &WebFrame, sign: f64) -> Side {
    let camera_across = sign * (frame.across(&Vec3::zeros()) - frame.middle);
    if camera_across > frame.half_width {
        Side::Near
    } else if camera_across < -frame.half_width {
        Side::Far
    } else {
        Side::Above
    }
}

/// `frame` with the web's axis along `e` (laid in the flange's plane), the
/// middle and half-width of the web's `top` read across it.
pub(super) fn frame_along(cloud: &PointCloud, top: &PlaneCluster, frame: &WebFrame, e: &Vec3) -> Option<WebFrame> {
    let n = frame.n;
    let e = (e - n * e.dot(&n)).try_normalize(1e-9)?;
    let e = if e.dot(&frame.e) >= 0.0 { e } else { -e };
    let u = n.cross(&e);
    let (lo, hi) = top_edges_across(cloud, top, &frame.origin, &u)?;
    Some(WebFrame { e, u, middle: 0.5 * (lo + hi), half_width: 0.5 * (hi - lo), ..*frame })
}

/// Where the web's `top` ends on either side across `u`, mm from
/// `origin`: a hundredth of its points in from either side, so a stray
/// point does not widen it.
fn top_edges_across(cloud: &PointCloud, top: &PlaneCluster, origin: &Vec3, u: &Vec3) -> Option<(f64, f64)> {
    let points = cloud.points();
    let mut across: Vec<f64> = top.members.iter().map(|&i| (vec3(&points[i as usize]) - origin).dot(u)).collect();
    if across.len() < 2 {
        return None;
    }
    across.sort_by(f64::total_cmp);
    let k = across.len() / 100;
    Some((across[k], across[across.len() - 1 - k]))
}
