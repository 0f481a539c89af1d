//! The boundary read from a cloud without a grid: strips along the edge
//! walked outward until their on-plane points stop, with the shortfall a
//! noisy plate's thinning leaves measured on its interior and added.

use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::{MAD_PER_SIGMA, Vec3, extent, vec3};

use super::super::gather::gather_filter_map;
use super::{Boundary, BoundaryParams, BoundarySample, CoarseEdge, ExtentRule};

/// Samples the boundary of a plate beside `edge` in a cloud without a
/// pixel grid whose points lie about `spacing_mm` apart. Every valid point
/// on the plate's plane within the band counts, not only the plate's
/// members: the plane criterion has trimmed the outermost ones.
///
/// A strip has a boundary only where its on-plane points, walked outward
/// from the inner side of the band, stop: at the first empty stretch wider
/// than any the plate's interior shows ([`hole_threshold`]), or at the
/// band's outer side. A strip whose points run on through the band has
/// none: the plate goes on there (a lap's lower plate beyond the upper
/// plate's end), or a coplanar plate lies across a gap too narrow for this
/// cloud to show. Either way no edge is seen there, and none is invented.
pub fn sample_scattered(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    scatter_mm: Option<f64>,
) -> Boundary {
    use rayon::prelude::*;

    if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
        return Boundary::default();
    }
    // Two spacings: a strip one spacing wide misses the boundary row's
    // point about as often as it holds it, and its outermost point is then
    // a row in; at two the row is nearly always there.
    let strip_mm = STRIP_SPACINGS * spacing_mm;
    let points = cloud.points();
    let mut in_band: Vec<BandPoint> = gather_filter_map(points, |i, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        let d = v - edge.point;
        let out = d.dot(&edge.outward);
        let on_plane = plane.signed_distance(&v).abs() <= params.on_plane_mm;
        (on_plane && out.abs() <= params.band_mm).then(|| BandPoint {
            strip: strip_of(d.dot(&edge.direction), strip_mm),
            out,
            index: i as u32,
        })
    });
    // Strip by strip, each walked outward; the index settles a tie, so the
    // order does not depend on the sort.
    in_band
        .par_sort_unstable_by(|a, b| a.strip.cmp(&b.strip).then(a.out.total_cmp(&b.out)).then(a.index.cmp(&b.index)));
    let strips = || in_band.chunk_by(|a, b| a.strip == b.strip);
    let point = |b: &BandPoint| vec3(&points[b.index as usize]);
    let hole_mm = hole_threshold(strips(), params.band_mm, spacing_mm);
    let thinning = Thinning::measure(cloud, plane, edge, params, strip_mm, scatter_mm, strips());
    let samples = strips()
        .filter_map(|strip| {
            let last = strip_boundary(strip, hole_mm, params.band_mm)?;
            let (last_out, last_point) = (strip[last].out, point(&strip[last]));
            // The k points of the strip's last row (within half a spacing
            // of the outermost) split the spacing beyond the row into k + 1
            // gaps on average: the plate ends one gap beyond the outermost.
            let row = strip[..=last].iter().filter(|b| b.out >= last_out - spacing_mm / 2.0).count();
            let beyond = spacing_mm / (row + 1) as f64 + thinning.shortfall_mm(strip[last].strip);
            let position = plane.project(&last_point) + edge.outward * beyond;
            // The walk may end on a point past the plate's end along the
            // edge, where only the foot of a steep face grazes the plane
            // (a lap's upper plate running on beyond the lower plate): it
            // lies on the edge's line, so it places the edge across
            // rightly, but not where the plate is. The strip's points
            // inside the coarse edge are the plate's, and bound the
            // sample along the edge.
            let along = |p: &Vec3| (p - edge.point).dot(&edge.direction);
            let (lo, hi) = extent(strip[..=last].iter().filter(|b| b.out <= 0.0).map(|b| along(&point(b))));
            let shift = along(&position).clamp(lo, hi) - along(&position);
            let position = position + edge.direction * shift;
            Some(BoundarySample { position, along: along(&position) })
        })
        .collect();
    Boundary {
        samples,
        across_other_edge: Vec::new(),
        line_spacing_mm: strip_mm,
        extent_rule: ExtentRule::LongestStretch,
    }
}

