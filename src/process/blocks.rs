//! An organized frame indexed for the torch by its own pixel grid: the
//! frame cut into square blocks of pixels, each bounded once by the rays
//! `(x / z, y / z)` and the ranges of its points, and a coarse grid over
//! ray space listing the blocks whose rays meet each of its cells.
//!
//! Why not [`super::rays::RayIndex`] on such a frame: binning every point
//! by its ray is a counting sort of the whole frame (a count, a placement
//! of 2.3 M points, and the ranges of every tile), while the torch reads
//! only the rays round the seam. A camera's pixel grid already keeps
//! neighbouring rays together, so a block of pixels covers a small patch
//! of rays and bounding it is one read of its points, with nothing moved.
//! The bounds are measured, not taken from the camera's model, so a ball
//! finds every point within it whatever the frame's calibration: a point
//! within the ball has its ray in the ball's window of rays, its block's
//! bounds hold that ray, and the coarse cells the window meets list the
//! block.
//!
//! The same pass gives the frame's least and greatest ray, which the
//! hidden space's grid is laid from ([`super::shadow::LazyShadows`]), and
//! that grid reads the blocks the same way, tile by tile, where the torch
//! asks.
//!
//! The same pass bounds each block's patches of [`PATCH_PX`] x
//! [`PATCH_PX`] pixels too (a box of their points, nothing divided: the
//! kernels' [`crate::kernels::quad_boxes`], a band of a patch's rows at a
//! time, in vector lanes where the CPU has them), and a
//! block a ball meets is read patch by patch: only the patches whose box
//! the ball meets (a ball's window of rays and its ranges hold a slab of
//! surface several times what the ball holds where the ball only reaches
//! into it; the boxes hold their points a few pixels wide). A ball of a
//! few of the cloud's spacings (the nearest-point queries that measure
//! the spacing) meets a few patches of a block, not its every pixel. The
//! hidden space's tiles, which ask by rays alone, read the patches whose
//! rays they meet, worked out from the boxes the first time the block is
//! read. Each coarse cell keeps the ranges of the blocks listed in it, so
//! a ball in the air in front of the surfaces (most of a torch) passes
//! over the cells of its window without reading their lists.

use std::sync::OnceLock;

use rayon::prelude::*;

use nalgebra::Vector3;

use super::rays::{MIN_BINNED_DEPTH_MM, nearest_apart_by_balls, rays_within};
use crate::kernels::{self, QuadBox};

type Vec3 = Vector3<f64>;

/// A block's side, pixels: a few of the cloud's spacings, so a torch's
/// ball (millimetres to centimetres across) reads few blocks beyond it,
/// while the blocks stay few enough to list (a 2.3 MP frame has about
/// nine thousand).
pub const BLOCK_PX: usize = 16;

/// A patch's side, pixels: a block is read patch by patch where a ball
/// meets part of it. A few pixels, so a ball a few spacings wide reads
/// little beyond itself, while a block's patches stay few enough to test
/// one by one (sixteen).
pub const PATCH_PX: usize = 4;

// A patch's row is one quad of the kernel that bounds the frame.
const _: () = assert!(PATCH_PX == kernels::QUAD);

/// A block's patches a side, and in all.
const PATCHES_A_SIDE: usize = BLOCK_PX / PATCH_PX;
const PATCHES_PER_BLOCK: usize = PATCHES_A_SIDE * PATCHES_A_SIDE;

/// How far a window of rays is widened against rounding, in `(x / z,
/// y / z)`, relative and absolute: far below a pixel's angle, far above
/// the double-precision error of a ray's direction.
const RAY_SLACK_RELATIVE: f64 = 1e-9;
const RAY_SLACK: f64 = 1e-12;

/// How far the range bounds are widened, mm, against rounding (as the
/// index by rays widens its own).
const RANGE_SLACK_MM: f64 = 1e-3;

/// How far a ball is widened against rounding, mm, where it is tested
/// against a box of points: as the range bounds are.
const BOX_SLACK_MM: f64 = RANGE_SLACK_MM;

/// A rectangle of rays, `[u0, u1, v0, v1]` in `(x / z, y / z)`.
pub type RayRect = [f64; 4];

