//! The cell daemon over real loopback TCP: started in-process on ephemeral
//! ports, driven by the mock camera and controller and by crafted bytes.
//! Protocol behaviour uses small frames; only the end-to-end accuracy
//! checks plan full simulated frames (four plans in all).

use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::oneshot;
use tokio::task::JoinHandle;
use weldseam::camera::CameraModel;
use weldseam::cloud::PointCloud;
use weldseam::config::Config;
use weldseam::geometry::{Vec3, distance_to_polyline};
use weldseam::joint::JointType;
use weldseam::mock::ClientError;
use weldseam::mock::camera::{CameraOptions, MockCamera};
use weldseam::mock::controller::ControllerClient;
use weldseam::server::{self, ServerError, ServerState, Stopped};
use weldseam::sim::{Simulation, demo_scene, simulate};
use weldseam_proto::frame::{self, HEADER_BYTES, Header};
use weldseam_proto::message::{FrameSelect, Hello, PlanReply, PlanRequest, Role, Tag, Trigger, joint_code};
use weldseam_proto::{ErrorCode, Message, PROTOCOL_VERSION};

const WAIT: Duration = Duration::from_secs(60);

struct Cell {
    camera: String,
    controller: String,
    stop: Option<oneshot::Sender<()>>,
    server: JoinHandle<Result<Stopped, ServerError>>,
}

impl Cell {
    async fn start(config: Config) -> Cell {
        let camera = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let controller = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let (camera_addr, controller_addr) =
            (camera.local_addr().unwrap().to_string(), controller.local_addr().unwrap().to_string());
        let state = ServerState::new(config).unwrap();
        let (stop, stopped) = oneshot::channel::<()>();
        let server = tokio::spawn(server::run(camera, controller, stopped, state));
        Cell { camera: camera_addr, controller: controller_addr, stop: Some(stop), server }
    }

    async fn controller(&self) -> ControllerClient {
        ControllerClient::connect(&self.controller, "test-controller").await.unwrap()
    }

    /// Starts a mock camera serving `frames`; it stops with the returned sender.
    fn camera(&self, frames: Vec<Arc<PointCloud>>, options: CameraOptions) -> (oneshot::Sender<()>, JoinHandle<()>) {
        let (tx, rx) = oneshot::channel::<()>();
        let cam = MockCamera::new(self.camera.clone(), frames, options);
        let handle = tokio::spawn(async move {
            let _ = cam.run(rx).await;
        });
        (tx, handle)
    }

    async fn shutdown(mut self) -> Stopped {
        let _ = self.stop.take().unwrap().send(());
        tokio::time::timeout(WAIT, self.server).await.unwrap().unwrap().unwrap()
    }
}

fn config() -> Config {
    let mut c = Config::default();
    c.server.stall_timeout = Duration::from_millis(400);
    c.server.fresh_frame_timeout = Duration::from_secs(10);
    c.server.pipeline_threads = 2;
    c.server.shutdown_grace = Duration::from_secs(60);
    c
}

/// A 64 x 48 organized frame of a flat plate 700 mm away: valid points,
/// no seam.
fn small_cloud() -> PointCloud {
    let (w, h) = (64, 48);
    let points = (0..w * h).map(|i| [(i % w) as f32 * 0.4, (i / w) as f32 * 0.4, 700.0]).collect();
    PointCloud::organized(w, h, points).unwrap()
}

fn request(id: u64, frame: FrameSelect) -> PlanRequest {
    PlanRequest {
        request_id: id,
        joint: joint_code::LAP,
        groove_depth_mm: None,
        pose: [800.0, 0.0, 500.0, 180.0, 0.0, 0.0],
        step_mm: None,
        work_angle_deg: None,
        travel_angle_deg: None,
        frame,
        timeout_ms: 0,
    }
}

fn sim_request(id: u64, joint: JointType, sim: &Simulation, frame: FrameSelect) -> PlanRequest {
    weldseam::mock::controller::request_for_simulation(id, joint, sim, frame)
}

