//! Background removal (section 3.3): which plane clusters are the two
//! workpiece plates and which are the table or other background.
//!
//! The paper deletes the cluster with the largest xy bounding box. That
//! fails when the plates run off the image (the table splits and a table
//! piece is kept as a plate) and when the plates fill the view (a plate is
//! deleted). The robust rule uses what a cell guarantees instead: the
//! plates are parallel planes nearer the camera than whatever they rest
//! on. Butt plates are the nearest layer holding two coplanar clusters; a
//! lap is the nearest pair of layers one plate thickness apart; a tee is a
//! long narrow plane (the web's top) a web's height, more than any lap
//! step, over a layer it lies across, seen on both of its sides (the
//! flange).

use crate::cloud::{Point, PointCloud};
use crate::geometry::fit::{Moments, Plane};
use crate::geometry::{Vec3, extent, plane_axes, vec3};
use crate::joint::JointType;

use super::view_border::ViewBorder;
use super::web_face::MAX_FACE_LEAN_DEG;
use super::workpieces::MAX_JOINT_OPENING_MM;

/// A cluster of plane points with its fitted plane.
#[derive(Debug, Clone)]
pub struct PlaneCluster {
    /// The cluster's label in [`super::clustering::Clusters::labels`].
    pub label: u32,
    pub members: Vec<u32>,
    pub plane: Plane,
    pub centroid: Vec3,
    /// The area the points cover on their plane, mm².
    pub area_mm2: f64,
    /// The direction the points spread along most, and how many times
    /// further than across it: a bar lying on a plate is long and narrow.
    pub long_axis: Vec3,
    pub elongation: f64,
}

impl PlaneCluster {
    /// The cluster's plane, place and shape without its points.
    pub fn clone_shape(&self) -> PlaneCluster {
        PlaneCluster { members: Vec::new(), ..*self }
    }
}

#[cfg(test)]
impl PlaneCluster {
    /// The cluster of the points of `points` that `pick` keeps, each
    /// standing for a square millimetre: unit tests' planes.
    pub(crate) fn of_points(points: &[Vec3], pick: impl Fn(&Vec3) -> bool) -> PlaneCluster {
        use crate::geometry::fit::Moments;
        let members: Vec<u32> = (0..points.len() as u32).filter(|&i| pick(&points[i as usize])).collect();
        let moments: Moments = members.iter().map(|&i| &points[i as usize]).collect();
        let (long_axis, elongation) = moments.elongation().expect("two distinct points");
        PlaneCluster {
            label: 0,
            area_mm2: members.len() as f64,
            plane: moments.plane().expect("points spanning a plane"),
            centroid: moments.centroid().expect("points"),
            members,
            long_axis,
            elongation,
        }
    }
}

/// The two workpiece plates. For a lap joint `plates[0]` is the upper
/// plate and `plates[1]` the lower one (robust method; the paper's method
/// sorts them later by the depth of their edges).
#[derive(Debug, Clone)]
pub struct Workpiece {
    pub plates: [PlaneCluster; 2],
    /// How far behind the plates (the butt plates' top, or the lower lap
    /// plate) the next parallel surface lies, mm along the normal: the
    /// table or fixture they rest on, when the camera sees it. The plates
    /// are no thicker than this, so neither is a groove (robust method).
    pub depth_to_support_mm: Option<f64>,
    /// Whether that surface is only a narrow strip between butt plates
    /// (robust method): the joint's own floor (a V-groove's apex in a
    /// noisy cloud, the table seen through a gap), whose depth measures
    /// the groove rather than bounding it. A requested groove
    /// depth is then judged by the groove-depth gate against the measured
    /// one, not refused against this depth.
    pub support_between_plates: bool,
    /// The other clusters of each plate's layer (robust method): pieces
    /// of a plate a streak or a dropout split off, or whatever else lies
    /// in its plane. The coverage report joins those beside the weld that
    /// continue the plate across a narrow break, so a seam that stops
    /// where one piece ends is not taken for the whole joint. Butt plates
    /// share one layer, and so these.
    pub layer_mates: [Vec<PlaneCluster>; 2],
}

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
    /// which is seen on both of its long sides: a tee's web on its flange,
    /// or an object lying on the workpiece; not a plate of a butt or lap
    /// joint. The layers alone cannot tell the two apart.
    #[error(
        "a long plane of {top_mm2:.0} mm², {above_mm:.1} mm nearer the camera, lies across the plane under it, \
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
    /// over a plane beside it.
    #[error(
        "found {found} planes but no long narrow one (a web's top, at most {max_width_mm} mm wide) {min_mm} to \
         {max_mm} mm over a plane beside it (offsets {offsets_mm:?} mm) for a tee joint"
    )]
    NoWeb { found: usize, offsets_mm: Vec<f64>, min_mm: f64, max_mm: f64, max_width_mm: f64 },
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

/// The two corner joints [`find_corner`] recognises.
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

/// How large the second plate of a layer must be, against the first, to
/// count as a plate beside it rather than a piece of fixture or a clamp.
const SIDE_BY_SIDE_AREA_RATIO: f64 = 0.25;

/// A plane at least this many times longer than wide is a bar that can lie
/// across another plane, cutting it in two.
const BAR_ELONGATION: f64 = 2.0;

/// Whether `top`, nearer the camera, lies across the plane that `a` and
/// `b` are pieces of: `top` is long and narrow, and the two lie on
/// opposite sides of its long axis. A lap's upper plate ends on its lower
/// plate, so the lower one is seen on one side of it only; two butt
/// plates have nothing lying along the gap between them.
fn lies_across(top: &PlaneCluster, a: &PlaneCluster, b: &PlaneCluster, normal: &Vec3) -> bool {
    if top.elongation < BAR_ELONGATION {
        return false;
    }
    side_of(top, a, normal) * side_of(top, b, normal) < 0.0
}

/// How much of `under` is seen beside `top` on each side of it, mm²: its
/// points between `top`'s ends along its long axis and beyond its sides
/// across it, each standing for an equal share of `under`'s area. A bar
/// lying across a plate leaves the plate seen on both of its sides, also
/// where the plate is one cluster round the bar's end; a lap's upper plate
/// ends on its lower plate, seen beside one of its sides only. Counting
/// only past the top's own reach across keeps a plate the image border
/// cuts slantwise, whose long axis runs askew of its edges, to one side.
fn seen_beside(top: &PlaneCluster, under: &PlaneCluster, normal: &Vec3, points: &[Point]) -> [f64; 2] {
    let across_axis = normal.cross(&top.long_axis);
    let place = |p: Vec3| {
        let d = p - top.centroid;
        (top.long_axis.dot(&d), across_axis.dot(&d))
    };
    let reach: Vec<(f64, f64)> = member_points(&top.members, points).map(place).collect();
    let (along_lo, along_hi) = extent(reach.iter().map(|r| r.0));
    let (across_lo, across_hi) = extent(reach.iter().map(|r| r.1));
    let mut counts = [0usize; 2];
    for (along, across) in member_points(&under.members, points).map(place) {
        if !(along_lo..=along_hi).contains(&along) {
            continue;
        }
        if across < across_lo {
            counts[0] += 1;
        } else if across > across_hi {
            counts[1] += 1;
        }
    }
    let per_point_mm2 = under.area_mm2 / under.members.len().max(1) as f64;
    counts.map(|n| n as f64 * per_point_mm2)
}

impl PlaneCluster {
    /// How wide a long narrow cluster is, mm: a rectangle L by W covers
    /// L W and spreads L / W times further along than across.
    pub fn width_mm(&self) -> f64 {
        (self.area_mm2 / self.elongation.max(1.0)).sqrt()
    }
}

/// Which side of `top`'s long axis `c` lies on, and how far: positive on
/// the side `normal × long axis` points to.
fn side_of(top: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> f64 {
    normal.cross(&top.long_axis).dot(&(c.centroid - top.centroid))
}

/// Beyond a web's top, the share of returns at the flange's or the web's
/// level (of those far below) above which the web is no corner's: a
/// tee's flange, a plate a clamp lies on, the rest of a streak-cut plate.
const CORNER_LEVEL_SHARE_MAX: f64 = 0.05;
/// Beyond a web's top, at least this many returns far below it (and a
/// fifth of the top's own count) before it is taken for a corner's: a
/// sliver of plate at the image border has nothing beyond it.
const CORNER_DEEP_RETURNS_MIN: usize = 30;
/// The widest top taken for a corner's web, mm: issue 15's webs are 4 to
/// 12 mm thick; a wider strip of plate beside a plate (a piece a clamp or
/// a streak cut off) is left to the butt, lap and tee rules.
const CORNER_WEB_WIDTH_MAX_MM: f64 = 16.0;

/// A corner joint, if the clusters show one: a long narrow plane (a web's
/// top, at most `web_thickness_max_mm` and `CORNER_WEB_WIDTH_MAX_MM`
/// wide) beside a larger plane (the flange) seen on one of its sides only,
/// either flush with it or proud of it by at most a lap step (an outside
/// corner), or a web's height over it (an inside corner); and beyond the
/// top's far edge (away from the flange, past the top's rim, along its
/// length, a web's height at most) nothing at the flange's or the top's
/// level nor over them (`what_lies_beyond`), and either
/// - the cloud's returns there lie far below, deeper than the flange by
///   more than a lap step (the table past the web's outer face), with the
///   flange at least four times the top's size; or, beside an outside
///   corner's edge only,
/// - they go down a steep face from the edge and the table is not in the
///   cloud (a crop took it): the plate's outer face; or
/// - there are next to none, and the edge does not run along the view's
///   border: the outer face is turned from the camera and the table is
///   out of the cloud. Such an edge cannot be told from a butt or a lap
///   plate a crop cut as narrow, and is refused with that said.
///
/// `points` is the frame the clusters index; `view_border` gives the
/// border its rays span ([`ViewBorder::of_cloud`], read only when asked),
/// where a plate the image cuts ends with nothing beyond it (a butt plate
/// barely in view). A crop's border runs along an edge only where the crop
/// was cut along the edge.
pub fn find_corner<'v>(
    planes: &[PlaneCluster],
    s: &Selection,
    points: &[Point],
    view_border: impl Fn() -> Option<&'v ViewBorder>,
) -> Option<Corner> {
    // Each plane facing the camera with its index among those searched.
    let planes: Vec<(usize, &PlaneCluster)> = planes.iter().enumerate().filter(|(_, c)| s.faces_camera(c)).collect();
    let offset = |c: &PlaneCluster| s.normal.dot(&c.centroid);
    for &(top_index, top) in &planes {
        if top.elongation < BAR_ELONGATION || top.width_mm() > s.web_thickness_max_mm.min(CORNER_WEB_WIDTH_MAX_MM) {
            continue;
        }
        let flanges = planes.iter().filter(|&&(index, c)| {
            let step = offset(c) - offset(top);
            index != top_index
                && top.area_mm2 < c.area_mm2
                && step >= -s.coplanar_tolerance_mm
                && step <= s.web_height_max_mm
        });
        for &(flange_index, flange) in flanges {
            let step = offset(flange) - offset(top);
            let kind = if step <= s.lap_step_max_mm { CornerKind::Outside } else { CornerKind::Inside };
            let width_mm = top.width_mm();
            let what = match (what_lies_beyond(top, flange, step, s, points), kind) {
                (Some(Beyond::Drop { median_mm }), CornerKind::Outside) => format!(
                    "a plate's edge about {width_mm:.0} mm thick lies {:.1} mm over the flange's top beside it, and \
                     the cloud drops {median_mm:.0} mm beyond it",
                    step.max(0.0)
                ),
                (Some(Beyond::Drop { median_mm }), CornerKind::Inside) => format!(
                    "a plate about {width_mm:.0} mm thick stands {step:.0} mm tall at the end of the flange, seen on \
                     one of its sides only, and the cloud drops {median_mm:.0} mm beyond it"
                ),
                (Some(Beyond::Face { deepest_mm }), CornerKind::Outside) => format!(
                    "a plate's edge about {width_mm:.0} mm thick lies {:.1} mm over the flange's top beside it, and \
                     beyond it the cloud goes down a steep face, seen {deepest_mm:.0} mm deep to where the cloud ends",
                    step.max(0.0)
                ),
                (Some(Beyond::Nothing { far_edge }), CornerKind::Outside)
                    if !view_border().is_some_and(|border| runs_along(border, &far_edge, top, s)) =>
                {
                    format!(
                        "a plate's edge about {width_mm:.0} mm wide lies {:.1} mm over the flange's top beside it, \
                         and the cloud shows nothing beyond it, inside the view: an outside corner's plate whose \
                         outer face is turned from the camera and whose table is out of the cloud, or a plate a crop \
                         cut {width_mm:.0} mm wide (widen the crop to plan a butt joint or a lap)",
                        step.max(0.0)
                    )
                }
                _ => continue,
            };
            return Some(Corner { kind, what, standing: top_index, flange: flange_index });
        }
    }
    None
}

