//! The space the camera could not see: what lies behind every surface it
//! saw, along its rays.
//!
//! A camera sees a solid's faces that turn towards it and nothing behind
//! them: a clamp's block shows its top and the faces towards the camera,
//! while its far faces and the space they close are not in the cloud at
//! all. Clearance against the seen points alone would let a torch pass
//! through such a block wherever its far side is. So the space behind a
//! seen surface, as the camera sees it, is taken as occupied: a torch may
//! go only where the camera saw through to something behind.
//!
//! The frame is the camera's: the camera at the origin, looking along
//! `+z` (the planner refuses clouds that cannot be camera-frame views, so
//! every cloud it plans on is one). Rays are binned on a grid over
//! `(x / z, y / z)`, a cell [`CELL_SPACINGS`] times the cloud's own
//! angular spacing (its caller measures it,
//! [`super::clearance::Obstacles::seen_from_camera`]); each cell keeps
//! the nearest range the camera measured along its rays.
//!
//! A point is behind a seen surface when the cells round its ray (the
//! 3 x 3 about it) hold a surface in at least [`MIN_SEEN_CELLS`] of the
//! nine, each nearer than the point by more than [`BEHIND_TOLERANCE_MM`].
//! Asking the neighbours too is what keeps the measure honest at the
//! cloud's own faults: a camera's lone return in the air casts no shadow
//! (its neighbours see past it), and a point just beside a surface's edge
//! is not behind it (the cells beyond the edge see farther).

use nalgebra::Vector3;
use rayon::prelude::*;

// Nearer the camera's plane than the index's bound, a point's ray is not
// binned here either (it would fall beyond any view).
use super::rays::{MIN_BINNED_DEPTH_MM as MIN_DEPTH_MM, ray_bounds};

type Vec3 = Vector3<f64>;

/// The grid's cell, in multiples of the cloud's median angular spacing:
/// wide enough that a surface leaves few cells empty, fine enough that a
/// cell stays within a millimetre or so at the working distance.
pub const CELL_SPACINGS: f64 = 1.5;

/// Of the nine cells round a ray, how many must hold a surface for a
/// point on it to be behind one: most of them, so a dropout or two on
/// shiny metal does not open a shadow, and a lone return does not make
/// one.
pub const MIN_SEEN_CELLS: usize = 5;

/// How far behind a seen surface a point must be to count as behind it,
/// mm: several times a structured-light camera's depth noise at the
/// working distance, so a surface's own noise is not a solid behind it.
pub const BEHIND_TOLERANCE_MM: f64 = 2.0;

/// The most cells the grid may have: a cloud spread wide at a fine
/// spacing gets coarser cells rather than an unbounded grid (16 MiB of
/// ranges at most).
pub const MAX_CELLS: usize = 1 << 22;

/// The fewest points a thread bins into a grid of its own: below this a
/// grid's allocation costs more than the points it spares another thread.
const MIN_POINTS_PER_SHARE: usize = 1 << 16;

/// The space behind the surfaces a camera saw.
#[derive(Debug, Clone)]
pub struct Shadows {
    /// The cloud's median angular spacing, in `(x / z, y / z)`.
    spacing: f64,
    /// The cell's width in `(x / z, y / z)`, and the grid's corner there.
    cell: f64,
    origin: [f64; 2],
    width: usize,
    height: usize,
    /// Per cell, the range beyond which a point on its rays is behind a
    /// seen surface (infinite where it is not), mm.
    behind_from: Vec<f32>,
}

impl Shadows {
    /// The shadows of `points`, camera frame, mm, whose median angular
    /// spacing is `spacing` (in `(x / z, y / z)`); `None` when no point
    /// lies in front of the camera or the spacing is not positive
    /// (nothing is then taken as hidden).
    pub fn new(points: &[[f32; 3]], spacing: f64) -> Option<Shadows> {
        let ray = |p: &[f32; 3]| {
            let [x, y, z] = p.map(f64::from);
            (z > MIN_DEPTH_MM && [x, y, z].iter().all(|c| c.is_finite()))
                .then(|| (x / z, y / z, (x * x + y * y + z * z).sqrt()))
        };
        if !(spacing > 0.0 && spacing.is_finite()) {
            return None;
        }
        let (lo, hi, _) = ray_bounds(points);
        if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
            return None;
        }
        // One cell of border all round, so every seen cell has its nine.
        let mut cell = spacing * CELL_SPACINGS;
        let cells_for = |cell: f64| {
            let w = ((hi[0] - lo[0]) / cell).ceil() as usize + 3;
            let h = ((hi[1] - lo[1]) / cell).ceil() as usize + 3;
            (w, h)
        };
        while cells_for(cell).0.saturating_mul(cells_for(cell).1) > MAX_CELLS {
            cell *= 2.0;
        }
        let (width, height) = cells_for(cell);
        let origin = [lo[0] - cell, lo[1] - cell];
        // The nearest range per cell: each thread's share of the points
        // into a grid of its own, the grids then met cell by cell (a
        // minimum, so the order does not matter).
        let share = points.len().div_ceil(rayon::current_num_threads()).max(MIN_POINTS_PER_SHARE);
        let nearest = points
            .par_chunks(share)
            .map(|chunk| {
                let mut nearest = vec![f32::INFINITY; width * height];
                for (u, v, range) in chunk.iter().filter_map(ray) {
                    let (i, j) = (((u - origin[0]) / cell) as usize, ((v - origin[1]) / cell) as usize);
                    let c = &mut nearest[j * width + i];
                    *c = c.min(range as f32);
                }
                nearest
            })
            .reduce_with(|mut a, b| {
                a.iter_mut().zip(b).for_each(|(a, b)| *a = a.min(b));
                a
            })
            .unwrap_or_else(|| vec![f32::INFINITY; width * height]);
        let mut behind_from = vec![f32::INFINITY; width * height];
        behind_from.par_chunks_mut(width).enumerate().filter(|(j, _)| (1..height - 1).contains(j)).for_each(
            |(j, row)| {
                for (i, out) in row.iter_mut().enumerate().take(width - 1).skip(1) {
                    let (mut seen, mut farthest) = (0, f32::NEG_INFINITY);
                    for dj in 0..3 {
                        for di in 0..3 {
                            let r = nearest[(j + dj - 1) * width + (i + di - 1)];
                            if r.is_finite() {
                                seen += 1;
                                farthest = farthest.max(r);
                            }
                        }
                    }
                    if seen >= MIN_SEEN_CELLS {
                        *out = farthest + BEHIND_TOLERANCE_MM as f32;
                    }
                }
            },
        );
        Some(Shadows { spacing, cell, origin, width, height, behind_from })
    }

    /// Whether `p` (camera frame, mm) lies behind a surface the camera
    /// saw.
    pub fn hides(&self, p: &Vec3) -> bool {
        if p.z <= MIN_DEPTH_MM {
            return false;
        }
        let (u, v) = ((p.x / p.z - self.origin[0]) / self.cell, (p.y / p.z - self.origin[1]) / self.cell);
        if !(u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64) {
            return false;
        }
        let (i, j) = (u as usize, v as usize);
        (p.norm() as f32) > self.behind_from[j * self.width + i]
    }

    /// The grid's cell, in `(x / z, y / z)`.
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// The cloud's median angular spacing, in `(x / z, y / z)`: times a
    /// range, about the spacing of its points there, mm.
    pub fn spacing(&self) -> f64 {
        self.spacing
    }
}

#[cfg(test)]
#[path = "shadow_tests.rs"]
mod tests;
