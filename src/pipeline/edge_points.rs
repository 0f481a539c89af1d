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

use crate::camera::CameraModel;
use crate::cloud::PointCloud;
use crate::geometry::Vec3;

use super::neighbours::NeighbourSearch;

/// How the full count `N` of Eq. 15 is obtained.
#[derive(Debug, Clone, Copy)]
pub enum FullCount {
    /// Eq. 6 at the point's depth: the paper.
    Frontal,
    /// The lattice count of a plane with this normal through the point.
    Plane(Vec3),
}

/// The edge criterion's settings.
#[derive(Debug, Clone, Copy)]
pub struct EdgeCriterion {
    pub full: FullCount,
    /// A point is an edge point when `N_r <= ratio · N`.
    pub ratio: f64,
    /// True when `ratio · N` lies below the plane criterion's threshold, so
    /// a member whose whole search window holds only members of its plate
    /// cannot be an edge point and may be skipped (see [`edge_points`]).
    pub safe_interior: bool,
}

/// Returns the members of plate `label` (`plate` lists its indices in the
/// cloud, all with `labels[i] == label`) that are edge points.
///
/// On a pixel grid, when the criterion allows it, members whose window
/// holds no non-member are skipped with a summed-area table instead of
/// counted: their count equals the plane criterion's, which passed.
pub fn edge_points(
    cloud: &PointCloud,
    camera: &CameraModel,
    search: &NeighbourSearch,
    labels: &[u32],
    label: u32,
    plate: &[u32],
    criterion: &EdgeCriterion,
) -> Vec<u32> {
    let EdgeCriterion { full, ratio, safe_interior } = *criterion;
    let points = cloud.points();
    let radius = search.radius_mm();
    let outside = (safe_interior && cloud.is_organized()).then(|| OutsideCounts::new(cloud, labels, label));
    plate
        .par_iter()
        .copied()
        .filter(|&i| {
            let i = i as usize;
            let p = points[i];
            if let Some(outside) = &outside {
                let (wx, wy) = camera.neighbour_window(p, radius);
                if outside.in_window(i, wx, wy) == 0 {
                    return false;
                }
            }
            let n = match full {
                FullCount::Frontal => camera.theoretical_neighbours(radius, p[2] as f64),
                FullCount::Plane(normal) => search.full_plane_count(i, &normal),
            };
            let nr = search.count(i, |j| labels[j] == label);
            nr as f64 <= ratio * n
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
        for r in 0..h {
            let mut row_sum = 0u32;
            for c in 0..w {
                row_sum += (labels[r * w + c] != label) as u32;
                table[(r + 1) * (w + 1) + c + 1] = table[r * (w + 1) + c + 1] + row_sum;
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
        // A window clipped by the image border counts as touching outside.
        let clipped = (col < wx || row < wy || col + wx >= self.width || row + wy >= self.height) as u32;
        at(r1, c1) + at(r0, c0) - at(r0, c1) - at(r1, c0) + clipped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frontal plate at 600 mm covering columns below `cut` of a 50 x 30 grid.
    fn plate() -> (PointCloud, Vec<u32>, Vec<u32>) {
        let camera = CameraModel::default();
        let (w, h, cut) = (50, 30, 30);
        let mut pts = Vec::new();
        let mut labels = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(camera.cx() - 25.0 + col as f64, camera.cy() - 15.0 + row as f64);
                if col < cut {
                    pts.push([(r[0] * 600.0) as f32, (r[1] * 600.0) as f32, 600.0]);
                    labels.push(0);
                } else {
                    pts.push([f32::NAN; 3]);
                    labels.push(super::super::clustering::UNCLUSTERED);
                }
            }
        }
        let members = (0..(w * h) as u32).filter(|&i| labels[i as usize] == 0).collect();
        (PointCloud::organized(w, h, pts).unwrap(), labels, members)
    }

    #[test]
    fn robust_threshold_finds_the_straight_edge_that_half_misses() {
        let camera = CameraModel::default();
        let (cloud, labels, members) = plate();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let on_edge_row = |pts: &[u32]| pts.iter().filter(|&&i| i / 50 == 15).map(|&i| i % 50).collect::<Vec<_>>();
        let robust = edge_points(
            &cloud,
            &camera,
            &search,
            &labels,
            0,
            &members,
            &EdgeCriterion { full: FullCount::Plane(Vec3::z()), ratio: 0.75, safe_interior: true },
        );
        let cols = on_edge_row(&robust);
        assert!(cols.contains(&29), "the last column is an edge: {cols:?}");
        // Columns 0 and 1 touch the grid's border, which is an edge too.
        assert!(cols.iter().all(|&c| c <= 1 || c >= 27), "interior points are not edges: {cols:?}");
        let paper = edge_points(
            &cloud,
            &camera,
            &search,
            &labels,
            0,
            &members,
            &EdgeCriterion { full: FullCount::Frontal, ratio: 0.5, safe_interior: true },
        );
        assert!(on_edge_row(&paper).len() < cols.len());
    }

    #[test]
    fn summed_area_shortcut_changes_nothing() {
        let camera = CameraModel::default();
        let (cloud, labels, members) = plate();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let full = FullCount::Plane(Vec3::z());
        let fast = edge_points(
            &cloud,
            &camera,
            &search,
            &labels,
            0,
            &members,
            &EdgeCriterion { full, ratio: 0.75, safe_interior: true },
        );
        let slow = edge_points(
            &cloud,
            &camera,
            &search,
            &labels,
            0,
            &members,
            &EdgeCriterion { full, ratio: 0.75, safe_interior: false },
        );
        assert_eq!(fast, slow);
    }
}
