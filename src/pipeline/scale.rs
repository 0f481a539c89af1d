//! The scale of a cloud: how far apart its points are, and from that the
//! neighbour radius and the full-plane neighbour count the criteria are
//! measured against.
//!
//! The paper derives the count a full plane gives within the radius R from
//! the camera (Eq. 4 to 14: resolution, density at the working distance,
//! the accuracy correction), and the robust method refines that to the
//! lattice count of the plane tilted to the workpiece. That holds for a raw
//! frame of the configured camera and for nothing else: a cloud that was
//! voxel-downsampled, merged, cropped or taken by another camera has its
//! own spacing, 3 to 40 times sparser in the public scans we tried, and
//! against the camera's count no point is a plane point; at the paper's
//! R = 1 mm a 1 mm grid leaves almost no neighbours at all.
//!
//! So for such a cloud both come from the data:
//! - the spacing `s` is measured from the neighbour counts of an even
//!   sample of points: a surface with areal density ρ gives ρ π r² points
//!   within r, so `s = 1/√ρ = r √(π / median count)`, the radius r doubled
//!   until the median count is large enough to measure;
//! - the radius becomes `max(R, s √(N / π))`, the radius at which a full
//!   plane holds [`TARGET_FULL_COUNT`] points: enough that the count's
//!   sampling noise stays well inside the criteria's margins (0.8 and 0.75
//!   of the full count);
//! - the full-plane count is measured locally, because density changes
//!   with depth and tilt even in one cloud: in cubes of
//!   [`DENSITY_CELL_RADII`] radii, over an even sample of the cube's
//!   points whose neighbours surround them (no empty quarter around the
//!   point, [`surrounded`]: edge points are left out), the lower quartile
//!   of their counts. Not the median: resampling leaves a plate's density
//!   uneven, and only ever upwards. Where a voxel grid cuts a plate tilted
//!   a few degrees, the surface crosses a layer of voxels every few
//!   millimetres and each crossing yields a double row of centroids: the
//!   counts swing between the base density and half as much again, and a
//!   median between the two would make the plate's base stripes look like
//!   edges to Eq. 15.
//!
//! Nothing here knows the camera: it measures the cloud.

#[cfg(test)]
use std::ops::ControlFlow;

use rayon::prelude::*;

use crate::cloud::{Point, PointCloud};
use crate::geometry::{Vec3, vec3};

use super::Deadline;
#[cfg(test)]
use super::neighbours::cells::CellIndex;
use super::neighbours::cells::counts_around;
use super::neighbours::{MAX_SAMPLED_NEIGHBOURS, NeighbourSearch};
use super::orientation::scatter_normal_of_visit;

/// The full-plane neighbour count the derived radius aims at. Counts of
/// well-spread points scatter by a few points around their mean; at 50 the
/// scatter is under a tenth, inside the plane criterion's 0.8 and the edge
/// criterion's 0.75.
pub(crate) const TARGET_FULL_COUNT: f64 = 50.0;

/// The least median neighbour count the spacing is read from: below it a
/// count is too coarse a measure of density, and the radius doubles.
const MIN_MEASURED_COUNT: u32 = 12;

/// Counts are read up to this many neighbours: enough for a density twenty
/// times the target, few enough that a clump costs little.
const MAX_MEASURED_COUNT: u32 = 1024;

/// The sample the spacing is measured on.
const SPACING_SAMPLES: usize = 4096;

/// The largest radius the spacing search doubles to, mm: a cloud sparser
/// than a point per few centimetres has no plate a weld can be planned on.
pub(crate) const MAX_MEASURING_RADIUS_MM: f64 = 64.0;

/// The side of the cubes the full-plane count is measured in, in radii.
const DENSITY_CELL_RADII: f64 = 8.0;

/// The points sampled per cube, at most.
const DENSITY_SAMPLES_PER_CELL: usize = 48;

/// The fewest sampled points a cube's own median is trusted with; sparser
/// cubes take the cloud's median.
const MIN_DENSITY_SAMPLES: usize = 8;

/// The sectors a point's neighbourhood is divided into around it, and how
/// many adjacent empty ones (a quarter turn) make its neighbours not
/// surround it.
const SECTORS: u32 = 16;
// The sectors by comparison ([`sector_of`]) are sixteenths of a turn.
const _: () = assert!(SECTORS == 16);
const EMPTY_SECTORS_OF_AN_EDGE: u32 = 4;

