//! A camera-frame cloud indexed by its rays, for the torch's solid: every
//! point binned by its ray's direction `(x / z, y / z)` on a grid of
//! cells, the points stored in cell order, and each tile of cells
//! bounded by the nearest and farthest range of its points.
//!
//! Why rays and not a k-d tree: the torch reaches 100 mm and more round a
//! seam, so its obstacles are most of a frame (a million points of a
//! 2.3 MP frame and more), and a k-d tree over them is sorted for every
//! plan, at O(n log n), while the torch asks a few thousand balls of it.
//! Binning by ray is two passes over the points (a count and a placement)
//! and keeps a camera's image order within a cell. A ball's points lie on
//! the rays through the ball, a window of cells round the ray of its
//! centre: for a centre `c` and radius `r` every point `q` within `r` of
//! it has `z ≥ c_z − r` and
//!
//! ```text
//! |q_x / q_z − c_x / c_z| ≤ r √(1 + (c_x / c_z)²) / (c_z − r)
//! ```
//!
//! (and the same in `y`), so the window is exact, not a guess. A torch in
//! the air mostly holds no point: a tile whose range interval misses the
//! ball's, `[|c| − r, |c| + r]`, is passed over in one comparison, and
//! only tiles a surface crosses near the ball are read point by point.
//!
//! Points at the camera's plane or behind it (none in a camera's frame,
//! but a cloud given bare may hold them) have no ray to bin: they are
//! kept aside and read by every query.

use rayon::prelude::*;

use nalgebra::Vector3;

type Vec3 = Vector3<f64>;

/// Nearer the camera's plane than this, mm, a point is not binned (its
/// ray's direction would run beyond any view); such points are read by
/// every query instead.
pub const MIN_BINNED_DEPTH_MM: f64 = 1.0;

/// The points a cell holds on average where the cloud fills its view: a
/// few, so a cell is about as wide as two of the cloud's spacings and
/// a query's window reads few cells that miss the ball.
pub const POINTS_PER_CELL: f64 = 4.0;

/// The most cells the grid may have; a cloud spread wide with few points
/// gets wider cells rather than an unbounded grid (16 MiB of offsets at
/// most).
pub const MAX_CELLS: usize = 1 << 22;

/// A tile's side, in cells: the unit the range bounds prune by.
pub const TILE_CELLS: usize = 8;

/// How far the range bounds are widened, mm, against rounding: far above
/// the single-precision error of a range of a few metres, far below
/// anything a torch's margin measures.
const RANGE_SLACK_MM: f64 = 1e-3;

/// The cloud's points by ray.
pub struct RayIndex {
    /// The cell's width in `(x / z, y / z)`, and the grid's corner there.
    cell: f64,
    origin: [f64; 2],
    width: usize,
    height: usize,
    /// Where each cell's points start in `points` (one more entry than
    /// cells).
    starts: Vec<u32>,
    /// The binned points, in cell order (image order within a cell).
    points: Vec<[f32; 3]>,
    tiles_wide: usize,
    /// Per tile, the nearest and farthest range of its points, mm
    /// (infinite and negative infinite for an empty tile).
    tile_ranges: Vec<[f32; 2]>,
    /// The farthest range of any binned point, mm (0 for none).
    farthest_mm: f64,
    /// The points too near the camera's plane to bin.
    aside: Vec<[f32; 3]>,
}

fn ray(p: &[f32; 3]) -> Option<(f64, f64)> {
    let [x, y, z] = p.map(f64::from);
    (z > MIN_BINNED_DEPTH_MM).then(|| (x / z, y / z))
}

/// The least and greatest ray direction `(x / z, y / z)` over the points a
/// grid by ray bins (finite, deeper than [`MIN_BINNED_DEPTH_MM`]), and how
/// many they are: read in parallel, for the index and the hidden space's
/// grid alike.
pub fn ray_bounds(points: &[[f32; 3]]) -> ([f64; 2], [f64; 2], usize) {
    let empty = || ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], 0usize);
    points
        .par_iter()
        .filter(|p| is_finite(p))
        .filter_map(ray)
        .fold(empty, |(lo, hi, n), (u, v)| ([lo[0].min(u), lo[1].min(v)], [hi[0].max(u), hi[1].max(v)], n + 1))
        .reduce(empty, |a, b| {
            ([a.0[0].min(b.0[0]), a.0[1].min(b.0[1])], [a.1[0].max(b.1[0]), a.1[1].max(b.1[1])], a.2 + b.2)
        })
}

