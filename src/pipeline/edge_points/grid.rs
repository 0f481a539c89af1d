//! The edge criterion's fast classification on a pixel grid: most members
//! are settled without counting, by a lower bound of their same-plate
//! count, and only the rest are counted, exactly, through the kernels.
//!
//! The bound: the plane criterion's count is a lower bound of a point's
//! neighbours, and at most the window's non-members are not of its plate,
//! so when that bound exceeds `ratio · N` the point is no edge. The
//! window's members are read from column sums of the window rows, kept
//! per band of rows as the window slides down.

use rayon::prelude::*;

use super::FullPlaneCount;
use crate::cloud::Point;
use crate::kernels::{self, LabelledGrid, LabelledWindow, RowBounds, members_corner};
use crate::pipeline::neighbours::NeighbourSearch;

/// Rows handed to a rayon job at a time: enough to amortise the first
/// row's window sums, few enough that the rows along an edge, where the
/// exact counts are, spread over the threads.
const BAND_ROWS: usize = 32;

/// The edge points of `N` (1 or 2) plates: the members of plate `k` are
/// the pixels labelled `plate_labels[k]`, all in `rows`, taken row by row,
/// so in index order. A member is an edge point when it has at most `ratio · N`
/// same-plate neighbours, `N` from `full`; `lower_bounds` holds a lower
/// bound of each point's neighbours of any label.
pub(super) fn edge_points<const N: usize, F: FullPlaneCount>(
    search: &NeighbourSearch,
    lower_bounds: &[u16],
    labels: &[u32],
    plate_labels: [u32; N],
    rows: std::ops::Range<usize>,
    ratio: f64,
    full: &F,
) -> [Vec<u32>; N] {
    let criterion = Limits { lower_bounds, ratio, full };
    let cloud = search.cloud();
    let (w, h) = (cloud.width(), cloud.height());
    let rows = rows.start.min(h)..rows.end.min(h);
    let grid = GridCount::new(search, labels);
    // Bands stay on multiples of BAND_ROWS: the rows outside `rows` hold
    // no member, so the edge points are those of the whole frame.
    let bands: Vec<[Vec<u32>; N]> = (rows.start / BAND_ROWS..rows.end.div_ceil(BAND_ROWS))
        .into_par_iter()
        .map_init(
            || Band::<N>::new(w, plate_labels),
            |band, b| {
                let mut edges: [Vec<u32>; N] = std::array::from_fn(|_| Vec::new());
                for row in (b * BAND_ROWS).max(rows.start)..((b + 1) * BAND_ROWS).min(rows.end) {
                    band.row(&grid, &criterion, row, &mut edges);
                }
                band.count_pending(&grid, &criterion, usize::MAX, &mut edges);
                edges
            },
        )
        .collect();
    std::array::from_fn(|k| bands.iter().flat_map(|edges| edges[k].iter().copied()).collect())
}

/// What the classification is handed: the criterion's ratio and full-plane
/// count, and the lower bounds of the neighbour counts.
struct Limits<'a, F> {
    lower_bounds: &'a [u16],
    ratio: f64,
    full: &'a F,
}

impl<F: FullPlaneCount> Limits<'_, F> {
    /// `ratio · N` at point `i`: the most same-plate neighbours of an edge.
    #[inline]
    fn limit(&self, i: usize) -> f64 {
        self.ratio * self.full.at(i)
    }
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
        criterion: &Limits<impl FullPlaneCount>,
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
            counts: &criterion.lower_bounds[first..first + w],
            wx,
            window_rows: self.rows.len(),
        };
        let threshold = |c: usize| criterion.limit(first + c);
        // Columns whose window lies inside the row go four at a time, the
        // rest one by one, in column order.
        let mut quads = wx..wx;
        let quad_area = (2 * wx + 1) as u64 * self.rows.len() as u64;
        let per_point = criterion.full.per_point();
        if per_point.is_some() && quad_area <= u16::MAX as u64 {
            quads.end = quads.start + w.saturating_sub(2 * wx) / 4 * 4;
        }
        let open = &mut self.open;
        open.clear();
        bounds.open_members(0..quads.start, threshold, open);
        if let Some(full) = per_point.filter(|_| !quads.is_empty()) {
            let full = &full[first..first + w];
            if !bounds.open_members_in_quads(quads.clone(), quad_area as u32, full, criterion.ratio, open) {
                bounds.open_members(quads.clone(), threshold, open);
            }
        }
        bounds.open_members(quads.end..w, threshold, open);
        // Counted once the rows below have been read for their corners,
        // which brings the window's points into the cache.
        let ready = row + wy;
        self.pending.extend(open.iter().map(|&(c, k)| (ready, (first + c as usize) as u32, k)));
        self.count_pending(grid, criterion, row, edges);
    }

    /// Counts the pending members whose window rows have been read by
    /// row `read` (all at the band's end), in the order they were found.
    fn count_pending(
        &mut self,
        grid: &GridCount,
        criterion: &Limits<impl FullPlaneCount>,
        read: usize,
        edges: &mut [Vec<u32>; N],
    ) {
        while let Some(&(ready, i, k)) = self.pending.front() {
            if ready > read {
                break;
            }
            self.pending.pop_front();
            let (i, k) = (i as usize, k as usize);
            if grid.is_edge(i, self.plate_labels[k], criterion.limit(i)) {
                edges[k].push(i as u32);
            }
        }
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
    /// `label`: the count of `NeighbourSearch::count` (the tests' reference) over the same
    /// window with the same predicate, stopped once it exceeds the
    /// threshold.
    fn is_edge(&self, i: usize, label: u32, threshold: f64) -> bool {
        let grid = LabelledGrid { points: self.points, labels: self.labels, width: self.width, height: self.height };
        let query = LabelledWindow {
            centre: i,
            window: self.window(self.points[i]),
            label,
            radius_sq: self.radius_sq,
            threshold,
        };
        kernels::labelled_count_at_most(&grid, &query)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::pipeline::edge_points::tests::{plate, setup};

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
        assert_eq!(*first, kernels::Isa::Scalar);
        for (isa, decided) in &ran[1..] {
            assert!(decided == scalar, "{isa:?} decides as the scalar form");
        }
        let edges = scalar.iter().filter(|&&edge| edge).count();
        assert!(edges > 100 && edges < 3 * members.len(), "{edges}");
    }
}
