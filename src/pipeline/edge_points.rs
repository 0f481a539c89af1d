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
//!
//! Either way the criterion needs, for a member of a plate, its count of
//! same-plate neighbours within the radius and the count a complete plane
//! would give there ([`FullPlaneCount`]). [`reference`] counts every
//! member; on a pixel grid [`grid`] settles most members by a bound and
//! counts the rest, with the same result point for point.

use rayon::prelude::*;

mod grid;

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
            FullCount::Frontal => Frontal(search).at(i),
            FullCount::Plane => Measured(&plane.full).at(i),
        }
    }
}

/// The count `N` of Eq. 15 a complete plane would give at a point: what
/// the criterion compares a member's same-plate count with, however that
/// count is taken. The classification is handed it and asks it nothing
/// about where it comes from (the camera model, counts measured by an
/// earlier stage, or the cloud's own spacing).
pub(crate) trait FullPlaneCount: Sync {
    /// `N` at point `i`.
    fn at(&self, i: usize) -> f64;

    /// `N` of every point as whole numbers, when they are known beforehand
    /// (the fast classification then reads them in lanes); `None` when
    /// each is worked out at its point.
    fn per_point(&self) -> Option<&[u16]> {
        None
    }
}

/// Eq. 6 at the point's depth, from the camera model: the paper's `N`.
struct Frontal<'a>(&'a NeighbourSearch<'a>);

impl FullPlaneCount for Frontal<'_> {
    #[inline]
    fn at(&self, i: usize) -> f64 {
        let search = self.0;
        search.camera().theoretical_neighbours(search.radius_mm(), search.cloud().points()[i][2] as f64)
    }
}

/// Counts measured beforehand, one per point ([`PlanePoints::full`]).
struct Measured<'a>(&'a [u16]);

impl FullPlaneCount for Measured<'_> {
    #[inline]
    fn at(&self, i: usize) -> f64 {
        self.0[i] as f64
    }

    fn per_point(&self) -> Option<&[u16]> {
        Some(self.0)
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
        if let Some([edges]) = by_cell(search, plane, [plate], criterion) {
            return edges;
        }
        // The tests' KD-tree: member by member.
        return plate
            .members
            .par_iter()
            .copied()
            .filter(|&i| counted_edge_up_to_threshold(search, plane, plate, criterion, i))
            .collect();
    }
    let rows = member_rows(search, [plate.members]);
    let [edges] = on_grid(search, plane, plate.labels, [plate.label], rows, criterion);
    edges
}

/// The rows of the frame holding any of `members`: all a plate's edge
/// points lie in them, and a workpiece of several in a frame spans a few
/// of its rows.
fn member_rows<const N: usize>(search: &NeighbourSearch, members: [&[u32]; N]) -> std::ops::Range<usize> {
    let width = search.cloud().width().max(1);
    let (lo, hi) = members.iter().flat_map(|m| m.iter()).fold((u32::MAX, 0), |(lo, hi), &i| (lo.min(i), hi.max(i)));
    if lo > hi { 0..0 } else { lo as usize / width..hi as usize / width + 1 }
}

/// [`edge_points`] of plates without a pixel grid, with distinct labels,
/// in one pass over the cloud's cells ([`NeighbourSearch::query_by_cell`]):
/// each cell's candidates flagged once per plate by label, each member
/// then counted over its own plate's flags. `None` when the search has no
/// cells.
fn by_cell<const N: usize>(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    plates: [Plate; N],
    criterion: &EdgeCriterion,
) -> Option<[Vec<u32>; N]> {
    const NONE: u8 = u8::MAX;
    let n = search.cloud().len();
    let mut plate_of = vec![NONE; n];
    for (k, plate) in plates.iter().enumerate() {
        for &i in plate.members {
            plate_of[i as usize] = k as u8;
        }
    }
    let answers = search.query_by_cell(
        || std::array::from_fn::<Vec<u32>, N, _>(|_| Vec::new()),
        |i| plate_of[i] != NONE,
        |flags, candidates| {
            for (bits, plate) in flags.iter_mut().zip(&plates) {
                candidates.flags_into(bits, |j| plate.labels[j] == plate.label);
            }
        },
        |flags, i, neighbours| {
            let k = plate_of[i] as usize;
            edge_by_count(search, plane, criterion, i, |cap| neighbours.count_flagged_up_to(&flags[k], cap))
        },
    )?;
    let mut is_edge = vec![false; n];
    for (i, edge) in answers.into_points() {
        is_edge[i] = edge;
    }
    Some(plates.map(|plate| plate.members.iter().copied().filter(|&i| is_edge[i as usize]).collect()))
}

