//! The plan trace and its pictures (issue 12, item 7): the trace is filled
//! on a simulated frame of each joint and keeps the stage and reason of a
//! refusal beside what came before it; the pictures show the plates in
//! their colours and the seam where the truth projects, in the camera's
//! own view and in the view along the normal of a cloud without a grid;
//! the cross-sections mark the planned point at every station.

use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::RgbColor;
use weldseam::config::{Config, Method};
use weldseam::joint::JointType;
use weldseam::pipeline::quality::Gate;
use weldseam::pipeline::{PlanRequest, PlanTrace, Planner, Stage};
use weldseam::report::camera_view::{CameraView, View};
use weldseam::report::{self, Canvas, colour};
use weldseam::sim::variants::Variant;
use weldseam::sim::{Simulation, demo_scene};

use crate::scenes;

fn demo(joint: JointType) -> (&'static Simulation, PlanRequest) {
    let spec = demo_scene(joint);
    let sim = scenes::by_default_camera(&spec);
    let request = PlanRequest::new(joint, spec.joint.groove_depth_mm(), sim.pose);
    (sim, request)
}

/// How many pixels of `canvas` in rows `rows` satisfy `test`.
fn count(canvas: &Canvas, rows: std::ops::Range<u32>, test: impl Fn(Rgb888) -> bool) -> usize {
    rows.flat_map(|y| (0..canvas.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| canvas.pixel(x, y).is_some_and(&test))
        .count()
}

/// Plate 1's blue and plate 2's orange at any depth shade (the shading
/// scales the channels, so the hue's order survives it).
fn is_plate(k: usize) -> impl Fn(Rgb888) -> bool {
    move |c: Rgb888| {
        let (r, g, b) = (i32::from(c.r()), i32::from(c.g()), i32::from(c.b()));
        if k == 0 { b > r + 80 && b > g + 40 } else { r > b + 100 && r > g + 40 }
    }
}

/// Asserts that each plate covers a good part of the view and that the
/// seam is drawn where `truth` (camera-frame points on the true seam)
/// projects.
fn assert_plates_and_seam_where_the_truth_is(what: &str, view: &CameraView, truth: &[nalgebra::Vector3<f64>]) {
    let canvas = &view.canvas;
    let (_, view_height) = view.view.as_ref().expect("a view of the frame").size();
    let rows = view.view_origin.1 as u32..view.view_origin.1 as u32 + view_height;
    let area = (canvas.width() * view_height) as usize;
    for k in 0..2 {
        let share = count(canvas, rows.clone(), is_plate(k)) as f64 / area as f64;
        assert!(share > 0.05, "{what}: plate {} covers {:.1} % of the view", k + 1, 100.0 * share);
    }
    for p in truth {
        let (x, y) = view.to_canvas(p).expect("the true seam projects");
        let near = (-3..=3)
            .flat_map(|dy| (-3..=3).map(move |dx| (dx, dy)))
            .any(|(dx, dy)| canvas.pixel((x as i64 + dx) as u32, (y as i64 + dy) as u32) == Some(colour::SEAM));
        assert!(near, "{what}: no seam pixel within 3 px of the truth at ({x:.0}, {y:.0})");
    }
}

/// Points along the true seam, away from its ends.
fn true_seam(sim: &Simulation) -> Vec<nalgebra::Vector3<f64>> {
    let (a, b) = (sim.truth.start_camera, sim.truth.end_camera);
    [0.2, 0.5, 0.8].iter().map(|t| a + (b - a) * *t).collect()
}

fn assert_filled(what: &str, trace: &PlanTrace, waypoints: usize) {
    assert!(trace.refusal.is_none(), "{what}: {:?}", trace.refusal);
    assert!(trace.cloud.is_some() && trace.camera.is_some(), "{what}: the frame the stages saw");
    let valid = trace.cloud.as_ref().map_or(0, |c| c.valid_count());
    let plane = trace.plane_points.iter().filter(|&&p| p).count();
    assert!(plane > valid / 2, "{what}: {plane} plane points of {valid}");
    assert!(trace.planes.len() >= 2 && trace.plate(0).is_some() && trace.plate(1).is_some(), "{what}: plates");
    assert!(trace.edge_points.iter().all(|e| e.len() > 100), "{what}: edge points");
    for k in 0..2 {
        let picked = trace.edge_lines.iter().filter(|l| l.plate == k && l.picked).count();
        assert_eq!(picked, 1, "{what}: lines picked on plate {}", k + 1);
    }
    assert!(trace.fit_samples.iter().all(|s| s.len() > 50), "{what}: fit samples");
    assert!(trace.weld_edges.is_some() && trace.weld.is_some(), "{what}: weld edges and weld");
    assert_eq!(trace.waypoints_camera.len(), waypoints, "{what}: waypoints");
}

#[test]
fn the_trace_of_each_joint_is_filled_and_its_pictures_show_the_plates_and_the_seam_on_the_truth() {
    for joint in JointType::ALL {
        let (sim, request) = demo(joint);
        let planner = Planner::new(Config::default());
        let (outcome, trace) = planner.plan_traced(&sim.cloud, &request);
        let plan = outcome.unwrap_or_else(|e| panic!("{joint}: {e}"));
        // Tracing changes nothing about the plan.
        assert_eq!(plan.seams, planner.plan(&sim.cloud, &request).unwrap().seams, "{joint}");
        assert_filled(joint.name(), &trace, plan.seams[0].waypoints.len());
        assert!(trace.dominant_normal.is_some() && trace.quality.is_some(), "{joint}: robust figures");

        let pictures = report::render(&trace);
        let view = &pictures.camera_view;
        assert!(matches!(view.view, Some(View::Pixels { .. })), "{joint}: a raw frame is drawn on its grid");
        assert_eq!(view.canvas.width(), 960, "{joint}: half the 1920 px frame");
        assert_plates_and_seam_where_the_truth_is(joint.name(), view, &true_seam(sim));
        assert_eq!(view.canvas.pixel(1, 1), Some(colour::TITLE_PLANNED), "{joint}: a plan's title is green");

        let sections = pictures.sections.unwrap_or_else(|| panic!("{joint}: no sections"));
        assert_eq!(sections.width(), 960);
        // Each of the four panels marks its planned point and both edges.
        for (qx, qy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (x0, y0) = (qx * 480, sections.height() / 2 * qy);
            let panel = |ink: Rgb888| {
                (y0..y0 + sections.height() / 2)
                    .flat_map(|y| (x0..x0 + 480).map(move |x| (x, y)))
                    .filter(|&(x, y)| sections.pixel(x, y) == Some(ink))
                    .count()
            };
            assert!(panel(colour::SEAM) > 30 && panel(colour::WELD_EDGE) > 30, "{joint}: panel {qx},{qy}");
        }
    }
}

#[test]
fn a_cloud_without_a_grid_is_drawn_along_the_normal_with_the_seam_on_the_truth() {
    let (sim, request) = demo(JointType::VButt);
    let sim = Variant::parse("cropped:30,voxel:1").unwrap().apply(sim, 7);
    assert!(!sim.cloud.is_organized());
    let (outcome, trace) = Planner::new(Config::default()).plan_traced(&sim.cloud, &request);
    let plan = outcome.unwrap();
    assert_filled("voxel", &trace, plan.seams[0].waypoints.len());
    let pictures = report::render(&trace);
    let view = &pictures.camera_view;
    let Some(View::Along { size, .. }) = &view.view else { panic!("{:?}", view.view) };
    // The strip along the seam lies across the picture.
    assert!(size.0 > 2 * size.1, "{size:?}");
    assert_plates_and_seam_where_the_truth_is("voxel", view, &true_seam(&sim));
}

#[test]
fn the_papers_method_is_traced_with_its_lines_and_fits() {
    let (sim, request) = demo(JointType::IButt);
    let mut config = Config::default();
    config.pipeline.method = Method::Paper;
    let (outcome, trace) = Planner::new(config).plan_traced(&sim.cloud, &request);
    let plan = outcome.unwrap();
    assert_filled("paper", &trace, plan.seams[0].waypoints.len());
    assert!(trace.dominant_normal.is_none() && trace.quality.is_none());
    assert_eq!(trace.method, Method::Paper);
}

#[test]
fn a_refusal_keeps_its_stage_and_reason_beside_everything_found_before_it() {
    // A V-groove asked for as a lap: refused where the plates are chosen.
    let (sim, request) = demo(JointType::VButt);
    let lap = PlanRequest { joint: JointType::Lap.into(), groove_depth_mm: None, ..request };
    let planner = Planner::new(Config::default());
    let (outcome, trace) = planner.plan_traced(&sim.cloud, &lap);
    let error = outcome.unwrap_err();
    assert_eq!((error.rule.id, error.stage), ("lap.no_plate_step", Stage::Background), "{error}");
    assert_eq!(trace.refusal.as_ref(), Some(&error));
    assert!(trace.planes.len() >= 2 && trace.dominant_normal.is_some(), "the planes seen are kept");
    assert!(trace.plate_labels.is_none() && trace.weld.is_none() && trace.edge_lines.is_empty());
    let pictures = report::render(&trace);
    assert!(pictures.sections.is_none(), "no weld, no sections");
    assert_eq!(pictures.camera_view.canvas.pixel(1, 1), Some(colour::TITLE_REFUSED));

    // An I-butt whose gap is over a tightened limit: the seam is found,
    // then refused by the gap gate; its figures and sections are kept.
    let (sim, request) = demo(JointType::IButt);
    let mut config = Config::default();
    config.quality.max_gap_mm = 0.3;
    let (outcome, trace) = Planner::new(config).plan_traced(&sim.cloud, &request);
    let error = outcome.unwrap_err();
    assert_eq!(
        (error.rule.id, error.stage, error.gate),
        ("butt.gap_width", Stage::Quality, Some(Gate::GapWidth)),
        "{error}"
    );
    assert_eq!(trace.refusal.as_ref(), Some(&error));
    assert_eq!(trace.joint, Some(JointType::IButt));
    let gap = trace.quality.and_then(|q| q.gap_mm).expect("the gap the gate read");
    assert!(gap.min > 0.3, "{gap:?}");
    assert!(trace.weld.is_some() && trace.waypoints_camera.is_empty(), "found, but not sampled into waypoints");
    let pictures = report::render(&trace);
    assert!(pictures.sections.is_some());
    assert_eq!(pictures.camera_view.canvas.pixel(1, 1), Some(colour::TITLE_REFUSED));
}

#[test]
fn a_request_refused_before_any_frame_is_drawn_as_a_title_alone() {
    let (sim, request) = demo(JointType::VButt);
    let bad = PlanRequest { groove_depth_mm: Some(1e6), ..request };
    let (outcome, trace) = Planner::new(Config::default()).plan_traced(&sim.cloud, &bad);
    let error = outcome.unwrap_err();
    assert_eq!((error.rule.id, error.stage), ("groove.depth_out_of_range", Stage::Request), "{error}");
    assert!(trace.cloud.is_none());
    let pictures = report::render(&trace);
    assert!(pictures.camera_view.view.is_none() && pictures.sections.is_none());
    assert_eq!(pictures.camera_view.canvas.pixel(1, 1), Some(colour::TITLE_REFUSED));
}

/// The daemon's debug set directories in `dir`, by name, oldest first.
fn debug_sets(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("plan-"))
        .collect();
    names.sort();
    names
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_daemon_keeps_the_sets_of_its_last_plans_only() {
    use std::sync::Arc;
    use std::time::{Duration, Instant};
    use weldseam::config::DebugParams;
    use weldseam::mock::camera::CameraOptions;
    use weldseam::mock::controller::{ControllerClient, request_for_simulation};
    use weldseam_proto::message::FrameSelect;

    let dir = tempfile::tempdir().unwrap();
    let (sim, _) = demo(JointType::IButt);
    let mut config = Config::default();
    config.server.pipeline_threads = 2;
    config.debug = DebugParams { dir: dir.path().to_str().unwrap().into(), keep_last: 2 };
    let cell = crate::util::Cell::start(config).await;
    let (stop, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut ctl = ControllerClient::connect(&cell.controller, "debug-sets-test").await.unwrap();
    ctl.wait_for_camera(Duration::from_secs(5)).await.expect("the mock camera connects");
    let debug = &cell.daemon.state.debug;
    assert!(debug.ready(), "[debug] with a directory keeps sets");
    for id in 1..=3u64 {
        let request = request_for_simulation(id, JointType::IButt, sim, FrameSelect::Trigger);
        ctl.plan(request, Duration::from_secs(60)).await.unwrap();
        // The set is written after the reply; the next plan is traced only
        // once the writer is free, so wait for it (a hang is a failure).
        let deadline = Instant::now() + Duration::from_secs(60);
        while !(debug.ready() && debug_sets(dir.path()).iter().any(|n| n.ends_with(&format!("-r{id}")))) {
            assert!(Instant::now() < deadline, "set {id} never written: {:?}", debug_sets(dir.path()));
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }
    let sets = debug_sets(dir.path());
    assert_eq!(sets.len(), 2, "{sets:?}");
    assert!(sets[0].ends_with("-r2") && sets[1].ends_with("-r3"), "{sets:?}");
    for set in &sets {
        for file in ["camera.png", "sections.png", "trace.json"] {
            assert!(dir.path().join(set).join(file).is_file(), "{set}/{file}");
        }
    }
    let _ = stop.send(());
    camera.await.unwrap();
    cell.shutdown().await;
}