/// A corner joint seen: its kind, what was seen in words, and the plane
/// clusters (indices into those searched) of the standing plate's top and
/// of the flange.
#[derive(Debug, Clone, PartialEq)]
pub struct Corner {
    pub kind: CornerKind,
    pub what: String,
    pub standing: usize,
    pub flange: usize,
}

impl Corner {
    /// The refusal naming the corner.
    pub fn refusal(&self) -> BackgroundError {
        BackgroundError::LooksLikeCorner { kind: self.kind, what: self.what.clone() }
    }
}

/// What the cloud shows beyond a plate's edge, away from the flange
/// beside it, when nothing there lies at the flange's or the edge's level
/// or stands over them.
#[derive(Debug, Clone, PartialEq)]
enum Beyond {
    /// Enough returns, all deeper than the flange by more than a lap step:
    /// their median depth under the edge, mm.
    Drop { median_mm: f64 },
    /// Returns below the edge on a face going steeply down from it, and no
    /// table: the plate's outer face seen to where the cloud ends (a crop
    /// took the table). The deepest return, mm under the edge.
    Face { deepest_mm: f64 },
    /// Next to no returns at all: the edge's outermost point at each
    /// station along it, for where the view ends.
    Nothing { far_edge: Vec<Vec3> },
}

/// The least share of the returns below an edge that must lie on a face
/// going down from it (within [`MAX_FACE_LEAN_DEG`] of square to the
/// plate) for them to show the plate's outer face rather than a surface
/// below (a lap's other plate, a fixture).
const FACE_SHARE_MIN: f64 = 0.8;

/// What lies beyond `top`'s far edge (from `flange`, which lies `step`
/// under it): past the top's rim, along its length, a web's height across
/// at most. `None` where that shows no corner:
/// - returns at the flange's or the top's level, or over them, are more
///   than next to none (a tee's flange past its web, a plate a clamp lies
///   on, the clamp, the rest of a streak-cut plate): against the returns
///   far below where those show a drop, else against the top's own count;
/// - a drop beside a flange under four times the top's size;
/// - no drop, and the top does not touch the flange, or the returns below
///   lie on no face going down from the edge (a surface a lap step under
///   it).
fn what_lies_beyond(
    top: &PlaneCluster,
    flange: &PlaneCluster,
    step: f64,
    s: &Selection,
    points: &[Point],
) -> Option<Beyond> {
    let side = side_of(top, flange, &s.normal);
    if side == 0.0 {
        return None;
    }
    let away = s.normal.cross(&top.long_axis) * -side.signum();
    // Where the table is seen, the flange is seen whole beside the edge, at
    // least four times its size; a crop that took the table may leave less.
    let seen_whole = top.area_mm2 <= SIDE_BY_SIDE_AREA_RATIO * flange.area_mm2;
    // Without the table, only an edge that touches the flange is taken for
    // a corner's (a tee's flange on the web's far side lies a web's
    // thickness off, a V-groove's other plate a groove's width). Read from
    // the clusters' own points, before the pass over the whole cloud.
    let stations = Stations::along(top, away, s.neighbour_radius_mm, points);
    // Read once, when first asked: here, without the table, or after the
    // pass over the cloud when no drop is found.
    let gap = std::cell::OnceCell::new();
    let gap_mm = || *gap.get_or_init(|| gap_between(&stations, flange, points));
    let touches = |gap_mm: Option<f64>| gap_mm.is_some_and(|gap| gap <= s.neighbour_radius_mm + 2.0 * spacing_of(top));
    if !seen_whole && !touches(gap_mm()) {
        return None;
    }
    let far_edge =
        member_points(&top.members, points).map(|p| away.dot(&(p - top.centroid))).fold(f64::NEG_INFINITY, f64::max);
    let along = [stations.first_mm, stations.last_mm];
    let top_offset = s.normal.dot(&top.centroid);
    let max_lean = MAX_FACE_LEAN_DEG.to_radians().tan();
    let (mut level, mut over, mut on_face, mut deep, mut below) = (0usize, 0usize, 0usize, Vec::new(), 0usize);
    let mut deepest = 0.0_f64;
    for p in points.iter().map(vec3).filter(|p| p.iter().all(|v| v.is_finite())) {
        let rel = p - top.centroid;
        // Past the rim of the plate's own points the criterion left out.
        let across = away.dot(&rel) - far_edge - s.neighbour_radius_mm;
        let a = top.long_axis.dot(&rel);
        if across <= 0.0 || across > s.web_height_max_mm || a < along[0] || a > along[1] {
            continue;
        }
        let depth = s.normal.dot(&p) - top_offset;
        if depth.abs() <= s.coplanar_tolerance_mm || (depth - step).abs() <= s.coplanar_tolerance_mm {
            level += 1;
        } else if depth < 0.0 {
            over += 1;
        } else {
            below += 1;
            deepest = deepest.max(depth);
            // Within the lean of a face down from the edge's rim.
            on_face += usize::from(across <= depth * max_lean);
            if depth > step + s.lap_step_max_mm {
                deep.push(depth);
            }
        }
    }
    let enough = CORNER_DEEP_RETURNS_MIN.max(top.members.len() / 5);
    if deep.len() >= enough {
        if !seen_whole || level as f64 > CORNER_LEVEL_SHARE_MAX * deep.len() as f64 {
            return None;
        }
        deep.sort_by(f64::total_cmp);
        return Some(Beyond::Drop { median_mm: deep[deep.len() / 2] });
    }
    if (level + over) as f64 > CORNER_LEVEL_SHARE_MAX * top.members.len() as f64 {
        return None;
    }
    let gap_mm = gap_mm();
    tracing::debug!(
        level,
        over,
        below,
        on_face,
        deep = deep.len(),
        enough,
        gap_mm,
        "no drop to a table beyond a plate's edge"
    );
    if !touches(gap_mm) {
        return None;
    }
    if below >= CORNER_DEEP_RETURNS_MIN {
        return (on_face as f64 >= FACE_SHARE_MIN * below as f64).then_some(Beyond::Face { deepest_mm: deepest });
    }
    Some(Beyond::Nothing { far_edge: outermost_along(&stations, points) })
}

/// A plane cluster's mean point spacing, mm, from its area and count.
fn spacing_of(c: &PlaneCluster) -> f64 {
    (c.area_mm2 / c.members.len().max(1) as f64).sqrt()
}

/// The shortest station read along a plate's edge, mm: a bound on the
/// stations a long edge is cut into, whatever radius is configured.
const MIN_STATION_MM: f64 = 0.1;

/// A long narrow cluster cut into stations `station_mm` long along its
/// long axis, from its first point to its last, and how far out towards
/// `away` a point lies: each station's edge on that side is read from the
/// points in it.
struct Stations<'c> {
    top: &'c PlaneCluster,
    away: Vec3,
    station_mm: f64,
    /// The cluster's extent along its long axis, mm from its centroid.
    first_mm: f64,
    last_mm: f64,
    count: usize,
}

