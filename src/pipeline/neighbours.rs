//! Radius neighbour counts, the measurement behind the plane and edge
//! criteria (Eq. 14 and 15), and the count a full plane would give.
//!
//! Organized frames are searched on the pixel grid: every 3D neighbour
//! within R of a pixel's point lies inside a small image window around the
//! pixel ([`CameraModel::neighbour_window`]), so scanning that window gives
//! exactly the count a KD-tree query would. Unorganized clouds use a kiddo
//! KD-tree, which also serves as the reference the grid path is tested
//! against.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::camera::CameraModel;
use crate::cloud::{Point, PointCloud};
use crate::geometry::Vec3;

/// Finds the neighbours of cloud points within a fixed radius.
pub struct NeighbourSearch<'a> {
    cloud: &'a PointCloud,
    camera: &'a CameraModel,
    radius: f32,
    radius_sq: f32,
    tree: Option<KdIndex>,
}

struct KdIndex {
    tree: ImmutableKdTree<f32, 3>,
    /// Tree item → cloud point index.
    point_of_item: Vec<u32>,
}

/// True when `q` lies within the radius of `p`. One predicate for the grid
/// and the tree paths, so both classify ties identically.
#[inline(always)]
fn within(p: &Point, q: &Point, radius_sq: f32) -> bool {
    let dx = q[0] - p[0];
    let dy = q[1] - p[1];
    let dz = q[2] - p[2];
    dx * dx + dy * dy + dz * dz <= radius_sq
}

impl<'a> NeighbourSearch<'a> {
    /// Prepares a search with radius `radius_mm`. Builds a KD-tree only for
    /// unorganized clouds.
    pub fn new(cloud: &'a PointCloud, camera: &'a CameraModel, radius_mm: f64) -> Self {
        let radius = radius_mm as f32;
        let tree = (!cloud.is_organized()).then(|| build_tree(cloud.points()));
        NeighbourSearch { cloud, camera, radius, radius_sq: radius * radius, tree }
    }

    pub fn radius_mm(&self) -> f64 {
        self.radius as f64
    }

    /// Calls `visit(j)` for every valid point `j` within the radius of
    /// point `i` (including `i` itself). `i` must be valid.
    #[inline]
    pub fn for_each(&self, i: usize, mut visit: impl FnMut(usize)) {
        let points = self.cloud.points();
        let p = &points[i];
        match &self.tree {
            None => {
                let w = self.cloud.width();
                let (col, row) = (i % w, i / w);
                let (wx, wy) = self.camera.neighbour_window(*p, self.radius as f64);
                let (c0, c1) = (col.saturating_sub(wx), (col + wx).min(w - 1));
                let (r0, r1) = (row.saturating_sub(wy), (row + wy).min(self.cloud.height() - 1));
                for r in r0..=r1 {
                    let line = &points[r * w..(r + 1) * w];
                    for (c, q) in line.iter().enumerate().take(c1 + 1).skip(c0) {
                        // NaN compares false, so invalid pixels never count.
                        if within(p, q, self.radius_sq) {
                            visit(r * w + c);
                        }
                    }
                }
            }
            Some(index) => {
                // The tree gives candidates; the shared predicate decides.
                let reach = self.radius_sq * (1.0 + 1e-5);
                let found = index.tree.query(p).within::<SquaredEuclidean<f32>>(reach).unsorted().execute();
                for hit in found {
                    let j = index.point_of_item[hit.item as usize] as usize;
                    if within(p, &points[j], self.radius_sq) {
                        visit(j);
                    }
                }
            }
        }
    }

    /// Number of valid points within the radius of point `i` for which
    /// `member(j)` holds.
    #[inline]
    pub fn count(&self, i: usize, member: impl Fn(usize) -> bool) -> u32 {
        let mut n = 0;
        self.for_each(i, |j| n += member(j) as u32);
        n
    }

    /// The number of neighbours point `i` would have if the surface were a
    /// complete plane with unit normal `n` through it, as sampled by this
    /// camera: the theoretical count of Eq. 6, corrected for the plane's
    /// tilt and, on a pixel grid, for the grid itself.
    pub fn full_plane_count(&self, i: usize, n: &Vec3) -> f64 {
        let p = self.cloud.points()[i];
        let pv = Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        let r = self.radius as f64;
        if self.tree.is_some() {
            return std::f64::consts::PI * r * r * self.camera.plane_density_at([pv.x, pv.y, pv.z], [n.x, n.y, n.z]);
        }
        lattice_count_in_ellipse(self.camera, &pv, n, r)
    }
}

fn build_tree(points: &[Point]) -> KdIndex {
    let mut coords = Vec::with_capacity(points.len());
    let mut point_of_item = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        if p[0].is_finite() {
            coords.push(*p);
            point_of_item.push(i as u32);
        }
    }
    let tree = ImmutableKdTree::new_from_slice(&coords).unwrap_or_else(|_| {
        // Only an empty slice fails; an empty tree answers every query with nothing.
        ImmutableKdTree::new_from_slice(&[[f32::MAX; 3]]).expect("a one-point tree always builds")
    });
    KdIndex { tree, point_of_item }
}

