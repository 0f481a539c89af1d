//! The plane edge criterion (section 3.4.1, Eq. 15): points of a plate
//! whose neighbourhood is cut by the plate's boundary.
//!
//! The paper calls a point an edge point when its count of same-plane
//! neighbours is at most `μ N` with `μ = 0.5` and `N` the frontal count of
//! Eq. 6. A point exactly on a straight edge sees 0.5 to 0.6 of its disc,
//! and the plane criterion has already removed the outermost points, so
//! `0.5` keeps only ragged points. The robust criterion measures against
//! the full-plane count at the pixel (tilt and grid included) with a
//! threshold that a straight edge clears.

use rayon::prelude::*;

use crate::cloud::Point;
use crate::kernels::{self, Isa};

use super::neighbours::NeighbourSearch;
use super::plane_points::PlanePoints;

/// How the full count `N` of Eq. 15 is obtained.
#[derive(Debug, Clone, Copy)]
pub(crate) enum FullCount {
    /// Eq. 6 at the point's depth: the paper.
    Frontal,
    /// The full-plane lattice count the plane criterion measured the point
    /// against ([`PlanePoints::full`]).
    Plane,
}

impl FullCount {
    /// `N` for point `i`.
    fn of(self, search: &NeighbourSearch, plane: &PlanePoints, i: usize) -> f64 {
        match self {
            FullCount::Frontal => {
                search.camera().theoretical_neighbours(search.radius_mm(), search.cloud().points()[i][2] as f64)
            }
            FullCount::Plane => plane.full[i] as f64,
        }
    }
}

/// The edge criterion's settings.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeCriterion {
    pub full: FullCount,
    /// A point is an edge point when `N_r <= ratio · N`.
    pub ratio: f64,
}

/// One plate: the cloud's plate labels, this plate's label and members.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plate<'a> {
    pub labels: &'a [u32],
    pub label: u32,
    /// Indices into the cloud, all with `labels[i] == label`.
    pub members: &'a [u32],
}

/// Returns the members of `plate` that are edge points (Eq. 15). On a
/// pixel grid the members are the pixels labelled as the plate, in index
/// order.
///
/// On a pixel grid most members are settled without counting: the plane
/// criterion's count is a lower bound of a point's neighbours, and at most
/// the window's non-members are not of its plate, so when that bound
/// exceeds `ratio · N` the point is no edge. Only the rest are counted,
/// exactly.
pub(crate) fn edge_points(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    plate: Plate,
    criterion: &EdgeCriterion,
) -> Vec<u32> {
    if !search.cloud().is_organized() {
        return plate
            .members
            .par_iter()
            .copied()
            .filter(|&i| counted_edge_up_to_threshold(search, plane, plate, criterion, i))
            .collect();
    }
    let [edges] = on_grid(search, plane, plate.labels, [plate.label], criterion);
    edges
}

/// [`edge_points`] of two plates, in one pass over the frame when they
/// share their labels (each pixel then belongs to at most one of them).
pub(crate) fn edge_points_of_plates(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    plates: [Plate; 2],
    criterion: &EdgeCriterion,
) -> [Vec<u32>; 2] {
    let [a, b] = plates;
    if !search.cloud().is_organized() || !std::ptr::eq(a.labels, b.labels) || a.label == b.label {
        return plates.map(|p| edge_points(search, plane, p, criterion));
    }
    on_grid(search, plane, a.labels, [a.label, b.label], criterion)
}

/// The straightforward form: every member counted. Kept as the reference.
#[cfg(test)]
pub(crate) fn reference(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    plate: Plate,
    criterion: &EdgeCriterion,
) -> Vec<u32> {
    plate.members.iter().copied().filter(|&i| counted_edge(search, plane, plate, criterion, i)).collect()
}

/// Eq. 15 for member `i` of `plate`, by counting its same-plate neighbours.
#[cfg(test)]
fn counted_edge(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    plate: Plate,
    criterion: &EdgeCriterion,
    i: u32,
) -> bool {
    let i = i as usize;
    let n = criterion.full.of(search, plane, i);
    search.count(i, |j| plate.labels[j] == plate.label) as f64 <= criterion.ratio * n
}

/// [`counted_edge`], counting only until the count passes `ratio · N`:
/// the same answer, and no more neighbours than that however dense the
/// cloud.
fn counted_edge_up_to_threshold(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    plate: Plate,
    criterion: &EdgeCriterion,
    i: u32,
) -> bool {
    let i = i as usize;
    let limit = criterion.ratio * criterion.full.of(search, plane, i);
    if limit.is_nan() || limit < 0.0 {
        return false;
    }
    if limit >= u32::MAX as f64 {
        // No cloud holds that many points: every count is at most it.
        return true;
    }
    // A whole count is at most `limit` exactly when it is below
    // floor(limit) + 1; the first count to reach that decides "no edge".
    let cap = (limit.floor() + 1.0).min(u32::MAX as f64) as u32;
    search.count_up_to(i, |j| plate.labels[j] == plate.label, cap) < cap
}

/// Rows handed to a rayon job at a time: enough to amortise the first
/// row's window sums, few enough that the rows along an edge, where the
/// exact counts are, spread over the threads.
const BAND_ROWS: usize = 32;

/// The grid path for `N` (1 or 2) plates: the members of plate `k` are
/// the pixels labelled `plate_labels[k]`, taken row by row, so in index
/// order.
fn on_grid<const N: usize>(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    labels: &[u32],
    plate_labels: [u32; N],
    criterion: &EdgeCriterion,
) -> [Vec<u32>; N] {
    let cloud = search.cloud();
    let (w, h) = (cloud.width(), cloud.height());
    let grid = GridCount::new(search, labels);
    let bands: Vec<[Vec<u32>; N]> = (0..h.div_ceil(BAND_ROWS))
        .into_par_iter()
        .map_init(
            || Band::<N>::new(w, plate_labels),
            |band, b| {
                let mut edges: [Vec<u32>; N] = std::array::from_fn(|_| Vec::new());
                for row in b * BAND_ROWS..((b + 1) * BAND_ROWS).min(h) {
                    band.row(&grid, plane, criterion, row, &mut edges);
                }
                band.count_pending(&grid, plane, criterion, usize::MAX, &mut edges);
                edges
            },
        )
        .collect();
    std::array::from_fn(|k| bands.iter().flat_map(|edges| edges[k].iter().copied()).collect())
}

