//! The text link with a weld procedure configured, over loopback: a thick
//! V-groove planned in several passes, pulled in every dialect by the mock
//! robot as a robot program pulls it (`HELLO,<dialect>,PROCESS`): each
//! piece of each pass a seam of its own, root first, every weld waypoint
//! followed by its process line, every seam checked, and the poses, travel
//! speeds and weaves received those the plan gives.

use std::sync::Arc;
use std::time::Duration;

use weldseam::config::procedure::{WeavePattern, WeaveSpec};
use weldseam::config::{Config, ProcessParams};
use weldseam::convert::{from_proto, to_text};
use weldseam::joint::JointType;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::text_robot::{PulledSeam, TextRobot, reply_numbers};
use weldseam::pipeline::Planner;
use weldseam::pipeline::passes::{self, Motion};
use weldseam::process::Procedure;
use weldseam::sim::{JointGeometry, Simulation, demo_scene};
use weldseam_proto::text::{Dialect, Request, parse_request};

use crate::scenes;
use crate::util::Cell;

const WAIT: Duration = Duration::from_secs(180);

/// 12 mm plates with a 60° groove 9 mm deep and a 1 mm root gap: more
/// than one bead fills it, and the torch's nozzle clears the plates at
/// the root (deeper at this angle, it blocks: `process.torch_blocked`).
fn thick_groove() -> &'static Simulation {
    let mut spec = demo_scene(JointType::VButt);
    spec.joint =
        JointGeometry::VButt { thickness_mm: 12.0, groove_angle_deg: 60.0, groove_depth_mm: 9.0, root_gap_mm: 1.0 };
    scenes::by_default_camera(&spec)
}

fn config() -> Config {
    let mut c = Config::default();
    c.server.fresh_frame_timeout = Duration::from_secs(10);
    c.server.pipeline_threads = 2;
    c.server.shutdown_grace = Duration::from_secs(60);
    c.trajectory.step_mm = 20.0;
    // The example procedure's V-groove does not weave; here its root pass
    // weaves over the 1 mm gap, so every dialect is held to carry a weave,
    // not only the zeros of a pass that lays none.
    let mut procedure = Procedure::example();
    for entry in procedure.entries.iter_mut().filter(|e| e.joint == JointType::VButt) {
        entry.weave = Some(WeaveSpec {
            pattern: WeavePattern::Sine,
            above_gap_mm: 0.5,
            amplitude_per_gap: 0.5,
            max_amplitude_mm: 2.0,
            wavelength_mm: 3.0,
            dwell_s: 0.0,
        });
    }
    c.process = ProcessParams { procedure: Some(procedure), plate_thickness_mm: Some(12.0) };
    c
}

fn trigger_line(dialect: Dialect, sim: &Simulation) -> String {
    crate::text_link::trigger_line_for("v_butt", dialect, sim)
}

/// What the procedure cut from a seam, for a failure's message.
fn process_cut(seam: &weldseam::pipeline::Seam) -> Vec<(usize, usize, &'static str, String)> {
    let cut = seam.process.as_ref().map(|p| p.cut.as_slice()).unwrap_or_default();
    cut.iter().map(|c| (c.first, c.last, c.rule.id, c.reason.clone())).collect()
}

/// Within one unit of the last of `decimals`, and a little for the
/// rounding either way.
fn near(a: f64, b: f64, decimals: usize) -> bool {
    (a - b).abs() <= 1.01 * 10f64.powi(-(decimals as i32))
}