/// Neighbours nearer than this share of the radius carry no direction
/// (they sit on the point, as resampled duplicates do).
const MIN_DIRECTION_RADII: f64 = 0.05;

/// Whether the neighbours of point `i`, seen along the unit `normal`, lie
/// all around it: no empty sector of a quarter turn or more. Inside a
/// surface they do at any density; at its edge half the turn is empty.
/// This is the boundary test of angle gaps (as in PCL's boundary
/// estimation, with sectors instead of sorted angles), which density
/// changes cannot fool.
pub(crate) fn surrounded(search: &NeighbourSearch, i: usize, normal: &Vec3) -> bool {
    surrounded_by(search, i, normal, |_| true)
}

/// [`surrounded`] by the neighbours `j` for which `member(j)` holds.
pub(crate) fn surrounded_by(search: &NeighbourSearch, i: usize, normal: &Vec3, member: impl Fn(usize) -> bool) -> bool {
    let points = search.cloud().points();
    let mut sectors = Sectors::around(&points[i], normal, search.radius_mm());
    search.for_each(i, |j| {
        if member(j) {
            sectors.add(&points[j]);
        }
    });
    sectors.surrounded()
}

/// The sectors around a point occupied by its neighbours, seen along a
/// normal: the state of [`surrounded_by`].
struct Sectors {
    p: Vec3,
    /// Two unit vectors square to the normal and to each other.
    e1: Vec3,
    e2: Vec3,
    min_sq: f64,
    occupied: u32,
}

impl Sectors {
    fn around(p: &Point, normal: &Vec3, radius_mm: f64) -> Sectors {
        let e1 = normal.cross(&if normal.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() }).normalize();
        let e2 = normal.cross(&e1);
        let min_sq = (MIN_DIRECTION_RADII * radius_mm).powi(2);
        Sectors { p: vec3(p), e1, e2, min_sq, occupied: 0 }
    }

    #[inline]
    fn add(&mut self, q: &Point) {
        let d = vec3(q) - self.p;
        let (a, b) = (d.dot(&self.e1), d.dot(&self.e2));
        if a * a + b * b >= self.min_sq {
            self.occupied |= 1 << sector_of(a, b);
        }
    }

    fn surrounded(&self) -> bool {
        longest_empty_run(self.occupied) < EMPTY_SECTORS_OF_AN_EDGE
    }
}

/// The sector of the direction `(a, b)`: [`SECTORS`] equal turns counted
/// from the direction `(-1, 0)` the positive way, as [`sector_by_angle`]
/// numbers them.
///
/// By comparisons instead of an arc tangent: the signs give the quadrant,
/// and within it the boundaries at 22.5°, 45° and 67.5° are the lines
/// `|b| = t |a|`, `|b| = |a|` and `|a| = t |b|` with `t = tan 22.5°`.
/// A direction within a billionth of its length of a boundary (the axes
/// included, where the sign of a zero may decide) goes to
/// [`sector_by_angle`]: so far from a boundary neither form's rounding, a
/// few parts in 10¹⁶, can put it on the other side.
#[inline]
fn sector_of(a: f64, b: f64) -> u32 {
    const TAN_EIGHTH_TURN_HALVED: f64 = std::f64::consts::SQRT_2 - 1.0;
    const CLEAR: f64 = 1e-9;
    let (x, y) = (a.abs(), b.abs());
    let margin = CLEAR * (x + y);
    let gaps = [y - TAN_EIGHTH_TURN_HALVED * x, y - x, TAN_EIGHTH_TURN_HALVED * y - x];
    // The axes are boundaries too. NaN or infinite lengths fail the first
    // test and go to the reference as well; past it the gaps are finite.
    if !(x > margin && y > margin) || gaps.iter().any(|g| g.abs() < margin) {
        return sector_by_angle(a, b);
    }
    // The sixteenth of a turn the direction lies in within its quadrant,
    // counted from the a axis: the boundaries it lies beyond.
    let within = gaps.iter().filter(|&&g| g > 0.0).count() as u32;
    match (a > 0.0, b > 0.0) {
        (true, true) => 8 + within,
        (false, true) => 15 - within,
        (true, false) => 7 - within,
        (false, false) => within,
    }
}

