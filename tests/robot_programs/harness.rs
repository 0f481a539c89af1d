//! What every robot program's emulation runs against: the daemon on
//! loopback with a camera answering triggers (tests/util.rs's Cell), the
//! scenarios the programs must complete, the poses `plan --json` gives
//! for the same frame and request (the library's planner on the same
//! cloud) to compare the program's moves with, and a hook that stops the
//! daemon when the program sends a given line. The simulated frames are
//! the ones every suite shares (tests/scenes.rs).

use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use tokio::sync::oneshot;
use tokio::task::JoinHandle;
use weldseam::config::Config;
use weldseam::config::procedure::{WeavePattern, WeaveSpec};
use weldseam::convert::from_proto::text_plan_request;
use weldseam::geometry::Isometry3;
use weldseam::joint::JointType;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::ControllerClient;
use weldseam::pipeline::Planner;
use weldseam::sim::{Draw, Simulation};
use weldseam_proto::text::{Dialect, PlanLine};

use crate::scenes;
use crate::util::Cell;

/// Called with each line a program sends, before it goes out.
pub type SendHook = Box<dyn FnMut(&str) + Send>;

/// The demo lap joint (one seam, about 250 mm long).
pub fn lap() -> &'static Simulation {
    static SCENE: OnceLock<&'static Simulation> = OnceLock::new();
    SCENE.get_or_init(|| scenes::demo(JointType::Lap))
}

/// Three workpieces in one frame: an I-butt, a lap and a tee, of which
/// three seams are planned.
pub fn several() -> &'static Simulation {
    static SCENE: OnceLock<&'static Simulation> = OnceLock::new();
    SCENE.get_or_init(|| {
        let (_, spec) = weldseam::sim::multi_suite(Draw::Documented)
            .into_iter()
            .find(|(name, _)| name.starts_with("multi-01"))
            .expect("the three-workpiece scene");
        scenes::by_default_camera(&spec)
    })
}

/// 12 mm plates with a 60° V-groove 9 mm deep and a 1 mm root gap,
/// welded in several passes under the example procedure.
pub fn thick_groove() -> &'static Simulation {
    static SCENE: OnceLock<&'static Simulation> = OnceLock::new();
    SCENE.get_or_init(|| {
        let mut spec = weldseam::sim::demo_scene(JointType::VButt);
        spec.joint = weldseam::sim::JointGeometry::VButt {
            thickness_mm: 12.0,
            groove_angle_deg: 60.0,
            groove_depth_mm: 9.0,
            root_gap_mm: 1.0,
        };
        scenes::by_default_camera(&spec)
    })
}

/// What a scenario asks of a program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scenario {
    /// The lap joint, a waypoint every 25 mm: one seam.
    OneSeam,
    /// The lap joint at a 0.9 mm step: over 250 waypoints.
    LongSeam,
    /// Three seams in one frame, the joint left to the daemon.
    SeveralSeams,
    /// A tee's fillet asked of the lap joint: refused with a reason.
    Refusal,
    /// The daemon takes lines of 80 bytes only, and the plan line, with a
    /// joint set, is longer.
    TooLongLine,
    /// The daemon stops when the program sends its first CHECK: the whole
    /// plan fetched, the arc not yet on.
    StopBeforeArc,
    /// The daemon stops when the program sends its fifth NEXT.
    StopDuringFetch,
    /// A thick V-groove with the example weld procedure configured, its
    /// root pass weaving: each pass a seam on the link, every weld
    /// waypoint with its process line.
    Passes,
}