/// An organized frame's points by blocks of pixels.
pub struct BlockIndex<'a> {
    points: &'a [[f32; 3]],
    width: usize,
    blocks_wide: usize,
    /// Per block, the rectangle of its points' rays (empty, `u0 > u1`,
    /// when it holds none deeper than [`MIN_BINNED_DEPTH_MM`]) and the
    /// nearest and farthest range of those points, mm.
    rays: Vec<RayRect>,
    ranges: Vec<[f64; 2]>,
    /// Per block, the box of those points.
    block_boxes: Vec<BlockBox>,
    /// Per block, the boxes of its patches, row after row
    /// ([`PATCHES_PER_BLOCK`] to a block), and their rays and ranges once
    /// the block is first read.
    patch_boxes: Vec<BlockBox>,
    patch_bounds: Vec<OnceLock<Box<[PatchBounds]>>>,
    /// The farthest range of any point, mm (0 for none).
    farthest_mm: f64,
    /// The finite points too near the camera's plane to have a ray: read
    /// by every query.
    aside: Vec<[f32; 3]>,
    /// The least and greatest ray of all the frame's points, and how many
    /// points have one.
    lo: [f64; 2],
    hi: [f64; 2],
    binned: usize,
    /// The coarse grid over `[lo, hi]`: its cell's width, its size, and
    /// per cell the blocks whose rays meet it (offsets into `members`).
    cell: f64,
    grid_wide: usize,
    grid_high: usize,
    starts: Vec<u32>,
    members: Vec<u32>,
    /// Per block, the first coarse cell it is listed in, `[i, j]`: a
    /// block listed in several of the cells a query reads is read once,
    /// in the first of them.
    first_cell: Vec<[u32; 2]>,
    /// Per coarse cell, the nearest and farthest range of the blocks
    /// listed in it, mm (`[inf, -inf]` where none is): a query whose
    /// ranges miss a cell's reads none of its blocks.
    cell_ranges: Vec<[f64; 2]>,
    /// Per coarse cell, the least range a block listed in it or in one of
    /// the eight round it may hold, mm (infinite where none).
    nearest_round: Vec<f64>,
}

/// The box of one block's points that have a ray (finite, deeper than
/// [`MIN_BINNED_DEPTH_MM`]), `[x0, y0, z0, x1, y1, z1]`, and how many
/// they are.
#[derive(Clone, Copy)]
struct BlockBox {
    min: [f32; 3],
    max: [f32; 3],
    binned: usize,
}

const EMPTY_BOX: BlockBox = BlockBox { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3], binned: 0 };

/// A patch's rays and the nearest and farthest range of its points, as
/// [`BlockBox::rays`] and [`BlockBox::ranges`] give them.
struct PatchBounds {
    rays: RayRect,
    ranges: [f64; 2],
}

impl BlockBox {
    /// The box of a quad's points that have a ray, as the kernel bounded
    /// them: a plain minimum and maximum per coordinate, no division.
    fn of(quad: &QuadBox) -> BlockBox {
        BlockBox { min: quad.min, max: quad.max, binned: quad.binned as usize }
    }

    /// The squared distance from `centre` to the box, 0 inside it
    /// (infinite for an empty box).
    fn distance_squared(&self, centre: &Vec3) -> f64 {
        if self.binned == 0 {
            return f64::INFINITY;
        }
        (0..3)
            .map(|k| {
                let (lo, hi) = (f64::from(self.min[k]), f64::from(self.max[k]));
                let off = (lo - centre[k]).max(centre[k] - hi).max(0.0);
                off * off
            })
            .sum()
    }

    /// The box holding both boxes' points.
    fn union(&self, other: &BlockBox) -> BlockBox {
        let mut out = *self;
        for k in 0..3 {
            out.min[k] = out.min[k].min(other.min[k]);
            out.max[k] = out.max[k].max(other.max[k]);
        }
        out.binned += other.binned;
        out
    }

    /// The rays the box's points may lie on: for `z > 0`, `x / z` is least
    /// at the least `x` over the nearest or the farthest `z`, and so on
    /// (each division rounded as the points' own are, so the bound holds
    /// them exactly); empty for an empty box.
    fn rays(&self) -> RayRect {
        if self.binned == 0 {
            return EMPTY_RECT;
        }
        let [x0, y0, z0] = self.min.map(f64::from);
        let [x1, y1, z1] = self.max.map(f64::from);
        [(x0 / z0).min(x0 / z1), (x1 / z0).max(x1 / z1), (y0 / z0).min(y0 / z1), (y1 / z0).max(y1 / z1)]
    }

