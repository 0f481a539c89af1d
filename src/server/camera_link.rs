//! The camera link's handler: the hello, then frames in and triggers out.
//! Each frame is checked (size, at least one valid point), stored in the
//! history and handed to the requests waiting for it.

use std::sync::Arc;
use std::time::Instant;

use tokio::sync::Mutex;
use tracing::{Instrument, info, warn};
use weldseam_proto::message::{HelloAck, Role, Trigger};
use weldseam_proto::{ErrorCode, Message, PROTOCOL_VERSION};

use super::ServerState;
use super::connection::{Connection, HandshakeError, MessageWriter, Received};
use super::frames::StoredFrame;
use super::shutdown::Shutdown;
use crate::cloud::PointCloud;

type Writer = Arc<Mutex<MessageWriter<tokio::net::tcp::OwnedWriteHalf>>>;

/// The daemon's name in hello acks.
pub(crate) fn server_name() -> String {
    format!("weldseam {}", env!("CARGO_PKG_VERSION"))
}

/// Answers a handshake: an ack, or the typed refusal. Returns false when
/// the connection should close.
pub(crate) async fn handshake(conn: &mut Connection, role: Role, state: &ServerState) -> bool {
    match conn.expect_hello(role, state.config.server.stall_timeout).await {
        Ok(hello) => {
            info!(name = %hello.name, "{} connected", role.name());
            let ack = Message::HelloAck(HelloAck { protocol_version: PROTOCOL_VERSION, server: server_name() });
            conn.writer.send(&ack).await.is_ok()
        }
        Err(HandshakeError::Closed) => {
            info!("closed before its hello");
            false
        }
        Err(HandshakeError::Read(e)) => {
            warn!("bad hello: {e}");
            if let Some(code) = e.reply_code() {
                let _ = conn.writer.send(&Message::error(code, None, e.to_string())).await;
            }
            false
        }
        Err(e @ HandshakeError::Refused { code, .. }) => {
            warn!("refused: {e}");
            let _ = conn.writer.send(&Message::error(code, None, e.to_string())).await;
            false
        }
        Err(e @ HandshakeError::Timeout(_)) => {
            warn!("dropped: {e}");
            false
        }
    }
}

/// Serves one camera connection until it closes or the server stops.
pub async fn serve(mut conn: Connection, state: Arc<ServerState>, mut shutdown: Shutdown) {
    if !handshake(&mut conn, Role::Camera, &state).await {
        return;
    }
    let Connection { mut reader, writer, .. } = conn;
    let writer: Writer = Arc::new(Mutex::new(writer));
    let (registration, mut triggers) = state.frames.attach_camera();

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
        match read {
            Ok(Some(received)) => {
                if let Some(reply) = on_message(received, &state)
                    && let Err(e) = writer.lock().await.send(&reply).await
                {
                    warn!("cannot reply: {e}");
                    break;
                }
            }
            Ok(None) => {
                info!("camera disconnected");
                break;
            }
            Err(e) => {
                warn!("{e}");
                if let Some(code) = e.reply_code() {
                    let _ = writer.lock().await.send(&Message::error(code, None, e.to_string())).await;
                }
                if !e.framing_intact() {
                    break;
                }
            }
        }
    }
    drop(registration);
    forwarder.abort();
    writer.lock().await.shutdown().await;
}

/// Handles one message; returns the reply, if any.
fn on_message(received: Received, state: &ServerState) -> Option<Message> {
    let bytes = received.bytes;
    let frame = match received.message {
        Message::Frame(frame) => frame,
        Message::Ping => return Some(Message::Status(state.status())),
        other => {
            let text = format!("a {} message is not accepted on the camera link", other.tag().name());
            warn!("{text}");
            return Some(Message::error(ErrorCode::UnexpectedMessage, None, text));
        }
    };
    let meta = frame.meta;
    // The reader has checked width x height against the payload already.
    let Some(cloud) = PointCloud::organized(meta.width as usize, meta.height as usize, frame.points) else {
        let text = format!("frame {} does not have width x height points", meta.frame_id);
        warn!("{text}");
        return Some(Message::error(ErrorCode::FrameSizeMismatch, None, text));
    };
    let valid = cloud.valid_count();
    if valid == 0 {
        let text = format!("frame {} has no valid point; it was discarded", meta.frame_id);
        warn!("{text}");
        return Some(Message::error(ErrorCode::EmptyFrame, None, text));
    }
    info!(
        frame_id = meta.frame_id,
        trigger_id = meta.trigger_id,
        width = meta.width,
        height = meta.height,
        valid_points = valid,
        bytes,
        receive_ms = received.elapsed.as_millis() as u64,
        "frame received"
    );
    state.count_frame();
    state.frames.insert(StoredFrame {
        frame_id: meta.frame_id,
        trigger_id: meta.trigger_id,
        capture_time_us: meta.capture_time_us,
        cloud: Arc::new(cloud),
        arrived: Instant::now(),
    });
    None
}