/// A job's scratch: the member codes of the current window rows summed
/// per column, their prefix sums along the row, and the row's members
/// still to be counted.
///
/// A pixel's code holds a one in the 32 / N bit field of its plate. The
/// sums wrap, which keeps every difference of them right modulo 2^32: a
/// window's sum has each plate's member count in its field as long as the
/// window holds fewer pixels than a field can count.
struct Band<const N: usize> {
    plate_labels: [u32; N],
    /// The window rows `rows` summed, per column.
    columns: Vec<u32>,
    rows: std::ops::Range<usize>,
    /// `prefix[c]`: the sum of `columns[..c]`.
    prefix: Vec<u32>,
    /// The row's members the bound leaves open: column and plate.
    open: Vec<(u32, u8)>,
    /// Open members waiting for their exact count: the row by which their
    /// window has been read, index and plate.
    pending: std::collections::VecDeque<(usize, u32, u8)>,
}

/// One row's lower bounds: what they read and the window they use.
struct RowBounds<'a, const N: usize> {
    plate_labels: [u32; N],
    prefix: &'a [u32],
    labels: &'a [u32],
    counts: &'a [u16],
    /// Half the window's width.
    wx: usize,
    /// The rows the column sums hold.
    window_rows: usize,
}

impl<const N: usize> RowBounds<'_, N> {
    const FIELD_BITS: u32 = 32 / N as u32;
    /// The most pixels a window may hold for its sum to be read field by field.
    const MAX_WINDOW: u64 = (1u64 << Self::FIELD_BITS) - 1;

    fn plate_of(&self, label: u32) -> Option<usize> {
        self.plate_labels.iter().position(|&l| l == label)
    }

    /// The lower bound of the same-plate neighbours of the member of plate
    /// `k` at column `c`; `None` when the window holds too many pixels to
    /// tell.
    fn lower_bound(&self, c: usize, k: usize) -> Option<i64> {
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
    fn open_members(
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

impl<const N: usize> Band<N> {
    fn new(width: usize, plate_labels: [u32; N]) -> Self {
        Band {
            plate_labels,
            columns: vec![0; width],
            rows: 0..0,
            prefix: vec![0; width + 1],
            open: Vec::with_capacity(width),
            pending: std::collections::VecDeque::new(),
        }
    }

    /// Adds the codes of row `add` to the column sums and removes those
    /// of row `remove`, either being optional: one pass for the common
    /// step of the window one row down.
    fn add_and_remove(&mut self, labels: &[u32], add: Option<usize>, remove: Option<usize>) {
        let w = self.columns.len();
        let line = |row: Option<usize>| row.map(|r| &labels[r * w..(r + 1) * w]);
        let plate_labels = self.plate_labels;
        let code = |label: u32| -> u32 {
            let mut code = 0;
            for (k, &l) in plate_labels.iter().enumerate() {
                code |= ((label == l) as u32) << (k as u32 * RowBounds::<N>::FIELD_BITS);
            }
            code
        };
        match (line(add), line(remove)) {
            (Some(add), Some(remove)) => {
                for ((sum, &a), &r) in self.columns.iter_mut().zip(add).zip(remove) {
                    *sum = sum.wrapping_add(code(a)).wrapping_sub(code(r));
                }
            }
            (Some(add), None) => {
                self.columns.iter_mut().zip(add).for_each(|(sum, &a)| *sum = sum.wrapping_add(code(a)))
            }
            (None, Some(remove)) => {
                self.columns.iter_mut().zip(remove).for_each(|(sum, &r)| *sum = sum.wrapping_sub(code(r)))
            }
            (None, None) => {}
        }
    }

    /// Makes the column sums those of `target`, by adding and removing
    /// rows at the ends, or afresh when that is fewer rows.
    fn move_to(&mut self, labels: &[u32], target: std::ops::Range<usize>) {
        let shift = self.rows.start.abs_diff(target.start) + self.rows.end.abs_diff(target.end);
        if shift > target.len() {
            self.columns.fill(0);
            self.rows = target.start..target.start;
        }
        while self.rows != target {
            // Each step grows or shrinks the window at each end by a row.
            let add_end = (self.rows.end < target.end).then_some(self.rows.end);
            let remove_end = (self.rows.end > target.end).then(|| self.rows.end - 1);
            let remove_start = (self.rows.start < target.start).then_some(self.rows.start);
            let add_start = (self.rows.start > target.start).then(|| self.rows.start - 1);
            self.add_and_remove(labels, add_end.or(add_start), remove_start.or(remove_end));
            // A row added at one end and one removed at the other: the
            // other two moves wait for the next step.
            match (add_end, add_start) {
                (Some(_), _) => self.rows.end += 1,
                (None, Some(_)) => self.rows.start -= 1,
                _ => {}
            }
            match (remove_start, remove_end) {
                (Some(_), _) => self.rows.start += 1,
                (None, Some(_)) => self.rows.end -= 1,
                _ => {}
            }
        }
    }

    /// Appends the edge points of `row` to `edges`.
    fn row(
        &mut self,
        grid: &GridCount,
        plane: &PlanePoints,
        criterion: &EdgeCriterion,
        row: usize,
        edges: &mut [Vec<u32>; N],
    ) {
        let (w, h) = (grid.width, grid.height);
        let first = row * w;
        let line = &grid.labels[first..first + w];
        let Some(corner) = members_corner(line, &grid.points[first..first + w], self.plate_labels) else {
            return;
        };
        let (wx, wy) = grid.row_window(corner);
        self.move_to(grid.labels, row.saturating_sub(wy)..(row + wy + 1).min(h));
        let mut sum = 0u32;
        for (prefix, &column) in self.prefix[1..].iter_mut().zip(&self.columns) {
            sum = sum.wrapping_add(column);
            *prefix = sum;
        }
        let bounds = RowBounds {
            plate_labels: self.plate_labels,
            prefix: &self.prefix,
            labels: line,
            counts: &plane.counts[first..first + w],
            wx,
            window_rows: self.rows.len(),
        };
        let threshold = |c: usize| criterion.ratio * criterion.full.of(grid.search, plane, first + c);
        // Columns whose window lies inside the row go four at a time, the
        // rest one by one, in column order.
        let mut quads = wx..wx;
        let quad_area = (2 * wx + 1) as u64 * self.rows.len() as u64;
        if cfg!(target_arch = "x86_64") && matches!(criterion.full, FullCount::Plane) && quad_area <= u16::MAX as u64 {
            quads.end = quads.start + w.saturating_sub(2 * wx) / 4 * 4;
        }
        let open = &mut self.open;
        open.clear();
        bounds.open_members(0..quads.start, threshold, open);
        #[cfg(target_arch = "x86_64")]
        if !quads.is_empty() {
            let full = &plane.full[first..first + w];
            // SAFETY: SSE2 is part of the x86_64 baseline.
            unsafe { sse2::open_members(&bounds, quads.clone(), quad_area as u32, full, criterion.ratio, open) };
        }
        bounds.open_members(quads.end..w, threshold, open);
        // Counted once the rows below have been read for their corners,
        // which brings the window's points into the cache.
        let ready = row + wy;
        self.pending.extend(open.iter().map(|&(c, k)| (ready, (first + c as usize) as u32, k)));
        self.count_pending(grid, plane, criterion, row, edges);
    }

    /// Counts the pending members whose window rows have been read by
    /// row `read` (all at the band's end), in the order they were found.
    fn count_pending(
        &mut self,
        grid: &GridCount,
        plane: &PlanePoints,
        criterion: &EdgeCriterion,
        read: usize,
        edges: &mut [Vec<u32>; N],
    ) {
        while let Some(&(ready, i, k)) = self.pending.front() {
            if ready > read {
                break;
            }
            self.pending.pop_front();
            let (i, k) = (i as usize, k as usize);
            let threshold = criterion.ratio * criterion.full.of(grid.search, plane, i);
            if grid.is_edge(i, self.plate_labels[k], threshold) {
                edges[k].push(i as u32);
            }
        }
    }
}

/// The corner of a row's members: their least depth and largest `|x|` and
/// `|y|`, NaN skipped; `None` when the row has no member. Its window holds
/// every member's own ([`GridCount::row_window`]).
fn members_corner<const N: usize>(labels: &[u32], points: &[Point], plate_labels: [u32; N]) -> Option<Point> {
    let n = labels.len().min(points.len());
    #[cfg(target_arch = "x86_64")]
    let (mut corner, done) = {
        let done = n / 4 * 4;
        // SAFETY: SSE2 is part of the x86_64 baseline.
        (unsafe { sse2::members_corner(&labels[..done], &points[..done], plate_labels) }, done)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (mut corner, done) = (Corner::default(), 0);
    for (&label, p) in labels[done..n].iter().zip(&points[done..n]) {
        if plate_labels.contains(&label) {
            corner.add(p);
        }
    }
    corner.any.then_some([corner.x_max, corner.y_max, corner.z_min])
}

#[derive(Debug, Clone, Copy)]
struct Corner {
    z_min: f32,
    x_max: f32,
    y_max: f32,
    any: bool,
}

impl Default for Corner {
    fn default() -> Self {
        Corner { z_min: f32::INFINITY, x_max: 0.0, y_max: 0.0, any: false }
    }
}

impl Corner {
    /// Plain comparisons skip NaN as `f32::min` does, without its
    /// NaN-handling sequence.
    fn add(&mut self, p: &Point) {
        self.z_min = if p[2] < self.z_min { p[2] } else { self.z_min };
        self.x_max = if p[0].abs() > self.x_max { p[0].abs() } else { self.x_max };
        self.y_max = if p[1].abs() > self.y_max { p[1].abs() } else { self.y_max };
        self.any = true;
    }
}

/// What the exact counts read: the frame and its labels.
struct GridCount<'a> {
    search: &'a NeighbourSearch<'a>,
    points: &'a [Point],
    labels: &'a [u32],
    width: usize,
    height: usize,
    radius_sq: f32,
    /// The instruction set the counts run on, taken once per pass.
    isa: Isa,
}

impl<'a> GridCount<'a> {
    fn new(search: &'a NeighbourSearch<'a>, labels: &'a [u32]) -> Self {
        let cloud = search.cloud();
        let radius = search.radius_mm() as f32;
        GridCount {
            search,
            points: cloud.points(),
            labels,
            width: cloud.width(),
            height: cloud.height(),
            radius_sq: radius * radius,
            isa: kernels::isa(),
        }
    }

    fn window(&self, p: Point) -> (usize, usize) {
        self.search.camera().neighbour_window(p, self.search.radius_mm())
    }

    /// A window holding the own window of every point whose depth is at
    /// least `corner`'s and whose `|x|` and `|y|` are at most its: the
    /// corner's own, which grows towards the camera and off axis (up to
    /// its cap, which covers any image). Near the camera, where that
    /// growth has a cut-off, the whole image.
    fn row_window(&self, corner: Point) -> (usize, usize) {
        if corner[2] as f64 <= 2.0 * self.search.radius_mm() {
            return (self.width, self.height);
        }
        let (wx, wy) = self.window(corner);
        // A window as large as the image already reaches every pixel.
        (wx.min(self.width), wy.min(self.height))
    }

    /// True when point `i` has at most `threshold` neighbours labelled
    /// `label`: the count of [`NeighbourSearch::count`] over the same
    /// window with the same predicate, stopped once it exceeds the
    /// threshold.
    fn is_edge(&self, i: usize, label: u32, threshold: f64) -> bool {
        match self.isa {
            // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { avx2::is_edge(self, i, label, threshold) },
            // SAFETY: SSE2 is part of the x86_64 baseline.
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => unsafe { sse2::is_edge(self, i, label, threshold) },
            _ => self.is_edge_by(i, label, threshold, count_scalar),
        }
    }

    /// The points and labels of `cols` in row `row`.
    #[inline(always)]
    fn span(&self, row: usize, cols: std::ops::RangeInclusive<usize>) -> (&[Point], &[u32]) {
        let span = row * self.width + cols.start()..row * self.width + cols.end() + 1;
        (&self.points[span.clone()], &self.labels[span])
    }

    /// [`GridCount::is_edge`] with `count_span` counting one window row.
    /// The rows go from the point's outwards: the middle ones hold the
    /// most neighbours, so a point that is no edge is told sooner.
    #[inline(always)]
    fn is_edge_by(
        &self,
        i: usize,
        label: u32,
        threshold: f64,
        count_span: impl Fn(&Point, &[Point], &[u32], u32, f32) -> u32,
    ) -> bool {
        let (w, h) = (self.width, self.height);
        let p = self.points[i];
        let (col, row) = (i % w, i / w);
        let (wx, wy) = self.window(p);
        let (c0, c1) = (col.saturating_sub(wx), (col + wx).min(w - 1));
        let (below, above) = (row - row.saturating_sub(wy), (row + wy).min(h - 1) - row);
        let r2 = self.radius_sq;
        let (points, labels) = self.span(row, c0..=c1);
        let mut count = count_span(&p, points, labels, label, r2);
        // The rows at the same distance above and below together: two
        // independent counts per check.
        for d in 1..=below.max(above) {
            if count as f64 > threshold {
                return false;
            }
            if d <= below {
                let (points, labels) = self.span(row - d, c0..=c1);
                count += count_span(&p, points, labels, label, r2);
            }
            if d <= above {
                let (points, labels) = self.span(row + d, c0..=c1);
                count += count_span(&p, points, labels, label, r2);
            }
        }
        count as f64 <= threshold
    }
}

/// The row passes four pixels at a time in SSE2, the x86_64 baseline.
#[cfg(target_arch = "x86_64")]
mod sse2 {
    use std::arch::x86_64::*;

    use super::{Corner, GridCount, Point, RowBounds, count_scalar};
    use crate::kernels;

    /// `_MM_SHUFFLE` in reading order: lanes `a`, `b` of the first
    /// operand, then `c`, `d` of the second.
    pub(crate) const fn pick(a: i32, b: i32, c: i32, d: i32) -> i32 {
        a | b << 2 | c << 4 | d << 6
    }

    /// The x, y and z lanes of four consecutive points.
    #[target_feature(enable = "sse2")]
    pub(crate) fn lanes(quad: &[Point]) -> (__m128, __m128, __m128) {
        let coords = quad[..4].as_flattened();
        // SAFETY: `coords` holds twelve floats; unaligned loads need no
        // alignment.
        let (a, b, c) = unsafe {
            (_mm_loadu_ps(coords.as_ptr()), _mm_loadu_ps(coords[4..].as_ptr()), _mm_loadu_ps(coords[8..].as_ptr()))
        };
        // a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3.
        let x = _mm_shuffle_ps::<{ pick(0, 3, 0, 2) }>(a, _mm_shuffle_ps::<{ pick(2, 2, 1, 1) }>(b, c));
        let y = _mm_shuffle_ps::<{ pick(0, 2, 0, 2) }>(
            _mm_shuffle_ps::<{ pick(1, 1, 0, 0) }>(a, b),
            _mm_shuffle_ps::<{ pick(3, 3, 2, 2) }>(b, c),
        );
        let z = _mm_shuffle_ps::<{ pick(0, 2, 0, 2) }>(
            _mm_shuffle_ps::<{ pick(2, 2, 1, 1) }>(a, b),
            _mm_shuffle_ps::<{ pick(0, 0, 3, 3) }>(c, c),
        );
        (x, y, z)
    }

    #[target_feature(enable = "sse2")]
    fn load4(v: &[u32]) -> __m128i {
        let v = &v[..4];
        // SAFETY: `v` holds four u32.
        unsafe { _mm_loadu_si128(v.as_ptr().cast()) }
    }

    /// Four u16 widened to u32 lanes.
    #[target_feature(enable = "sse2")]
    fn load4_u16(v: &[u16]) -> __m128i {
        let v = &v[..4];
        // SAFETY: `v` holds four u16, one 64-bit load.
        let packed = unsafe { _mm_loadl_epi64(v.as_ptr().cast()) };
        _mm_unpacklo_epi16(packed, _mm_setzero_si128())
    }

    /// All ones in the lanes labelled as one of the plates.
    #[target_feature(enable = "sse2")]
    fn member_lanes<const N: usize>(labels: __m128i, plate_labels: [u32; N]) -> [__m128i; N] {
        plate_labels.map(|l| _mm_cmpeq_epi32(labels, _mm_set1_epi32(l as i32)))
    }

    /// [`super::members_corner`]'s accumulation over a multiple of four
    /// pixels. The compares of `minps` and `maxps` return their second
    /// operand when the first is NaN, which skips NaN as the scalar form
    /// does.
    #[target_feature(enable = "sse2")]
    pub(crate) fn members_corner<const N: usize>(labels: &[u32], points: &[Point], plate_labels: [u32; N]) -> Corner {
        let abs = _mm_castsi128_ps(_mm_set1_epi32(i32::MAX));
        let far = _mm_set1_ps(f32::INFINITY);
        let (mut z_min, mut x_max, mut y_max, mut any) = (far, _mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_si128());
        for (labels, quad) in labels.chunks_exact(4).zip(points.chunks_exact(4)) {
            let member = member_lanes(load4(labels), plate_labels)
                .into_iter()
                .fold(_mm_setzero_si128(), |a, m| _mm_or_si128(a, m));
            let member_ps = _mm_castsi128_ps(member);
            let (x, y, z) = lanes(quad);
            z_min = _mm_min_ps(_mm_or_ps(_mm_and_ps(member_ps, z), _mm_andnot_ps(member_ps, far)), z_min);
            x_max = _mm_max_ps(_mm_and_ps(member_ps, _mm_and_ps(x, abs)), x_max);
            y_max = _mm_max_ps(_mm_and_ps(member_ps, _mm_and_ps(y, abs)), y_max);
            any = _mm_or_si128(any, member);
        }
        let mut out = [[0f32; 4]; 3];
        // SAFETY: each row of `out` holds four floats.
        unsafe {
            _mm_storeu_ps(out[0].as_mut_ptr(), z_min);
            _mm_storeu_ps(out[1].as_mut_ptr(), x_max);
            _mm_storeu_ps(out[2].as_mut_ptr(), y_max);
        }
        let [z, x, y] = out;
        Corner {
            z_min: z.into_iter().fold(f32::INFINITY, |a, v| if v < a { v } else { a }),
            x_max: x.into_iter().fold(0.0, |a, v| if v > a { v } else { a }),
            y_max: y.into_iter().fold(0.0, |a, v| if v > a { v } else { a }),
            any: _mm_movemask_epi8(any) != 0,
        }
    }

    /// [`RowBounds::open_members`] for the columns `cols` (a multiple of
    /// four, every window inside the row and of `area` pixels) with the
    /// full counts `full` of the row: the bound in integer lanes, the
    /// threshold `ratio · N` in double lanes as the scalar form computes
    /// it.
    #[target_feature(enable = "sse2")]
    pub(crate) fn open_members<const N: usize>(
        bounds: &RowBounds<N>,
        cols: std::ops::Range<usize>,
        area: u32,
        full: &[u16],
        ratio: f64,
        open: &mut Vec<(u32, u8)>,
    ) {
        let wx = bounds.wx;
        let (ratio, area) = (_mm_set1_pd(ratio), _mm_set1_epi32(area as i32));
        let low_field = _mm_set1_epi32(0xffff);
        for c in cols.step_by(4) {
            let fields = _mm_sub_epi32(load4(&bounds.prefix[c + wx + 1..]), load4(&bounds.prefix[c - wx..]));
            let plates = member_lanes(load4(&bounds.labels[c..]), bounds.plate_labels);
            let (mut member, mut same) = (_mm_setzero_si128(), _mm_setzero_si128());
            for (k, m) in plates.into_iter().enumerate() {
                let field = match (N, k) {
                    (1, _) => fields,
                    (_, 0) => _mm_and_si128(fields, low_field),
                    _ => _mm_srli_epi32::<16>(fields),
                };
                member = _mm_or_si128(member, m);
                same = _mm_or_si128(same, _mm_and_si128(m, field));
            }
            let member_bits = _mm_movemask_ps(_mm_castsi128_ps(member));
            if member_bits == 0 {
                continue;
            }
            // At most the window's non-members are not of the plate.
            let bound = _mm_sub_epi32(_mm_add_epi32(load4_u16(&bounds.counts[c..]), same), area);
            let full = load4_u16(&full[c..]);
            let high = |v: __m128i| _mm_unpackhi_epi64(v, v);
            let above = |b: __m128i, n: __m128i| {
                _mm_movemask_pd(_mm_cmpgt_pd(_mm_cvtepi32_pd(b), _mm_mul_pd(ratio, _mm_cvtepi32_pd(n))))
            };
            let settled = above(bound, full) | above(high(bound), high(full)) << 2;
            let mut left = member_bits & !settled;
            while left != 0 {
                let lane = left.trailing_zeros() as usize;
                left &= left - 1;
                let k = bounds.plate_of(bounds.labels[c + lane]).unwrap_or(0);
                open.push(((c + lane) as u32, k as u8));
            }
        }
    }

    /// [`GridCount::is_edge`], four pixels at a time on spans that hold as
    /// many.
    #[target_feature(enable = "sse2")]
    pub(crate) fn is_edge(grid: &GridCount, i: usize, label: u32, threshold: f64) -> bool {
        grid.is_edge_by(
            i,
            label,
            threshold,
            #[inline(always)]
            |p, points, labels, label, radius_sq| {
                if points.len().min(labels.len()) >= 4 {
                    count_span(p, points, labels, label, radius_sq)
                } else {
                    count_scalar(p, points, labels, label, radius_sq)
                }
            },
        )
    }

    /// The pixels of a span labelled `label` and within the radius of `p`,
    /// for at least four pixels: see [`super::count_scalar`]. A length that
    /// is no multiple of four ends with the last four pixels, the lanes
    /// counted before masked off. Separate subtract, multiply and add in
    /// the scalar order and an ordered compare (NaN is false) give the
    /// same decision for every pixel.
    #[target_feature(enable = "sse2")]
    pub(crate) fn count_span(p: &Point, points: &[Point], labels: &[u32], label: u32, radius_sq: f32) -> u32 {
        let n = points.len().min(labels.len());
        let (px, py, pz) = (_mm_set1_ps(p[0]), _mm_set1_ps(p[1]), _mm_set1_ps(p[2]));
        let (r2, wanted) = (_mm_set1_ps(radius_sq), _mm_set1_epi32(label as i32));
        let count_at = |at: usize| -> __m128i {
            let (x, y, z) = lanes(&points[at..]);
            let near = kernels::sse2::within([px, py, pz], [x, y, z], r2);
            _mm_and_si128(_mm_castps_si128(near), _mm_cmpeq_epi32(load4(&labels[at..]), wanted))
        };
        // A counted lane is all ones, -1: subtracting counts it.
        let mut counts = _mm_setzero_si128();
        for at in (0..n - 3).step_by(4) {
            counts = _mm_sub_epi32(counts, count_at(at));
        }
        let done = n / 4 * 4;
        if done < n {
            // Lanes 0..done + 4 - n of the last four pixels were counted above.
            let fresh = _mm_cmpgt_epi32(_mm_setr_epi32(0, 1, 2, 3), _mm_set1_epi32((done + 3 - n) as i32));
            counts = _mm_sub_epi32(counts, _mm_and_si128(fresh, count_at(n - 4)));
        }
        let mut lanes = [0u32; 4];
        // SAFETY: `lanes` holds exactly four u32.
        unsafe { _mm_storeu_si128(lanes.as_mut_ptr().cast(), counts) };
        lanes.iter().sum()
    }
}

/// The exact counts eight pixels at a time, where the CPU runs AVX2.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::sse2::pick;
    use super::{GridCount, Point, count_scalar, sse2};
    use crate::kernels;

    /// [`GridCount::is_edge`], eight pixels at a time on spans that hold
    /// as many, four on shorter ones.
    #[target_feature(enable = "avx2")]
    pub(crate) fn is_edge(grid: &GridCount, i: usize, label: u32, threshold: f64) -> bool {
        grid.is_edge_by(
            i,
            label,
            threshold,
            #[inline(always)]
            |p, points, labels, label, radius_sq| match points.len().min(labels.len()) {
                8.. => count_span(p, points, labels, label, radius_sq),
                4.. => sse2::count_span(p, points, labels, label, radius_sq),
                _ => count_scalar(p, points, labels, label, radius_sq),
            },
        )
    }

    /// [`sse2::count_span`] eight pixels at a time, for at least eight
    /// pixels: each 128-bit half of the registers holds four points laid
    /// out as the SSE2 form has them, so the same in-lane shuffles regroup
    /// them.
    #[target_feature(enable = "avx2")]
    pub(crate) fn count_span(p: &Point, points: &[Point], labels: &[u32], label: u32, radius_sq: f32) -> u32 {
        let n = points.len().min(labels.len());
        let (px, py, pz) = (_mm256_set1_ps(p[0]), _mm256_set1_ps(p[1]), _mm256_set1_ps(p[2]));
        let (r2, wanted) = (_mm256_set1_ps(radius_sq), _mm256_set1_epi32(label as i32));
        let count_at = |at: usize| -> __m256i {
            let coords = points[at..at + 8].as_flattened();
            let labels = &labels[at..at + 8];
            // SAFETY: `coords` holds 24 floats and `labels` eight u32;
            // unaligned loads need no alignment.
            let (a, b, c, l) = unsafe {
                let half = |k: usize| coords[k..].as_ptr();
                (
                    _mm256_loadu2_m128(half(12), half(0)),
                    _mm256_loadu2_m128(half(16), half(4)),
                    _mm256_loadu2_m128(half(20), half(8)),
                    _mm256_loadu_si256(labels.as_ptr().cast()),
                )
            };
            let x = _mm256_shuffle_ps::<{ pick(0, 3, 0, 2) }>(a, _mm256_shuffle_ps::<{ pick(2, 2, 1, 1) }>(b, c));
            let y = _mm256_shuffle_ps::<{ pick(0, 2, 0, 2) }>(
                _mm256_shuffle_ps::<{ pick(1, 1, 0, 0) }>(a, b),
                _mm256_shuffle_ps::<{ pick(3, 3, 2, 2) }>(b, c),
            );
            let z = _mm256_shuffle_ps::<{ pick(0, 2, 0, 2) }>(
                _mm256_shuffle_ps::<{ pick(2, 2, 1, 1) }>(a, b),
                _mm256_shuffle_ps::<{ pick(0, 0, 3, 3) }>(c, c),
            );
            let near = _mm256_castps_si256(kernels::avx2::within([px, py, pz], [x, y, z], r2));
            _mm256_and_si256(near, _mm256_cmpeq_epi32(l, wanted))
        };
        // A counted lane is all ones, -1: subtracting counts it.
        let mut counts = _mm256_setzero_si256();
        for at in (0..n - 7).step_by(8) {
            counts = _mm256_sub_epi32(counts, count_at(at));
        }
        let done = n / 8 * 8;
        if done < n {
            // Lanes 0..done + 8 - n of the last eight pixels were counted above.
            let fresh =
                _mm256_cmpgt_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32((done + 7 - n) as i32));
            counts = _mm256_sub_epi32(counts, _mm256_and_si256(fresh, count_at(n - 8)));
        }
        let sum = _mm_add_epi32(_mm256_castsi256_si128(counts), _mm256_extracti128_si256::<1>(counts));
        let mut lanes = [0u32; 4];
        // SAFETY: `lanes` holds exactly four u32.
        unsafe { _mm_storeu_si128(lanes.as_mut_ptr().cast(), sum) };
        lanes.iter().sum()
    }
}