/// [`sector_of`] by the arc tangent: the reference.
fn sector_by_angle(a: f64, b: f64) -> u32 {
    let turn = b.atan2(a) / std::f64::consts::TAU + 0.5;
    ((turn * SECTORS as f64) as u32).min(SECTORS - 1)
}

/// The longest run of zero bits among the low [`SECTORS`] bits of
/// `occupied`, read around the circle.
fn longest_empty_run(occupied: u32) -> u32 {
    let empty = !occupied & ((1 << SECTORS) - 1);
    // The run across the wrap-around is the one found in two turns.
    let twice = empty as u64 | ((empty as u64) << SECTORS);
    let (mut longest, mut run) = (0, 0);
    for k in 0..2 * SECTORS {
        run = if twice >> k & 1 == 1 { run + 1 } else { 0 };
        longest = longest.max(run);
    }
    longest.min(SECTORS)
}

/// The spacing of a cloud, as measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Spacing {
    /// The typical distance between neighbouring points, mm.
    pub spacing_mm: f64,
    /// The radius the density was read at and the median count there.
    pub measured_at_mm: f64,
    pub median_count: u32,
    /// The points sampled.
    pub samples: usize,
}

/// Why a cloud's spacing could not be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum SpacingError {
    #[error("the cloud has no valid point")]
    Empty,
    #[error(
        "the cloud's points are too sparse to measure: fewer than {MIN_MEASURED_COUNT} neighbours in \
         {MAX_MEASURING_RADIUS_MM} mm around most points"
    )]
    TooSparse,
}

/// Up to `max` valid points of `points`, evenly spread over the array.
fn even_sample(points: &[Point], max: usize) -> Vec<usize> {
    let valid = || (0..points.len()).filter(|&i| points[i][0].is_finite());
    let stride = valid().count().div_ceil(max).max(1);
    valid().step_by(stride).collect()
}

/// The number of points within `radius_mm` of point `i` (itself
/// included), read up to `cap`, by a [`CellIndex`] query: the reference
/// the spacing's counts ([`counts_around`]) are tested against.
#[cfg(test)]
fn count_within(index: &CellIndex, points: &[Point], i: usize, radius_mm: f64, cap: u32) -> u32 {
    let p = points[i];
    let r_sq = (radius_mm * radius_mm) as f32;
    let mut n = 0;
    index.visit_near(&p, r_sq, |_, q| {
        n += crate::kernels::within(&p, q, r_sq) as u32;
        if n >= cap { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
    });
    n
}

fn median(values: &mut [u32]) -> u32 {
    let mid = values.len() / 2;
    *values.select_nth_unstable(mid).1
}

fn lower_quartile(values: &mut [u32]) -> u32 {
    let k = values.len() / 4;
    *values.select_nth_unstable(k).1
}

/// Measures the spacing of `cloud`, starting at radius `start_mm`.
pub(crate) fn measure_spacing(cloud: &PointCloud, start_mm: f64) -> Result<Spacing, SpacingError> {
    measure_spacing_until(cloud, start_mm, Deadline::NONE)
}

/// [`measure_spacing`] that stops counting once `deadline` has passed; its
/// result then means nothing, and the caller refuses the plan instead.
pub(crate) fn measure_spacing_until(
    cloud: &PointCloud,
    start_mm: f64,
    deadline: Deadline,
) -> Result<Spacing, SpacingError> {
    let points = cloud.points();
    // A few thousand counts: one pass over the cloud per radius against
    // the sample, with no index of the whole cloud.
    measure_spacing_by(cloud, start_mm, |radius, sample| {
        let centres: Vec<Point> = sample.iter().map(|&i| points[i]).collect();
        counts_around(points, &centres, radius, MAX_MEASURED_COUNT, deadline)
    })
}

/// [`measure_spacing`] with the counts of the sampled points within a
/// radius, read up to [`MAX_MEASURED_COUNT`], from `counts_at(radius,
/// sample)`.
fn measure_spacing_by(
    cloud: &PointCloud,
    start_mm: f64,
    mut counts_at: impl FnMut(f64, &[usize]) -> Vec<u32>,
) -> Result<Spacing, SpacingError> {
    let sample = even_sample(cloud.points(), SPACING_SAMPLES);
    if sample.is_empty() {
        return Err(SpacingError::Empty);
    }
    let mut radius = start_mm;
    while radius <= MAX_MEASURING_RADIUS_MM {
        let mut counts = counts_at(radius, &sample);
        let m = median(&mut counts);
        if m >= MIN_MEASURED_COUNT {
            let spacing_mm = radius * (std::f64::consts::PI / m as f64).sqrt();
            return Ok(Spacing { spacing_mm, measured_at_mm: radius, median_count: m, samples: sample.len() });
        }
        radius *= 2.0;
    }
    Err(SpacingError::TooSparse)
}

/// The radius at which a full plane of points `spacing_mm` apart holds
/// [`TARGET_FULL_COUNT`] points, never below `configured_mm`.
pub(crate) fn radius_for(spacing_mm: f64, configured_mm: f64) -> f64 {
    (spacing_mm * (TARGET_FULL_COUNT / std::f64::consts::PI).sqrt()).max(configured_mm)
}

/// The scale a frame is planned at: the neighbour radius and, for a cloud
/// measured from its data, its spacing. The lengths the configuration gives
/// for the paper's camera grow with the spacing where it is coarser.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scale {
    pub radius_mm: f64,
    /// The measured spacing; `None` when the camera model sets the scale.
    pub measured: Option<Spacing>,
    /// The configured radius the lengths below are relative to.
    configured_radius_mm: f64,
}