/// How far off its plane, in sigmas of its own scatter about it, a point
/// of a plate without a pixel grid still counts as on it
/// ([`on_plane_for_scatter`]): 2.5 keeps 98.8 % of a plate's points under
/// normal noise.
const ON_PLANE_SIGMAS: f64 = 2.5;

/// The fewest points of a band's inner third [`plane_scatter`] measures
/// a sigma from.
const MIN_SCATTER_POINTS: usize = 30;

/// How far off a plate's plane, in point spacings (or on-plane
/// tolerances, where larger), [`plane_scatter`] first reads its points:
/// wider than any camera's depth noise at its own spacing, narrower than
/// the step to another surface.
const SCATTER_WINDOW_SPACINGS: f64 = 3.0;

/// How far the points of a plate scatter about its plane, one sigma (mm),
/// measured in a cloud without a pixel grid whose points lie about
/// `spacing_mm` apart, on the points of the inner third of the band beside
/// `edge` (a robust sigma: the median absolute distance over that of
/// normal noise), from the points within [`SCATTER_WINDOW_SPACINGS`] of
/// the plane and again within four of the sigmas found. The inner third
/// lies well inside the plate whatever the coarse edge's error, so the
/// lower plate of a lap, a groove's bevel or a web standing beside it do
/// not enter. `None` below [`MIN_SCATTER_POINTS`] points.
pub fn plane_scatter(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
) -> Option<f64> {
    let window_mm = SCATTER_WINDOW_SPACINGS * spacing_mm.max(params.on_plane_mm);
    let inner = -params.band_mm..=-params.band_mm / 3.0;
    let distances: Vec<f64> = gather_filter_map(cloud.points(), |_, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        let d = plane.signed_distance(&v);
        (d.abs() <= window_mm && inner.contains(&(v - edge.point).dot(&edge.outward))).then_some(d.abs())
    });
    let sigma_within = |window: f64| {
        let mut within: Vec<f64> = distances.iter().copied().filter(|d| *d <= window).collect();
        if within.len() < MIN_SCATTER_POINTS {
            return None;
        }
        let mid = within.len() / 2;
        Some(*within.select_nth_unstable_by(mid, f64::total_cmp).1 / MAD_PER_SIGMA)
    };
    let first = sigma_within(window_mm)?;
    // A window much wider than the noise takes in more than the plate's
    // points; one much narrower cuts its tails and reads too small a sigma.
    sigma_within((4.0 * first).min(window_mm)).or(Some(first))
}

/// The on-plane tolerance for a plate whose points scatter `sigma_mm`
/// about its plane: the configured one, or [`ON_PLANE_SIGMAS`] sigmas
/// where the noise is larger. A tolerance a camera's noise exceeds keeps a
/// fraction of the plate's points, the strips' outermost kept point then
/// lies rows inside the plate's end, and the edge is read inside the plate
/// (by about 0.5 sigma² mm at a consumer camera's 1 mm voxels: 0.9 mm at
/// 1.3 mm of depth noise).
pub(super) fn on_plane_for_scatter(configured_mm: f64, sigma_mm: Option<f64>) -> f64 {
    sigma_mm.map_or(configured_mm, |s| configured_mm.max(ON_PLANE_SIGMAS * s))
}

/// How far further inside a plate's end its strips' outermost on-plane
/// point lies because the on-plane tolerance keeps only a fraction of its
/// points ([`sample_scattered`]), strip by strip.
///
/// The plate ends, on average, as far beyond its outermost point as a
/// position taken at random inside the plate lies beyond the nearest
/// point on its inner side: for gaps g between consecutive points across
/// a strip, Σg² / 2Σg (half a pitch for rows at a fixed pitch, one mean
/// gap for points strewn at random). The difference between that mean for
/// the on-plane points and for all of the plate's points (within
/// [`ON_PLANE_SIGMAS`] of its measured noise) is what the tolerance's
/// thinning adds to the gap at the end; the row rule of
/// [`sample_scattered`] accounts for the rest. Both are read from the
/// band's inner third, where nothing but the plate lies near its plane
/// (not a groove's bevel, which the wider tolerance would take for the
/// plate beyond its edge), and pooled over [`THINNING_POOL_STRIPS`] strips
/// either side, since the noise changes with depth along the edge.
struct Thinning {
    /// Per strip with points in the inner third, ascending: the strip and
    /// the running sums, from the first strip through this one, of Σg and
    /// Σg² over the on-plane points' gaps and over all the plate's points'.
    running: Vec<(i32, [f64; 4])>,
}

