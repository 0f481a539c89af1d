//! Version and capability negotiation over loopback: a version 7 peer gets
//! version 7's bytes, a version 8 peer version 8's with the capabilities it
//! asked for that the daemon has, a newer peer the newest both speak, and
//! a peer that leaves its agreed version, or says Hello twice, is answered
//! as PROTOCOL.md says.

use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use weldseam::config::Config;
use weldseam_proto::frame::{self, HEADER_BYTES};
use weldseam_proto::message::{DaemonLimits, Hello, HelloAck, Role};
use weldseam_proto::session::capability;
use weldseam_proto::{ErrorCode, Message, PROTOCOL_VERSION, Session};

use crate::util::Cell;

const WAIT: Duration = Duration::from_secs(30);

/// One whole message as raw bytes, and the version of its header.
async fn read_raw(stream: &mut TcpStream) -> Option<Vec<u8>> {
    let mut bytes = vec![0u8; HEADER_BYTES];
    tokio::time::timeout(WAIT, stream.read_exact(&mut bytes)).await.expect("the daemon answers in time").ok()?;
    let length = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    bytes.resize(HEADER_BYTES + length, 0);
    tokio::time::timeout(WAIT, stream.read_exact(&mut bytes[HEADER_BYTES..])).await.unwrap().ok()?;
    Some(bytes)
}

fn version_of(bytes: &[u8]) -> u16 {
    u16::from_le_bytes([bytes[4], bytes[5]])
}

async fn closed(stream: &mut TcpStream) -> bool {
    let mut byte = [0u8; 1];
    matches!(tokio::time::timeout(WAIT, stream.read(&mut byte)).await, Ok(Ok(0)) | Ok(Err(_)))
}

/// Connects, sends `hello` as a peer of `session` writes it, and returns
/// the stream and the daemon's raw answer.
async fn say_hello(addr: &str, session: Session, hello: Hello) -> (TcpStream, Vec<u8>) {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    stream.write_all(&frame::encode_in(session, &Message::Hello(hello)).unwrap()).await.unwrap();
    let answer = read_raw(&mut stream).await.expect("an answer to the Hello");
    (stream, answer)
}

fn hello(version: u16, role: Role, capabilities: u64) -> Hello {
    Hello { protocol_version: version, role, name: "peer".into(), capabilities }
}

fn config() -> Config {
    let mut c = Config::default();
    c.server.pipeline_threads = 1;
    c.server.plan_queue_depth = 3;
    c.server.frame_history = 5;
    c
}

