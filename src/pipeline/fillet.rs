//! The fillet roots of a tee joint (issue 15): where each side face of the
//! web meets the flange's top. The paper plans butt and lap joints only and
//! has no fillet; this stage is ours, built from the planes the robust
//! method already found (the web's top and the flange pieces either side
//! of it, [`super::background`]), or, where the web's top is out of view,
//! from the one side face [`super::web_face`] finds standing on the
//! flange ([`Web::Face`]: that face's root is the only one read).
//!
//! The geometry, in the camera frame, with `n` the flange's unit normal
//! into the workpiece (away from the camera), `e` the web top's long axis
//! laid in the flange's plane and `u = n × e` across the web:
//!
//! - height above the flange `h(p) = d_f − n·p`, for the flange plane
//!   `n·p = d_f`; the web's top lies at `h = H`, the web's height;
//! - a side face of the web: the points between the flange and the web's
//!   top (`h_lo ≤ h ≤ H − h_margin`, both margins a few point spacings)
//!   on that side of the web's middle and at most a trimmed rim and a few
//!   spacings beyond the top's edge. The plane criterion drops these
//!   points (their normals lie ~90° from the plates'), so they are read
//!   from the cloud itself, fitted by least squares (the scatter's least
//!   principal axis) and refitted without the points further than
//!   `trim_sigma` residuals from it; the residual is reported;
//! - the root: the line where the face `m·p = d_m` meets the flange,
//!   direction `r = n × m`, through the point of both planes nearest the
//!   web top's centroid (a 2 × 2 solve in the span of `n` and `m`);
//! - the stretch planned: stations a few spacings long along the root,
//!   each seen when it holds both a point of the face's foot (the face's
//!   lowest band at that station: a face turned nearly edge-on is seen
//!   only above a line slanting along it) and a flange point a few
//!   spacings outward of the root (beyond the margin that keeps the face's
//!   own foot out: where the web overhangs the flange's end, its foot lies
//!   at the flange's height with no flange beside it). The longest run of
//!   seen stations (across breaks no longer than
//!   [`super::boundary::JOINT_BREAK_SPACINGS`]) is the root planned, from
//!   the last evidence inward at each end, except where both kinds of
//!   evidence run up to the image's border ([`super::view_border`]): the
//!   root then ends where the border crosses the root itself, at most a
//!   station from the evidence's end (the evidence lies a spacing or more
//!   off the root, and a border crossing it obliquely cuts it before or
//!   after the root). Where the border cuts a foot seen well up the face,
//!   the root runs on along the flange seen up to it, to where the root
//!   leaves the view;
//! - the joint beyond the stretch: where the web's top and the flange up to
//!   the root go on past an end, the face is not seen there, and the root
//!   would stop short. That length is reported, for the coverage gate
//!   (`quality.max_joint_beyond_seam_mm`), and the flange's edge is read
//!   instead where it shows a longer root;
//! - the web-to-flange angle: between the face's upward direction and the
//!   flange's outward one, both across the root (90° for a square tee);
//! - the torch ([`super::trajectory::fillet_torch_axis`]) leans from the
//!   flange towards the web in the plane across the root.
//!
//! - a face turned edge-on to the camera returns no points (or only the mixed
//!   returns along the rays) although its root is in plain view: the flange is
//!   then seen right up to the root. The root is read from the flange's edge
//!   against the web instead: at each station the innermost flange point and
//!   the outermost point of the web's top, a line fitted to each, the root on
//!   the first. The flange's edge is read too where the points standing on that
//!   side are the web's end face (their foot runs across the web, not along
//!   it), where the face gives no root (its foot and the flange up to it seen
//!   together nowhere), and where the face is seen along less than half the
//!   web's top and the edge shows a longer root. A flange also ends at the edge
//!   of the web's shadow, from the camera or from the projector; the face the
//!   two edges imply then holds the ray that grazes the top's edge, so it is
//!   turned towards the shadowing eye by nothing. The root is taken only when
//!   that face is turned towards both the camera and the projector by more than
//!   the angle the two edges' sampling could fake (a few spacings over the
//!   web's height), and is otherwise refused saying so;
//!
//! One view sees at most one root: the web's faces are steep, so the web
//! hides the face on its far side and the flange beside it from the
//! camera or the projector. A root whose face is not seen, or whose flange
//! up to the root is not, is not invented: it is returned as not seen,
//! saying which and why.
//!
//! The root's position uncertainty (one sigma) is the face fit's
//! prediction error at the root's ends: `rms · √(1/N + h̄²/var h + (t −
//! t̄)²/var t)` for a face fitted over N points at mean height h̄ and
//! along-root spread var t, the root lying at h = 0, with the floor of
//! [`super::quality`] (a spacing over √12) for the sampling.

use std::collections::{HashMap, HashSet};

use crate::cloud::PointCloud;
use crate::geometry::fit::{Moments, Plane};
use crate::geometry::{Vec3, extent, vec3};

use super::background::PlaneCluster;
use super::boundary::JOINT_BREAK_SPACINGS;
use super::refit::{SeamAxes, SeamCurve};
use super::view_border::{BORDER_REACH_SPACINGS, SpanEnd, ViewBorder};
use super::web_face::StandingFace;

/// The fewest face points that make a face: a handful of returns on a web
/// face seen edge-on fix no plane.
pub const MIN_FACE_POINTS: usize = 30;

/// How far beyond the web top's trimmed edge a face point may lie, in
/// point spacings on top of the trimmed rim: depth noise and the face seen
/// at a grazing angle spread its points a little across.
const FACE_REACH_SPACINGS: f64 = 6.0;

/// The margins, in point spacings (and at least the on-plane tolerance),
/// that keep the flange's and the web top's own points (and their noise)
/// out of the face, and the face's foot out of the flange beside it. No
/// wider: where an image border or a dropout crosses the root obliquely,
/// the evidence a margin off the root stops that much times the slant
/// before or after the root does (two spacings cost 1 to 2 mm at the ends
/// of 1 mm voxel clouds).
const HEIGHT_MARGIN_SPACINGS: f64 = 1.0;

/// The face's foot: its points up to this many spacings above the lowest
/// face point of their station along the root.
const FOOT_BAND_SPACINGS: f64 = 10.0;

/// The flange seen up to the root: a flange point within this many
/// spacings outward of the root line.
const FLANGE_REACH_SPACINGS: f64 = 6.0;

/// How many of a flange piece's points are read to fit the flange's
/// plane and to tell which sides of the web it lies on.
const FLANGE_SAMPLES: usize = 20_000;

/// The length of a station along the root, in point spacings.
const STATION_SPACINGS: f64 = 4.0;

/// The least angle, degrees, between a face and the camera's ray to it: a
/// face turned further from the camera is not seen at all (or only as
/// noise), and points lying along the rays are the mixed returns a depth
/// jump leaves at the web's edge (a veil from its top down to whatever
/// lies behind), not a face.
pub const MIN_FACE_VIEW_DEG: f64 = 5.0;

/// The least share of the web top's length a root read from the web's
/// face must run for the flange's edge not to be tried instead. A face
/// seen along most of the web places its root from thousands of points,
/// better than the flange's edge does; one seen along a few millimetres
/// places only those.
const MIN_FACE_RUN_SHARE: f64 = 0.5;

/// The most a face's foot may turn from the web top's long axis, degrees,
/// and still be the web's side face. A side face runs along the top
/// (square or leaning, the two share the web's length); the web's end
/// face stands at 90° to it. The top's long axis, from the spread of a
/// top many times longer than wide, is good to a degree or two.
const MAX_ROOT_SKEW_DEG: f64 = 20.0;

/// A root read from the flange's edge: each edge's sampling may move the
/// face the edges imply by a spacing, both towards a face seen; the face
/// must be turned towards the camera and the projector by more than this
/// many spacings over the web's height to tell it from a shadow's edge.
const EDGE_VIEW_SPACINGS: f64 = 4.0;

/// A station's edge sample belongs to the edge's line within this many
/// spacings (or `trim_sigma` residuals, if more).
const EDGE_TOLERANCE_SPACINGS: f64 = 1.5;

/// The fewest stations that make an edge line.
const MIN_EDGE_STATIONS: usize = 8;

/// Refits of the face after trimming its outliers.
const FACE_REFITS: usize = 4;

/// The most stations a root is read at: a root a few metres long at a
/// fine spacing still costs nothing.
const MAX_STATIONS: usize = 20_000;

/// A tee as the background stage found it, and what the stage needs to
/// read its roots from the cloud.
#[derive(Clone, Copy)]
pub struct TeeView<'a> {
    pub cloud: &'a PointCloud,
    /// What is seen of the web: its top, or one side face.
    pub web: Web<'a>,
    /// Every cluster of the flange's layer.
    pub flange_pieces: &'a [&'a PlaneCluster],
    /// The cloud's point spacing at the web, mm.
    pub point_spacing_mm: f64,
    /// How far inside a plane's edge the plane criterion trimmed it, mm.
    pub rim_mm: f64,
    /// A point lies on the flange when within this distance of its plane.
    pub on_plane_mm: f64,
    /// Face points further than this many residuals from the fit are
    /// dropped and the face refitted.
    pub trim_sigma: f64,
    /// Where the structured-light projector sits in the camera frame (the
    /// camera's origin for a sensor without one): a flange it does not
    /// light ends in the web's shadow, not at the root.
    pub projector: Vec3,
    /// Whether a point projects inside the image, when the frame is the
    /// configured camera's grid: a web's top cut by the image's border
    /// does not end its root there.
    pub in_view: Option<&'a dyn Fn(&Vec3) -> bool>,
    /// The image's border as the cloud's rays show it: a root whose
    /// evidence reaches it ends where the root itself crosses it.
    pub border: Option<&'a ViewBorder>,
    /// How far the flange's edge may run on past where the web's top is
    /// seen, mm, when nothing tells whether the image cut the top there
    /// (`quality.max_joint_beyond_seam_mm`): further, the root is refused.
    pub max_beyond_mm: f64,
}

/// What the camera sees of the web that tells where it stands.
#[derive(Clone, Copy)]
pub enum Web<'a> {
    /// Its top, a plane cluster a web's height over the flange.
    Top(&'a PlaneCluster),
    /// One side face standing on the flange, the top out of view (a crop
    /// round the root): that face's root is the only one to read.
    Face(&'a StandingFace),
}

impl Web<'_> {
    /// A point on the web, for naming where a root not seen lies.
    pub fn centroid(&self) -> Vec3 {
        match self {
            Web::Top(top) => top.centroid,
            Web::Face(face) => face.centroid,
        }
    }
}

/// Which side of the web a root lies on, as the camera sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The side facing the camera.
    Near,
    /// The side turned away from the camera.
    Far,
    /// The camera looks down on the web's top, neither face turned to it.
    Above,
}

impl Side {
    /// `the root on the web's near side`, for reasons and evidence.
    pub fn root_name(self, sign: f64) -> String {
        let side = if sign > 0.0 { "+u" } else { "-u" };
        match self {
            Side::Near => format!("the root on the web's side facing the camera ({side})"),
            Side::Far => format!("the root on the web's far side ({side})"),
            Side::Above => format!("the root on the web's {side} side (the camera looks down on the web)"),
        }
    }
}

