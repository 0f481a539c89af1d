//! The daemon's serve order and its bounds on what one frame can cost:
//! plans served by when their frame became ready and, on one frame, by
//! the requests' arrival; a frame with no point the camera can measure
//! refused at the camera link and never handed to a waiting request; a
//! frame of one repeated point refused early; and every plan bounded by
//! `server.plan_timeout_ms`, the next plan going on at once. Driven over
//! loopback by a raw camera (so two frames can arrive in one write) and
//! the mock controller.

use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use weldseam::cloud::PointCloud;
use weldseam::config::Config;
use weldseam::joint::JointType;
use weldseam::mock::controller::ControllerClient;
use weldseam::sim::demo_scene;
use weldseam_proto::frame::{self, HEADER_BYTES, Header};
use weldseam_proto::message::{ErrorReply, FrameAck, FrameSelect, Hello, Role};
use weldseam_proto::{ErrorCode, Message};

use crate::daemon::request;
use crate::scenes;
use crate::util::Cell;

/// A hang guard: every answer here comes in well under it.
const WAIT: Duration = Duration::from_secs(60);

fn config() -> Config {
    let mut c = Config::default();
    c.server.fresh_frame_timeout = Duration::from_secs(20);
    c.server.pipeline_threads = 2;
    c.server.plan_queue_depth = 8;
    c.server.max_requests_per_connection = 8;
    c.server.shutdown_grace = Duration::from_secs(60);
    c
}

/// A raw camera connection, so frames can be written back to back.
struct RawCamera(TcpStream);

impl RawCamera {
    async fn connect(addr: &str) -> RawCamera {
        let mut cam = RawCamera(TcpStream::connect(addr).await.unwrap());
        let hello = Hello::new(Role::Camera, "raw", 0);
        cam.write(&[Message::Hello(hello)]).await;
        assert!(matches!(cam.recv().await, Message::HelloAck(_)));
        cam
    }

    /// Writes `messages` in one write.
    async fn write(&mut self, messages: &[Message]) {
        let bytes: Vec<u8> = messages.iter().flat_map(|m| frame::encode(m).unwrap()).collect();
        self.0.write_all(&bytes).await.unwrap();
    }

    async fn recv(&mut self) -> Message {
        let read = async {
            let mut head = [0u8; HEADER_BYTES];
            self.0.read_exact(&mut head).await.unwrap();
            let header = Header::parse(&head, u64::MAX).unwrap();
            let mut body = vec![0u8; header.length as usize];
            self.0.read_exact(&mut body).await.unwrap();
            frame::decode_body(header.tag, &body).unwrap()
        };
        tokio::time::timeout(WAIT, read).await.expect("the daemon answers the camera")
    }

    async fn trigger(&mut self) -> u64 {
        loop {
            match self.recv().await {
                Message::Trigger(t) => return t.trigger_id,
                Message::FrameAck(_) => continue,
                other => panic!("expected a trigger, got {other:?}"),
            }
        }
    }

    async fn ack(&mut self) -> FrameAck {
        loop {
            match self.recv().await {
                Message::FrameAck(ack) => return ack,
                Message::Trigger(_) => continue,
                other => panic!("expected a frame acknowledgement, got {other:?}"),
            }
        }
    }
}

fn now_us() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_micros() as u64
}

fn frame_message(frame_id: u64, trigger_id: u64, cloud: &PointCloud) -> Message {
    Message::Frame(weldseam::convert::to_proto::frame(cloud, frame_id, trigger_id, now_us()))
}

/// An organized frame of a flat plate 700 mm away: valid points, no seam,
/// so each plan of it ends with 46 after the pipeline has run.
fn plate(width: usize, height: usize) -> PointCloud {
    let points = (0..width * height).map(|i| [(i % width) as f32 * 0.4, (i / width) as f32 * 0.4, 700.0]).collect();
    PointCloud::organized(width, height, points).unwrap()
}

/// The next answer on the controller link: the request it answers, and
/// its error code and message when it is an error.
async fn answer(ctl: &mut ControllerClient) -> (u64, Option<(ErrorCode, String)>) {
    let (id, error) = answer_in_full(ctl).await;
    (id, error.map(|e| (e.code, e.message)))
}

/// [`answer`] with the whole error: on a connection granted `rule_ids`,
/// the rule that refused besides the code and the message.
async fn answer_in_full(ctl: &mut ControllerClient) -> (u64, Option<ErrorReply>) {
    loop {
        match tokio::time::timeout(WAIT, ctl.recv()).await.expect("a reply comes").unwrap() {
            Message::PlanReply(r) => return (r.request_id, None),
            Message::Error(e) => {
                let id = e.request_id.unwrap_or_else(|| panic!("an error for no request: {}", e.message));
                return (id, Some(e));
            }
            Message::Status(_) => continue,
            other => panic!("unexpected {other:?}"),
        }
    }
}

