//! The camera link's handler: the hello, then frames in and triggers out.
//! Each frame is checked (size, at least one valid point the camera can
//! measure, a capture time the daemon's clock can believe), stored in the
//! history, handed to the requests waiting for it, and acknowledged to the
//! camera with a FrameAck: held, or refused with its error code. A frame
//! refused here is never handed to a request, which goes on waiting for a
//! usable one.

use std::sync::Arc;
use std::time::Instant;

use tokio::sync::Mutex;
use tracing::{Instrument, info, warn};
use weldseam_proto::frame;
use weldseam_proto::message::{FrameAck, Hello, HelloAck, Role, Trigger};
use weldseam_proto::session::capability;
use weldseam_proto::{ErrorCode, Message};

use super::ServerState;
use super::board::FrameSummary;
use super::connection::{Connection, HandshakeError, MessageWriter, ReadError, Received};
use super::frames::{CameraRegistration, StoredFrame, wall_clock_us};
use super::shutdown::Shutdown;
use crate::camera::{CameraModel, Unmeasurable};
use crate::cloud::PointCloud;
use crate::convert::from_proto::{self, FrameInput};
use crate::convert::to_proto;
use crate::pipeline::input::guess_units;
use crate::pipeline::{CloudFrame, Units};

type Writer = Arc<Mutex<MessageWriter<tokio::net::tcp::OwnedWriteHalf>>>;

/// The daemon's name in hello acks.
pub(crate) fn server_name() -> String {
    format!("weldseam {}", env!("CARGO_PKG_VERSION"))
}

/// Answers a handshake: an ack, or the typed refusal. `join` runs on the
/// accepted Hello *before* the ack is sent (a camera is registered there),
/// so a peer that has read its HelloAck is already known to the daemon: a
/// request sent the moment a camera's ack arrived finds that camera.
/// Returns the peer's Hello and what `join` made, or None when the
/// connection should close (dropping what `join` made). Before the Hello
/// every error closes the connection: a peer that cannot say Hello is not
/// speaking this protocol, and must not keep a connection slot. Each
/// refusal goes in a header of the version the peer's message came in
/// (one this daemon knows the Error layout of), so its own decoder reads
/// why; the ack and everything after it, in the version agreed.
pub(crate) async fn handshake<T>(
    conn: &mut Connection,
    role: Role,
    state: &ServerState,
    join: impl FnOnce(&Hello) -> T,
) -> Option<(Hello, T)> {
    let refuse = |conn: &Connection, refusal: &Message| {
        let version = conn.reader.last_version().unwrap_or(weldseam_proto::PROTOCOL_VERSION);
        frame::encode_version_refusal(version, refusal)
    };
    match conn.expect_hello(role, state.config.server.hello_timeout).await {
        Ok((hello, session)) => {
            info!(name = %hello.name, version = session.version, capabilities = session.capabilities, "{} connected", role.name());
            let joined = join(&hello);
            let limits = session.has(capability::LIMITS).then(|| to_proto::limits(&state.config.server));
            let ack = Message::HelloAck(HelloAck {
                protocol_version: session.version,
                server: server_name(),
                capabilities: session.capabilities,
                limits,
            });
            conn.writer.set_session(session);
            conn.reader.set_session(session);
            conn.writer.send(&ack).await.is_ok().then_some((hello, joined))
        }
        Err(HandshakeError::Closed) => {
            info!("closed before its hello");
            None
        }
        Err(HandshakeError::Read(e)) => {
            warn!("bad hello: {e}");
            if let Some(code) = e.reply_code() {
                let refusal = Message::error(code, None, e.to_string());
                if let Ok(bytes) = refuse(conn, &refusal) {
                    let _ = conn.writer.send_encoded(&bytes).await;
                }
            }
            None
        }
        Err(e @ HandshakeError::Refused { code, .. }) => {
            warn!("refused: {e}");
            if let Ok(bytes) = refuse(conn, &Message::error(code, None, e.to_string())) {
                let _ = conn.writer.send_encoded(&bytes).await;
            }
            None
        }
        Err(e @ HandshakeError::Timeout(_)) => {
            warn!("dropped: {e}");
            None
        }
    }
}