/// The fast classification on a pixel grid ([`grid::edge_points`]),
/// handed the full-plane count the criterion names.
fn on_grid<const N: usize>(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    labels: &[u32],
    plate_labels: [u32; N],
    rows: std::ops::Range<usize>,
    criterion: &EdgeCriterion,
) -> [Vec<u32>; N] {
    let ratio = criterion.ratio;
    let counts = &plane.counts;
    match criterion.full {
        FullCount::Frontal => grid::edge_points(search, counts, labels, plate_labels, rows, ratio, &Frontal(search)),
        FullCount::Plane => {
            grid::edge_points(search, counts, labels, plate_labels, rows, ratio, &Measured(&plane.full))
        }
    }
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
    if !std::ptr::eq(a.labels, b.labels) || a.label == b.label {
        return plates.map(|p| edge_points(search, plane, p, criterion));
    }
    if !search.cloud().is_organized() {
        return by_cell(search, plane, plates, criterion)
            .unwrap_or_else(|| plates.map(|p| edge_points(search, plane, p, criterion)));
    }
    let rows = member_rows(search, [a.members, b.members]);
    on_grid(search, plane, a.labels, [a.label, b.label], rows, criterion)
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

/// `counted_edge` (the tests' reference), counting only until the count passes `ratio · N`:
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
    edge_by_count(search, plane, criterion, i, |cap| search.count_up_to(i, |j| plate.labels[j] == plate.label, cap))
}

/// Eq. 15 for a member `i` of a plate, given `count_up_to(cap)`, its count
/// of same-plate neighbours read up to `cap`: counted only until the
/// count passes `ratio · N`.
#[inline(always)]
fn edge_by_count(
    search: &NeighbourSearch,
    plane: &PlanePoints,
    criterion: &EdgeCriterion,
    i: usize,
    count_up_to: impl FnOnce(u32) -> u32,
) -> bool {
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
    count_up_to(cap) < cap
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::cloud::PointCloud;
    use crate::geometry::Vec3;
    use crate::pipeline::plane_points::{RobustPlaneCriterion, robust_criterion};

    /// A frontal plate at 600 mm covering columns below `cut` of a 50 x 30
    /// grid, with a few dropouts inside.
    pub(super) fn plate() -> PointCloud {
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

    pub(super) fn setup(cloud: &PointCloud, search: &NeighbourSearch) -> (PlanePoints, Vec<u32>, Vec<u32>) {
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
    fn plates_spanning_some_rows_give_the_reference_s_edges() {
        // The plate cut into two across its rows, 17 rows above and 13
        // below: each plate's rows are read alone, and together.
        let camera = CameraModel::default();
        let cloud = plate();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let tree = NeighbourSearch::kdtree(&cloud, &camera, 1.0);
        let (plane, mut labels, members) = setup(&cloud, &search);
        let width = cloud.width() as u32;
        for &i in &members {
            labels[i as usize] = u32::from(i / width >= 17);
        }
        let of = |label: u32| members.iter().copied().filter(|&i| labels[i as usize] == label).collect::<Vec<_>>();
        let (upper, lower) = (of(0), of(1));
        let plates = [
            Plate { labels: &labels, label: 0, members: &upper },
            Plate { labels: &labels, label: 1, members: &lower },
        ];
        let criterion = EdgeCriterion { full: FullCount::Plane, ratio: 0.75 };
        let together = edge_points_of_plates(&search, &plane, plates, &criterion);
        for (k, plate) in plates.into_iter().enumerate() {
            let expected = reference(&tree, &plane, plate, &criterion);
            assert!(!expected.is_empty(), "plate {k}");
            assert_eq!(edge_points(&search, &plane, plate, &criterion), expected, "plate {k} alone");
            assert_eq!(together[k], expected, "plate {k} beside the other");
        }
    }

    #[test]
    fn by_cell_classification_answers_as_the_reference() {
        // The plate as a cloud without a grid, split into two plates by
        // column and a few points left to neither.
        let camera = CameraModel::default();
        let grid = plate();
        let cloud = PointCloud::unorganized(grid.points().iter().copied().filter(|p| p[0].is_finite()).collect());
        for radius in [1.0, 2.5] {
            let search = NeighbourSearch::new(&cloud, &camera, radius);
            let (plane, _, _) = setup(&cloud, &search);
            let labels: Vec<u32> = (0..cloud.len())
                .map(|i| {
                    let x = cloud.points()[i][0];
                    if i % 13 == 4 {
                        u32::MAX
                    } else if x < -1.0 {
                        3
                    } else {
                        5
                    }
                })
                .collect();
            let members =
                |l: u32| -> Vec<u32> { (0..cloud.len() as u32).filter(|&i| labels[i as usize] == l).collect() };
            let (a, b) = (members(3), members(5));
            let plates =
                [Plate { labels: &labels, label: 3, members: &a }, Plate { labels: &labels, label: 5, members: &b }];
            for criterion in [
                EdgeCriterion { full: FullCount::Plane, ratio: 0.75 },
                EdgeCriterion { full: FullCount::Frontal, ratio: 0.5 },
            ] {
                let expected = plates.map(|p| reference(&search, &plane, p, &criterion));
                assert!(expected.iter().all(|e| !e.is_empty()), "edges to find at radius {radius}");
                assert_eq!(edge_points_of_plates(&search, &plane, plates, &criterion), expected, "both at once");
                assert_eq!(plates.map(|p| edge_points(&search, &plane, p, &criterion)), expected, "one by one");
            }
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
