//! The controller link's handler: the hello, then plan requests and pings.
//!
//! A request is checked first (joint, pose, hand-eye, groove depth, step,
//! angles, timeout), then it takes one of its connection's request places
//! (`server.max_requests_per_connection`) and a queue slot (or Busy is
//! answered at once), and its frame wait is registered at once, so the
//! instant it arrived is the one the freshness rule uses. A task per
//! request then waits for the frame and plans it on the pool. Requests run
//! concurrently with the link's reading, so a ping on the same connection
//! is answered while a plan runs.
//!
//! When the connection closes its requests are cancelled at once: waits
//! end and their slots are free for other controllers. When the daemon
//! shuts down, requests still waiting for a frame are answered with
//! `shutting_down`; plans already running finish and are answered.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::{Mutex, OwnedSemaphorePermit, Semaphore};
use tokio::task::JoinSet;
use tracing::{Instrument, error, info, warn};
use weldseam_proto::message::{FrameSelect, PlanReply, Role};
use weldseam_proto::{ErrorCode, Message, message};

use super::ServerState;
use super::camera_link::handshake;
use super::connection::{Connection, MessageWriter};
use super::frames::{FrameError, FrameRequest, FrameWait, StoredFrame, Wanted, wall_clock_us};
use super::jobs::{JobError, JobSlot, JobTimes};
use super::shutdown::{Shutdown, StopSignal};
use crate::convert::from_proto::{self, RequestError};
use crate::convert::to_proto::{plan_error_code, plan_result};
use crate::pipeline::{Plan, PlanRequest};

type Writer = Arc<Mutex<MessageWriter<tokio::net::tcp::OwnedWriteHalf>>>;

