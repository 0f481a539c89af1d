//! The KUKA and FANUC programs, run on their emulations against `weldseam
//! serve` on loopback: a 250-waypoint seam moved where `plan --json` puts
//! it, with the flange pose sent whatever the torch, one bead per seam
//! without a stop and without a network read under the arc; several
//! seams; a refusal and a too-long line read and branched on; the daemon
//! stopped during the fetch and before the arc (the torch never moves).

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{Translation3, UnitQuaternion};
use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::convert::to_proto::plan_result;
use weldseam::geometry::Isometry3;
use weldseam::geometry::conventions::PoseConvention;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::ControllerClient;
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::sim::{Draw, Simulation, demo_scene, simulate};

use super::karel::Controller;
use super::krl::Krl;
use super::robot::{Event, Trace};
use super::{fanuc, fanuc_tp, kuka};
use crate::util::Cell;

use super::robot::SendHook as Hook;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Vendor {
    Kuka,
    Fanuc,
}

/// One run of a program: its result code, the record, the pendant's
/// messages and the flange pose when it sent the plan line.
struct Run {
    result: i32,
    trace: Trace,
    messages: Vec<String>,
    alarms: Vec<usize>,
    capture_flange: Isometry3<f64>,
}

/// A torch 350 mm out, tilted: a pose sent with it in is 350 mm off.
fn torch() -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::new(12.0, -30.0, 350.0), UnitQuaternion::from_euler_angles(0.0, 0.35, 0.2))
}

fn convention(vendor: Vendor) -> PoseConvention {
    match vendor {
        Vendor::Kuka => PoseConvention::KUKA,
        Vendor::Fanuc => PoseConvention::FANUC,
    }
}

/// Runs the vendor's program (blocking) with the robot at `flange`.
fn run(vendor: Vendor, address: &str, flange: Isometry3<f64>, joint: &str, hook: Option<Hook>) -> Run {
    match vendor {
        Vendor::Kuka => {
            let xml = std::fs::read_to_string(super::listing::program_path("kuka/WeldSeam.xml")).unwrap();
            let mut k = Krl::new(&xml, address, flange, torch());
            k.on_send = hook;
            let mut dat = kuka::data_list(&mut k);
            let ov = kuka::Overrides { joint: Some(joint.into()), reply_timeout_ms: None };
            let result = kuka::weld_seam(&mut k, &mut dat, &ov);
            Run { result, trace: k.trace, messages: k.messages, alarms: Vec::new(), capture_flange: flange }
        }
        Vendor::Fanuc => {
            let mut tp = Controller::new(address, flange, torch());
            tp.on_send = hook;
            let mut helper =
                fanuc::load_program(&mut tp, &fanuc::Overrides { joint: Some(joint.into()), reply_ms: None });
            fanuc_tp::weld_seam(&mut tp, &mut helper);
            let result = tp.r[9].int();
            Run { result, trace: tp.trace, messages: tp.tperror, alarms: tp.alarms, capture_flange: flange }
        }
    }
}

async fn run_async(vendor: Vendor, address: String, sim: &Simulation, joint: &str, hook: Option<Hook>) -> Run {
    let flange = sim.pose.to_isometry(Default::default());
    let joint = joint.to_string();
    tokio::task::spawn_blocking(move || run(vendor, &address, flange, &joint, hook)).await.unwrap()
}

fn config(step_mm: f64) -> Config {
    let mut c = Config::default();
    c.server.fresh_frame_timeout = Duration::from_secs(10);
    c.server.pipeline_threads = 2;
    c.server.shutdown_grace = Duration::from_secs(5);
    c.trajectory.step_mm = step_mm;
    c.text_link.max_line_bytes = 80;
    c
}

