//! Corner joints: a plate's edge beside a larger plane seen on one of its
//! sides only, with nothing at their level beyond it ([`find_corner`]).
//! Their plates pass for a butt pair, a lap or a tee, so they are looked
//! for before the layers are read.

use crate::cloud::Point;
use crate::geometry::{Vec3, extent, vec3};
use crate::rules::{self, Rule};

use super::super::view_border::ViewBorder;
use super::super::web_face::MAX_FACE_LEAN_DEG;
use super::placement::{BAR_ELONGATION, SIDE_BY_SIDE_AREA_RATIO, member_points, side_of, spacing_of};
use super::{BackgroundError, CornerKind, PlaneCluster, Selection};

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

    /// The rule that decides the corner under a request that admits a
    /// fillet (`fillet_admitted`) or not: an inside corner's root planned
    /// as a tee's, else the corner's refusal ([`BackgroundError::rule`]).
    pub fn rule(&self, fillet_admitted: bool) -> &'static Rule {
        match self.kind {
            CornerKind::Inside if fillet_admitted => &rules::background::CORNER_INSIDE_PLANNED_AS_TEE_ROOT,
            _ => self.refusal().rule(),
        }
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
/// - the flange is not seen beside the top's edge over at least
///   [`MIN_BESIDE_SHARE`] of it (it lies off the top's ends: the top is
///   a sliver of plate continuing it, such as a beam's top beyond a tube
///   standing near its edge);
/// - a drop beside a flange under four times the top's size;
/// - an outside corner's edge (and, without the table, an inside
///   corner's) that does not touch the flange;
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
    // Read from the clusters' own points, before the pass over the whole
    // cloud. A corner's plates meet along the whole joint, so the flange is
    // seen beside the edge wherever the edge is seen (but for a dropout).
    let stations = Stations::along(top, away, s.neighbour_radius_mm, points);
    let beside = flange_beside(&stations, flange, points);
    if beside.share < MIN_BESIDE_SHARE {
        return None;
    }
    // An outside corner's edge touches its flange, and so does an inside
    // corner's where the table is out of the cloud; a tee's flange on the
    // web's far side lies a web's thickness off (a sliver of flange beyond
    // a web near its edge is as narrow as a plate's edge), a V-groove's
    // other plate a groove's width. Touching clusters still lie apart by
    // their rims: a plane point needs its whole neighbourhood on the plane,
    // so each cluster stops up to a neighbour radius short of the step
    // between them (the simulated outside corners: 1.3 to 2.0 mm apart at
    // a 1 mm radius and 0.2 to 0.4 mm spacing).
    let touch_mm = 2.0 * s.neighbour_radius_mm + 2.0 * spacing_of(top);
    let touches = beside.gap_mm.is_some_and(|gap| gap <= touch_mm);
    let outside = step <= s.lap_step_max_mm;
    if (outside || !seen_whole) && !touches {
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
    let gap_mm = beside.gap_mm;
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
    if !touches {
        return None;
    }
    if below >= CORNER_DEEP_RETURNS_MIN {
        return (on_face as f64 >= FACE_SHARE_MIN * below as f64).then_some(Beyond::Face { deepest_mm: deepest });
    }
    Some(Beyond::Nothing { far_edge: outermost_along(&stations, points) })
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

/// The least share of the stations along a plate's edge at which the
/// flange is seen beside it (on its own side of the edge) for the two to
/// be a corner's plates. A corner's flange runs along the whole joint; the
/// simulated corners show it beside 69 % of the edge and more (a dropout
/// or the flange's own shadow takes the rest), a plate continuing off a
/// sliver's end beside none of it.
const MIN_BESIDE_SHARE: f64 = 0.5;

/// How the flange lies beside a plate's edge ([`flange_beside`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Beside {
    /// How far apart the top's edge towards the flange and the flange's
    /// edge towards it lie, mm: the median over the stations where both
    /// have points. `None` where they share no station.
    gap_mm: Option<f64>,
    /// The share of the stations where the top is seen at which the flange
    /// is seen beside it.
    share: f64,
}

/// How the flange lies beside the top's edge towards it (against the
/// stations' `away`), station by station: the flange's points counted are
/// those on its own side of the top's edge.
fn flange_beside(stations: &Stations, flange: &PlaneCluster, points: &[Point]) -> Beside {
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
    let seen = inner.iter().filter(|edge| edge.is_finite()).count();
    let share = gaps.len() as f64 / seen.max(1) as f64;
    gaps.sort_by(f64::total_cmp);
    Beside { gap_mm: gaps.get(gaps.len() / 2).copied(), share }
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
