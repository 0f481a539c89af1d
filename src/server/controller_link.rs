//! The controller link's handler: the hello, then plan requests and pings.
//!
//! A request is converted to the library's form, then goes the plan path
//! both controller links share ([`super::planning`]): checked, given its
//! places and its frame wait at once. A task per request then waits for
//! the frame and plans it on the pool. Requests run
//! concurrently with the link's reading, so a ping on the same connection
//! is answered while a plan runs.
//!
//! When the connection closes its requests are cancelled at once: waits
//! end and their slots are free for other controllers. When the daemon
//! shuts down, requests still waiting for a frame are answered with
//! `shutting_down`; plans already running finish and are answered.

use std::sync::Arc;
use std::time::Instant;

use tokio::sync::{Mutex, Semaphore};
use tokio::task::JoinSet;
use tracing::{Instrument, info, warn};
use weldseam_proto::message::{FrameSelect, PlanReply, Role};
use weldseam_proto::session::capability;
use weldseam_proto::{ErrorCode, Message, message};

use super::ServerState;
use super::camera_link::handshake;
use super::connection::{Connection, MessageWriter};
use super::frames::Wanted;
use super::planning::{Accepted, Ask, Failure, Fulfilled, Planned, Refusal, accept, fulfil_traced, refused};
use super::shutdown::{Shutdown, StopSignal};
use crate::convert::from_proto::{self, RequestError};
use crate::convert::to_proto::{add_along_seam, plan_result};
use crate::geometry::pose::EulerConvention;

type Writer = Arc<Mutex<MessageWriter<tokio::net::tcp::OwnedWriteHalf>>>;

/// Serves one controller connection until it closes or the server stops;
/// then waits for its plans in flight (on shutdown) or cancels them (when
/// the peer has gone).
pub async fn serve(mut conn: Connection, state: Arc<ServerState>, mut shutdown: Shutdown) {
    let peer = conn.peer;
    let joined = handshake(&mut conn, Role::Controller, &state, |hello| {
        state.board.peer_joined(Role::Controller.name(), peer, &hello.name)
    })
    .await;
    let Some((_, _on_board)) = joined else {
        return;
    };
    let Connection { mut reader, writer, .. } = conn;
    let writer: Writer = Arc::new(Mutex::new(writer));
    let places = Arc::new(Semaphore::new(state.config.server.max_requests_per_connection));
    let stop = shutdown.stop_signal();
    let mut plans = JoinSet::new();
    let peer_gone = loop {
        while plans.try_join_next().is_some() {}
        let read = tokio::select! {
            r = reader.read() => r,
            _ = shutdown.recv() => break false,
        };
        let reply = match read {
            Ok(Some(received)) => match received.message {
                Message::Ping => Some(Message::Status(state.status())),
                Message::PlanRequest(request) => {
                    let arrived = Instant::now();
                    let request_id = request.request_id;
                    let accepted = match ask(&request, state.config.euler) {
                        Ok(ask) => accept(ask, arrived, &state, &places),
                        Err(refusal) => Err(refused(request_id, refusal, &state)),
                    };
                    match accepted {
                        Ok(accepted) => {
                            let job = plan(request_id, accepted, Arc::clone(&state), Arc::clone(&writer), stop.clone());
                            plans.spawn(job.in_current_span());
                            None
                        }
                        Err(refusal) => Some(refusal_message(request_id, &refusal)),
                    }
                }
                other => {
                    let text = format!("a {} message is not accepted on the controller link", other.tag().name());
                    warn!("{text}");
                    Some(Message::error(ErrorCode::UnexpectedMessage, None, text))
                }
            },
            Ok(None) => {
                info!("controller disconnected");
                break true;
            }
            Err(e) => {
                warn!("{e}");
                let reply = e.reply_code().map(|code| Message::error(code, None, e.to_string()));
                if !e.framing_intact() {
                    if let Some(reply) = reply {
                        let _ = writer.lock().await.send(&reply).await;
                    }
                    break true;
                }
                reply
            }
        };
        if let Some(reply) = reply
            && let Err(e) = writer.lock().await.send(&reply).await
        {
            warn!("cannot reply: {e}");
            break true;
        }
    };
    while plans.try_join_next().is_some() {}
    if peer_gone {
        // Nobody is left to answer: withdraw the waits and free the slots.
        if !plans.is_empty() {
            info!(requests = plans.len(), "cancelling the closed connection's requests");
        }
        plans.shutdown().await;
    } else {
        if !plans.is_empty() {
            info!(plans = plans.len(), "waiting for plans in flight");
        }
        while plans.join_next().await.is_some() {}
    }
    writer.lock().await.shutdown().await;
}

/// The Error refusing a request before it was queued, naming the rule
/// that refused it when one did (sent to a peer granted `rule_ids`).
fn refusal_message(request_id: u64, refusal: &Refusal) -> Message {
    match refusal.rule {
        Some(rule) => Message::refusal(refusal.code, Some(request_id), refusal.text.clone(), rule.id),
        None => Message::error(refusal.code, Some(request_id), refusal.text.clone()),
    }
}

/// The library's request and the daemon's options for a wire request.
fn ask(r: &message::PlanRequest, euler: EulerConvention) -> Result<Ask, Refusal> {
    let request = from_proto::plan_request(r, euler).map_err(|e| match e {
        RequestError::UnknownJoint(_) => Refusal::new(ErrorCode::UnknownJoint, e.to_string()),
        RequestError::HandEye(_)
        | RequestError::StartNear(_)
        | RequestError::RoiFrame(_)
        | RequestError::Roi(_)
        | RequestError::PoseConvention(_)
        | RequestError::PoseUnit { .. }
        | RequestError::Pose(_) => Refusal::new(ErrorCode::BadRequest, e.to_string()),
    })?;
    let wanted = match r.frame {
        FrameSelect::Trigger => Wanted::Trigger,
        FrameSelect::NextFrame => Wanted::NextFrame,
        FrameSelect::FrameId(id) => Wanted::FrameId(id),
    };
    Ok(Ask { request_id: r.request_id, request, wanted, timeout_ms: r.timeout_ms, camera: r.camera.clone() })
}

/// One request's life after acceptance: the shared plan path, then the
/// reply on this link, then (when the daemon keeps them) the plan's debug
/// set, written after the reply so it never delays one.
async fn plan(request_id: u64, accepted: Accepted, state: Arc<ServerState>, writer: Writer, stop: StopSignal) {
    let Fulfilled { outcome, trace: traced, seq } = fulfil_traced(accepted, &state, stop, "controller").await;
    let mut reported = None;
    let reply = match outcome {
        Ok(Planned { frame_id, plan }) => {
            let mut result = plan_result(&plan, state.config.euler);
            // The figures along each seam and its process travel to a peer
            // granted them, and into the debug set's profile picture.
            let granted = writer.lock().await.session().has(capability::ALONG_SEAM);
            if granted || traced.is_some() {
                add_along_seam(&mut result, &plan);
            }
            reported = traced.is_some().then(|| result.clone());
            Message::PlanReply(PlanReply { request_id, frame_id, result })
        }
        Err(Failure { code, text, rule, .. }) => match rule {
            Some(rule) => Message::refusal(code, Some(request_id), text, rule.id),
            None => Message::error(code, Some(request_id), text),
        },
    };
    if let Err(e) = writer.lock().await.send(&reply).await {
        warn!(request_id, "cannot send the reply: {e}");
    }
    if let Some(trace) = traced {
        state.debug.keep(request_id, seq, trace, reported);
    }
}
