//! Boundary sampling: where exactly a plate ends beside the weld.
//!
//! Edge points from the edge criterion lie up to R inside the true edge,
//! because the plane criterion has already trimmed the outermost points.
//! On a pixel grid the true boundary can be read directly: walk each scan
//! line outward across the coarse weld edge while the pixels stay on the
//! plate's plane; the plate ends between the last such pixel and the next,
//! so the boundary sample is half a pixel step beyond the last one. The
//! walk also runs past the ends of the coarse edge, so the samples reach
//! the plate's corners and give the seam's true extent.
//!
//! Without a grid ([`sample_scattered`]) the same rule is read from the
//! points themselves: cut the band beside the coarse edge into strips one
//! point spacings wide along the edge; in each strip the plate ends on
//! average one gap beyond its outermost point on the plate's plane, where
//! the k points of the strip's last row split the spacing into k + 1 gaps
//! (one point: half a spacing, as on the grid).
//! The strips cover every on-plane point of the band, so they too reach the
//! plate's corners.

use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, vec3};

/// One sample of a plate's boundary: a point on the plate's plane and its
/// coordinate along the coarse edge.
#[derive(Debug, Clone, Copy)]
pub struct BoundarySample {
    pub position: Vec3,
    pub along: f64,
}

/// The coarse edge to refine and the plate it belongs to.
#[derive(Debug, Clone, Copy)]
pub struct CoarseEdge {
    pub point: Vec3,
    /// Unit direction along the edge.
    pub direction: Vec3,
    /// Unit vector in the plate's plane, across the edge, pointing out of
    /// the plate (towards the weld).
    pub outward: Vec3,
}

/// Settings of the walk.
#[derive(Debug, Clone, Copy)]
pub struct BoundaryParams {
    /// Half-width of the band around the coarse edge searched, mm.
    pub band_mm: f64,
    /// A pixel is on the plate when within this distance of its plane.
    pub on_plane_mm: f64,
}

struct Walker<'a> {
    cloud: &'a PointCloud,
    plane: &'a Plane,
    edge: &'a CoarseEdge,
    params: &'a BoundaryParams,
    /// Walk along columns (true) or rows, and in which sense.
    along_cols: bool,
    sense: isize,
}

impl Walker<'_> {
    fn index(&self, scanline: usize, k: isize) -> Option<usize> {
        let (w, h) = (self.cloud.width() as isize, self.cloud.height() as isize);
        let (col, row) = if self.along_cols { (k, scanline as isize) } else { (scanline as isize, k) };
        (col >= 0 && row >= 0 && col < w && row < h).then(|| (row * w + col) as usize)
    }

    fn outward_of(&self, p: &Vec3) -> f64 {
        (p - self.edge.point).dot(&self.edge.outward)
    }

    fn on_plate(&self, i: usize) -> Option<Vec3> {
        let p = self.cloud.points()[i];
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(&p);
        (self.plane.signed_distance(&v).abs() <= self.params.on_plane_mm
            && self.outward_of(&v).abs() <= self.params.band_mm)
            .then_some(v)
    }

    /// Walks outward from position `k` on `scanline` and returns the
    /// boundary sample, or `None` when the walk leaves the image or the
    /// band before the plate ends (no boundary there).
    fn walk(&self, scanline: usize, mut k: isize, mean_step: f64) -> Option<(isize, BoundarySample)> {
        let mut last = self.on_plate(self.index(scanline, k)?)?;
        let mut previous: Option<Vec3> = self.index(scanline, k - self.sense).and_then(|i| self.on_plate(i));
        loop {
            let next_k = k + self.sense;
            let next = self.index(scanline, next_k)?;
            match self.on_plate(next) {
                Some(v) => {
                    previous = Some(last);
                    last = v;
                    k = next_k;
                }
                None => {
                    let p = self.cloud.points()[next];
                    // Still on the plane but outside the band: no edge here.
                    if p[0].is_finite() && self.plane.signed_distance(&vec3(&p)).abs() <= self.params.on_plane_mm {
                        return None;
                    }
                    break;
                }
            }
        }
        let step =
            previous.map(|p| self.outward_of(&last) - self.outward_of(&p)).filter(|s| *s > 0.0).unwrap_or(mean_step);
        let position = self.plane.project(&last) + self.edge.outward * (step / 2.0);
        Some((k, BoundarySample { position, along: (position - self.edge.point).dot(&self.edge.direction) }))
    }
}