    /// The nearest and farthest range the box's points may have, mm.
    fn ranges(&self) -> [f64; 2] {
        if self.binned == 0 {
            return [f64::INFINITY, f64::NEG_INFINITY];
        }
        let (mut near, mut far) = (0.0, 0.0);
        for k in 0..3 {
            let (a, b) = (f64::from(self.min[k]), f64::from(self.max[k]));
            let nearest = if a > 0.0 {
                a
            } else if b < 0.0 {
                -b
            } else {
                0.0
            };
            near += nearest * nearest;
            far += a.abs().max(b.abs()).powi(2);
        }
        [near.sqrt(), far.sqrt()]
    }
}

const EMPTY_RECT: RayRect = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];

fn ray_of(p: &[f32; 3]) -> Option<(f64, f64)> {
    let [x, y, z] = p.map(f64::from);
    (z > MIN_BINNED_DEPTH_MM && p.iter().all(|c| c.is_finite())).then(|| (x / z, y / z))
}

fn meets(a: &RayRect, b: &RayRect) -> bool {
    a[0] <= b[1] && b[0] <= a[1] && a[2] <= b[3] && b[2] <= a[3]
}

impl<'a> BlockIndex<'a> {
    /// Indexes an organized frame of `width` pixels a row (its points,
    /// camera frame, mm, row after row; an empty pixel's not finite).
    pub fn new(points: &'a [[f32; 3]], width: usize) -> BlockIndex<'a> {
        let width = width.max(1);
        let height = points.len().div_ceil(width);
        let blocks_wide = width.div_ceil(BLOCK_PX);
        let blocks_high = height.div_ceil(BLOCK_PX);
        // One read of every point, a row of blocks to a task, into the
        // boxes of the blocks' patches.
        let mut patch_boxes = vec![EMPTY_BOX; blocks_wide * blocks_high * PATCHES_PER_BLOCK];
        let asides: Vec<Vec<[f32; 3]>> = patch_boxes
            .par_chunks_mut((blocks_wide * PATCHES_PER_BLOCK).max(1))
            .enumerate()
            .map(|(bj, row)| {
                let mut aside = Vec::new();
                let mut quads = vec![QuadBox::EMPTY; width.div_ceil(PATCH_PX)];
                // A band of a patch's rows at a time, each patch's box
                // from one quad of the band.
                for first in (bj * BLOCK_PX..((bj + 1) * BLOCK_PX).min(height)).step_by(PATCH_PX) {
                    let line = |j: usize| &points[j * width..((j + 1) * width).min(points.len())];
                    let band: Vec<&[[f32; 3]]> = (first..(first + PATCH_PX).min(height)).map(line).collect();
                    let patch_row = (first - bj * BLOCK_PX) / PATCH_PX * PATCHES_A_SIDE;
                    // Only a frame's last row may be short of its width:
                    // it is bounded on its own.
                    let (whole, short) = band.split_at(band.iter().take_while(|l| l.len() == width).count());
                    let mut too_near = 0;
                    for rows in [whole].into_iter().chain(short.chunks(1)).filter(|rows| !rows.is_empty()) {
                        let quads = &mut quads[..rows[0].len().div_ceil(PATCH_PX)];
                        kernels::quad_boxes(rows, MIN_BINNED_DEPTH_MM as f32, quads);
                        for (k, quad) in quads.iter().enumerate() {
                            let (block, patch) = (k / PATCHES_A_SIDE, k % PATCHES_A_SIDE);
                            let own = &mut row[block * PATCHES_PER_BLOCK + patch_row + patch];
                            *own = own.union(&BlockBox::of(quad));
                            too_near += (quad.finite - quad.binned) as usize;
                        }
                    }
                    if too_near > 0 {
                        let is_too_near =
                            |p: &&[f32; 3]| p[2] <= MIN_BINNED_DEPTH_MM as f32 && p.iter().all(|c| c.is_finite());
                        aside.extend(band.iter().flat_map(|line| line.iter().filter(is_too_near)));
                    }
                }
                aside
            })
            .collect();
        let aside = asides.concat();
        // Each block's bounds from its patches' boxes.
        let bounds: Vec<(RayRect, [f64; 2], BlockBox)> = patch_boxes
            .par_chunks(PATCHES_PER_BLOCK)
            .map(|patches| {
                let block = patches.iter().fold(EMPTY_BOX, |b, p| b.union(p));
                (block.rays(), block.ranges(), block)
            })
            .collect();
        let rays: Vec<RayRect> = bounds.iter().map(|b| b.0).collect();
        let ranges: Vec<[f64; 2]> = bounds.iter().map(|b| b.1).collect();
        let block_boxes: Vec<BlockBox> = bounds.iter().map(|b| b.2).collect();
        let binned = block_boxes.iter().map(|b| b.binned).sum();
        let farthest_mm = ranges.iter().map(|r| r[1]).fold(0.0, f64::max);
        let mut index = BlockIndex {
            points,
            width,
            blocks_wide,
            rays,
            ranges,
            block_boxes,
            patch_bounds: (0..bounds.len()).map(|_| OnceLock::new()).collect(),
            patch_boxes,
            farthest_mm,
            aside,
            lo: [f64::INFINITY; 2],
            hi: [f64::NEG_INFINITY; 2],
            binned,
            cell: 1.0,
            grid_wide: 1,
            grid_high: 1,
            starts: Vec::new(),
            members: Vec::new(),
            first_cell: Vec::new(),
            nearest_round: Vec::new(),
            cell_ranges: Vec::new(),
        };
        (index.lo, index.hi) = index.exact_ray_bounds();
        index.list_blocks();
        index
    }

    /// The frame's least and greatest ray, each exactly as the points'
    /// own divisions give it: the block whose bound is the most promising
    /// is read first, then every other block whose bound can beat the
    /// best found so far, patch by patch (a few columns or rows of blocks
    /// at the frame's edges). The extreme point's own block and patch are
    /// among them, as their bounds hold it.
    fn exact_ray_bounds(&self) -> ([f64; 2], [f64; 2]) {
        // (the bound's side of the ray, whether it is an upper end, the
        // ray's coordinate)
        let extreme = |bound: usize, upper: bool, coordinate: usize| -> f64 {
            let sign = if upper { -1.0 } else { 1.0 };
            let key = |rays: &RayRect| if rays[0] <= rays[1] { sign * rays[bound] } else { f64::INFINITY };
            let mut best = f64::INFINITY;
            let read = |b: usize, best: &mut f64| {
                for (k, patch) in self.patches(b).iter().enumerate() {
                    if key(&patch.rays) <= *best {
                        self.patch_points(b, k, |p| {
                            let (u, v) = ray_of(p).expect("a patch's points read have a ray");
                            *best = best.min(sign * if coordinate == 0 { u } else { v });
                        });
                    }
                }
            };
            let first = (0..self.rays.len()).min_by(|&a, &b| key(&self.rays[a]).total_cmp(&key(&self.rays[b])));
            if let Some(first) = first {
                read(first, &mut best);
            }
            for b in 0..self.rays.len() {
                if Some(b) != first && key(&self.rays[b]) <= best {
                    read(b, &mut best);
                }
            }
            sign * best
        };
        if self.binned == 0 {
            return ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        }
        ([extreme(0, false, 0), extreme(2, false, 1)], [extreme(1, true, 0), extreme(3, true, 1)])
    }

    /// Lays the coarse grid over the frame's rays, a cell about a block's
    /// width of rays, and lists each block in the cells its rays meet.
    fn list_blocks(&mut self) {
        let filled = self.rays.iter().filter(|r| r[0] <= r[1]).count();
        let extent = [self.hi[0] - self.lo[0], self.hi[1] - self.lo[1]];
        let mut cell = (extent[0] * extent[1] / filled.max(1) as f64).sqrt();
        if !(cell > 0.0 && cell.is_finite()) {
            cell = (extent[0].max(extent[1]) / filled.max(1) as f64).max(1e-9);
        }
        let (wide, high) = if filled > 0 {
            ((extent[0] / cell).floor() as usize + 1, (extent[1] / cell).floor() as usize + 1)
        } else {
            (1, 1)
        };
        // As many cells as blocks at most: a frame's blocks spread far
        // apart in rays (a cloud with a few wild points) widen the cells.
        let (mut wide, mut high, mut cell) = (wide, high, cell);
        while wide.saturating_mul(high) > 4 * self.rays.len().max(1) {
            cell *= 2.0;
            wide = (extent[0] / cell).floor() as usize + 1;
            high = (extent[1] / cell).floor() as usize + 1;
        }
        (self.cell, self.grid_wide, self.grid_high) = (cell, wide, high);
        let cells_of = |r: &RayRect| -> [usize; 4] { self.cells_of(r) };
        let mut counts = vec![0u32; wide * high + 1];
        let mut first_cell = vec![[u32::MAX; 2]; self.rays.len()];
        for (b, r) in self.rays.iter().enumerate() {
            if r[0] > r[1] {
                continue;
            }
            let [i0, i1, j0, j1] = cells_of(r);
            first_cell[b] = [i0 as u32, j0 as u32];
            for j in j0..=j1 {
                for i in i0..=i1 {
                    counts[j * wide + i + 1] += 1;
                }
            }
        }
        for c in 0..wide * high {
            counts[c + 1] += counts[c];
        }
        let mut next = counts.clone();
        let mut members = vec![0u32; counts[wide * high] as usize];
        for (b, r) in self.rays.iter().enumerate() {
            if r[0] > r[1] {
                continue;
            }
            let [i0, i1, j0, j1] = cells_of(r);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let slot = &mut next[j * wide + i];
                    members[*slot as usize] = b as u32;
                    *slot += 1;
                }
            }
        }
        self.cell_ranges = (0..wide * high)
            .map(|c| {
                let listed = &members[counts[c] as usize..counts[c + 1] as usize];
                listed
                    .iter()
                    .map(|&b| self.ranges[b as usize])
                    .fold([f64::INFINITY, f64::NEG_INFINITY], |a, r| [a[0].min(r[0]), a[1].max(r[1])])
            })
            .collect();
        let least: Vec<f64> = self.cell_ranges.iter().map(|r| r[0]).collect();
        self.nearest_round = (0..wide * high)
            .map(|c| {
                let (i, j) = (c % wide, c / wide);
                let mut nearest = f64::INFINITY;
                for jj in j.saturating_sub(1)..=(j + 1).min(high - 1) {
                    for ii in i.saturating_sub(1)..=(i + 1).min(wide - 1) {
                        nearest = nearest.min(least[jj * wide + ii]);
                    }
                }
                nearest
            })
            .collect();
        (self.starts, self.members, self.first_cell) = (counts, members, first_cell);
    }

    /// The coarse grid's cell, in `(x / z, y / z)`.
    pub fn coarse_cell(&self) -> f64 {
        self.cell
    }

    /// A range no point whose ray lies within half a coarse cell
    /// ([`BlockIndex::coarse_cell`]) of `(u, v)` is nearer than, mm
    /// (infinite where no such point is): such a point's block is listed
    /// in the cell `(u, v)` falls in or one next to it.
    pub fn least_range_near(&self, u: f64, v: f64) -> f64 {
        self.least_range_round(self.coarse_cell_of(u, v))
    }

    /// The coarse cell `(u, v)` falls in, clipped to the grid, as
    /// [`BlockIndex::least_range_round`] reads it (`None` where the frame
    /// has no point with a ray): [`BlockIndex::least_range_near`] in two
    /// halves, so a run of rays can be placed before any bound is read.
    #[inline]
    pub fn coarse_cell_of(&self, u: f64, v: f64) -> Option<usize> {
        if self.binned == 0 {
            return None;
        }
        let [i, _, j, _] = self.cells_of(&[u, u, v, v]);
        Some(j * self.grid_wide + i)
    }

    /// [`BlockIndex::least_range_near`]'s bound for the cell
    /// [`BlockIndex::coarse_cell_of`] gave.
    #[inline]
    pub fn least_range_round(&self, cell: Option<usize>) -> f64 {
        cell.map_or(f64::INFINITY, |c| self.nearest_round[c])
    }

    /// A range no point whose ray lies in `rect` is nearer than, mm
    /// (infinite where none is): the least of [`least_range_near`]'s
    /// bounds over the coarse cells `rect` meets, as such a point's block
    /// is listed in the cell its ray falls in.
    ///
    /// [`least_range_near`]: BlockIndex::least_range_near
    pub fn least_range_in(&self, rect: &RayRect) -> f64 {
        if self.binned == 0 || !meets(rect, &[self.lo[0], self.hi[0], self.lo[1], self.hi[1]]) {
            return f64::INFINITY;
        }
        let [i0, i1, j0, j1] = self.cells_of(rect);
        let mut least = f64::INFINITY;
        for j in j0..=j1 {
            for range in &self.nearest_round[j * self.grid_wide + i0..=j * self.grid_wide + i1] {
                least = least.min(*range);
            }
        }
        least
    }

    /// The coarse cells `[i0, i1, j0, j1]` a rectangle of rays meets,
    /// clipped to the grid.
    fn cells_of(&self, r: &RayRect) -> [usize; 4] {
        let index = |t: f64, origin: f64, cells: usize| -> usize {
            let k = ((t - origin) / self.cell).floor();
            if k <= 0.0 { 0 } else { (k as usize).min(cells - 1) }
        };
        [
            index(r[0], self.lo[0], self.grid_wide),
            index(r[1], self.lo[0], self.grid_wide),
            index(r[2], self.lo[1], self.grid_high),
            index(r[3], self.lo[1], self.grid_high),
        ]
    }

    /// The least and greatest ray `(x / z, y / z)` over the frame's points
    /// that have one, and how many they are: what
    /// [`super::rays::ray_bounds`] gives for the same points.
    pub fn ray_bounds(&self) -> ([f64; 2], [f64; 2], usize) {
        (self.lo, self.hi, self.binned)
    }

    /// Visits every block whose rays meet `rect` and whose ranges meet
    /// `[near, far]`, once each.
    pub fn blocks_meeting(&self, rect: &RayRect, near: f64, far: f64, mut visit: impl FnMut(usize)) {
        if self.binned == 0 || !meets(rect, &[self.lo[0], self.hi[0], self.lo[1], self.hi[1]]) {
            return;
        }
        let [i0, i1, j0, j1] = self.cells_of(rect);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let c = j * self.grid_wide + i;
                let [nearest, farthest] = self.cell_ranges[c];
                if farthest < near || nearest > far {
                    continue;
                }
                for &b in &self.members[self.starts[c] as usize..self.starts[c + 1] as usize] {
                    let b = b as usize;
                    let [fi, fj] = self.first_cell[b].map(|k| k as usize);
                    // Read in the first cell of the query's it is listed in.
                    if (i, j) != (fi.max(i0), fj.max(j0)) {
                        continue;
                    }
                    let [r0, r1] = self.ranges[b];
                    if meets(&self.rays[b], rect) && r1 >= near && r0 <= far {
                        visit(b);
                    }
                }
            }
        }
    }

    /// The bounds of block `b`'s patches, worked out from their boxes the
    /// first time the block is read.
    fn patches(&self, b: usize) -> &[PatchBounds] {
        self.patch_bounds[b].get_or_init(|| {
            self.patch_boxes[b * PATCHES_PER_BLOCK..(b + 1) * PATCHES_PER_BLOCK]
                .iter()
                .map(|p| PatchBounds { rays: p.rays(), ranges: p.ranges() })
                .collect()
        })
    }

    /// Visits the points of patch `k` of block `b` that have a ray, row
    /// by row.
    fn patch_points(&self, b: usize, k: usize, mut visit: impl FnMut(&[f32; 3])) {
        let (bi, bj) = (b % self.blocks_wide, b / self.blocks_wide);
        let first_column = bi * BLOCK_PX + k % PATCHES_A_SIDE * PATCH_PX;
        let first_row = bj * BLOCK_PX + k / PATCHES_A_SIDE * PATCH_PX;
        // A patch beyond a frame not a whole number of blocks wide holds
        // nothing; the last row of a frame not a whole number of rows is
        // short.
        let end_column = (first_column + PATCH_PX).min(self.width);
        for j in first_row..first_row + PATCH_PX {
            let row = j * self.width;
            if row >= self.points.len() || first_column >= end_column {
                break;
            }
            let from = (row + first_column).min(self.points.len());
            let to = (row + end_column).clamp(from, self.points.len());
            for p in &self.points[from..to] {
                if ray_of(p).is_some() {
                    visit(p);
                }
            }
        }
    }

    /// Visits the points of block `b` that have a ray and lie in a patch
    /// whose rays meet `rect` and whose ranges meet `[near, far]`, patch
    /// by patch: every point of the block with its ray in `rect` and its
    /// range in `[near, far]`, and some others.
    pub fn block_points_meeting(
        &self,
        b: usize,
        rect: &RayRect,
        near: f64,
        far: f64,
        mut visit: impl FnMut(&[f32; 3]),
    ) {
        for (k, patch) in self.patches(b).iter().enumerate() {
            let [r0, r1] = patch.ranges;
            if meets(&patch.rays, rect) && r1 >= near && r0 <= far {
                self.patch_points(b, k, &mut visit);
            }
        }
    }

    /// The rays `[u0, u1, v0, v1]` a point within `radius` of `centre` may
    /// lie on, or `None` when every ray may (a ball reaching the camera's
    /// plane); the bound of [`super::rays`], widened against rounding.
    pub(super) fn window(centre: &Vec3, radius: f64) -> Option<RayRect> {
        let [u, v, hu, hv] = rays_within(centre, radius)?;
        let (hu, hv) = (hu * (1.0 + RAY_SLACK_RELATIVE) + RAY_SLACK, hv * (1.0 + RAY_SLACK_RELATIVE) + RAY_SLACK);
        Some([u - hu, u + hu, v - hv, v + hv])
    }

    /// Visits every point within `radius` of `centre` (strictly inside the
    /// squared distance, as [`super::rays::RayIndex::near`] promises), and
    /// possibly some beyond it; the caller tests each.
    pub fn near(&self, centre: &Vec3, radius: f64, visit: impl FnMut(&[f32; 3])) {
        self.near_where(centre, radius, |_, _| true, visit);
    }

    /// [`BlockIndex::near`], passing over every block and patch whose box
    /// of points (its least and greatest coordinates) `keep` rejects: for
    /// a caller who knows a box holds none of the points it wants
    /// (`keep` must return `true` for any box holding one).
    pub fn near_where(
        &self,
        centre: &Vec3,
        radius: f64,
        keep: impl Fn(&[f32; 3], &[f32; 3]) -> bool,
        mut visit: impl FnMut(&[f32; 3]),
    ) {
        self.aside.iter().for_each(&mut visit);
        let everything = [f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY];
        let rect = Self::window(centre, radius).unwrap_or(everything);
        let distance = centre.norm();
        let (near, far) = (distance - radius - RANGE_SLACK_MM, distance + radius + RANGE_SLACK_MM);
        // A point within the ball lies in its block's box and its patch's,
        // so a box farther from the centre than the radius holds none:
        // the boxes fit the points far closer than the rays and ranges do.
        let reach = radius + BOX_SLACK_MM;
        let reach_squared = reach * reach;
        self.blocks_meeting(&rect, near, far, |b| {
            let block = &self.block_boxes[b];
            if block.distance_squared(centre) > reach_squared || !keep(&block.min, &block.max) {
                return;
            }
            for (k, patch) in self.patch_boxes[b * PATCHES_PER_BLOCK..(b + 1) * PATCHES_PER_BLOCK].iter().enumerate() {
                if patch.distance_squared(centre) <= reach_squared && keep(&patch.min, &patch.max) {
                    self.patch_points(b, k, &mut visit);
                }
            }
        });
    }

    /// The distance from `p` to the nearest indexed point apart from it,
    /// and how many lie exactly on it: what
    /// [`super::rays::RayIndex::nearest_apart`] gives for the same points.
    pub fn nearest_apart(&self, p: &[f32; 3]) -> (Option<f64>, usize) {
        // About two pixels' rays at the point's depth to begin with.
        let per_pixel = self.cell / BLOCK_PX as f64;
        let radius = (2.0 * per_pixel * f64::from(p[2]).abs().max(MIN_BINNED_DEPTH_MM)).max(1e-6);
        nearest_apart_by_balls(p, radius, self.farthest_mm, |centre, radius, visit| self.near(centre, radius, visit))
    }
}

#[cfg(test)]
#[path = "blocks_tests.rs"]
mod tests;
