//! Quality figures and gates (issue 12) end to end: every seam carries its
//! figures, a seam that fails a gate is refused with the figure, its value
//! and the limit (in the library, `plan --json` and the protocol's error
//! code), and `quality.warn_only` turns the refusal into a warning.

use std::process::Command;
use std::sync::Arc;
use std::time::Duration;

use weldseam::config::Config;
use weldseam::joint::JointType;
use weldseam::mock::ClientError;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::{ControllerClient, request_for_simulation};
use weldseam::pipeline::quality::Gate;
use weldseam::pipeline::{PlanRequest, Planner, Stage};
use weldseam::sim::{JointGeometry, SceneSpec, Simulation, demo_scene};
use weldseam_proto::ErrorCode;
use weldseam_proto::message::FrameSelect;

use crate::scenes;
use crate::util::{Cell, write_temp};

/// The demo I-butt scene (what `simulate --joint i-butt` renders), its
/// gap checked to be wider than `limit_mm`.
fn i_butt_spec_wider_than(limit_mm: f64) -> SceneSpec {
    let spec = demo_scene(JointType::IButt);
    let JointGeometry::IButt { gap_mm, .. } = spec.joint else { panic!("the demo I-butt scene is an I-butt") };
    assert!(gap_mm > limit_mm + 0.2, "the demo gap ({gap_mm} mm) must be clearly over the test's limit");
    spec
}

/// [`i_butt_spec_wider_than`] and its rendered frame.
fn i_butt_wider_than(limit_mm: f64) -> (SceneSpec, &'static Simulation) {
    let spec = i_butt_spec_wider_than(limit_mm);
    let sim = scenes::by_default_camera(&spec);
    (spec, sim)
}

fn request(spec: &SceneSpec, sim: &Simulation) -> PlanRequest {
    PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose)
}

fn with_max_gap(limit_mm: f64, warn_only: bool) -> Config {
    let mut config = Config::default();
    config.quality.max_gap_mm = limit_mm;
    if warn_only {
        config.quality.warn_only = vec!["gap_width".into()];
    }
    config
}

#[test]
fn every_seam_carries_its_quality_figures() {
    for joint in JointType::ALL {
        let spec = demo_scene(joint);
        let sim = scenes::by_default_camera(&spec);
        let plan = Planner::new(Config::default()).plan(&sim.cloud, &request(&spec, sim)).unwrap();
        let seam = &plan.seams[0];
        let q = seam.quality.unwrap_or_else(|| panic!("{joint}: no quality figures"));
        assert!(seam.warnings.is_empty(), "{joint}: {:?}", seam.warnings);
        assert!(q.point_spacing_mm > 0.05 && q.point_spacing_mm < 1.0, "{joint}: {q:?}");
        assert!(q.uncertainty_across_mm > 0.0 && q.uncertainty_across_mm < 0.2, "{joint}: {q:?}");
        assert!(q.plate_angle_deg < 1.0, "{joint}: {q:?}");
        match spec.joint {
            JointGeometry::IButt { gap_mm, .. } => {
                let gap = q.gap_mm.unwrap();
                assert!((gap.mean - gap_mm).abs() < 0.3, "{joint}: gap {gap:?} against the true {gap_mm} mm");
                assert!(q.misalignment_mm.unwrap() < 0.2 && q.lap_step_mm.is_none(), "{joint}: {q:?}");
            }
            JointGeometry::VButt { .. } => assert!(q.gap_mm.is_some() && q.misalignment_mm.unwrap() < 0.2),
            JointGeometry::Lap { upper_thickness_mm, .. } => {
                let step = q.lap_step_mm.unwrap();
                assert!((step - upper_thickness_mm).abs() < 0.3, "{joint}: step {step} against {upper_thickness_mm}");
                assert!(q.gap_mm.is_none() && q.misalignment_mm.is_none());
            }
            JointGeometry::Tee { .. } | JointGeometry::Corner { .. } => {
                unreachable!("only the planned joints are planned here")
            }
        }
    }
}