/// What a root was read from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RootEvidence {
    /// The web's side face fitted to its points, met with the flange.
    Face,
    /// The face turned too nearly edge-on to return points: the flange's
    /// edge against the web, under the web top's edge. The face the two
    /// edges imply is turned `view_margin_deg` towards both the camera and
    /// the projector, more than `least_margin_deg`, which tells it from a
    /// shadow's edge (where the margin is nil).
    FlangeEdge { view_margin_deg: f64, least_margin_deg: f64 },
}

/// A root seen and fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct Root {
    pub side: Side,
    pub evidence: RootEvidence,
    /// +1 or −1: the side of the web along `u = n × e`.
    pub sign: f64,
    /// The root line over the stretch seen: `axes.e` along the root, `a`
    /// outward along the flange, away from the web, `b` the flange normal.
    pub line: SeamCurve,
    /// The web's side face, its fit's RMS residual, the points kept and
    /// the points the trimming dropped (for a root read from the flange's
    /// edge: the face the edges imply, and the flange edge's line fit
    /// across its stations).
    pub face: Plane,
    pub face_rms_mm: f64,
    pub face_points: usize,
    pub face_dropped: usize,
    /// The flange plane near the root and the RMS distance of the flange
    /// points beside the root from it.
    pub flange: Plane,
    pub flange_rms_mm: f64,
    pub flange_points: usize,
    /// The angle between the web's face and the flange on the open side,
    /// degrees (90 for a square tee).
    pub web_angle_deg: f64,
    /// The web's height over the flange, mm (with its top out of view, the
    /// height its face is seen to: it stands at least that tall).
    pub web_height_mm: f64,
    /// The fraction of the stations of the stretch planned with the face's
    /// foot seen, and with the flange seen up to the root.
    pub coverage: [f64; 2],
    /// The stretch planned over the length of root seen anywhere (the
    /// longest run of stations against all seen stations' extent).
    pub seen_share: f64,
    /// The root's length seen anywhere, mm.
    pub seen_mm: f64,
    /// How far beyond the stretch's first and last end the web's top and
    /// the flange up to the root are still seen together, mm: the joint
    /// going on where the face's foot is not seen. `None` where it is not
    /// measured (no top in view, or a root read from the flange's edge,
    /// which is clipped to the top's extent).
    pub joint_beyond_ends_mm: Option<[f64; 2]>,
    /// One-sigma position uncertainty across the root (in the flange's
    /// plane) and along the flange normal, mm.
    pub uncertainty_across_mm: f64,
    pub uncertainty_normal_mm: f64,
}

impl Root {
    /// The stretch planned, along `line`'s feature axis.
    pub fn span(&self) -> (f64, f64) {
        (self.line.s_min, self.line.s_max)
    }

    /// What the root was read from, in words.
    pub fn describe(&self) -> String {
        match self.evidence {
            RootEvidence::Face => format!(
                "the web's side face fitted to {} points (rms {:.2} mm), meeting the flange at {:.1}°",
                self.face_points, self.face_rms_mm, self.web_angle_deg
            ),
            RootEvidence::FlangeEdge { view_margin_deg, least_margin_deg } => format!(
                "the web's side face returns no points, turned edge-on to the camera; the root is the flange's \
                 edge against the web, a line through {} stations (rms {:.2} mm), under the web top's edge: the \
                 face they imply meets the flange at {:.1}° and is turned {view_margin_deg:.1}° towards the camera \
                 and the projector (a shadow's edge would be turned 0°; at least {least_margin_deg:.1}° is asked)",
                self.face_points, self.face_rms_mm, self.web_angle_deg
            ),
        }
    }

    /// The unit direction in the flange's plane, across the root, away from
    /// the web.
    pub fn away_from_web(&self) -> Vec3 {
        self.line.axes.a
    }
}

/// A root not seen, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct RootNotSeen {
    pub side: Side,
    pub sign: f64,
    pub reason: String,
    /// Whether any of the flange lies on this side of the web (none does
    /// beside an inside corner's outer face).
    pub flange_seen: bool,
    /// Where the root would lie, roughly: at the web's foot on that side.
    pub near_camera: Vec3,
}

/// The web's frame: where its top is and how the flange lies.
#[derive(Debug, Clone, Copy)]
struct WebFrame {
    /// Into the workpiece.
    n: Vec3,
    /// Along the web.
    e: Vec3,
    /// Across the web.
    u: Vec3,
    origin: Vec3,
    /// The flange plane's offset along `n`.
    flange_offset: f64,
    /// The web's middle and half its top's width across, mm from `origin`.
    middle: f64,
    half_width: f64,
    height: f64,
    /// Whether the flange lies on the web's −u and +u sides.
    flange_sides: [bool; 2],
    /// The side (`sign`) of the one face seen, when the web's top is not:
    /// `middle` and `half_width` then place that face, not the top.
    face_only: Option<f64>,
}

impl WebFrame {
    /// Whether the flange lies on the web's side `sign`.
    fn flange_on(&self, sign: f64) -> bool {
        self.flange_sides[usize::from(sign > 0.0)]
    }

    fn height_of(&self, p: &Vec3) -> f64 {
        self.flange_offset - self.n.dot(p)
    }

    fn across(&self, p: &Vec3) -> f64 {
        (p - self.origin).dot(&self.u)
    }

    /// Where a face point on side `sign` may lie, outward of the web's
    /// middle, mm, and up to which height over the flange: from the web's
    /// middle to a little beyond the top's trimmed edge, below the top's
    /// own points; or round the one face seen, up to where it is seen.
    fn face_band(&self, view: &TeeView, sign: f64, margin: f64) -> ((f64, f64), f64) {
        let spacing = view.point_spacing_mm;
        match self.face_only {
            Some(seen) if seen == sign => {
                let reach = FACE_REACH_SPACINGS * spacing;
                ((self.half_width - reach, self.half_width + reach), self.height)
            }
            _ => ((0.0, self.half_width + view.rim_mm + FACE_REACH_SPACINGS * spacing), self.height - margin),
        }
    }
}

/// Finds both roots of the tee in `view`: `[−u side, +u side]`, each
/// fitted or said not to be seen.
pub fn find_roots(view: &TeeView) -> [Result<Root, RootNotSeen>; 2] {
    let Some(frame) = web_frame(view) else {
        let why = "the flange's plane and the web give no frame to read the roots in".to_string();
        let near = view.web.centroid();
        return [-1.0, 1.0].map(|sign| {
            Err(RootNotSeen {
                side: Side::Above,
                sign,
                reason: format!("no root is seen: {why}"),
                near_camera: near,
                flange_seen: true,
            })
        });
    };
    [-1.0, 1.0].map(|sign| match frame.face_only {
        Some(seen) if seen != sign => {
            let side = side_seen(&frame, sign);
            Err(RootNotSeen {
                side,
                sign,
                reason: format!(
                    "{} is not planned: the web's top is out of view and its other side face is the one seen; the \
                     web hides this one",
                    side.root_name(sign)
                ),
                near_camera: frame.origin + frame.n * frame.height_of(&frame.origin),
                flange_seen: frame.flange_on(sign),
            })
        }
        _ => find_root(view, &frame, sign),
    })
}

/// The flange's plane from all its pieces (one plate on both sides of the
/// web), fitted to a sample of their points ([`flange_samples`]), and
/// those points.
pub(super) fn flange_plane(cloud: &PointCloud, pieces: &[&PlaneCluster]) -> Option<(Plane, Vec<Vec3>)> {
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

/// The margin, mm, that keeps a plane's own points (and their noise) out
/// of a face standing on it: [`HEIGHT_MARGIN_SPACINGS`] spacings, and at
/// least the on-plane tolerance.
pub(super) fn height_margin(on_plane_mm: f64, spacing: f64) -> f64 {
    on_plane_mm.max(HEIGHT_MARGIN_SPACINGS * spacing)
}

/// The cloud's valid points, read as they are needed: a frame of millions
/// of points is not copied.
pub(super) fn valid_points(cloud: &PointCloud) -> impl Iterator<Item = Vec3> + '_ {
    cloud.points().iter().filter(|p| p.iter().all(|c| c.is_finite())).map(vec3)
}

/// The web's frame from the flange pieces and its top, or its one face
/// seen.
fn web_frame(view: &TeeView) -> Option<WebFrame> {
    let flange_points = flange_samples(view.cloud, view.flange_pieces);
    let frame = match view.web {
        Web::Top(top) => frame_from_top(view.cloud, top, &flange_points.iter().collect::<Moments>().plane()?)?,
        // The face search fitted the flange's plane to these same pieces.
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
    (frame.height > 0.0).then_some(WebFrame { flange_sides, ..frame })
}

/// The web's frame from its top: along its long axis, its middle and half
/// width from its points' spread across it.
fn frame_from_top(cloud: &PointCloud, top: &PlaneCluster, flange: &Plane) -> Option<WebFrame> {
    let n = flange.normal;
    let e = (top.long_axis - n * top.long_axis.dot(&n)).try_normalize(1e-9)?;
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
    })
}

/// Which side of the web `sign` is, as the camera (at the frame's origin)
/// sees it.
fn side_seen(frame: &WebFrame, sign: f64) -> Side {
    let camera_across = sign * (frame.across(&Vec3::zeros()) - frame.middle);
    if camera_across > frame.half_width {
        Side::Near
    } else if camera_across < -frame.half_width {
        Side::Far
    } else {
        Side::Above
    }
}

fn find_root(view: &TeeView, frame: &WebFrame, sign: f64) -> Result<Root, RootNotSeen> {
    let side = side_seen(frame, sign);
    // The web's foot on this side, where its root would lie.
    let foot_at = frame.origin
        + frame.u * (frame.middle + sign * (frame.half_width + view.rim_mm))
        + frame.n * frame.height_of(&frame.origin);
    let flange_seen = frame.flange_on(sign);
    let not_seen = |why: String| RootNotSeen {
        side,
        sign,
        reason: format!("{} is not planned: {why}", side.root_name(sign)),
        near_camera: foot_at,
        flange_seen,
    };
    if !flange_seen {
        return Err(not_seen("the flange on this side is not seen (hidden by the web)".into()));
    }
    match root_from_face(view, frame, sign, side) {
        Ok(root) => Ok(face_or_flange_edge(view, frame, sign, side, root)),
        // A face turned edge-on to the camera returns nothing, or only the
        // mixed returns along the rays; one glimpsed where the flange
        // beside it is not seen gives no root either. The flange's edge may
        // still show the root; where it ends at a shadow's edge instead,
        // the edge's own test refuses it.
        Err(why) => root_from_flange_edge(view, frame, sign, side)
            .map_err(|edge| not_seen(format!("{why}; and the flange's edge does not show it: {edge}"))),
    }
}

