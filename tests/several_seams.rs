//! Issue 15's frames through the planner as it is: tee joints, which it
//! does not plan, are refused (by name wherever the groove probe sees the
//! web standing between the flange's two sides), and a frame of several
//! workpieces carries the truth of every seam, where the rendered returns
//! show it.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::names_a_tee;
use weldseam::geometry::Vec3;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::quality::Gate;
use weldseam::pipeline::{PlanError, PlanRequest, Planner, Stage};
use weldseam::sim::{JointGeometry, SceneSpec, demo_scene, multi_suite, simulate, tee_suite};

fn plan_tee(spec: &SceneSpec, joint: RequestedJoint) -> Result<usize, PlanError> {
    let sim = simulate(spec, &CameraModel::default());
    let depth = (joint == RequestedJoint::Type(JointType::VButt)).then_some(5.0);
    Planner::new(Config::default()).plan(&sim.cloud, &PlanRequest::new(joint, depth, sim.pose)).map(|p| p.seams.len())
}

#[test]
fn a_tee_request_is_refused_as_not_planned_yet() {
    let err = plan_tee(&demo_scene(JointType::TFillet), JointType::TFillet.into()).unwrap_err();
    assert_eq!(err.stage, Stage::Request);
    assert!(err.reason.contains("t_fillet planning is not built yet"), "{err}");
}

#[test]
fn a_tee_seen_as_a_butt_joint_or_auto_is_refused_by_name() {
    // The demo tee and three suite tees the camera sees from either side.
    let suite = tee_suite();
    let scenes = [("demo", demo_scene(JointType::TFillet)), ("suite 0", suite[0].1.clone())]
        .into_iter()
        .chain([9, 14].map(|k| (suite[k].0.as_str(), suite[k].1.clone())));
    for (name, spec) in scenes {
        for joint in [RequestedJoint::Auto, JointType::IButt.into(), JointType::VButt.into()] {
            let err = plan_tee(&spec, joint).map(|n| format!("{n} seams")).unwrap_err();
            assert!(names_a_tee(&err.reason), "{name} as {joint}: {err}");
            assert_eq!((err.stage, err.gate), (Stage::Groove, Some(Gate::JointMismatch)), "{name} as {joint}");
        }
    }
}

#[test]
fn a_tee_requested_as_a_lap_is_refused_for_its_layers_not_by_name() {
    // What is true today: the web's top is no lap's upper plate (40 to 100
    // mm above the flange, not a plate thickness), so the layers refuse it
    // before any stage could say it is a tee.
    let err = plan_tee(&demo_scene(JointType::TFillet), JointType::Lap.into()).unwrap_err();
    assert_eq!(err.stage, Stage::Background, "{err}");
    assert!(!names_a_tee(&err.reason) && err.reason.contains("no two layers"), "{err}");
}

#[test]
fn a_frame_of_several_workpieces_shows_every_seam_its_truth_sees() {
    let camera = CameraModel { width_px: 960, height_px: 600, ..CameraModel::default() };
    let (name, spec) = multi_suite().into_iter().find(|(_, s)| s.others.len() == 2).expect("a frame of three parts");
    let sim = simulate(&spec, &camera);
    let tees = spec.workpieces().iter().filter(|w| matches!(w.joint, JointGeometry::Tee { .. })).count();
    assert_eq!(sim.seams.len(), 3 + tees, "{name}");
    let points: Vec<Vec3> = sim
        .cloud
        .points()
        .iter()
        .filter(|p| p[0].is_finite())
        .map(|p| Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect();
    for seam in &sim.seams {
        assert_eq!(seam.truth.joint, spec.workpieces()[seam.workpiece].joint.joint_type(), "{name}");
        // Every seen stretch has returns within a pixel or two (about 0.7
        // mm a pixel at this resolution and standoff) all along it.
        for [y0, y1] in &seam.seen_mm {
            let t = &seam.truth;
            let along = (t.end_camera - t.start_camera) / t.length_mm.max(1e-9);
            let y_start = seam_y_at(&spec, seam.workpiece, &t.start_camera, &sim.base_from_camera);
            for k in 0..=10 {
                let y = y0 + (y1 - y0) * k as f64 / 10.0;
                let p = t.start_camera + along * (y - y_start);
                let nearest = points.iter().map(|q| (q - p).norm()).fold(f64::INFINITY, f64::min);
                assert!(nearest < 3.0, "{name}: {}: nothing within {nearest:.2} mm at y = {y:.1}", seam.label());
            }
        }
    }
    assert!(sim.seams.iter().filter(|s| s.is_seen()).count() >= 3, "{name}: {:?}", sim.seams);
}

/// The workpiece-frame y of a camera-frame point on a workpiece's seam.
fn seam_y_at(spec: &SceneSpec, workpiece: usize, p_camera: &Vec3, base_from_camera: &nalgebra::Isometry3<f64>) -> f64 {
    let base_from_own = spec.base_from_workpiece * spec.workpieces()[workpiece].pose();
    let in_base = base_from_camera.transform_point(&(*p_camera).into());
    base_from_own.inverse_transform_point(&in_base).y
}