/// How many strips either side of a strip [`Thinning`] pools its gaps
/// over: ten spacings along the edge, over which the noise hardly changes.
const THINNING_POOL_STRIPS: i32 = 5;

impl Thinning {
    /// None where the plate's noise is within the tolerance (every point
    /// of the plate is on its plane), or unknown.
    fn none() -> Self {
        Thinning { running: Vec::new() }
    }

    fn measure<'a>(
        cloud: &PointCloud,
        plane: &Plane,
        edge: &CoarseEdge,
        params: &BoundaryParams,
        strip_mm: f64,
        scatter_mm: Option<f64>,
        on_plane: impl Iterator<Item = &'a [BandPoint]>,
    ) -> Self {
        let all_mm = on_plane_for_scatter(params.on_plane_mm, scatter_mm);
        if all_mm <= params.on_plane_mm {
            return Thinning::none();
        }
        let inner = -params.band_mm..=-params.band_mm / 3.0;
        let mut all: Vec<(i32, f64)> = gather_filter_map(cloud.points(), |_, p| {
            if !p[0].is_finite() {
                return None;
            }
            let v = vec3(p);
            let d = v - edge.point;
            let out = d.dot(&edge.outward);
            let near_plane = plane.signed_distance(&v).abs() <= all_mm;
            (near_plane && inner.contains(&out)).then(|| (strip_of(d.dot(&edge.direction), strip_mm), out))
        });
        all.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut per_strip: std::collections::BTreeMap<i32, [f64; 4]> = std::collections::BTreeMap::new();
        for strip in on_plane {
            let [s1, s2] = gap_sums(strip.iter().map(|b| b.out).filter(|out| inner.contains(out)));
            let entry = per_strip.entry(strip[0].strip).or_default();
            (entry[0], entry[1]) = (s1, s2);
        }
        for strip in all.chunk_by(|a, b| a.0 == b.0) {
            let [s1, s2] = gap_sums(strip.iter().map(|a| a.1));
            let entry = per_strip.entry(strip[0].0).or_default();
            (entry[2], entry[3]) = (s1, s2);
        }
        let mut total = [0.0; 4];
        let running = per_strip
            .into_iter()
            .map(|(strip, sums)| {
                for (t, s) in total.iter_mut().zip(sums) {
                    *t += s;
                }
                (strip, total)
            })
            .collect();
        Thinning { running }
    }

    /// How much further in than the row rule says strip `strip`'s
    /// outermost on-plane point lies, mm; zero where nothing was thinned.
    fn shortfall_mm(&self, strip: i32) -> f64 {
        let upto = |s: i32| {
            let n = self.running.partition_point(|(k, _)| *k <= s);
            n.checked_sub(1).map_or([0.0; 4], |i| self.running[i].1)
        };
        let (hi, lo) =
            (upto(strip.saturating_add(THINNING_POOL_STRIPS)), upto(strip.saturating_sub(THINNING_POOL_STRIPS + 1)));
        let sums: [f64; 4] = std::array::from_fn(|i| hi[i] - lo[i]);
        let empty_space = |s1: f64, s2: f64| (s1 > 0.0).then(|| s2 / (2.0 * s1));
        match (empty_space(sums[0], sums[1]), empty_space(sums[2], sums[3])) {
            (Some(on_plane), Some(all)) => (on_plane - all).max(0.0),
            _ => 0.0,
        }
    }
}

/// Σg and Σg² over the gaps g between consecutive values of `outs`
/// (ascending).
fn gap_sums(outs: impl Iterator<Item = f64>) -> [f64; 2] {
    let mut previous: Option<f64> = None;
    let mut sums = [0.0; 2];
    for out in outs {
        if let Some(before) = previous {
            let gap = out - before;
            sums[0] += gap;
            sums[1] += gap * gap;
        }
        previous = Some(out);
    }
    sums
}

/// The width of [`sample_scattered`]'s strips, in point spacings.
pub(super) const STRIP_SPACINGS: f64 = 2.0;

/// The narrowest empty stretch across a strip taken for the plate's end,
/// in point spacings: rows lie about one spacing apart, so a stretch half
/// as wide again is already rare inside a plate.
const MIN_HOLE_SPACINGS: f64 = 1.5;