/// The root from the face, or from the flange's edge where the face is
/// seen along less than [`MIN_FACE_RUN_SHARE`] of the web's top, or where
/// the web's top and the flange up to the root go on past the face's root
/// by more than the coverage gate allows, and the flange's edge shows a
/// longer root. A face turned nearly edge-on returns points along part of
/// the web only (a few millimetres where a gap in the flange or the web's
/// end lets the camera see it, or the stretch where it is turned a little
/// less), and their root, read over that stretch, is refused by the
/// coverage gates or, mixed with the web's end face, by the fit's
/// residual; the flange's edge beside the same face runs the web's length.
fn face_or_flange_edge(view: &TeeView, frame: &WebFrame, sign: f64, side: Side, root: Root) -> Root {
    let Web::Top(top) = view.web else {
        return root;
    };
    let points = view.cloud.points();
    let (lo, hi) = extent(top.members.iter().map(|&i| (vec3(&points[i as usize]) - frame.origin).dot(&frame.e)));
    let span = |r: &Root| r.line.s_max - r.line.s_min;
    let beyond = root.joint_beyond_ends_mm.map_or(0.0, |[before, after]| before.max(after));
    // (A top without members spans minus infinity: the face's root stays.)
    if span(&root) >= MIN_FACE_RUN_SHARE * (hi - lo) && beyond <= view.max_beyond_mm {
        return root;
    }
    match root_from_flange_edge(view, frame, sign, side) {
        Ok(edge) if span(&edge) > span(&root) => {
            tracing::debug!(
                face_mm = span(&root),
                edge_mm = span(&edge),
                "a face seen along a short stretch: the root from the flange's edge"
            );
            edge
        }
        _ => root,
    }
}