impl Scale {
    /// The camera model's scale: the configured radius.
    pub(crate) fn of_camera(configured_radius_mm: f64) -> Scale {
        Scale { radius_mm: configured_radius_mm, measured: None, configured_radius_mm }
    }

    /// The scale of a cloud with the measured `spacing`.
    pub(crate) fn of_spacing(spacing: Spacing, configured_radius_mm: f64) -> Scale {
        Scale {
            radius_mm: radius_for(spacing.spacing_mm, configured_radius_mm),
            measured: Some(spacing),
            configured_radius_mm,
        }
    }

    /// A length configured for the paper's radius, grown in proportion to
    /// the radius in use: search bands around edges scale with how far
    /// inside the edge the criteria leave their points.
    pub(crate) fn band(&self, configured_mm: f64) -> f64 {
        configured_mm * self.radius_mm / self.configured_radius_mm
    }

    /// The point spacing near `p`, mm: measured from the cloud, or the
    /// `camera`'s pixel footprint there.
    pub(crate) fn spacing_at(&self, camera: &crate::camera::CameraModel, p: &Vec3) -> f64 {
        self.measured.map_or_else(|| camera.pixel_footprint_at(p), |m| m.spacing_mm)
    }

    /// A tolerance between neighbouring points, at least `per_spacing`
    /// spacings where the spacing was measured.
    pub(crate) fn at_least_spacings(&self, configured_mm: f64, per_spacing: f64) -> f64 {
        match self.measured {
            Some(s) => configured_mm.max(per_spacing * s.spacing_mm),
            None => configured_mm,
        }
    }
}

/// The full-plane neighbour count measured across a cloud, cube by cube.
#[derive(Debug, Clone)]
pub(crate) struct DensityMap {
    cube_mm: f64,
    /// Packed cube coordinates, sorted, and each cube's full count.
    keys: Vec<u64>,
    counts: Vec<f64>,
    /// The cloud's median count, for cubes with too few points.
    fallback: f64,
    radius_mm: f64,
}

