//! Clouds without a pixel grid, end to end through `Planner::plan`: the
//! Euclidean clustering, the tree-based neighbour search and the boundary
//! samples taken from RANSAC inliers all run here, where an organized
//! frame never takes them. A PLY file of the same points goes through
//! `cloud::load` to the same plan.

use weldseam::camera::CameraModel;
use weldseam::cloud::{PointCloud, ply};
use weldseam::config::Config;
use weldseam::eval::seam_error;
use weldseam::joint::JointType;
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::sim::{demo_scene, simulate};

/// The valid points of a window of `cloud` around the true seam, `margin`
/// pixels beyond the seam's ends on every side, as a bag of points.
fn unorganized_window(cloud: &PointCloud, camera: &CameraModel, ends: [&nalgebra::Vector3<f64>; 2]) -> PointCloud {
    let [a, b] = ends.map(|p| camera.project(p).expect("the seam is in front of the camera"));
    let margin = 60.0;
    let (u0, u1) = ((a.0.min(b.0) - margin).max(0.0) as usize, (a.0.max(b.0) + margin) as usize);
    let (v0, v1) = ((a.1.min(b.1) - margin).max(0.0) as usize, (a.1.max(b.1) + margin) as usize);
    let mut points = Vec::new();
    for row in v0..v1.min(cloud.height()) {
        for col in u0..u1.min(cloud.width()) {
            if let Some(p) = cloud.at(col, row) {
                points.push(*p);
            }
        }
    }
    PointCloud::unorganized(points)
}

#[test]
fn a_v_butt_seam_is_planned_from_an_unorganized_cloud_and_its_ply_file() {
    let camera = CameraModel::default();
    let spec = demo_scene(JointType::VButt);
    let sim = simulate(&spec, &camera);
    let cloud = unorganized_window(&sim.cloud, &camera, [&sim.truth.start_camera, &sim.truth.end_camera]);
    assert!(!cloud.is_organized() && cloud.len() > 50_000, "{} points", cloud.len());

    let planner = Planner::new(Config::default());
    let request = PlanRequest::new(JointType::VButt, spec.joint.groove_depth_mm(), sim.pose);
    let plan = planner.plan(&cloud, &request).expect("the unorganized cloud plans");
    let err = seam_error(&sim.truth, &plan.seams[0]).expect("waypoints");
    assert!(err.max_mm < 1.0, "max error {:.3} mm", err.max_mm);
    assert!(plan.stats.clusters >= 2, "Euclidean clustering found the plates: {:?}", plan.stats);

    let mut bytes = Vec::new();
    ply::write_binary_le(&cloud, &mut bytes).expect("write PLY");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("window.ply");
    std::fs::write(&path, &bytes).unwrap();
    let loaded = weldseam::cloud::load(&path).expect("read PLY");
    assert_eq!(loaded, cloud, "the PLY file holds the same points");
    let from_file = planner.plan(&loaded, &request).expect("the PLY file plans");
    assert_eq!(from_file.seams, plan.seams, "the same plan from the file");
}
