//! The kernels' plain forms, on any CPU: the reference that every vector
//! form must equal, and the path where none runs.

use super::{
    BLOCK, LabelledGrid, LabelledWindow, LaneMasks, NormalTest, Planes, QUAD, QuadBox, TileScales, generic, within,
};
use crate::cloud::Point;

/// Whether the unnormalised normal `n` at point `p`, turned away from the
/// camera, is within the angle whose squared cosine is `cos_sq` of the unit
/// `reference`: `dot >= 0` and `dot² >= cos² |n|²`. Single precision in a
/// fixed order, so the lane forms of [`super::normal_test`] decide the same.
#[inline(always)]
pub fn cross_agrees(n: [f32; 3], p: [f32; 3], reference: [f32; 3], cos_sq: f32) -> bool {
    let towards = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
    let sign = if towards < 0.0 { -1.0f32 } else { 1.0 };
    let dot = sign * (n[0] * reference[0] + n[1] * reference[1] + n[2] * reference[2]);
    let norm_sq = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    norm_sq > 1e-24 && dot >= 0.0 && dot * dot >= cos_sq * norm_sq
}

/// The cross product of central differences `du × dv`, the unnormalised
/// grid normal, term for term as the orientation stage's grid normal test
/// computes it.
#[inline(always)]
pub fn cross(du: [f32; 3], dv: [f32; 3]) -> [f32; 3] {
    [du[1] * dv[2] - du[2] * dv[1], du[2] * dv[0] - du[0] * dv[2], du[0] * dv[1] - du[1] * dv[0]]
}

/// [`super::count_block`] one lane and one neighbour at a time.
pub(super) fn count_block(
    planes: Planes,
    first: usize,
    ranges: impl Iterator<Item = (usize, usize)>,
    radius_sq: f32,
) -> [u32; BLOCK] {
    let mut counts = [0u32; BLOCK];
    for (start, end) in ranges {
        for at in start..end {
            for (l, count) in counts.iter_mut().enumerate() {
                *count += within(&planes.point(first + l), &planes.point(at + l), radius_sq) as u32;
            }
        }
    }
    counts
}

/// The points of a span labelled `label` and within the radius of `p`.
pub(super) fn count_span(p: &Point, points: &[Point], labels: &[u32], label: u32, radius_sq: f32) -> u32 {
    points.iter().zip(labels).map(|(q, &l)| ((l == label) & within(p, q, radius_sq)) as u32).sum()
}

/// [`super::labelled_count_at_most`] counting one point at a time.
pub(super) fn labelled_count_at_most(grid: &LabelledGrid, query: &LabelledWindow) -> bool {
    generic::labelled_count_at_most(grid, query, count_span)
}

/// The least of `v`, by `<`: a NaN never wins; infinity for no value.
#[inline(always)]
fn least(v: &[f32]) -> f32 {
    v.iter().fold(f32::INFINITY, |a, &x| if x < a { x } else { a })
}

/// The greatest of `v`, by `>`: a NaN never wins; minus infinity for no
/// value.
#[inline(always)]
fn greatest(v: &[f32]) -> f32 {
    v.iter().fold(f32::NEG_INFINITY, |a, &x| if x > a { x } else { a })
}

/// [`super::depth_range`] one lane at a time.
pub(super) fn depth_range(z: &[f32; BLOCK]) -> (f32, f32) {
    (least(z), greatest(z))
}

/// The smallest squared norm of a grid normal that [`cross_agrees`] takes
/// for a direction.
pub(super) const MIN_NORM_SQ: f32 = 1e-24;

/// [`super::normal_test`] one lane at a time, by the criterion's own
/// per-point functions: the reference of the lane forms.
pub(super) fn normal_test(planes: Planes, width: usize, first: usize, step: usize, test: &NormalTest) -> LaneMasks {
    let mut masks = LaneMasks::default();
    for l in 0..BLOCK {
        let i = first + l;
        let p = planes.point(i);
        let (left, right) = (planes.point(i - step), planes.point(i + step));
        let (up, down) = (planes.point(i - step * width), planes.point(i + step * width));
        let du = [right[0] - left[0], right[1] - left[1], right[2] - left[2]];
        let dv = [down[0] - up[0], down[1] - up[1], down[2] - up[2]];
        let complete = (du[0] + du[1] + du[2] + dv[0] + dv[1] + dv[2] + p[0]).is_finite();
        masks.complete |= (complete as u32) << l;
        masks.facing |= (cross_agrees(cross(du, dv), p, test.reference, test.cos_sq) as u32) << l;
    }
    masks
}

/// Adding this to a float below 2²² in magnitude leaves its nearest
/// integer in the low mantissa bits.
pub(super) const FLOOR_SHIFT: f32 = 12_582_912.0;

/// The magnitude [`floor_i32`] clamps to: far beyond any tile or depth
/// index a camera's view gives.
pub(super) const FLOOR_LIMIT: f32 = 4.0e6;

/// `x.floor()` as an integer, for the tile and depth indices of the memo
/// keys. Values are clamped to ±[`FLOOR_LIMIT`] (NaN to the low end). No
/// float-to-int conversion: the baseline x86-64 has no single-instruction
/// floor, and Rust's saturating casts do not vectorise, while adding
/// [`FLOOR_SHIFT`] (1.5 · 2²³) leaves `round(x)` in the low mantissa bits.
#[inline(always)]
pub(super) fn floor_i32(x: f32) -> i32 {
    // Not `clamp`, which keeps NaN: `max` maps it to the low end.
    #[allow(clippy::manual_clamp)]
    let x = x.max(-FLOOR_LIMIT).min(FLOOR_LIMIT);
    let rounded = (x + FLOOR_SHIFT).to_bits() as i32 - FLOOR_SHIFT.to_bits() as i32;
    rounded - ((rounded as f32) > x) as i32
}