impl DensityMap {
    /// Measures the full-plane count within the search's radius across
    /// its cloud.
    pub(crate) fn measure(search: &NeighbourSearch) -> Option<DensityMap> {
        let cloud = search.cloud();
        let radius_mm = search.radius_mm();
        let cube_mm = radius_mm * DENSITY_CELL_RADII;
        let sampled = density_samples(cloud.points(), cube_mm);
        let runs: Vec<&[(u64, u32)]> = sampled.chunk_by(|a, b| a.0 == b.0).collect();
        let cap = MAX_MEASURED_COUNT;
        let measured: Vec<(u64, Option<u32>, Vec<u32>)> = runs
            .par_iter()
            .map_init(Vec::new, |neighbours, run| {
                let mut counts: Vec<u32> =
                    run.iter().filter_map(|&(_, i)| surrounded_count(search, i as usize, cap, neighbours)).collect();
                let own = (counts.len() >= MIN_DENSITY_SAMPLES).then(|| lower_quartile(&mut counts));
                (run[0].0, own, counts)
            })
            .collect();
        let mut all: Vec<u32> = measured.iter().flat_map(|(_, _, c)| c.iter().copied()).collect();
        if all.is_empty() {
            return None;
        }
        let fallback = lower_quartile(&mut all) as f64;
        let keys = measured.iter().map(|(k, _, _)| *k).collect();
        let counts = measured.iter().map(|(_, own, _)| own.map_or(fallback, |c| c as f64)).collect();
        Some(DensityMap { cube_mm, keys, counts, fallback, radius_mm })
    }

    /// The neighbour count a full plane gives within the radius at `p`.
    #[inline]
    pub(crate) fn full_count_at(&self, p: &Point) -> f64 {
        match self.keys.binary_search(&pack_cube(p, self.cube_mm)) {
            Ok(k) => self.counts[k],
            Err(_) => self.fallback,
        }
    }

    /// The surface one point stands for at `p`, mm²: the disc of the
    /// radius over the full count.
    pub(crate) fn area_per_point_at(&self, p: &Point) -> f64 {
        std::f64::consts::PI * self.radius_mm * self.radius_mm / self.full_count_at(p).max(1.0)
    }

    /// The cloud's full count where a cube has too few points of its own.
    pub(crate) fn cloud_full_count(&self) -> f64 {
        self.fallback
    }
}

/// The neighbour count of point `i` read up to `cap` when its
/// [`scatter_normal`](super::orientation::scatter_normal) exists and its
/// neighbours [`surrounded`] it along
/// that normal, else `None`: the three from one visit of the neighbours
/// instead of one each (the normal's sample is the visit's first
/// neighbours, the sectors and the count take them all). `neighbours` is
/// scratch space; past [`MAX_SAMPLED_NEIGHBOURS`] neighbours it stops
/// growing and the sectors are read by a second visit.
fn surrounded_count(search: &NeighbourSearch, i: usize, cap: u32, neighbours: &mut Vec<u32>) -> Option<u32> {
    let cloud = search.cloud();
    let points = cloud.points();
    neighbours.clear();
    let mut total = 0usize;
    search.for_each(i, |j| {
        if neighbours.len() < MAX_SAMPLED_NEIGHBOURS {
            neighbours.push(j as u32);
        }
        total += 1;
    });
    let normal = scatter_normal_of_visit(cloud, search, i, neighbours)?;
    let all_around = if total <= neighbours.len() {
        let mut sectors = Sectors::around(&points[i], &normal, search.radius_mm());
        for &j in neighbours.iter() {
            sectors.add(&points[j as usize]);
        }
        sectors.surrounded()
    } else {
        surrounded(search, i, &normal)
    };
    all_around.then(|| total.min(cap as usize) as u32)
}

/// The points of a parallel chunk of [`density_samples`]' passes.
const DENSITY_CHUNK: usize = 1 << 14;