fn is_finite(p: &[f32; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}

fn range(p: &[f32; 3]) -> f64 {
    p.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt()
}

impl RayIndex {
    /// Indexes the finite ones of `points` (camera frame, mm); a point
    /// with a coordinate not finite (an organized frame's empty pixel) is
    /// left out.
    pub fn new(points: &[[f32; 3]]) -> RayIndex {
        let (lo, hi, binned) = ray_bounds(points);
        let extent = if binned > 0 { [hi[0] - lo[0], hi[1] - lo[1]] } else { [0.0; 2] };
        let mut cell = (extent[0] * extent[1] * POINTS_PER_CELL / binned.max(1) as f64).sqrt();
        // A cloud on a line of rays, or a single ray, has no area: its
        // cells are as wide as its extent allows.
        if !(cell > 0.0 && cell.is_finite()) {
            cell = (extent[0].max(extent[1]) / binned.max(1) as f64).max(1e-9);
        }
        let cells_for = |cell: f64| {
            let w = (extent[0] / cell).floor() as usize + 1;
            let h = (extent[1] / cell).floor() as usize + 1;
            (w, h)
        };
        while cells_for(cell).0.saturating_mul(cells_for(cell).1) > MAX_CELLS {
            cell *= 2.0;
        }
        let (width, height) = cells_for(cell);
        let origin = if binned > 0 { lo } else { [0.0; 2] };
        let cell_of = |(u, v): (f64, f64)| {
            let i = (((u - origin[0]) / cell) as usize).min(width - 1);
            let j = (((v - origin[1]) / cell) as usize).min(height - 1);
            j * width + i
        };
        // A counting sort by cell: the count, the offsets, the placement.
        const ASIDE: u32 = u32::MAX;
        const LEFT_OUT: u32 = u32::MAX - 1;
        let keys: Vec<u32> = points
            .par_iter()
            .map(|p| match ray(p) {
                _ if !is_finite(p) => LEFT_OUT,
                Some(r) => cell_of(r) as u32,
                None => ASIDE,
            })
            .collect();
        let mut starts = vec![0u32; width * height + 1];
        for &k in keys.iter().filter(|&&k| k < LEFT_OUT) {
            starts[k as usize + 1] += 1;
        }
        for c in 0..width * height {
            starts[c + 1] += starts[c];
        }
        let mut next = starts.clone();
        let mut binned_points = vec![[0f32; 3]; binned];
        let mut aside = Vec::new();
        for (p, &k) in points.iter().zip(&keys) {
            match k {
                LEFT_OUT => {}
                ASIDE => aside.push(*p),
                _ => {
                    let slot = &mut next[k as usize];
                    binned_points[*slot as usize] = *p;
                    *slot += 1;
                }
            }
        }
        drop(keys);
        let tiles_wide = width.div_ceil(TILE_CELLS);
        let tiles_high = height.div_ceil(TILE_CELLS);
        let tile_ranges: Vec<[f32; 2]> = (0..tiles_wide * tiles_high)
            .into_par_iter()
            .map(|t| {
                let (ti, tj) = (t % tiles_wide, t / tiles_wide);
                let mut bounds = [f32::INFINITY, f32::NEG_INFINITY];
                for j in tj * TILE_CELLS..((tj + 1) * TILE_CELLS).min(height) {
                    let row = j * width;
                    let first = row + ti * TILE_CELLS;
                    let last = row + ((ti + 1) * TILE_CELLS).min(width);
                    for p in &binned_points[starts[first] as usize..starts[last] as usize] {
                        let r = range(p) as f32;
                        bounds = [bounds[0].min(r), bounds[1].max(r)];
                    }
                }
                bounds
            })
            .collect();
        let farthest_mm = tile_ranges.iter().map(|r| f64::from(r[1])).fold(0.0, f64::max);
        RayIndex {
            cell,
            origin,
            width,
            height,
            starts,
            points: binned_points,
            tiles_wide,
            tile_ranges,
            farthest_mm,
            aside,
        }
    }

    /// The points binned by ray, in cell order: all the finite ones but
    /// those too near the camera's plane.
    pub fn binned(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// The cells `[i0, i1] x [j0, j1]` whose rays may pass within
    /// `radius` of `centre`, or `None` when every ray may (a ball
    /// reaching the camera's plane).
    fn window(&self, centre: &Vec3, radius: f64) -> Option<[usize; 4]> {
        let [u, v, hu, hv] = rays_within(centre, radius)?;
        // One cell more each way: a point on the window's edge may round
        // into the cell beyond.
        let index = |t: f64, origin: f64, cells: usize| -> usize {
            let k = ((t - origin) / self.cell).floor();
            if k <= 0.0 { 0 } else { (k as usize).min(cells - 1) }
        };
        let i0 = index(u - hu, self.origin[0], self.width).saturating_sub(1);
        let i1 = (index(u + hu, self.origin[0], self.width) + 1).min(self.width - 1);
        let j0 = index(v - hv, self.origin[1], self.height).saturating_sub(1);
        let j1 = (index(v + hv, self.origin[1], self.height) + 1).min(self.height - 1);
        Some([i0, i1, j0, j1])
    }

    /// Visits every point within `radius` of `centre` (strictly inside
    /// the squared distance `radius²`, as a k-d tree's `within` does not
    /// promise either way: a point on the sphere may or may not be
    /// visited), and possibly some beyond it; the caller tests each.
    pub fn near(&self, centre: &Vec3, radius: f64, mut visit: impl FnMut(&[f32; 3])) {
        let mut scan = |ps: &[[f32; 3]]| ps.iter().for_each(&mut visit);
        scan(&self.aside);
        let [i0, i1, j0, j1] = self.window(centre, radius).unwrap_or([0, self.width - 1, 0, self.height - 1]);
        let distance = centre.norm();
        let (near, far) = (distance - radius - RANGE_SLACK_MM, distance + radius + RANGE_SLACK_MM);
        for tj in j0 / TILE_CELLS..=j1 / TILE_CELLS {
            for ti in i0 / TILE_CELLS..=i1 / TILE_CELLS {
                let [lo, hi] = self.tile_ranges[tj * self.tiles_wide + ti];
                if f64::from(hi) < near || f64::from(lo) > far {
                    continue;
                }
                let (ci0, ci1) = (i0.max(ti * TILE_CELLS), i1.min((ti + 1) * TILE_CELLS - 1));
                for j in j0.max(tj * TILE_CELLS)..=j1.min((tj + 1) * TILE_CELLS - 1) {
                    let row = j * self.width;
                    let (a, b) = (self.starts[row + ci0] as usize, self.starts[row + ci1 + 1] as usize);
                    scan(&self.points[a..b]);
                }
            }
        }
    }

    /// The distance from `p` (one of the indexed points, or any point) to
    /// the nearest indexed point apart from it, and how many indexed
    /// points lie exactly on it (squared distances in single precision,
    /// as a k-d tree of `f32` measures them); `None` for the distance
    /// when every point lies on `p`.
    pub fn nearest_apart(&self, p: &[f32; 3]) -> (Option<f64>, usize) {
        let radius = self.cell * f64::from(p[2]).abs().max(MIN_BINNED_DEPTH_MM);
        nearest_apart_by_balls(p, radius, self.farthest_mm, |centre, radius, visit| self.near(centre, radius, visit))
    }
}

/// The ray `(u, v)` through `centre` and the half-widths `(hu, hv)` of
/// the rays a point within `radius` of it may lie on, as `[u, v, hu, hv]`:
/// the ball seen from the camera spans at most `radius` over its nearest
/// depth, widened by the ray's slant. `None` when every ray may (a ball
/// reaching the camera's plane).
pub(super) fn rays_within(centre: &Vec3, radius: f64) -> Option<[f64; 4]> {
    let depth = centre.z - radius;
    if depth <= MIN_BINNED_DEPTH_MM {
        return None;
    }
    let (u, v) = (centre.x / centre.z, centre.y / centre.z);
    let reach = radius / depth;
    Some([u, v, reach * (1.0 + u * u).sqrt(), reach * (1.0 + v * v).sqrt()])
}

/// The distance from `p` to the nearest point apart from it and how many
/// points lie exactly on it (squared distances in single precision, as a
/// k-d tree of `f32` measures them; `None` for the distance when every
/// point lies on `p`), read by balls round `p` that `near` visits,
/// doubling from `radius` until one holds a point apart or every point
/// indexed, the farthest `farthest_mm` from the camera.
pub(super) fn nearest_apart_by_balls(
    p: &[f32; 3],
    mut radius: f64,
    farthest_mm: f64,
    near: impl Fn(&Vec3, f64, &mut dyn FnMut(&[f32; 3])),
) -> (Option<f64>, usize) {
    let centre = Vec3::new(p[0].into(), p[1].into(), p[2].into());
    loop {
        let (mut best, mut on) = (f32::INFINITY, 0);
        near(&centre, radius, &mut |q: &[f32; 3]| {
            let d = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
            if d == 0.0 {
                on += 1;
            } else {
                best = best.min(d);
            }
        });
        let found = f64::from(best).sqrt();
        // Found within the ball asked: nothing outside it is nearer.
        if found < radius {
            return (Some(found), on);
        }
        // Every point read: the ball holds every point indexed (a window
        // spanning the grid is not enough, as its tiles or blocks are still
        // passed over by their ranges), so what was found is all there is.
        if radius > centre.norm() + farthest_mm + RANGE_SLACK_MM || !radius.is_finite() {
            return (best.is_finite().then_some(found), on);
        }
        radius *= 2.0;
    }
}

#[cfg(test)]
#[path = "rays_tests.rs"]
mod tests;