/// The boundary samples of one edge.
#[derive(Debug, Clone, Default)]
pub struct Boundary {
    pub samples: Vec<BoundarySample>,
    /// Distance along the edge between neighbouring scan lines, mm. The
    /// plate ends on average half of it beyond the outermost samples.
    pub line_spacing_mm: f64,
}

impl Boundary {
    /// The range of `along` the samples cover, widened by half a scan line
    /// at each end. Samples that the fit later trims (a walk cut short by
    /// a mixed pixel) still prove the plate is there, so all count.
    pub fn extent(&self, along: impl Fn(&BoundarySample) -> f64) -> Option<(f64, f64)> {
        let (lo, hi) = self.samples.iter().map(along).fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)));
        (lo <= hi).then(|| (lo - self.line_spacing_mm / 2.0, hi + self.line_spacing_mm / 2.0))
    }
}

/// Samples the boundary of the plate whose member pixels are `members`
/// beside `edge`. Organized clouds only.
pub fn sample_boundary(
    cloud: &PointCloud,
    members: &[u32],
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
) -> Boundary {
    let points = cloud.points();
    let w = cloud.width();
    let near: Vec<usize> = members
        .iter()
        .map(|&i| i as usize)
        .filter(|&i| (vec3(&points[i]) - edge.point).dot(&edge.outward).abs() <= params.band_mm)
        .collect();
    if near.is_empty() {
        return Boundary::default();
    }
    // Walk along the image axis that crosses the edge most directly.
    let mean_axis_step = |dc: usize, dr: usize| -> f64 {
        let mut sum = 0.0;
        let mut n = 0usize;
        for &i in near.iter().step_by((near.len() / 500).max(1)) {
            let (col, row) = (i % w + dc, i / w + dr);
            if col < w && row < cloud.height() {
                let q = points[row * w + col];
                if q[0].is_finite() {
                    sum += (vec3(&q) - vec3(&points[i])).dot(&edge.outward);
                    n += 1;
                }
            }
        }
        if n == 0 { 0.0 } else { sum / n as f64 }
    };
    let (col_step, row_step) = (mean_axis_step(1, 0), mean_axis_step(0, 1));
    let along_cols = col_step.abs() >= row_step.abs();
    let axis_step = if along_cols { col_step } else { row_step };
    if axis_step == 0.0 {
        return Boundary::default();
    }
    let walker = Walker { cloud, plane, edge, params, along_cols, sense: if axis_step > 0.0 { 1 } else { -1 } };
    let mean_step = axis_step.abs();

    // The outermost member on each scan line starts that line's walk.
    let split = |i: usize| {
        if along_cols { (i / w, (i % w) as isize) } else { (i % w, (i / w) as isize) }
    };
    let mut start: std::collections::BTreeMap<usize, isize> = std::collections::BTreeMap::new();
    for &i in &near {
        let (line, k) = split(i);
        let entry = start.entry(line).or_insert(k);
        if (k - *entry) * walker.sense > 0 {
            *entry = k;
        }
    }
    let mut found: Vec<(usize, isize, BoundarySample)> = Vec::new();
    for (&line, &k) in &start {
        if let Some((end, s)) = walker.walk(line, k, mean_step) {
            found.push((line, end, s));
        }
    }
    extend_past_ends(&walker, &mut found, mean_step);
    found.sort_by_key(|(line, _, _)| *line);
    let line_spacing_mm = median_line_spacing(&found);
    Boundary { samples: found.into_iter().map(|(_, _, s)| s).collect(), line_spacing_mm }
}