#[tokio::test]
async fn each_peer_gets_the_newest_version_both_speak_and_only_the_capabilities_it_asked_for() {
    let cell = Cell::start(config()).await;
    let server = format!("weldseam {}", env!("CARGO_PKG_VERSION"));

    // Version 7: version 7's HelloAck, byte for byte, and every later
    // message in a version 7 header.
    let (mut v7, answer) = say_hello(&cell.controller, Session::V7, hello(7, Role::Controller, 0)).await;
    let expected = HelloAck { protocol_version: 7, server: server.clone(), capabilities: 0, limits: None };
    assert_eq!(answer, frame::encode_in(Session::V7, &Message::HelloAck(expected)).unwrap());
    assert_eq!(answer.len(), HEADER_BYTES + 2 + 8 + server.len(), "no field of version 8");
    v7.write_all(&frame::encode_in(Session::V7, &Message::Ping).unwrap()).await.unwrap();
    let status = read_raw(&mut v7).await.unwrap();
    assert_eq!(version_of(&status), 7);
    assert!(matches!(frame::decode(&status, 1 << 20), Ok(Message::Status(_))));

    // Version 8 without capabilities: granted none, no limits.
    let (_v8, answer) = say_hello(&cell.camera, Session::NEWEST, hello(8, Role::Camera, 0)).await;
    assert_eq!(version_of(&answer), 8);
    let bare = HelloAck { protocol_version: 8, server: server.clone(), capabilities: 0, limits: None };
    assert_eq!(frame::decode(&answer, 1 << 20), Ok(Message::HelloAck(bare)));

    // Version 8 asking for the limits and a capability no daemon has:
    // granted the limits only, which are the configured ones.
    let (_asked, answer) =
        say_hello(&cell.controller, Session::NEWEST, hello(8, Role::Controller, capability::LIMITS | 1 << 63)).await;
    let Ok(Message::HelloAck(ack)) = frame::decode(&answer, 1 << 20) else { panic!("a HelloAck") };
    assert_eq!(ack.capabilities, capability::LIMITS);
    let s = &config().server;
    let limits = ack.limits.expect("the limits granted");
    assert_eq!(
        limits,
        DaemonLimits {
            max_frame_bytes: s.max_frame_bytes,
            max_message_bytes: weldseam_proto::MAX_CONTROL_MESSAGE_BYTES as u64,
            plan_queue_depth: 3,
            max_requests_per_connection: s.max_requests_per_connection as u32,
            fresh_frame_timeout_ms: s.fresh_frame_timeout.as_millis() as u64,
            max_request_timeout_ms: s.max_request_timeout.as_millis() as u64,
            capture_time_tolerance_ms: s.capture_time_tolerance.as_millis() as u64,
            frame_history: 5,
            frame_history_bytes: s.frame_history_bytes,
            stall_timeout_ms: s.stall_timeout.as_millis() as u64,
        }
    );

    // A version 9 peer whose Hello has a field this daemon does not know:
    // answered in version 8, which it may go on in (or close).
    let mut newer = frame::encode(&Message::Hello(hello(9, Role::Controller, capability::LIMITS))).unwrap();
    newer[4..6].copy_from_slice(&9u16.to_le_bytes());
    newer[HEADER_BYTES..HEADER_BYTES + 2].copy_from_slice(&9u16.to_le_bytes());
    newer.extend_from_slice(&[0xaa; 5]);
    let length = (newer.len() - HEADER_BYTES) as u64;
    newer[8..16].copy_from_slice(&length.to_le_bytes());
    let mut v9 = TcpStream::connect(&cell.controller).await.unwrap();
    v9.write_all(&newer).await.unwrap();
    let answer = read_raw(&mut v9).await.unwrap();
    assert_eq!(version_of(&answer), PROTOCOL_VERSION);
    let Ok(Message::HelloAck(ack)) = frame::decode(&answer, 1 << 20) else { panic!("a HelloAck") };
    assert_eq!((ack.protocol_version, ack.capabilities), (PROTOCOL_VERSION, capability::LIMITS));
    v9.write_all(&frame::encode(&Message::Ping).unwrap()).await.unwrap();
    let status = read_raw(&mut v9).await.unwrap();
    assert!(matches!(frame::decode(&status, 1 << 20), Ok(Message::Status(_))));
    cell.shutdown().await;
}