/// Counts the pixel offsets `(du, dv)` whose rays meet the plane through
/// `p` with normal `n` within `radius` of `p`.
///
/// Near `p` the plane maps pixel offsets linearly to 3D displacements,
/// `d ≈ J (du, dv)`, so the offsets within the radius are the lattice points
/// inside the ellipse `(du, dv)ᵀ JᵀJ (du, dv) <= R²`, counted row by row.
/// This is what a pixel grid really gives; `π R² D` can be 15 % off it.
pub fn lattice_count_in_ellipse(camera: &CameraModel, p: &Vec3, n: &Vec3, radius: f64) -> f64 {
    let z = p.z;
    let ray = Vec3::new(p.x / z, p.y / z, 1.0);
    let n_dot_ray = n.dot(&ray);
    if n_dot_ray.abs() < 1e-6 {
        return 0.0;
    }
    // ∂q/∂u and ∂q/∂v of q(u, v) = (n·p)/(n·r(u, v)) r(u, v) at p.
    let eu = Vec3::new(1.0 / camera.fx(), 0.0, 0.0);
    let ev = Vec3::new(0.0, 1.0 / camera.fy(), 0.0);
    let ju = (eu - ray * (n.dot(&eu) / n_dot_ray)) * z;
    let jv = (ev - ray * (n.dot(&ev) / n_dot_ray)) * z;
    let (a, b, c) = (ju.dot(&ju), ju.dot(&jv), jv.dot(&jv));
    let det = a * c - b * b;
    if det <= 0.0 {
        return 0.0;
    }
    let r2 = radius * radius;
    let dv_max = (r2 * a / det).sqrt().floor() as i64;
    let mut count = 0i64;
    for dv in -dv_max..=dv_max {
        let dv = dv as f64;
        let disc = b * b * dv * dv - a * (c * dv * dv - r2);
        if disc < 0.0 {
            continue;
        }
        let s = disc.sqrt();
        let lo = ((-b * dv - s) / a).ceil() as i64;
        let hi = ((-b * dv + s) / a).floor() as i64;
        count += (hi - lo + 1).max(0);
    }
    count as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frontal plane at depth z sampled by the camera, with an optional
    /// hole of invalid pixels for columns >= `cut`.
    fn plane_cloud(camera: &CameraModel, w: usize, h: usize, z: f64, n: Vec3, cut: usize) -> PointCloud {
        let mut pts = Vec::with_capacity(w * h);
        let (u0, v0) = (camera.cx() - w as f64 / 2.0, camera.cy() - h as f64 / 2.0);
        let anchor = Vec3::new(0.0, 0.0, z);
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(u0 + col as f64, v0 + row as f64);
                let r = Vec3::new(r[0], r[1], r[2]);
                let t = n.dot(&anchor) / n.dot(&r);
                let q = r * t;
                pts.push(if col >= cut { [f32::NAN; 3] } else { [q.x as f32, q.y as f32, q.z as f32] });
            }
        }
        PointCloud::organized(w, h, pts).unwrap()
    }

    #[test]
    fn grid_counts_equal_kdtree_counts() {
        let camera = CameraModel::default();
        let n = Vec3::new(0.3, 0.2, 1.0).normalize();
        let cloud = plane_cloud(&camera, 40, 30, 520.0, n, 31);
        let flat = PointCloud::unorganized(cloud.points().to_vec());
        let grid = NeighbourSearch::new(&cloud, &camera, 1.0);
        let tree = NeighbourSearch::new(&flat, &camera, 1.0);
        // The flat cloud dropped invalid points; map indices through valid order.
        let valid: Vec<usize> = (0..cloud.len()).filter(|&i| cloud.points()[i][0].is_finite()).collect();
        for (k, &i) in valid.iter().enumerate() {
            assert_eq!(grid.count(i, |_| true), tree.count(k, |_| true), "point {i}");
        }
    }

    #[test]
    fn lattice_count_predicts_interior_counts_exactly() {
        let camera = CameraModel::default();
        for (z, n) in [
            (500.0, Vec3::z()),
            (900.0, Vec3::new(0.5, 0.0, 1.0).normalize()),
            (700.0, Vec3::new(-0.2, 0.4, 1.0).normalize()),
        ] {
            let cloud = plane_cloud(&camera, 41, 41, z, n, usize::MAX);
            let search = NeighbourSearch::new(&cloud, &camera, 1.0);
            let centre = 20 * 41 + 20;
            let actual = search.count(centre, |_| true) as f64;
            let expected = search.full_plane_count(centre, &n);
            assert!((actual - expected).abs() <= 1.0, "z {z}: actual {actual}, lattice {expected}");
        }
    }

    #[test]
    fn edge_points_see_about_half_the_plane() {
        let camera = CameraModel::default();
        let cloud = plane_cloud(&camera, 41, 41, 600.0, Vec3::z(), 21);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let edge = 20 * 41 + 20;
        let ratio = search.count(edge, |_| true) as f64 / search.full_plane_count(edge, &Vec3::z());
        assert!((0.45..0.65).contains(&ratio), "{ratio}");
    }

    #[test]
    fn members_filter_the_count() {
        let camera = CameraModel::default();
        let cloud = plane_cloud(&camera, 21, 21, 600.0, Vec3::z(), usize::MAX);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let all = search.count(220, |_| true);
        let left = search.count(220, |j| j % 21 <= 10);
        assert!(left < all && left > all / 3);
    }
}