impl Scenario {
    pub fn scene(self) -> &'static Simulation {
        match self {
            Scenario::SeveralSeams => several(),
            Scenario::Passes => thick_groove(),
            _ => lap(),
        }
    }

    /// The joint the program asks for.
    pub fn joint(self) -> &'static str {
        match self {
            Scenario::SeveralSeams => "auto",
            Scenario::Refusal => "t_fillet",
            Scenario::TooLongLine => "v_butt+i_butt+lap",
            Scenario::Passes => "v_butt",
            _ => "lap",
        }
    }

    pub fn config(self) -> Config {
        let mut c = Config::default();
        c.server.fresh_frame_timeout = Duration::from_secs(10);
        c.server.pipeline_threads = 2;
        c.server.shutdown_grace = Duration::from_secs(30);
        c.trajectory.step_mm = match self {
            Scenario::LongSeam => 0.9,
            _ => 25.0,
        };
        if self == Scenario::Passes {
            // The example procedure's V-groove does not weave; here its
            // root pass weaves over the 1 mm gap, so each program's weave
            // is held to the plan's as well.
            let mut procedure = weldseam::process::Procedure::example();
            for entry in procedure.entries.iter_mut().filter(|e| e.joint == JointType::VButt) {
                entry.weave = Some(WeaveSpec {
                    pattern: WeavePattern::Sine,
                    above_gap_mm: 0.5,
                    amplitude_per_gap: 0.5,
                    max_amplitude_mm: 2.0,
                    // Not a whole part of the 24 mm between waypoints,
                    // so a weave whose phase began again at a waypoint
                    // would be seen.
                    wavelength_mm: 3.5,
                    dwell_s: 0.0,
                });
            }
            c.process.procedure = Some(procedure);
            c.process.plate_thickness_mm = Some(12.0);
        }
        if self == Scenario::TooLongLine {
            c.text_link.max_line_bytes = 80;
        }
        c
    }

    /// Whether the daemon stops when the program sends `line` (without its
    /// line end), its `nexts`th NEXT when it is one.
    pub fn stops_at(self, line: &str, nexts: usize) -> bool {
        match self {
            Scenario::StopBeforeArc => line.starts_with("CHECK"),
            Scenario::StopDuringFetch => line == "NEXT" && nexts == 5,
            _ => false,
        }
    }
}

/// The daemon of one scenario, its camera, and a way to stop it from the
/// program's thread.
pub struct Daemon {
    pub text_addr: std::net::SocketAddr,
    cell: Arc<Mutex<Option<Cell>>>,
    camera: Option<(oneshot::Sender<()>, JoinHandle<()>)>,
}

impl Daemon {
    pub async fn start(scenario: Scenario) -> Daemon {
        let cell = Cell::start(scenario.config()).await;
        let frames = vec![Arc::new(scenario.scene().cloud.clone())];
        let camera = cell.camera(frames, CameraOptions::default());
        let mut ctl = ControllerClient::connect(&cell.controller, "test").await.unwrap();
        ctl.wait_for_camera(Duration::from_secs(10)).await.unwrap();
        drop(ctl);
        let text_addr = cell.daemon.text_addr;
        Daemon { text_addr, cell: Arc::new(Mutex::new(Some(cell))), camera: Some(camera) }
    }

    /// A hook for the program's thread (not a runtime thread): called with
    /// each line the program sends, it stops the daemon when the scenario
    /// says, before the line goes out.
    pub fn stopper(&self, scenario: Scenario) -> SendHook {
        let cell = Arc::clone(&self.cell);
        let runtime = tokio::runtime::Handle::current();
        let mut nexts = 0;
        Box::new(move |sent: &str| {
            // A piece of a line (RAPID sends a long one in pieces) or a
            // whole line with or without its end.
            let line = sent.trim_end_matches(['\r', '\n']);
            nexts += usize::from(line == "NEXT");
            if scenario.stops_at(line, nexts) {
                let taken = cell.lock().unwrap().take();
                if let Some(cell) = taken {
                    runtime.block_on(cell.shutdown());
                }
            }
        })
    }

    /// Stops the camera and, unless a scenario did, the daemon.
    pub async fn stop(mut self) {
        if let Some((stop, camera)) = self.camera.take() {
            let _ = stop.send(());
            let _ = camera.await;
        }
        let taken = self.cell.lock().unwrap().take();
        if let Some(cell) = taken {
            cell.shutdown().await;
        }
    }
}

/// The weld waypoints `plan --json` gives for the scenario's frame, asked
/// as the program's plan line asks (the joint and the capture pose in
/// `dialect`), seam by seam, as tool poses in the base frame (mm).
pub fn reference(scenario: Scenario, dialect: Dialect, pose_numbers: &[f64]) -> Vec<Vec<Isometry3<f64>>> {
    let config = scenario.config();
    let line = PlanLine { joint: scenario.joint().into(), pose: pose_numbers.to_vec(), groove_depth: None };
    let request = text_plan_request(&line, dialect, config.euler).expect("the program's plan line");
    let planner = Planner::new(config);
    let plan = planner.plan(&scenario.scene().cloud, &request).expect("the reference plan");
    plan.seams
        .iter()
        .map(|seam| {
            seam.waypoints.iter().map(|w| Isometry3::from_parts(w.position.into(), w.orientation.into())).collect()
        })
        .collect()
}