#[tokio::test]
async fn a_peer_is_held_to_its_version_and_refused_in_a_header_it_can_read() {
    let cell = Cell::start(config()).await;
    let error_code = |bytes: &[u8]| match frame::decode(bytes, 1 << 20) {
        Ok(Message::Error(e)) => e.code,
        other => panic!("an Error, not {other:?}"),
    };

    // A version 7 peer on the wrong link: refused in a version 7 header.
    let (mut wrong, answer) = say_hello(&cell.camera, Session::V7, hello(7, Role::Controller, 0)).await;
    assert_eq!((version_of(&answer), error_code(&answer)), (7, ErrorCode::UnexpectedMessage));
    assert!(closed(&mut wrong).await);

    // A Hello whose header and body disagree on the version: 2, closed.
    let mut torn = frame::encode_in(Session::V7, &Message::Hello(hello(7, Role::Camera, 0))).unwrap();
    torn[HEADER_BYTES] = 8;
    let mut stream = TcpStream::connect(&cell.camera).await.unwrap();
    stream.write_all(&torn).await.unwrap();
    let answer = read_raw(&mut stream).await.unwrap();
    assert_eq!((version_of(&answer), error_code(&answer)), (7, ErrorCode::UnsupportedVersion));
    assert!(closed(&mut stream).await);

    // No magic, so no version to answer in: the daemon's newest header,
    // even where the bytes in the version's place read 7.
    let mut foreign = frame::encode_in(Session::V7, &Message::Hello(hello(7, Role::Camera, 0))).unwrap();
    foreign[..4].copy_from_slice(b"GET ");
    let mut stream = TcpStream::connect(&cell.camera).await.unwrap();
    stream.write_all(&foreign).await.unwrap();
    let answer = read_raw(&mut stream).await.unwrap();
    assert_eq!((version_of(&answer), error_code(&answer)), (PROTOCOL_VERSION, ErrorCode::BadMagic));
    assert!(closed(&mut stream).await);

    // A second Hello is a message out of place: 6, and the connection goes on.
    let (mut twice, _) = say_hello(&cell.camera, Session::V7, hello(7, Role::Camera, 0)).await;
    twice.write_all(&frame::encode_in(Session::V7, &Message::Hello(hello(7, Role::Camera, 0))).unwrap()).await.unwrap();
    let answer = read_raw(&mut twice).await.unwrap();
    assert_eq!((version_of(&answer), error_code(&answer)), (7, ErrorCode::UnexpectedMessage));
    twice.write_all(&frame::encode_in(Session::V7, &Message::Ping).unwrap()).await.unwrap();
    assert!(matches!(frame::decode(&read_raw(&mut twice).await.unwrap(), 1 << 20), Ok(Message::Status(_))));

    // After agreeing on version 7, a message in a version 8 header: 2 in
    // the agreed version's header, and the connection closes.
    twice.write_all(&frame::encode(&Message::Ping).unwrap()).await.unwrap();
    let answer = read_raw(&mut twice).await.unwrap();
    assert_eq!((version_of(&answer), error_code(&answer)), (7, ErrorCode::UnsupportedVersion));
    assert!(closed(&mut twice).await);
    cell.shutdown().await;
}

#[tokio::test]
async fn the_hello_is_bounded_by_the_hello_timeout_not_the_stall_timeout() {
    let mut c = config();
    c.server.stall_timeout = Duration::from_millis(100);
    c.server.hello_timeout = Duration::from_millis(5_000);
    let cell = Cell::start(c).await;
    let mut stream = TcpStream::connect(&cell.camera).await.unwrap();
    // Silent for longer than the stall timeout, well within the Hello's.
    tokio::time::sleep(Duration::from_millis(600)).await;
    stream.write_all(&frame::encode(&Message::Hello(hello(8, Role::Camera, 0))).unwrap()).await.unwrap();
    let answer = read_raw(&mut stream).await.expect("the Hello is answered");
    assert!(matches!(frame::decode(&answer, 1 << 20), Ok(Message::HelloAck(_))));
    cell.shutdown().await;
}