/// Serves one controller connection until it closes or the server stops;
/// then waits for its plans in flight (on shutdown) or cancels them (when
/// the peer has gone).
pub async fn serve(mut conn: Connection, state: Arc<ServerState>, mut shutdown: Shutdown) {
    if handshake(&mut conn, Role::Controller, &state, |_| ()).await.is_none() {
        return;
    }
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
                    match accept(&request, &state, &places) {
                        Ok(accepted) => {
                            let job =
                                plan(request, accepted, arrived, Arc::clone(&state), Arc::clone(&writer), stop.clone());
                            plans.spawn(job.in_current_span());
                            None
                        }
                        Err((code, text)) => {
                            state.metrics.request_refused(code);
                            warn!(
                                request_id = request.request_id,
                                code = code.name(),
                                outcome = code.name(),
                                "request refused: {text}"
                            );
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

/// A request that passed its checks, with its places taken and its frame
/// wait registered.
struct Accepted {
    request: PlanRequest,
    wait: FrameWait,
    timeout: Duration,
    slot: JobSlot,
    _place: OwnedSemaphorePermit,
}

type Refusal = (ErrorCode, String);

/// Checks a request, takes its places and starts its frame wait.
fn accept(r: &message::PlanRequest, state: &ServerState, places: &Arc<Semaphore>) -> Result<Accepted, Refusal> {
    let s = &state.config.server;
    let bad = |text: String| (ErrorCode::BadRequest, text);
    let request = from_proto::plan_request(r).map_err(|e| match e {
        RequestError::UnknownJoint(_) => (ErrorCode::UnknownJoint, e.to_string()),
        RequestError::HandEye(_) | RequestError::StartNear(_) | RequestError::RoiFrame(_) | RequestError::Roi(_) => {
            bad(e.to_string())
        }
    })?;
    if r.camera.as_deref() == Some("") {
        return Err(bad("camera is an empty name; leave it absent to use any camera".into()));
    }
    let max_timeout = s.max_request_timeout;
    let timeout = match r.timeout_ms {
        0 => s.fresh_frame_timeout,
        ms if u128::from(ms) > max_timeout.as_millis() => {
            return Err(bad(format!(
                "timeout_ms {ms} is over the daemon's server.max_request_timeout_ms ({})",
                max_timeout.as_millis()
            )));
        }
        ms => Duration::from_millis(ms.into()),
    };
    state.jobs.planner().check_request(&request).map_err(|e| bad(e.reason))?;
    let place = Arc::clone(places).try_acquire_owned().map_err(|_| {
        (
            ErrorCode::Busy,
            format!(
                "this connection already has {} requests waiting or running \
                 (server.max_requests_per_connection); retry when one is answered",
                s.max_requests_per_connection
            ),
        )
    })?;
    let slot = state.jobs.reserve().map_err(|e| (ErrorCode::Busy, e.to_string()))?;
    let wanted = match r.frame {
        FrameSelect::Trigger => Wanted::Trigger,
        FrameSelect::NextFrame => Wanted::NextFrame,
        FrameSelect::FrameId(id) => Wanted::FrameId(id),
    };
    let wait = state
        .frames
        .request(&FrameRequest::now(wanted, r.camera.clone()))
        .map_err(|e| (frame_error_code(&e), e.to_string()))?;
    Ok(Accepted { request, wait, timeout, slot, _place: place })
}

fn frame_error_code(e: &FrameError) -> ErrorCode {
    match e {
        FrameError::NoCamera { .. } | FrameError::CameraGone => ErrorCode::NoCamera,
        FrameError::Timeout { .. } => ErrorCode::FrameTimeout,
        FrameError::UnknownFrame(_) | FrameError::NotArrived { .. } => ErrorCode::UnknownFrame,
        FrameError::Stale(_) => ErrorCode::StaleFrame,
    }
}

/// Why a request got no plan, as its error reply.
struct Failure {
    code: ErrorCode,
    text: String,
}

/// One request's life after acceptance: frame, plan, reply, and one log
/// line with everything an operator needs about it.
async fn plan(
    r: message::PlanRequest,
    accepted: Accepted,
    arrived: Instant,
    state: Arc<ServerState>,
    writer: Writer,
    mut stop: StopSignal,
) {
    let request_id = r.request_id;
    let Accepted { request, wait, timeout, slot, _place } = accepted;
    let fetched = tokio::select! {
        f = wait.wait(timeout) => f,
        _ = stop.stopped() => Err(FrameError::CameraGone),
    };
    let frame_wait = arrived.elapsed();
    let mut log = PlanLog { request_id, joint: request.joint.name(), frame_wait, ..PlanLog::default() };
    // The plan's trace and report, for the debug set written after the reply.
    let (mut traced, mut reported) = (None, None);
    let reply = match fetched {
        // A camera link closed by the shutdown is not a camera that left.
        Err(_) if stop.is_stopping() => Err(Failure {
            code: ErrorCode::ShuttingDown,
            text: "the daemon is shutting down; no frame will be planned for this request".into(),
        }),
        Err(e) => Err(Failure { code: frame_error_code(&e), text: e.to_string() }),
        Ok(frame) => {
            log.frame = Some(Arc::clone(&frame));
            state.idle.touch();
            // The frame says which units and frame its points are in.
            let request = PlanRequest { units: frame.input.units, cloud_frame: frame.input.cloud_frame, ..request };
            let cloud = Arc::clone(&frame.cloud);
            let (outcome, times) = match &state.debug {
                Some(debug) if debug.ready() => {
                    let (outcome, trace, times) = slot.run_traced(cloud, request).await;
                    traced = trace;
                    (outcome, times)
                }
                _ => slot.run(cloud, request).await,
            };
            state.idle.touch();
            log.times = times;
            match outcome {
                Ok(plan) => {
                    state.count_plan();
                    let result = plan_result(&plan, state.config.euler);
                    reported = traced.is_some().then(|| result.clone());
                    log.plan = Some(plan);
                    Ok(Message::PlanReply(PlanReply { request_id, frame_id: frame.frame_id, result }))
                }
                Err(JobError::Plan(e)) => {
                    Err(Failure { code: plan_error_code(&e), text: format!("frame {}: {e}", frame.frame_id) })
                }
                Err(e @ JobError::Panicked) => {
                    error!(request_id, frame_id = frame.frame_id, "{e}");
                    Err(Failure { code: ErrorCode::Internal, text: e.to_string() })
                }
            }
        }
    };
    let reply = match reply {
        Ok(reply) => reply,
        Err(Failure { code, text }) => {
            log.failure = Some((code, text.clone()));
            Message::error(code, Some(request_id), text)
        }
    };
    log.latency = arrived.elapsed();
    log.emit();
    state.metrics.plan_answered(&reply, arrived.elapsed());
    if let Err(e) = writer.lock().await.send(&reply).await {
        warn!(request_id, "cannot send the reply: {e}");
    }
    if let (Some(debug), Some(trace)) = (&state.debug, traced) {
        debug.keep(request_id, trace, reported);
    }
}

/// The one log line per plan request.
#[derive(Default)]
struct PlanLog {
    request_id: u64,
    joint: &'static str,
    frame: Option<Arc<StoredFrame>>,
    frame_wait: Duration,
    times: JobTimes,
    plan: Option<Plan>,
    failure: Option<(ErrorCode, String)>,
    latency: Duration,
}

impl PlanLog {
    fn emit(&self) {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let frame_id = self.frame.as_ref().map(|f| f.frame_id);
        let camera = self.frame.as_ref().map(|f| f.camera.to_string());
        // Capture to plan start, by the camera's stamp on the daemon's clock.
        let frame_age_ms = self.frame.as_ref().map(|f| {
            let planned_us = wall_clock_us().saturating_sub((self.times.planning.as_micros()) as u64);
            planned_us.saturating_sub(f.capture_time_us) as f64 / 1e3
        });
        let seam = self.plan.as_ref().and_then(|p| p.seams.first());
        let stages = self.plan.as_ref().map(|p| {
            p.timings.stages.iter().map(|(s, t)| format!("{}={t:.1}", s.name())).collect::<Vec<_>>().join(" ")
        });
        let outcome = self.failure.as_ref().map(|(code, _)| code.name()).unwrap_or("planned");
        let fields = format!(
            "frame_wait_ms={:.1} queue_ms={:.1} plan_ms={:.1}",
            ms(self.frame_wait),
            ms(self.times.queued),
            ms(self.times.planning)
        );
        let detail = self.failure.as_ref().map(|(_, text)| text.as_str()).unwrap_or("");
        let line = tracing::field::display(detail);
        if self.failure.is_some() {
            warn!(
                request_id = self.request_id,
                joint = self.joint,
                frame_id,
                camera,
                frame_age_ms,
                outcome,
                times = fields,
                latency_ms = ms(self.latency),
                reason = line,
                "plan"
            );
        } else {
            info!(
                request_id = self.request_id,
                joint = self.joint,
                frame_id,
                camera,
                frame_age_ms,
                seams = self.plan.as_ref().map(|p| p.seams.len()),
                seam_length_mm = seam.map(|s| s.length_mm),
                waypoints = seam.map(|s| s.waypoints.len()),
                edge_fit_rms_mm = seam.map(|s| format!("{:.3}/{:.3}", s.edge_fit_rms_mm[0], s.edge_fit_rms_mm[1])),
                edge_samples = seam.map(|s| format!("{}/{}", s.edge_samples[0], s.edge_samples[1])),
                edge_samples_dropped =
                    seam.map(|s| format!("{}/{}", s.edge_samples_dropped[0], s.edge_samples_dropped[1])),
                stages_ms = stages,
                outcome,
                times = fields,
                latency_ms = ms(self.latency),
                "plan"
            );
        }
    }
}