/// The sequence, round after round: two NextFrame requests, then
/// Trigger T1, then Trigger T2; the camera answers T1 with F1 and T2 with
/// F2, both in one write. F1 is ready first and goes to the first three
/// requests, in the order they arrived; F2 only to the fourth. So the
/// plans must be answered in the order the requests were sent. One
/// connection's replies are written as their plans end, and plans run one
/// at a time, each long enough that its reply leaves before the next one
/// ends: the reply order is the serve order.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn plans_are_served_by_frame_then_by_arrival() {
    let cell = Cell::start(config()).await;
    let mut cam = RawCamera::connect(&cell.camera).await;
    let mut ctl = ControllerClient::connect(&cell.controller, "order").await.unwrap();
    ctl.wait_for_camera(WAIT).await.unwrap();
    // Large enough that a plan takes tens of milliseconds: the reply of
    // one plan must leave before the next plan ends even while the other
    // tests of this binary share the cores, or the reply order stops
    // showing the serve order.
    let cloud = plate(480, 360);
    let rounds = 20;
    let mut out_of_order = Vec::new();
    for round in 0..rounds {
        let base = round * 10;
        let selects = [FrameSelect::NextFrame, FrameSelect::NextFrame, FrameSelect::Trigger, FrameSelect::Trigger];
        for (k, select) in selects.into_iter().enumerate() {
            ctl.send(&Message::PlanRequest(request(base + k as u64, select))).await.unwrap();
        }
        // The Status comes after the link has accepted all four.
        ctl.ping(WAIT).await.unwrap();
        let (t1, t2) = (cam.trigger().await, cam.trigger().await);
        let (f1, f2) = (2 * round + 1, 2 * round + 2);
        cam.write(&[frame_message(f1, t1, &cloud), frame_message(f2, t2, &cloud)]).await;
        assert_eq!(cam.ack().await.requests, 3, "F1 goes to both NextFrame requests and T1's");
        assert_eq!(cam.ack().await.requests, 1, "F2 goes to T2's request");
        let mut order = Vec::new();
        for _ in 0..4 {
            let (id, error) = answer(&mut ctl).await;
            if let Some((code, message)) = &error {
                assert_eq!(*code, ErrorCode::PlanFailed, "{message}");
            }
            order.push(id - base);
        }
        if order != [0, 1, 2, 3] {
            out_of_order.push(order);
        }
    }
    assert!(
        out_of_order.is_empty(),
        "{} of {rounds} rounds were served out of order: {out_of_order:?}",
        out_of_order.len()
    );
    cell.shutdown().await;
}

/// Frames without a point the camera can measure: every point beyond
/// `camera.max_depth_mm`, or every point infinite. Each is refused with 21
/// at the camera link, and a NextFrame request waiting meanwhile is
/// answered by the next usable frame, not failed by the unusable one.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_frame_without_a_measurable_point_is_refused_and_never_handed_on() {
    let cell = Cell::start(config()).await;
    let mut cam = RawCamera::connect(&cell.camera).await;
    let mut ctl = ControllerClient::connect(&cell.controller, "empty").await.unwrap();
    ctl.wait_for_camera(WAIT).await.unwrap();
    let far_z = (Config::default().camera.max_depth_mm * 4.0) as f32;
    let (w, h) = (64, 48);
    let far = PointCloud::organized(w, h, (0..w * h).map(|i| [(i % w) as f32, (i / w) as f32, far_z]).collect());
    let infinite = PointCloud::organized(w, h, vec![[f32::INFINITY, 0.0, f32::INFINITY]; w * h]);
    let far_unorganized = PointCloud::unorganized(vec![[1.0, 2.0, far_z]; 500]);
    for (id, cloud) in [(1, far.unwrap()), (2, infinite.unwrap()), (3, far_unorganized)] {
        ctl.send(&Message::PlanRequest(request(id, FrameSelect::NextFrame))).await.unwrap();
        ctl.ping(WAIT).await.unwrap();
        cam.write(&[frame_message(id, 0, &cloud)]).await;
        let ack = cam.ack().await;
        assert_eq!((ack.frame_id, ack.code, ack.requests), (id, ErrorCode::EmptyFrame.code(), 0), "{}", ack.message);
        assert!(ack.message.contains("max_depth_mm") || ack.message.contains("no valid point"), "{}", ack.message);
        let usable = 100 + id;
        cam.write(&[frame_message(usable, 0, &plate(64, 48))]).await;
        assert_eq!(cam.ack().await.requests, 1);
        let (answered, error) = answer(&mut ctl).await;
        assert_eq!(answered, id);
        let (code, message) = error.expect("a plate without a seam");
        assert_eq!(code, ErrorCode::PlanFailed, "{message}");
        assert!(message.starts_with(&format!("frame {usable}:")), "planned from the wrong frame: {message}");
    }
    let status = ctl.ping(WAIT).await.unwrap();
    assert_eq!(status.frames_received, 3, "only the usable frames are held");
    cell.shutdown().await;
}

