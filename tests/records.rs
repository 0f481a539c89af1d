//! Plan records end to end: the daemon, fed the demo's scenes by the mock
//! camera and asked for each plan by the mock controller as `weldseam
//! demo` does, records every plan; each record, planned again from its
//! frame, request and configuration, gives the same plan bit for bit; a
//! record changed on disk is said to differ, naming the figure.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use weldseam::config::Config;
use weldseam::joint::JointType;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::{ControllerClient, request_for_simulation};
use weldseam::records::{self, Outcome, replay::replay};
use weldseam::server::local::LocalDaemon;
use weldseam::sim::scenarios::several_workpieces;
use weldseam::sim::{CameraPlacement, SceneSpec, demo_scene, simulate};
use weldseam_proto::message::{FrameSelect, joint_code};

const WAIT: Duration = Duration::from_secs(120);

/// The demo's scenes, in its order: one per joint type, its tee seen
/// tilted 20° across the web, and the frame of three workpieces.
fn demo_scenes() -> Vec<(JointType, SceneSpec)> {
    let mut scenes: Vec<(JointType, SceneSpec)> = JointType::ALL.into_iter().map(|j| (j, demo_scene(j))).collect();
    let tee = demo_scene(JointType::TFillet);
    let tee =
        SceneSpec { placement: CameraPlacement { tilt_deg: 20.0, tilt_azimuth_deg: 0.0, ..tee.placement }, ..tee };
    scenes.push((JointType::TFillet, tee));
    scenes
}

/// Waits until `dir` holds `count` records.
async fn records_in(dir: &Path, count: usize) -> Vec<records::Entry> {
    let deadline = tokio::time::Instant::now() + WAIT;
    loop {
        let entries = records::list(dir).unwrap();
        if entries.len() >= count || tokio::time::Instant::now() > deadline {
            return entries;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[test]
fn every_plan_of_the_demo_replays_to_the_same_plan() {
    let dir = tempfile::tempdir().unwrap();
    let runtime = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    runtime.block_on(async {
        let mut config = Config::default();
        config.records.dir = dir.path().to_str().unwrap().to_string();
        config.server.pipeline_threads = 2;
        let sims: Vec<_> = demo_scenes().into_iter().map(|(j, spec)| (j, simulate(&spec, &config.camera))).collect();
        let several = simulate(&several_workpieces(3), &config.camera);
        let daemon = LocalDaemon::start(config).await.unwrap();
        let frames = sims.iter().map(|(_, s)| &s.cloud).chain([&several.cloud]).map(|c| Arc::new(c.clone())).collect();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let camera =
            weldseam::mock::camera::MockCamera::new(daemon.camera_addr.to_string(), frames, CameraOptions::default());
        let camera = tokio::spawn(camera.run(stopped));
        let mut controller = ControllerClient::connect(&daemon.controller_addr.to_string(), "records").await.unwrap();
        controller.wait_for_camera(WAIT).await.unwrap();
        let mut requests: Vec<_> = sims
            .iter()
            .enumerate()
            .map(|(k, (joint, sim))| request_for_simulation(k as u64 + 1, *joint, sim, FrameSelect::Trigger))
            .collect();
        let mut auto =
            request_for_simulation(requests.len() as u64 + 1, JointType::VButt, &several, FrameSelect::Trigger);
        (auto.joint, auto.groove_depth_mm) = (joint_code::AUTO, None);
        requests.push(auto);
        let mut replies = Vec::new();
        for (k, request) in requests.into_iter().enumerate() {
            replies.push(controller.plan(request, WAIT).await.expect("the demo's scenes are planned"));
            // One plan's record at a time: none is dropped for a busy writer.
            assert_eq!(records_in(dir.path(), k + 1).await.len(), k + 1, "plan {} was not recorded", k + 1);
        }
        let _ = stop.send(());
        let _ = camera.await;
        daemon.stop().await.unwrap();

        let entries = records::list(dir.path()).unwrap();
        assert_eq!(entries.len(), replies.len());
        for (entry, reply) in entries.iter().zip(&replies) {
            let record = records::read(&entry.path).unwrap();
            assert_eq!(record.request_id, reply.request_id);
            let Outcome::Planned(recorded) = &record.outcome else { panic!("{}: recorded as refused", entry.id) };
            assert_eq!(recorded.seams.len(), reply.result.seams.len());
            let replayed = replay(&record).unwrap();
            assert_eq!(replayed.config_hash, record.config_hash, "{}: the config reads back differently", entry.id);
            assert!(replayed.same(), "{}: the replay changed: {:?}", entry.id, replayed.changes);
        }

        // The command line lists them and replays one.
        let weldseam = |args: &[&std::ffi::OsStr]| {
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_weldseam")).args(args).output().unwrap();
            (out.status.success(), String::from_utf8_lossy(&out.stdout).into_owned())
        };
        let (listed, table) = weldseam(&["records".as_ref(), dir.path().as_os_str()]);
        assert!(listed, "{table}");
        for entry in &entries {
            assert!(table.lines().any(|l| l.starts_with(&entry.id) && l.contains("planned")), "{table}");
        }
        let (same, said) = weldseam(&["replay".as_ref(), entries[0].path.as_os_str()]);
        assert!(same && said.contains("the same plan, bit for bit"), "{said}");

        // A waypoint moved in the record is named as a change.
        let mut record = records::read(&entries[0].path).unwrap();
        let Outcome::Planned(result) = &mut record.outcome else { unreachable!() };
        result.seams[0].waypoints[0].xyz[0] += 1e-9;
        let changes = replay(&record).unwrap().changes;
        assert!(changes.listed.iter().any(|c| c.starts_with(".planned.seams[0].waypoints[0].xyz[0]:")), "{changes:?}");
    });
}