/// Serves one camera connection until it closes or the server stops.
pub async fn serve(mut conn: Connection, state: Arc<ServerState>, mut shutdown: Shutdown) {
    let peer = conn.peer;
    let joined = handshake(&mut conn, Role::Camera, &state, |hello| {
        (state.frames.attach_camera(&hello.name), state.board.peer_joined(Role::Camera.name(), peer, &hello.name))
    })
    .await;
    let Some((_, ((registration, mut triggers), _on_board))) = joined else {
        return;
    };
    let Connection { mut reader, writer, .. } = conn;
    let writer: Writer = Arc::new(Mutex::new(writer));

    // Triggers go out from their own task so a frame being received is
    // never interrupted.
    let trigger_writer = Arc::clone(&writer);
    let forwarder = tokio::spawn(
        async move {
            while let Some(trigger_id) = triggers.recv().await {
                let sent = trigger_writer.lock().await.send(&Message::Trigger(Trigger { trigger_id })).await;
                match sent {
                    Ok(()) => info!(trigger_id, "trigger sent"),
                    Err(e) => {
                        warn!(trigger_id, "cannot send a trigger: {e}");
                        break;
                    }
                }
            }
        }
        .in_current_span(),
    );

    loop {
        let read = tokio::select! {
            r = reader.read() => r,
            _ = shutdown.recv() => break,
        };
        let reply = match read {
            Ok(Some(received)) => on_message(received, &registration, &state),
            Ok(None) => {
                info!("camera disconnected");
                break;
            }
            Err(ReadError::Decode(e)) if e.frame_ids().is_some() => {
                // A frame whose header was read but whose size or units
                // are wrong: acknowledged as refused, by its ids.
                let (frame_id, trigger_id) = e.frame_ids().unwrap_or_default();
                warn!(frame_id, trigger_id, "{e}");
                Some(refusal(frame_id, trigger_id, e.code(), e.to_string()))
            }
            Err(e) => {
                warn!("{e}");
                let reply = e.reply_code().map(|code| Message::error(code, None, e.to_string()));
                if !e.framing_intact() {
                    if let Some(reply) = reply {
                        let _ = writer.lock().await.send(&reply).await;
                    }
                    break;
                }
                reply
            }
        };
        if let Some(reply) = reply
            && let Err(e) = writer.lock().await.send(&reply).await
        {
            warn!("cannot reply: {e}");
            break;
        }
    }
    drop(registration);
    forwarder.abort();
    writer.lock().await.shutdown().await;
}

/// Why a camera-frame cloud holds no point the camera can measure, if it
/// holds none: every valid point nearer than `camera.min_depth_mm`,
/// farther than `camera.max_depth_mm` or farther off the axis than
/// `camera.max_off_axis_deg` (in millimetres, the units guessed as the
/// planner guesses them when the frame leaves them open). The planner
/// drops such points before any stage, so every plan of the frame would
/// fail. The test is never stricter than the planner's: the field of
/// view of the frame's pixel grid, which the planner may estimate from
/// the frame, is left to it. A base-frame cloud's depths depend on the
/// request's pose, so only the planner can judge them.
fn nothing_measurable(cloud: &PointCloud, input: FrameInput, camera: &CameraModel) -> Option<String> {
    if input.cloud_frame != CloudFrame::Camera {
        return None;
    }
    let metres = match input.units {
        Units::Millimetres => false,
        Units::Metres => true,
        Units::Auto => guess_units(cloud).metres,
    };
    let scale = if metres { 1000.0 } else { 1.0 };
    let volume = camera.measurable_volume(cloud.width(), cloud.height(), false);
    let (mut near, mut far, mut off_view) = (0usize, 0usize, 0usize);
    for p in cloud.points().iter().filter(|p| p[0].is_finite()) {
        match volume.reject(&p.map(|c| c * scale)) {
            None => return None,
            Some(Unmeasurable::Near) => near += 1,
            Some(Unmeasurable::Far) => far += 1,
            Some(Unmeasurable::OffView) => off_view += 1,
        }
    }
    Some(format!(
        "of its {} points none is one the camera can measure: {near} lie nearer than camera.min_depth_mm \
         ({} mm), {far} farther than camera.max_depth_mm ({} mm) and {off_view} farther off the axis than \
         camera.max_off_axis_deg ({}°){}",
        near + far + off_view,
        camera.min_depth_mm,
        camera.max_depth_mm,
        camera.max_off_axis_deg,
        if metres { ", read in metres" } else { "" }
    ))
}

