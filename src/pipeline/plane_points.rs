//! The plane point criterion (section 3.2): which points lie inside a
//! plane, as opposed to on edges, side faces, holes or outliers.
//!
//! The paper's criterion (Eq. 14) keeps a point when its neighbour count
//! within R reaches `N'min` of Eq. 13, a frontal plane's count at the
//! point's depth less the accuracy margin. It misjudges tilted plates
//! (their density is about `cos θ` of the frontal one) and ignores that a
//! pixel grid's count differs from `π R² D` by up to 15 %. The robust
//! criterion compares the count with what a complete plane of the
//! workpiece's orientation gives at that very pixel, and also requires the
//! local normal to agree with the workpiece's, which no count can check.

use rayon::prelude::*;

use crate::camera::CameraModel;
use crate::cloud::PointCloud;
use crate::geometry::Vec3;

use super::neighbours::NeighbourSearch;
use super::orientation::{local_normal, normal_step};

/// Eq. 14: `P` is a plane point when `N_r >= N'min(L)`, with `L` the
/// point's depth z (Eq. 13).
pub fn paper_criterion(cloud: &PointCloud, camera: &CameraModel, search: &NeighbourSearch) -> Vec<bool> {
    let radius = search.radius_mm();
    let points = cloud.points();
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            let p = &points[i];
            if !p[0].is_finite() {
                return false;
            }
            let threshold = camera.min_plane_neighbours(radius, p[2] as f64);
            search.count(i, |_| true) as f64 >= threshold
        })
        .collect()
}

/// Settings of the robust criterion.
#[derive(Debug, Clone, Copy)]
pub struct RobustPlaneCriterion {
    /// The workpiece's dominant unit normal, facing away from the camera.
    pub normal: Vec3,
    /// Least fraction of the full-plane neighbour count.
    pub min_ratio: f64,
    /// Largest angle between the local and the dominant normal, degrees.
    pub max_angle_deg: f64,
}

/// The robust plane criterion: `N_r >= ratio · N_plane(p)` where
/// `N_plane` is the lattice count of a complete plane with the dominant
/// normal through `p`, and the local normal within the angle limit.
pub fn robust_criterion(
    cloud: &PointCloud,
    camera: &CameraModel,
    search: &NeighbourSearch,
    criterion: &RobustPlaneCriterion,
) -> Vec<bool> {
    let points = cloud.points();
    let cos_limit = criterion.max_angle_deg.to_radians().cos();
    let radius = search.radius_mm();
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            let p = &points[i];
            if !p[0].is_finite() {
                return false;
            }
            let step = normal_step(camera.fx(), p[2] as f64, radius);
            let facing = local_normal(cloud, search, i, step).is_some_and(|n| n.dot(&criterion.normal) >= cos_limit);
            if !facing {
                return false;
            }
            let full = search.full_plane_count(i, &criterion.normal);
            full > 0.0 && search.count(i, |_| true) as f64 >= criterion.min_ratio * full
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plate at depth `z` tilted by `tilt_deg` about the image y axis, on
    /// columns below `plate_cols`, and a steep bevel after it.
    fn scene(z: f64, tilt_deg: f64, plate_cols: usize) -> (PointCloud, Vec3) {
        let camera = CameraModel::default();
        let (w, h) = (60, 40);
        let t = tilt_deg.to_radians();
        let n = Vec3::new(t.sin(), 0.0, t.cos());
        let bevel = Vec3::new((t - 1.0).sin(), 0.0, (t - 1.0).cos());
        let anchor = Vec3::new(0.0, 0.0, z);
        let mut pts = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(camera.cx() - 30.0 + col as f64, camera.cy() - 20.0 + row as f64);
                let r = Vec3::new(r[0], r[1], r[2]);
                let m = if col < plate_cols { n } else { bevel };
                let q = r * (m.dot(&anchor) / m.dot(&r));
                pts.push([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        (PointCloud::organized(w, h, pts).unwrap(), n)
    }

    #[test]
    fn paper_criterion_loses_a_tilted_plate_that_the_robust_one_keeps() {
        let camera = CameraModel::default();
        let (cloud, n) = scene(900.0, 35.0, 60);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let centre = 20 * 60 + 30;
        let paper = paper_criterion(&cloud, &camera, &search);
        assert!(!paper[centre], "foreshortening drops the paper's count below N'min");
        let robust = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
        assert!(robust_criterion(&cloud, &camera, &search, &robust)[centre]);
    }

    #[test]
    fn robust_criterion_rejects_a_bevel_face_and_keeps_the_plate() {
        let camera = CameraModel::default();
        let (cloud, n) = scene(600.0, 10.0, 30);
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        let robust = RobustPlaneCriterion { normal: n, min_ratio: 0.8, max_angle_deg: 20.0 };
        let mask = robust_criterion(&cloud, &camera, &search, &robust);
        assert!(mask[20 * 60 + 10], "plate interior");
        assert!(!mask[20 * 60 + 50], "bevel interior");
    }

    #[test]
    fn invalid_points_are_never_plane_points() {
        let camera = CameraModel::default();
        let cloud = PointCloud::organized(3, 3, vec![[f32::NAN; 3]; 9]).unwrap();
        let search = NeighbourSearch::new(&cloud, &camera, 1.0);
        assert!(paper_criterion(&cloud, &camera, &search).iter().all(|&b| !b));
    }
}