/// Samples the boundary of a plate beside `edge` in a cloud without a
/// pixel grid whose points lie about `spacing_mm` apart. Every valid point
/// on the plate's plane within the band counts, not only the plate's
/// members: the plane criterion has trimmed the outermost ones. Points
/// farther out than `reach_mm` beyond the edge are left out, so a
/// coplanar neighbour plate across a narrow gap is never taken for this
/// one.
pub fn sample_scattered(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    reach_mm: f64,
) -> Boundary {
    use rayon::prelude::*;
    use std::collections::BTreeMap;

    if spacing_mm.is_nan() || spacing_mm <= 0.0 {
        return Boundary::default();
    }
    let outward_limit = params.band_mm.min(reach_mm);
    // Two spacings: a strip one spacing wide misses the boundary row's
    // point about as often as it holds it, and its outermost point is then
    // a row in; at two the row is nearly always there.
    let strip_mm = STRIP_SPACINGS * spacing_mm;
    // (strip, outward offset, point) of every on-plane point in the band.
    let in_band: Vec<(i64, f64, Vec3)> = cloud
        .points()
        .par_iter()
        .filter(|p| p[0].is_finite())
        .filter_map(|p| {
            let v = vec3(p);
            let d = v - edge.point;
            let out = d.dot(&edge.outward);
            let on_plane = plane.signed_distance(&v).abs() <= params.on_plane_mm;
            (on_plane && out >= -params.band_mm && out <= outward_limit)
                .then(|| (crate::geometry::floor_i64(d.dot(&edge.direction) / strip_mm), out, v))
        })
        .collect();
    let mut strips: BTreeMap<i64, Vec<(f64, Vec3)>> = BTreeMap::new();
    for (strip, out, v) in in_band {
        strips.entry(strip).or_default().push((out, v));
    }
    let samples = strips
        .into_values()
        .filter_map(|strip| {
            let &(last_out, last) = strip.iter().max_by(|a, b| a.0.total_cmp(&b.0))?;
            // The k points of the strip's last row (within half a spacing
            // of the outermost) split the spacing beyond the row into k + 1
            // gaps on average: the plate ends one gap beyond the outermost.
            let row = strip.iter().filter(|(out, _)| *out >= last_out - spacing_mm / 2.0).count();
            let beyond = spacing_mm / (row + 1) as f64;
            let position = plane.project(&last) + edge.outward * beyond;
            Some(BoundarySample { position, along: (position - edge.point).dot(&edge.direction) })
        })
        .collect();
    Boundary { samples, line_spacing_mm: strip_mm }
}

/// The width of [`sample_scattered`]'s strips, in point spacings.
const STRIP_SPACINGS: f64 = 2.0;

