//! The region of interest through `Planner::plan` and the command line:
//! clutter outside the box is as good as absent, a base-frame box crops
//! the points the pose and hand-eye place inside it, and boxes that are
//! not boxes, or keep too few points, are refused by name.

use std::process::Command;

use nalgebra::Point3;
use weldseam::cloud::{INVALID_POINT, PointCloud};
use weldseam::config::Config;
use weldseam::eval::seam_error;
use weldseam::geometry::Vec3;
use weldseam::joint::JointType;
use weldseam::pipeline::roi::Roi;
use weldseam::pipeline::{CloudFrame, Plan, PlanRequest, Planner, Stage};
use weldseam::sim::Simulation;

use crate::scenes;

fn lap() -> &'static Simulation {
    scenes::demo(JointType::Lap)
}

/// A camera-frame box around the true seam, `margin` mm beyond it.
fn seam_box(sim: &Simulation, margin: f64) -> Roi {
    let (a, b) = (sim.truth.start_camera, sim.truth.end_camera);
    let m = Vec3::new(margin, margin, margin);
    Roi::new((a.inf(&b) - m).into(), (a.sup(&b) + m).into(), CloudFrame::Camera).unwrap()
}

fn inside(roi: &Roi, p: &Point3<f64>) -> bool {
    (0..3).all(|k| roi.min()[k] <= p[k] && p[k] <= roi.max()[k])
}

/// `cloud` with each valid point `f` returns None for made invalid, and
/// the others replaced.
fn mapped(cloud: &PointCloud, f: impl Fn(Point3<f64>) -> Option<Point3<f64>>) -> PointCloud {
    let points = cloud
        .points()
        .iter()
        .map(|p| {
            if !p[0].is_finite() {
                return INVALID_POINT;
            }
            f(Point3::new(p[0].into(), p[1].into(), p[2].into()))
                .map_or(INVALID_POINT, |q| [q.x as f32, q.y as f32, q.z as f32])
        })
        .collect();
    PointCloud::organized(cloud.width(), cloud.height(), points).unwrap()
}

