//! The seam's ends read again from the plate's last rows along the fitted
//! edge, where the strips or scan lines mistake them at the cloud's
//! border.

use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, extent, vec3};

use super::super::gather::gather_filter_map;
use super::scattered::{HOLE_OVER_INTERIOR, STRIP_SPACINGS, percentile_99};
use super::{BoundaryParams, CoarseEdge};

/// Refines the ends of a weld edge's extent `(lo, hi)`, read from strips
/// to a strip's width, where the cloud's border cuts the plate, in a cloud
/// without a pixel grid, in the camera frame. `edge` is a line fitted to
/// the boundary samples, `edge_rms_mm` its fit's RMS; `along` gives the
/// coordinate the extent is in.
///
/// Where the image border or a crop cuts the band beside the weld, a
/// strip sees part of the plate only and either misses the edge (the
/// seam stops short) or takes the border for it (the seam runs on). The
/// rows between half a spacing and a spacing and a half inside the edge
/// ([`RIM_ROWS_SPACINGS`]) run wherever the plate runs beside the weld,
/// and nothing beyond the edge (another plate, the foot of a face grazing
/// the plane) lies in them. Each end walks along the rim's on-plane
/// points from a point well inside the strips' extent for as long as they
/// follow one another within [`RIM_BREAK_SPACINGS`] (or the rim's own
/// steps), and across a stretch the rows miss where the plate is seen on
/// both sides of them ([`RimBands::reach`]); the plate ends half a spacing
/// beyond the last point.
///
/// The rim's end is taken only where the cloud itself ends there: where
/// no point of any depth, carried along its line of sight onto the
/// plate's plane, lies in the rows beyond it ([`RIM_AT_BORDER_SPACINGS`]).
/// Elsewhere the table or a shadow lies beyond a plate's own end, and the
/// strips read that end. A rim that stops more than a spacing short of
/// the rows' last points moves an end in only where the strips run past
/// all of them. Where the edge's fit scatters too much to place the rows
/// ([`MAX_RIM_EDGE_RMS_SPACINGS`]), the extent stays.
#[allow(clippy::too_many_arguments)]
pub fn rim_refined_extent(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    edge_rms_mm: f64,
    along: impl Fn(&Vec3) -> f64 + Sync,
    (lo, hi): (f64, f64),
) -> (f64, f64) {
    // The rows keep half a spacing clear of the fitted edge: an edge whose
    // samples scatter by more than a quarter spacing (two RMS past the
    // clearance) wanders in and out of them, and its rim says nothing.
    let known = edge_rms_mm <= MAX_RIM_EDGE_RMS_SPACINGS * spacing_mm;
    if !(spacing_mm.is_finite() && spacing_mm > 0.0 && known) {
        return (lo, hi);
    }
    let inside = RIM_START_STRIPS * STRIP_SPACINGS * spacing_mm;
    if hi - lo <= 2.0 * inside {
        return (lo, hi);
    }
    let [inner, outer] = RIM_ROWS_SPACINGS.map(|rows| -rows * spacing_mm);
    let beside = RIM_BESIDE_SPACINGS * spacing_mm;
    let offset = |q: &Vec3| (q - edge.point).dot(&edge.outward);
    // Every on-plane point of the rows and of the bands beside them, and
    // every other point whose line of sight crosses the plate's plane in
    // the rows (the plane n·x = offset meets the line of sight t v at
    // t = offset / n·v), by where it lies along the edge.
    let classified: Vec<(f64, RimBand)> = gather_filter_map(cloud.points(), |_, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        if plane.signed_distance(&v).abs() <= params.on_plane_mm {
            let band = RimBand::of(offset(&v), [inner, outer], beside)?;
            return Some((along(&v), band));
        }
        let t = plane.offset / plane.normal.dot(&v);
        let q = v * t;
        let crosses = t.is_finite() && t > 0.0 && (outer..=inner).contains(&offset(&q));
        crosses.then(|| (along(&q), RimBand::SightLine))
    });
    let sorted = |wanted: RimBand| {
        let mut at: Vec<f64> = classified.iter().filter(|c| c.1 == wanted).map(|c| c.0).collect();
        at.sort_unstable_by(f64::total_cmp);
        at
    };
    let [rim, near, deep] = [RimBand::Rows, RimBand::Near, RimBand::Deep].map(sorted);
    // The rows' extent as the cloud shows it, whatever lies in them.
    let in_view = classified.iter().filter(|c| matches!(c.1, RimBand::Rows | RimBand::SightLine)).map(|c| c.0);
    let (view_lo, view_hi) = extent(in_view);
    if rim.is_empty() {
        return (lo, hi);
    }
    // A tilted plate's voxel centroids, or a camera's anisotropic grid,
    // leave wider steps along the rim than the mean spacing says: the
    // rim's own steps set the break, as the plate's do for the strips.
    let typical = percentile_99(rim.windows(2).map(|w| w[1] - w[0])).unwrap_or(0.0);
    let break_mm = (RIM_BREAK_SPACINGS * spacing_mm).max(HOLE_OVER_INTERIOR * typical);
    let half = spacing_mm / 2.0;
    let border_mm = RIM_AT_BORDER_SPACINGS * spacing_mm;
    let bands = RimBands { rim: &rim, near: &near, deep: &deep, break_mm };
    // A rim that runs to within a spacing of the rows' last points has
    // seen the plate go on until the cloud ends. One that stops further
    // short, with points off the plane beyond it in the rows, may have
    // lost the plate's last points to noise rather than seen its end: it
    // moves an end in only where the strips read past everything the rows
    // show by more than a strip (their extent adds half of one), taking
    // the border for the edge.
    let strip_mm = STRIP_SPACINGS * spacing_mm;
    let end = match rim.iter().rposition(|&a| a <= hi - inside) {
        Some(from) => {
            let rim_end = bands.reach(rim[from], Sense::Up);
            let at_border = view_hi - rim_end <= border_mm;
            let (refined, kept) = (rim_end + half, hi);
            let trusted = refined >= kept || view_hi - rim_end <= spacing_mm || kept > view_hi + strip_mm;
            if at_border && trusted { refined } else { kept }
        }
        None => hi,
    };
    let start = match rim.iter().position(|&a| a >= lo + inside) {
        Some(from) => {
            let rim_start = bands.reach(rim[from], Sense::Down);
            let at_border = rim_start - view_lo <= border_mm;
            let (refined, kept) = (rim_start - half, lo);
            let trusted = refined <= kept || rim_start - view_lo <= spacing_mm || kept < view_lo - strip_mm;
            if at_border && trusted { refined } else { kept }
        }
        None => lo,
    };
    (start, end)
}