impl<'c> Stations<'c> {
    fn along(top: &'c PlaneCluster, away: Vec3, station_mm: f64, points: &[Point]) -> Stations<'c> {
        let station_mm = station_mm.max(MIN_STATION_MM);
        let (first_mm, last_mm) =
            extent(member_points(&top.members, points).map(|p| top.long_axis.dot(&(p - top.centroid))));
        let count = if last_mm >= first_mm { ((last_mm - first_mm) / station_mm) as usize + 1 } else { 0 };
        Stations { top, away, station_mm, first_mm, last_mm, count }
    }

    /// The station `p` lies at, if any, and how far out it lies, mm from
    /// the cluster's centroid.
    fn place(&self, p: &Vec3) -> (Option<usize>, f64) {
        let rel = p - self.top.centroid;
        let at = (self.top.long_axis.dot(&rel) - self.first_mm) / self.station_mm;
        let station = (at >= 0.0 && at < self.count as f64).then_some(at as usize);
        (station, self.away.dot(&rel))
    }
}

/// The finite points of `members`.
fn member_points<'p>(members: &'p [u32], points: &'p [Point]) -> impl Iterator<Item = Vec3> + 'p {
    every_member_point(members, 1, points)
}

/// The finite points of every `every`-th member: a sample read without
/// reading the members skipped.
fn every_member_point<'p>(members: &'p [u32], every: usize, points: &'p [Point]) -> impl Iterator<Item = Vec3> + 'p {
    members
        .iter()
        .step_by(every)
        .filter_map(|&i| points.get(i as usize))
        .map(vec3)
        .filter(|p| p.iter().all(|v| v.is_finite()))
}

/// How far apart the top's edge towards `flange` (against the stations'
/// `away`) and the flange's edge towards it lie, mm: the median over the
/// stations where both have points (the flange's on its own side of the
/// top's edge). `None` where they share no station.
fn gap_between(stations: &Stations, flange: &PlaneCluster, points: &[Point]) -> Option<f64> {
    let mut inner = vec![f64::INFINITY; stations.count];
    for (station, out) in member_points(&stations.top.members, points).map(|p| stations.place(&p)) {
        if let Some(k) = station {
            inner[k] = inner[k].min(out);
        }
    }
    let mut flange_edge = vec![f64::NEG_INFINITY; stations.count];
    for (station, out) in member_points(&flange.members, points).map(|p| stations.place(&p)) {
        if let Some(k) = station.filter(|&k| out <= inner[k]) {
            flange_edge[k] = flange_edge[k].max(out);
        }
    }
    let mut gaps: Vec<f64> =
        inner.iter().zip(&flange_edge).filter(|(_, f)| f.is_finite()).map(|(edge, f)| edge - f).collect();
    gaps.sort_by(f64::total_cmp);
    gaps.get(gaps.len() / 2).copied()
}

/// The top's outermost point towards the stations' `away` at each station:
/// its edge on that side, point by point.
fn outermost_along(stations: &Stations, points: &[Point]) -> Vec<Vec3> {
    let mut outermost: Vec<Option<(f64, Vec3)>> = vec![None; stations.count];
    for p in member_points(&stations.top.members, points) {
        if let (Some(k), out) = stations.place(&p)
            && outermost[k].is_none_or(|(best, _)| out > best)
        {
            outermost[k] = Some((out, p));
        }
    }
    outermost.into_iter().flatten().map(|(_, p)| p).collect()
}

/// Whether a plate's far edge (its outermost points along it) runs along
/// the view's border ([`ViewBorder::runs_along`]), within the plate's rim
/// (a neighbour radius) and two spacings of it.
fn runs_along(border: &ViewBorder, far_edge: &[Vec3], top: &PlaneCluster, s: &Selection) -> bool {
    border.runs_along(far_edge, s.neighbour_radius_mm + 2.0 * spacing_of(top))
}

/// Fits a plane to each cluster and estimates its area from the sampling
/// density the camera gives on that plane.
pub fn describe(
    cloud: &PointCloud,
    members: Vec<Vec<u32>>,
    area_per_point: impl Fn(&Vec3, &Vec3) -> f64,
) -> Vec<PlaneCluster> {
    let points = cloud.points();
    members
        .into_iter()
        .enumerate()
        .filter_map(|(label, m)| {
            // A fixed stride keeps the fit cheap on million-point plates.
            let stride = (m.len() / 50_000).max(1);
            let moments: Moments = m.iter().step_by(stride).map(|&i| vec3(&points[i as usize])).collect();
            let plane = moments.plane()?;
            let centroid = moments.centroid()?;
            let area_mm2 = m.len() as f64 * area_per_point(&centroid, &plane.normal);
            let (long_axis, elongation) = moments.elongation()?;
            Some(PlaneCluster { label: label as u32, members: m, plane, centroid, area_mm2, long_axis, elongation })
        })
        .collect()
}

/// The paper's rule: delete the cluster with the largest xy bounding box,
/// keep the two largest of the rest.
pub fn paper_select(cloud: &PointCloud, mut planes: Vec<PlaneCluster>) -> Result<Workpiece, BackgroundError> {
    let points = cloud.points();
    let bbox_area = |c: &PlaneCluster| {
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for &i in &c.members {
            let p = points[i as usize];
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        ((hi[0] - lo[0]) * (hi[1] - lo[1])) as f64
    };
    if let Some(background) = (0..planes.len()).max_by(|&a, &b| bbox_area(&planes[a]).total_cmp(&bbox_area(&planes[b])))
    {
        planes.remove(background);
    }
    planes.sort_by_key(|c| std::cmp::Reverse(c.members.len()));
    take_two(planes)
}

fn take_two(planes: Vec<PlaneCluster>) -> Result<Workpiece, BackgroundError> {
    let found = planes.len();
    let mut it = planes.into_iter();
    match (it.next(), it.next()) {
        (Some(a), Some(b)) => Ok(Workpiece {
            plates: [a, b],
            depth_to_support_mm: None,
            support_between_plates: false,
            layer_mates: Default::default(),
        }),
        _ => Err(BackgroundError::TooFewPlanes { found }),
    }
}

/// How the two plates of a joint lie: side by side in one plane (butt
/// joints, V or I), one on the other a plate thickness apart (lap), or a
/// web standing on a flange (tee: `plates[0]` is the web's top,
/// `plates[1]` the largest flange piece and `layer_mates[1]` the others).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Butt,
    Lap,
    Tee,
}

impl Layout {
    pub fn of(joint: JointType) -> Layout {
        match joint {
            JointType::VButt | JointType::IButt => Layout::Butt,
            JointType::Lap => Layout::Lap,
            JointType::TFillet => Layout::Tee,
        }
    }
}

/// Settings of the robust selection.
#[derive(Debug, Clone, Copy)]
pub struct Selection {
    /// The joint requested; None to decide the layout from the layers.
    pub joint: Option<JointType>,
    /// The workpiece's dominant normal, away from the camera.
    pub normal: Vec3,
    pub coplanar_tolerance_mm: f64,
    pub lap_step_min_mm: f64,
    pub lap_step_max_mm: f64,
    /// A web's top lies more than `lap_step_max_mm` and at most this far
    /// over its flange, and is at most `web_thickness_max_mm` wide.
    pub web_height_max_mm: f64,
    pub web_thickness_max_mm: f64,
    /// Clusters whose normal is further than this from `normal` are not
    /// workpiece planes.
    pub max_tilt_deg: f64,
    /// The plane criterion's neighbour radius (Eq. 6): a plate's points
    /// within it of the plate's edge may fail the criterion (their disc
    /// reaches past the edge), so a cluster can end up to this far inside
    /// its plate, and what lies beyond a plate is read past that rim.
    pub neighbour_radius_mm: f64,
}

impl Selection {
    /// Whether `c` faces the camera as the workpiece does: within
    /// `max_tilt_deg` of its dominant normal. Other clusters are no
    /// workpiece planes.
    pub fn faces_camera(&self, c: &PlaneCluster) -> bool {
        c.plane.normal.dot(&self.normal) >= self.max_tilt_deg.to_radians().cos()
    }
}

/// The two plates the robust rule chose, how they lie, and in words why.
#[derive(Debug, Clone)]
pub struct Selected {
    pub workpiece: Workpiece,
    pub layout: Layout,
    /// What the layers showed: the plates' offsets and areas, and for an
    /// automatic choice why the other layout was not it.
    pub evidence: String,
}

/// The clusters sorted into layers along the normal, nearest the camera
/// first, each layer's clusters largest first.
struct Layers {
    layers: Vec<Vec<PlaneCluster>>,
    normal: Vec3,
    found: usize,
    offsets_mm: Vec<f64>,
}

impl Layers {
    fn offset(&self, c: &PlaneCluster) -> f64 {
        self.normal.dot(&c.centroid)
    }

    /// The offset of layer `k`'s largest cluster.
    fn depth(&self, k: usize) -> f64 {
        self.offset(&self.layers[k][0])
    }