/// A memo key from its tile row and column (16 bits each) and depth step.
#[inline(always)]
fn key_of(tile_row: i32, tile_col: i32, depth_step: i32) -> u64 {
    ((tile_row as i16 as u16 as u64) << 48) | ((tile_col as i16 as u16 as u64) << 32) | (depth_step as u32 as u64)
}

/// [`super::tile_key`]: single precision and no rounding calls, so the
/// lane forms can do the same operations.
#[inline(always)]
pub(super) fn tile_key(p: &Point, scales: &TileScales) -> u64 {
    let z = p[2];
    let tile_row = floor_i32(p[1] / z * scales.tiles_per_y);
    let tile_col = floor_i32(p[0] / z * scales.tiles_per_x);
    // Depths are positive, so rounding is the floor of z / step + ½.
    let depth_step = floor_i32(z * scales.steps_per_mm + 0.5);
    key_of(tile_row, tile_col, depth_step)
}

/// [`super::tile_keys`] one lane at a time.
pub(super) fn tile_keys([xs, ys, zs]: &[[f32; BLOCK]; 3], scales: &TileScales) -> [u64; BLOCK] {
    std::array::from_fn(|l| tile_key(&[xs[l], ys[l], zs[l]], scales))
}

/// The corner of a row's members while it is gathered.
#[derive(Debug, Clone, Copy)]
pub(super) struct Corner {
    pub z_min: f32,
    pub x_max: f32,
    pub y_max: f32,
    pub any: bool,
}

impl Default for Corner {
    fn default() -> Self {
        Corner { z_min: f32::INFINITY, x_max: 0.0, y_max: 0.0, any: false }
    }
}

impl Corner {
    /// Plain comparisons skip NaN as `f32::min` does, without its
    /// NaN-handling sequence.
    pub(super) fn add(&mut self, p: &Point) {
        self.z_min = if p[2] < self.z_min { p[2] } else { self.z_min };
        self.x_max = if p[0].abs() > self.x_max { p[0].abs() } else { self.x_max };
        self.y_max = if p[1].abs() > self.y_max { p[1].abs() } else { self.y_max };
        self.any = true;
    }
}

/// One row's lower bounds of the edge criterion's same-plate counts:
/// what they read and the window they use. `prefix` holds the prefix sums
/// along the row of the window's member codes, one bit field of
/// `32 / N` bits per plate.
pub(crate) struct RowBounds<'a, const N: usize> {
    pub plate_labels: [u32; N],
    pub prefix: &'a [u32],
    pub labels: &'a [u32],
    pub counts: &'a [u16],
    /// Half the window's width.
    pub wx: usize,
    /// The rows the column sums hold.
    pub window_rows: usize,
}

impl<const N: usize> RowBounds<'_, N> {
    pub(crate) const FIELD_BITS: u32 = 32 / N as u32;
    /// The most pixels a window may hold for its sum to be read field by field.
    const MAX_WINDOW: u64 = (1u64 << Self::FIELD_BITS) - 1;

    pub(crate) fn plate_of(&self, label: u32) -> Option<usize> {
        self.plate_labels.iter().position(|&l| l == label)
    }

    /// The lower bound of the same-plate neighbours of the member of plate
    /// `k` at column `c`; `None` when the window holds too many pixels to
    /// tell.
    pub(crate) fn lower_bound(&self, c: usize, k: usize) -> Option<i64> {
        let w = self.labels.len();
        let (c0, c1) = (c.saturating_sub(self.wx), (c + self.wx + 1).min(w));
        let area = (c1 - c0) as u64 * self.window_rows as u64;
        if area > Self::MAX_WINDOW {
            return None;
        }
        let fields = self.prefix[c1].wrapping_sub(self.prefix[c0]);
        let members = (fields >> (k as u32 * Self::FIELD_BITS)) as u64 & Self::MAX_WINDOW;
        // At most the window's non-members are not of this plate.
        Some(self.counts[c] as i64 - (area as i64 - members as i64))
    }

    /// Appends to `open` the members in `cols` whose bound does not exceed
    /// `threshold(c)`, the criterion's `ratio · N` at column `c`.
    pub(crate) fn open_members(
        &self,
        cols: std::ops::Range<usize>,
        threshold: impl Fn(usize) -> f64 + Copy,
        open: &mut Vec<(u32, u8)>,
    ) {
        for c in cols {
            let Some(k) = self.plate_of(self.labels[c]) else { continue };
            if self.lower_bound(c, k).is_none_or(|b| b as f64 <= threshold(c)) {
                open.push((c as u32, k as u8));
            }
        }
    }
}

/// [`super::quad_boxes`] one point at a time, from column `first` of each
/// row: `out[q]` is the quad `q` quads on from it.
pub(super) fn quad_boxes(rows: &[&[Point]], first: usize, min_depth: f32, out: &mut [QuadBox]) {
    for (q, quad) in out.iter_mut().enumerate() {
        let mut b = QuadBox::EMPTY;
        let from = first + q * QUAD;
        for row in rows {
            for p in &row[from..(from + QUAD).min(row.len())] {
                // A comparison with a NaN is false: an empty pixel is not
                // finite.
                let is_finite = p.iter().all(|c| c.abs() < f32::INFINITY);
                let has_ray = is_finite && p[2] > min_depth;
                if has_ray {
                    for ((c, low), high) in p.iter().zip(&mut b.min).zip(&mut b.max) {
                        *low = if *c < *low { *c } else { *low };
                        *high = if *c > *high { *c } else { *high };
                    }
                }
                b.binned += u32::from(has_ray);
                b.finite += u32::from(is_finite);
            }
        }
        *quad = b;
    }
}