/// The paper's metric: 12 points on the true seam, each within 1 mm of
/// the waypoint polyline.
fn assert_matches_truth(reply: &PlanReply, sim: &Simulation) {
    let seam = reply.result.seams.first().expect("a seam");
    let path: Vec<Vec3> = seam.waypoints.iter().map(|w| Vec3::from(w.xyz)).collect();
    let (a, b) = (sim.truth.start_base, sim.truth.end_base);
    let worst = (0..12).map(|k| distance_to_polyline(&(a + (b - a) * (k as f64 / 11.0)), &path)).fold(0.0, f64::max);
    assert!(worst < 1.0, "{:?}: worst of 12 truth points is {worst:.3} mm from the trajectory", sim.truth.joint);
}

fn refused(r: Result<PlanReply, ClientError>) -> (ErrorCode, String) {
    match r {
        Err(ClientError::Refused(e)) => (e.code, e.message),
        other => panic!("expected an error reply, got {other:?}"),
    }
}

/// A raw connection for crafted bytes.
struct Raw(TcpStream);

impl Raw {
    async fn connect(addr: &str) -> Raw {
        Raw(TcpStream::connect(addr).await.unwrap())
    }

    async fn hello(addr: &str, role: Role) -> Raw {
        let mut raw = Raw::connect(addr).await;
        raw.send(&Message::Hello(Hello { protocol_version: PROTOCOL_VERSION, role, name: "raw".into() })).await;
        assert!(matches!(raw.recv().await, Some(Message::HelloAck(_))));
        raw
    }

    async fn write(&mut self, bytes: &[u8]) {
        self.0.write_all(bytes).await.unwrap();
    }

    async fn send(&mut self, m: &Message) {
        self.write(&frame::encode(m).unwrap()).await;
    }

    /// The next message, or None once the daemon has closed the connection.
    async fn recv(&mut self) -> Option<Message> {
        let mut head = [0u8; HEADER_BYTES];
        let read = tokio::time::timeout(WAIT, self.0.read_exact(&mut head)).await.expect("the daemon answers");
        read.ok()?;
        let header = Header::parse(&head, u64::MAX).unwrap();
        let mut body = vec![0u8; header.length as usize];
        self.0.read_exact(&mut body).await.ok()?;
        Some(frame::decode_body(header.tag, &body).unwrap())
    }

    async fn expect_error(&mut self, code: ErrorCode) {
        match self.recv().await {
            Some(Message::Error(e)) => assert_eq!(e.code, code, "{}", e.message),
            other => panic!("expected error {code}, got {other:?}"),
        }
    }

    async fn expect_closed(&mut self) {
        assert!(self.recv().await.is_none(), "the daemon should have closed the connection");
    }

    async fn ping(&mut self) {
        self.send(&Message::Ping).await;
        assert!(matches!(self.recv().await, Some(Message::Status(_))));
    }
}

/// Waits until the daemon reports a connected camera, so a trigger
/// request does not race the camera's connection.
async fn wait_for_camera(ctl: &mut ControllerClient) {
    ctl.wait_for_camera(Duration::from_secs(5)).await.expect("the mock camera connects");
}

