//! The daemon's connection handling under hostile and careless peers, over
//! real loopback TCP: peers that send a byte at a time, floods of
//! connections that never say hello, and the metrics endpoint that counts
//! them. Every peer here is bounded in count and time and stops by itself.

use std::time::{Duration, Instant};

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use weldseam::config::Config;
use weldseam::mock::controller::ControllerClient;
use weldseam::server::Stopped;
use weldseam::server::local::LocalDaemon;

use crate::util::Cell;
use weldseam_proto::frame::{self, HEADER_BYTES, Header};
use weldseam_proto::message::{Frame, FrameMeta, Hello, Role};
use weldseam_proto::{Message, PROTOCOL_VERSION};

/// How long any single step may take before the test calls it a hang.
const WAIT: Duration = Duration::from_secs(30);

fn config() -> Config {
    let mut c = Config::default();
    c.server.pipeline_threads = 1;
    c.server.shutdown_grace = Duration::from_secs(10);
    c
}

fn hello(role: Role) -> Vec<u8> {
    frame::encode(&Message::Hello(Hello {
        protocol_version: PROTOCOL_VERSION,
        role,
        name: "peer".into(),
        capabilities: 0,
    }))
    .unwrap()
}

/// Reads one message, or None when the daemon closed the connection.
async fn recv(stream: &mut TcpStream) -> Option<Message> {
    let mut head = [0u8; HEADER_BYTES];
    stream.read_exact(&mut head).await.ok()?;
    let header = Header::parse(&head, u64::MAX).ok()?;
    let mut body = vec![0u8; header.length as usize];
    stream.read_exact(&mut body).await.ok()?;
    frame::decode_body(header.tag, &body).ok()
}

/// Connects and completes the hello; None when the daemon refused or
/// closed instead of acknowledging.
async fn handshake(addr: &str, role: Role) -> Option<TcpStream> {
    let mut stream = TcpStream::connect(addr).await.ok()?;
    stream.write_all(&hello(role)).await.ok()?;
    match recv(&mut stream).await? {
        Message::HelloAck(_) => Some(stream),
        _ => None,
    }
}

/// Sends `bytes` one at a time, `gap` apart, until they run out or the
/// daemon closes the connection. Returns how long after its first byte
/// the daemon closed it, or None if it never did.
async fn trickle(mut stream: TcpStream, bytes: Vec<u8>, gap: Duration) -> Option<Duration> {
    let started = Instant::now();
    let (mut read, mut write) = stream.split();
    let send = async {
        for b in bytes {
            if write.write_all(&[b]).await.is_err() {
                break;
            }
            tokio::time::sleep(gap).await;
        }
    };
    let mut sink = [0u8; 64];
    let closed = async {
        // The daemon sends nothing to this peer but may close it.
        while let Ok(n) = read.read(&mut sink).await {
            if n == 0 {
                break;
            }
        }
    };
    tokio::select! {
        _ = send => None,
        _ = closed => Some(started.elapsed()),
    }
}

/// A 32 x 32 frame of valid points, encoded.
fn small_frame() -> Vec<u8> {
    let meta =
        FrameMeta { frame_id: 1, trigger_id: 0, capture_time_us: 0, width: 32, height: 32, units: 0, cloud_frame: 0 };
    let points = (0..32 * 32).map(|i| [(i % 32) as f32, (i / 32) as f32, 700.0]).collect();
    frame::encode(&Message::Frame(Frame { meta, points })).unwrap()
}

