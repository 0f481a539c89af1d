//! Local surface normals and the workpiece's dominant orientation.
//!
//! Plane welds join plates that lie parallel to each other and, in a cell,
//! to the table under them, so one normal describes every plane the
//! pipeline looks for. The robust plane criterion needs it twice: to
//! predict the neighbour count of a tilted plane (the foreshortening Eq. 6
//! leaves out), and to reject bevel and side faces, whose neighbour counts
//! can pass for a plate's when the camera looks at them squarely.

use rayon::prelude::*;

use crate::cloud::PointCloud;
use crate::geometry::Vec3;
use crate::geometry::fit::Moments;
pub use crate::kernels::{cross, cross_agrees};

use super::grid_search::Grid;
use super::neighbours::{NeighbourSearch, SAMPLE_SLACK, VisitNeighbours};

/// Estimates the unit normal of the surface at point `i`, oriented away
/// from the camera. On a pixel grid it is the cross product of central
/// differences `step` pixels apart along each image axis (one-sided where a
/// neighbour is missing); elsewhere, the principal axes of the neighbours.
pub fn local_normal(cloud: &PointCloud, search: &NeighbourSearch, i: usize, step: usize) -> Option<Vec3> {
    let n = if cloud.is_organized() { grid_normal(cloud, i, step)? } else { scatter_normal(cloud, search, i)? };
    let p = vec_at(cloud, i)?;
    Some(if n.dot(&p) < 0.0 { -n } else { n })
}

/// The pixel step whose 3D length is about `radius_mm` at depth `z`: long
/// enough to average the depth noise, short enough to stay on one face.
pub fn normal_step(fx: f64, z: f64, radius_mm: f64) -> usize {
    crate::geometry::round_i64(radius_mm * fx / z).clamp(1, 8) as usize
}

/// The points of a pixel grid by index: the cloud itself, or the fast
/// path's coordinate planes, which are the ones in cache while it runs.
pub trait GridPoints {
    fn width(&self) -> usize;
    fn height(&self) -> usize;
    /// Point `i`, row-major; invalid points are NaN.
    fn point(&self, i: usize) -> [f32; 3];
}

impl GridPoints for PointCloud {
    fn width(&self) -> usize {
        PointCloud::width(self)
    }

    fn height(&self) -> usize {
        PointCloud::height(self)
    }

    #[inline(always)]
    fn point(&self, i: usize) -> [f32; 3] {
        self.points()[i]
    }
}

impl GridPoints for Grid {
    fn width(&self) -> usize {
        Grid::width(self)
    }

    fn height(&self) -> usize {
        Grid::height(self)
    }

    #[inline(always)]
    fn point(&self, i: usize) -> [f32; 3] {
        Grid::point(self, i)
    }
}

/// [`normal_step`] for single-precision depths by comparison alone: the
/// step only falls as depth grows, so it is one plus the number of
/// breakpoints a depth lies below. The breakpoints are found by bisecting
/// the bit patterns of positive floats against `normal_step` itself, so
/// the table answers exactly as the function does.
#[derive(Debug, Clone, Copy)]
pub struct StepTable {
    /// `below[k]`: the least positive depth whose step is at most `k + 1`;
    /// depths under it take a step of at least `k + 2`.
    below: [f32; 7],
    fx: f64,
    radius_mm: f64,
}

