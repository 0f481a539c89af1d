//! Plan records end to end: the daemon, fed the demo's scenes by the mock
//! camera and asked for each plan by the mock controller as `weldseam
//! demo` does, records every plan; each record, planned again from its
//! frame, request and configuration, gives the same plan bit for bit; a
//! record changed on disk is said to differ, naming the figure. With a
//! weld procedure configured, a record holds the plan as the controller
//! received it, field for field (the figures along each seam and its
//! process included), and its replay gives that plan again.

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
use weldseam::sim::{CameraPlacement, JointGeometry, SceneSpec, demo_scene, simulate};
use weldseam_proto::message::{FrameSelect, joint_code};
use weldseam_proto::session::capability;

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

/// A daemon started from a config file that names the shipped procedure:
/// a 12 mm V-groove planned in several passes is recorded with everything
/// the controller received (figures along the seam, the process with its
/// passes and cut stretches, the rule ids), and planned again from the
/// record it is the same plan, those fields compared too.
#[test]
fn a_record_holds_and_replays_the_figures_and_process_a_plan_carries() {
    let dir = tempfile::tempdir().unwrap();
    let procedure = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/procedures/gmaw-mild-steel.toml");
    let text = format!(
        "[trajectory]\nstep_mm = 20.0\n\n[server]\npipeline_threads = 2\nfresh_frame_timeout_ms = 10000\n\n\
         [records]\ndir = {:?}\n\n[process]\nprocedure = {:?}\nplate_thickness_mm = 12.0\n",
        dir.path().to_str().unwrap(),
        procedure.to_str().unwrap()
    );
    let config = Config::parse(&text, "the test's config").unwrap();
    assert!(config.process.procedure.is_some());
    let mut spec = demo_scene(JointType::VButt);
    spec.joint =
        JointGeometry::VButt { thickness_mm: 12.0, groove_angle_deg: 60.0, groove_depth_mm: 9.0, root_gap_mm: 1.0 };
    let sim = simulate(&spec, &config.camera);
    let runtime = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let reply = runtime.block_on(async {
        let daemon = LocalDaemon::start_with_config_text(config, text.clone()).await.unwrap();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let camera = weldseam::mock::camera::MockCamera::new(
            daemon.camera_addr.to_string(),
            vec![Arc::new(sim.cloud.clone())],
            CameraOptions::default(),
        );
        let camera = tokio::spawn(camera.run(stopped));
        let asked = capability::RULE_IDS | capability::ALONG_SEAM;
        let addr = daemon.controller_addr.to_string();
        let mut controller = ControllerClient::connect_asking(&addr, "records", asked).await.unwrap();
        controller.wait_for_camera(WAIT).await.unwrap();
        let request = request_for_simulation(1, JointType::VButt, &sim, FrameSelect::Trigger);
        let reply = controller.plan(request, WAIT).await.expect("the groove is planned");
        assert_eq!(records_in(dir.path(), 1).await.len(), 1, "the plan was not recorded");
        let _ = stop.send(());
        let _ = camera.await;
        daemon.stop().await.unwrap();
        reply
    });
    let seam = &reply.result.seams[0];
    let process = seam.process.as_ref().expect("a procedure is configured");
    assert!(process.waypoints.iter().flatten().any(|w| w.passes.len() >= 2), "several passes");
    assert_eq!(seam.along_seam.as_ref().map(Vec::len), Some(seam.waypoints.len()));

    let entry = &records::list(dir.path()).unwrap()[0];
    let record = records::read(&entry.path).unwrap();
    assert_eq!(record.format, records::FORMAT_VERSION);
    assert!(record.procedure_text.as_deref().is_some_and(|t| t.contains("[[entry]]")), "the procedure's text is kept");
    let Outcome::Planned(recorded) = &record.outcome else { panic!("recorded as refused: {:?}", record.outcome) };
    // Field for field, as the controller received it.
    assert_eq!(recorded, &reply.result);
    let replayed = replay(&record).unwrap();
    assert!(replayed.same(), "the replay changed: {:?}", replayed.changes);
    let Outcome::Planned(again) = &replayed.outcome else { panic!("replayed as refused") };
    assert_eq!(again.seams[0].process, seam.process);
    assert_eq!(again.seams[0].along_seam, seam.along_seam);

    // The export writes the answer with the figures and process, and the
    // procedure it was planned with.
    let pcd = dir.path().join("export.pcd");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["records".as_ref(), dir.path().as_os_str(), "--export".as_ref(), entry.id.as_ref(), pcd.as_os_str()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let exported: serde_json::Value =
        serde_json::from_slice(&std::fs::read(pcd.with_extension("json")).unwrap()).unwrap();
    let exported_seam = &exported["outcome"]["Planned"]["seams"][0];
    // JSON reads a float back to within its last digit: compare the shape.
    let exported_process = &exported_seam["process"];
    assert_eq!(exported_process["procedure"].as_str(), Some(process.procedure.as_str()));
    let passes: Vec<usize> = process.waypoints.iter().map(|w| w.as_ref().map_or(0, |w| w.passes.len())).collect();
    let exported_passes: Vec<usize> = exported_process["waypoints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["passes"].as_array().map_or(0, Vec::len))
        .collect();
    assert_eq!(exported_passes, passes);
    assert_eq!(exported_seam["along_seam"].as_array().map(Vec::len), Some(seam.waypoints.len()));
    assert_eq!(exported["procedure"].as_str(), record.procedure_text.as_deref());

    // A pass's speed changed in the record is named as a change.
    let mut changed = record.clone();
    let Outcome::Planned(result) = &mut changed.outcome else { unreachable!() };
    let at = result.seams[0].process.as_mut().unwrap().waypoints.iter_mut().flatten().next().unwrap();
    at.passes[0].travel_speed_mm_s += 1e-9;
    let changes = replay(&changed).unwrap().changes;
    assert!(
        changes
            .listed
            .iter()
            .any(|c| c.starts_with(".planned.seams[0].process.waypoints[") && c.contains("travel_speed_mm_s")),
        "{changes:?}"
    );
}