/// The pixels of one window row labelled `label` and within the radius of
/// `p`, by [`super::neighbours`]' predicate term for term.
fn count_scalar(p: &Point, points: &[Point], labels: &[u32], label: u32, radius_sq: f32) -> u32 {
    points.iter().zip(labels).map(|(q, &l)| ((l == label) & kernels::within(p, q, radius_sq)) as u32).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::cloud::PointCloud;
    use crate::geometry::Vec3;
    use crate::pipeline::plane_points::{RobustPlaneCriterion, robust_criterion};

    /// A frontal plate at 600 mm covering columns below `cut` of a 50 x 30
    /// grid, with a few dropouts inside.
    fn plate() -> PointCloud {
        let camera = CameraModel::default();
        let (w, h, cut) = (50, 30, 30);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(camera.cx() - 25.0 + col as f64, camera.cy() - 15.0 + row as f64);
                let dropout = (row * 50 + col) % 97 == 5;
                pts.push(if col < cut && !dropout {
                    [(r[0] * 600.0) as f32, (r[1] * 600.0) as f32, 600.0]
                } else {
                    [f32::NAN; 3]
                });
            }
        }
        PointCloud::organized(w, h, pts).unwrap()
    }

    fn setup(cloud: &PointCloud, search: &NeighbourSearch) -> (PlanePoints, Vec<u32>, Vec<u32>) {
        let plane =
            robust_criterion(search, &RobustPlaneCriterion { normal: Vec3::z(), min_ratio: 0.8, max_angle_deg: 20.0 });
        let labels: Vec<u32> = plane.mask.iter().map(|&m| if m { 0 } else { u32::MAX }).collect();
        let members = (0..cloud.len() as u32).filter(|&i| plane.mask[i as usize]).collect();
        (plane, labels, members)
    }

    #[test]
    fn robust_threshold_finds_the_straight_edge_that_half_misses() {
        let camera = CameraModel::default();
        let cloud = plate();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let (plane, labels, members) = setup(&cloud, &search);
        let plate = Plate { labels: &labels, label: 0, members: &members };
        let on_row = |pts: &[u32]| pts.iter().filter(|&&i| i / 50 == 15).map(|&i| i % 50).collect::<Vec<_>>();
        let robust = edge_points(&search, &plane, plate, &EdgeCriterion { full: FullCount::Plane, ratio: 0.75 });
        let cols = on_row(&robust);
        let last = *on_row(&members).iter().max().unwrap();
        assert!(cols.contains(&last), "the outermost plane point is an edge: {cols:?}");
        // Columns near 0 touch the grid's border, which is an edge too.
        assert!(cols.iter().all(|&c| c <= 3 || c + 3 >= last), "interior points are not edges: {cols:?}");
        let paper = edge_points(&search, &plane, plate, &EdgeCriterion { full: FullCount::Frontal, ratio: 0.5 });
        assert!(on_row(&paper).len() < cols.len());
    }

    #[test]
    fn skipping_by_lower_bound_changes_nothing() {
        let camera = CameraModel::default();
        let cloud = plate();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let tree = NeighbourSearch::kdtree(&cloud, &camera, 1.0);
        let (plane, labels, members) = setup(&cloud, &search);
        let plate = Plate { labels: &labels, label: 0, members: &members };
        for criterion in [
            EdgeCriterion { full: FullCount::Plane, ratio: 0.75 },
            EdgeCriterion { full: FullCount::Frontal, ratio: 0.5 },
        ] {
            let mut fast = edge_points(&search, &plane, plate, &criterion);
            fast.sort();
            assert_eq!(fast, reference(&tree, &plane, plate, &criterion));
        }
    }

    #[test]
    fn windows_too_large_for_the_sums_are_counted_exactly() {
        // Points at the radius from the camera: every window is the whole
        // 300 x 250 frame, more pixels than a plate's field of the sums
        // can count.
        let camera = CameraModel::default();
        let (w, h) = (300, 250);
        let pts = (0..w * h).map(|i| [(i % 7) as f32 * 1e-3, (i % 5) as f32 * 1e-3, 1.0]).collect();
        let cloud = PointCloud::organized(w, h, pts).unwrap();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let labels: Vec<u32> = (0..w * h)
            .map(|i| {
                if i % 7500 == 11 {
                    1
                } else if i < 70_000 {
                    0
                } else {
                    9
                }
            })
            .collect();
        let members = |l: u32| -> Vec<u32> { (0..(w * h) as u32).filter(|&i| labels[i as usize] == l).collect() };
        let (a, b) = (members(0), members(1));
        // Plate 1's ten points see each other only: edges at ratio 1 of a
        // full count of 10; plate 0 is no edge.
        let plane = PlanePoints {
            mask: vec![true; w * h],
            counts: vec![u16::MAX; w * h],
            full: labels.iter().map(|&l| if l == 1 { 10 } else { 0 }).collect(),
        };
        let criterion = EdgeCriterion { full: FullCount::Plane, ratio: 1.0 };
        let plates =
            [Plate { labels: &labels, label: 0, members: &a }, Plate { labels: &labels, label: 1, members: &b }];
        let [edges_a, edges_b] = edge_points_of_plates(&search, &plane, plates, &criterion);
        assert!(edges_a.is_empty());
        assert_eq!(edges_b, b);
        assert_eq!(edges_b, reference(&search, &plane, plates[1], &criterion));
    }

    #[test]
    fn simd_counts_equal_the_scalar_predicate() {
        // Distances on both sides of the radius, exact ties, invalid
        // points and other labels, over every span length to 23 and every
        // start, so that each lane position meets each case.
        let p = [0.25f32, -0.5, 600.0];
        let offsets = [0.0f32, 0.5, 0.999_999, 1.0, 1.000_001, 0.6, 0.8, 2.0, 0.7];
        let points: Vec<Point> = (0..40)
            .map(|k| {
                let d = offsets[k % offsets.len()];
                match k % 4 {
                    _ if k % 11 == 3 => [f32::NAN; 3],
                    0 => [p[0] + d, p[1], p[2]],
                    1 => [p[0], p[1] - d, p[2]],
                    2 => [p[0], p[1], p[2] + d],
                    _ => [p[0] + 0.6 * d, p[1] + 0.8 * d, p[2]],
                }
            })
            .collect();
        let labels: Vec<u32> = (0..40).map(|k| if k % 5 == 2 { 3 } else { 1 }).collect();
        let mut counted = 0;
        for start in 0..17 {
            for len in 0..24.min(40 - start) {
                let span = start..start + len;
                let scalar = count_scalar(&p, &points[span.clone()], &labels[span.clone()], 1, 1.0);
                #[cfg(target_arch = "x86_64")]
                if len >= 4 {
                    // SAFETY: SSE2 is part of the x86_64 baseline.
                    let quads = unsafe { sse2::count_span(&p, &points[span.clone()], &labels[span.clone()], 1, 1.0) };
                    assert_eq!(quads, scalar, "{start} + {len}");
                }
                #[cfg(target_arch = "x86_64")]
                if len >= 8 && Isa::Avx2.supported() {
                    // SAFETY: the CPU runs AVX2, checked just above.
                    let octets = unsafe { avx2::count_span(&p, &points[span.clone()], &labels[span], 1, 1.0) };
                    assert_eq!(octets, scalar, "{start} + {len}");
                }
                counted += scalar;
            }
        }
        assert!(counted > 1000);
    }

    /// A fixed pseudo-random sequence for the SIMD tests.
    fn noise(n: usize, seed: u64) -> Vec<u32> {
        let mut x = seed;
        (0..n)
            .map(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (x >> 33) as u32
            })
            .collect()
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn four_pixel_corners_equal_the_scalar_ones() {
        let n = 64;
        let r = noise(4 * n, 7);
        let labels: Vec<u32> = r[..n].iter().map(|v| v % 4).collect();
        let points: Vec<Point> = (0..n)
            .map(|k| {
                let v = |j: usize| (r[n + 3 * k + j] % 2000) as f32 - 1000.0;
                if r[k].is_multiple_of(9) { [f32::NAN; 3] } else { [v(0), v(1), v(2).abs() + 1.0] }
            })
            .collect();
        for len in (0..=n).step_by(4) {
            for plates in [[1, 2], [3, 7], [8, 9]] {
                let mut scalar = Corner::default();
                for (l, p) in labels[..len].iter().zip(&points[..len]) {
                    if plates.contains(l) {
                        scalar.add(p);
                    }
                }
                // SAFETY: SSE2 is part of the x86_64 baseline.
                let quads = unsafe { sse2::members_corner(&labels[..len], &points[..len], plates) };
                let key = |c: Corner| (c.z_min, c.x_max, c.y_max, c.any);
                assert_eq!(key(quads), key(scalar), "{len} pixels, plates {plates:?}");
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn four_column_bounds_equal_the_scalar_ones() {
        fn check<const N: usize>(plate_labels: [u32; N], seed: u64) -> usize {
            let w = 70;
            let r = noise(4 * w, seed);
            let labels: Vec<u32> = r[..w].iter().map(|v| if v % 7 == 0 { 5 } else { v % 2 }).collect();
            let counts: Vec<u16> = r[w..2 * w].iter().map(|v| (v % 120) as u16).collect();
            let full: Vec<u16> = r[2 * w..3 * w].iter().map(|v| (v % 100 + 40) as u16).collect();
            let mut opened = 0;
            for (wx, window_rows) in [(0, 1), (2, 5), (6, 13), (9, 3)] {
                // Column sums of `window_rows` rows, made up from the row's
                // own codes at different multiples.
                let field = 32 / N as u32;
                let columns: Vec<u32> = (0..w)
                    .map(|c| {
                        let code = |k: usize| (labels[c] == plate_labels[k]) as u32;
                        let rows = (r[3 * w + c] as usize % window_rows) as u32 + code(0).max(code(N - 1));
                        (0..N).map(|k| (code(k) * rows) << (k as u32 * field)).sum()
                    })
                    .collect();
                let prefix: Vec<u32> = std::iter::once(0)
                    .chain(columns.iter().scan(0u32, |s, &c| {
                        *s = s.wrapping_add(c);
                        Some(*s)
                    }))
                    .collect();
                let bounds =
                    RowBounds { plate_labels, prefix: &prefix, labels: &labels, counts: &counts, wx, window_rows };
                let area = ((2 * wx + 1) * window_rows) as u32;
                let quads = wx..wx + (w - 2 * wx) / 4 * 4;
                for ratio in [0.2, 0.75, 1.3] {
                    let mut scalar = Vec::new();
                    bounds.open_members(quads.clone(), |c| ratio * full[c] as f64, &mut scalar);
                    let mut simd = Vec::new();
                    // SAFETY: SSE2 is part of the x86_64 baseline.
                    unsafe { sse2::open_members(&bounds, quads.clone(), area, &full, ratio, &mut simd) };
                    assert_eq!(simd, scalar, "wx {wx}, {window_rows} rows, ratio {ratio}");
                    opened += simd.len();
                }
            }
            opened
        }
        // Some members open and some settled in each case.
        for opened in [check([1], 3), check([0, 1], 4), check([1, 0], 5)] {
            assert!((20..600).contains(&opened), "{opened} opened");
        }
    }

    #[test]
    fn every_exact_count_path_decides_alike() {
        let camera = CameraModel::default();
        let cloud = plate();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let (_, labels, members) = setup(&cloud, &search);
        let decisions = |grid: &GridCount| -> Vec<bool> {
            let thresholds = [10.0, 20.0, 31.5, 40.0];
            members.iter().flat_map(|&i| thresholds.map(|t| grid.is_edge(i as usize, 0, t))).collect()
        };
        let (ran, _skipped) = kernels::on_every_isa(|_| decisions(&GridCount::new(&search, &labels)));
        let (first, scalar) = &ran[0];
        assert_eq!(*first, Isa::Scalar);
        for (isa, decided) in &ran[1..] {
            assert!(decided == scalar, "{isa:?} decides as the scalar form");
        }
        let edges = scalar.iter().filter(|&&edge| edge).count();
        assert!(edges > 100 && edges < 3 * members.len(), "{edges}");
    }
}
