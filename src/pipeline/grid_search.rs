//! The fast path of the radius counts on a pixel grid: coordinates stored
//! as separate x, y, z planes, and eight horizontally adjacent pixels
//! counted together, one per SIMD lane. For a given window offset the
//! eight neighbours are eight consecutive pixels, so every step is a
//! contiguous load and the loop vectorises without gathers.
//!
//! The counts use the same predicate as [`super::neighbours`], term for
//! term in the same order (no fused multiply-add), so a pixel counted here
//! is counted there: a count over part of the window is a lower bound of
//! the exact count, never more. The one exception, [`Grid::count_runs`],
//! fuses the squared distance and lowers the radius by enough that it
//! too counts no pixel the predicate leaves out.

use crate::cloud::PointCloud;
use crate::kernels::{self, Planes};

/// Pixels counted together.
pub(crate) const LANES: usize = kernels::BLOCK;

/// One row of window offsets: `dv` and the inclusive `du` range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Span {
    pub dv: isize,
    pub du_lo: isize,
    pub du_hi: isize,
}

/// The bounding box of a set of spans' offsets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SpanExtent {
    pub dv_min: isize,
    pub dv_max: isize,
    pub du_min: isize,
    pub du_max: isize,
}

impl SpanExtent {
    /// `None` for no spans.
    pub(crate) fn of(spans: &[Span]) -> Option<SpanExtent> {
        let first = spans.first()?;
        let start = SpanExtent { dv_min: first.dv, dv_max: first.dv, du_min: first.du_lo, du_max: first.du_hi };
        Some(spans.iter().fold(start, |e, s| SpanExtent {
            dv_min: e.dv_min.min(s.dv),
            dv_max: e.dv_max.max(s.dv),
            du_min: e.du_min.min(s.du_lo),
            du_max: e.du_max.max(s.du_hi),
        }))
    }
}

/// Spans prepared for counting many blocks of one grid: each span as the
/// index distance from a block's first pixel to the span's first pixel
/// and its length, so a block checks the spans' extent once instead of
/// every span's slices.
#[derive(Debug, Default)]
pub(crate) struct SpanRuns {
    spans: Vec<Span>,
    runs: Vec<(isize, usize)>,
    extent: Option<SpanExtent>,
    width: usize,
}

impl SpanRuns {
    /// Makes the runs of the spans `fill` writes (into an emptied buffer)
    /// on a grid `width` pixels wide.
    pub(crate) fn prepare(&mut self, width: usize, fill: impl FnOnce(&mut Vec<Span>)) {
        self.spans.clear();
        fill(&mut self.spans);
        let row = width as isize;
        let runs = self.spans.iter().map(|s| (s.dv * row + s.du_lo, (s.du_hi - s.du_lo + 1).max(0) as usize));
        self.runs.clear();
        self.runs.extend(runs);
        self.extent = SpanExtent::of(&self.spans);
        self.width = width;
    }
}

/// An organized cloud's coordinates as three planes.
pub(crate) struct Grid {
    width: usize,
    height: usize,
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
}

impl Grid {
    /// Splits an organized cloud into coordinate planes.
    pub(crate) fn new(cloud: &PointCloud) -> Grid {
        use rayon::prelude::*;
        let points = cloud.points();
        let plane = |axis: usize| -> Vec<f32> { points.par_iter().map(|p| p[axis]).collect() };
        Grid { width: cloud.width(), height: cloud.height(), xs: plane(0), ys: plane(1), zs: plane(2) }
    }

    /// The coordinates of the `LANES` pixels starting at index `at`, as
    /// three lane arrays.
    #[inline(always)]
    pub(crate) fn lanes(&self, at: usize) -> [[f32; LANES]; 3] {
        let take = |v: &[f32]| -> [f32; LANES] {
            let mut out = [0.0; LANES];
            out.copy_from_slice(&v[at..at + LANES]);
            out
        };
        [take(&self.xs), take(&self.ys), take(&self.zs)]
    }

    /// Point `i`, row-major, from the planes.
    #[inline(always)]
    pub(crate) fn point(&self, i: usize) -> [f32; 3] {
        [self.xs[i], self.ys[i], self.zs[i]]
    }

    pub(crate) fn width(&self) -> usize {
        self.width
    }

    pub(crate) fn height(&self) -> usize {
        self.height
    }

    /// True when every offset of `spans` stays inside the image for all
    /// lanes of the block whose first pixel is `(col, row)`.
    pub(crate) fn spans_fit(&self, col: usize, row: usize, spans: &[Span]) -> bool {
        SpanExtent::of(spans).is_some_and(|e| self.extent_fits(col, row, &e))
    }

