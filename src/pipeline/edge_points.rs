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

use super::neighbours::NeighbourSearch;
use super::plane_points::PlanePoints;

/// How the full count `N` of Eq. 15 is obtained.
#[derive(Debug, Clone, Copy)]
pub enum FullCount {
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
pub struct EdgeCriterion {
    pub full: FullCount,
    /// A point is an edge point when `N_r <= ratio · N`.
    pub ratio: f64,
}

/// One plate: the cloud's plate labels, this plate's label and members.
#[derive(Debug, Clone, Copy)]
pub struct Plate<'a> {
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
pub fn edge_points(search: &NeighbourSearch, plane: &PlanePoints, plate: Plate, criterion: &EdgeCriterion) -> Vec<u32> {
    if !search.cloud().is_organized() {
        let is_edge = |i: usize| {
            let n = criterion.full.of(search, plane, i);
            search.count(i, |j| plate.labels[j] == plate.label) as f64 <= criterion.ratio * n
        };
        return plate.members.par_iter().copied().filter(|&i| is_edge(i as usize)).collect();
    }
    let [edges] = on_grid(search, plane, plate.labels, [plate.label], criterion);
    edges
}

/// [`edge_points`] of two plates, in one pass over the frame when they
/// share their labels (each pixel then belongs to at most one of them).
pub fn edge_points_of_plates(
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
pub fn reference(search: &NeighbourSearch, plane: &PlanePoints, plate: Plate, criterion: &EdgeCriterion) -> Vec<u32> {
    plate
        .members
        .iter()
        .copied()
        .filter(|&i| {
            let i = i as usize;
            let n = criterion.full.of(search, plane, i);
            search.count(i, |j| plate.labels[j] == plate.label) as f64 <= criterion.ratio * n
        })
        .collect()
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
                edges
            },
        )
        .collect();
    std::array::from_fn(|k| bands.iter().flat_map(|edges| edges[k].iter().copied()).collect())
}

/// A job's scratch: the member codes of the current window rows summed
/// per column, their prefix sums along the row, and the row's members.
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
    /// The row's members: column and plate.
    members: Vec<(u32, u8)>,
}

impl<const N: usize> Band<N> {
    const FIELD_BITS: u32 = 32 / N as u32;
    /// The most pixels a window may hold for its sum to be read field by field.
    const MAX_WINDOW: u64 = (1u64 << Self::FIELD_BITS) - 1;

    fn new(width: usize, plate_labels: [u32; N]) -> Self {
        Band {
            plate_labels,
            columns: vec![0; width],
            rows: 0..0,
            prefix: vec![0; width + 1],
            members: Vec::with_capacity(width),
        }
    }

    fn plate_of(&self, label: u32) -> Option<usize> {
        self.plate_labels.iter().position(|&l| l == label)
    }

    /// Adds (`sign` 1) or removes (`sign` -1) the codes of `row` to the
    /// column sums.
    fn add_row(&mut self, labels: &[u32], row: usize, sign: u32) {
        let w = self.columns.len();
        let line = &labels[row * w..(row + 1) * w];
        let plate_labels = self.plate_labels;
        for (sum, &label) in self.columns.iter_mut().zip(line) {
            let mut code = 0u32;
            for (k, &l) in plate_labels.iter().enumerate() {
                code |= ((label == l) as u32) << (k as u32 * Self::FIELD_BITS);
            }
            *sum = sum.wrapping_add(code.wrapping_mul(sign));
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
        while self.rows.end < target.end {
            self.add_row(labels, self.rows.end, 1);
            self.rows.end += 1;
        }
        while self.rows.end > target.end {
            self.rows.end -= 1;
            self.add_row(labels, self.rows.end, u32::MAX);
        }
        while self.rows.start < target.start {
            self.add_row(labels, self.rows.start, u32::MAX);
            self.rows.start += 1;
        }
        while self.rows.start > target.start {
            self.rows.start -= 1;
            self.add_row(labels, self.rows.start, 1);
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
        let points = &grid.points[first..first + w];
        self.members.clear();
        // The farthest any member's coordinates reach towards the camera
        // and off axis: the window of that corner point holds every
        // member's own window.
        let (mut z_min, mut x_max, mut y_max) = (f32::INFINITY, 0f32, 0f32);
        for (c, (&label, p)) in line.iter().zip(points).enumerate() {
            if let Some(k) = self.plate_of(label) {
                self.members.push((c as u32, k as u8));
                z_min = z_min.min(p[2]);
                x_max = x_max.max(p[0].abs());
                y_max = y_max.max(p[1].abs());
            }
        }
        if self.members.is_empty() {
            return;
        }
        let (wx, wy) = grid.window([x_max, y_max, z_min]);
        self.move_to(grid.labels, row.saturating_sub(wy)..(row + wy + 1).min(h));
        let mut sum = 0u32;
        for (prefix, &column) in self.prefix[1..].iter_mut().zip(&self.columns) {
            sum = sum.wrapping_add(column);
            *prefix = sum;
        }
        let window_rows = self.rows.len() as u64;
        for &(c, k) in &self.members {
            let (c, k) = (c as usize, k as usize);
            let i = first + c;
            let (c0, c1) = (c.saturating_sub(wx), (c + wx + 1).min(w));
            let area = (c1 - c0) as u64 * window_rows;
            let threshold = criterion.ratio * criterion.full.of(grid.search, plane, i);
            let settled = area <= Self::MAX_WINDOW && {
                let fields = self.prefix[c1].wrapping_sub(self.prefix[c0]);
                let members = (fields >> (k as u32 * Self::FIELD_BITS)) as u64 & Self::MAX_WINDOW;
                // At most the window's non-members are not of this plate.
                let lower_bound = plane.counts[i] as i64 - (area as i64 - members as i64);
                lower_bound as f64 > threshold
            };
            if !settled && grid.is_edge(i, self.plate_labels[k], threshold) {
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

    /// True when point `i` has at most `threshold` neighbours labelled
    /// `label`: the count of [`NeighbourSearch::count`] over the same
    /// window with the same predicate, stopped once it exceeds the
    /// threshold.
    fn is_edge(&self, i: usize, label: u32, threshold: f64) -> bool {
        let (w, h) = (self.width, self.height);
        let p = self.points[i];
        let (col, row) = (i % w, i / w);
        let (wx, wy) = self.window(p);
        let (c0, c1) = (col.saturating_sub(wx), (col + wx).min(w - 1));
        let (r0, r1) = (row.saturating_sub(wy), (row + wy).min(h - 1));
        let mut count = 0u32;
        for r in r0..=r1 {
            let span = r * w + c0..r * w + c1 + 1;
            count += count_span(&p, &self.points[span.clone()], &self.labels[span], label, self.radius_sq);
            if count as f64 > threshold {
                return false;
            }
        }
        count as f64 <= threshold
    }
}

/// The pixels of one window row labelled `label` and within the radius of
/// `p`, by [`super::neighbours`]' predicate term for term.
#[inline]
fn count_span(p: &Point, points: &[Point], labels: &[u32], label: u32, radius_sq: f32) -> u32 {
    points
        .iter()
        .zip(labels)
        .map(|(q, &l)| {
            let (dx, dy, dz) = (q[0] - p[0], q[1] - p[1], q[2] - p[2]);
            ((l == label) & (dx * dx + dy * dy + dz * dz <= radius_sq)) as u32
        })
        .sum()
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
}
