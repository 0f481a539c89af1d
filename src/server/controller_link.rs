//! The controller link's handler: the hello, then plan requests and pings.
//!
//! A request is checked first (joint, pose, groove depth, step, angles), a
//! queue slot is reserved (or Busy is answered at once), and a task per
//! request fetches its frame by the request's rule and plans it on the
//! pool. Requests run concurrently with the link's reading, so a ping on
//! the same connection is answered while a plan runs.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::Mutex;
use tokio::task::JoinSet;
use tracing::{Instrument, error, info, warn};
use weldseam_proto::message::{FrameSelect, PlanReply, Role};
use weldseam_proto::{ErrorCode, Message, message};

use super::ServerState;
use super::camera_link::handshake;
use super::connection::{Connection, MessageWriter};
use super::frames::{FrameError, StoredFrame};
use super::jobs::{JobError, JobSlot};
use super::shutdown::Shutdown;
use crate::geometry::pose::RobotPose;
use crate::pipeline::{PlanRequest, Stage};
use crate::report::{joint_from_proto, plan_result};

type Writer = Arc<Mutex<MessageWriter<tokio::net::tcp::OwnedWriteHalf>>>;

/// The longest frame wait a request may ask for.
const MAX_REQUEST_TIMEOUT: Duration = Duration::from_secs(600);

/// Serves one controller connection until it closes or the server stops;
/// then waits for its plans in flight.
pub async fn serve(mut conn: Connection, state: Arc<ServerState>, mut shutdown: Shutdown) {
    if !handshake(&mut conn, Role::Controller, &state).await {
        return;
    }
    let Connection { mut reader, writer, .. } = conn;
    let writer: Writer = Arc::new(Mutex::new(writer));
    let mut plans = JoinSet::new();
    loop {
        while plans.try_join_next().is_some() {}
        let read = tokio::select! {
            r = reader.read() => r,
            _ = shutdown.recv() => break,
        };
        let reply = match read {
            Ok(Some(received)) => match received.message {
                Message::Ping => Some(Message::Status(state.status())),
                Message::PlanRequest(request) => {
                    let arrived = Instant::now();
                    match accept(&request, &state) {
                        Ok((plan_request, slot)) => {
                            let job =
                                plan(request, plan_request, slot, arrived, Arc::clone(&state), Arc::clone(&writer));
                            plans.spawn(job.in_current_span());
                            None
                        }
                        Err((code, text)) => {
                            state.metrics.request_refused(code);
                            warn!(request_id = request.request_id, code = code.name(), "request refused: {text}");
                            Some(Message::error(code, Some(request.request_id), text))
                        }
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
                break;
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
    while plans.try_join_next().is_some() {}
    if !plans.is_empty() {
        info!(plans = plans.len(), "waiting for plans in flight");
    }
    while plans.join_next().await.is_some() {}
    writer.lock().await.shutdown().await;
}

/// Checks a request and reserves its queue slot.
fn accept(r: &message::PlanRequest, state: &ServerState) -> Result<(PlanRequest, JobSlot), (ErrorCode, String)> {
    let joint = r.joint_type().ok_or_else(|| {
        (
            ErrorCode::UnknownJoint,
            format!("joint code {} is unknown; expected 0 (v_butt), 1 (i_butt) or 2 (lap)", r.joint),
        )
    })?;
    let [x, y, z, rx, ry, rz] = r.pose;
    let request = PlanRequest {
        joint: joint_from_proto(joint),
        groove_depth_mm: r.groove_depth_mm,
        pose: RobotPose { xyz_mm: [x, y, z], angles_deg: [rx, ry, rz] },
        hand_eye: None,
        step_mm: r.step_mm,
        work_angle_deg: r.work_angle_deg,
        travel_angle_deg: r.travel_angle_deg,
    };
    request.validate().map_err(|e| (ErrorCode::BadRequest, e.reason))?;
    let slot = state.jobs.reserve().map_err(|e| (ErrorCode::Busy, e.to_string()))?;
    Ok((request, slot))
}

/// Fetches the request's frame by its rule.
async fn fetch_frame(
    select: FrameSelect,
    timeout: Duration,
    state: &ServerState,
) -> Result<Arc<StoredFrame>, FrameError> {
    match select {
        FrameSelect::FrameId(id) => state.frames.by_id(id),
        FrameSelect::NextFrame => state.frames.next_frame()?.wait(timeout).await,
        FrameSelect::Trigger => state.frames.trigger()?.wait(timeout).await,
    }
}

fn frame_error_code(e: &FrameError) -> ErrorCode {
    match e {
        FrameError::NoCamera | FrameError::CameraGone => ErrorCode::NoCamera,
        FrameError::Timeout(_) => ErrorCode::FrameTimeout,
        FrameError::UnknownFrame(_) => ErrorCode::UnknownFrame,
    }
}

/// One request's life after acceptance: frame, plan, reply.
async fn plan(
    r: message::PlanRequest,
    request: PlanRequest,
    slot: JobSlot,
    arrived: Instant,
    state: Arc<ServerState>,
    writer: Writer,
) {
    let request_id = r.request_id;
    let timeout = match r.timeout_ms {
        0 => state.config.server.fresh_frame_timeout,
        ms => Duration::from_millis(ms.into()).min(MAX_REQUEST_TIMEOUT),
    };
    let reply = match fetch_frame(r.frame, timeout, &state).await {
        Err(e) => {
            warn!(request_id, "no frame for the request: {e}");
            Message::error(frame_error_code(&e), Some(request_id), e.to_string())
        }
        Ok(frame) => match slot.run(Arc::clone(&frame.cloud), request).await {
            Ok(plan) => {
                state.count_plan();
                let result = plan_result(&plan, state.config.euler);
                info!(
                    request_id,
                    frame_id = frame.frame_id,
                    seams = result.seams.len(),
                    waypoints = result.seams.iter().map(|s| s.waypoints.len()).sum::<usize>(),
                    latency_ms = arrived.elapsed().as_millis() as u64,
                    "plan answered"
                );
                Message::PlanReply(PlanReply { request_id, frame_id: frame.frame_id, result })
            }
            Err(JobError::Plan(e)) => {
                warn!(request_id, frame_id = frame.frame_id, "no plan: {e}");
                let code = if e.stage == Stage::Request { ErrorCode::BadRequest } else { ErrorCode::PlanFailed };
                Message::error(code, Some(request_id), format!("frame {}: {e}", frame.frame_id))
            }
            Err(e @ JobError::Panicked) => {
                error!(request_id, frame_id = frame.frame_id, "{e}");
                Message::error(ErrorCode::Internal, Some(request_id), e.to_string())
            }
        },
    };
    state.metrics.plan_answered(&reply, arrived.elapsed());
    if let Err(e) = writer.lock().await.send(&reply).await {
        warn!(request_id, "cannot send the reply: {e}");
    }
}