fn plan(planner: &Planner, sim: &Simulation, cloud: &PointCloud, roi: Option<Roi>) -> Plan {
    let request = PlanRequest { roi, ..PlanRequest::new(JointType::Lap, None, sim.pose) };
    planner.plan(cloud, &request).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn clutter_outside_the_box_plans_as_the_clean_frame() {
    let sim = lap();
    let roi = seam_box(sim, 40.0);
    // Everything the camera sees outside the box is moved along its ray to
    // 300 mm: a large object between the camera and the workpiece.
    let cluttered = mapped(&sim.cloud, |p| Some(if inside(&roi, &p) { p } else { p * (300.0 / p.z) }));
    let planner = Planner::new(Config::default());
    let clean = plan(&planner, sim, &sim.cloud, None);
    let cropped = plan(&planner, sim, &cluttered, Some(roi));
    assert_eq!(cropped.stats.valid_points, plan(&planner, sim, &sim.cloud, Some(roi)).stats.valid_points);
    let error = seam_error(&sim.truth, &cropped.seams[0]).expect("waypoints");
    assert!(error.max_mm < 1.0, "worst error {:.3} mm", error.max_mm);
    let ends = |p: &Plan| {
        let w = &p.seams[0].waypoints;
        [w[0].position, w[w.len() - 1].position]
    };
    for (a, b) in ends(&cropped).iter().zip(ends(&clean)) {
        assert!((a - b).norm() < 0.5, "the cropped plan ends {:.2} mm from the clean one", (a - b).norm());
    }
}

#[test]
fn a_base_frame_box_crops_what_the_pose_and_hand_eye_place_inside_it() {
    let sim = lap();
    // The camera-frame seam box's corners in the base frame, and the
    // axis-aligned box around them there.
    let camera_box = seam_box(sim, 30.0);
    let corners: Vec<Point3<f64>> = (0..8)
        .map(|k| {
            let pick = |axis: usize| if k >> axis & 1 == 0 { camera_box.min()[axis] } else { camera_box.max()[axis] };
            sim.base_from_camera * Point3::new(pick(0), pick(1), pick(2))
        })
        .collect();
    let lo = corners.iter().fold(Vec3::repeat(f64::MAX), |m, c| m.inf(&c.coords));
    let hi = corners.iter().fold(Vec3::repeat(f64::MIN), |m, c| m.sup(&c.coords));
    let base_box = Roi::new(lo.into(), hi.into(), CloudFrame::Base).unwrap();
    // The same crop done by hand, through the simulation's own transform.
    let by_hand = mapped(&sim.cloud, |p| inside(&base_box, &(sim.base_from_camera * p)).then_some(p));
    let planner = Planner::new(Config::default());
    let boxed = plan(&planner, sim, &sim.cloud, Some(base_box));
    let expected = plan(&planner, sim, &by_hand, None);
    assert_eq!(boxed.seams, expected.seams);
    assert_eq!(boxed.stats, expected.stats);
    assert!(seam_error(&sim.truth, &boxed.seams[0]).expect("waypoints").max_mm < 1.0);
}

#[test]
fn the_configured_box_applies_unless_the_request_brings_its_own() {
    let sim = lap();
    let roi = seam_box(sim, 40.0);
    let mut config = Config::default();
    config.pipeline.roi = vec![roi.min().x, roi.min().y, roi.min().z, roi.max().x, roi.max().y, roi.max().z];
    let configured = Planner::new(config.clone());
    let from_config = plan(&configured, sim, &sim.cloud, None);
    let from_request = plan(&Planner::new(Config::default()), sim, &sim.cloud, Some(roi));
    assert_eq!(from_config.seams, from_request.seams);
    // A request's own box wins: one around a corner of the frame keeps
    // too few points, and says so with the box and the count.
    let corner = Roi::new([-1.0, -1.0, 0.0], [1.0, 1.0, 100.0], CloudFrame::Camera).unwrap();
    let request = PlanRequest { roi: Some(corner), ..PlanRequest::new(JointType::Lap, None, sim.pose) };
    let e = configured.plan(&sim.cloud, &request).unwrap_err();
    assert_eq!((e.rule.id, e.stage), ("frame.too_few_points_in_region", Stage::Input), "{e}");
    assert!(e.reason.contains("x -1..1, y -1..1, z 0..100 mm (camera frame) keeps 0 of"), "{}", e.reason);
    // A configured box that is not one is refused by its key.
    config.pipeline.roi = vec![0.0, 0.0, 0.0, 1.0, 1.0];
    let e = Planner::new(config).plan(&sim.cloud, &PlanRequest::new(JointType::Lap, None, sim.pose)).unwrap_err();
    assert_eq!(e.rule.id, "frame.region_of_interest_invalid", "{e}");
    assert!(e.reason.contains("pipeline.roi"), "{}", e.reason);
}

#[test]
fn bad_boxes_on_the_command_line_are_refused_naming_the_flag() {
    let run = |roi: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_weldseam"))
            .args(["plan", "--cloud", "absent.pcd", "--joint", "lap", "--pose=0,0,500,180,0,0", "--roi", roi])
            .output()
            .expect("run weldseam");
        assert!(!out.status.success(), "--roi {roi} was accepted");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let cases = [
        ("1,2,3", "--roi needs 6"),
        ("0,0,500,10,10,400", "z min (500 mm) must be below its max (400 mm)"),
        ("0,0,0,20000,1,1", "at most 10000 mm"),
        ("0,0,0,nan,1,1", "not finite"),
    ];
    for (roi, expected) in cases {
        let stderr = run(roi);
        assert!(stderr.contains(expected), "--roi {roi}: {stderr}");
    }
}