    /// How far behind layer `k` the next layer lies, if there is one.
    fn depth_behind(&self, k: usize) -> Option<f64> {
        (k + 1 < self.layers.len()).then(|| self.depth(k + 1) - self.depth(k))
    }
}

/// Where a butt joint's plates are: the layer holding them.
fn find_butt(l: &Layers, s: &Selection, joint: JointType) -> Result<usize, BackgroundError> {
    let Some(pos) = l.layers.iter().position(|layer| layer.len() >= 2) else {
        // Say what the layers look like when they look like a lap.
        if l.layers.len() >= 2 {
            let step_mm = l.depth(1) - l.depth(0);
            if (s.lap_step_min_mm..=s.lap_step_max_mm).contains(&step_mm) {
                return Err(BackgroundError::LooksLikeLap { joint, step_mm });
            }
        }
        return Err(BackgroundError::NoCoplanarPair { found: l.found, offsets_mm: l.offsets_mm.clone() });
    };
    // The plates are the workpiece's top: a nearer plane may be a clamp,
    // but not one larger than a plate. One lying across the pair (a clamp,
    // or a tee's web on its flange) stands between the pair's edges, where
    // the groove probe sees it and says which.
    let smaller_mm2 = l.layers[pos][1].area_mm2;
    if let Some(cover) = l.layers[..pos].iter().map(|layer| &layer[0]).find(|c| c.area_mm2 > smaller_mm2) {
        return Err(BackgroundError::PairUnderLargerPlane {
            area_mm2: cover.area_mm2,
            above_mm: l.depth(pos) - l.offset(cover),
            smaller_mm2,
        });
    }
    let [first, second, rest @ ..] = l.layers[pos].as_slice() else { return Ok(pos) };
    if let Some(third) = rest
        .iter()
        .find(|c| c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * smaller_mm2 && lies_beyond_pair(first, second, c, &l.normal))
    {
        return Err(BackgroundError::ThreeSideBySide {
            joint,
            first_mm2: first.area_mm2,
            second_mm2: second.area_mm2,
            third_mm2: third.area_mm2,
        });
    }
    Ok(pos)
}

/// How far beyond a butt pair, across their seam, a third plate's centroid
/// must lie to be a plate beside them: in units of the distance between
/// the pair's centroids, counted from the nearer of the two. A piece a
/// clamp or a streak cut off one of the pair has that plate's centroid
/// across the seam (it runs on along the seam, not beside it), moved at
/// most by how differently the image border cuts the two pieces; a plate
/// abutting one of the pair lies a plate's width further out.
const BEYOND_PAIR_SPACINGS: f64 = 0.5;

/// Where `c`'s centroid lies across the pair `a`, `b`: its place on the
/// line through theirs, in the plane of the layer (0 at `a`'s, 1 at
/// `b`'s); None for a pair whose centroids coincide.
fn across_pair(a: &PlaneCluster, b: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> Option<f64> {
    let in_plane = |v: Vec3| v - normal * normal.dot(&v);
    let across = in_plane(b.centroid - a.centroid);
    let spacing = across.norm();
    (spacing > 0.0).then(|| in_plane(c.centroid - a.centroid).dot(&across) / (spacing * spacing))
}

/// Whether `c` lies beside the pair `a`, `b` across their seam, beyond
/// either: its centroid more than [`BEYOND_PAIR_SPACINGS`] of their
/// distance outside the pair.
fn lies_beyond_pair(a: &PlaneCluster, b: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> bool {
    across_pair(a, b, c, normal).is_some_and(|t| !(-BEYOND_PAIR_SPACINGS..=1.0 + BEYOND_PAIR_SPACINGS).contains(&t))
}

/// Whether `c` is a strip between the pair `a`, `b`: its centroid between
/// theirs, and it is a bar ([`BAR_ELONGATION`]) narrower than either
/// plate. A V-groove's apex, which the voxels of a noisy cloud flatten
/// into a narrow plane, or the table a gap shows lie so; what the plates
/// rest on reaches out under and beside them.
fn lies_between_pair(a: &PlaneCluster, b: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> bool {
    across_pair(a, b, c, normal).is_some_and(|t| {
        (0.0..=1.0).contains(&t) && c.elongation >= BAR_ELONGATION && c.width_mm() < a.width_mm().min(b.width_mm())
    })
}

/// A tee's web top over its flange: the top's place in the layers, the
/// flange's layer, and the largest flange piece on each side of the web
/// (the side `normal × long axis` points to second), None on a side where
/// no piece is seen.
#[derive(Debug, Clone, Copy, PartialEq)]
struct TeeLayers {
    top: (usize, usize),
    flange: usize,
    sides: [Option<usize>; 2],
}

impl TeeLayers {
    fn two_sided(&self) -> bool {
        self.sides.iter().all(Option::is_some)
    }

    fn top<'l>(&self, l: &'l Layers) -> &'l PlaneCluster {
        &l.layers[self.top.0][self.top.1]
    }

    fn height(&self, l: &Layers) -> f64 {
        l.depth(self.flange) - l.offset(self.top(l))
    }

    fn piece_mm2(&self, l: &Layers, side: usize) -> f64 {
        self.sides[side].map_or(0.0, |k| l.layers[self.flange][k].area_mm2)
    }
}

/// Where a tee is: the nearest long narrow plane, the largest of its layer
/// (butt plates lie side by side; a sliver of plate beside a larger one is
/// no web), at most a web's thickness wide, whose nearest lower layer lies
/// a web's height under it (more than a lap's step: a clamp on a plate is
/// no taller than that, and a lap's upper plate lies on its lower one)
/// and holds a plane beside it, with no larger plane nearer the camera
/// (a V-groove's root land under its plates is narrow and long too). A
/// web seen over its flange on both sides first; else one over a plane on
/// one side.
fn find_tee(l: &Layers, s: &Selection, points: &[Point]) -> Option<TeeLayers> {
    let mut one_sided = None;
    for (upper, layer) in l.layers.iter().enumerate() {
        let top = &layer[0];
        if top.elongation < BAR_ELONGATION || top.width_mm() > s.web_thickness_max_mm || upper + 1 >= l.layers.len() {
            continue;
        }
        // A web's top is its workpiece's nearest surface: a narrow plane
        // under a larger one lies below the workpiece's top (a V-groove's
        // root land between its plates), not on top of a web.
        if l.layers[..upper].iter().any(|nearer| nearer[0].area_mm2 > top.area_mm2) {
            continue;
        }
        let flange = upper + 1;
        let height = l.depth(flange) - l.offset(top);
        if height <= s.lap_step_max_mm || height > s.web_height_max_mm {
            continue;
        }
        // On each side the piece the web's top stands beside, else the
        // largest: a plate of another workpiece grouped with the tee can
        // lie in the flange's layer, larger than the flange's piece
        // (multi-05 of the several-workpiece suite's draw 2, whose I-butt
        // plate 2.5 mm over the flange was taken for it).
        let on_side = |positive: bool| {
            let side: Vec<usize> = (0..l.layers[flange].len())
                .filter(|&k| {
                    let side = side_of(top, &l.layers[flange][k], &l.normal);
                    if positive { side > 0.0 } else { side < 0.0 }
                })
                .collect();
            let pieces: Vec<&PlaneCluster> = side.iter().map(|&k| &l.layers[flange][k]).collect();
            side.get(standing_beside(top, &pieces, &l.normal, points, MAX_JOINT_OPENING_MM)).copied()
        };
        let found = TeeLayers { top: (upper, 0), flange, sides: [on_side(false), on_side(true)] };
        if found.two_sided() {
            return Some(found);
        }
        if one_sided.is_none() && found.sides.iter().any(Option::is_some) {
            one_sided = Some(found);
        }
    }
    one_sided
}

/// The nearest layer of workpiece planes, its clusters largest first
/// (None when no plane faces the camera): where no web's top is found,
/// the flange of a tee whose top is out of view (a crop round its root),
/// for [`super::web_face`] to find the web's face standing on.
pub fn nearest_layer(planes: &[PlaneCluster], s: &Selection) -> Option<Vec<PlaneCluster>> {
    let offset = |c: &PlaneCluster| s.normal.dot(&c.centroid);
    let mut facing: Vec<&PlaneCluster> = planes.iter().filter(|c| s.faces_camera(c)).collect();
    facing.sort_by(|a, b| offset(a).total_cmp(&offset(b)));
    // Chained as `robust_select` chains its layers: from the nearest one.
    let first = offset(facing.first()?);
    let mut layer: Vec<&PlaneCluster> =
        facing.into_iter().take_while(|c| offset(c) - first <= s.coplanar_tolerance_mm).collect();
    layer.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    Some(layer.into_iter().cloned().collect())
}

/// Where a lap's plates are: the upper and the lower layer.
fn find_lap(l: &Layers, s: &Selection, points: &[Point]) -> Result<(usize, usize), BackgroundError> {
    for upper in 0..l.layers.len() {
        for lower in upper + 1..l.layers.len() {
            let step = l.depth(lower) - l.depth(upper);
            if step > s.lap_step_max_mm {
                break;
            }
            if step >= s.lap_step_min_mm {
                // Two plates side by side on top are a butt joint's.
                if let [first, second, ..] = l.layers[upper].as_slice()
                    && second.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * first.area_mm2
                {
                    return Err(BackgroundError::LooksLikeButt {
                        first_mm2: first.area_mm2,
                        second_mm2: second.area_mm2,
                        tolerance_mm: s.coplanar_tolerance_mm,
                    });
                }
                // The lower plate seen on both sides of the upper one: the
                // upper one lies across it. Split into two clusters by it,
                // or one cluster round its end (a clamp shorter than the
                // plate is wide).
                let (top, under) = (&l.layers[upper][0], &l.layers[lower]);
                let across = |first_mm2: f64, second_mm2: f64| BackgroundError::LiesAcross {
                    top_mm2: top.area_mm2,
                    above_mm: step,
                    first_mm2,
                    second_mm2,
                };
                if let Some(piece) = under[1..].iter().find(|c| {
                    c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * under[0].area_mm2
                        && lies_across(top, &under[0], c, &l.normal)
                }) {
                    return Err(across(under[0].area_mm2, piece.area_mm2));
                }
                // The whole layer under it: a bar lying across a plate can
                // cut it into pieces each smaller than a quarter of the
                // plate beside them (fault-clamp-i-butt-02, whose clamp
                // over an I-butt joint was planned as a lap 62 mm off).
                if top.elongation >= BAR_ELONGATION {
                    let [one, other] = under
                        .iter()
                        .map(|c| seen_beside(top, c, &l.normal, points))
                        .fold([0.0, 0.0], |[a, b], [one, other]| [a + one, b + other]);
                    let (larger, smaller) = (one.max(other), one.min(other));
                    if smaller > 0.0 && smaller >= SIDE_BY_SIDE_AREA_RATIO * larger {
                        return Err(across(larger, smaller));
                    }
                }
                return Ok((upper, lower));
            }
        }
    }
    Err(BackgroundError::NoLapStep {
        found: l.found,
        offsets_mm: l.offsets_mm.clone(),
        min_mm: s.lap_step_min_mm,
        max_mm: s.lap_step_max_mm,
    })
}

/// A lap's lower plate is the plane its upper plate's edge stands on,
/// which is not always the largest of the layer under it: a part touching
/// the lower plate a millimetre or two lower lies in the same layer (within
/// the coplanar tolerance), and can be the larger of the two
/// (fault-touching-part-lap-00 of fault draw 7: the part, 33 mm beyond the
/// strip of lower plate beside the upper plate's edge and 1.79 mm lower,
/// was taken for the lower plate, and the root was planned 1.79 mm under
/// the lower plate's top). The index into `l.layers[lower]` of the plate
/// [`standing_beside`] the upper plate.
///
/// Between a lap's upper plate and its lower plate only the band the step
/// hides from the camera lies unseen (the step times the tangent of the
/// view's slant, taken at most 45 degrees here), with the rim the plane
/// criterion trims off each plate (a neighbour radius). A plate of the
/// layer further across than that is no lower plate the upper one stands
/// on, however near: at 1 mm voxels multi-03's I-butt, its plates seen as
/// one plane, stands 16 mm from a V-butt plate 3.8 mm lower, of another
/// workpiece the table between them did not set apart.
fn lower_plate_of(l: &Layers, upper: usize, lower: usize, s: &Selection, points: &[Point]) -> usize {
    let top = &l.layers[upper][0];
    let under: Vec<&PlaneCluster> = l.layers[lower].iter().collect();
    let step = l.depth(lower) - l.offset(top);
    let hidden_mm = step.max(0.0) + 2.0 * s.neighbour_radius_mm;
    standing_beside(top, &under, &l.normal, points, hidden_mm.min(MAX_JOINT_OPENING_MM))
}

/// Of `pieces` (largest first), the one `top` stands beside: of those at
/// least [`SIDE_BY_SIDE_AREA_RATIO`] of the largest, the ones nearest
/// `top` across the plane, within [`BESIDE_TOLERANCE_CELLS`] of the
/// nearest, and of them the largest (two pieces of one plate a streak
/// splits along the seam stand beside it alike). The largest, 0, where
/// only one piece is that large, or none lies within `reach_mm` of `top`
/// (read to a cell), or no points are given.
fn standing_beside(
    top: &PlaneCluster,
    pieces: &[&PlaneCluster],
    normal: &Vec3,
    points: &[Point],
    reach_mm: f64,
) -> usize {
    let Some(largest) = pieces.first() else {
        return 0;
    };
    let plates = pieces.iter().take_while(|c| c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * largest.area_mm2).count();
    if plates < 2 {
        return 0;
    }
    let Some(gaps) = gaps_across(top, &pieces[..plates], normal, points, reach_mm) else {
        return 0;
    };
    let nearest = gaps.iter().flatten().fold(f64::INFINITY, |a, &b| a.min(b));
    let tolerance = BESIDE_TOLERANCE_CELLS * BESIDE_CELL_SPACINGS * spacing_of(top);
    gaps.iter().position(|g| g.is_some_and(|g| g <= nearest + tolerance)).unwrap_or(0)
}

/// The cells of [`gaps_across`], in point spacings of the upper plane: a
/// cell that wide holds about nine of a plate's points, so every fourth
/// marks it about twice (in a frame's pixel order, in three of its four
/// rows), and a cell left empty inside a plate is crossed in one step.
const BESIDE_CELL_SPACINGS: f64 = 3.0;

/// Every how many of a cluster's points [`gaps_across`] marks a cell with.
const BESIDE_MARK_STRIDE: usize = 4;

/// Every how many of the upper plane's points [`gaps_across`] marks a cell
/// with: it is the largest plane of a lap, and its nearest cells to each
/// other plate are all that is read of it, so a cell it leaves empty here
/// and there moves the gap by a cell at most where the edge is read best.
const BESIDE_TOP_MARK_STRIDE: usize = 8;

/// Every how many of the clusters' points [`gaps_across`] takes their
/// extent from.
const BESIDE_BOUNDS_STRIDE: usize = 8;

/// How many cells further from a lap's upper plate (or a web's top) than
/// the nearest plate of the layer under it another plate of that layer may
/// lie and still stand beside it: each plate's nearest point is read to a
/// cell, and the cells count steps along the diagonal as one.
const BESIDE_TOLERANCE_CELLS: f64 = 2.0;

/// The most cells the grid of [`gaps_across`] may hold; a coarser cell is
/// taken beyond it.
const BESIDE_MAX_CELLS: f64 = 4.0e6;

/// How far across the plane each of `others` lies from `top`, mm: steps of
/// a grid of cells [`BESIDE_CELL_SPACINGS`] wide from the cells `top`'s
/// points mark to the nearest cell the other's points mark, each step a
/// cell (also along the diagonal). `None` for one further than `reach_mm`
/// and a cell (a gap is read to a cell); `None` for all where the points
/// give no extent.
fn gaps_across(
    top: &PlaneCluster,
    others: &[&PlaneCluster],
    normal: &Vec3,
    points: &[Point],
    reach_mm: f64,
) -> Option<Vec<Option<f64>>> {
    let [u_axis, v_axis] = plane_axes(normal)?;
    let project = |p: Vec3| (p.dot(&u_axis), p.dot(&v_axis));
    // The extent from every few points, widened by a cell: a point the
    // sample misses lies in the border cells it is clamped into.
    let [u0, v0, u1, v1] = std::iter::once(top)
        .chain(others.iter().copied())
        .flat_map(|c| every_member_point(&c.members, BESIDE_BOUNDS_STRIDE, points))
        .map(project)
        .fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |[u0, v0, u1, v1], (u, v)| {
            [u0.min(u), v0.min(v), u1.max(u), v1.max(v)]
        });
    if !(u1 > u0 && v1 > v0) {
        return None;
    }
    let fine = (BESIDE_CELL_SPACINGS * spacing_of(top)).max(f64::EPSILON);
    let [u0, v0, u1, v1] = [u0 - fine, v0 - fine, u1 + fine, v1 + fine];
    let cell_mm = fine.max(((u1 - u0) * (v1 - v0) / BESIDE_MAX_CELLS).sqrt());
    let (width, height) = (((u1 - u0) / cell_mm) as usize + 1, ((v1 - v0) / cell_mm) as usize + 1);
    let cell_of = |p: Vec3| {
        let (u, v) = project(p);
        let (x, y) = (((u - u0) / cell_mm) as usize, ((v - v0) / cell_mm) as usize);
        y.min(height - 1) * width + x.min(width - 1)
    };
    // Steps from the top's cells, a ring at a time, out to the reach and
    // the cell it is read to.
    let reach = (reach_mm / cell_mm).ceil() as u32 + 1;
    let mut steps = vec![u32::MAX; width * height];
    let mut front: Vec<usize> = Vec::new();
    for c in every_member_point(&top.members, BESIDE_TOP_MARK_STRIDE, points).map(cell_of) {
        if steps[c] != 0 {
            steps[c] = 0;
            front.push(c);
        }
    }
    for step in 1..=reach {
        let mut next = Vec::new();
        for &c in &front {
            let (x, y) = (c % width, c / width);
            for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                    let n = ny * width + nx;
                    if steps[n] == u32::MAX {
                        steps[n] = step;
                        next.push(n);
                    }
                }
            }
        }
        front = next;
    }
    let gaps = others
        .iter()
        .map(|c| {
            let nearest = every_member_point(&c.members, BESIDE_MARK_STRIDE, points)
                .map(|p| steps[cell_of(p)])
                .min()
                .filter(|&s| s != u32::MAX);
            nearest.map(|s| s as f64 * cell_mm).filter(|&gap| gap <= reach_mm + cell_mm)
        })
        .collect();
    Some(gaps)
}