/// The median distance along the edge from one scan line's sample to the
/// next line's, per line. `found` is sorted by line.
fn median_line_spacing(found: &[(usize, isize, BoundarySample)]) -> f64 {
    let mut steps: Vec<f64> = found
        .windows(2)
        .filter(|w| w[1].0 > w[0].0)
        .map(|w| (w[1].2.along - w[0].2.along).abs() / (w[1].0 - w[0].0) as f64)
        .collect();
    if steps.is_empty() {
        return 0.0;
    }
    let mid = steps.len() / 2;
    *steps.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Continues sampling on the scan lines beyond the first and last sampled
/// ones, each walk starting a few pixels inside the previous line's
/// boundary pixel, for as long as the plate is there. The plane criterion
/// trims about R off a plate's corners, so without this the seam would
/// stop short of the plate ends. `found` holds (line, boundary pixel,
/// sample).
fn extend_past_ends(walker: &Walker, found: &mut Vec<(usize, isize, BoundarySample)>, mean_step: f64) {
    if found.is_empty() {
        return;
    }
    found.sort_by_key(|(line, _, _)| *line);
    let lines = if walker.along_cols { walker.cloud.height() } else { walker.cloud.width() };
    // Both ends are fixed before extending: extension appends to `found`.
    let ends =
        [(-1isize, found[0].0 as isize, found[0].1), (1, found[found.len() - 1].0 as isize, found[found.len() - 1].1)];
    const MAX_EXTENSION_LINES: usize = 40;
    for (direction, mut line, mut boundary) in ends {
        for _ in 0..MAX_EXTENSION_LINES {
            line += direction;
            if line < 0 || line as usize >= lines {
                break;
            }
            let walked =
                (1..8).find_map(|inset| walker.walk(line as usize, boundary - inset * walker.sense, mean_step));
            match walked {
                Some((end, s)) => {
                    found.push((line as usize, end, s));
                    boundary = end;
                }
                None => break,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;

    /// Slope of the test edge: slanted so the rows see every sub-pixel phase.
    const SLOPE: f64 = 0.1;

    /// A frontal plate at 700 mm whose edge is the line x = `edge_x` + SLOPE y,
    /// ending at y = `end_y`; beyond it the table 40 mm further away.
    fn frame(edge_x: f64, end_y: f64) -> (PointCloud, Vec<u32>) {
        let camera = CameraModel::default();
        let (w, h) = (80, 80);
        let mut pts = Vec::new();
        let mut members = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(camera.cx() - 40.0 + col as f64, camera.cy() - 40.0 + row as f64);
                let (x, y) = (r[0] * 700.0, r[1] * 700.0);
                let on_plate = x < edge_x + SLOPE * y && y < end_y;
                let z = if on_plate { 700.0 } else { 740.0 };
                // Members are the plate minus an eroded 1 mm band, as the plane criterion leaves it.
                if on_plate && x < edge_x + SLOPE * y - 1.0 && y < end_y - 1.0 {
                    members.push((row * w + col) as u32);
                }
                pts.push([(r[0] * z) as f32, (r[1] * z) as f32, z as f32]);
            }
        }
        (PointCloud::organized(w, h, pts).unwrap(), members)
    }

    #[test]
    fn samples_lie_on_the_true_edge_within_a_quarter_pixel() {
        let edge_x = 3.1;
        let (cloud, members) = frame(edge_x, 1e9);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(edge_x - 1.2, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
        let samples = sample_boundary(&cloud, &members, &plane, &edge, &params).samples;
        assert_eq!(samples.len(), 80);
        let pixel = 700.0 / CameraModel::default().fx();
        // Signed distance of each sample from the true edge line, across it.
        let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x;
        let mean = samples.iter().map(|s| offset(&s.position)).sum::<f64>() / samples.len() as f64;
        let worst = samples.iter().map(|s| offset(&s.position).abs()).fold(0.0, f64::max);
        assert!(mean.abs() < 0.1 * pixel, "mean offset {mean} mm");
        assert!(worst < 0.6 * pixel, "worst offset {worst} mm");
    }

    #[test]
    fn samples_reach_the_plate_corner() {
        let end_y = 2.0;
        let (cloud, members) = frame(3.1, end_y);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(2.0, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
        let boundary = sample_boundary(&cloud, &members, &plane, &edge, &params);
        let last = boundary.samples.iter().map(|s| s.position.y).fold(f64::MIN, f64::max);
        let pixel = 700.0 / CameraModel::default().fy();
        assert!(last > end_y - 1.01 * pixel && last < end_y, "last sample at y = {last}, plate ends at {end_y}");
        // Half a scan line beyond the last sample is the unbiased end.
        let (_, end) = boundary.extent(|s| s.position.y).unwrap();
        assert!((end - end_y).abs() < 0.55 * pixel, "extent ends at {end}, plate at {end_y}");
    }

    /// A plate of points about `spacing` apart (a jittered square grid,
    /// as voxel centroids lie) whose edge is x = `edge_x` + SLOPE y, and a
    /// coplanar plate beyond a `gap` wide gap.
    fn scattered(spacing: f64, edge_x: f64, gap: f64) -> PointCloud {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut jitter = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.5 * spacing
        };
        let mut points = Vec::new();
        let n = (60.0 / spacing) as i64;
        for row in -n..=n {
            for col in -n..=n {
                let (x, y) = (col as f64 * spacing + jitter(), row as f64 * spacing + jitter());
                let edge = edge_x + SLOPE * y;
                if x < edge || x > edge + gap {
                    points.push([x as f32, y as f32, 700.0]);
                }
            }
        }
        PointCloud::unorganized(points)
    }

    #[test]
    fn scattered_samples_lie_on_the_true_edge_within_a_fifth_of_the_spacing() {
        let (spacing, edge_x) = (1.0, 3.3);
        let cloud = scattered(spacing, edge_x, 2.0);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
        // The other plate starts 2 mm beyond the edge: reach halfway.
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, spacing, 3.0);
        assert!(boundary.samples.len() > 50, "{} samples", boundary.samples.len());
        let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x;
        // Away from the plate's ends, where the last strips hold only part
        // of a row and sample the plate's end rather than its side.
        let offsets: Vec<f64> =
            boundary.samples.iter().filter(|s| s.position.y.abs() < 57.0).map(|s| offset(&s.position)).collect();
        let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
        assert!(mean.abs() < 0.2 * spacing, "mean offset {mean} mm");
        let worst = offsets.iter().map(|o| o.abs()).fold(0.0, f64::max);
        assert!(worst < spacing, "a sample {worst} mm off the edge");
    }

    #[test]
    fn scattered_samples_never_cross_to_the_plate_beyond_the_gap() {
        let cloud = scattered(1.0, 3.3, 1.5);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(1.3, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, 2.75);
        let beyond = boundary.samples.iter().filter(|s| (s.position.x - 3.3 - SLOPE * s.position.y) > 1.0).count();
        assert_eq!(beyond, 0);
        assert!(!sample_scattered(&cloud, &plane, &edge, &params, f64::NAN, 2.75).samples.iter().any(|_| true));
    }
}