#[test]
fn a_seam_that_fails_a_gate_is_refused_with_the_figure_its_value_and_the_limit() {
    let (spec, sim) = i_butt_wider_than(0.3);
    let refused = Planner::new(with_max_gap(0.3, false)).plan(&sim.cloud, &request(&spec, sim)).unwrap_err();
    assert_eq!(refused.rule.id, "butt.gap_width", "{refused}");
    assert_eq!((refused.stage, refused.gate), (Stage::Quality, Some(Gate::GapWidth)), "{refused}");
    assert!(refused.reason.contains("wider than 0.30 mm"), "{refused}");
}

#[test]
fn a_gate_named_in_warn_only_warns_on_the_seam_instead() {
    let (spec, sim) = i_butt_wider_than(0.3);
    let plan = Planner::new(with_max_gap(0.3, true)).plan(&sim.cloud, &request(&spec, sim)).unwrap();
    let warnings = &plan.seams[0].warnings;
    assert_eq!(warnings.iter().map(|w| w.rule.id).collect::<Vec<_>>(), ["butt.gap_width"]);
    assert_eq!(warnings[0].gate, Gate::GapWidth);
    assert_eq!(warnings[0].limit, 0.3);
    assert!(warnings[0].value > 0.5, "{warnings:?}");
}

#[test]
fn a_config_naming_an_unknown_gate_is_refused_with_the_list_of_gates() {
    let err = Config::parse("[quality]\nwarn_only = [\"gap\"]\n", "test").unwrap_err().to_string();
    assert!(err.contains("quality.warn_only") && err.contains("\"gap\" is not a gate"), "{err}");
    assert!(err.contains("gap_width") && err.contains("position_uncertainty"), "{err}");
}

#[test]
fn plan_json_prints_the_refusal_with_its_code() {
    i_butt_spec_wider_than(0.3);
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("i-butt.pcd");
    let truth = dir.path().join("i-butt.json");
    let status = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["simulate", "--joint", "i-butt", "--out", cloud.to_str().unwrap(), "--truth", truth.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(status.success());
    let (_config_dir, config) = write_temp("weldseam.toml", b"[quality]\nmax_gap_mm = 0.3\n");
    let truth: serde_json::Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
    let mut args = vec!["plan", "--cloud", cloud.to_str().unwrap(), "--config", config.to_str().unwrap(), "--json"];
    args.extend(truth["plan_args"].as_str().unwrap().split_whitespace());
    let out = Command::new(env!("CARGO_BIN_EXE_weldseam")).args(&args).output().unwrap();
    assert!(!out.status.success(), "a refused seam is a failed plan");
    let reply: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    let error = &reply["error"];
    assert_eq!((error["code"].as_str(), error["gate"].as_str()), (Some("gap_width"), Some("gap_width")), "{reply}");
    assert_eq!((error["stage"].as_str(), error["rule"].as_str()), (Some("quality"), Some("butt.gap_width")), "{reply}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("seam refused in") && stderr.contains("wider than 0.30 mm"), "{stderr}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_daemon_answers_a_refused_seam_with_the_gates_error_code() {
    let (spec, sim) = i_butt_wider_than(0.3);
    let mut config = with_max_gap(0.3, false);
    config.server.pipeline_threads = 2;
    let cell = Cell::start(config).await;
    let (stop, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut ctl = ControllerClient::connect(&cell.controller, "quality-test").await.unwrap();
    ctl.wait_for_camera(Duration::from_secs(5)).await.expect("the mock camera connects");
    let request = request_for_simulation(7, spec.joint.joint_type(), sim, FrameSelect::Trigger);
    match ctl.plan(request, Duration::from_secs(60)).await {
        Err(ClientError::Refused(e)) => {
            assert_eq!((e.code, e.request_id), (ErrorCode::GapWidth, Some(7)), "{e:?}");
            assert!(e.message.contains("wider than 0.30 mm"), "{}", e.message);
        }
        other => panic!("expected the gap_width refusal, got {other:?}"),
    }
    let _ = stop.send(());
    camera.await.unwrap();
    cell.shutdown().await;
}