#[tokio::test]
async fn a_controller_that_half_closes_is_taken_as_gone_and_its_requests_free_their_places() {
    let cell = Cell::start(config()).await;
    let (_camera, _) = say_hello(&cell.camera, Session::NEWEST, hello(8, Role::Camera, 0)).await;
    let (mut controller, _) = say_hello(&cell.controller, Session::NEWEST, hello(8, Role::Controller, 0)).await;
    let request = weldseam_proto::message::PlanRequest {
        request_id: 1,
        joint: weldseam_proto::message::joint_code::LAP,
        groove_depth_mm: None,
        pose: [800.0, 0.0, 500.0, 180.0, 0.0, 0.0],
        step_mm: None,
        work_angle_deg: None,
        travel_angle_deg: None,
        frame: weldseam_proto::message::FrameSelect::NextFrame,
        timeout_ms: 20_000,
        camera: None,
        hand_eye: None,
        start_near: None,
        roi: None,
        pose_in: None,
        one_seam: false,
    };
    controller.write_all(&frame::encode(&Message::PlanRequest(request)).unwrap()).await.unwrap();
    controller.shutdown().await.unwrap();
    // No reply, the daemon's side closed, long before the request's 20 s.
    let started = std::time::Instant::now();
    assert!(read_raw(&mut controller).await.is_none(), "no reply after a half-close");
    assert!(started.elapsed() < Duration::from_secs(10));
    // The request's place is free again.
    let (mut other, _) = say_hello(&cell.controller, Session::NEWEST, hello(8, Role::Controller, 0)).await;
    let mut queue = u32::MAX;
    for _ in 0..50 {
        other.write_all(&frame::encode(&Message::Ping).unwrap()).await.unwrap();
        if let Ok(Message::Status(s)) = frame::decode(&read_raw(&mut other).await.unwrap(), 1 << 20) {
            queue = s.queue_length;
        }
        if queue == 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(queue, 0, "the half-closed connection's request was cancelled");
    cell.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_refusal_names_its_rule_only_to_a_controller_granted_rule_ids() {
    use weldseam::mock::ClientError;
    use weldseam::mock::controller::ControllerClient;
    use weldseam_proto::message::FrameSelect;

    use crate::daemon::small_cloud;

    // A flat plate: valid points and no seam, so a rule of the planner refuses it.
    let cloud = small_cloud();
    let request = |request_id| crate::daemon::request(request_id, FrameSelect::FrameId(1));
    // The rule the library's planner refuses the same points and request by.
    let library_request = weldseam::convert::from_proto::plan_request(&request(0), config().euler).unwrap();
    let refusal = weldseam::pipeline::Planner::new(config()).plan(&cloud, &library_request).unwrap_err();
    let rule = refusal.rule.id;
    assert!(weldseam::rules::by_id(rule).is_some(), "{rule}: not in the catalogue");

    let cell = Cell::start(config()).await;
    let (mut camera, _) = say_hello(&cell.camera, Session::NEWEST, hello(8, Role::Camera, 0)).await;
    let frame = Message::Frame(weldseam::convert::to_proto::frame(&cloud, 1, 0, 0));
    camera.write_all(&frame::encode(&frame).unwrap()).await.unwrap();
    let Ok(Message::FrameAck(ack)) = frame::decode(&read_raw(&mut camera).await.unwrap(), 1 << 30) else {
        panic!("a FrameAck")
    };
    assert_eq!(ack.code, 0, "{}", ack.message);

    // Granted: the Error ends with the rule.
    let mut granted = ControllerClient::connect_asking(&cell.controller, "ids", capability::RULE_IDS).await.unwrap();
    assert_eq!(granted.capabilities, capability::RULE_IDS);
    let Err(ClientError::Refused(named)) = granted.plan(request(1), WAIT).await else { panic!("a refusal") };
    assert_eq!((named.code, named.request_id), (ErrorCode::PlanFailed, Some(1)), "{}", named.message);
    assert_eq!(named.rule.as_deref(), Some(rule), "{}", named.message);

    // Not asked for (version 8 without it, and version 7): today's bytes,
    // the same message, no rule.
    for session in [Session::NEWEST, Session::V7] {
        let (mut plain, _) = say_hello(&cell.controller, session, hello(session.version, Role::Controller, 0)).await;
        plain.write_all(&frame::encode_in(session, &Message::PlanRequest(request(2))).unwrap()).await.unwrap();
        let bytes = read_raw(&mut plain).await.unwrap();
        let expected = Message::error(ErrorCode::PlanFailed, Some(2), named.message.clone());
        assert_eq!(bytes, frame::encode_in(session, &expected).unwrap(), "version {}", session.version);
    }
    cell.shutdown().await;
}