/// Item 10: a peer that keeps a message going one byte at a time is
/// dropped within the whole-message bound even though it is never silent
/// for the stall timeout, and two such peers on the camera link do not
/// keep a real camera out.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slow_senders_are_dropped_and_cannot_keep_the_camera_out() {
    let mut c = config();
    c.server.max_camera_connections = 2;
    // Each byte comes well within the stall timeout ...
    c.server.stall_timeout = Duration::from_millis(1_000);
    // ... but no message may take more than 1.5 s plus its length at
    // 64 KiB/s (about 0.2 s for the frame below).
    c.server.message_timeout = Duration::from_millis(1_500);
    c.server.min_transfer_bytes_per_s = 64 << 10;
    let gap = Duration::from_millis(250);
    let cell = Cell::start(c).await;

    // One peer dribbles headers of pings, the other the points of a frame
    // whose header it sent at once. Each would take over 15 s to finish.
    let pinger = handshake(&cell.camera, Role::Camera).await.expect("the first peer says hello");
    let pings: Vec<u8> = (0..4).flat_map(|_| frame::encode(&Message::Ping).unwrap()).collect();
    let mut framer = handshake(&cell.camera, Role::Camera).await.expect("the second peer says hello");
    let frame_bytes = small_frame();
    framer.write_all(&frame_bytes[..HEADER_BYTES + 36]).await.unwrap();
    let points = frame_bytes[HEADER_BYTES + 36..HEADER_BYTES + 36 + 64].to_vec();
    let slow_pings = tokio::spawn(trickle(pinger, pings, gap));
    let slow_frame = tokio::spawn(trickle(framer, points, gap));

    // A real camera keeps trying to connect, as cameras do.
    let started = Instant::now();
    let mut camera = None;
    while camera.is_none() && started.elapsed() < Duration::from_secs(12) {
        let left = Duration::from_secs(12).saturating_sub(started.elapsed());
        camera = tokio::time::timeout(left, handshake(&cell.camera, Role::Camera)).await.ok().flatten();
        if camera.is_none() {
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }
    let mut camera = camera.expect("the real camera got its hello acknowledged within 12 s");
    camera.write_all(&small_frame()).await.unwrap();
    camera.write_all(&frame::encode(&Message::Ping).unwrap()).await.unwrap();
    match tokio::time::timeout(WAIT, recv(&mut camera)).await.unwrap() {
        Some(Message::FrameAck(ack)) => assert_eq!((ack.frame_id, ack.code), (1, 0), "the frame is held"),
        other => panic!("expected the frame's acknowledgement, got {other:?}"),
    }
    match tokio::time::timeout(WAIT, recv(&mut camera)).await.unwrap() {
        Some(Message::Status(s)) => assert_eq!(s.frames_received, 1),
        other => panic!("expected a status, got {other:?}"),
    }

    // Both slow peers were dropped, well before they could finish.
    for (name, peer) in [("the ping dribbler", slow_pings), ("the frame dribbler", slow_frame)] {
        let closed = tokio::time::timeout(WAIT, peer).await.unwrap().unwrap();
        let closed = closed.unwrap_or_else(|| panic!("{name} was never dropped"));
        assert!(closed < Duration::from_secs(10), "{name} was dropped only after {closed:?}");
    }
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

/// Item 11: 200 connections opened at once from one address that never
/// say hello do not keep a controller out for more than a moment.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flood_of_silent_connections_does_not_keep_a_controller_out() {
    let cell = Cell::start(config()).await;
    let mut flood = Vec::new();
    for _ in 0..200 {
        flood.push(TcpStream::connect(&cell.controller).await.unwrap());
    }
    let started = Instant::now();
    let mut ctl = tokio::time::timeout(Duration::from_secs(5), ControllerClient::connect(&cell.controller, "cell-1"))
        .await
        .expect("the controller's hello was answered within 5 s of the flood")
        .expect("the controller was accepted");
    ctl.ping(WAIT).await.expect("the controller is served");
    eprintln!("controller served {:?} after a flood of 200 silent connections", started.elapsed());
    drop(flood);
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

/// Fetches `path` from the metrics endpoint with a bare HTTP/1.1 request.
async fn http_get(addr: &str, path: &str) -> String {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    let request = format!("GET {path} HTTP/1.1\r\nHost: weldseam\r\nConnection: close\r\n\r\n");
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut response = String::new();
    tokio::time::timeout(WAIT, stream.read_to_string(&mut response)).await.unwrap().unwrap();
    response
}

/// The metrics endpoint serves, in the Prometheus text format, what the
/// links did: plan outcomes and their latency, frames and bytes in,
/// connections per link and refused peers.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_metrics_endpoint_counts_plans_frames_connections_and_refusals() {
    let mut c = config();
    c.server.hello_timeout = Duration::from_millis(200);
    c.server.fresh_frame_timeout = Duration::from_millis(200);
    let daemon = LocalDaemon::start_with_metrics(c).await.unwrap();
    let (camera_addr, controller_addr, metrics_addr) = (
        daemon.camera_addr.to_string(),
        daemon.controller_addr.to_string(),
        daemon.metrics_addr.expect("started with metrics").to_string(),
    );

    // A camera sends one frame; a controller asks for a frame by an id
    // that does not exist; a silent connection runs out of time.
    let mut cam = handshake(&camera_addr, Role::Camera).await.unwrap();
    cam.write_all(&small_frame()).await.unwrap();
    let mut ctl = ControllerClient::connect(&controller_addr, "cell-1").await.unwrap();
    let mut status = ctl.ping(WAIT).await.unwrap();
    for _ in 0..200 {
        if status.frames_received == 1 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
        status = ctl.ping(WAIT).await.unwrap();
    }
    let mut request = weldseam::mock::controller::request_for_simulation(
        1,
        weldseam::joint::JointType::Lap,
        crate::scenes::demo(weldseam::joint::JointType::Lap),
        weldseam_proto::message::FrameSelect::FrameId(99),
    );
    assert!(ctl.plan(request.clone(), WAIT).await.is_err(), "frame 99 does not exist");
    request.request_id = 2;
    request.frame = weldseam_proto::message::FrameSelect::FrameId(1);
    assert!(ctl.plan(request, WAIT).await.is_err(), "the small frame has no seam");
    let mut silent = TcpStream::connect(&controller_addr).await.unwrap();
    let mut sink = [0u8; 1];
    let closed = tokio::time::timeout(WAIT, silent.read(&mut sink)).await.unwrap();
    assert!(matches!(closed, Ok(0) | Err(_)), "the silent connection was closed");

    let response = http_get(&metrics_addr, "/metrics").await;
    assert!(response.starts_with("HTTP/1.1 200"), "{response}");
    for line in [
        "weldseam_plans_total{outcome=\"unknown_frame\"} 1",
        "weldseam_plans_total{outcome=\"plan_failed\"} 1",
        // Both were answered after a frame lookup, so both have a latency.
        "weldseam_reply_seconds_count 2",
        "weldseam_frames_total 1",
        "weldseam_connections{link=\"camera\"} 1",
        "weldseam_connections{link=\"controller\"} 1",
        "weldseam_refused_peers_total{link=\"controller\",reason=\"hello_timeout\"} 1",
        "weldseam_queue_depth 0",
    ] {
        assert!(response.lines().any(|l| l == line), "no line {line:?} in\n{response}");
    }
    let received = response
        .lines()
        .find_map(|l| l.strip_prefix("weldseam_received_bytes_total{link=\"camera\"} "))
        .and_then(|v| v.parse::<u64>().ok())
        .expect("bytes received on the camera link");
    assert!(received > small_frame().len() as u64, "{received} bytes counted on the camera link");
    assert!(http_get(&metrics_addr, "/other").await.starts_with("HTTP/1.1 404"));

    drop((cam, ctl));
    tokio::time::timeout(WAIT, daemon.stop()).await.unwrap().unwrap();
}

