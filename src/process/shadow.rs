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

use std::sync::{Arc, OnceLock};

use nalgebra::Vector3;
use rayon::prelude::*;

use super::blocks::BlockIndex;

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

/// The grid's cell and its corner in `(x / z, y / z)`, and its size in
/// cells, over the rays `[lo, hi]` of a cloud whose spacing is given.
#[derive(Debug, Clone, Copy)]
struct Layout {
    cell: f64,
    origin: [f64; 2],
    width: usize,
    height: usize,
}

impl Layout {
    fn over(lo: [f64; 2], hi: [f64; 2], spacing: f64) -> Option<Layout> {
        if !(spacing > 0.0 && spacing.is_finite() && lo[0] <= hi[0] && lo[1] <= hi[1]) {
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
        Some(Layout { cell, origin: [lo[0] - cell, lo[1] - cell], width, height })
    }

    /// The cell `(i, j)` of the ray through `p`, if `p` is in front of the
    /// camera and its ray on the grid.
    #[inline]
    fn cell_of(&self, p: &Vec3) -> Option<(usize, usize)> {
        if p.z <= MIN_DEPTH_MM {
            return None;
        }
        let (u, v) = ((p.x / p.z - self.origin[0]) / self.cell, (p.y / p.z - self.origin[1]) / self.cell);
        (u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64).then_some((u as usize, v as usize))
    }
}

/// The range beyond which a point on a cell's rays is behind a seen
/// surface, from the nearest range of the nine cells round it
/// (`nearest(di, dj)`, `di` and `dj` from 0 to 2): infinite where too few
/// of them saw one.
fn hidden_beyond(nearest: impl Fn(usize, usize) -> f32) -> f32 {
    let (mut seen, mut farthest) = (0, f32::NEG_INFINITY);
    for dj in 0..3 {
        for di in 0..3 {
            let r = nearest(di, dj);
            if r.is_finite() {
                seen += 1;
                farthest = farthest.max(r);
            }
        }
    }
    if seen >= MIN_SEEN_CELLS { farthest + BEHIND_TOLERANCE_MM as f32 } else { f32::INFINITY }
}

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
        let (lo, hi, _) = ray_bounds(points);
        let Layout { cell, origin, width, height } = Layout::over(lo, hi, spacing)?;
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
                    *out = hidden_beyond(|di, dj| nearest[(j + dj - 1) * width + (i + di - 1)]);
                }
            },
        );
        Some(Shadows { spacing, cell, origin, width, height, behind_from })
    }

    /// Whether `p` (camera frame, mm) lies behind a surface the camera
    /// saw.
    pub fn hides(&self, p: &Vec3) -> bool {
        let layout = Layout { cell: self.cell, origin: self.origin, width: self.width, height: self.height };
        layout.cell_of(p).is_some_and(|(i, j)| (p.norm() as f32) > self.behind_from[j * self.width + i])
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

/// How far the two cells [`LazyShadows::clears_ball`] widens a window by
/// are stretched against rounding, relative: far above the rounding of a
/// ray's cell index, far below a cell.
const CELL_REACH_SLACK: f64 = 1e-6;

/// The cells a tile of the hidden space's grid has a side of, where it is
/// laid tile by tile as the torch asks: a few torches' width of rays at
/// the working distance, so a torch reads few tiles and a tile few blocks.
pub const TILE_CELLS: usize = 16;

/// How many points [`LazyShadows::hides_each`] places before it looks
/// any of them up: enough that their divisions overlap, few enough to
/// keep on the stack. Speed only.
const RUN_POINTS: usize = 16;

/// A point as [`LazyShadows::hides`] reads it: its cell of the grid (none
/// off the grid or at the camera's plane), its range, mm, and the blocks'
/// coarse cell its ray falls in (none where the blocks do not prune).
#[derive(Clone, Copy)]
struct Placed {
    cell: Option<(usize, usize)>,
    range: f64,
    coarse: Option<usize>,
}

impl Placed {
    const NOWHERE: Placed = Placed { cell: None, range: 0.0, coarse: None };
}

/// [`Shadows`] of an organized frame, laid over the same grid (the frame's
/// own least ray, the same cells) but computed a tile at a time, the first
/// time a point on the tile's rays is asked about: the torch reads the
/// rays round the seam, not the frame. The tiles are read from the
/// frame's blocks of pixels ([`BlockIndex`]), so nothing passes over the
/// whole frame but the blocks' own bounds.
pub struct LazyShadows<'a> {
    blocks: Arc<BlockIndex<'a>>,
    spacing: f64,
    layout: Layout,
    tiles_wide: usize,
    /// Per tile, its cells' ranges beyond which a point is hidden, row
    /// after row, once computed.
    tiles: Vec<OnceLock<Vec<f32>>>,
    /// Whether the blocks' coarse cells are wide enough to rule a point
    /// out by its range alone ([`BlockIndex::least_range_near`]).
    prunes: bool,
}