/// How much wider than the plate interior's widest common stretch (its
/// 99th percentile) an empty stretch must be to end the plate.
pub(super) const HOLE_OVER_INTERIOR: f64 = 1.25;

/// The empty stretch across a strip that ends a plate, mm: measured on the
/// cloud itself, from the gaps between consecutive points in the inner
/// third of the band (well inside the plate, whatever the coarse edge's
/// error), and never under [`MIN_HOLE_SPACINGS`] spacings. Voxel centroids
/// of a tilted plate, or a camera's anisotropic grid, leave wider gaps
/// than the mean spacing says; this keeps them from ending the plate.
fn hole_threshold<'a>(strips: impl Iterator<Item = &'a [BandPoint]> + Clone, band_mm: f64, spacing_mm: f64) -> f64 {
    let inner = -band_mm / 3.0;
    let gaps =
        strips.flat_map(|strip| strip.windows(2).filter(move |w| w[1].out <= inner).map(|w| w[1].out - w[0].out));
    let floor = MIN_HOLE_SPACINGS * spacing_mm;
    percentile_99(gaps).map_or(floor, |q99| floor.max(HOLE_OVER_INTERIOR * q99))
}

/// The 99th percentile of `values`, the value a sort puts at rank
/// ⌊0.99 n⌋ (the last for fewer than a hundred); `None` when there are
/// none. The values are read twice, counted and then scanned keeping the
/// largest hundredth, so a band's thousands of gaps are never held.
pub(super) fn percentile_99(values: impl Iterator<Item = f64> + Clone) -> Option<f64> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    let n = values.clone().count();
    let rank = (n * 99 / 100).min(n.checked_sub(1)?);
    // The values from the rank up: the rank's is the least of them.
    let kept = n - rank;
    let mut largest = BinaryHeap::with_capacity(kept + 1);
    for v in values {
        largest.push(Reverse(TotalOrder(v)));
        if largest.len() > kept {
            largest.pop();
        }
    }
    largest.peek().map(|Reverse(TotalOrder(v))| *v)
}

/// An `f64` ordered by [`f64::total_cmp`].
#[derive(Debug, Clone, Copy)]
struct TotalOrder(f64);

impl PartialEq for TotalOrder {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other).is_eq()
    }
}

impl Eq for TotalOrder {}

impl PartialOrd for TotalOrder {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for TotalOrder {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The index of a strip's last point before the plate ends, walking
/// outward from the band's inner side; `None` when the points run on to
/// the band's outer side (no end seen), or when they start outside the
/// coarse edge. The coarse edge runs through the plate's edge points, a
/// little inside the plate, so a run that starts inside it is the plate's;
/// one that starts outside lies past the plate's end: another plate's
/// points, or the foot of a steep face (a lap's upper plate beyond the
/// lower plate's end) whose lowest points graze the plane. Where the image
/// border cuts the band this also drops the strips that see only the
/// plate's outer rim, and the seam stops up to a millimetre or two short
/// of the border: short, never beyond. `strip` is sorted by outward offset.
fn strip_boundary(strip: &[BandPoint], hole_mm: f64, band_mm: f64) -> Option<usize> {
    if strip.first()?.out > 0.0 {
        return None;
    }
    strip.windows(2).position(|w| w[1].out - w[0].out > hole_mm).or_else(|| {
        let last = strip.len() - 1;
        (band_mm - strip[last].out > hole_mm).then_some(last)
    })
}

/// The strip `along_mm` along an edge falls in, for strips `strip_mm`
/// wide. A cloud spans a few thousand strips; clamping could only join
/// strips far past any plate.
fn strip_of(along_mm: f64, strip_mm: f64) -> i32 {
    crate::geometry::floor_i64(along_mm / strip_mm).clamp(i32::MIN.into(), i32::MAX.into()) as i32
}

/// An on-plane point of the band beside an edge in a cloud without a
/// pixel grid ([`sample_scattered`]): the strip along the edge it falls
/// in, its offset outward across the edge, and its index in the cloud,
/// which gives the point itself when a strip's sample needs it (16 bytes,
/// where the strip, the offset and the point took 40).
#[derive(Debug, Clone, Copy, Default)]
struct BandPoint {
    out: f64,
    strip: i32,
    index: u32,
}