/// A cell with a camera that serves `sim`'s frame.
async fn cell_for(c: Config, sim: &Simulation) -> (Cell, tokio::sync::oneshot::Sender<()>) {
    let cell = Cell::start(c).await;
    let (stop_camera, _camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut ctl = ControllerClient::connect(&cell.controller, "test").await.unwrap();
    ctl.wait_for_camera(Duration::from_secs(5)).await.unwrap();
    (cell, stop_camera)
}

/// The plan line's pose, as the daemon reads it.
fn sent_pose(vendor: Vendor, trace: &Trace) -> Vec<f64> {
    let line = trace.sent().into_iter().find(|l| l.starts_with("TRIGGER")).expect("a plan line").to_string();
    line.trim_end()
        .split(',')
        .skip(2)
        .map(|f| f.trim().parse().unwrap())
        .take(convention(vendor).numbers_len())
        .collect()
}

/// Where the program must move, line by line: what `plan --json` prints
/// for the frame at the pose the program sent (the same planner call and
/// report), each seam's first and last waypoint backed off along the
/// torch axis for approach and retract.
fn planned_lines(c: &Config, sim: &Simulation, joint: &str, sent: &[f64], vendor: Vendor) -> Vec<(u8, Isometry3<f64>)> {
    let euler = c.euler;
    let pose = convention(vendor).to_robot_pose(sent, euler).unwrap();
    let requested: RequestedJoint = joint.parse().unwrap();
    let request = PlanRequest::new(requested, None, pose);
    let plan = Planner::new(c.clone()).plan_owned(sim.cloud.clone(), &request).expect("the frame plans");
    let report = plan_result(&plan, euler);
    let offset = c.text_link.approach_offset_mm;
    let mut lines = Vec::new();
    for seam in &report.seams {
        let isos: Vec<Isometry3<f64>> = seam
            .waypoints
            .iter()
            .map(|w| weldseam::geometry::pose::RobotPose { xyz_mm: w.xyz, angles_deg: w.rpy_deg }.to_isometry(euler))
            .collect();
        let back = |iso: &Isometry3<f64>| {
            Isometry3::from_parts(
                Translation3::from(iso.translation.vector - iso.rotation * nalgebra::Vector3::z() * offset),
                iso.rotation,
            )
        };
        lines.push((1, back(&isos[0])));
        lines.extend(isos.iter().map(|i| (2, *i)));
        lines.push((3, back(isos.last().unwrap())));
    }
    lines
}

/// The checks every welding run must pass: result 0, the flange pose sent
/// (to the line's decimals), one move per planned line to its pose within
/// 0.01 mm and 0.01 degree, each seam one bead without a stop and without
/// a network line, and nothing left on.
fn assert_welded_as_planned(vendor: Vendor, run: &Run, planned: &[(u8, Isometry3<f64>)], seams: usize) {
    assert_eq!(
        run.result,
        0,
        "{vendor:?}: {:?} after {:?}",
        run.messages,
        run.trace.reads().iter().rev().take(3).collect::<Vec<_>>()
    );
    let sent = convention(vendor).to_isometry(&sent_pose(vendor, &run.trace)).unwrap();
    let off = sent.inverse() * run.capture_flange;
    assert!(off.translation.vector.norm() < 0.002, "{vendor:?}: sent {sent} for the flange {}", run.capture_flange);
    assert!(off.rotation.angle().to_degrees() < 0.0002, "{vendor:?}: sent {sent}");
    let moves = run.trace.moves();
    assert_eq!(moves.len(), planned.len(), "{vendor:?}: one move per line");
    for (k, (m, (kind, iso))) in moves.iter().zip(planned).enumerate() {
        let at = convention(vendor).to_isometry(&m.pose).unwrap();
        let d = at.inverse() * iso;
        let mm = (at.translation.vector - iso.translation.vector).norm();
        assert!(mm <= 0.01, "{vendor:?}: line {k} (kind {kind}) {mm:.4} mm off");
        assert!(
            d.rotation.angle().to_degrees() <= 0.01,
            "{vendor:?}: line {k} turned {:.4} deg",
            d.rotation.angle().to_degrees()
        );
    }
    let welds = run.trace.welds().unwrap_or_else(|e| panic!("{vendor:?}: {e}"));
    assert_eq!(welds.len(), seams, "{vendor:?}: one arc per seam");
    for w in &welds {
        assert_eq!(w.network, 0, "{vendor:?}: a network line under the arc");
        assert!(
            w.continuous(),
            "{vendor:?}: the bead stops: {:?}",
            w.moves.iter().map(|m| m.blended).collect::<Vec<_>>()
        );
        assert!(w.moves.iter().all(|m| (m.speed_mm_s - 8.0).abs() < 1e-3), "{vendor:?}: weld speed");
    }
}

/// A refused run: the code, nothing moved, the arc never on.
fn assert_refused(vendor: Vendor, run: &Run, code: i32) {
    assert_eq!(run.result, code, "{vendor:?}: {:?}", run.messages);
    assert!(run.trace.moves().is_empty(), "{vendor:?}: the torch moved");
    assert!(!run.trace.events.contains(&Event::ArcOn), "{vendor:?}: the arc went on");
    if vendor == Vendor::Fanuc {
        assert_eq!(run.alarms, [if code < 0 { 1 } else { 2 }], "the TP program branched on R[9]");
    }
}

/// One seam of 250 waypoints and more (1 mm step), both vendors: welded
/// where `plan --json` says; then a refused joint and a line longer than
/// the daemon takes, each read and branched on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_weld_a_long_seam_where_the_plan_says_and_branch_on_refusals() {
    let c = config(0.9);
    let sim = simulate(&demo_scene(JointType::Lap), &CameraModel::default());
    let (cell, stop_camera) = cell_for(c.clone(), &sim).await;
    for vendor in [Vendor::Kuka, Vendor::Fanuc] {
        let done = run_async(vendor, cell.daemon.text_addr.to_string(), &sim, "lap", None).await;
        let planned = planned_lines(&c, &sim, "lap", &sent_pose(vendor, &done.trace), vendor);
        assert!(planned.len() >= 252, "{} lines: 250 waypoints and more", planned.len());
        assert_welded_as_planned(vendor, &done, &planned, 1);
        assert!(done.trace.reads().iter().any(|r| r.starts_with("0,1,")), "{vendor:?}: CHECK answered");

        let refused = run_async(vendor, cell.daemon.text_addr.to_string(), &sim, "v_butt", None).await;
        assert!(refused.result < 0, "{vendor:?}: {:?}", refused.messages);
        assert_refused(vendor, &refused, refused.result);
        let reason = refused.messages.last().expect("the reason on the pendant");
        assert!(!reason.starts_with('-') || vendor == Vendor::Kuka, "{vendor:?}: the cause first: {reason}");

        let long = run_async(vendor, cell.daemon.text_addr.to_string(), &sim, "v_butt+i_butt+lap+t_fillet", None).await;
        assert_refused(vendor, &long, -5);
    }
    let _ = stop_camera.send(());
    cell.shutdown().await;
}