fn refusal(frame_id: u64, trigger_id: u64, code: ErrorCode, message: String) -> Message {
    Message::FrameAck(FrameAck { frame_id, trigger_id, code: code.code(), requests: 0, message })
}

/// Handles one message; returns the reply, if any.
fn on_message(received: Received, camera: &CameraRegistration, state: &ServerState) -> Option<Message> {
    let bytes = received.bytes;
    // The reader measures from the message's first byte: the upload began
    // that long before now, on both of the daemon's clocks.
    let upload_started = Instant::now().checked_sub(received.elapsed).unwrap_or_else(Instant::now);
    let upload_started_us = wall_clock_us().saturating_sub(received.elapsed.as_micros() as u64);
    let frame = match received.message {
        Message::Frame(frame) => frame,
        Message::Ping => return Some(Message::Status(state.status())),
        other => {
            let text = format!("a {} message is not accepted on the camera link", other.tag().name());
            warn!("{text}");
            return Some(Message::error(ErrorCode::UnexpectedMessage, None, text));
        }
    };
    state.idle.touch();
    let meta = frame.meta;
    let (frame_id, trigger_id) = (meta.frame_id, meta.trigger_id);
    // The reader has checked width x height, the units and the cloud frame
    // already; a frame of height 1 becomes an unorganized cloud.
    let Some((cloud, input)) = from_proto::frame(frame) else {
        let text = format!("frame {frame_id} does not have width x height points");
        warn!("{text}");
        return Some(refusal(frame_id, trigger_id, ErrorCode::FrameSizeMismatch, text));
    };
    let valid = cloud.valid_count();
    let cloud_organized = cloud.is_organized();
    if valid == 0 {
        let text = format!("frame {frame_id} has no valid point; it was discarded");
        warn!("{text}");
        return Some(refusal(frame_id, trigger_id, ErrorCode::EmptyFrame, text));
    }
    if let Some(problem) = nothing_measurable(&cloud, input, &state.config.camera) {
        let text = format!("frame {frame_id} has no valid point: {problem}; it was discarded");
        warn!(frame_id, trigger_id, "{text}");
        return Some(refusal(frame_id, trigger_id, ErrorCode::EmptyFrame, text));
    }
    if let Some(problem) = state.frames.capture_time_problem(meta.capture_time_us, upload_started_us) {
        let text = format!("frame {frame_id} was discarded: {problem}");
        warn!(frame_id, trigger_id, capture_time_us = meta.capture_time_us, "{text}");
        state.frames.refused_answer(camera.id(), trigger_id, &text);
        return Some(refusal(frame_id, trigger_id, ErrorCode::BadCaptureTime, text));
    }
    state.count_frame();
    state.board.frame_received(FrameSummary {
        frame_id,
        camera: camera.name().to_string(),
        capture_time_us: meta.capture_time_us,
        received_us: wall_clock_us(),
        points: valid,
    });
    let delivery = state.frames.insert(
        camera.id(),
        StoredFrame {
            frame_id,
            trigger_id,
            capture_time_us: meta.capture_time_us,
            camera: Arc::clone(camera.name()),
            cloud: Arc::new(cloud),
            input,
            upload_started,
            upload_started_us,
            arrived: Instant::now(),
        },
    );
    let (held_frames, held_bytes) = state.frames.held();
    info!(
        frame_id,
        trigger_id,
        capture_time_us = meta.capture_time_us,
        width = meta.width,
        height = meta.height,
        organized = cloud_organized,
        units = ?input.units,
        cloud_frame = ?input.cloud_frame,
        valid_points = valid,
        bytes,
        receive_ms = received.elapsed.as_millis() as u64,
        requests = delivery.requests,
        held_frames,
        held_bytes,
        "frame received"
    );
    let message = match (delivery.requests, delivery.skipped) {
        (0, Some(reason)) => format!("held, but no waiting request could use it: {reason}"),
        _ => String::new(),
    };
    Some(Message::FrameAck(FrameAck { frame_id, trigger_id, code: 0, requests: delivery.requests, message }))
}