/// The points the full-plane count is measured on, as `(cube, index)`
/// sorted: in each cube of side `cube_mm`, up to
/// [`DENSITY_SAMPLES_PER_CELL`] of its valid points, every `stride`-th in
/// index order from its first (the stride the cube's number of points
/// needs).
///
/// Two passes over the cloud in parallel chunks keep only what is
/// sampled, not a cube key for every point: the first counts each chunk's
/// points per cube, which gives every cube its stride and every chunk the
/// number of each cube's points before it; the second then knows each
/// point's rank in its cube as it reaches it.
fn density_samples(points: &[Point], cube_mm: f64) -> Vec<(u64, u32)> {
    let key_of = |p: &Point| pack_cube(p, cube_mm);
    // Each chunk's cubes, sorted, and its valid points in each.
    let tallies: Vec<Vec<(u64, u32)>> = points
        .par_chunks(DENSITY_CHUNK)
        .map(|chunk| {
            let mut keys: Vec<u64> = chunk.iter().filter(|p| p[0].is_finite()).map(key_of).collect();
            keys.sort_unstable();
            keys.chunk_by(|a, b| a == b).map(|run| (run[0], run.len() as u32)).collect()
        })
        .collect();
    let mut cubes: Vec<(u64, u32)> = tallies.iter().flatten().copied().collect();
    cubes.sort_unstable();
    cubes.dedup_by(|later, kept| {
        let same = later.0 == kept.0;
        if same {
            kept.1 += later.1;
        }
        same
    });
    let stride_of = |n: u32| (n as usize).div_ceil(DENSITY_SAMPLES_PER_CELL).max(1);
    // For each chunk's cubes: the cube's stride and its points in the
    // chunks before.
    let mut before = vec![0u32; cubes.len()];
    let starts: Vec<Vec<(usize, u32)>> = tallies
        .iter()
        .map(|tally| {
            tally
                .iter()
                .map(|&(key, n)| {
                    let c = cubes.partition_point(|&(k, _)| k < key);
                    let start = before[c];
                    before[c] += n;
                    (stride_of(cubes[c].1), start)
                })
                .collect()
        })
        .collect();
    let mut sampled: Vec<(u64, u32)> = points
        .par_chunks(DENSITY_CHUNK)
        .zip(tallies.par_iter().zip(starts.par_iter()))
        .enumerate()
        .flat_map_iter(|(k, (chunk, (tally, starts)))| {
            let mut rank: Vec<u32> = starts.iter().map(|&(_, start)| start).collect();
            let mut kept = Vec::new();
            for (j, p) in chunk.iter().enumerate().filter(|(_, p)| p[0].is_finite()) {
                let key = key_of(p);
                let t = tally.partition_point(|&(k, _)| k < key);
                if (rank[t] as usize).is_multiple_of(starts[t].0) {
                    kept.push((key, (k * DENSITY_CHUNK + j) as u32));
                }
                rank[t] += 1;
            }
            kept
        })
        .collect();
    sampled.par_sort_unstable();
    sampled
}