/// Three workpieces in view, `auto`: every seam fetched and checked, then
/// welded seam by seam, each one bead.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_weld_several_seams_one_bead_each() {
    let (_, spec) = weldseam::sim::multi_suite(Draw::Documented)
        .into_iter()
        .find(|(n, _)| n.starts_with("multi-01"))
        .expect("the scene");
    let sim = simulate(&spec, &CameraModel::default());
    let c = config(25.0);
    let (cell, stop_camera) = cell_for(c.clone(), &sim).await;
    for vendor in [Vendor::Kuka, Vendor::Fanuc] {
        let done = run_async(vendor, cell.daemon.text_addr.to_string(), &sim, "auto", None).await;
        let planned = planned_lines(&c, &sim, "auto", &sent_pose(vendor, &done.trace), vendor);
        assert_welded_as_planned(vendor, &done, &planned, 3);
        assert_eq!(done.trace.sent().iter().filter(|l| l.starts_with("CHECK,")).count(), 3, "{vendor:?}");
    }
    let _ = stop_camera.send(());
    cell.shutdown().await;
}

/// A hook that, at the first line `when` accepts, stops the daemon and
/// waits until it is down before the line goes out.
fn stop_at(when: fn(&str, usize) -> bool) -> (Hook, tokio::sync::oneshot::Receiver<()>, std::sync::mpsc::Sender<()>) {
    let (hit_tx, hit_rx) = tokio::sync::oneshot::channel();
    let (ack_tx, ack_rx) = std::sync::mpsc::channel::<()>();
    let mut hit_tx = Some(hit_tx);
    let mut nexts = 0;
    let hook: Hook = Box::new(move |line: &str| {
        if line.starts_with("NEXT") {
            nexts += 1;
        }
        if hit_tx.is_some() && when(line, nexts) {
            let _ = hit_tx.take().unwrap().send(());
            let _ = ack_rx.recv_timeout(Duration::from_secs(60));
        }
    });
    (hook, hit_rx, ack_tx)
}

/// The daemon stopped during the fetch (at the 40th NEXT) and before the
/// arc (at the first CHECK, the last line before motion): the program
/// reads the lost link, branches on its code and the torch never moves.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_stay_off_the_seam_when_the_daemon_stops_before_the_arc() {
    let c = config(5.0);
    let sim = simulate(&demo_scene(JointType::Lap), &CameraModel::default());
    let during_fetch: fn(&str, usize) -> bool = |line, nexts| line.starts_with("NEXT") && nexts == 40;
    let before_arc: fn(&str, usize) -> bool = |line, _| line.starts_with("CHECK");
    for vendor in [Vendor::Kuka, Vendor::Fanuc] {
        for when in [during_fetch, before_arc] {
            let (cell, stop_camera) = cell_for(c.clone(), &sim).await;
            let (hook, hit, ack) = stop_at(when);
            let running = run_async(vendor, cell.daemon.text_addr.to_string(), &sim, "lap", Some(hook));
            let stopping = async {
                hit.await.expect("the program reached the line");
                let _ = stop_camera.send(());
                cell.shutdown().await;
                ack.send(()).unwrap();
            };
            let (stopped, ()) = tokio::join!(running, stopping);
            assert!(
                stopped.result == 2 || stopped.result == -47,
                "{vendor:?}: {} {:?}",
                stopped.result,
                stopped.messages
            );
            assert_refused(vendor, &stopped, stopped.result);
            assert!(!stopped.messages.is_empty(), "{vendor:?}: a reason on the pendant");
        }
    }
}
