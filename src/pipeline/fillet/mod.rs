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
//!   `trim_sigma` standard deviations from it, the scale read from the
//!   median residual so that what shares the band (a tube's rounded
//!   corners, parts past the face's ends) cannot widen it, until the kept
//!   points settle; the residual is reported;
//! - the root: the line where the face `m·p = d_m` meets the flange,
//!   direction `r = n × m`, through the point of both planes nearest the
//!   web top's centroid (a 2 × 2 solve in the span of `n` and `m`). The
//!   flange there is the flange where the face stands on it: its height
//!   and its tilt along the root read from its points beside the root,
//!   its tilt across from all its pieces ([`flange_at_root`]), as a real
//!   flange lies off one plane by as much as the root's tolerance;
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
//!
//! The stage's files: `frame.rs` the web's frame (where its top and the
//! flange lie), `face.rs` the root from the web's side face, `flange_edge.rs`
//! the root from the flange's edge against the web, `stretch.rs` the
//! stretch of a root seen and where its ends lie; this file the types and
//! the entry point, [`find_roots`], which picks the evidence for each root.

mod face;
mod flange_at_root;
mod flange_edge;
mod frame;
#[cfg(test)]
mod member_tests;
#[cfg(test)]
mod noisy_flange_tests;
mod stretch;
#[cfg(test)]
mod tests;

use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, extent, vec3};

use super::background::PlaneCluster;
use super::refit::SeamCurve;
use super::straightness::RootBend;
use super::view_border::ViewBorder;
use super::web_face::StandingFace;
use crate::rules::Rule;
use crate::rules::refit::{
    TEE_ROOT_HIDDEN_BY_WEB, TEE_ROOT_NOT_SEEN, TEE_SHORT_FACE_GIVES_WAY_TO_FLANGE_EDGE, TEE_WEB_NOT_OVER_FLANGE,
};

use face::root_from_face;
use flange_edge::root_from_flange_edge;
use frame::{WebFrame, side_seen, web_frame};

pub use face::MIN_FACE_VIEW_DEG;
pub(super) use face::{FaceFit, fit_face};
pub(super) use frame::{flange_plane, height_margin, valid_points};

/// The fewest face points that make a face: a handful of returns on a web
/// face seen edge-on fix no plane.
pub const MIN_FACE_POINTS: usize = 30;

/// The least share of the web top's length a root read from the web's
/// face must run for the flange's edge not to be tried instead. A face
/// seen along most of the web places its root from thousands of points,
/// better than the flange's edge does; one seen along a few millimetres
/// places only those.
const MIN_FACE_RUN_SHARE: f64 = 0.5;

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
    /// The web is a member standing on the flange with every side a root
    /// (a block, its top found by the faces falling from it): its frame
    /// runs along its top's outline, and its ends' roots are read too.
    pub every_side: bool,
    /// The thickest web, mm (`pipeline.tee_web_thickness_max_mm`): a face
    /// seen without the web's top whose root runs no longer may be a web's
    /// end.
    pub web_thickness_max_mm: f64,
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
    /// How far the root's evidence bends from straight along the stretch
    /// (the larger of its two kinds', [`super::straightness`]), where the
    /// stretch holds stations enough to tell.
    pub bend: Option<RootBend>,
    /// The rules that moved or cut the root's ends from where its evidence
    /// first put them, in the order they applied.
    pub ends_set_by: Vec<&'static Rule>,
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

/// Why one kind of evidence gives no root (or, for [`super::web_face`],
/// no face): the rule that decided it, and the reason in words.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{reason}")]
pub struct NotRead {
    pub rule: &'static Rule,
    pub reason: String,
}

impl NotRead {
    pub fn by(rule: &'static Rule, reason: impl Into<String>) -> NotRead {
        NotRead { rule, reason: reason.into() }
    }

    /// The rule that decided the evidence gives nothing.
    pub fn rule(&self) -> &'static Rule {
        self.rule
    }
}

/// A root not seen, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct RootNotSeen {
    pub side: Side,
    pub sign: f64,
    /// The rule that left the root unplanned: where neither the face nor
    /// the flange's edge shows it, the edge's rule when the edge was
    /// refused for a reason of its own, else the face's.
    pub rule: &'static Rule,
    pub reason: String,
    /// Whether any of the flange lies on this side of the web (none does
    /// beside an inside corner's outer face).
    pub flange_seen: bool,
    /// Where the root would lie, roughly: at the web's foot on that side.
    pub near_camera: Vec3,
}

/// Finds both roots of the tee in `view`: `[−u side, +u side]`, each
/// fitted or said not to be seen.
pub fn find_roots(view: &TeeView) -> [Result<Root, RootNotSeen>; 2] {
    roots_in(view, false)
}

/// The roots at the ends of a member with every side a root
/// ([`TeeView::every_side`]): its top's other two sides' feet, read as
/// [`find_roots`] reads the two along it.
pub fn find_end_roots(view: &TeeView) -> [Result<Root, RootNotSeen>; 2] {
    roots_in(view, true)
}