    /// [`Grid::spans_fit`] for spans whose extent is known.
    #[inline]
    pub(crate) fn extent_fits(&self, col: usize, row: usize, e: &SpanExtent) -> bool {
        let (col, row) = (col as isize, row as isize);
        row + e.dv_min >= 0
            && row + e.dv_max < self.height as isize
            && col + e.du_min >= 0
            && col + e.du_max + (LANES as isize - 1) < self.width as isize
    }

    /// The exact count of pixel `i`: the valid pixels within `radius_sq`
    /// over its window of half-size `(wx, wy)`, clipped to the image, by
    /// the KD-tree path's predicate. For lanes whose window leaves the
    /// image sideways, which the block counts cannot take.
    pub(crate) fn count_window(&self, i: usize, (wx, wy): (usize, usize), radius_sq: f32) -> u32 {
        let (w, h) = (self.width, self.height);
        let (col, row) = (i % w, i / w);
        let (c0, c1) = (col.saturating_sub(wx), col.saturating_add(wx).min(w - 1));
        let (r0, r1) = (row.saturating_sub(wy), row.saturating_add(wy).min(h - 1));
        let p = self.point(i);
        let mut count = 0;
        for r in r0..=r1 {
            let line = r * w + c0..=r * w + c1;
            let (xs, ys, zs) = (&self.xs[line.clone()], &self.ys[line.clone()], &self.zs[line]);
            for ((&x, &y), &z) in xs.iter().zip(ys).zip(zs) {
                count += kernels::within(&p, &[x, y, z], radius_sq) as u32;
            }
        }
        count
    }