/// The packed coordinates of the cube of side `cube_mm` holding `p`
/// (21 bits an axis, clamped).
fn pack_cube(p: &Point, cube_mm: f64) -> u64 {
    const HALF: i64 = 1 << 20;
    let field = |v: f32| ((v as f64 / cube_mm).floor().clamp(-(HALF as f64), (HALF - 1) as f64) as i64 + HALF) as u64;
    (field(p[0]) << 42) | (field(p[1]) << 21) | field(p[2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::pipeline::orientation::scatter_normal;

    /// [`surrounded_count`] as three visits: the normal's, the sectors',
    /// the count's. The reference.
    fn surrounded_count_reference(search: &NeighbourSearch, i: usize, cap: u32) -> Option<u32> {
        let normal = scatter_normal(search.cloud(), search, i)?;
        surrounded(search, i, &normal).then(|| search.count_up_to(i, |_| true, cap))
    }

    /// The spacing as measured by a [`CellIndex`] per radius and its
    /// queries. The reference.
    fn measure_spacing_reference(cloud: &PointCloud, start_mm: f64) -> Result<Spacing, SpacingError> {
        let points = cloud.points();
        measure_spacing_by(cloud, start_mm, |radius, sample| {
            let index = CellIndex::for_radius(points, radius);
            sample.iter().map(|&i| count_within(&index, points, i, radius, MAX_MEASURED_COUNT)).collect()
        })
    }

    /// A plate of points about `spacing` apart with a jitter, a hole and
    /// a cut edge, tilted, with duplicates: what a voxel grid leaves.
    fn jittered_plate(spacing: f32, n: usize) -> PointCloud {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let mut points = Vec::new();
        for k in 0..n * n {
            let (col, row) = ((k % n) as f32, (k / n) as f32);
            if (col - 20.0).powi(2) + (row - 25.0).powi(2) < 30.0 || col > row + 30.0 {
                continue;
            }
            let (x, y) = ((col + 0.3 * next()) * spacing, (row + 0.3 * next()) * spacing);
            points.push([x, y, 400.0 + 0.3 * x + 0.1 * next()]);
            if k % 17 == 0 {
                points.push([x, y, 400.0 + 0.3 * x]);
            }
        }
        PointCloud::unorganized(points)
    }

    /// [`density_samples`] as every valid point keyed by cube, sorted,
    /// and each cube's run stepped through. The reference.
    fn density_samples_reference(points: &[Point], cube_mm: f64) -> Vec<(u64, u32)> {
        let mut by_cube: Vec<(u64, u32)> = (0..points.len())
            .filter(|&i| points[i][0].is_finite())
            .map(|i| (pack_cube(&points[i], cube_mm), i as u32))
            .collect();
        by_cube.sort_unstable();
        by_cube
            .chunk_by(|a, b| a.0 == b.0)
            .flat_map(|run| run.iter().step_by(run.len().div_ceil(DENSITY_SAMPLES_PER_CELL).max(1)).copied())
            .collect()
    }

    #[test]
    fn the_density_sample_is_each_cubes_points_stepped_through() {
        // Plates of many chunks whose cubes span chunk boundaries, with
        // invalid points between; a cloud in cube order and one shuffled.
        let plate = jittered_plate(0.4, 400);
        let mut points = plate.points().to_vec();
        for k in (0..points.len()).step_by(7) {
            points[k] = crate::cloud::INVALID_POINT;
        }
        let mut shuffled = points.clone();
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for k in (1..shuffled.len()).rev() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            shuffled.swap(k, (state % (k as u64 + 1)) as usize);
        }
        assert!(points.len() > 4 * DENSITY_CHUNK);
        for cloud in [&points, &shuffled] {
            for cube_mm in [0.5, 3.0, 40.0] {
                let sample = density_samples(cloud, cube_mm);
                assert_eq!(sample, density_samples_reference(cloud, cube_mm), "cubes of {cube_mm} mm");
                assert!(!sample.is_empty());
            }
        }
    }

    #[test]
    fn the_spacing_is_measured_as_the_reference_measures_it() {
        for cloud in [grid(1.0, 120, 0.3), grid(0.37, 90, 0.0), jittered_plate(1.0, 70), jittered_plate(2.6, 60)] {
            for start in [0.5, 1.0, 3.0] {
                assert_eq!(measure_spacing(&cloud, start), measure_spacing_reference(&cloud, start));
            }
        }
    }

    #[test]
    fn one_visit_decides_each_sampled_point_as_three_do() {
        let camera = CameraModel::default();
        // A clump of duplicates past the scratch list's bound: its points'
        // sectors are read by a second visit.
        let mut clumped = jittered_plate(1.0, 70).points().to_vec();
        clumped.extend(std::iter::repeat_n([30.0f32, 40.0, 409.0], MAX_SAMPLED_NEIGHBOURS + 10));
        let clumped = PointCloud::unorganized(clumped);
        for cloud in [grid(1.0, 60, 0.2), jittered_plate(1.0, 70), jittered_plate(0.5, 50), clumped] {
            let radius = radius_for(measure_spacing(&cloud, 1.0).unwrap().spacing_mm, 1.0);
            let search = NeighbourSearch::new(&cloud, &camera, radius);
            let mut scratch = Vec::new();
            let mut surrounded_points = 0;
            for i in 0..cloud.len() {
                for cap in [0, 7, MAX_MEASURED_COUNT] {
                    let fast = surrounded_count(&search, i, cap, &mut scratch);
                    assert_eq!(fast, surrounded_count_reference(&search, i, cap), "point {i}, cap {cap}");
                    surrounded_points += fast.is_some() as usize;
                }
            }
            assert!(surrounded_points > cloud.len() && surrounded_points < 3 * cloud.len(), "{surrounded_points}");
        }
    }

    #[test]
    fn sectors_by_comparison_are_the_sectors_by_angle() {
        let mut directions: Vec<(f64, f64)> = Vec::new();
        // Every boundary, exactly and a few units in the last place either
        // side, in every length; the axes with either zero.
        for k in 0..64 {
            let angle = k as f64 * std::f64::consts::TAU / 64.0 - std::f64::consts::PI;
            for length in [1e-3, 0.7, 3.0, 1e3] {
                let (a, b) = (length * angle.cos(), length * angle.sin());
                for ulps in -3i64..=3 {
                    let nudge = |v: f64| f64::from_bits((v.to_bits() as i64 + ulps) as u64);
                    directions.extend([(nudge(a), b), (a, nudge(b))]);
                }
            }
        }
        directions.extend([(1.0, 0.0), (-1.0, 0.0), (1.0, -0.0), (-1.0, -0.0), (0.0, 1.0), (-0.0, 1.0), (0.0, -1.0)]);
        // And a spread of directions between.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let a = (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let b = (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            directions.push((a, b));
        }
        for (a, b) in directions {
            assert_eq!(sector_of(a, b), sector_by_angle(a, b), "({a:e}, {b:e})");
        }
    }

    /// A square grid of points `spacing` apart on the plane z = 500 +
    /// slope x, `n` by `n`.
    fn grid(spacing: f32, n: usize, slope: f32) -> PointCloud {
        let points = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f32 * spacing, (k / n) as f32 * spacing);
                [x, y, 500.0 + slope * x]
            })
            .collect();
        PointCloud::unorganized(points)
    }

    #[test]
    fn the_spacing_of_a_grid_is_its_step() {
        for spacing in [0.2f32, 1.0, 1.4, 5.0] {
            let cloud = grid(spacing, 200, 0.0);
            let s = measure_spacing(&cloud, 1.0).unwrap();
            let error = (s.spacing_mm - spacing as f64).abs() / spacing as f64;
            assert!(error < 0.1, "step {spacing}: measured {s:?}");
        }
    }

    #[test]
    fn a_cloud_too_sparse_or_empty_is_refused() {
        assert_eq!(measure_spacing(&grid(200.0, 5, 0.0), 1.0), Err(SpacingError::TooSparse));
        assert_eq!(measure_spacing(&PointCloud::unorganized(vec![[f32::NAN; 3]]), 1.0), Err(SpacingError::Empty));
    }

    #[test]
    fn the_derived_radius_holds_the_target_count_and_the_configured_floor() {
        let r = radius_for(1.0, 1.0);
        assert!((std::f64::consts::PI * r * r - TARGET_FULL_COUNT).abs() < 1e-9);
        assert_eq!(radius_for(0.05, 1.0), 1.0);
    }

    #[test]
    fn empty_runs_are_read_around_the_circle() {
        assert_eq!(longest_empty_run(0xFFFF), 0);
        assert_eq!(longest_empty_run(0), SECTORS);
        assert_eq!(longest_empty_run(0b1111_1111_1111_0000), 4);
        assert_eq!(longest_empty_run(0b0011_1111_1111_1100), 4, "two at each end make four");
        assert_eq!(longest_empty_run(0b1010_1010_1010_1010), 1);
    }

    #[test]
    fn a_point_at_an_edge_is_not_surrounded_and_one_inside_is() {
        let cloud = grid(1.0, 60, 0.2);
        let camera = CameraModel::default();
        let search = NeighbourSearch::new(&cloud, &camera, radius_for(1.0, 1.0));
        let normal = Vec3::new(-0.2, 0.0, 1.0).normalize();
        let at = |col: usize, row: usize| row * 60 + col;
        assert!(surrounded(&search, at(30, 30), &normal));
        assert!(!surrounded(&search, at(0, 30), &normal));
        assert!(!surrounded(&search, at(30, 59), &normal));
        assert!(!surrounded(&search, at(59, 59), &normal));
        assert!(surrounded(&search, at(2, 30), &normal), "two spacings in, the disc reaches past the edge");
    }

    #[test]
    fn the_full_count_is_the_interior_count_even_beside_an_edge() {
        // A tilted plate 1 mm apart: interior points have about π r² / s²
        // neighbours, times the tilt's stretch along x.
        let cloud = grid(1.0, 120, 0.5);
        let camera = CameraModel::default();
        let radius = radius_for(1.0, 1.0);
        let search = NeighbourSearch::new(&cloud, &camera, radius);
        let map = DensityMap::measure(&search).unwrap();
        let expected = std::f64::consts::PI * radius * radius / 1.25f64.sqrt();
        for p in [[60.0f32, 60.0, 530.0], [0.0, 0.0, 500.0], [119.0, 119.0, 559.5]] {
            let full = map.full_count_at(&p);
            assert!((full - expected).abs() / expected < 0.12, "{p:?}: {full} against {expected}");
        }
    }
}