/// The robust rule: plates are the nearest parallel layers that fit the
/// joint type; with no type given, the layers decide: two plates side by
/// side in the nearest such layer make a butt joint, two layers a plate
/// thickness apart with one plate on top a lap, and where both fit, the
/// one whose top plate is nearer the camera (the workpiece's top) unless
/// that top is too small beside the butt plates to be a plate (a clamp).
/// `points` is the frame the clusters index.
pub fn robust_select(planes: Vec<PlaneCluster>, s: &Selection, points: &[Point]) -> Result<Selected, BackgroundError> {
    let mut planes: Vec<PlaneCluster> = planes.into_iter().filter(|c| s.faces_camera(c)).collect();
    let found = planes.len();
    if found < 2 {
        return Err(BackgroundError::TooFewPlanes { found });
    }
    let offset = |c: &PlaneCluster| s.normal.dot(&c.centroid);
    planes.sort_by(|a, b| offset(a).total_cmp(&offset(b)));
    let offsets_mm: Vec<f64> = planes.iter().map(|c| (offset(c) * 10.0).round() / 10.0).collect();

    // Layers: runs of clusters whose offsets agree, nearest the camera first.
    let mut layers: Vec<Vec<PlaneCluster>> = Vec::new();
    for c in planes {
        match layers.last_mut() {
            Some(layer) if offset(&c) - offset(&layer[0]) <= s.coplanar_tolerance_mm => layer.push(c),
            _ => layers.push(vec![c]),
        }
    }
    for layer in &mut layers {
        layer.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    }
    let l = Layers { layers, normal: s.normal, found, offsets_mm };

    let butt = |l: &Layers, pos: usize, why: String| {
        let [a, b] = [&l.layers[pos][0], &l.layers[pos][1]];
        let evidence = format!(
            "two plates side by side ({:.0} and {:.0} mm², {:.1} mm apart along the normal){why}",
            a.area_mm2,
            b.area_mm2,
            (l.offset(b) - l.offset(a)).abs()
        );
        (Layout::Butt, [(pos, 0), (pos, 1)], l.depth_behind(pos), evidence)
    };
    let lap = |l: &Layers, (upper, lower): (usize, usize), why: String| {
        let k = lower_plate_of(l, upper, lower, s, points);
        let (top, under) = (&l.layers[upper][0], &l.layers[lower][k]);
        let evidence = format!(
            "an upper plate of {:.0} mm² {:.1} mm over a lower one of {:.0} mm²{why}",
            top.area_mm2,
            l.offset(under) - l.offset(top),
            under.area_mm2
        );
        (Layout::Lap, [(upper, 0), (lower, k)], l.depth_behind(lower), evidence)
    };
    let tee_found = find_tee(&l, s, points);
    let tee = |l: &Layers, t: &TeeLayers| {
        let top = t.top(l);
        let sides = match t.sides {
            [Some(_), Some(_)] => {
                format!("seen on both of its sides ({:.0} and {:.0} mm²)", t.piece_mm2(l, 0), t.piece_mm2(l, 1))
            }
            _ => format!("seen on one of its sides only ({:.0} mm²)", t.piece_mm2(l, 0).max(t.piece_mm2(l, 1))),
        };
        let evidence = format!(
            "a web's top of {:.0} mm², about {:.0} mm wide, {:.1} mm over a flange {sides}",
            top.area_mm2,
            top.width_mm(),
            t.height(l)
        );
        // The larger flange piece is the second plate; the other stays a
        // layer mate.
        let larger = if t.piece_mm2(l, 0) >= t.piece_mm2(l, 1) { t.sides[0] } else { t.sides[1] };
        (Layout::Tee, [t.top, (t.flange, larger.unwrap_or(0))], l.depth_behind(t.flange), evidence)
    };
    let (layout, picks, depth_to_support_mm, evidence) = match (s.joint, tee_found) {
        (Some(JointType::TFillet), Some(t)) => tee(&l, &t),
        (Some(JointType::TFillet), None) => {
            return Err(BackgroundError::NoWeb {
                found: l.found,
                offsets_mm: l.offsets_mm.clone(),
                min_mm: s.lap_step_max_mm,
                max_mm: s.web_height_max_mm,
                max_width_mm: s.web_thickness_max_mm,
            });
        }
        (Some(joint), Some(t)) if t.two_sided() => {
            let top = t.top(&l);
            return Err(BackgroundError::LooksLikeTee {
                joint,
                top_mm2: top.area_mm2,
                width_mm: top.width_mm(),
                height_mm: t.height(&l),
                first_mm2: t.piece_mm2(&l, 0),
                second_mm2: t.piece_mm2(&l, 1),
            });
        }
        (None, Some(t)) if t.two_sided() => tee(&l, &t),
        (Some(joint), _) if Layout::of(joint) == Layout::Butt => butt(&l, find_butt(&l, s, joint)?, String::new()),
        (Some(_), _) => lap(&l, find_lap(&l, s, points)?, String::new()),
        (None, _) => match (find_butt(&l, s, JointType::IButt), find_lap(&l, s, points)) {
            // A plate over the pair, not a clamp: as large as a plate beside
            // it, and over a lower plate of its own, not lying across the
            // pair (a clamp or a fixture over a butt joint's gap).
            (Ok(pos), Ok(lap_layers))
                if lap_layers.0 < pos
                    && lap_layers.1 != pos
                    && l.layers[lap_layers.0][0].area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * l.layers[pos][1].area_mm2 =>
            {
                lap(&l, lap_layers, " nearer the camera than the nearest coplanar pair".into())
            }
            // The lap's upper layer is the pair's, and the lap found no
            // second plate beside the first there: a plate and a piece.
            (Ok(pos), Ok((upper, lower))) if upper == pos => {
                return Err(BackgroundError::Ambiguous {
                    first_mm2: l.layers[pos][0].area_mm2,
                    second_mm2: l.layers[pos][1].area_mm2,
                    step_mm: l.depth(lower) - l.depth(upper),
                });
            }
            (Ok(pos), _) => butt(&l, pos, String::new()),
            (Err(BackgroundError::LooksLikeLap { .. }), Ok(lap_layers)) => {
                lap(&l, lap_layers, ", and no two plates side by side in one plane".into())
            }
            (Err(butt_error), Ok(lap_layers)) => lap(&l, lap_layers, format!("; not a butt joint: {butt_error}")),
            (Err(butt), Err(lap)) => {
                if let Some(t) = tee_found {
                    let top = t.top(&l);
                    return Err(BackgroundError::OneSidedWeb {
                        top_mm2: top.area_mm2,
                        width_mm: top.width_mm(),
                        height_mm: t.height(&l),
                        beside_mm2: t.piece_mm2(&l, 0).max(t.piece_mm2(&l, 1)),
                    });
                }
                return Err(BackgroundError::Unrecognised { butt: Box::new(butt), lap: Box::new(lap) });
            }
        },
    };
    let [(pair_layer, first_k), (second_layer, second_k)] = picks;
    let support_between_plates = layout == Layout::Butt
        && l.layers.get(pair_layer + 1).is_some_and(|behind| {
            let (a, b) = (&l.layers[pair_layer][first_k], &l.layers[second_layer][second_k]);
            behind.iter().all(|c| lies_between_pair(a, b, c, &l.normal))
        });
    // Take the two plates out of their layers, the later pick first so the
    // earlier one's place does not move.
    let mut layers = l.layers;
    let mut take = |(layer, k): (usize, usize)| layers[layer].swap_remove(k);
    let (second, first) = (take(picks[1]), take(picks[0]));
    let layer_mates = [layers[picks[0].0].clone(), std::mem::take(&mut layers[picks[1].0])];
    let workpiece = Workpiece { plates: [first, second], depth_to_support_mm, support_between_plates, layer_mates };
    Ok(Selected { workpiece, layout, evidence })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The robust rule over clusters that index no frame: what only
    /// their points show is not seen.
    fn robust_select(planes: Vec<PlaneCluster>, s: &Selection) -> Result<Selected, BackgroundError> {
        super::robust_select(planes, s, &[])
    }

    /// A plate as long along y as it is wide across x.
    fn cluster(offset: f64, area: f64, centre_x: f64) -> PlaneCluster {
        PlaneCluster {
            label: 0,
            members: vec![0; area as usize],
            plane: Plane { normal: Vec3::z(), offset },
            centroid: Vec3::new(centre_x, 0.0, offset),
            area_mm2: area,
            long_axis: Vec3::y(),
            elongation: 1.0,
        }
    }

    /// A bar along y, five times longer than wide.
    fn bar(offset: f64, area: f64, centre_x: f64) -> PlaneCluster {
        PlaneCluster { elongation: 5.0, ..cluster(offset, area, centre_x) }
    }

    #[test]
    fn a_third_plate_beside_a_butt_pair_is_refused_and_a_piece_along_it_is_not() {
        // Plates of 100 mm side by side at x = 0 and 100, a third abutting
        // the second at x = 190: two joints in one plane.
        let pair = [cluster(700.0, 20_000.0, 0.0), cluster(700.5, 18_000.0, 100.0)];
        let beside = [pair.as_slice(), &[cluster(699.5, 12_000.0, 190.0)]].concat();
        let err = robust_select(beside.clone(), &selection(JointType::IButt)).unwrap_err();
        assert!(matches!(err, BackgroundError::ThreeSideBySide { .. }), "{err}");
        assert!(err.to_string().contains("region of interest"), "{err}");
        // On the other side of the pair too, and under auto.
        let before = [pair.as_slice(), &[cluster(699.5, 12_000.0, -95.0)]].concat();
        assert!(matches!(robust_select(before, &auto()), Err(BackgroundError::Unrecognised { .. })));
        // A piece of the second plate a clamp cut off lies along the seam,
        // across it where that plate lies: the pair is planned.
        let mut piece = cluster(700.5, 9_000.0, 104.0);
        piece.centroid.y = 150.0;
        let cut = [pair.as_slice(), &[piece]].concat();
        assert_eq!(robust_select(cut, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
        // So is a third plane too small to be a plate (a spatter bead, a
        // tack).
        let bead = [pair.as_slice(), &[cluster(700.0, 300.0, 190.0)]].concat();
        assert_eq!(robust_select(bead, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
    }

    #[test]
    fn a_narrow_strip_between_butt_plates_is_their_floor_and_a_wide_plane_their_support() {
        // Butt plates 100 mm wide at x = 0 and 100; behind them a strip 3 mm
        // wide along the seam (a V's apex in a noisy cloud), or the table.
        let plate = |x: f64| PlaneCluster { elongation: 3.0, ..cluster(700.0, 30_000.0, x) };
        let strip = PlaneCluster { elongation: 100.0, ..cluster(707.6, 900.0, 50.0) };
        let pair = [plate(0.0), plate(100.0)];
        let floor = robust_select([pair.as_slice(), &[strip]].concat(), &selection(JointType::VButt)).unwrap();
        assert!(floor.workpiece.depth_to_support_mm.is_some_and(|d| (d - 7.6).abs() < 1e-9));
        assert!(floor.workpiece.support_between_plates);
        let table = cluster(740.0, 200_000.0, 50.0);
        let rest = robust_select([pair.as_slice(), &[table]].concat(), &selection(JointType::VButt)).unwrap();
        assert_eq!(rest.workpiece.depth_to_support_mm, Some(40.0));
        assert!(!rest.workpiece.support_between_plates);
    }

    fn selection(joint: JointType) -> Selection {
        Selection { joint: Some(joint), ..auto() }
    }

    fn auto() -> Selection {
        Selection {
            joint: None,
            normal: Vec3::z(),
            coplanar_tolerance_mm: 3.0,
            lap_step_min_mm: 1.0,
            lap_step_max_mm: 30.0,
            web_height_max_mm: 250.0,
            web_thickness_max_mm: 30.0,
            max_tilt_deg: 10.0,
            neighbour_radius_mm: 1.0,
        }
    }

    /// A web's top along y, 8 mm wide and 200 mm long, `height` over a
    /// flange at 760 seen on both of its sides (or only on +x), the table
    /// further.
    fn tee(height: f64, both_sides: bool) -> Vec<PlaneCluster> {
        let web = PlaneCluster { elongation: 25.0, ..cluster(760.0 - height, 1_600.0, 0.0) };
        let mut planes = vec![web, cluster(760.0, 30_000.0, 80.0), cluster(800.0, 90_000.0, 0.0)];
        if both_sides {
            planes.push(cluster(760.2, 12_000.0, -60.0));
        }
        planes
    }

    /// A frame of 1 mm returns along y 0..200: a web's top 8 mm wide at
    /// x -8..0 and depth `top_z`, the flange at x 0..100 and depth 760,
    /// and beyond the web (x -60..-8) returns at depth `beyond_z`, if any.
    /// The clusters are the top's and the flange's.
    fn corner_frame(top_z: f64, beyond_z: Option<f64>) -> (Vec<PlaneCluster>, Vec<Point>) {
        corner_frame_apart(top_z, beyond_z, 0)
    }

    /// [`corner_frame`] with the flange starting `gap` mm off the top's
    /// edge, at x = gap..100.
    fn corner_frame_apart(top_z: f64, beyond_z: Option<f64>, gap: i32) -> (Vec<PlaneCluster>, Vec<Point>) {
        let mut points: Vec<Point> = Vec::new();
        let strip = |points: &mut Vec<Point>, x0: i32, x1: i32, z: f64| {
            let first = points.len() as u32;
            for x in x0..x1 {
                for y in 0..200 {
                    points.push([x as f32 + 0.5, y as f32, z as f32]);
                }
            }
            (first..points.len() as u32).collect::<Vec<u32>>()
        };
        let web = strip(&mut points, -8, 0, top_z);
        let flange = strip(&mut points, gap, 100, 760.0);
        if let Some(z) = beyond_z {
            strip(&mut points, -60, -8, z);
        }
        let plane = |members: Vec<u32>, x: f64, z: f64, elongation: f64| PlaneCluster {
            area_mm2: members.len() as f64,
            members,
            plane: Plane { normal: Vec3::z(), offset: z },
            centroid: Vec3::new(x, 100.0, z),
            label: 0,
            long_axis: Vec3::y(),
            elongation,
        };
        (vec![plane(web, -4.0, top_z, 25.0), plane(flange, 50.0, 760.0, 2.0)], points)
    }

    fn corner_kind(top_z: f64, beyond_z: Option<f64>) -> Option<CornerKind> {
        let (planes, points) = corner_frame(top_z, beyond_z);
        find_corner(&planes, &auto(), &points, || None).map(|corner| corner.kind)
    }

    #[test]
    fn a_plates_edge_flush_or_proud_beside_a_flange_with_a_drop_beyond_is_an_outside_corner() {
        assert_eq!(corner_kind(760.0, Some(830.0)), Some(CornerKind::Outside));
        assert_eq!(corner_kind(757.0, Some(830.0)), Some(CornerKind::Outside));
        let (planes, points) = corner_frame(760.0, Some(830.0));
        let corner = find_corner(&planes, &auto(), &points, || None).unwrap();
        let reason = corner.refusal().to_string();
        assert!(reason.contains("corner joint") && reason.contains("8 mm thick"), "{reason}");
        assert!(reason.contains("outside corner's weld is not planned"), "{reason}");
        // The clusters named are the plate's edge and the flange.
        assert_eq!((corner.standing, corner.flange), (0, 1));
    }

    #[test]
    fn a_web_a_web_height_over_a_flange_with_a_drop_beyond_is_an_inside_corner() {
        assert_eq!(corner_kind(700.0, Some(860.0)), Some(CornerKind::Inside));
        let (planes, points) = corner_frame(700.0, Some(860.0));
        let reason = find_corner(&planes, &auto(), &points, || None).unwrap().refusal().to_string();
        assert!(reason.contains("request t_fillet or auto"), "{reason}");
    }

    #[test]
    fn an_edge_with_its_outer_face_going_down_to_where_the_cloud_ends_is_an_outside_corner() {
        // A crop 25 mm deep took the table; the plate's outer face is seen
        // from under the edge's rim (beyond the flange's level) down to the
        // crop.
        let (planes, mut points) = corner_frame(758.0, None);
        for z in 764..783 {
            for y in 0..200 {
                points.push([-9.0, y as f32, z as f32]);
            }
        }
        let corner = find_corner(&planes, &auto(), &points, || None).expect("refused");
        assert_eq!(corner.kind, CornerKind::Outside);
        let reason = corner.refusal().to_string();
        assert!(reason.contains("steep face") && reason.contains("24 mm deep"), "{reason}");
    }

    #[test]
    fn a_sliver_cut_by_the_image_border_is_no_corner() {
        // Butt plates, one barely in view: the image's border runs along
        // the sliver's far edge (x = -7.5 at 760 mm).
        let (planes, points) = corner_frame(760.0, None);
        let border = ViewBorder::from_tangents([-7.5 / 760.0, 1.0, -1.0, 1.0]);
        assert_eq!(find_corner(&planes, &auto(), &points, || Some(&border)), None);
    }

    #[test]
    fn an_edge_with_nothing_beyond_inside_the_view_or_in_a_cloud_without_a_grid_is_refused() {
        // An outside corner's plate whose outer face is turned from the
        // camera and whose table a crop took: nothing at a plate's level
        // beyond its edge, and no drop to show. Without the image's border
        // (a cropped or merged cloud) a plate cut as narrow looks the same.
        let (planes, points) = corner_frame(758.0, None);
        let corner = find_corner(&planes, &auto(), &points, || None).expect("refused");
        assert_eq!(corner.kind, CornerKind::Outside);
        let reason = corner.refusal().to_string();
        assert!(reason.contains("8 mm wide") && reason.contains("2.0 mm over"), "{reason}");
        assert!(reason.contains("widen the crop") && reason.contains("not planned"), "{reason}");
        // In a grid whose border touches the edge only at the image's
        // corner (y = 0), the edge is in view: still refused.
        let corner_of_image = ViewBorder::from_tangents([-1.0, 1.0, 0.0, 1.0]);
        assert!(find_corner(&planes, &auto(), &points, || Some(&corner_of_image)).is_some());
        // Off the flange by a web's thickness (a cropped tee's flange on
        // the far side of its web) or a groove's width, the edge is no
        // corner's.
        let (planes, points) = corner_frame_apart(758.0, None, 8);
        assert_eq!(find_corner(&planes, &auto(), &points, || None), None);
        // The rest of a plate at either level beyond is a plate.
        assert_eq!(corner_kind(758.0, Some(758.0)), None);
        assert_eq!(corner_kind(758.0, Some(760.0)), None);
        // A web's top a web's height over the flange, nothing beyond: a
        // tee whose far side is out of the cloud as much as a corner.
        assert_eq!(corner_kind(700.0, None), None);
    }

    #[test]
    fn returns_at_the_flanges_level_beyond_make_it_no_corner() {
        // A tee's flange beyond its web, a plate under a clamp, the rest of
        // a plate a streak cut.
        assert_eq!(corner_kind(700.0, Some(760.0)), None);
        assert_eq!(corner_kind(760.0, Some(760.0)), None);
    }

    #[test]
    fn a_drop_no_deeper_than_a_lap_step_is_no_corner() {
        assert_eq!(corner_kind(760.0, Some(780.0)), None);
    }

    #[test]
    fn a_web_a_web_height_over_its_flange_seen_on_both_sides_is_a_tee() {
        for joint in [Some(JointType::TFillet), None] {
            let chosen = robust_select(tee(50.0, true), &Selection { joint, ..auto() }).unwrap();
            assert_eq!(chosen.layout, Layout::Tee, "{joint:?}");
            assert_eq!(chosen.workpiece.plates[0].area_mm2, 1_600.0);
            // The larger flange piece, the other its layer mate.
            assert_eq!(chosen.workpiece.plates[1].area_mm2, 30_000.0);
            assert_eq!(chosen.workpiece.layer_mates[1].len(), 1);
            assert_eq!(chosen.workpiece.depth_to_support_mm, Some(40.0));
            assert!(chosen.evidence.contains("50.0 mm over a flange seen on both"), "{}", chosen.evidence);
        }
        // A butt or lap joint requested: named for what it looks like.
        for joint in [JointType::IButt, JointType::VButt, JointType::Lap] {
            let err = robust_select(tee(50.0, true), &selection(joint)).unwrap_err();
            assert!(err.is_joint_mismatch() && err.to_string().contains("looks like a tee joint"), "{err}");
        }
    }

    #[test]
    fn a_bar_no_taller_than_a_lap_step_or_too_wide_is_no_web() {
        // A clamp 25 mm over the plates (the fault suite's): within a lap's
        // step, so what it was before, butt plates with a clamp over them.
        let clamp = tee(25.0, true);
        assert_eq!(robust_select(clamp, &auto()).unwrap().layout, Layout::Butt);
        let err = robust_select(tee(25.0, true), &selection(JointType::TFillet)).unwrap_err();
        assert!(matches!(err, BackgroundError::NoWeb { .. }), "{err}");
        // A plate 60 mm wide over the table: no web's top.
        let mut wide = tee(50.0, true);
        wide[0].elongation = 3.0;
        wide[0].area_mm2 = 11_000.0;
        assert_ne!(robust_select(wide.clone(), &auto()).map(|s| s.layout).ok(), Some(Layout::Tee));
        assert!(matches!(robust_select(wide, &selection(JointType::TFillet)), Err(BackgroundError::NoWeb { .. })));
    }

    #[test]
    fn a_v_groove_s_root_land_under_its_plates_is_no_web_s_top() {
        // A V-butt cropped round its seam: its plates either side at 360,
        // the groove's root land 3 mm wide 9 mm under them, and the table
        // beyond the plates' end 37 mm under the land: the land is long,
        // narrow and a web's height over a plane, but it lies under the
        // workpiece's top.
        let land = PlaneCluster { elongation: 80.0, ..cluster(369.0, 1_200.0, 0.0) };
        let planes =
            vec![cluster(360.0, 11_000.0, -25.0), cluster(360.1, 11_500.0, 25.0), land, cluster(406.0, 2_000.0, 40.0)];
        let err = robust_select(planes.clone(), &selection(JointType::TFillet)).unwrap_err();
        assert!(matches!(err, BackgroundError::NoWeb { .. }), "{err}");
        assert_eq!(robust_select(planes, &auto()).unwrap().layout, Layout::Butt);
    }

    #[test]
    fn a_web_over_a_flange_seen_on_one_side_is_planned_only_when_named() {
        let chosen = robust_select(tee(60.0, false), &selection(JointType::TFillet)).unwrap();
        assert_eq!(chosen.layout, Layout::Tee);
        assert!(chosen.evidence.contains("one of its sides only"), "{}", chosen.evidence);
        let err = robust_select(tee(60.0, false), &auto()).unwrap_err();
        assert!(matches!(err, BackgroundError::OneSidedWeb { .. }) && err.is_unrecognised(), "{err}");
        assert!(err.to_string().contains("tee joint"), "{err}");
    }

    #[test]
    fn a_split_table_is_not_taken_for_a_plate() {
        // Two table pieces, larger than the plates, 40 mm further away.
        let planes = vec![
            cluster(740.0, 90_000.0, -300.0),
            cluster(700.0, 20_000.0, -50.0),
            cluster(740.0, 80_000.0, 300.0),
            cluster(700.5, 25_000.0, 50.0),
        ];
        let w = robust_select(planes, &selection(JointType::IButt)).unwrap().workpiece;
        assert!(w.plates.iter().all(|p| p.plane.offset < 701.0));
    }

    #[test]
    fn table_pieces_under_plates_seen_as_one_are_refused() {
        // The plates merged across an unresolved gap (one plane), the table
        // 34 mm below split in two by the workpiece: no seam lies between
        // the table pieces, whatever their edges look like.
        let planes =
            vec![cluster(905.0, 160_000.0, 0.0), cluster(939.0, 40_000.0, -250.0), cluster(939.3, 30_000.0, 250.0)];
        let err = robust_select(planes, &selection(JointType::IButt)).unwrap_err();
        assert!(matches!(err, BackgroundError::PairUnderLargerPlane { .. }), "{err}");
        assert!(err.to_string().contains("34.0 mm nearer the camera"), "{err}");
        // A clamp on the plates is smaller than either plate and is passed over.
        let planes =
            vec![cluster(880.0, 2_000.0, 0.0), cluster(905.0, 60_000.0, -100.0), cluster(905.2, 50_000.0, 100.0)];
        let w = robust_select(planes, &selection(JointType::IButt)).unwrap().workpiece;
        assert!(w.plates.iter().all(|p| p.plane.offset > 904.0));
    }

    #[test]
    fn plates_filling_the_view_are_both_kept() {
        let planes = vec![cluster(700.0, 70_000.0, -100.0), cluster(700.2, 60_000.0, 100.0)];
        assert!(robust_select(planes, &selection(JointType::VButt)).is_ok());
    }

    #[test]
    fn lap_takes_the_nearest_layers_one_thickness_apart_upper_first() {
        let planes =
            vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
        let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
        assert_eq!(w.plates[0].plane.offset, 700.0);
        assert_eq!(w.plates[1].plane.offset, 706.0);
    }

    #[test]
    fn a_bar_lying_across_a_plate_is_no_lap() {
        // A clamp 15 mm over one plate, which is seen on both of its sides;
        // the other plate lies 7 mm lower, the table further.
        let planes = || {
            vec![
                bar(685.0, 8_000.0, 0.0),
                cluster(700.0, 9_000.0, -40.0),
                cluster(700.0, 8_500.0, 40.0),
                cluster(707.0, 14_000.0, 80.0),
                cluster(760.0, 90_000.0, 0.0),
            ]
        };
        let lap = robust_select(planes(), &selection(JointType::Lap)).unwrap_err();
        assert!(matches!(lap, BackgroundError::LiesAcross { .. }), "{lap}");
        assert!(lap.to_string().contains("clamp"), "{lap}");
        // As butt plates, the two sides are a pair, and what lies between
        // their edges is the groove probe's to name.
        let butt = robust_select(planes(), &selection(JointType::IButt)).unwrap();
        assert_eq!(butt.workpiece.plates.each_ref().map(|p| p.plane.offset), [700.0, 700.0]);
        assert_eq!(robust_select(planes(), &auto()).unwrap().layout, Layout::Butt);
    }

    /// Points on a 1 mm grid over the rectangle `x`, `y` (mm, ends
    /// excluded) at depth `z`, leaving out those `hidden` keeps.
    fn grid(x: [i32; 2], y: [i32; 2], z: f64, hidden: impl Fn(f64, f64) -> bool) -> Vec<Vec3> {
        (x[0]..x[1])
            .flat_map(|i| (y[0]..y[1]).map(move |j| Vec3::new(i as f64 + 0.5, j as f64 + 0.5, z)))
            .filter(|p| !hidden(p.x, p.y))
            .collect()
    }

    /// A plane cluster of each group of points (each at its own depth),
    /// indexing the frame of all of them, returned with them.
    fn frame_of(groups: &[Vec<Vec3>]) -> (Vec<PlaneCluster>, Vec<Point>) {
        let all: Vec<Vec3> = groups.concat();
        let clusters = groups.iter().map(|g| PlaneCluster::of_points(&all, |p| p.z == g[0].z)).collect();
        (clusters, all.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect())
    }

    #[test]
    fn a_bar_across_a_plate_seen_round_its_end_is_no_lap() {
        // A clamp 30 mm wide, 15 mm over a plate 120 mm wide, from 10 mm
        // inside the plate's one side onto the lower plate past its
        // other: the plate is seen on both of the clamp's sides, one
        // cluster round its end. The lower plate lies 7 mm under it.
        let clamp = |x: f64, y: f64| (-50.0..70.0).contains(&x) && y.abs() < 15.0;
        let (planes, points) = frame_of(&[
            grid([-50, 70], [-15, 15], 685.0, |_, _| false),
            grid([-60, 60], [-100, 100], 700.0, clamp),
            grid([60, 160], [-100, 100], 707.0, clamp),
        ]);
        let err = super::robust_select(planes.clone(), &selection(JointType::Lap), &points).unwrap_err();
        let BackgroundError::LiesAcross { first_mm2, second_mm2, .. } = err else { panic!("{err}") };
        // Beside the clamp, 85 by 110 mm of the plate on either side.
        assert!((first_mm2 - 9_350.0).abs() < 200.0 && (second_mm2 - 9_350.0).abs() < 200.0, "{err}");
        // Without the points, the clusters alone do not show it.
        assert!(robust_select(planes, &selection(JointType::Lap)).is_ok());
    }

    #[test]
    fn a_bar_across_a_small_plate_beside_a_large_one_is_no_lap() {
        // Butt plates at 700: A 200 by 200 mm, B 58 mm wide beside it. A
        // clamp 24 mm wide lies across B, 21 mm over it, and stops short
        // of A: B is seen in two pieces, one on each side of the clamp,
        // each far smaller than A. The layer under the clamp, not its
        // largest piece, is what it lies across.
        let clamp = |p: &Vec3| (-70.0..-3.0).contains(&p.x) && (90.0..114.0).contains(&p.y);
        let all: Vec<Vec3> = [
            grid([-70, -3], [90, 114], 679.0, |_, _| false),
            grid([0, 200], [0, 200], 700.0, |_, _| false),
            grid([-60, -2], [0, 200], 700.0, |x, y| clamp(&Vec3::new(x, y, 0.0))),
        ]
        .concat();
        let planes = vec![
            PlaneCluster::of_points(&all, |p| p.z < 690.0),
            PlaneCluster::of_points(&all, |p| p.z > 690.0 && p.x > 0.0),
            PlaneCluster::of_points(&all, |p| p.z > 690.0 && p.x < 0.0 && p.y < 90.0),
            PlaneCluster::of_points(&all, |p| p.z > 690.0 && p.x < 0.0 && p.y > 114.0),
        ];
        let points: Vec<Point> = all.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let err = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap_err();
        let BackgroundError::LiesAcross { first_mm2, second_mm2, .. } = err else { panic!("{err}") };
        // Beside the clamp, B's two pieces: 58 by 90 and 58 by 86 mm.
        assert!((first_mm2 - 5_220.0).abs() < 100.0 && (second_mm2 - 4_988.0).abs() < 100.0, "{err}");
    }

    #[test]
    fn a_lap_whose_lower_plate_runs_on_past_the_upper_plates_end_is_kept() {
        // The upper plate 100 by 300 mm; the lower one, 6 mm under it,
        // reaches 20 mm under it and runs on 50 mm past its end, where
        // it is seen on both sides of the upper plate's long axis.
        let upper = |x: f64, y: f64| (-100.0..0.0).contains(&x) && (-150.0..150.0).contains(&y);
        let (planes, points) =
            frame_of(&[grid([-100, 0], [-150, 150], 700.0, |_, _| false), grid([-20, 100], [-150, 200], 706.0, upper)]);
        let chosen = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap();
        assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.centroid.z), [700.0, 706.0]);
    }

    #[test]
    fn a_lap_whose_lower_plate_is_seen_on_one_side_only_is_kept() {
        // The lower plate split in two along the seam (a streak), both
        // pieces beside the upper plate on the same side of it.
        let mut planes = vec![
            bar(700.0, 20_000.0, 0.0),
            cluster(706.0, 15_000.0, 60.0),
            cluster(706.0, 12_000.0, 60.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        planes[1].centroid.y = -80.0;
        planes[2].centroid.y = 80.0;
        let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
        assert_eq!(w.plates[0].plane.offset, 700.0);
        assert_eq!(w.plates[1].area_mm2, 15_000.0);
    }

    #[test]
    fn a_lap_s_lower_plate_is_the_plane_its_upper_plate_stands_beside_not_the_largest_of_its_layer() {
        // The upper plate over x < 0 at 700; the lower plate 6 mm under it
        // from x = -20, seen from x = 0 to 30; a larger part touching it
        // from x = 30 on lies 1.8 mm lower, in the same layer (3 mm).
        let upper = |x: f64, _: f64| x < 0.0;
        let (planes, points) = frame_of(&[
            grid([-100, 0], [-100, 100], 700.0, |_, _| false),
            grid([-20, 30], [-100, 100], 706.0, upper),
            grid([30, 110], [-100, 100], 707.8, |_, _| false),
        ]);
        let chosen = super::robust_select(planes.clone(), &selection(JointType::Lap), &points).unwrap();
        assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.centroid.z), [700.0, 706.0]);
        assert_eq!(chosen.workpiece.layer_mates[1].iter().map(|c| c.centroid.z).collect::<Vec<_>>(), [707.8]);
        assert!(chosen.evidence.contains("6.0 mm over a lower one of 6000 mm²"), "{}", chosen.evidence);
        // Without the points nothing says which stands beside it: the
        // largest, as before.
        let unread = robust_select(planes, &selection(JointType::Lap)).unwrap();
        assert_eq!(unread.workpiece.plates[1].centroid.z, 707.8);
        // Two pieces of the lower plate a streak splits along the seam
        // both stand beside the upper plate: the larger is taken.
        let (planes, points) = frame_of(&[
            grid([-100, 0], [-100, 100], 700.0, |_, _| false),
            grid([-20, 30], [-100, 10], 706.0, upper),
            grid([-20, 30], [12, 100], 706.5, upper),
        ]);
        let split = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap();
        assert_eq!(split.workpiece.plates[1].centroid.z, 706.0);
        // A plate 3.8 mm lower but 16 mm across, with the table between
        // (another workpiece): further than the band a 3.8 mm step hides
        // and the plates' rims, so it is not taken for the lower plate
        // because it is the nearer.
        let (planes, points) = frame_of(&[
            grid([-100, 0], [-100, 100], 700.0, |_, _| false),
            grid([16, 60], [-100, 100], 703.8, |_, _| false),
            grid([80, 200], [-100, 100], 704.0, |_, _| false),
        ]);
        let apart = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap();
        assert_eq!(apart.workpiece.plates[1].centroid.z, 704.0);
    }

    #[test]
    fn a_tee_s_flange_is_the_plane_its_web_stands_beside_not_a_larger_plate_in_its_layer() {
        // A web 8 mm thick along y, its top 80 mm over a flange seen on
        // both of its sides; 30 mm beyond the flange's +x piece, a larger
        // plate of another workpiece lies 2 mm higher, in the flange's
        // layer.
        let (planes, points) = frame_of(&[
            grid([-4, 4], [-100, 100], 680.0, |_, _| false),
            grid([4, 60], [-100, 100], 760.0, |_, _| false),
            grid([-40, -4], [-100, 100], 760.5, |_, _| false),
            grid([90, 200], [-100, 100], 758.0, |_, _| false),
        ]);
        let chosen = super::robust_select(planes.clone(), &selection(JointType::TFillet), &points).unwrap();
        assert_eq!(chosen.layout, Layout::Tee);
        assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.centroid.z), [680.0, 760.0]);
        let e = &chosen.evidence;
        assert!(e.contains("both of its sides") && e.contains("11200") && !e.contains("22000"), "{e}");
        // Without the points, the largest on each side, as before.
        let unread = robust_select(planes, &selection(JointType::TFillet)).unwrap();
        assert_eq!(unread.workpiece.plates[1].centroid.z, 758.0);
    }

    #[test]
    fn the_wrong_joint_requested_is_named_for_what_it_looks_like() {
        // A lap: the upper plate 6 mm over the lower one, the table behind.
        let lap = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
        for joint in [JointType::IButt, JointType::VButt] {
            let err = robust_select(lap.clone(), &selection(joint)).unwrap_err();
            assert!(err.is_joint_mismatch(), "{err}");
            assert!(err.to_string().contains("6.0 mm apart") && err.to_string().contains("looks like a lap"), "{err}");
        }
        // Butt plates side by side, the table 20 mm behind them (within a
        // lap's step range).
        let butt = vec![cluster(700.0, 30_000.0, -60.0), cluster(700.3, 25_000.0, 60.0), cluster(720.0, 90_000.0, 0.0)];
        let err = robust_select(butt.clone(), &selection(JointType::Lap)).unwrap_err();
        assert!(err.is_joint_mismatch() && err.to_string().contains("looks like a butt joint"), "{err}");
        assert!(robust_select(butt, &selection(JointType::IButt)).is_ok());
        // A clamp beside a lap's upper plate is not a second plate.
        let clamped = vec![
            cluster(700.0, 30_000.0, -60.0),
            cluster(700.5, 2_000.0, 60.0),
            cluster(706.0, 20_000.0, 50.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        assert!(robust_select(clamped, &selection(JointType::Lap)).is_ok());
    }

    #[test]
    fn with_no_type_given_the_layers_decide() {
        let lap = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
        let chosen = robust_select(lap, &auto()).unwrap();
        assert_eq!(chosen.layout, Layout::Lap);
        assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.plane.offset), [700.0, 706.0]);
        assert!(chosen.evidence.contains("6.0 mm over"), "{}", chosen.evidence);
        let butt = vec![cluster(700.0, 30_000.0, -60.0), cluster(700.3, 25_000.0, 60.0), cluster(720.0, 90_000.0, 0.0)];
        let chosen = robust_select(butt, &auto()).unwrap();
        assert_eq!(chosen.layout, Layout::Butt);
        assert_eq!(chosen.workpiece.depth_to_support_mm, Some(20.0));
        // A plate over a lower plate of its own, nearer than a coplanar
        // pair further on: the nearer top decides.
        let over = vec![
            cluster(694.0, 8_000.0, 0.0),
            cluster(700.0, 30_000.0, -60.0),
            cluster(710.0, 25_000.0, 60.0),
            cluster(710.3, 25_000.0, 160.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        assert_eq!(robust_select(over.clone(), &auto()).unwrap().layout, Layout::Lap);
        // A plate lying across a coplanar pair (a clamp or a fixture) is
        // not a lap's upper plate, however large.
        let across = vec![
            cluster(694.0, 20_000.0, 0.0),
            cluster(700.0, 30_000.0, -60.0),
            cluster(700.3, 25_000.0, 60.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        assert_eq!(robust_select(across, &auto()).unwrap().layout, Layout::Butt);
        // A plate with a small piece beside it, 4 mm over a lower plane: a
        // butt pair barely in view, or a lap's upper plate cut by a streak.
        let piece = vec![
            cluster(700.0, 20_000.0, 0.0),
            cluster(700.0, 1_600.0, -70.0),
            cluster(704.0, 40_000.0, -120.0),
            cluster(760.0, 90_000.0, 0.0),
        ];
        let err = robust_select(piece.clone(), &auto()).unwrap_err();
        assert!(matches!(err, BackgroundError::Ambiguous { .. }) && err.is_unrecognised(), "{err}");
        assert_eq!(robust_select(piece, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
        // Two planes 60 mm apart are neither.
        let apart = vec![cluster(700.0, 1000.0, 0.0), cluster(760.0, 1000.0, 0.0)];
        let err = robust_select(apart, &auto()).unwrap_err();
        assert!(err.is_unrecognised() && !err.is_joint_mismatch(), "{err}");
        assert!(err.to_string().contains("no two coplanar") && err.to_string().contains("no two layers"), "{err}");
    }

    #[test]
    fn failures_say_what_was_found() {
        let one = vec![cluster(700.0, 1000.0, 0.0)];
        assert_eq!(
            robust_select(one, &selection(JointType::IButt)).unwrap_err().to_string(),
            "found 1 workpiece plane(s), need 2"
        );
        let apart = vec![cluster(700.0, 1000.0, 0.0), cluster(760.0, 1000.0, 0.0)];
        assert!(matches!(
            robust_select(apart.clone(), &selection(JointType::IButt)),
            Err(BackgroundError::NoCoplanarPair { .. })
        ));
        assert!(matches!(robust_select(apart, &selection(JointType::Lap)), Err(BackgroundError::NoLapStep { .. })));
    }
}