/// The plate's on-plane points in its rim (the rows [`rim_refined_extent`]
/// follows and the band as wide again deeper in: half a spacing to two
/// and a half inside the fitted `edge`, clear of whatever lies beyond
/// it) within `near_mm` along the edge of either end of `(lo, hi)`, as
/// `along` reads a point: where the plate's last rows run at each end of
/// its edge, to tell whether the image's border cut them there.
#[allow(clippy::too_many_arguments)]
pub fn rim_points_at_ends(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    along: impl Fn(&Vec3) -> f64 + Sync,
    (lo, hi): (f64, f64),
    near_mm: f64,
) -> Vec<Vec3> {
    let [inner, outer] = RIM_ROWS_SPACINGS.map(|rows| -rows * spacing_mm);
    let rim = (outer - RIM_BESIDE_SPACINGS * spacing_mm)..=inner;
    gather_filter_map(cloud.points(), |_, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        let at = along(&v);
        let at_an_end = (at - lo).abs() <= near_mm || (at - hi).abs() <= near_mm;
        let in_rim = || rim.contains(&(v - edge.point).dot(&edge.outward));
        (at_an_end && plane.signed_distance(&v).abs() <= params.on_plane_mm && in_rim()).then_some(v)
    })
}

/// Where a point read by [`rim_refined_extent`] lies across the edge. (Its
/// default only fills the slots of a gathered vector before they are
/// written.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum RimBand {
    /// On the plate's plane, in the rows the rim follows.
    #[default]
    Rows,
    /// On the plane, between the rows and the fitted edge.
    Near,
    /// On the plane, deeper into the plate than the rows.
    Deep,
    /// Off the plane, its line of sight crossing the plane in the rows.
    SightLine,
}

impl RimBand {
    /// The band of an on-plane point `offset` mm outward of the fitted
    /// edge, with the rows `[inner, outer]` (both negative, inside the
    /// plate) and bands `beside` mm wide on either side of them.
    fn of(offset: f64, [inner, outer]: [f64; 2], beside: f64) -> Option<Self> {
        if (outer..=inner).contains(&offset) {
            Some(Self::Rows)
        } else if (inner..=(inner + beside).min(0.0)).contains(&offset) {
            Some(Self::Near)
        } else if ((outer - beside)..outer).contains(&offset) {
            Some(Self::Deep)
        } else {
            None
        }
    }
}