fn frame_message(frame_id: u64, trigger_id: u64, cloud: &PointCloud) -> Message {
    Message::Frame(weldseam::mock::camera::frame_of(cloud, frame_id, trigger_id, 0))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_joint_end_to_end_in_trigger_mode() {
    let joints = JointType::ALL;
    let sims: Vec<Simulation> = joints.iter().map(|j| simulate(&demo_scene(*j), &CameraModel::default())).collect();
    let cell = Cell::start(config()).await;
    let (stop_cam, cam) =
        cell.camera(sims.iter().map(|s| Arc::new(s.cloud.clone())).collect(), CameraOptions::default());
    let mut ctl = cell.controller().await;
    wait_for_camera(&mut ctl).await;
    for (k, (joint, sim)) in joints.iter().zip(&sims).enumerate() {
        let id = 10 + k as u64;
        let reply = ctl.plan(sim_request(id, *joint, sim, FrameSelect::Trigger), WAIT).await.unwrap();
        assert_eq!(reply.request_id, id);
        assert_eq!(reply.frame_id, 1 + k as u64, "the frame answering this request's trigger");
        assert_matches_truth(&reply, sim);
    }
    let _ = stop_cam.send(());
    cam.await.unwrap();
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn free_run_next_frame_ping_during_plan_and_shutdown_with_plan_in_flight() {
    let sim = simulate(&demo_scene(JointType::Lap), &CameraModel::default());
    let cell = Cell::start(config()).await;
    let options = CameraOptions { free_run_hz: Some(4.0), ..CameraOptions::default() };
    let (stop_cam, cam) = cell.camera(vec![Arc::new(sim.cloud.clone())], options);
    let mut ctl = cell.controller().await;
    // Wait until the camera is streaming, so the request has a next frame.
    let mut pinger = cell.controller().await;
    for _ in 0..200 {
        if pinger.ping(WAIT).await.unwrap().frames_received > 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    let before = pinger.ping(WAIT).await.unwrap().frames_received;
    assert!(before > 0, "the free-running camera sent no frame");
    let plan = tokio::spawn(async move {
        ctl.plan(sim_request(7, JointType::Lap, &sim, FrameSelect::NextFrame), WAIT).await.map(|r| (r, sim))
    });
    // A ping is answered while the plan is queued or running.
    let mut seen_busy_queue = false;
    for _ in 0..400 {
        if pinger.ping(WAIT).await.unwrap().queue_length == 1 {
            seen_busy_queue = true;
            break;
        }
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    assert!(seen_busy_queue, "no ping saw the plan in the queue");
    // Keep the camera until the frame after the request has arrived.
    for _ in 0..400 {
        if pinger.ping(WAIT).await.unwrap().frames_received > before {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let _ = stop_cam.send(());
    cam.await.unwrap();
    // Shutdown while the plan is in flight: it completes, then the server stops.
    let stopped = cell.shutdown().await;
    let (reply, sim) = plan.await.unwrap().unwrap();
    assert!(reply.frame_id > before, "NextFrame used frame {} which had arrived before the request", reply.frame_id);
    assert_matches_truth(&reply, &sim);
    assert_eq!(stopped, Stopped::Clean);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stale_frames_are_never_used_unless_named() {
    let mut c = config();
    c.server.fresh_frame_timeout = Duration::from_millis(300);
    let cell = Cell::start(c).await;
    // A camera that sends one frame and then answers nothing.
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    cam.send(&frame_message(1, 0, &small_cloud())).await;
    let mut ctl = cell.controller().await;
    for _ in 0..200 {
        if ctl.ping(WAIT).await.unwrap().frames_received == 1 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let (code, _) = refused(ctl.plan(request(1, FrameSelect::Trigger), WAIT).await);
    assert_eq!(code, ErrorCode::FrameTimeout);
    assert!(matches!(cam.recv().await, Some(Message::Trigger(Trigger { trigger_id: 1 }))));
    let (code, _) = refused(ctl.plan(request(2, FrameSelect::NextFrame), WAIT).await);
    assert_eq!(code, ErrorCode::FrameTimeout);
    // Named by id, the old frame is used (this flat frame has no seam).
    let (code, message) = refused(ctl.plan(request(3, FrameSelect::FrameId(1)), WAIT).await);
    assert_eq!(code, ErrorCode::PlanFailed);
    assert!(message.contains("frame 1"), "{message}");
    let (code, _) = refused(ctl.plan(request(4, FrameSelect::FrameId(99)), WAIT).await);
    assert_eq!(code, ErrorCode::UnknownFrame);
    drop(cam);
    // With no camera at all: a typed error, never the old frame.
    for _ in 0..200 {
        if !ctl.ping(WAIT).await.unwrap().camera_connected {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let (code, _) = refused(ctl.plan(request(5, FrameSelect::Trigger), WAIT).await);
    assert_eq!(code, ErrorCode::NoCamera);
    let (code, _) = refused(ctl.plan(request(6, FrameSelect::NextFrame), WAIT).await);
    assert_eq!(code, ErrorCode::NoCamera);
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_controller_input_gets_typed_errors() {
    let cell = Cell::start(config()).await;
    let hello = frame::encode(&Message::Hello(Hello {
        protocol_version: PROTOCOL_VERSION,
        role: Role::Controller,
        name: "x".into(),
    }))
    .unwrap();

    // Framing lost: an error reply, then the connection closes.
    let mut raw = Raw::connect(&cell.controller).await;
    let mut bad = hello.clone();
    bad[..4].copy_from_slice(b"HTTP");
    raw.write(&bad).await;
    raw.expect_error(ErrorCode::BadMagic).await;
    raw.expect_closed().await;

    let mut raw = Raw::connect(&cell.controller).await;
    let mut bad = hello.clone();
    bad[4] = 7;
    raw.write(&bad).await;
    raw.expect_error(ErrorCode::UnsupportedVersion).await;
    raw.expect_closed().await;

    let mut raw = Raw::connect(&cell.controller).await;
    raw.send(&Message::Hello(Hello { protocol_version: PROTOCOL_VERSION, role: Role::Camera, name: "x".into() })).await;
    raw.expect_error(ErrorCode::UnexpectedMessage).await;
    raw.expect_closed().await;

    let mut raw = Raw::hello(&cell.controller, Role::Controller).await;
    raw.write(&Header::new(Tag::PlanRequest, 1 << 40).to_bytes()).await;
    raw.expect_error(ErrorCode::TooLarge).await;
    raw.expect_closed().await;

    // Framing intact: an error reply, and the connection goes on.
    let mut raw = Raw::hello(&cell.controller, Role::Controller).await;
    let good = frame::encode(&Message::PlanRequest(request(1, FrameSelect::Trigger))).unwrap();
    let mut truncated = Header::new(Tag::PlanRequest, 20).to_bytes().to_vec();
    truncated.extend_from_slice(&good[HEADER_BYTES..HEADER_BYTES + 20]);
    raw.write(&truncated).await;
    raw.expect_error(ErrorCode::Malformed).await;
    raw.write(&Header { version: PROTOCOL_VERSION, tag: 900, length: 3 }.to_bytes()).await;
    raw.write(&[1, 2, 3]).await;
    raw.expect_error(ErrorCode::UnknownMessage).await;
    raw.send(&Message::PlanRequest(PlanRequest { joint: 9, ..request(2, FrameSelect::Trigger) })).await;
    raw.expect_error(ErrorCode::UnknownJoint).await;
    let mut nan = request(3, FrameSelect::Trigger);
    nan.pose[4] = f64::NAN;
    raw.send(&Message::PlanRequest(nan)).await;
    raw.expect_error(ErrorCode::BadRequest).await;
    raw.send(&Message::PlanRequest(PlanRequest { joint: joint_code::V_BUTT, ..request(4, FrameSelect::Trigger) }))
        .await;
    raw.expect_error(ErrorCode::BadRequest).await;
    raw.send(&Message::PlanRequest(request(5, FrameSelect::FrameId(42)))).await;
    raw.expect_error(ErrorCode::UnknownFrame).await;
    raw.send(&Message::Trigger(Trigger { trigger_id: 1 })).await;
    raw.expect_error(ErrorCode::UnexpectedMessage).await;
    raw.ping().await;

    // A peer that stalls mid-message is dropped; others are unaffected.
    let mut staller = Raw::hello(&cell.controller, Role::Controller).await;
    staller.write(&good[..HEADER_BYTES + 4]).await;
    staller.expect_closed().await;
    raw.ping().await;
    let mut fresh = cell.controller().await;
    fresh.ping(WAIT).await.unwrap();
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_frames_get_typed_errors_and_a_camera_dropping_mid_frame_can_reconnect() {
    let cell = Cell::start(config()).await;
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    let small = small_cloud();
    let good = frame::encode(&frame_message(1, 0, &small)).unwrap();

    // width x height not matching the payload.
    let mut wrong = good.clone();
    wrong[HEADER_BYTES + 24..HEADER_BYTES + 28].copy_from_slice(&65u32.to_le_bytes());
    cam.write(&wrong).await;
    cam.expect_error(ErrorCode::FrameSizeMismatch).await;
    // No valid point.
    let empty = PointCloud::organized(4, 2, vec![[f32::NAN; 3]; 8]).unwrap();
    cam.send(&frame_message(2, 0, &empty)).await;
    cam.expect_error(ErrorCode::EmptyFrame).await;
    let zeros = PointCloud::organized(4, 2, vec![[0.0; 3]; 8]).unwrap();
    cam.send(&frame_message(3, 0, &zeros)).await;
    cam.expect_error(ErrorCode::EmptyFrame).await;
    // A controller's message on the camera link.
    cam.send(&Message::PlanRequest(request(1, FrameSelect::Trigger))).await;
    cam.expect_error(ErrorCode::UnexpectedMessage).await;
    // Over the frame limit: framing is lost.
    cam.write(&Header::new(Tag::Frame, u64::MAX).to_bytes()).await;
    cam.expect_error(ErrorCode::TooLarge).await;
    cam.expect_closed().await;

    // A camera that drops in the middle of a frame.
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    cam.write(&good[..good.len() / 2]).await;
    drop(cam);
    let mut ctl = cell.controller().await;
    assert_eq!(ctl.ping(WAIT).await.unwrap().frames_received, 0);

    // The mock camera comes back and answers a trigger.
    let (stop_cam, cam_task) = cell.camera(vec![Arc::new(small)], CameraOptions::default());
    let mut answered = None;
    for id in 0..200 {
        match ctl.plan(request(id, FrameSelect::Trigger), WAIT).await {
            Err(ClientError::Refused(e)) if e.code == ErrorCode::NoCamera => {
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
            other => {
                answered = Some(other);
                break;
            }
        }
    }
    let (code, message) = refused(answered.expect("the camera reconnected"));
    assert_eq!(code, ErrorCode::PlanFailed, "the trigger was answered by a frame: {message}");
    assert_eq!(ctl.ping(WAIT).await.unwrap().frames_received, 1);
    let _ = stop_cam.send(());
    cam_task.await.unwrap();
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_controllers_at_once_and_one_dropping_mid_plan() {
    let cell = Cell::start(config()).await;
    let (stop_cam, cam) = cell.camera(vec![Arc::new(small_cloud())], CameraOptions::default());
    let mut a = cell.controller().await;
    wait_for_camera(&mut a).await;
    let mut b = cell.controller().await;
    let (ra, rb) =
        tokio::join!(a.plan(request(1, FrameSelect::Trigger), WAIT), b.plan(request(2, FrameSelect::Trigger), WAIT));
    let (ca, ma) = refused(ra);
    let (cb, mb) = refused(rb);
    // Both got a frame of their own (the flat frame has no seam).
    assert_eq!((ca, cb), (ErrorCode::PlanFailed, ErrorCode::PlanFailed), "{ma} / {mb}");
    assert_ne!(ma, mb, "each request had its own triggered frame");

    // A controller that leaves right after asking.
    let mut quitter = cell.controller().await;
    quitter.send(&Message::PlanRequest(request(3, FrameSelect::Trigger))).await.unwrap();
    drop(quitter);
    let mut status = a.ping(WAIT).await.unwrap();
    for _ in 0..400 {
        if status.frames_received >= 3 && status.queue_length == 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
        status = a.ping(WAIT).await.unwrap();
    }
    assert_eq!((status.frames_received, status.queue_length), (3, 0));
    let (code, _) = refused(b.plan(request(4, FrameSelect::Trigger), WAIT).await);
    assert_eq!(code, ErrorCode::PlanFailed);
    let _ = stop_cam.send(());
    cam.await.unwrap();
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_queue_answers_busy_at_once() {
    let mut c = config();
    c.server.plan_queue_depth = 1;
    c.server.fresh_frame_timeout = Duration::from_secs(5);
    let cell = Cell::start(c).await;
    // A camera that never answers triggers keeps the first request waiting.
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    let mut a = cell.controller().await;
    a.send(&Message::PlanRequest(request(1, FrameSelect::Trigger))).await.unwrap();
    assert!(matches!(cam.recv().await, Some(Message::Trigger(_))));
    let mut b = cell.controller().await;
    let (code, _) = refused(b.plan(request(2, FrameSelect::Trigger), WAIT).await);
    assert_eq!(code, ErrorCode::Busy);
    // The camera answers; the first request gets its frame.
    cam.send(&frame_message(1, 1, &small_cloud())).await;
    match a.recv().await.unwrap() {
        Message::Error(e) => assert_eq!((e.code, e.request_id), (ErrorCode::PlanFailed, Some(1))),
        other => panic!("{other:?}"),
    }
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn peers_outside_the_allowlist_are_refused() {
    let mut c = config();
    c.server.controller_allow = vec!["192.0.2.1".parse().unwrap()];
    let cell = Cell::start(c).await;
    let mut raw = Raw::connect(&cell.controller).await;
    raw.send(&Message::Ping).await;
    raw.expect_closed().await;
    // The camera link has no allowlist.
    Raw::hello(&cell.camera, Role::Camera).await.ping().await;
    cell.shutdown().await;
}
