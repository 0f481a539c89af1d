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

use crate::cloud::PointCloud;

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

/// Returns the members of `plate` that are edge points (Eq. 15).
///
/// On a pixel grid most members are settled without counting: the plane
/// criterion's count is a lower bound of a point's neighbours, and at most
/// the window's non-members (a summed-area table lookup) are not of its
/// plate, so when that bound exceeds `ratio · N` the point is no edge. Only
/// the rest are counted, exactly.
pub fn edge_points(search: &NeighbourSearch, plane: &PlanePoints, plate: Plate, criterion: &EdgeCriterion) -> Vec<u32> {
    let cloud = search.cloud();
    let camera = search.camera();
    let points = cloud.points();
    let radius = search.radius_mm();
    let Plate { labels, label, members } = plate;
    let full = |i: usize| criterion.full.of(search, plane, i);
    let is_edge = |i: usize| search.count(i, |j| labels[j] == label) as f64 <= criterion.ratio * full(i);
    if !cloud.is_organized() {
        return members.par_iter().copied().filter(|&i| is_edge(i as usize)).collect();
    }
    let outside = &OutsideCounts::new(cloud, labels, label);
    let (is_edge, full) = (&is_edge, &full);
    let (w, h) = (cloud.width(), cloud.height());
    // The widest the window of a point at depth z can be anywhere in the
    // image: a window at least as large as a point's own only weakens the
    // lower bound below, so one per row serves every member of the row.
    let corner = |half: f64, f: f64| (1.0 + (half / f) * (half / f)).sqrt();
    let (kx, ky) = (corner(w as f64, camera.fx()), corner(h as f64, camera.fy()));
    let row_window = |z_min: f64| -> (usize, usize) {
        if z_min <= radius * 1.001 {
            return (w, h);
        }
        let reach = radius / (z_min - radius);
        let span = |f: f64, k: f64| crate::geometry::ceil_i64(f * reach * k).max(0) as usize;
        (span(camera.fx(), kx), span(camera.fy(), ky))
    };
    (0..h)
        .into_par_iter()
        .flat_map_iter(|row| {
            let line = row * w..(row + 1) * w;
            let z_min =
                line.clone().filter(|&i| labels[i] == label).map(|i| points[i][2] as f64).fold(f64::MAX, f64::min);
            let (wx, wy) = if z_min < f64::MAX { row_window(z_min) } else { (0, 0) };
            line.filter(move |&i| labels[i] == label)
                .filter(move |&i| {
                    // At most the window's non-members are not of this plate.
                    let lower_bound = plane.counts[i] as i64 - outside.in_window(i, wx, wy) as i64;
                    lower_bound as f64 <= criterion.ratio * full(i) && is_edge(i)
                })
                .map(|i| i as u32)
                .collect::<Vec<u32>>()
        })
        .collect()
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

/// Summed-area table of the pixels that are not members of one plate.
struct OutsideCounts {
    width: usize,
    height: usize,
    table: Vec<u32>,
}

impl OutsideCounts {
    fn new(cloud: &PointCloud, labels: &[u32], label: u32) -> Self {
        let (w, h) = (cloud.width(), cloud.height());
        let mut table = vec![0u32; (w + 1) * (h + 1)];
        // Row prefix sums in parallel, then each row adds the one above.
        table[w + 1..].par_chunks_mut(w + 1).enumerate().for_each(|(r, out)| {
            let mut row_sum = 0u32;
            for (c, cell) in out[1..].iter_mut().enumerate() {
                row_sum += (labels[r * w + c] != label) as u32;
                *cell = row_sum;
            }
        });
        for r in 1..h {
            let (above, rest) = table[r * (w + 1)..].split_at_mut(w + 1);
            for (cell, up) in rest[..w + 1].iter_mut().zip(above.iter()) {
                *cell += up;
            }
        }
        OutsideCounts { width: w, height: h, table }
    }

    /// Non-members in the window of half-size `(wx, wy)` around pixel `i`.
    fn in_window(&self, i: usize, wx: usize, wy: usize) -> u32 {
        let (col, row) = (i % self.width, i / self.width);
        let (c0, c1) = (col.saturating_sub(wx), (col + wx + 1).min(self.width));
        let (r0, r1) = (row.saturating_sub(wy), (row + wy + 1).min(self.height));
        let at = |r: usize, c: usize| self.table[r * (self.width + 1) + c];
        // Pixels beyond the border are no neighbours, so the clipped
        // window's count is what the lower bound needs.
        at(r1, c1) + at(r0, c0) - at(r0, c1) - at(r1, c0)
    }
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
}