/// The pieces the robot welds for the scenario's frame, asked as the
/// program asks: each piece of each pass its poses (base frame, mm) with
/// the travel speed (mm/s) and the weave's half-swing (mm) and frequency
/// (Hz) into each, as the daemon sends them.
pub fn reference_pieces(
    scenario: Scenario,
    dialect: Dialect,
    pose_numbers: &[f64],
) -> Vec<Vec<(Isometry3<f64>, [f64; 3])>> {
    let config = scenario.config();
    let line = PlanLine { joint: scenario.joint().into(), pose: pose_numbers.to_vec(), groove_depth: None };
    let request = text_plan_request(&line, dialect, config.euler).expect("the program's plan line");
    let plan = Planner::new(config).plan(&scenario.scene().cloud, &request).expect("the reference plan");
    plan.seams
        .iter()
        .flat_map(weldseam::pipeline::passes::seam_pieces)
        .map(|piece| {
            piece
                .into_iter()
                .map(|(w, m)| {
                    let m = m.expect("a procedure is configured");
                    let pose = Isometry3::from_parts(w.position.into(), w.orientation.into());
                    (pose, [m.travel_speed_mm_s, m.weave_amplitude_mm, m.weave_frequency_hz])
                })
                .collect()
        })
        .collect()
}

/// Whether two tool poses agree to 0.01 mm and 0.01°.
pub fn same_pose(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Result<(), String> {
    let distance = (a.translation.vector - b.translation.vector).norm();
    let angle = a.rotation.angle_to(&b.rotation).to_degrees();
    if distance <= 0.01 && angle <= 0.01 { Ok(()) } else { Err(format!("{distance:.4} mm and {angle:.4}° apart")) }
}

/// The reference is what the daemon serves: a KUKA session's weld lines
/// on the harness's daemon agree with `reference` to the line's decimals,
/// and the stop hook stops the daemon at the line the scenario names.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_reference_is_what_the_daemon_serves_and_the_hook_stops_it() {
    use std::io::{BufRead, BufReader, Write};

    let scenario = Scenario::StopDuringFetch;
    let daemon = Daemon::start(scenario).await;
    let convention = weldseam::convert::to_text::convention(Dialect::Kuka);
    let pose = convention.numbers(&scenario.scene().pose.to_isometry(Default::default()));
    let pose: Vec<f64> = pose[..6].iter().map(|v| (v * 1e4).round() / 1e4).collect();
    let trigger = format!("TRIGGER,lap,{}", pose.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(","));
    let mut hook = daemon.stopper(scenario);
    let addr = daemon.text_addr;
    let replies = tokio::task::spawn_blocking(move || {
        let stream = std::net::TcpStream::connect(addr).unwrap();
        stream.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
        let mut reader = BufReader::new(stream.try_clone().unwrap());
        let mut writer = stream;
        let mut replies = Vec::new();
        let lines = ["HELLO,kuka".to_string(), trigger].into_iter().chain(std::iter::repeat_n("NEXT".to_string(), 8));
        for line in lines {
            hook(&line);
            if writer.write_all(format!("{line}\r\n").as_bytes()).is_err() {
                break;
            }
            let mut reply = String::new();
            if reader.read_line(&mut reply).unwrap_or(0) == 0 {
                break;
            }
            replies.push(reply);
        }
        replies
    })
    .await
    .unwrap();
    daemon.stop().await;
    // Hello, the ok line and four lines pulled; the fifth NEXT met a
    // stopped daemon.
    assert_eq!(replies.len(), 6, "{replies:?}");
    let expected = reference(scenario, Dialect::Kuka, &pose);
    for (k, reply) in replies[3..].iter().enumerate() {
        let n: Vec<f64> = reply.trim().split(',').map(|f| f.parse().unwrap()).collect();
        assert_eq!(n[0], 2.0, "{reply}");
        let robot = convention.to_robot_pose(&n[3..9], Default::default()).unwrap();
        let got = robot.to_isometry(Default::default());
        same_pose(&got, &expected[0][k]).unwrap_or_else(|e| panic!("waypoint {k}: {e}"));
    }
}