fn roots_in(view: &TeeView, turned: bool) -> [Result<Root, RootNotSeen>; 2] {
    let Some(frame) = web_frame(view, turned) else {
        let why = "the flange's plane and the web give no frame to read the roots in".to_string();
        let near = view.web.centroid();
        return [-1.0, 1.0].map(|sign| {
            Err(RootNotSeen {
                side: Side::Above,
                sign,
                rule: &TEE_WEB_NOT_OVER_FLANGE,
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
                rule: &TEE_ROOT_HIDDEN_BY_WEB,
                reason: format!(
                    "{} is not planned: the web's top is out of view and only its face on the other side is seen; \
                     what stands behind that face (the web's far side and its root, or nothing where the member is a \
                     block) is hidden from the camera",
                    side.root_name(sign)
                ),
                near_camera: frame.origin + frame.n * frame.height_of(&frame.origin),
                flange_seen: frame.flange_on(sign),
            })
        }
        _ => find_root(view, &frame, sign),
    })
}

fn find_root(view: &TeeView, frame: &WebFrame, sign: f64) -> Result<Root, RootNotSeen> {
    let side = side_seen(frame, sign);
    // The web's foot on this side, where its root would lie.
    let foot_at = frame.origin
        + frame.u * (frame.middle + sign * (frame.half_width + view.rim_mm))
        + frame.n * frame.height_of(&frame.origin);
    let flange_seen = frame.flange_on(sign);
    let not_seen = |rule: &'static Rule, why: String| RootNotSeen {
        side,
        sign,
        rule,
        reason: format!("{} is not planned: {why}", side.root_name(sign)),
        near_camera: foot_at,
        flange_seen,
    };
    if !flange_seen {
        return Err(not_seen(
            &TEE_ROOT_HIDDEN_BY_WEB,
            "the flange on this side is not seen (hidden by the web)".into(),
        ));
    }
    if view.every_side {
        return member_root(view, frame, sign, side).map_err(|why| not_seen(why.rule, why.reason));
    }
    match root_from_face(view, frame, sign, side) {
        Ok(root) => Ok(face_or_flange_edge(view, frame, sign, side, root)),
        // A face turned edge-on to the camera returns nothing, or only the
        // mixed returns along the rays; one glimpsed where the flange
        // beside it is not seen gives no root either. The flange's edge may
        // still show the root; where it ends at a shadow's edge instead,
        // the edge's own test refuses it.
        Err(why) => root_from_flange_edge(view, frame, sign, side).map_err(|edge| {
            let rule = if *edge.rule == TEE_ROOT_NOT_SEEN { why.rule } else { edge.rule };
            not_seen(rule, format!("{why}; and the flange's edge does not show it: {edge}"))
        }),
    }
}

/// A root of a member with every side a root ([`TeeView::every_side`]):
/// read only from its side face, and only on a side the camera looks at
/// from outside the face. A block's faces are as far apart as its top is
/// wide: from over its top (or beyond its far side) the camera sees a
/// face from behind its plane, not at all, and the flange's edge it
/// sees there is where the block hides the flange, not the root (the
/// edge of a web a few millimetres thick lies over its root instead).
/// The joint along such a side runs as far as its top's edge is seen, so
/// the root's share of the joint is read against that length too: a
/// stretch of foot seen along a few millimetres of a block's side is not
/// the block's root.
fn member_root(view: &TeeView, frame: &WebFrame, sign: f64, side: Side) -> Result<Root, NotRead> {
    if side != Side::Near {
        return Err(NotRead::by(
            &TEE_ROOT_HIDDEN_BY_WEB,
            "the camera looks at the member's side face there from behind its plane (from over its top or beyond \
             it): the face is not seen, and the flange's edge beside it is where the member hides the flange",
        ));
    }
    let mut root = root_from_face(view, frame, sign, side)?;
    if let Web::Top(top) = view.web {
        let points = view.cloud.points();
        let (lo, hi) = extent(top.members.iter().map(|&i| (vec3(&points[i as usize]) - frame.origin).dot(&frame.e)));
        let span = root.line.s_max - root.line.s_min;
        if hi > lo && root.seen_mm < hi - lo {
            root.seen_share = root.seen_share.min(span / (hi - lo));
            root.seen_mm = hi - lo;
        }
    }
    Ok(root)
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
        Ok(mut edge) if span(&edge) > span(&root) => {
            edge.ends_set_by.push(&TEE_SHORT_FACE_GIVES_WAY_TO_FLANGE_EDGE);
            tracing::debug!(
                rule = TEE_SHORT_FACE_GIVES_WAY_TO_FLANGE_EDGE.id,
                face_mm = span(&root),
                edge_mm = span(&edge),
                "a face seen along a short stretch: the root from the flange's edge"
            );
            edge
        }
        _ => root,
    }
}