    /// The coordinate planes, as the kernels read them.
    #[inline(always)]
    pub(crate) fn planes(&self) -> Planes<'_> {
        Planes { xs: &self.xs, ys: &self.ys, zs: &self.zs }
    }

    /// For the `LANES` pixels starting at `(col, row)`, counts the valid
    /// pixels at the offsets `spans` within `radius_sq` of each. The caller
    /// checks [`Grid::spans_fit`] first.
    pub(crate) fn count_block(&self, col: usize, row: usize, spans: &[Span], radius_sq: f32) -> [u32; LANES] {
        kernels::count_block(self.planes(), row * self.width + col, self.span_ranges(col, row, spans), radius_sq)
    }

    /// A lower bound of [`Grid::count_block`] over prepared runs; `None`
    /// when they leave the image for some lane of the block (or were made
    /// for another width), which the caller then counts another way.
    ///
    /// Where the CPU fuses multiply and add, the squared distance takes
    /// two fused steps instead of two multiplies and two adds: it rounds
    /// differently, so the radius is lowered by a relative 2⁻¹⁹ to keep
    /// every counted point within the radius by the exact predicate (both
    /// forms lie within 3 · 2⁻²⁴ of the true sum of squares of the same
    /// differences, so a fused value under `r² (1 - 2⁻¹⁹)` puts the exact
    /// one under `r²`). Only points within a millionth of the radius of
    /// the rim can be left out, and the count stays a lower bound.
    pub(crate) fn count_runs(&self, col: usize, row: usize, runs: &SpanRuns, radius_sq: f32) -> Option<[u32; LANES]> {
        let extent = runs.extent?;
        if runs.width != self.width || !self.extent_fits(col, row, &extent) {
            return None;
        }
        // Rounding the f64 product to f32 adds at most 2⁻²⁴, which the
        // 2⁻¹⁹ leaves room for.
        let inner = (radius_sq as f64 * (1.0 - 2f64.powi(-19))) as f32;
        // SAFETY: the runs' extent fits the image at this block, checked
        // just above: every span's row is inside the image, and its
        // columns from `du_lo` to `du_hi + LANES - 1` inside that row.
        let fused = unsafe { kernels::count_runs_fused(self.planes(), row * self.width + col, &runs.runs, inner) };
        Some(fused.unwrap_or_else(|| self.count_block(col, row, &runs.spans, radius_sq)))
    }

    /// The offsets of `spans` as index ranges of the first lane's
    /// neighbour, for the block starting at `(col, row)`.
    fn span_ranges<'s>(
        &self,
        col: usize,
        row: usize,
        spans: &'s [Span],
    ) -> impl Iterator<Item = (usize, usize)> + Clone + 's {
        let width = self.width;
        spans.iter().map(move |s| {
            let base = ((row as isize + s.dv) as usize * width + col) as isize;
            ((base + s.du_lo) as usize, (base + s.du_hi) as usize + 1)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::pipeline::neighbours::NeighbourSearch;

    /// A 48 x 32 patch of a wobbly plane at 520 mm with scattered dropouts.
    fn patch(camera: &CameraModel) -> PointCloud {
        let (w, h) = (48usize, 32usize);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(900.0 + col as f64, 580.0 + row as f64);
                let wobble = ((row * 7 + col * 13) % 5) as f64 * 0.05;
                let z = 520.0 + col as f64 * 0.05 + wobble;
                let invalid = (row * 31 + col * 17) % 23 == 0;
                pts.push(if invalid { [f32::NAN; 3] } else { [(r[0] * z) as f32, (r[1] * z) as f32, z as f32] });
            }
        }
        PointCloud::organized(w, h, pts).unwrap()
    }

    #[test]
    fn window_counts_equal_the_reference_up_to_the_borders() {
        let camera = CameraModel::default();
        let cloud = patch(&camera);
        let grid = Grid::new(&cloud);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        for (i, p) in cloud.points().iter().enumerate().filter(|(_, p)| p[0].is_finite()) {
            let window = camera.neighbour_window(*p, 1.0);
            assert_eq!(grid.count_window(i, window, 1.0), search.count(i, |_| true), "pixel {i}");
        }
    }

    #[test]
    fn block_counts_equal_the_reference_over_the_same_offsets() {
        let camera = CameraModel::default();
        let cloud = patch(&camera);
        let w = cloud.width();
        let grid = Grid::new(&cloud);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let (wx, wy) = (8isize, 8isize);
        let full: Vec<Span> = (-wy..=wy).map(|dv| Span { dv, du_lo: -wx, du_hi: wx }).collect();
        let (col, row) = (12, 14);
        assert!(grid.spans_fit(col, row, &full));
        let counts = kernels::with_isa(kernels::Isa::Scalar, || grid.count_block(col, row, &full, 1.0)).unwrap();
        let (ran, _skipped) = kernels::on_every_isa(|_| grid.count_block(col, row, &full, 1.0));
        for (isa, got) in ran {
            assert_eq!(got, counts, "{isa:?} and the scalar form agree");
        }
        for (l, &got) in counts.iter().enumerate() {
            let i = row * w + col + l;
            if cloud.points()[i][0].is_finite() {
                assert_eq!(got, search.count(i, |_| true), "lane {l}");
            }
        }
    }

    #[test]
    fn run_counts_never_count_a_point_the_exact_predicate_leaves_out() {
        // Neighbours strewn across the rim of the ball, within a few
        // millionths of the radius, where fused and separate rounding can
        // disagree: the run counts must stay at or under the exact ones.
        let (w, h) = (40usize, 9usize);
        let mut seed = 0x9e37_79b9_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let centre = [3.0f64, -2.0, 500.0];
        let mut pts = vec![[0.0f32; 3]; w * h];
        for (i, p) in pts.iter_mut().enumerate() {
            let (theta, phi) = (next() * std::f64::consts::TAU, next() * std::f64::consts::PI);
            let r = 1.0 + (next() - 0.5) * 8e-6;
            let d = [phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos()];
            // The block's own lanes sit at the centre, the rest on the rim.
            let on_rim = !(i / w == 4 && (16..16 + LANES).contains(&(i % w)));
            let r = if on_rim { r } else { 0.0 };
            *p = std::array::from_fn(|k| (centre[k] + r * d[k]) as f32);
        }
        let cloud = PointCloud::organized(w, h, pts).unwrap();
        let grid = Grid::new(&cloud);
        let spans: Vec<Span> = (-4..=4).map(|dv| Span { dv, du_lo: -16, du_hi: 16 }).collect();
        let mut runs = SpanRuns::default();
        runs.prepare(w, |out| out.extend_from_slice(&spans));
        let (mut fewer, mut total) = (0, 0);
        // Every squared radius within 600 steps of 1: each neighbour's
        // squared distance falls right at some of them.
        for step in -600i32..=600 {
            let radius_sq = f32::from_bits(1.0f32.to_bits().wrapping_add_signed(step));
            let exact = grid.count_block(16, 4, &spans, radius_sq);
            let bound = grid.count_runs(16, 4, &runs, radius_sq).expect("the spans fit");
            for l in 0..LANES {
                assert!(bound[l] <= exact[l], "lane {l}, r² {radius_sq}: {} > {}", bound[l], exact[l]);
                fewer += exact[l] - bound[l];
                total += exact[l];
            }
        }
        assert!(total > 100_000, "the rim holds neighbours: {total}");
        // A millionth of the radius around the rim holds few of them.
        assert!(fewer * 10 < total, "{fewer} of {total} left out");
    }

    #[test]
    fn spans_that_leave_the_image_do_not_fit() {
        let cloud = PointCloud::organized(20, 10, vec![[0.0, 0.0, 500.0]; 200]).unwrap();
        let grid = Grid::new(&cloud);
        let spans = [Span { dv: -1, du_lo: -2, du_hi: 2 }];
        assert!(grid.spans_fit(2, 1, &spans));
        assert!(!grid.spans_fit(1, 1, &spans));
        assert!(!grid.spans_fit(2, 0, &spans));
        assert!(!grid.spans_fit(11, 1, &spans), "the last lane would read past the row");
    }
}