/// A robot program on the text link, once the daemon counts the camera
/// (a PING answers with the cameras connected), or after 5 s of asking.
async fn robot_once_the_camera_is_in(cell: &Cell) -> TextRobot {
    let mut robot = TextRobot::connect(&cell.daemon.text_addr.to_string(), WAIT).await.unwrap();
    for _ in 0..100 {
        if robot.ask("PING").await.unwrap().starts_with("0,1,") {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    robot
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_dialect_pulls_each_pass_with_its_speeds_and_weave() {
    let sim = thick_groove();
    let config = config();
    let cell = Cell::start(config.clone()).await;
    let (stop_camera, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut robot = robot_once_the_camera_is_in(&cell).await;
    for dialect in Dialect::ALL {
        let hello = robot.ask(&format!("HELLO,{},PROCESS", dialect.name())).await.unwrap();
        assert_eq!(reply_numbers(&hello, dialect, 3), Some(vec![0.0, 2.0, 1.0]), "{hello}");
        let trigger = trigger_line(dialect, sim);
        let ok = robot.ask(&trigger).await.unwrap();
        let status = reply_numbers(&ok, dialect, 3).unwrap_or_default();
        assert_eq!(status.first(), Some(&0.0), "{dialect:?}: {ok}");
        let pulled: Vec<PulledSeam> =
            robot.pull_plan(dialect, status[2] as u64, true).await.unwrap_or_else(|e| panic!("{dialect:?}: {e}"));
        assert_eq!(pulled.len(), status[1] as usize);

        // The same plan in-process, from the request the daemon read.
        let Ok(Request::Trigger(line)) = parse_request(&trigger, Some(dialect)) else { panic!("{trigger}") };
        let request = from_proto::text_plan_request(&line, dialect, config.euler).unwrap();
        let plan = Planner::new(config.clone()).plan(&sim.cloud, &request).unwrap();
        let seam = &plan.seams[0];
        let passes = passes::pass_trajectories(seam).expect("a procedure is configured");
        // Where the dialect's program has no weave function, the pieces
        // come woven into the path ([`to_text::weave_laid_by`]).
        let expected: Vec<Vec<(Vec<f64>, Motion)>> = plan
            .seams
            .iter()
            .flat_map(|seam| to_text::link_pieces(seam, dialect, true))
            .map(|piece| piece.into_iter().map(|(w, m)| (to_text::pose(&w, dialect), m.unwrap())).collect())
            .collect();
        assert!(passes.pieces.len() >= 2, "{dialect:?}: a 9 mm groove in several passes: {:?}", process_cut(seam));
        assert_eq!(pulled.len(), expected.len(), "{dialect:?}: one seam on the link per piece of a pass");
        let (position, rotation) = dialect.decimals();
        let unit = if dialect == Dialect::Ur { 0.001 } else { 1.0 };
        let mut weaving = 0;
        for (k, (got, want)) in pulled.iter().zip(&expected).enumerate() {
            assert_eq!(got.weld.len(), want.len(), "{dialect:?} seam {}", k + 1);
            for ((pose, process), (want_pose, motion)) in got.weld.iter().zip(want) {
                for (i, (a, b)) in pose.iter().zip(want_pose).enumerate() {
                    assert!(
                        near(*a, *b, if i < 3 { position } else { rotation }),
                        "{dialect:?}: {pose:?} {want_pose:?}"
                    );
                }
                let [speed, amplitude, frequency] = process.expect("a process line after each weld line");
                assert!(near(speed, motion.travel_speed_mm_s * unit, position), "{dialect:?}: {speed} for {motion:?}");
                assert!(speed > 0.0);
                assert!(near(amplitude, motion.weave_amplitude_mm * unit, position), "{amplitude} for {motion:?}");
                assert!(near(frequency, motion.weave_frequency_hz, 3), "{frequency} for {motion:?}");
                weaving += usize::from(amplitude > 0.0);
            }
        }
        // The root is the first seam, and only it lies in the gap: the
        // only pass that may weave.
        let root_points = passes.pieces.iter().filter(|p| p.pass == passes::PassId::Root).count();
        eprintln!(
            "{dialect:?}: {} seams on the link ({root_points} of the root), {} lines, {} of them carrying a weave",
            pulled.len(),
            status[2],
            weaving
        );
        assert_eq!(passes.pieces[0].pass, passes::PassId::Root);
        match to_text::weave_laid_by(dialect) {
            to_text::WeaveLaidBy::Controller => {
                assert!(weaving > 0, "{dialect:?}: the root pass weaves, and no line carried its weave");
            }
            to_text::WeaveLaidBy::Path => {
                // No line carries a weave; the root's piece comes as the
                // points of its woven path, more than the plan's.
                assert_eq!(weaving, 0, "{dialect:?}: a weave on a line of a path already woven");
                let root = passes.pieces[0].points.len();
                assert!(
                    pulled[0].weld.len() > 2 * root,
                    "{dialect:?}: {} lines for {root} points",
                    pulled[0].weld.len()
                );
            }
        }
    }

    // A program that does not ask gets the same seams, poses only.
    let hello = robot.ask("HELLO,kuka").await.unwrap();
    assert_eq!(hello, "0,2,0\r\n");
    let ok = robot.ask(&trigger_line(Dialect::Kuka, sim)).await.unwrap();
    let status = reply_numbers(&ok, Dialect::Kuka, 3).unwrap();
    let pulled = robot.pull_plan(Dialect::Kuka, status[2] as u64, false).await.unwrap();
    assert!(pulled.len() >= 3 && pulled.iter().all(|s| s.weld.iter().all(|(_, p)| p.is_none())));
    drop(robot);
    let _ = stop_camera.send(());
    camera.await.unwrap();
    cell.shutdown().await;
}

/// `weldseam controller --text --process`, run as a process against the
/// daemon on 127.0.0.1 port 0 with the procedure configured, in the ABB
/// and the FANUC dialect: it asks for the process lines, pulls and checks
/// every seam, and prints each weld waypoint's travel speed and weave,
/// those the plan gives. The binary
/// controller, which asks for `along_seam`, prints the procedure and each
/// waypoint's passes and speed beside its pose.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_controller_command_prints_each_weld_waypoints_speed_and_weave() {
    let sim = thick_groove();
    let config = config();
    let cell = Cell::start(config.clone()).await;
    let (stop_camera, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    drop(robot_once_the_camera_is_in(&cell).await);
    let [x, y, z] = sim.pose.xyz_mm;
    let [rx, ry, rz] = sim.pose.angles_deg;
    let pose = format!("--pose={x},{y},{z},{rx},{ry},{rz}");
    let run = |args: Vec<String>| {
        tokio::task::spawn_blocking(move || {
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_weldseam")).args(&args).output().unwrap();
            let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
            assert!(out.status.success(), "{args:?}: {stdout}{}", String::from_utf8_lossy(&out.stderr));
            stdout
        })
    };
    let text_addr = cell.daemon.text_addr.to_string();
    let mut sessions = Vec::new();
    for dialect in [Dialect::Abb, Dialect::Fanuc] {
        let session = run(["controller", "--text", "--process", "--dialect", dialect.name(), "--connect", &text_addr]
            .into_iter()
            .map(String::from)
            .chain(["--joint".into(), "v_butt".into(), pose.clone()])
            .collect())
        .await
        .unwrap();
        sessions.push((dialect, session));
    }
    let binary = run(["controller", "--connect", &cell.controller, "--joint", "v_butt", &pose]
        .into_iter()
        .map(String::from)
        .collect())
    .await
    .unwrap();
    let _ = stop_camera.send(());
    camera.await.unwrap();
    cell.shutdown().await;

    // The same plan in-process: one seam on the link per piece of a pass.
    let trigger = trigger_line(Dialect::Abb, sim);
    let Ok(Request::Trigger(line)) = parse_request(&trigger, Some(Dialect::Abb)) else { panic!("{trigger}") };
    let request = from_proto::text_plan_request(&line, Dialect::Abb, config.euler).unwrap();
    let plan = Planner::new(config.clone()).plan(&sim.cloud, &request).unwrap();
    let pieces: Vec<Vec<Motion>> = plan
        .seams
        .iter()
        .flat_map(passes::seam_pieces)
        .map(|piece| piece.into_iter().map(|(_, m)| m.unwrap()).collect())
        .collect();
    assert!(pieces.len() >= 2, "several passes: {:?}", process_cut(&plan.seams[0]));
    let expected: Vec<(usize, usize, &Motion)> = pieces
        .iter()
        .enumerate()
        .flat_map(|(s, piece)| piece.iter().enumerate().map(move |(w, m)| (s + 1, w + 1, m)))
        .collect();
    // Each dialect's session: every process line printed as received, and
    // a row per weld waypoint, those of the plan.
    for (dialect, session) in &sessions {
        let lines: Vec<&str> = session.lines().collect();
        let hello = format!("> HELLO,{},PROCESS", dialect.name());
        assert_eq!(lines[..2], [hello.as_str(), "< 0,2,1"], "{session}");
        assert!(lines.iter().any(|l| l.starts_with("< 4,1,")), "{session}");
        let rows: Vec<(usize, usize, f64, f64, f64)> = lines
            .iter()
            .filter_map(|l| {
                let (place, rest) = l.trim_start().split_once("  speed ")?;
                let (seam, waypoint) = place.split_once('.')?;
                let (speed, rest) = rest.split_once(" mm/s  weave ")?;
                let (amplitude, rest) = rest.split_once(" mm at ")?;
                let frequency = rest.strip_suffix(" Hz")?;
                Some((
                    seam.parse().ok()?,
                    waypoint.parse().ok()?,
                    speed.parse().ok()?,
                    amplitude.parse().ok()?,
                    frequency.parse().ok()?,
                ))
            })
            .collect();
        assert_eq!(rows.len(), expected.len(), "a row per weld waypoint of every seam on the link:\n{session}");
        let (position, _) = dialect.decimals();
        for ((seam, waypoint, speed, amplitude, frequency), (s, w, motion)) in rows.iter().zip(&expected) {
            assert_eq!((*seam, *waypoint), (*s, *w));
            assert!(
                *speed > 0.0 && near(*speed, motion.travel_speed_mm_s, position),
                "{dialect:?} {seam}.{waypoint}: {speed} for {motion:?}"
            );
            assert!(near(*amplitude, motion.weave_amplitude_mm, position), "{amplitude} for {motion:?}");
            assert!(near(*frequency, motion.weave_frequency_hz, 3), "{frequency} for {motion:?}");
        }
    }

    // The binary link's table: the procedure, then per waypoint its
    // passes and the first pass's speed, or that it is cut.
    let seam = &plan.seams[0];
    let process = seam.process.as_ref().unwrap();
    assert!(binary.contains(&format!("  procedure {}", process.procedure)), "{binary}");
    assert!(binary.contains("passes speed mm/s"), "{binary}");
    let cut_rows = binary.lines().filter(|l| l.trim_end().ends_with(" cut")).count();
    let cut_waypoints: usize = process.cut.iter().map(|c| c.last - c.first + 1).sum();
    assert_eq!(cut_rows, cut_waypoints, "{binary}");
    assert_eq!(binary.lines().filter(|l| l.starts_with("  cut: waypoints ")).count(), process.cut.len(), "{binary}");
}