impl StepTable {
    pub fn new(fx: f64, radius_mm: f64) -> StepTable {
        let step = |bits: u32| normal_step(fx, f32::from_bits(bits) as f64, radius_mm);
        let below = std::array::from_fn(|k| {
            // Least bit pattern of a positive finite float with step <= k + 1.
            let (mut lo, mut hi) = (1u32, f32::MAX.to_bits());
            if step(hi) > k + 1 {
                return f32::INFINITY;
            }
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if step(mid) <= k + 1 {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            f32::from_bits(lo)
        });
        StepTable { below, fx, radius_mm }
    }

    /// The depth under which a positive depth takes a step of `step` or
    /// more, for `step` from 2 to 8.
    #[inline(always)]
    pub fn depth_limit(&self, step: usize) -> f32 {
        self.below[step - 2]
    }

    /// `normal_step(fx, z, radius_mm)`.
    #[inline(always)]
    pub fn step(&self, z: f32) -> usize {
        if z > 0.0 {
            1 + self.below.iter().filter(|&&b| z < b).count()
        } else {
            // Zero, negative or NaN: outside the monotone range.
            normal_step(self.fx, z as f64, self.radius_mm)
        }
    }
}

/// True when the grid normal at point `i` (see [`local_normal`]) is within
/// the angle whose cosine is `cos_limit` of the unit normal `reference`.
/// The same test as `local_normal(..).dot(reference) >= cos_limit`, in
/// single precision without a square root: it runs on every pixel.
pub fn grid_normal_agrees<G: GridPoints>(grid: &G, i: usize, step: usize, reference: &Vec3, cos_limit: f64) -> bool {
    let Some(n) = grid_cross(grid, i, step) else { return false };
    let reference = [reference.x as f32, reference.y as f32, reference.z as f32];
    cross_agrees(n, grid.point(i), reference, (cos_limit * cos_limit) as f32)
}

#[inline]
fn vec_at(cloud: &PointCloud, i: usize) -> Option<Vec3> {
    let p = cloud.points().get(i)?;
    p[0].is_finite().then(|| Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
}

fn grid_normal(cloud: &PointCloud, i: usize, step: usize) -> Option<Vec3> {
    let n = grid_cross(cloud, i, step)?;
    let n = Vec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
    let norm = n.norm();
    (norm > 1e-12).then(|| n / norm)
}

/// The unnormalised cross product of the central differences at pixel `i`.
#[inline]
fn grid_cross<G: GridPoints>(grid: &G, i: usize, step: usize) -> Option<[f32; 3]> {
    let (w, h) = (grid.width(), grid.height());
    let (col, row) = (i % w, i / w);
    let centre = grid.point(i);
    if !centre[0].is_finite() {
        return None;
    }
    let valid = |j: usize| {
        let p = grid.point(j);
        p[0].is_finite().then_some(p)
    };
    let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let difference = |before: Option<[f32; 3]>, after: Option<[f32; 3]>| match (before, after) {
        (Some(b), Some(a)) => Some(sub(a, b)),
        (None, Some(a)) => Some(sub(a, centre)),
        (Some(b), None) => Some(sub(centre, b)),
        (None, None) => None,
    };
    let left = if col >= step { valid(i - step) } else { None };
    let right = if col + step < w { valid(i + step) } else { None };
    let up = if row >= step { valid(i - step * w) } else { None };
    let down = if row + step < h { valid(i + step * w) } else { None };
    let du = difference(left, right)?;
    let dv = difference(up, down)?;
    Some(cross(du, dv))
}

/// The normal of the neighbours' principal axes, from at most
/// [`SCATTER_NORMAL_SAMPLE`] of them, nearest cells first: a plane fit
/// needs no more, and reading every neighbour of a dense cloud would cost
/// far more than the fit.
pub(crate) fn scatter_normal(cloud: &PointCloud, search: &NeighbourSearch, i: usize) -> Option<Vec3> {
    let mut m = Moments::default();
    search.for_each_sampled(i, SCATTER_NORMAL_SAMPLE, |j| {
        if let Some(q) = vec_at(cloud, j) {
            m.add(&q);
        }
    });
    m.plane().map(|plane| plane.normal)
}

/// [`scatter_normal`] of point `i` from its neighbours as a whole visit of
/// them gives them (`neighbours`, in [`NeighbourSearch::visit_until`]'s
/// order): the same sample, the leading ones, so the same normal, for a
/// caller that reads every neighbour anyway.
pub(crate) fn scatter_normal_of_visit(
    cloud: &PointCloud,
    search: &NeighbourSearch,
    i: usize,
    neighbours: &[u32],
) -> Option<Vec3> {
    // As `for_each_sampled` stops: after its cap, and never before the first.
    let sample = search.frame_neighbours_at_most(&cloud.points()[i]).clamp(1, SCATTER_NORMAL_SAMPLE);
    let mut m = Moments::default();
    for &j in neighbours.iter().take(sample) {
        if let Some(q) = vec_at(cloud, j as usize) {
            m.add(&q);
        }
    }
    m.plane().map(|plane| plane.normal)
}

/// Whether the [`local_normal`] of point `i` of a cloud without a pixel
/// grid lies within the angle whose cosine is `cos_limit` of the unit
/// `reference`, and the point's neighbour count read up to `count_cap` (as
/// [`NeighbourSearch::count_up_to`] reads it), from one visit of its
/// neighbours: the normal's sample is the first neighbours in the order
/// both visit.
///
/// The decision is the reference's ([`local_normal`], nalgebra's
/// eigen-decomposition) without its iterations where it cannot differ: the
/// least eigenvalue in closed form ([`least_eigenvector`]) and its vector
/// from two rows of `C − λ I` answer when the eigenvalues are well apart
/// and the cosine is clear of the limit by far more than either method's
/// rounding; every other point is decided by the reference. The tests
/// check the two point for point.
#[cfg(test)]
pub(crate) fn scatter_facing_and_count(
    search: &NeighbourSearch,
    i: usize,
    count_cap: u32,
    reference: &Vec3,
    cos_limit: f64,
) -> (bool, u32) {
    scatter_facing_and_count_of(
        search,
        i,
        &super::neighbours::SearchedPoint(search, i),
        count_cap,
        reference,
        cos_limit,
    )
}

/// `scatter_facing_and_count` (the tests' reference) with point `i`'s neighbours read through
/// `neighbours`, which must give them as `search` does, in its order (the
/// normal's sample is the first of them).
pub(crate) fn scatter_facing_and_count_of(
    search: &NeighbourSearch,
    i: usize,
    neighbours: &impl VisitNeighbours,
    count_cap: u32,
    reference: &Vec3,
    cos_limit: f64,
) -> (bool, u32) {
    let cloud = search.cloud();
    let points = cloud.points();
    let sample_cap = search.frame_neighbours_at_most(&points[i]).min(SCATTER_NORMAL_SAMPLE);
    let count_cap = count_cap as usize;
    let stop = sample_cap.max(count_cap);
    // The sample's indices first, its sums after, in the same order: the
    // sums' chains of additions then run in registers, not through the
    // visitor's captures.
    let mut sample = [0u32; SCATTER_NORMAL_SAMPLE + SAMPLE_SLACK];
    let visited = neighbours.sample_until(&mut sample, stop);
    let mut sums = SampleSums::default();
    for &j in &sample[..visited.min(sample_cap)] {
        sums.add(&points[j as usize]);
    }
    let count = visited.min(count_cap) as u32;
    let p = vec_at(cloud, i);
    let fast = p.and_then(|p| sums.clear_decision(&p, reference, cos_limit));
    let facing =
        fast.unwrap_or_else(|| local_normal(cloud, search, i, 1).is_some_and(|n| n.dot(reference) >= cos_limit));
    (facing, count)
}

/// How far a cosine must lie from the limit for the closed-form normal to
/// decide: its error against the iterative one is below 1e-7 wherever the
/// gap below holds, so a thousand times that is a wide margin.
const CLEAR_COSINE: f64 = 1e-4;

/// The least relative gap between the least eigenvalue and the next one
/// (over the trace) for the closed form to decide: an error η in the
/// eigenvalue turns its vector by about η over the gap.
const CLEAR_GAP: f64 = 0.01;

/// First and second moments of a normal's sample about its first point.
#[derive(Default)]
struct SampleSums {
    count: usize,
    origin: [f64; 3],
    sum: [f64; 3],
    /// xx, xy, xz, yy, yz, zz.
    sum_sq: [f64; 6],
}

impl SampleSums {
    #[inline(always)]
    fn add(&mut self, q: &[f32; 3]) {
        let q = [q[0] as f64, q[1] as f64, q[2] as f64];
        if self.count == 0 {
            self.origin = q;
        }
        let d = [q[0] - self.origin[0], q[1] - self.origin[1], q[2] - self.origin[2]];
        self.count += 1;
        for (s, v) in self.sum.iter_mut().zip(d) {
            *s += v;
        }
        let products = [d[0] * d[0], d[0] * d[1], d[0] * d[2], d[1] * d[1], d[1] * d[2], d[2] * d[2]];
        for (s, v) in self.sum_sq.iter_mut().zip(products) {
            *s += v;
        }
    }

    /// The decision `normal · reference >= cos_limit` of the normal
    /// [`local_normal`] gives at `p`, when the closed form settles it;
    /// `None` when it must be left to the reference (too few points, a
    /// degenerate or nearly degenerate spread, a cosine near the limit, a
    /// normal nearly square to the line of sight).
    fn clear_decision(&self, p: &Vec3, reference: &Vec3, cos_limit: f64) -> Option<bool> {
        if self.count < 3 {
            return None;
        }
        let n = self.count as f64;
        let mean = self.sum.map(|s| s / n);
        let s = &self.sum_sq;
        let c = [
            s[0] / n - mean[0] * mean[0],
            s[1] / n - mean[0] * mean[1],
            s[2] / n - mean[0] * mean[2],
            s[3] / n - mean[1] * mean[1],
            s[4] / n - mean[1] * mean[2],
            s[5] / n - mean[2] * mean[2],
        ];
        let v = least_eigenvector(c)?;
        let mut normal = Vec3::new(v[0], v[1], v[2]);
        let towards = normal.dot(p);
        if towards.abs() < CLEAR_COSINE * p.norm() {
            return None;
        }
        if towards < 0.0 {
            normal = -normal;
        }
        let cosine = normal.dot(reference);
        ((cosine - cos_limit).abs() >= CLEAR_COSINE).then_some(cosine >= cos_limit)
    }
}

/// True for a positive number; false for zero, a negative one and NaN.
fn positive(v: f64) -> bool {
    v > 0.0
}

/// The unit eigenvector of the least eigenvalue of the symmetric 3 x 3
/// matrix with upper triangle `c` (xx, xy, xz, yy, yz, zz): the eigenvalues
/// by the trigonometric closed form (Smith, 1961), the vector as the
/// largest cross product of two rows of `C − λ I`. `None` when the least
/// eigenvalue is not clearly apart from the next ([`CLEAR_GAP`]) or the
/// matrix is degenerate.
fn least_eigenvector(c: [f64; 6]) -> Option<[f64; 3]> {
    let [a00, a01, a02, a11, a12, a22] = c;
    let trace = a00 + a11 + a22;
    if !positive(trace) {
        return None;
    }
    let q = trace / 3.0;
    let off = a01 * a01 + a02 * a02 + a12 * a12;
    let (b00, b11, b22) = (a00 - q, a11 - q, a22 - q);
    let p = ((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0).sqrt();
    if !positive(p) {
        return None;
    }
    let det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let least = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    let middle = trace - largest - least;
    if middle - least < CLEAR_GAP * trace || least > middle {
        return None;
    }
    let rows = [[a00 - least, a01, a02], [a01, a11 - least, a12], [a02, a12, a22 - least]];
    let cross =
        |u: &[f64; 3], w: &[f64; 3]| [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
    let norm_sq = |v: &[f64; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let candidates = [cross(&rows[0], &rows[1]), cross(&rows[0], &rows[2]), cross(&rows[1], &rows[2])];
    let best = candidates.iter().max_by(|a, b| norm_sq(a).total_cmp(&norm_sq(b)))?;
    let length = norm_sq(best).sqrt();
    // The largest cross product is at least the product of the other two
    // eigenvalues over √3; far below it, the rows are not what they seem.
    if !positive(length - 1e-3 * (middle - least) * (largest - least)) {
        return None;
    }
    Some(best.map(|v| v / length))
}

/// The most neighbours a normal without a pixel grid is fitted to. With
/// the radius holding some 50 points of a full plane (measured clouds) or
/// more (the paper's radius on dense clouds), 64 spread over the disc fix
/// the normal to a degree or two under the cameras' depth noise, well
/// inside the plane criterion's 20 degrees.
const SCATTER_NORMAL_SAMPLE: usize = 64;

/// The workpiece's dominant normal: the most common local normal over a
/// sparse, evenly spread sample of the frame, each sample counted by how
/// squarely the camera sees its surface (the cosine between the normal and
/// the line of sight), refined by averaging the normals that agree with it
/// within `agree_deg`.
///
/// A surface leaves points in proportion to its area times that cosine,
/// so counted plainly a large face seen at a grazing angle (a block's
/// sides seen down its corner, a tall web beside a narrow flange) can
/// outnumber the plates the camera was aimed at; counted by the cosine
/// once more, the support goes as area times its square, and the surfaces
/// the camera faces (the plates, which the capture pose looks at) win
/// unless they are much the smaller.
pub fn dominant_normal(cloud: &PointCloud, search: &NeighbourSearch, fx: f64, agree_deg: f64) -> Option<Vec3> {
    const SAMPLES: usize = 6000;
    const CANDIDATES: usize = 240;
    // An even stride over all pixels; invalid ones simply give no normal.
    // The stride is odd so it does not run down one image column.
    let stride = ((cloud.len() / SAMPLES).max(1)) | 1;
    // On rayon: a cloud without a grid fits a plane per sample. Collected
    // in sample order, so the sums below add up as a serial loop's would:
    // a slot per sample, NaN where there is no normal, then those removed
    // in place (a filtered collect would gather rayon's pieces and copy
    // them, twice the normals at once).
    let mut samples: Vec<(Vec3, f64)> = (0..cloud.len().div_ceil(stride))
        .into_par_iter()
        .map(|k| {
            let i = k * stride;
            let p = cloud.points()[i];
            let none = (Vec3::repeat(f64::NAN), 0.0);
            if !p[0].is_finite() {
                return none;
            }
            let Some(n) = local_normal(cloud, search, i, normal_step(fx, p[2] as f64, search.radius_mm() * 2.0)) else {
                return none;
            };
            (n, seen_squarely(&n, p))
        })
        .collect();
    samples.retain(|(n, _)| !n.x.is_nan());
    if samples.is_empty() {
        return None;
    }
    let cos_agree = agree_deg.to_radians().cos();
    let support = |n: &Vec3| samples.iter().filter(|(m, _)| m.dot(n) >= cos_agree).map(|s| s.1).sum::<f64>();
    let cand_stride = (samples.len() / CANDIDATES).max(1);
    let candidates: Vec<&Vec3> = samples.iter().step_by(cand_stride).map(|(n, _)| n).collect();
    let supports: Vec<f64> = candidates.par_iter().map(|n| support(n)).collect();
    // The last of equals, as a serial `max_by_key` picks.
    let (best, _) = candidates.into_iter().zip(supports).max_by(|a, b| a.1.total_cmp(&b.1))?;
    let mut mean = *best;
    for _ in 0..3 {
        let sum: Vec3 = samples.iter().map(|(m, _)| m).filter(|m| m.dot(&mean) >= cos_agree).sum();
        let norm = sum.norm();
        if norm < 1e-12 {
            break;
        }
        mean = sum / norm;
    }
    Some(mean)
}

/// How squarely the camera at the origin sees a surface of normal `n` at
/// point `p`: the cosine between the normal and the line of sight.
fn seen_squarely(n: &Vec3, p: [f32; 3]) -> f64 {
    let sight = Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    n.dot(&sight).abs() / sight.norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_table_answers_as_normal_step() {
        for (fx, radius) in [(2742.857, 1.0), (1371.4, 1.0), (2742.857, 2.0), (5000.0, 0.5)] {
            let table = StepTable::new(fx, radius);
            let mut zs: Vec<f32> = (1..4000).map(|k| k as f32 * 0.5).collect();
            // Every breakpoint and its neighbours, where rounding decides.
            for b in table.below.iter().filter(|b| b.is_finite()) {
                zs.extend([f32::from_bits(b.to_bits() - 1), *b, f32::from_bits(b.to_bits() + 1)]);
            }
            zs.extend([0.0, -1.0, f32::NAN, f32::INFINITY, f32::MIN_POSITIVE, 1e-30, 1e30]);
            for z in zs {
                assert_eq!(table.step(z), normal_step(fx, z as f64, radius), "fx {fx}, R {radius}, z {z}");
            }
        }
    }
    use crate::camera::CameraModel;

    fn tilted_grid(n: Vec3) -> PointCloud {
        let camera = CameraModel::default();
        let (w, h) = (60, 40);
        let anchor = Vec3::new(0.0, 0.0, 700.0);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(900.0 + col as f64, 580.0 + row as f64);
                let r = Vec3::new(r[0], r[1], r[2]);
                // A bevel-like strip on the right third, at 50° to the plate.
                let q = if col < 40 {
                    r * (n.dot(&anchor) / n.dot(&r))
                } else {
                    let m = Vec3::new(50f64.to_radians().sin(), 0.0, 50f64.to_radians().cos());
                    r * (m.dot(&anchor) / m.dot(&r))
                };
                pts.push([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        PointCloud::organized(w, h, pts).unwrap()
    }

    #[test]
    fn local_normal_recovers_the_plane_and_faces_away() {
        let n = Vec3::new(0.2, -0.3, 1.0).normalize();
        let cloud = tilted_grid(n);
        let camera = CameraModel::default();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let got = local_normal(&cloud, &search, 20 * 60 + 10, 3).unwrap();
        assert!(got.dot(&n) > 0.9999, "{got:?}");
    }

    /// [`dominant_normal`] as one serial loop: the reference of its
    /// parallel form.
    fn dominant_normal_serial(cloud: &PointCloud, search: &NeighbourSearch, fx: f64, agree_deg: f64) -> Option<Vec3> {
        let stride = ((cloud.len() / 6000).max(1)) | 1;
        let samples: Vec<(Vec3, f64)> = (0..cloud.len())
            .step_by(stride)
            .filter_map(|i| {
                let p = cloud.points()[i];
                if !p[0].is_finite() {
                    return None;
                }
                let n = local_normal(cloud, search, i, normal_step(fx, p[2] as f64, search.radius_mm() * 2.0))?;
                Some((n, seen_squarely(&n, p)))
            })
            .collect();
        let normals: Vec<Vec3> = samples.iter().map(|s| s.0).collect();
        let cos_agree = agree_deg.to_radians().cos();
        let support = |n: &Vec3| samples.iter().filter(|(m, _)| m.dot(n) >= cos_agree).map(|s| s.1).sum::<f64>();
        let best =
            normals.iter().step_by((normals.len() / 240).max(1)).max_by(|a, b| support(a).total_cmp(&support(b)))?;
        let mut mean = *best;
        for _ in 0..3 {
            let sum: Vec3 = normals.iter().filter(|m| m.dot(&mean) >= cos_agree).sum();
            if sum.norm() < 1e-12 {
                break;
            }
            mean = sum / sum.norm();
        }
        Some(mean)
    }

    #[test]
    fn dominant_normal_is_the_serial_loops_to_the_last_digit() {
        let camera = CameraModel::default();
        for seed in [1, 2, 3] {
            let cloud = scattered_scene(seed);
            for radius in [0.8, 2.0] {
                let search = NeighbourSearch::new(&cloud, &camera, radius);
                for agree in [2.0, 5.0, 40.0] {
                    let got = dominant_normal(&cloud, &search, camera.fx(), agree);
                    assert_eq!(got, dominant_normal_serial(&cloud, &search, camera.fx(), agree), "seed {seed}");
                }
            }
        }
        let grid = tilted_grid(Vec3::new(0.25, 0.1, 1.0).normalize());
        let search = NeighbourSearch::new(&grid, &camera, 1.0);
        assert_eq!(
            dominant_normal(&grid, &search, camera.fx(), 5.0),
            dominant_normal_serial(&grid, &search, camera.fx(), 5.0)
        );
    }

    #[test]
    fn dominant_normal_ignores_a_minority_face() {
        let n = Vec3::new(0.25, 0.1, 1.0).normalize();
        let cloud = tilted_grid(n);
        let camera = CameraModel::default();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let got = dominant_normal(&cloud, &search, camera.fx(), 5.0).unwrap();
        assert!(got.dot(&n) > 0.9999, "{got:?}");
    }

    /// A plate the camera faces (10° off its axis) in 26 columns of the
    /// grid beside a face it sees at a grazing 70° in 34: counted plainly
    /// the grazing face has the more normals, counted by how squarely each
    /// is seen the plate wins, as the capture pose that looks at the plates
    /// means it to.
    #[test]
    fn dominant_normal_is_the_surface_the_camera_faces_not_a_larger_grazing_one() {
        let plate = Vec3::new(10f64.to_radians().sin(), 0.0, 10f64.to_radians().cos());
        let grazing = Vec3::new(-(70f64.to_radians().sin()), 0.0, 70f64.to_radians().cos());
        let camera = CameraModel::default();
        let anchor = Vec3::new(0.0, 0.0, 700.0);
        let (w, h) = (60, 40);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(900.0 + col as f64, 580.0 + row as f64);
                let r = Vec3::new(r[0], r[1], r[2]);
                let n = if col < 26 { plate } else { grazing };
                let q = r * (n.dot(&anchor) / n.dot(&r));
                pts.push([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        let cloud = PointCloud::organized(w, h, pts).unwrap();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let got = dominant_normal(&cloud, &search, camera.fx(), 5.0).unwrap();
        assert!(got.dot(&plate) > 0.9999, "{got:?}");
    }

    #[test]
    fn the_fast_agreement_test_matches_the_normal() {
        let n = Vec3::new(0.2, -0.3, 1.0).normalize();
        let cloud = tilted_grid(n);
        let camera = CameraModel::default();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        for i in (0..cloud.len()).step_by(7) {
            for (reference, limit) in [(n, 20f64), (Vec3::z(), 15.0), (Vec3::new(0.9, 0.0, 0.44).normalize(), 30.0)] {
                let cos = limit.to_radians().cos();
                let slow = local_normal(&cloud, &search, i, 3).is_some_and(|m| m.dot(&reference) >= cos);
                assert_eq!(grid_normal_agrees(&cloud, i, 3, &reference, cos), slow, "pixel {i}");
            }
        }
    }

    /// A scattered cloud of a noisy plate, a steep face, a thin line of
    /// points and a loose clump: normals of every kind of spread.
    fn scattered_scene(seed: u64) -> PointCloud {
        let mut state = seed;
        let mut unit = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f64 / (1u64 << 24) as f64
        };
        let mut pts = Vec::new();
        for k in 0..6000 {
            let (u, v) = (unit() * 40.0, unit() * 30.0);
            let p = match k % 4 {
                0 | 1 => [u, v, 600.0 + 0.3 * u + 0.1 * v + unit() * 0.2],
                2 => [40.0 + unit() * 0.3 + 0.02 * v, v, 600.0 + u * 0.5],
                _ => [u * 0.5, 10.0 + unit() * 0.05, 600.0 + unit() * 0.05],
            };
            pts.push([p[0] as f32, p[1] as f32, p[2] as f32]);
        }
        for _ in 0..300 {
            pts.push([(20.0 + unit() * 2.0) as f32, (15.0 + unit() * 2.0) as f32, (590.0 + unit() * 2.0) as f32]);
        }
        PointCloud::unorganized(pts)
    }

    #[test]
    fn the_closed_form_decides_as_the_iterative_normal() {
        let camera = CameraModel::default();
        for seed in [1, 2, 3] {
            let cloud = scattered_scene(seed);
            for radius in [0.8, 2.0] {
                let search = NeighbourSearch::new(&cloud, &camera, radius);
                let references = [
                    (Vec3::new(-0.3, -0.1, 1.0).normalize(), 20f64),
                    (Vec3::z(), 15.0),
                    (Vec3::new(1.0, 0.0, -0.5).normalize(), 30.0),
                ];
                for i in 0..cloud.len() {
                    for (reference, limit) in &references {
                        let cos = limit.to_radians().cos();
                        let slow = local_normal(&cloud, &search, i, 1).is_some_and(|n| n.dot(reference) >= cos);
                        for cap in [0, 5, 40, 100] {
                            let fast = scatter_facing_and_count(&search, i, cap, reference, cos);
                            assert_eq!(fast, (slow, search.count_up_to(i, |_| true, cap)), "point {i}, seed {seed}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn the_closed_form_eigenvector_is_nalgebras() {
        let mut state = 7u64;
        let mut unit = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f64 / (1u64 << 24) as f64 - 0.5
        };
        let mut decided = 0;
        for _ in 0..20_000 {
            let m = nalgebra::Matrix3::from_fn(|_, _| unit());
            let scale =
                nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0 + unit(), 1e-3 + unit().abs()));
            let c = m * scale * m.transpose();
            let Some(v) = least_eigenvector([c[(0, 0)], c[(0, 1)], c[(0, 2)], c[(1, 1)], c[(1, 2)], c[(2, 2)]]) else {
                continue;
            };
            decided += 1;
            let eig = nalgebra::SymmetricEigen::new(c);
            let least = eig.eigenvalues.imin();
            let expected = eig.eigenvectors.column(least);
            let dot = (v[0] * expected[0] + v[1] * expected[1] + v[2] * expected[2]).abs();
            assert!(dot > 1.0 - 1e-9, "{c}: {v:?} against {expected}");
        }
        assert!(decided > 10_000, "{decided}");
    }

    #[test]
    fn isolated_point_has_no_normal() {
        let mut pts = vec![[f32::NAN; 3]; 9];
        pts[4] = [0.0, 0.0, 500.0];
        let cloud = PointCloud::organized(3, 3, pts).unwrap();
        let camera = CameraModel::default();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        assert!(local_normal(&cloud, &search, 4, 1).is_none());
    }
}