impl<'a> LazyShadows<'a> {
    /// The shadows of the frame `blocks` index, whose median angular
    /// spacing is `spacing`; `None` where [`Shadows::new`] gives none.
    pub fn new(blocks: Arc<BlockIndex<'a>>, spacing: f64) -> Option<LazyShadows<'a>> {
        let (lo, hi, _) = blocks.ray_bounds();
        let layout = Layout::over(lo, hi, spacing)?;
        let tiles_wide = layout.width.div_ceil(TILE_CELLS);
        let tiles = (0..tiles_wide * layout.height.div_ceil(TILE_CELLS)).map(|_| OnceLock::new()).collect();
        let prunes = 2.0 * layout.cell <= blocks.coarse_cell() / 2.0;
        Some(LazyShadows { blocks, spacing, layout, tiles_wide, tiles, prunes })
    }

    /// Whether `p` (camera frame, mm) lies behind a surface the camera
    /// saw: what [`Shadows::hides`] answers for the same frame.
    pub fn hides(&self, p: &Vec3) -> bool {
        self.hides_placed(&self.place(p))
    }

    /// [`LazyShadows::hides`] for each of `points` in turn, handed to
    /// `visit` with its index until `visit` returns `false`: the same
    /// answer for each point, with the rays and ranges of a run of them
    /// worked out before any is looked up, so that their divisions and
    /// roots proceed side by side instead of each question waiting on
    /// its own.
    pub fn hides_each(&self, points: &[Vec3], mut visit: impl FnMut(usize, bool) -> bool) {
        for (run, chunk) in points.chunks(RUN_POINTS).enumerate() {
            let mut placed = [Placed::NOWHERE; RUN_POINTS];
            for (out, p) in placed.iter_mut().zip(chunk) {
                *out = self.place(p);
            }
            for (k, placed) in placed[..chunk.len()].iter().enumerate() {
                if !visit(run * RUN_POINTS + k, self.hides_placed(placed)) {
                    return;
                }
            }
        }
    }

    /// A point's cell, its range and, where the blocks prune, their
    /// coarse cell its ray falls in: everything [`LazyShadows::hides`]
    /// divides for.
    #[inline]
    fn place(&self, p: &Vec3) -> Placed {
        let cell = self.layout.cell_of(p);
        let coarse =
            if self.prunes && cell.is_some() { self.blocks.coarse_cell_of(p.x / p.z, p.y / p.z) } else { None };
        Placed { cell, range: p.norm(), coarse }
    }

    #[inline]
    fn hides_placed(&self, placed: &Placed) -> bool {
        let Some((i, j)) = placed.cell else { return false };
        // Nearer than every point round its ray, by more than the rounding
        // of a range, a point is in front of whatever the nine cells saw:
        // most of a torch in the air is answered so, with no tile laid.
        // (The nine cells reach two cells from the point's ray, within
        // half a coarse cell of the blocks where `prunes` holds.)
        if self.prunes && placed.range <= self.blocks.least_range_round(placed.coarse) + BEHIND_TOLERANCE_MM / 2.0 {
            return false;
        }
        let (ti, tj) = (i / TILE_CELLS, j / TILE_CELLS);
        let tile = self.tiles[tj * self.tiles_wide + ti].get_or_init(|| self.tile(ti, tj));
        let (i0, width) = (ti * TILE_CELLS, (((ti + 1) * TILE_CELLS).min(self.layout.width)) - ti * TILE_CELLS);
        (placed.range as f32) > tile[(j - tj * TILE_CELLS) * width + (i - i0)]
    }

    /// Whether no point within `radius` of `centre` is behind a seen
    /// surface, by the blocks' ranges alone, no tile laid: `false` where
    /// some may be. A point the ball holds has its ray in the ball's
    /// window of rays, the nine cells round that ray reach two cells from
    /// it, and the points seen on those cells are no nearer than the
    /// least range of the blocks listed there; a ball no farther than
    /// that, with the margin [`LazyShadows::hides`] prunes by, is in
    /// front of all of them.
    pub fn clears_ball(&self, centre: &Vec3, radius: f64) -> bool {
        let Some([u0, u1, v0, v1]) = BlockIndex::window(centre, radius) else { return false };
        let reach = 2.0 * self.layout.cell * (1.0 + CELL_REACH_SLACK);
        let rect = [u0 - reach, u1 + reach, v0 - reach, v1 + reach];
        centre.norm() + radius <= self.blocks.least_range_in(&rect) + BEHIND_TOLERANCE_MM / 2.0
    }

    /// One tile's cells: the nearest range of every cell round them, read
    /// off the blocks whose rays meet those cells, and the rule of
    /// [`Shadows::new`] applied to each.
    fn tile(&self, ti: usize, tj: usize) -> Vec<f32> {
        let Layout { cell, origin, width, height } = self.layout;
        let (i0, i1) = (ti * TILE_CELLS, ((ti + 1) * TILE_CELLS).min(width) - 1);
        let (j0, j1) = (tj * TILE_CELLS, ((tj + 1) * TILE_CELLS).min(height) - 1);
        // The cells round the tile, one more each way where the grid has
        // them.
        let (ni0, ni1, nj0, nj1) =
            (i0.saturating_sub(1), (i1 + 1).min(width - 1), j0.saturating_sub(1), (j1 + 1).min(height - 1));
        let nw = ni1 - ni0 + 1;
        let mut nearest = vec![f32::INFINITY; nw * (nj1 - nj0 + 1)];
        // The rays of those cells, one cell wider each way against
        // rounding: every point that falls in them is read.
        let rect = [
            origin[0] + (ni0 as f64 - 1.0) * cell,
            origin[0] + (ni1 as f64 + 2.0) * cell,
            origin[1] + (nj0 as f64 - 1.0) * cell,
            origin[1] + (nj1 as f64 + 2.0) * cell,
        ];
        let (near, far) = (f64::NEG_INFINITY, f64::INFINITY);
        self.blocks.blocks_meeting(&rect, near, far, |b| {
            self.blocks.block_points_meeting(b, &rect, near, far, |p| {
                let [x, y, z] = p.map(f64::from);
                let (i, j) = (((x / z - origin[0]) / cell) as usize, ((y / z - origin[1]) / cell) as usize);
                if (ni0..=ni1).contains(&i) && (nj0..=nj1).contains(&j) {
                    let c = &mut nearest[(j - nj0) * nw + (i - ni0)];
                    *c = c.min((x * x + y * y + z * z).sqrt() as f32);
                }
            });
        });
        let mut out = Vec::with_capacity((i1 - i0 + 1) * (j1 - j0 + 1));
        for j in j0..=j1 {
            for i in i0..=i1 {
                let inner = (1..width - 1).contains(&i) && (1..height - 1).contains(&j);
                out.push(if inner {
                    hidden_beyond(|di, dj| nearest[(j + dj - 1 - nj0) * nw + (i + di - 1 - ni0)])
                } else {
                    f32::INFINITY
                });
            }
        }
        out
    }

    /// The cloud's median angular spacing, in `(x / z, y / z)`.
    pub fn spacing(&self) -> f64 {
        self.spacing
    }
}

#[cfg(test)]
#[path = "shadow_tests.rs"]
mod tests;