/// A frame of one point repeated 2.3 million times, as a stuck or broken
/// camera sends: refused at once in the input stage, with its
/// figure and limit, and a plan queued behind it goes on. The wait is a
/// hang guard, not a speed figure (that is in `weldseam bench`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_frame_of_one_repeated_point_is_refused_and_the_next_plan_goes_on() {
    let cell = Cell::start(config()).await;
    let mut cam = RawCamera::connect(&cell.camera).await;
    // Granted rule_ids, the refusal names the rule that read the frame.
    let ids = weldseam_proto::session::capability::RULE_IDS;
    let mut ctl = ControllerClient::connect_asking(&cell.controller, "degenerate", ids).await.unwrap();
    ctl.wait_for_camera(WAIT).await.unwrap();
    // Unorganized, as a camera bridge that drops the grid sends it: the
    // density of a cloud without a grid is measured from its points.
    let stuck = PointCloud::unorganized(vec![[10.0, -20.0, 700.0]; 2_300_000]);
    ctl.send(&Message::PlanRequest(request(1, FrameSelect::NextFrame))).await.unwrap();
    ctl.ping(WAIT).await.unwrap();
    cam.write(&[frame_message(1, 0, &stuck)]).await;
    assert_eq!(cam.ack().await.requests, 1);
    ctl.send(&Message::PlanRequest(request(2, FrameSelect::NextFrame))).await.unwrap();
    ctl.ping(WAIT).await.unwrap();
    cam.write(&[frame_message(2, 0, &plate(64, 48))]).await;
    assert_eq!(cam.ack().await.requests, 1);
    // Request 1's turn passes to request 2 as soon as its plan stops, and
    // the two answers are sent by two tasks, so under load the small
    // plate's answer may reach the link first; the answers are read by
    // request id (the serve order has its own test).
    let guard = Duration::from_secs(20);
    let both = async { [answer_in_full(&mut ctl).await, answer_in_full(&mut ctl).await] };
    let mut answers = tokio::time::timeout(guard, both).await.expect("the stuck frame stalled the queue");
    answers.sort_by_key(|(id, _)| *id);
    let [(first, stuck), (second, next)] = answers;
    assert_eq!((first, second), (1, 2));
    let refusal = stuck.expect("the stuck frame is refused");
    assert_eq!(refusal.code, ErrorCode::PlanFailed, "{}", refusal.message);
    assert_eq!(refusal.rule.as_deref(), Some("frame.one_point_repeated"), "{}", refusal.message);
    assert!(refusal.message.contains("distinct"), "the figure the rule reads: {}", refusal.message);
    assert_eq!(next.map(|e| e.code), Some(ErrorCode::PlanFailed), "the plate is planned and has no seam");
    cell.shutdown().await;
}

/// A plan over `server.plan_timeout_ms` is stopped and refused with 50
/// (`plan_timeout`), naming the limit; the plan queued behind it starts at
/// once and is answered as usual.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_over_its_time_limit_is_refused_and_the_next_one_goes_on() {
    let mut c = config();
    // Far below what planning a full frame takes, far above a tiny plate.
    c.server.plan_timeout = Duration::from_millis(30);
    let sim = scenes::rendered(&demo_scene(JointType::VButt), &c.camera);
    let cell = Cell::start(c).await;
    let mut cam = RawCamera::connect(&cell.camera).await;
    let mut ctl = ControllerClient::connect(&cell.controller, "timeout").await.unwrap();
    ctl.wait_for_camera(WAIT).await.unwrap();
    for (id, select) in [(1, FrameSelect::NextFrame), (2, FrameSelect::FrameId(2))] {
        ctl.send(&Message::PlanRequest(request(id, select))).await.unwrap();
    }
    ctl.ping(WAIT).await.unwrap();
    cam.write(&[frame_message(1, 0, &sim.cloud), frame_message(2, 0, &plate(16, 12))]).await;
    // Request 1 is planned first, but its refusal and request 2's answer
    // are sent by two tasks once request 1 has stopped, so they may reach
    // the link in either order (the order plans are served in is
    // plans_are_served_by_frame_then_by_arrival's to show).
    let mut answers = [answer(&mut ctl).await, answer(&mut ctl).await];
    answers.sort_by_key(|(id, _)| *id);
    let [(first, over_time), (second, tiny)] = answers;
    assert_eq!((first, second), (1, 2));
    let (code, message) = over_time.expect("the full frame's plan is over the limit");
    assert_eq!(code, ErrorCode::PlanTimeout, "{message}");
    assert!(message.contains("server.plan_timeout_ms") && message.contains("30 ms"), "{message}");
    assert_eq!(tiny.map(|e| e.0), Some(ErrorCode::PlanFailed), "the tiny plate is planned and has no seam");
    cell.shutdown().await;
}
