//! The kernels' plain forms, on any CPU: the reference that every vector
//! form must equal, and the path where none runs.

use super::{BLOCK, LabelledGrid, Planes, generic, within};
use crate::cloud::Point;

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
pub(super) fn labelled_count_at_most(
    grid: &LabelledGrid,
    i: usize,
    window: (usize, usize),
    label: u32,
    radius_sq: f32,
    threshold: f64,
) -> bool {
    generic::labelled_count_at_most(grid, i, window, label, radius_sq, threshold, count_span)
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
