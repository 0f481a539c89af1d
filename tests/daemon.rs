//! The cell daemon over real loopback TCP: started in-process on ephemeral
//! ports, driven by the mock camera and controller and by crafted bytes.
//! Protocol behaviour uses small frames; only the end-to-end accuracy
//! checks plan full simulated frames (four plans in all).

use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use weldseam::cloud::PointCloud;
use weldseam::config::Config;
use weldseam::geometry::{Vec3, distance_to_polyline};
use weldseam::joint::JointType;
use weldseam::mock::ClientError;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::ControllerClient;
use weldseam::server::Stopped;

use crate::scenes;
use crate::util::Cell;
use weldseam::sim::Simulation;
use weldseam_proto::frame::{self, HEADER_BYTES, Header};
use weldseam_proto::message::{FrameSelect, Hello, PlanReply, PlanRequest, PoseIn, Role, Tag, Trigger, joint_code};
use weldseam_proto::{ErrorCode, Message, PROTOCOL_VERSION};

mod along_seam;
mod requests;

const WAIT: Duration = Duration::from_secs(60);

// The suite's own ways into the shared test cell.
impl Cell {
    async fn controller(&self) -> ControllerClient {
        ControllerClient::connect(&self.controller, "test-controller").await.unwrap()
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
pub(crate) fn small_cloud() -> PointCloud {
    let (w, h) = (64, 48);
    let points = (0..w * h).map(|i| [(i % w) as f32 * 0.4, (i / w) as f32 * 0.4, 700.0]).collect();
    PointCloud::organized(w, h, points).unwrap()
}

/// A lap request on `frame` at a fixed pose; its plan needs no seam.
pub(crate) fn request(id: u64, frame: FrameSelect) -> PlanRequest {
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
        camera: None,
        hand_eye: None,
        start_near: None,
        roi: None,
        pose_in: None,
        one_seam: false,
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
        Raw::hello_as(addr, role, "raw").await
    }

    /// Connects and says Hello as `name`; returns once the ack is read.
    async fn hello_as(addr: &str, role: Role, name: &str) -> Raw {
        let mut raw = Raw::connect(addr).await;
        raw.send(&Message::Hello(Hello {
            protocol_version: PROTOCOL_VERSION,
            role,
            name: name.into(),
            capabilities: 0,
        }))
        .await;
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

    /// The daemon's acknowledgement of a frame: its code (0 = held).
    async fn expect_ack(&mut self, frame_id: u64, code: u16) -> weldseam_proto::message::FrameAck {
        match self.recv().await {
            Some(Message::FrameAck(ack)) => {
                assert_eq!((ack.frame_id, ack.code), (frame_id, code), "{}", ack.message);
                ack
            }
            other => panic!("expected the acknowledgement of frame {frame_id}, got {other:?}"),
        }
    }

    /// The next trigger, skipping frame acknowledgements.
    async fn expect_trigger(&mut self) -> u64 {
        loop {
            match self.recv().await {
                Some(Message::Trigger(t)) => return t.trigger_id,
                Some(Message::FrameAck(_)) => continue,
                other => panic!("expected a trigger, got {other:?}"),
            }
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

/// A frame captured now.
fn frame_message(frame_id: u64, trigger_id: u64, cloud: &PointCloud) -> Message {
    Message::Frame(weldseam::convert::to_proto::frame(cloud, frame_id, trigger_id, now_us(0)))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_joint_end_to_end_in_trigger_mode() {
    let joints = JointType::ALL;
    let sims: Vec<&Simulation> = joints.iter().map(|&j| scenes::demo(j)).collect();
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
    let sim = scenes::demo(JointType::Lap);
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
        ctl.plan(sim_request(7, JointType::Lap, sim, FrameSelect::NextFrame), WAIT).await.map(|r| (r, sim))
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
    // Keep the camera until a frame that qualifies has arrived: one may
    // have arrived between `before` and the request, and one may have been
    // uploading when the request came, so the third frame is surely fresh.
    for _ in 0..400 {
        if pinger.ping(WAIT).await.unwrap().frames_received >= before + 3 {
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
    assert_matches_truth(&reply, sim);
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
    assert_eq!(cam.expect_trigger().await, 1);
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
        capabilities: 0,
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
    let old = weldseam_proto::OLDEST_SERVED_VERSION - 1;
    bad[4..6].copy_from_slice(&old.to_le_bytes());
    raw.write(&bad).await;
    // The refusal comes in the old version's header, which this crate's
    // own header check would refuse in turn: read as raw bytes.
    let mut head = [0u8; HEADER_BYTES];
    tokio::time::timeout(WAIT, raw.0.read_exact(&mut head)).await.expect("the daemon answers").unwrap();
    assert_eq!(u16::from_le_bytes([head[4], head[5]]), old);
    let mut body = vec![0u8; u64::from_le_bytes(head[8..16].try_into().unwrap()) as usize];
    raw.0.read_exact(&mut body).await.unwrap();
    assert!(
        matches!(frame::decode_body(Tag::Error as u16, &body), Ok(Message::Error(e)) if e.code == ErrorCode::UnsupportedVersion)
    );
    raw.expect_closed().await;

    let mut raw = Raw::connect(&cell.controller).await;
    raw.send(&Message::Hello(Hello {
        protocol_version: PROTOCOL_VERSION,
        role: Role::Camera,
        name: "x".into(),
        capabilities: 0,
    }))
    .await;
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
    let too_deep =
        PlanRequest { joint: joint_code::V_BUTT, groove_depth_mm: Some(500.0), ..request(4, FrameSelect::Trigger) };
    raw.send(&Message::PlanRequest(too_deep)).await;
    raw.expect_error(ErrorCode::BadRequest).await;
    raw.send(&Message::PlanRequest(request(5, FrameSelect::FrameId(42)))).await;
    raw.expect_error(ErrorCode::UnknownFrame).await;
    // A pose in a convention of its own: read (so the request gets as far
    // as the frame it names), or refused naming the field.
    let kuka = PoseIn {
        convention: "kuka_abc".into(),
        length_unit: 0,
        angle_unit: 0,
        values: vec![800.0, 0.0, 500.0, 0.0, 0.0, 180.0],
    };
    let in_kuka = PlanRequest { pose_in: Some(kuka.clone()), ..request(7, FrameSelect::FrameId(42)) };
    raw.send(&Message::PlanRequest(in_kuka)).await;
    raw.expect_error(ErrorCode::UnknownFrame).await;
    for bad in [
        PoseIn { convention: "zyz".into(), ..kuka.clone() },
        PoseIn { angle_unit: 3, ..kuka.clone() },
        PoseIn { values: vec![800.0, 0.0, 500.0], ..kuka.clone() },
    ] {
        raw.send(&Message::PlanRequest(PlanRequest { pose_in: Some(bad), ..request(8, FrameSelect::Trigger) })).await;
        raw.expect_error(ErrorCode::BadRequest).await;
    }
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
    // Refused frames are acknowledged with their id and the error code.
    cam.expect_ack(1, ErrorCode::FrameSizeMismatch.code()).await;
    // No valid point.
    let empty = PointCloud::organized(4, 2, vec![[f32::NAN; 3]; 8]).unwrap();
    cam.send(&frame_message(2, 0, &empty)).await;
    cam.expect_ack(2, ErrorCode::EmptyFrame.code()).await;
    let zeros = PointCloud::organized(4, 2, vec![[0.0; 3]; 8]).unwrap();
    cam.send(&frame_message(3, 0, &zeros)).await;
    cam.expect_ack(3, ErrorCode::EmptyFrame.code()).await;
    // Units neither mm nor m.
    let mut units = good.clone();
    units[HEADER_BYTES + 32..HEADER_BYTES + 36].copy_from_slice(&7u32.to_le_bytes());
    cam.write(&units).await;
    cam.expect_ack(1, ErrorCode::UnknownUnits.code()).await;
    // A capture time an hour ahead of the daemon's clock.
    cam.send(&frame_stamped(4, 0, &small, now_us(3_600_000))).await;
    let ack = cam.expect_ack(4, ErrorCode::BadCaptureTime.code()).await;
    assert!(ack.message.contains("capture_time_tolerance_ms"), "{}", ack.message);
    // A good frame is held.
    cam.send(&frame_message(5, 0, &small)).await;
    let ack = cam.expect_ack(5, 0).await;
    assert_eq!((ack.requests, ack.message.as_str()), (0, ""));
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
    let status = ctl.ping(WAIT).await.unwrap();
    assert_eq!((status.frames_received, status.latest_frame_id), (1, Some(5)), "only frame 5 was held");

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
    assert_eq!(ctl.ping(WAIT).await.unwrap().frames_received, 2);
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
    cam.expect_trigger().await;
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

/// Microseconds since the Unix epoch on this machine's clock, shifted by
/// `offset_ms`.
fn now_us(offset_ms: i64) -> u64 {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_micros() as i64;
    (now + offset_ms * 1000).max(0) as u64
}

fn frame_stamped(frame_id: u64, trigger_id: u64, cloud: &PointCloud, capture_time_us: u64) -> Message {
    Message::Frame(weldseam::convert::to_proto::frame(cloud, frame_id, trigger_id, capture_time_us))
}

/// Reads until the reply or error for `request_id` (at most `WAIT`).
async fn wait_reply(ctl: &mut ControllerClient, request_id: u64) -> Result<PlanReply, ClientError> {
    let answer = async {
        loop {
            match ctl.recv().await? {
                Message::PlanReply(r) if r.request_id == request_id => return Ok(r),
                Message::Error(e) if e.request_id == Some(request_id) || e.request_id.is_none() => {
                    return Err(ClientError::Refused(e));
                }
                _ => continue,
            }
        }
    };
    tokio::time::timeout(WAIT, answer).await.map_err(|_| ClientError::Timeout(WAIT.as_millis()))?
}

/// Polls until the daemon's plan queue is empty or `wait` passes.
async fn wait_for_empty_queue(ctl: &mut ControllerClient, wait: Duration) -> bool {
    let deadline = tokio::time::Instant::now() + wait;
    while tokio::time::Instant::now() < deadline {
        if ctl.ping(WAIT).await.unwrap().queue_length == 0 {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    false
}

/// Polls until the daemon has received `frames` frames in all.
async fn wait_for_frames(ctl: &mut ControllerClient, frames: u64) {
    for _ in 0..500 {
        if ctl.ping(WAIT).await.unwrap().frames_received >= frames {
            return;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    panic!("the daemon did not receive {frames} frames");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_with_implausible_capture_times_never_answer_a_fresh_request() {
    let mut c = config();
    c.server.fresh_frame_timeout = Duration::from_millis(1500);
    let cell = Cell::start(c).await;
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    let mut ctl = cell.controller().await;
    let small = small_cloud();
    // Stamped 0 (no clock), a minute old, and an hour ahead: each answers
    // its trigger, and none may be planned as a fresh frame.
    for (k, stamp) in [0, now_us(-60_000), now_us(3_600_000)].into_iter().enumerate() {
        let id = 10 + k as u64;
        ctl.send(&Message::PlanRequest(request(id, FrameSelect::Trigger))).await.unwrap();
        let trigger_id = loop {
            match cam.recv().await {
                Some(Message::Trigger(t)) => break t.trigger_id,
                Some(_) => continue,
                None => panic!("the camera link closed"),
            }
        };
        cam.send(&frame_stamped(id, trigger_id, &small, stamp)).await;
        let (code, message) = refused(wait_reply(&mut ctl, id).await);
        assert_eq!(code, ErrorCode::StaleFrame, "capture time {stamp}: {message}");
        assert!(message.contains("capture"), "{message}");
    }
    // A NextFrame request skips such a frame and times out.
    ctl.send(&Message::PlanRequest(request(20, FrameSelect::NextFrame))).await.unwrap();
    ctl.ping(WAIT).await.unwrap();
    tokio::time::sleep(Duration::from_millis(200)).await;
    cam.send(&frame_stamped(20, 0, &small, 0)).await;
    let (code, message) = refused(wait_reply(&mut ctl, 20).await);
    assert_eq!(code, ErrorCode::FrameTimeout, "{message}");
    assert!(message.contains("capture"), "the timeout names the skipped frame: {message}");
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_frame_whose_upload_began_before_the_request_never_answers_it() {
    let mut c = config();
    c.server.fresh_frame_timeout = Duration::from_millis(1000);
    c.server.stall_timeout = Duration::from_secs(5);
    let cell = Cell::start(c).await;
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    let mut ctl = cell.controller().await;
    // The frame is stamped a little after the request, so only the
    // upload's start tells it apart from a fresh one.
    let bytes = frame::encode(&frame_stamped(1, 0, &small_cloud(), now_us(150))).unwrap();
    let (first, rest) = bytes.split_at(bytes.len() / 2);
    cam.write(first).await;
    tokio::time::sleep(Duration::from_millis(50)).await;
    ctl.send(&Message::PlanRequest(request(1, FrameSelect::NextFrame))).await.unwrap();
    ctl.ping(WAIT).await.unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    cam.write(rest).await;
    let (code, message) = refused(wait_reply(&mut ctl, 1).await);
    assert_eq!(code, ErrorCode::FrameTimeout, "the frame uploading when the request came was used: {message}");
    assert_eq!(ctl.ping(WAIT).await.unwrap().frames_received, 1);
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_closed_connection_releases_its_queue_slots_at_once() {
    let mut c = config();
    c.server.plan_queue_depth = 4;
    c.server.fresh_frame_timeout = Duration::from_secs(20);
    let cell = Cell::start(c).await;
    let _cam = Raw::hello(&cell.camera, Role::Camera).await;
    let mut quitter = cell.controller().await;
    for id in 1..=4 {
        let r = PlanRequest { timeout_ms: 20_000, ..request(id, FrameSelect::NextFrame) };
        quitter.send(&Message::PlanRequest(r)).await.unwrap();
    }
    quitter.ping(WAIT).await.unwrap();
    drop(quitter);
    let mut other = cell.controller().await;
    assert!(
        wait_for_empty_queue(&mut other, Duration::from_secs(5)).await,
        "the closed connection's waits held the queue"
    );
    let r = PlanRequest { timeout_ms: 200, ..request(9, FrameSelect::NextFrame) };
    let (code, message) = refused(other.plan(r, WAIT).await);
    assert_eq!(code, ErrorCode::FrameTimeout, "{message}");
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_connection_cannot_hold_every_slot_nor_wait_forever() {
    let mut c = config();
    c.server.plan_queue_depth = 4;
    let cell = Cell::start(c).await;
    let _cam = Raw::hello(&cell.camera, Role::Camera).await;
    let mut greedy = cell.controller().await;
    // An endless wait is refused, naming the limit.
    let endless = PlanRequest { timeout_ms: u32::MAX, ..request(1, FrameSelect::NextFrame) };
    greedy.send(&Message::PlanRequest(endless)).await.unwrap();
    let answer = tokio::time::timeout(Duration::from_secs(5), wait_reply(&mut greedy, 1)).await;
    let (code, message) = refused(answer.expect("an endless wait is refused at once"));
    assert_eq!(code, ErrorCode::BadRequest, "{message}");
    assert!(message.contains("max_request_timeout_ms"), "{message}");
    // Four long waits from one connection: it gets its share, not every slot.
    for id in 2..=5 {
        let r = PlanRequest { timeout_ms: 20_000, ..request(id, FrameSelect::NextFrame) };
        greedy.send(&Message::PlanRequest(r)).await.unwrap();
    }
    let (code, message) = refused(wait_reply(&mut greedy, 4).await);
    assert_eq!(code, ErrorCode::Busy, "{message}");
    let mut other = cell.controller().await;
    let r = PlanRequest { timeout_ms: 200, ..request(9, FrameSelect::NextFrame) };
    let (code, message) = refused(other.plan(r, WAIT).await);
    assert_eq!(code, ErrorCode::FrameTimeout, "another controller still gets a slot: {message}");
    drop(greedy);
    cell.shutdown().await;
}

/// A camera's HelloAck means the daemon knows the camera: a request sent
/// the moment the ack has arrived finds it. The camera link used to send
/// the ack first and register the camera after, so a request could slip
/// in between and be refused with no_camera (the test above failed so now
/// and then, its requests refused before the camera counted). Each camera
/// here has its own name, so no earlier camera can answer for it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_camera_is_known_to_the_daemon_once_its_hello_is_acknowledged() {
    const CAMERAS: usize = 40;
    let mut c = config();
    c.server.max_camera_connections = CAMERAS;
    let cell = Cell::start(c).await;
    let mut ctl = cell.controller().await;
    let mut cameras = Vec::with_capacity(CAMERAS);
    for k in 0..CAMERAS {
        let name = format!("camera-{k}");
        cameras.push(Raw::hello_as(&cell.camera, Role::Camera, &name).await);
        let r = PlanRequest { timeout_ms: 1, camera: Some(name), ..request(k as u64 + 1, FrameSelect::NextFrame) };
        let (code, message) = refused(ctl.plan(r, WAIT).await);
        assert_eq!(code, ErrorCode::FrameTimeout, "camera {k}, right after its ack: {message}");
    }
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_unnamed_trigger_reaches_every_camera_so_a_silent_one_cannot_block_it() {
    let cell = Cell::start(config()).await;
    let (stop_cam, cam) = cell.camera(vec![Arc::new(small_cloud())], CameraOptions::default());
    let mut ctl = cell.controller().await;
    wait_for_camera(&mut ctl).await;
    // A second camera, connected last, that never answers.
    let mut silent = Raw::hello(&cell.camera, Role::Camera).await;
    silent.ping().await;
    let (code, message) = refused(ctl.plan(request(1, FrameSelect::Trigger), WAIT).await);
    assert_eq!(code, ErrorCode::PlanFailed, "the answering camera's frame was planned: {message}");
    let _ = stop_cam.send(());
    cam.await.unwrap();
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_frame_id_request_waits_for_a_frame_still_uploading() {
    let mut c = config();
    c.server.stall_timeout = Duration::from_secs(5);
    let cell = Cell::start(c).await;
    let mut cam = Raw::hello(&cell.camera, Role::Camera).await;
    let mut ctl = cell.controller().await;
    let small = small_cloud();
    cam.send(&frame_stamped(1, 0, &small, now_us(0))).await;
    wait_for_frames(&mut ctl, 1).await;
    let bytes = frame::encode(&frame_stamped(2, 0, &small, now_us(0))).unwrap();
    let (first, rest) = bytes.split_at(bytes.len() / 2);
    cam.write(first).await;
    ctl.send(&Message::PlanRequest(request(5, FrameSelect::FrameId(2)))).await.unwrap();
    tokio::time::sleep(Duration::from_millis(200)).await;
    cam.write(rest).await;
    let (code, message) = refused(wait_reply(&mut ctl, 5).await);
    assert_eq!(code, ErrorCode::PlanFailed, "frame 2 was planned once it arrived: {message}");
    assert!(message.contains("frame 2"), "{message}");
    cell.shutdown().await;
}