/// Which way along the edge a rim walk goes.
#[derive(Debug, Clone, Copy)]
enum Sense {
    Up,
    Down,
}

impl Sense {
    /// The nearer of two positions to where a walk this way started.
    fn nearer(self, a: f64, b: f64) -> f64 {
        match self {
            Sense::Up => a.min(b),
            Sense::Down => a.max(b),
        }
    }

    /// Whether `a` lies beyond `b`, going this way.
    fn beyond(self, a: f64, b: f64) -> bool {
        match self {
            Sense::Up => a > b,
            Sense::Down => a < b,
        }
    }
}

/// The along-edge positions (sorted) of the on-plane points of the rim's
/// rows and of the bands beside them, and the widest step that continues
/// a walk.
struct RimBands<'a> {
    rim: &'a [f64],
    near: &'a [f64],
    deep: &'a [f64],
    break_mm: f64,
}

impl RimBands<'_> {
    /// How far the plate runs beside the weld from `from`, a point of the
    /// rows, in `sense`. The rows are one point spacing wide, and the rows
    /// of a lattice (voxel centroids) can run along them a little further
    /// apart than that: where the last lattice row leaves them and the
    /// next has not yet come in, the rows hold no point for a stretch
    /// although the plate goes on. Such a stretch has the plate on both
    /// sides of the rows, nearer the edge and deeper in; where a border
    /// cuts the plate obliquely, or the plate ends, one side stops with
    /// the rows. So the walk follows the rows, then goes on as far as both
    /// bands beside them go on together, and from there along the rows
    /// again.
    fn reach(&self, from: f64, sense: Sense) -> f64 {
        let mut at = from;
        // Each round moves `at` on to a further point, so the rounds are
        // at most the points there are.
        for _ in 0..=self.rim.len() + self.near.len() + self.deep.len() {
            let along_rows = walk(self.rim, at, self.break_mm, sense);
            let [near, deep] = [self.near, self.deep].map(|band| walk(band, along_rows, self.break_mm, sense));
            let bracketed = sense.nearer(near, deep);
            if !sense.beyond(bracketed, along_rows) {
                return along_rows;
            }
            at = bracketed;
        }
        at
    }
}

/// The furthest of the sorted positions `at` reached from `from` in
/// `sense` by steps of at most `break_mm`; `from` when none is.
fn walk(at: &[f64], from: f64, break_mm: f64, sense: Sense) -> f64 {
    let mut reached = from;
    match sense {
        Sense::Up => {
            for &a in &at[at.partition_point(|&a| a <= from)..] {
                if a - reached > break_mm {
                    break;
                }
                reached = a;
            }
        }
        Sense::Down => {
            for &a in at[..at.partition_point(|&a| a < from)].iter().rev() {
                if reached - a > break_mm {
                    break;
                }
                reached = a;
            }
        }
    }
    reached
}

/// How close to the cloud's end along the rim's rows, in point spacings,
/// the rim must run for [`rim_refined_extent`] to take the plate's end
/// from it: where the cloud ends, the rim ends within a step or two of
/// the last point of any depth in its rows.
const RIM_AT_BORDER_SPACINGS: f64 = 3.0;

/// The largest RMS of an edge's fit, in point spacings, for which
/// [`rim_refined_extent`] reads its rim: two RMS within the rows' half a
/// spacing of clearance. A noisy cloud's edge (a consumer camera's at
/// 400 mm and beyond) keeps the strips' ends.
const MAX_RIM_EDGE_RMS_SPACINGS: f64 = 0.25;

/// The rows [`rim_refined_extent`] follows, as offsets inside a fitted
/// edge in point spacings: the plate's last row lies within a spacing of
/// its end, so this band of one spacing holds a point about every spacing
/// along the plate, and is half a spacing clear of the edge, where the
/// foot of a face or the noise of the edge's fit could put points.
const RIM_ROWS_SPACINGS: [f64; 2] = [0.5, 1.5];

/// The width, in point spacings, of the bands on either side of the rim's
/// rows that show the plate going on where the rows hold no point
/// ([`RimBands::reach`]): the one nearer the edge is the half spacing the
/// rows keep clear of it, the deeper one as wide as the rows.
const RIM_BESIDE_SPACINGS: f64 = 1.0;

/// The widest step along the rim, in point spacings, that still continues
/// it: a point every spacing on average, so three is a dropout or two.
const RIM_BREAK_SPACINGS: f64 = 3.0;

/// How far inside the strips' extent, in strips, a rim walk starts: the
/// strips read each end to about one strip.
const RIM_START_STRIPS: f64 = 2.0;