/// Sends `request` (its first lines, without the blank line) and reads
/// the whole answer.
async fn http(addr: &str, request: &str) -> String {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    let request = format!("{request}\r\nHost: weldseam\r\nConnection: close\r\n\r\n");
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut response = String::new();
    tokio::time::timeout(WAIT, stream.read_to_string(&mut response)).await.unwrap().unwrap();
    response
}

/// The operator page's listener with a token: the page's own files for
/// anyone, the cell's data and the metrics only with the token (header or
/// query), GET only, and nothing else.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_serves_its_data_only_with_the_token_and_only_to_get() {
    let mut c = config();
    c.server.http_token = Some("0123456789abcdef".into());
    let daemon = LocalDaemon::start_with_metrics(c).await.unwrap();
    let addr = daemon.metrics_addr.expect("started with metrics").to_string();
    let page = http(&addr, "GET / HTTP/1.1").await;
    assert!(page.starts_with("HTTP/1.1 200") && page.contains("<script src=\"page.js\">"), "{page}");
    assert!(page.to_ascii_lowercase().contains("content-security-policy: default-src 'self'"), "{page}");
    for refused in
        ["GET /api/state HTTP/1.1", "GET /metrics HTTP/1.1", "GET /api/state?token=0123456789abcdeX HTTP/1.1"]
    {
        assert!(http(&addr, refused).await.starts_with("HTTP/1.1 401"), "{refused}");
    }
    let state = http(&addr, "GET /api/state?token=0123456789abcdef HTTP/1.1").await;
    assert!(state.starts_with("HTTP/1.1 200"), "{state}");
    let body: serde_json::Value = serde_json::from_str(state.split("\r\n\r\n").nth(1).unwrap()).unwrap();
    assert_eq!(body["plans"], serde_json::json!([]), "{body}");
    assert_eq!(body["queue"]["depth"], 4, "{body}");
    let metrics = http(&addr, "GET /metrics HTTP/1.1\r\nAuthorization: Bearer 0123456789abcdef").await;
    assert!(metrics.starts_with("HTTP/1.1 200") && metrics.contains("weldseam_records_held"), "{metrics}");
    let posted = http(&addr, "POST /api/state?token=0123456789abcdef HTTP/1.1\r\nContent-Length: 0").await;
    assert!(posted.starts_with("HTTP/1.1 405"), "{posted}");
    let gone = http(&addr, "GET /api/plans/7/camera.png?token=0123456789abcdef HTTP/1.1").await;
    assert!(gone.starts_with("HTTP/1.1 404"), "{gone}");
    tokio::time::timeout(WAIT, daemon.stop()).await.unwrap().unwrap();
}
