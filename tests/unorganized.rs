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
use weldseam::sim::{Draw, demo_scene};

use crate::scenes;

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
    let sim = scenes::rendered(&spec, &camera);
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

/// The valid points of an organized frame in a shuffled order, as a raw
/// camera export without its grid would hold them (a fixed shuffle: a
/// splitmix sequence drives Fisher-Yates).
fn shuffled_export(cloud: &PointCloud, seed: u64) -> PointCloud {
    let mut points: Vec<[f32; 3]> = cloud.points().iter().copied().filter(|p| p[0].is_finite()).collect();
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    for i in (1..points.len()).rev() {
        points.swap(i, (next() % (i as u64 + 1)) as usize);
    }
    PointCloud::unorganized(points)
}

#[test]
fn every_eval_scene_exported_without_its_grid_plans_digit_for_digit_as_the_frame() {
    let camera = CameraModel::default();
    let planner = Planner::new(Config::default());
    // Every sixth scene: each joint at near, middle and far standoffs and
    // several tilts, within the suite's time budget; the whole suite is
    // planned this way by `weldseam eval --variant unorganized`.
    for (k, (name, spec)) in weldseam::sim::suite::eval_suite(Draw::Documented).into_iter().enumerate().step_by(6) {
        let sim = scenes::rendered(&spec, &camera);
        let export = shuffled_export(&sim.cloud, k as u64);
        let (grid, _) = weldseam::pipeline::regrid::regrid(&export, &camera).expect("a raw export is re-gridded");
        let differ: Vec<usize> = (0..grid.len())
            .filter(|&i| grid.points()[i].map(f32::to_bits) != sim.cloud.points()[i].map(f32::to_bits))
            .collect();
        assert!(
            differ.is_empty(),
            "{name}: {} pixels differ, first {:?}",
            differ.len(),
            differ.iter().take(3).map(|&i| (i, grid.points()[i], sim.cloud.points()[i])).collect::<Vec<_>>()
        );
        let request = PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose);
        let frame = planner.plan(&sim.cloud, &request).map(|p| (p.seams, p.stats));
        let exported = planner.plan(&export, &request).map(|p| (p.seams, p.stats));
        assert_eq!(exported, frame, "{name}");
    }
}

#[test]
fn downsampled_merged_decimated_and_moved_clouds_keep_the_unorganized_path() {
    use weldseam::pipeline::regrid::{NotARawFrame, regrid};
    let camera = CameraModel::default();
    let sim = scenes::rendered(&demo_scene(JointType::VButt), &camera);
    let valid = || sim.cloud.points().iter().copied().filter(|p| p[0].is_finite());

    // Voxel-downsampled at 1 mm: one centroid per occupied voxel.
    let mut voxels: std::collections::BTreeMap<[i64; 3], ([f64; 3], f64)> = Default::default();
    for p in valid() {
        let key = p.map(|c| (c as f64).floor() as i64);
        let e = voxels.entry(key).or_insert(([0.0; 3], 0.0));
        (0..3).for_each(|i| e.0[i] += p[i] as f64);
        e.1 += 1.0;
    }
    let centroids = voxels.values().map(|(s, n)| s.map(|c| (c / n) as f32)).collect();
    let e = regrid(&PointCloud::unorganized(centroids), &camera).unwrap_err();
    assert!(matches!(e, NotARawFrame::OffGrid { .. }), "{e}");

    // Two views merged: the same camera's frame twice, the second one
    // measured again (its depths 0.05 mm farther).
    let merged = valid().chain(valid().step_by(100).map(|p| p.map(|c| c * (1.0 + 0.05 / p[2])))).collect();
    let e = regrid(&PointCloud::unorganized(merged), &camera).unwrap_err();
    assert!(matches!(e, NotARawFrame::Collisions { .. }), "{e}");

    // Every second row and column kept.
    let mut decimated = Vec::new();
    for row in (0..sim.cloud.height()).step_by(2) {
        for col in (0..sim.cloud.width()).step_by(2) {
            decimated.extend(sim.cloud.at(col, row).copied());
        }
    }
    let e = regrid(&PointCloud::unorganized(decimated), &camera).unwrap_err();
    assert!(matches!(e, NotARawFrame::Sparse { .. } | NotARawFrame::Scattered { .. }), "{e}");

    // Moved 0.1 mm sideways (another frame, or another camera's
    // intrinsics): off the pixel centres.
    let moved = valid().map(|p| [p[0] + 0.1, p[1], p[2]]).collect();
    let e = regrid(&PointCloud::unorganized(moved), &camera).unwrap_err();
    assert!(matches!(e, NotARawFrame::OffGrid { .. }), "{e}");
}