/// The root where the web's side face, fitted to its points, meets the
/// flange, or why the face gives none.
fn root_from_face(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, String> {
    let spacing = view.point_spacing_mm;
    let margin = height_margin(view.on_plane_mm, spacing);
    let ((inner, reach), h_hi) = frame.face_band(view, sign, margin);
    let face_points: Vec<Vec3> = valid_points(view.cloud)
        .filter(|p| {
            let h = frame.height_of(p);
            let off = sign * (frame.across(p) - frame.middle);
            (margin..=h_hi).contains(&h) && (inner..=reach).contains(&off)
        })
        .collect();
    let hidden = if side == Side::Far { ", hidden by the web" } else { "" };
    if face_points.len() < MIN_FACE_POINTS {
        return Err(format!(
            "the web's side face there is not seen{hidden} ({} points between the flange and the web's top, \
             fewer than {MIN_FACE_POINTS})",
            face_points.len()
        ));
    }
    let Some(face) = fit_face(&face_points, view.trim_sigma) else {
        return Err("the points on the web's side face span no plane".into());
    };
    // A side face runs the web's length. Where the side face is turned
    // edge-on and returns nothing, the points between the flange and the
    // web's top on this side can be the web's end face, standing across
    // the web: its "root" would be a few millimetres of the web's
    // thickness. (A face lying parallel to the flange is refused below.)
    let foot_line = frame.n.cross(&face.plane.normal).try_normalize(1e-6);
    if let (None, Some(foot_line)) = (frame.face_only, foot_line) {
        let skew_deg = foot_line.dot(&frame.e).abs().clamp(0.0, 1.0).acos().to_degrees();
        if skew_deg > MAX_ROOT_SKEW_DEG {
            return Err(format!(
                "the {} points between the flange and the web's top stand across the web (their foot \
                 {skew_deg:.0}° from the top's long axis, over {MAX_ROOT_SKEW_DEG}°): the web's end, not its \
                 side face{hidden}",
                face.inliers.len()
            ));
        }
    }
    // The face's normal out of the web, towards this side.
    let m = if face.plane.normal.dot(&frame.u) * sign >= 0.0 { face.plane.normal } else { -face.plane.normal };
    let d_m = m.dot(&face.centroid);
    let view_deg = m.dot(&(-face.centroid).normalize()).clamp(-1.0, 1.0).asin().to_degrees();
    if view_deg < MIN_FACE_VIEW_DEG {
        return Err(format!(
            "the {} points between the flange and the web's top lie along the camera's rays ({view_deg:.1}° from \
             them, below {MIN_FACE_VIEW_DEG}°): mixed returns at the web's edge, not its side face{hidden}",
            face.inliers.len()
        ));
    }
    let n = frame.n;
    let Some(r) = n.cross(&m).try_normalize(1e-6) else {
        return Err("the points between the flange and the web's top lie parallel to the flange".into());
    };
    let r = if r.dot(&frame.e) >= 0.0 { r } else { -r };
    // The point on both planes nearest the web's origin.
    let o = frame.origin;
    let nm = n.dot(&m);
    let det = 1.0 - nm * nm;
    let (rn, rm) = (frame.flange_offset - n.dot(&o), d_m - m.dot(&o));
    let p0 = o + n * ((rn - nm * rm) / det) + m * ((rm - nm * rn) / det);
    // Across the root in the flange, away from the web.
    let w = {
        let w = r.cross(&n);
        if w.dot(&m) >= 0.0 { w } else { -w }
    };
    // Up the face from the root.
    let up = {
        let v = r.cross(&m);
        if v.dot(&n) <= 0.0 { v } else { -v }
    };
    let web_angle_deg = up.dot(&w).clamp(-1.0, 1.0).acos().to_degrees();

    // The evidence along the root: the face's foot and the flange up to it.
    let along = |p: &Vec3| (p - p0).dot(&r);
    let foot_points = station_feet(&face.inliers, along, |p| frame.height_of(p), spacing);
    let foot: Vec<f64> = foot_points.iter().map(along).collect();
    // Outward of the face's own foot (which lies at the flange's height
    // too, where the web overhangs the flange's end) by the same margin
    // that keeps the flange out of the face.
    let flange_reach = margin + FLANGE_REACH_SPACINGS * spacing;
    // And the flange seen under where the web stands, inward of the root:
    // past the web's end.
    let web_width = 2.0 * frame.half_width;
    let mut beside: Vec<Vec3> = Vec::new();
    let mut under_web: Vec<f64> = Vec::new();
    for p in valid_points(view.cloud).filter(|p| frame.height_of(p).abs() <= view.on_plane_mm) {
        let out = (p - p0).dot(&w);
        if (margin..=flange_reach).contains(&out) {
            beside.push(p);
        } else if (-web_width..=-margin).contains(&out) {
            under_web.push(along(&p));
        }
    }
    if foot.is_empty() {
        return Err("the web's side face is not seen down to the flange".into());
    }
    if beside.is_empty() {
        return Err(format!(
            "the flange is not seen up to the web's face{}",
            if side == Side::Far { " (the web hides it)" } else { " (in the web's shadow)" }
        ));
    }
    let flange_along: Vec<f64> = beside.iter().map(along).collect();
    let Some(run) = seen_run(&foot, &flange_along, spacing) else {
        return Err("the web's face and the flange up to it are not seen together anywhere along the root".into());
    };
    let run = match view.border {
        Some(border) => ends_at_border(border, &p0, &r, run, [&foot_points, &beside], spacing),
        None => run,
    };
    let run = ends_past_cut_foot(view, &p0, &r, run, &foot_points, &beside, &under_web, spacing);
    // Where the web's top stands over the root and the flange is seen up
    // to it beyond the stretch, the joint goes on though the face's foot
    // is not seen there (turned nearly edge-on, or covered): the quality
    // gate refuses a root stopping short of it.
    let joint_beyond_ends_mm = match view.web {
        Web::Top(top) => {
            let points = view.cloud.points();
            let top_along: Vec<f64> = top.members.iter().map(|&i| along(&vec3(&points[i as usize]))).collect();
            Some(joint_beyond_run(&top_along, &flange_along, (run.s0, run.s1), spacing))
        }
        Web::Face(_) => None,
    };
    // The flange near the root: its points beside the run, against the
    // plane of all its pieces.
    let near_flange: Vec<&Vec3> = beside.iter().filter(|p| (run.s0..=run.s1).contains(&along(p))).collect();
    let flange_plane = Plane { normal: n, offset: frame.flange_offset };
    let flange_rms_mm = rms(near_flange.iter().map(|p| flange_plane.signed_distance(p)));

    // The face fit's prediction error at the root's ends (h = 0).
    let stats = FaceSpread::of(&face.inliers, |p| frame.height_of(p), along);
    let floor = spacing / 12f64.sqrt();
    let at_end = |t: f64| {
        let n = face.inliers.len() as f64;
        let lever = 1.0 / n + stats.mean_h.powi(2) / (n * stats.var_h) + (t - stats.mean_t).powi(2) / (n * stats.var_t);
        face.rms_mm * lever.sqrt()
    };
    let face_sigma = at_end(run.s0).max(at_end(run.s1));
    // Across: the face's offset error, seen through the web's angle to the
    // flange; along the normal: the flange's (thousands of points) and the
    // face's share where the web is not square.
    let sin = web_angle_deg.to_radians().sin().max(0.1);
    let uncertainty_across_mm = (face_sigma / sin).hypot(floor);
    let uncertainty_normal_mm = (face_sigma * web_angle_deg.to_radians().cos().abs() / sin).hypot(floor);

    let line = SeamCurve {
        axes: SeamAxes { origin: p0, e: r, a: w, b: n },
        coef_a: vec![0.0, 0.0],
        coef_b: vec![0.0, 0.0],
        s_min: run.s0,
        s_max: run.s1,
    };
    Ok(Root {
        side,
        evidence: RootEvidence::Face,
        sign,
        line,
        face: Plane { normal: m, offset: d_m },
        face_rms_mm: face.rms_mm,
        face_points: face.inliers.len(),
        face_dropped: face.dropped,
        flange: flange_plane,
        flange_rms_mm,
        flange_points: near_flange.len(),
        web_angle_deg,
        web_height_mm: frame.height,
        coverage: run.coverage,
        seen_share: run.share,
        seen_mm: run.seen_mm,
        joint_beyond_ends_mm,
        uncertainty_across_mm,
        uncertainty_normal_mm,
    })
}

/// The root where the flange's edge meets the web, for a side whose face
/// is turned too nearly edge-on to return points.
///
/// Along the web, at each station, the innermost flange point on this side
/// and the outermost point of the web's top are read; a line is fitted to
/// each across its stations (trimmed). The flange's edge is the root only
/// if nothing hides the flange there: the face the two edges imply (from
/// the root up to the top's edge) must be turned towards the camera and
/// the projector. Where the flange instead ends at the edge of the web's
/// shadow (from the camera, or from the projector), that implied face
/// holds the ray that grazes the top's edge, so it is turned from the
/// shadowing eye by nothing; sampling moves each edge by up to a spacing,
/// both towards calling the face seen, so the margin must exceed
/// [`EDGE_VIEW_SPACINGS`] spacings over the web's height. A root turned
/// less than that is refused, not guessed.
fn root_from_flange_edge(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, String> {
    let root = flange_edge_root(view, frame, sign, side)?;
    // The web's axis from its top's spread lies off the web where the
    // image's border cuts the top obliquely: the edge, looked for outward
    // of the web's middle line along that axis, then runs into the
    // search's bound before the web ends. Read again along the edge's own
    // direction.
    let Web::Top(top) = view.web else {
        return Ok(root);
    };
    let along_edge = root.line.axes.e;
    if along_edge.dot(&frame.e).abs() >= MAX_AXIS_TURN_DEG.to_radians().cos() {
        return Ok(root);
    }
    match frame_along(view.cloud, top, frame, &along_edge) {
        Some(turned) => flange_edge_root(view, &turned, sign, side).or(Ok(root)),
        None => Ok(root),
    }
}

/// How far, degrees, the flange's edge may run from the web's axis before
/// the edge is read again along its own direction: a degree moves the edge
/// by a spacing every 20 to 60 mm along a root (spacings of 0.3 to 1 mm).
const MAX_AXIS_TURN_DEG: f64 = 1.0;

/// `frame` with the web's axis along `e` (laid in the flange's plane), the
/// middle and half-width of the web's `top` read across it.
fn frame_along(cloud: &PointCloud, top: &PlaneCluster, frame: &WebFrame, e: &Vec3) -> Option<WebFrame> {
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

/// The root from the flange's edge in the web's frame `frame`
/// ([`root_from_flange_edge`]).
fn flange_edge_root(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, String> {
    let Web::Top(web_top) = view.web else {
        return Err("the web's top is out of view, so its edge cannot stand in for the face".into());
    };
    let spacing = view.point_spacing_mm;
    let top_edge = frame.half_width + view.rim_mm;
    // A web leaning 45° puts its root a web height outward of its top.
    let outermost = top_edge + frame.height;
    let top_reach = top_edge + FACE_REACH_SPACINGS * spacing;
    let mut flange: Vec<EdgeSample> = Vec::new();
    let mut top: Vec<EdgeSample> = Vec::new();
    for p in valid_points(view.cloud) {
        let off = sign * (frame.across(&p) - frame.middle);
        if !(0.0..=outermost).contains(&off) {
            continue;
        }
        let (t, h) = ((p - frame.origin).dot(&frame.e), frame.height_of(&p));
        if h.abs() <= view.on_plane_mm {
            flange.push(EdgeSample { t, off, h });
        } else if off <= top_reach && web_top.plane.signed_distance(&p).abs() <= view.on_plane_mm {
            top.push(EdgeSample { t, off, h });
        }
    }
    let stations = Stations::over(flange.iter().chain(&top).map(|s| s.t), spacing)
        .ok_or_else(|| "no flange point lies beside the web".to_string())?;
    let flange_edge = stations.extremes(&flange, |a, b| a.off < b.off);
    let top_edge_samples = stations.extremes(&top, |a, b| a.off > b.off);
    let tolerance = |rms: f64| (view.trim_sigma * rms).max(EDGE_TOLERANCE_SPACINGS * spacing);
    let root_line = EdgeLine::fit(&flange_edge, tolerance)
        .ok_or_else(|| format!("the flange's edge is seen at {} stations along the web, too few", flange_edge.len()))?;
    let top_line = EdgeLine::fit(&top_edge_samples, tolerance).ok_or_else(|| {
        format!("the web top's edge is seen at {} stations along the web, too few", top_edge_samples.len())
    })?;

    // The implied face across the middle of the root's stations.
    let t_mid = 0.5 * (root_line.t_range.0 + root_line.t_range.1);
    let lean = top_line.at(t_mid) - root_line.at(t_mid);
    let slant = lean.hypot(frame.height);
    let (n, e, outward) = (frame.n, frame.e, frame.u * sign);
    let root_at = |t: f64| frame.origin + e * t + frame.u * (frame.middle + sign * root_line.at(t)) + n * frame.height;
    let root_mid = root_at(t_mid);
    let m = ((outward * frame.height + n * lean) / slant).normalize();
    let turned_deg = |eye: Vec3| {
        let to_eye = eye - root_mid;
        (m.dot(&to_eye) / to_eye.norm()).clamp(-1.0, 1.0).asin().to_degrees()
    };
    let view_margin_deg = turned_deg(Vec3::zeros()).min(turned_deg(view.projector));
    let least_margin_deg = (EDGE_VIEW_SPACINGS * spacing / frame.height).atan().to_degrees();
    if view_margin_deg < least_margin_deg {
        return Err(format!(
            "the face from the flange's edge up to the web top's edge is turned {view_margin_deg:.1}° towards the \
             camera or the projector, below {least_margin_deg:.1}° ({EDGE_VIEW_SPACINGS} point spacings of \
             {spacing:.2} mm over the web's {:.0} mm): the flange may end at the web's shadow, not at the root",
            frame.height
        ));
    }

    // The root line and its frame: `r` along it, `w` outward in the flange.
    let p0 = root_at(0.0);
    let r = (root_at(1.0) - p0).normalize();
    let w = {
        let w = r.cross(&n);
        if w.dot(&outward) >= 0.0 { w } else { -w }
    };
    let stretch = (root_at(1.0) - p0).norm();
    let along = |t: f64| t * stretch;
    // The evidence of the root: every flange point at the edge's line (not
    // only each station's innermost, whose place along a station would
    // round the root's ends off by up to a station), in the stations whose
    // innermost point lies on the line (where the flange runs on under the
    // web, past its end, a station's innermost point leaves the line) and
    // the stations next to them. The station holding the web's end holds
    // the flange past it too, so its innermost point leaves the line; its
    // points at the line still show the root up to the web's end, and the
    // web top's extent (below) ends the root there, not a station short.
    let at_edge = tolerance(root_line.rms_mm);
    let on_line: HashSet<usize> = root_line.kept.iter().map(|s| stations.index(s.t)).collect();
    let beside_line =
        |k: usize| [k.checked_sub(1), Some(k), k.checked_add(1)].into_iter().flatten().any(|j| on_line.contains(&j));
    let edge: Vec<f64> = flange
        .iter()
        .filter(|s| (s.off - root_line.at(s.t)).abs() <= at_edge && beside_line(stations.index(s.t)))
        .map(|s| along(s.t))
        .collect();
    // The root runs where the flange's edge does: the web's top, nearer
    // the camera, may leave the image before the root does; it need only
    // be seen above enough of the root to be judged by the coverage gate.
    let run = seen_run(&edge, &edge, spacing)
        .ok_or_else(|| "the flange's edge is not seen along the web anywhere".to_string())?;
    // Only where the web stands: past the web's end the flange's edge runs
    // on nearly straight (the web's end hides the flange behind it a little
    // more at each step), so the root ends where the web's top does, unless
    // the image's border cut the top there (the top, nearer the camera,
    // leaves the image before the root does); with no grid to tell, it
    // ends there too.
    // The top's edge from every point at its line, like the flange's
    // evidence above: a station's outermost point would round its extent
    // off, and, one to a station at a place of its own along it, would
    // leave every third or so of the coverage gate's stations empty.
    let top_on_line: HashSet<usize> = top_line.kept.iter().map(|s| stations.index(s.t)).collect();
    let top_at_line: Vec<f64> = top
        .iter()
        .filter(|s| {
            (s.off - top_line.at(s.t)).abs() <= tolerance(top_line.rms_mm) && top_on_line.contains(&stations.index(s.t))
        })
        .map(|s| s.t)
        .collect();
    let (top_lo, top_hi) = extent(top_at_line.iter().copied());
    let top_at = |t: f64| frame.origin + e * t + frame.u * (frame.middle + sign * top_line.at(t));
    let step = STATION_SPACINGS * spacing / stretch;
    // Past the top's end: off the configured camera's grid, or where no
    // ray of the cloud reaches (within the sampling's reach of its border).
    let reach = BORDER_REACH_SPACINGS * spacing;
    let cut_by_border = |t: f64| match (view.in_view, view.border) {
        (Some(in_view), _) => !in_view(&top_at(t)),
        (None, Some(border)) => border.outside_mm(&top_at(t)) > -reach,
        (None, None) => false,
    };
    let s0 = if cut_by_border(top_lo - step) { run.s0 } else { run.s0.max(along(top_lo)) };
    let s1 = if cut_by_border(top_hi + step) { run.s1 } else { run.s1.min(along(top_hi)) };
    if view.in_view.is_none() && view.border.is_none() {
        let past = (s0 - run.s0).max(run.s1 - s1);
        if past > view.max_beyond_mm {
            return Err(format!(
                "the flange's edge runs on {past:.1} mm past where the web's top is seen, more than {:.1} mm \
                 (quality.max_joint_beyond_seam_mm): the web may end there, or the image cut its top (neither \
                 the camera's grid nor the cloud's rays show where the image ends)",
                view.max_beyond_mm
            ));
        }
    }
    if s1 <= s0 {
        return Err("the flange's edge is not seen where the web's top is".to_string());
    }
    let run = SeenRun { s0, s1, share: ((s1 - s0) / run.seen_mm).min(1.0), ..run };
    let top_seen: Vec<f64> = top_at_line.iter().map(|&t| along(t)).collect();
    let coverage = [covered_share(&top_seen, run.s0, run.s1, spacing), run.coverage[1]];
    let web_angle_deg = frame.height.atan2(lean).to_degrees();

    // The flange beside the root, over the run.
    let flange_reach = FLANGE_REACH_SPACINGS * spacing;
    let beside: Vec<f64> = flange
        .iter()
        .filter(|s| {
            let out = s.off - root_line.at(s.t);
            (0.0..=flange_reach).contains(&out) && (run.s0..=run.s1).contains(&along(s.t))
        })
        .map(|s| s.h)
        .collect();
    let floor = spacing / 12f64.sqrt();
    let in_run = root_line.kept.iter().filter(|s| (run.s0..=run.s1).contains(&along(s.t))).count().max(1);
    Ok(Root {
        side,
        evidence: RootEvidence::FlangeEdge { view_margin_deg, least_margin_deg },
        sign,
        line: SeamCurve {
            axes: SeamAxes { origin: p0, e: r, a: w, b: n },
            coef_a: vec![0.0, 0.0],
            coef_b: vec![0.0, 0.0],
            s_min: run.s0,
            s_max: run.s1,
        },
        face: Plane { normal: m, offset: m.dot(&root_mid) },
        face_rms_mm: root_line.rms_mm,
        face_points: root_line.kept.len(),
        face_dropped: root_line.dropped,
        flange: Plane { normal: n, offset: frame.flange_offset },
        flange_rms_mm: rms(beside.iter().copied()),
        flange_points: beside.len(),
        web_angle_deg,
        web_height_mm: frame.height,
        coverage,
        seen_share: run.share,
        seen_mm: run.seen_mm,
        // Clipped to where the web's top is seen, above.
        joint_beyond_ends_mm: None,
        // The edge's line across its stations, and the sampling: the root
        // lies within a spacing inward of the flange's last point.
        uncertainty_across_mm: (root_line.rms_mm / (in_run as f64).sqrt()).hypot(floor),
        uncertainty_normal_mm: floor,
    })
}

/// The run's ends moved to where the root crosses the image's border,
/// each where the face's foot and the flange beside the root (`evidence`,
/// along the root `origin + t · r`) both reach that border within its last
/// station ([`ViewBorder::end_at_border`]): a border crossing the root
/// obliquely cuts the evidence, which lies a spacing or more off the root,
/// before or after it cuts the root. An end moves at most a station, in
/// either direction; one that the evidence does not carry to the border
/// stays where the evidence puts it.
fn ends_at_border(
    border: &ViewBorder,
    origin: &Vec3,
    r: &Vec3,
    run: SeenRun,
    evidence: [&[Vec3]; 2],
    spacing: f64,
) -> SeenRun {
    let station = STATION_SPACINGS * spacing;
    let reach = BORDER_REACH_SPACINGS * spacing;
    let along = |p: &Vec3| (p - origin).dot(r);
    let near = |at: f64| {
        evidence.map(|set| set.iter().copied().filter(|p| (along(p) - at).abs() <= station).collect::<Vec<Vec3>>())
    };
    let moved = |end: SpanEnd, at: f64| {
        let sets = near(at);
        let sets: [&[Vec3]; 2] = [&sets[0], &sets[1]];
        border.end_at_border(origin, r, end, at, &sets, reach, station).unwrap_or(at)
    };
    let (s0, s1) = (moved(SpanEnd::Start, run.s0), moved(SpanEnd::End, run.s1));
    if s1 <= s0 {
        return run;
    }
    SeenRun { s0, s1, share: ((s1 - s0) / run.seen_mm).min(1.0), ..run }
}

/// The run's ends carried on past where the image's border, not the web,
/// ends the face's foot. A face seen only well above the flange (its lower
/// part turned nearly edge-on) has its foot up the face, and where the
/// border crosses the web that foot leaves the view before the root does:
/// the camera is tilted, and what stands higher is seen further in. When
/// the foot's last point lies at the border (within the sampling's reach
/// of it: past the camera's grid a reach on, or by the border the cloud's
/// rays show), the root runs on as far as the flange is seen up to it
/// (across breaks no longer than [`JOINT_BREAK_SPACINGS`]), short of any
/// flange seen under where the web would stand (`under_web`: the web
/// ended there). Where that flange runs to the border too, the end moves
/// on to where the root itself leaves the view, at most a station on; it
/// never lies out of view. An end the border does not cut (the web's end,
/// its shadow, something covering the foot) stays where the evidence puts
/// it.
#[allow(clippy::too_many_arguments)]
fn ends_past_cut_foot(
    view: &TeeView,
    origin: &Vec3,
    r: &Vec3,
    run: SeenRun,
    foot: &[Vec3],
    beside: &[Vec3],
    under_web: &[f64],
    spacing: f64,
) -> SeenRun {
    let station = STATION_SPACINGS * spacing;
    let reach = BORDER_REACH_SPACINGS * spacing;
    let max_break = JOINT_BREAK_SPACINGS * spacing;
    let step = 0.25 * spacing;
    let along = |p: &Vec3| (p - origin).dot(r);
    let at_border = |p: &Vec3, outward: f64| match (view.in_view, view.border) {
        (Some(in_view), _) => !in_view(&(p + r * (outward * reach))),
        (None, Some(border)) => border.outside_mm(p) > -reach,
        (None, None) => false,
    };
    let root_in_view = |s: f64| {
        let p = origin + r * s;
        match (view.in_view, view.border) {
            (Some(in_view), _) => in_view(&p),
            (None, Some(border)) => border.outside_mm(&p) <= 0.0,
            (None, None) => true,
        }
    };
    let carried = |end: f64, outward: f64| {
        let ahead_of_end = |s: f64| outward * (s - end);
        let Some(last_foot) = foot.iter().max_by(|a, b| ahead_of_end(along(a)).total_cmp(&ahead_of_end(along(b))))
        else {
            return end;
        };
        if !at_border(last_foot, outward) {
            return end;
        }
        let web_ends = under_web.iter().map(|&s| ahead_of_end(s)).filter(|&d| d > 0.0).fold(f64::INFINITY, f64::min);
        let mut ahead: Vec<(f64, &Vec3)> =
            beside.iter().map(|p| (ahead_of_end(along(p)), p)).filter(|&(d, _)| d > 0.0 && d < web_ends).collect();
        ahead.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut reached: Option<(f64, &Vec3)> = None;
        for (d, p) in ahead {
            if d - reached.map_or(0.0, |(r, _)| r) > max_break {
                break;
            }
            reached = Some((d, p));
        }
        let Some((mut to, last_flange)) = reached else {
            return end;
        };
        if at_border(last_flange, outward) {
            let limit = (to + station).min(web_ends);
            while to + step <= limit && root_in_view(end + outward * (to + step)) {
                to += step;
            }
        }
        while to > 0.0 && !root_in_view(end + outward * to) {
            to = (to - step).max(0.0);
        }
        end + outward * to
    };
    let (s0, s1) = (carried(run.s0, -1.0), carried(run.s1, 1.0));
    if (s0, s1) == (run.s0, run.s1) {
        return run;
    }
    // The face's foot is not seen along what was added.
    let foot_share = run.coverage[0] * (run.s1 - run.s0) / (s1 - s0);
    SeenRun { s0, s1, coverage: [foot_share, run.coverage[1]], share: ((s1 - s0) / run.seen_mm).min(1.0), ..run }
}

/// The share of the stations from `s0` to `s1` holding a sample.
fn covered_share(samples: &[f64], s0: f64, s1: f64, spacing: f64) -> f64 {
    let width = (STATION_SPACINGS * spacing).max((s1 - s0) / MAX_STATIONS as f64).max(f64::MIN_POSITIVE);
    let count = (((s1 - s0) / width).ceil() as usize).max(1);
    let mut seen = vec![false; count];
    for s in samples.iter().filter(|s| (s0..=s1).contains(*s)) {
        seen[(((s - s0) / width) as usize).min(count - 1)] = true;
    }
    seen.iter().filter(|&&b| b).count() as f64 / count as f64
}

/// A point beside the web: along it from the web top's centroid, outward
/// from the web's middle, and its height over the flange, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
struct EdgeSample {
    t: f64,
    off: f64,
    h: f64,
}

/// Stations along the web, [`STATION_SPACINGS`] long (at most
/// [`MAX_STATIONS`] of them).
struct Stations {
    start: f64,
    width: f64,
    count: usize,
}

impl Stations {
    fn over(ts: impl Iterator<Item = f64>, spacing: f64) -> Option<Stations> {
        let (lo, hi) = extent(ts);
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let width = (STATION_SPACINGS * spacing).max((hi - lo) / MAX_STATIONS as f64).max(f64::MIN_POSITIVE);
        let count = (((hi - lo) / width).floor() as usize + 1).min(MAX_STATIONS);
        Some(Stations { start: lo, width, count })
    }

    fn index(&self, t: f64) -> usize {
        (((t - self.start) / self.width).floor().max(0.0) as usize).min(self.count - 1)
    }

    /// Each station's sample that `beyond` puts first: the innermost of the
    /// flange, the outermost of the web's top.
    fn extremes(&self, samples: &[EdgeSample], beyond: impl Fn(&EdgeSample, &EdgeSample) -> bool) -> Vec<EdgeSample> {
        let mut best: Vec<Option<EdgeSample>> = vec![None; self.count];
        for s in samples {
            let k = self.index(s.t);
            if best[k].is_none_or(|b| beyond(s, &b)) {
                best[k] = Some(*s);
            }
        }
        best.into_iter().flatten().collect()
    }
}

/// A straight edge across its stations, `off = a + b·t`: least squares,
/// started from the median offset and refitted without the stations
/// further than `tolerance(rms)` from it (a dropout that cuts the flange
/// short, or the flange running on past the web's end).
#[derive(Debug, Clone, PartialEq)]
struct EdgeLine {
    a: f64,
    b: f64,
    rms_mm: f64,
    kept: Vec<EdgeSample>,
    dropped: usize,
    t_range: (f64, f64),
}

impl EdgeLine {
    fn at(&self, t: f64) -> f64 {
        self.a + self.b * t
    }

    fn fit(samples: &[EdgeSample], tolerance: impl Fn(f64) -> f64) -> Option<EdgeLine> {
        if samples.len() < MIN_EDGE_STATIONS {
            return None;
        }
        let mut offs: Vec<f64> = samples.iter().map(|s| s.off).collect();
        offs.sort_by(f64::total_cmp);
        let mut line = EdgeLine {
            a: offs[offs.len() / 2],
            b: 0.0,
            rms_mm: 0.0,
            kept: Vec::new(),
            dropped: 0,
            t_range: (0.0, 0.0),
        };
        for _ in 0..=FACE_REFITS {
            let limit = tolerance(line.rms_mm);
            let kept: Vec<EdgeSample> =
                samples.iter().filter(|s| (s.off - line.at(s.t)).abs() <= limit).copied().collect();
            if kept.len() < MIN_EDGE_STATIONS {
                return None;
            }
            let n = kept.len() as f64;
            let (mt, mo) = (kept.iter().map(|s| s.t).sum::<f64>() / n, kept.iter().map(|s| s.off).sum::<f64>() / n);
            let (stt, sto) =
                kept.iter().fold((0.0, 0.0), |(tt, to), s| (tt + (s.t - mt).powi(2), to + (s.t - mt) * (s.off - mo)));
            let b = if stt > 0.0 { sto / stt } else { 0.0 };
            let settled = kept == line.kept;
            line = EdgeLine {
                a: mo - b * mt,
                b,
                rms_mm: 0.0,
                t_range: extent(kept.iter().map(|s| s.t)),
                dropped: samples.len() - kept.len(),
                kept,
            };
            line.rms_mm = rms(line.kept.iter().map(|s| s.off - line.at(s.t)));
            if settled {
                break;
            }
        }
        Some(line)
    }
}

fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

/// A plane fitted to a face's points, refitted without its outliers.
#[derive(Debug, Clone)]
pub(super) struct FaceFit {
    pub plane: Plane,
    pub centroid: Vec3,
    pub inliers: Vec<Vec3>,
    pub rms_mm: f64,
    pub dropped: usize,
}

/// Least squares (the scatter's least axis), then refits without the
/// points further than `trim_sigma` residuals from the plane.
pub(super) fn fit_face(points: &[Vec3], trim_sigma: f64) -> Option<FaceFit> {
    let mut inliers: Vec<Vec3> = points.to_vec();
    let mut fit = None;
    for _ in 0..=FACE_REFITS {
        let moments: Moments = inliers.iter().collect();
        let plane = moments.plane()?;
        let centroid = moments.centroid()?;
        let rms_mm = rms(inliers.iter().map(|p| plane.signed_distance(p)));
        fit =
            Some(FaceFit { plane, centroid, inliers: inliers.clone(), rms_mm, dropped: points.len() - inliers.len() });
        let limit = trim_sigma * rms_mm;
        let kept: Vec<Vec3> = points.iter().filter(|p| plane.signed_distance(p).abs() <= limit).copied().collect();
        if kept.len() == inliers.len() || kept.len() < MIN_FACE_POINTS {
            break;
        }
        inliers = kept;
    }
    fit
}

/// The face points' spread in height and along the root.
struct FaceSpread {
    mean_h: f64,
    var_h: f64,
    mean_t: f64,
    var_t: f64,
}

impl FaceSpread {
    fn of(points: &[Vec3], height: impl Fn(&Vec3) -> f64, along: impl Fn(&Vec3) -> f64) -> FaceSpread {
        let n = points.len().max(1) as f64;
        let (hs, ts): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (height(p), along(p))).unzip();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
        let var = |v: &[f64], m: f64| (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).max(f64::MIN_POSITIVE);
        let (mean_h, mean_t) = (mean(&hs), mean(&ts));
        FaceSpread { mean_h, var_h: var(&hs, mean_h), mean_t, var_t: var(&ts, mean_t) }
    }
}

/// The stretch of the root seen: the longest run of stations holding both
/// kinds of evidence, across breaks of at most
/// [`JOINT_BREAK_SPACINGS`], its ends at the last evidence inward.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SeenRun {
    s0: f64,
    s1: f64,
    coverage: [f64; 2],
    share: f64,
    seen_mm: f64,
}

/// The face's foot at each station along the root (`along`, stations of
/// [`STATION_SPACINGS`]): the face points up to [`FOOT_BAND_SPACINGS`]
/// above the lowest face point of their own station. A face turned nearly
/// edge-on to the camera or the projector returns points only where it is
/// turned a little less, above a line slanting along the root (the angle
/// of incidence changes along it): under the face's single lowest point
/// the foot would hold part of the root only.
fn station_feet(
    points: &[Vec3],
    along: impl Fn(&Vec3) -> f64,
    height: impl Fn(&Vec3) -> f64,
    spacing: f64,
) -> Vec<Vec3> {
    let width = STATION_SPACINGS * spacing;
    let station = |p: &Vec3| (along(p) / width).floor() as i64;
    let mut lowest: HashMap<i64, f64> = HashMap::new();
    for p in points {
        let h = height(p);
        lowest.entry(station(p)).and_modify(|low| *low = low.min(h)).or_insert(h);
    }
    let band = FOOT_BAND_SPACINGS * spacing;
    points.iter().copied().filter(|p| lowest.get(&station(p)).is_some_and(|&low| height(p) <= low + band)).collect()
}

/// How far beyond each end of the stretch `(s0, s1)` the joint is still
/// seen, mm: over the stations on from each end (across breaks no longer
/// than [`JOINT_BREAK_SPACINGS`]) holding both a point of the web's top
/// (`top`, along the root) and a flange point beside the root (`flange`),
/// to the outermost place both reach.
fn joint_beyond_run(top: &[f64], flange: &[f64], (s0, s1): (f64, f64), spacing: f64) -> [f64; 2] {
    let width = STATION_SPACINGS * spacing;
    let station = |s: f64| (s / width).floor() as i64;
    let extents = |samples: &[f64]| {
        let mut at: HashMap<i64, (f64, f64)> = HashMap::new();
        for &s in samples {
            at.entry(station(s)).and_modify(|(lo, hi)| (*lo, *hi) = (lo.min(s), hi.max(s))).or_insert((s, s));
        }
        at
    };
    let (top_at, flange_at) = (extents(top), extents(flange));
    let both = |k: i64| top_at.get(&k).zip(flange_at.get(&k));
    let max_break = (JOINT_BREAK_SPACINGS * spacing / width).floor() as i64;
    // The outermost station seen from `from` on in direction `step`.
    let outermost = |from: i64, step: i64| {
        let (mut k, mut last, mut missed) = (from, None, 0);
        while missed <= max_break {
            if both(k).is_some() {
                (last, missed) = (Some(k), 0);
            } else {
                missed += 1;
            }
            k += step;
        }
        last.and_then(both)
    };
    let before = outermost(station(s0), -1).map_or(0.0, |(t, f)| (s0 - t.0.max(f.0)).max(0.0));
    let after = outermost(station(s1), 1).map_or(0.0, |(t, f)| (t.1.min(f.1) - s1).max(0.0));
    [before, after]
}

fn seen_run(foot: &[f64], flange: &[f64], spacing: f64) -> Option<SeenRun> {
    let (lo, hi) = extent(foot.iter().chain(flange).copied());
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let width = (STATION_SPACINGS * spacing).max((hi - lo) / MAX_STATIONS as f64).max(f64::MIN_POSITIVE);
    let stations = (((hi - lo) / width).floor() as usize + 1).min(MAX_STATIONS);
    let station = |s: f64| (((s - lo) / width).floor() as usize).min(stations - 1);
    let mut has = vec![[false; 2]; stations];
    foot.iter().for_each(|&s| has[station(s)][0] = true);
    flange.iter().for_each(|&s| has[station(s)][1] = true);
    let seen: Vec<bool> = has.iter().map(|h| h[0] && h[1]).collect();
    // Runs of seen stations joined across short breaks.
    let max_break = ((JOINT_BREAK_SPACINGS * spacing) / width).floor() as usize;
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for k in (0..stations).filter(|&k| seen[k]) {
        match runs.last_mut() {
            Some((_, last)) if k - *last - 1 <= max_break => *last = k,
            _ => runs.push((k, k)),
        }
    }
    let &(first, last) = runs.iter().max_by_key(|(a, b)| b - a)?;
    let all_seen = runs.iter().map(|(a, b)| b - a + 1).sum::<usize>();
    let in_run = |k: usize| (first..=last).contains(&k);
    let (run_lo, run_hi) = (lo + first as f64 * width, lo + (last + 1) as f64 * width);
    let inside = |v: &[f64]| v.iter().copied().filter(|s| (run_lo..run_hi).contains(s)).collect::<Vec<f64>>();
    let (foot_in, flange_in) = (inside(foot), inside(flange));
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (s0, s1) = (min(&foot_in).max(min(&flange_in)), max(&foot_in).min(max(&flange_in)));
    if s1 <= s0 {
        return None;
    }
    let count = (last - first + 1) as f64;
    let share_of = |j: usize| (first..=last).filter(|&k| in_run(k) && has[k][j]).count() as f64 / count;
    let seen_mm = all_seen as f64 * width;
    Some(SeenRun { s0, s1, coverage: [share_of(0), share_of(1)], share: ((s1 - s0) / seen_mm).min(1.0), seen_mm })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the web stands across the camera's x: 200 mm to the camera's
    /// −x, so the camera (at the origin, looking down +z) sees its +x face.
    const WEB_X: f64 = -200.0;

    /// A web face standing on a flange: the flange z = 700, the face x =
    /// WEB_X + 5, points on the face from 1 to 39 mm above the flange,
    /// along y from −50 to 49.
    fn face_points(noise: f64) -> Vec<Vec3> {
        let mut pts = Vec::new();
        for i in 0..100 {
            for j in 0..20 {
                let jitter = noise * (((i * 7 + j * 13) % 11) as f64 / 5.0 - 1.0);
                pts.push(Vec3::new(WEB_X + 5.0 + jitter, -50.0 + i as f64, 700.0 - 1.0 - 2.0 * j as f64));
            }
        }
        pts
    }

    #[test]
    fn a_face_is_fitted_through_its_outliers_and_its_residual_reported() {
        let mut pts = face_points(0.05);
        // A few stray returns a centimetre off the face.
        pts.extend((0..20).map(|k| Vec3::new(WEB_X + 15.0, k as f64, 690.0)));
        let fit = fit_face(&pts, 3.0).unwrap();
        assert!(fit.dropped >= 20, "{} dropped", fit.dropped);
        assert!(fit.rms_mm < 0.06, "{}", fit.rms_mm);
        assert!((fit.plane.normal.x.abs() - 1.0).abs() < 1e-4, "{:?}", fit.plane.normal);
        assert!((fit.plane.signed_distance(&Vec3::new(WEB_X + 5.0, 0.0, 690.0))).abs() < 0.01);
    }

    #[test]
    fn the_root_is_where_the_face_meets_the_flange_and_runs_where_both_are_seen() {
        // A 40 mm web 10 mm thick centred on x = WEB_X: its top at z = 660
        // 4 mm either side of it (a trimmed rim of 1 mm), its +x face 5 mm
        // out, seen from y = −50 to 49; the flange seen at z = 700 from the
        // face outward, but only for y < 20 beside the face; the −x side
        // shows no face, and the flange from the edge of the web's shadow
        // on (where the camera's ray over the top's edge lands).
        let shadow_edge = (WEB_X - 4.0) * 700.0 / 660.0;
        let mut pts = face_points(0.0);
        for i in 0..100 {
            for j in 0..=8 {
                pts.push(Vec3::new(WEB_X - 4.0 + j as f64, -50.0 + i as f64, 660.0));
            }
            for j in 0..30 {
                let y = -50.0 + i as f64;
                if y < 20.0 {
                    pts.push(Vec3::new(WEB_X + 5.0 + 0.5 * j as f64, y, 700.0));
                }
                pts.push(Vec3::new(shadow_edge - j as f64, y, 700.0));
            }
        }
        let roots = roots_of(&pts);
        let seen: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
        assert_eq!(seen.len(), 1, "{roots:?}");
        let root = seen[0];
        // The root is x = WEB_X + 5, z = 700, from y = −50 to the flange's
        // end at 19, on the side facing the camera.
        assert_eq!(root.side, Side::Near);
        for s in [root.line.s_min, root.line.s_max] {
            let p = root.line.at(s);
            assert!((p.x - WEB_X - 5.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
        }
        let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 19.0).abs() < 1e-6, "{ends:?}");
        assert!((root.web_angle_deg - 90.0).abs() < 1e-6, "{}", root.web_angle_deg);
        assert!((root.web_height_mm - 40.0).abs() < 1e-6);
        assert!(root.coverage.iter().all(|c| *c > 0.99), "{:?}", root.coverage);
        assert!(root.away_from_web().x > 0.99);
        // The other side: no face seen, so no root, and the reason says so.
        let hidden = roots.iter().find_map(|r| r.as_ref().err()).unwrap();
        assert_eq!(hidden.side, Side::Far);
        assert!(hidden.reason.contains("far side") && hidden.reason.contains("hidden by the web"), "{}", hidden.reason);
    }

    #[test]
    fn a_flange_in_one_piece_round_the_webs_end_is_seen_on_both_sides() {
        // The web of the test above, its +x face seen; the flange one plane
        // on both sides, joined beyond the web's end (y from 50 to 60), far
        // wider on the -x side, so the piece's centroid lies there. The +x
        // root is still read: the flange's points lie on that side too.
        let mut pts = face_points(0.0);
        for i in 0..100 {
            let y = -50.0 + i as f64;
            for j in 0..=8 {
                pts.push(Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0));
            }
            for j in 0..30 {
                pts.push(Vec3::new(WEB_X + 5.0 + 0.5 * j as f64, y, 700.0));
            }
            for j in 0..120 {
                pts.push(Vec3::new(WEB_X - 30.0 - j as f64, y, 700.0));
            }
        }
        for i in 0..10 {
            for j in 0..170 {
                pts.push(Vec3::new(WEB_X + 20.0 - j as f64, 50.0 + i as f64, 700.0));
            }
        }
        let flange = |p: &Vec3| p.z == 700.0;
        let on_flange: Vec<&Vec3> = pts.iter().filter(|p| flange(p)).collect();
        let mean_x = on_flange.iter().map(|p| p.x).sum::<f64>() / on_flange.len() as f64;
        assert!(mean_x < WEB_X - 4.0, "the piece's centroid lies on the -x side: {mean_x}");
        let roots = roots_with_flange_pieces(&pts, &[&flange]);
        let seen: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
        assert_eq!(seen.len(), 1, "{roots:?}");
        let root = seen[0];
        assert_eq!(root.side, Side::Near);
        assert!((root.line.at(root.line.s_min).x - WEB_X - 5.0).abs() < 1e-6);
        let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
        // The -x side shows no face, and its flange stops short of the web:
        // not planned, and not for want of a flange on that side.
        let hidden = roots.iter().find_map(|r| r.as_ref().err()).unwrap();
        assert_eq!(hidden.side, Side::Far);
        assert!(hidden.flange_seen, "{}", hidden.reason);
    }

    #[test]
    fn a_web_seen_by_one_face_only_gives_that_face_s_root_and_names_the_other() {
        // The face of the tests above, x = WEB_X + 5, seen from 1 to 39 mm
        // over the flange; no web's top; the flange seen on both sides.
        let mut pts = face_points(0.0);
        for i in 0..100 {
            let y = -50.0 + i as f64;
            pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
            pts.extend((0..30).map(|j| Vec3::new(WEB_X - 10.0 - j as f64, y, 700.0)));
        }
        let cloud = cloud_of(&pts);
        let flange = PlaneCluster::of_points(&pts, |p| p.z == 700.0);
        let face = StandingFace {
            plane: Plane { normal: Vec3::x(), offset: WEB_X + 5.0 },
            centroid: Vec3::new(WEB_X + 5.0, 0.0, 680.0),
            flange: flange.plane,
            points: 2000,
            seen_height_mm: 39.0,
        };
        let roots = find_roots(&test_view(&cloud, Web::Face(&face), &[&flange]));
        let seen: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
        assert_eq!(seen.len(), 1, "{roots:?}");
        let root = seen[0];
        assert_eq!((root.side, root.evidence), (Side::Near, RootEvidence::Face));
        for s in [root.line.s_min, root.line.s_max] {
            let p = root.line.at(s);
            assert!((p.x - WEB_X - 5.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
        }
        let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
        assert!(root.away_from_web().x > 0.99);
        assert!((root.web_height_mm - 39.0).abs() < 1e-9);
        // The other face is not looked for: with the top out of view
        // nothing places it, and the web hides it.
        let other = roots.iter().find_map(|r| r.as_ref().err()).unwrap();
        assert_eq!(other.side, Side::Far);
        assert!(other.flange_seen);
        assert!(other.reason.contains("top is out of view"), "{}", other.reason);
    }

    /// A tee whose +x face (x = WEB_X + 5) returns points only from
    /// `lowest(y)` up to 39 mm over the flange, along y from −50 to 49;
    /// its top (z = 660) and the flange up to the root (z = 700) seen on
    /// both sides along the same stretch, every point `keep` keeps.
    fn tee_with_face_seen_above(lowest: impl Fn(f64) -> f64, keep: impl Fn(&Vec3) -> bool) -> Vec<Vec3> {
        let mut pts = Vec::new();
        for i in 0..100 {
            let y = -50.0 + i as f64;
            pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
            pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
            pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
            pts.extend(
                (0..20)
                    .map(|j| 1.0 + 2.0 * j as f64)
                    .filter(|&h| h >= lowest(y))
                    .map(|h| Vec3::new(WEB_X + 5.0, y, 700.0 - h)),
            );
        }
        pts.retain(keep);
        pts
    }

    /// The tee of `pts` to read roots in: the web's top the points at
    /// z = 660, the flange's pieces those at z = 700 either side of WEB_X.
    fn tee_parts(pts: &[Vec3]) -> (PointCloud, PlaneCluster, [PlaneCluster; 2]) {
        let sides = [
            PlaneCluster::of_points(pts, |p| p.z == 700.0 && p.x > WEB_X),
            PlaneCluster::of_points(pts, |p| p.z == 700.0 && p.x < WEB_X),
        ];
        (cloud_of(pts), PlaneCluster::of_points(pts, |p| p.z == 660.0), sides)
    }

    /// The root of `roots` on the web's +x face ([`assert_on_plus_x_face`]).
    fn plus_x_face_root(roots: &[Result<Root, RootNotSeen>]) -> Root {
        let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera").clone();
        assert_on_plus_x_face(&root);
        root
    }

    /// Asserts `root` is read from the web's +x face and lies on the
    /// face's line x = WEB_X + 5, z = 700.
    fn assert_on_plus_x_face(root: &Root) {
        assert_eq!(root.evidence, RootEvidence::Face);
        for s in [root.line.s_min, root.line.s_max] {
            let p = root.line.at(s);
            assert!((p.x - WEB_X - 5.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
        }
    }

    fn ends_y(root: &Root) -> [f64; 2] {
        [root.line.s_min, root.line.s_max].map(|s| root.line.at(s).y)
    }

    #[test]
    fn a_face_seen_higher_up_along_the_web_gives_its_root_all_along() {
        // The face's lowest return rises from 1 mm over the flange (y < 0)
        // to 25 mm (y = 49), as where the face turns past the grazing angle
        // the sensor returns: the root runs the web's length, not only
        // where the face is seen within its foot's band of its lowest point.
        let pts = tee_with_face_seen_above(|y| if y < 0.0 { 1.0 } else { 1.0 + 0.5 * y }, |_| true);
        let (cloud, top, [plus, minus]) = tee_parts(&pts);
        let root = plus_x_face_root(&find_roots(&test_view(&cloud, Web::Top(&top), &[&plus, &minus])));
        let ends = ends_y(&root);
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
        assert_eq!(root.joint_beyond_ends_mm, Some([0.0, 0.0]));
    }

    #[test]
    fn the_web_and_the_flange_seen_past_the_face_s_end_are_reported_beyond_the_root() {
        // The face returns nothing for y > 20 while the web's top and the
        // flange up to the root go on to y = 49: the face's root is read
        // where the face is seen, and the 29 mm of joint beyond it reported
        // (for the flange's edge to be read instead, and the quality gate
        // to refuse a root stopping short).
        let pts = tee_with_face_seen_above(|y| if y <= 20.0 { 1.0 } else { f64::INFINITY }, |_| true);
        let (cloud, top, [plus, minus]) = tee_parts(&pts);
        let pieces = [&plus, &minus];
        let view = test_view(&cloud, Web::Top(&top), &pieces);
        let frame = web_frame(&view).expect("the web's frame");
        let sign = frame.u.x.signum();
        let root = root_from_face(&view, &frame, sign, side_seen(&frame, sign)).expect("the +x face's root");
        assert_on_plus_x_face(&root);
        let ends = ends_y(&root);
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 20.0).abs() < 1e-6, "{ends:?}");
        let [before, after] = root.joint_beyond_ends_mm.expect("measured under a web's top");
        assert_eq!(before, 0.0);
        assert!((after - 29.0).abs() < 1e-6, "{after}");
    }

    #[test]
    fn a_root_runs_to_the_image_border_past_where_the_border_cuts_its_face() {
        // The face seen from 20 mm over the flange up; the image's border
        // slanting so that what stands higher leaves the view sooner: the
        // root (z = 700) is in view for y < 45, the face's lowest returns
        // (z = 680) for y < 35, the web's top for y < 25. The root runs on
        // along the flange up to it, to within a step of where it leaves
        // the view.
        let in_view = |p: &Vec3| p.y < 45.0 + 0.5 * (p.z - 700.0);
        let pts = tee_with_face_seen_above(|_| 20.0, in_view);
        let (cloud, top, [plus, minus]) = tee_parts(&pts);
        let pieces = [&plus, &minus];
        let view = test_view(&cloud, Web::Top(&top), &pieces);
        let ends = ends_y(&plus_x_face_root(&find_roots(&TeeView { in_view: Some(&in_view), ..view })));
        assert!((ends[0] + 50.0).abs() < 1e-6, "{ends:?}");
        assert!((44.5..45.0).contains(&ends[1]), "{ends:?}");
        // Without the grid nothing says the border cut the face: the root
        // ends where its face's foot is seen.
        let ends = ends_y(&plus_x_face_root(&find_roots(&view)));
        assert!((ends[1] - 34.0).abs() < 1e-6, "{ends:?}");
    }

    /// The roots [`find_roots`] reads from `pts`: the web's top the points
    /// at z = 660, the flange's pieces those at z = 700 either side of
    /// x = WEB_X, a point spacing of 1 mm.
    fn roots_of(pts: &[Vec3]) -> [Result<Root, RootNotSeen>; 2] {
        roots_of_web_at(pts, WEB_X)
    }

    fn roots_of_web_at(pts: &[Vec3], web_x: f64) -> [Result<Root, RootNotSeen>; 2] {
        roots_with_flange_pieces(
            pts,
            &[&|p: &Vec3| p.z == 700.0 && p.x > web_x, &|p: &Vec3| p.z == 700.0 && p.x < web_x],
        )
    }

    /// The roots [`find_roots`] reads from `pts` with the web's top the
    /// points at z = 660 and a flange piece of the points each of `pieces`
    /// picks.
    fn roots_with_flange_pieces(pts: &[Vec3], pieces: &[&dyn Fn(&Vec3) -> bool]) -> [Result<Root, RootNotSeen>; 2] {
        let cloud = cloud_of(pts);
        let top = PlaneCluster::of_points(pts, |p| p.z == 660.0);
        let clusters: Vec<PlaneCluster> = pieces.iter().map(|pick| PlaneCluster::of_points(pts, pick)).collect();
        let pieces: Vec<&PlaneCluster> = clusters.iter().collect();
        find_roots(&test_view(&cloud, Web::Top(&top), &pieces))
    }

    fn cloud_of(pts: &[Vec3]) -> PointCloud {
        PointCloud::unorganized(pts.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect())
    }

    /// The tee of `web` on `flange_pieces` in `cloud`: a point spacing of
    /// 1 mm, a 1 mm rim trimmed, the default tolerances, no image border.
    fn test_view<'a>(cloud: &'a PointCloud, web: Web<'a>, flange_pieces: &'a [&'a PlaneCluster]) -> TeeView<'a> {
        TeeView {
            cloud,
            web,
            flange_pieces,
            point_spacing_mm: 1.0,
            rim_mm: 1.0,
            on_plane_mm: 0.4,
            trim_sigma: 3.0,
            projector: Vec3::new(150.0, 0.0, 0.0),
            in_view: None,
            border: None,
            max_beyond_mm: 2.0,
        }
    }

    #[test]
    fn a_face_edge_on_to_the_camera_gives_its_root_from_the_flange_edge_and_a_shadow_edge_gives_none() {
        // The web of the test above with no face points at all: its +x
        // root at x = WEB_X + 4 is read from the flange's edge there. On
        // the −x side the flange is seen from where the camera's ray over
        // the top's edge (x = WEB_X − 4, z = 660) lands on it: the shadow's
        // edge, which must not be taken for a root.
        let shadow_edge = (WEB_X - 4.0) * 700.0 / 660.0;
        let mut pts = Vec::new();
        for i in 0..100 {
            let y = -50.0 + i as f64;
            for j in 0..=8 {
                pts.push(Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0));
            }
            for j in 0..30 {
                pts.push(Vec3::new(WEB_X + 4.0 + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0));
                pts.push(Vec3::new(shadow_edge - 0.5 * j as f64, y, 700.0));
            }
        }
        let roots = roots_of(&pts);
        let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera").clone();
        let hidden = roots.iter().find_map(|r| r.as_ref().err()).expect("the shadowed root refused");
        assert!(matches!(root.evidence, RootEvidence::FlangeEdge { view_margin_deg, .. } if view_margin_deg > 10.0));
        for s in [root.line.s_min, root.line.s_max] {
            let p = root.line.at(s);
            assert!((p.x - WEB_X - 4.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
        }
        let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
        assert!((root.web_angle_deg - 90.0).abs() < 1e-6, "{}", root.web_angle_deg);
        assert!(hidden.reason.contains("shadow"), "{}", hidden.reason);
    }

    /// The ends (y) of the root [`roots_of`] reads from `pts` on the web's
    /// camera side, which must come from the flange's edge and lie on the
    /// line x = WEB_X + 4, z = 700 (the edge-on web of the tests below).
    fn flange_edge_root_ends(pts: &[Vec3]) -> [f64; 2] {
        let roots = roots_of(pts);
        let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera");
        assert!(matches!(root.evidence, RootEvidence::FlangeEdge { .. }), "{:?}", root.evidence);
        [root.line.s_min, root.line.s_max].map(|s| {
            let p = root.line.at(s);
            assert!((p.x - WEB_X - 4.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
            p.y
        })
    }

    #[test]
    fn the_webs_end_face_is_no_side_face_and_the_root_runs_to_the_webs_end() {
        // The web of the test above, its top from y = −50 to 47 and its
        // +x root at x = WEB_X + 4 seen only on the flange's edge (the side
        // face edge-on). Its end face, across the web at y = 47.5, returns
        // points on both sides of its middle; past it the flange runs on
        // under where the web would stand, so the station holding the
        // web's end holds flange points off the root's line.
        let mut pts = Vec::new();
        for i in 0..110 {
            let y = -50.0 + i as f64;
            if y <= 47.0 {
                pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
            } else {
                pts.extend((0..14).map(|j| Vec3::new(WEB_X - 10.0 + j as f64, y, 700.0)));
            }
            pts.extend((0..30).map(|j| Vec3::new(WEB_X + 4.0 + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0)));
        }
        // The end cut 17° off square, so that the camera sees it.
        for h in 1..40 {
            pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, 47.5 + 0.3 * j as f64, 700.0 - h as f64)));
        }
        // From the flange's first point to the web top's last: not a
        // station (4 mm) short of the web's end.
        let ends = flange_edge_root_ends(&pts);
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 47.0).abs() < 1e-6, "{ends:?}");
    }

    #[test]
    fn a_web_top_seen_all_along_the_root_covers_it_whatever_its_stations() {
        // The edge-on web of the test before last, its top seen every
        // 0.5 mm from y = −50, its edge's points a few hundredths of a
        // millimetre in or out, the flange from y = −48: the top's edge
        // covers the root all along, though its outermost point in each
        // station, one to a station at a place of its own, left some of
        // the coverage gate's stations (as wide, from the root's start)
        // empty.
        let mut pts = Vec::new();
        for i in 0..200 {
            let y = -50.0 + 0.5 * i as f64;
            pts.extend((0..8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
            pts.push(Vec3::new(WEB_X + 4.0 - 0.01 * ((i * 37) % 11) as f64, y, 660.0));
            if y >= -48.0 {
                pts.extend((0..30).map(|j| Vec3::new(WEB_X + 4.0 + 0.5 * j as f64, y, 700.0)));
            }
            pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
        }
        let roots = roots_of(&pts);
        let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera");
        assert!(matches!(root.evidence, RootEvidence::FlangeEdge { .. }), "{:?}", root.evidence);
        assert!(root.coverage.iter().all(|c| *c > 0.99), "{:?}", root.coverage);
    }

    /// Row `i` (y = −50 + i) of an edge-on web: its top (z = 660) 8 mm
    /// wide round WEB_X, the flange (z = 700) from its +x root at
    /// x = WEB_X + 4 outward, every other row's points half a step out, and
    /// from 26 mm off on its −x side.
    fn edge_on_web_row(i: usize) -> impl Iterator<Item = Vec3> {
        let y = -50.0 + i as f64;
        let top = (0..=8).map(move |j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0));
        let plus = (0..30).map(move |j| Vec3::new(WEB_X + 4.0 + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0));
        let minus = (0..30).map(move |j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0));
        top.chain(plus).chain(minus)
    }

    #[test]
    fn a_face_seen_along_part_of_the_web_gives_way_to_the_flanges_edge() {
        // The edge-on web of the tests above, its +x face (x = WEB_X + 4)
        // returning points only along part of the web, its flange seen up
        // to the root all along: the root runs the web's length, from the
        // flange's edge. Seen from y = 44 to 49, the face's root is 5 mm
        // long; seen from y = −50 to 20 (71 % of the web's top), the web's
        // top and the flange up to the root go on 29 mm past it.
        for face_seen in [44.0..=49.0, -50.0..=20.0] {
            let mut pts = Vec::new();
            for i in 0..100 {
                let y = -50.0 + i as f64;
                pts.extend(edge_on_web_row(i));
                if face_seen.contains(&y) {
                    pts.extend((0..20).map(|j| Vec3::new(WEB_X + 4.0, y, 699.0 - 2.0 * j as f64)));
                }
            }
            let ends = flange_edge_root_ends(&pts);
            assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{face_seen:?}: {ends:?}");
        }
    }

    #[test]
    fn a_web_axis_off_the_web_is_read_again_along_the_flange_s_edge() {
        // The edge-on web of the tests above, 200 mm long (y from −50 to
        // 149), the image's border cutting its top (z = 660) at y = 20 but
        // the flange (z = 700) only past the web's end. The top's long axis
        // is taken 3° off the web, as from a top the border cuts
        // obliquely: the flange's edge at x = WEB_X + 4, looked for outward
        // of the web's middle line along that axis, crosses that line about
        // 75 mm past the top's middle. Read again along the edge's own
        // line, the root runs the web's length on the edge.
        let in_view = |p: &Vec3| p.y < 20.0 + 4.0 * (p.z - 660.0);
        let mut pts = Vec::new();
        for i in 0..200 {
            pts.extend(edge_on_web_row(i));
        }
        pts.retain(in_view);
        let (cloud, mut top, [plus, minus]) = tee_parts(&pts);
        let skew = 3f64.to_radians();
        top.long_axis = Vec3::new(skew.sin(), skew.cos(), 0.0);
        let pieces = [&plus, &minus];
        let view = TeeView { in_view: Some(&in_view), ..test_view(&cloud, Web::Top(&top), &pieces) };
        let roots = find_roots(&view);
        let root = roots.iter().find_map(|r| r.as_ref().ok()).unwrap_or_else(|| panic!("{roots:?}"));
        assert!(matches!(root.evidence, RootEvidence::FlangeEdge { .. }), "{:?}", root.evidence);
        for s in [root.line.s_min, root.line.s_max] {
            let p = root.line.at(s);
            assert!((p.x - WEB_X - 4.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
        }
        // (Along the edge's fitted line: its ends to a few hundredths.)
        let ends = ends_y(root);
        assert!((ends[0] + 50.0).abs() < 0.05 && (ends[1] - 149.0).abs() < 0.05, "{ends:?}");
    }

    #[test]
    fn a_face_that_gives_no_root_leaves_it_to_the_flanges_edge() {
        // The edge-on web of the tests above, its +x face (x = WEB_X + 4)
        // returning points only from y = −50 to −30, where a dropout takes
        // the flange's first 10 mm beside the root: the face's foot and the
        // flange up to it are seen together nowhere, and the root is read
        // from the flange's edge where that is seen, from y = −28 on.
        let mut pts = Vec::new();
        for i in 0..100 {
            let y = -50.0 + i as f64;
            pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
            let from = if y < -28.0 { WEB_X + 14.0 } else { WEB_X + 4.0 };
            pts.extend((0..30).map(|j| Vec3::new(from + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0)));
            pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
            if y <= -30.0 {
                pts.extend((0..20).map(|j| Vec3::new(WEB_X + 4.0, y, 699.0 - 2.0 * j as f64)));
            }
        }
        let ends = flange_edge_root_ends(&pts);
        assert!((ends[0] + 28.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
    }

    #[test]
    fn a_flange_ending_at_the_projectors_shadow_gives_no_root() {
        // A web between the camera (x = 0) and the projector (x = 150),
        // its top from x = 71 to 79 at z = 660, no face points: the camera
        // looks at its −x face, which the projector does not light, so the
        // flange there is seen from where the projector's ray over the
        // top's edge lands; on the +x side, from where the camera's does.
        let lit_from = 150.0 + (71.0 - 150.0) * 700.0 / 660.0;
        let seen_from = 79.0 * 700.0 / 660.0;
        let mut pts = Vec::new();
        for i in 0..100 {
            let y = -50.0 + i as f64;
            pts.extend((0..=8).map(|j| Vec3::new(71.0 + j as f64, y, 660.0)));
            for j in 0..30 {
                pts.push(Vec3::new(lit_from - 0.5 * j as f64, y, 700.0));
                pts.push(Vec3::new(seen_from + 0.5 * j as f64, y, 700.0));
            }
        }
        for root in roots_of_web_at(&pts, 75.0) {
            let not_seen = root.expect_err("a shadow's edge is no root");
            assert!(not_seen.reason.contains("shadow"), "{}", not_seen.reason);
        }
    }

    #[test]
    fn the_run_seen_bridges_short_breaks_and_not_long_ones() {
        // Evidence every 0.5 mm from 0 to 40 and 44 to 60 (a 4 mm break,
        // bridged), then 100 to 110 (a 40 mm break, not).
        let s: Vec<f64> = (0..=220)
            .map(|k| k as f64 * 0.5)
            .filter(|s| (0.0..=40.0).contains(s) || (44.0..=60.0).contains(s) || *s >= 100.0)
            .collect();
        let run = seen_run(&s, &s, 0.5).unwrap();
        assert_eq!((run.s0, run.s1), (0.0, 60.0));
        assert!(run.share < 1.0 && run.share > 0.8, "{}", run.share);
        assert!(run.coverage[0] < 1.0);
        // Nothing seen together: no run.
        assert!(seen_run(&[0.0, 1.0], &[50.0, 51.0], 0.5).is_none());
    }
}
