//! The plan path both controller links share, the binary one and the text
//! one: a request is checked (joint, pose, hand-eye, groove depth, step,
//! angles, timeout), takes one of its connection's request places
//! (`server.max_requests_per_connection`) and a queue slot (or Busy is
//! answered at once), and its frame wait is registered at once, so the
//! instant it arrived is the one the freshness rule uses ([`accept`]).
//! Then [`fulfil`] waits for the frame, plans it on the pool, counts the
//! outcome and logs one line with everything an operator needs about it.
//! Every refusal and warning is logged and counted by the planner's rule
//! that made it (its `rule` field and `weldseam_refusals_total{rule=...}`,
//! `weldseam_warnings_total{rule=...}`), and the rule travels to the
//! reply. The links only read requests and write replies in their own form.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tracing::{error, info, warn};
use weldseam_proto::ErrorCode;

use super::ServerState;
use super::board::PlanSummary;
use super::frames::{FrameError, FrameRequest, FrameWait, Handed, StoredFrame, Wanted, wall_clock_us};
use super::jobs::{JobError, JobSlot, JobTimes};
use super::recorder;
use super::shutdown::StopSignal;
use crate::convert::to_proto::{add_along_seam, plan_error_code, plan_result};
use crate::pipeline::trace::PlanTrace;
use crate::pipeline::{Plan, PlanRequest};
use crate::records::Outcome;
use crate::rules::Rule;

/// A plan request in the library's form, with what the daemon needs to
/// serve it: which frame, how long to wait, which camera.
#[derive(Debug, Clone)]
pub(crate) struct Ask {
    /// Echoed in the reply and the log.
    pub request_id: u64,
    pub request: PlanRequest,
    pub wanted: Wanted,
    /// How long to wait for the frame, ms; 0 is the daemon's default.
    pub timeout_ms: u32,
    /// The camera (its Hello name) to use; any when None.
    pub camera: Option<String>,
}

/// A request that passed its checks, with its places taken and its frame
/// wait registered.
pub(crate) struct Accepted {
    request_id: u64,
    request: PlanRequest,
    wait: FrameWait,
    timeout: Duration,
    slot: JobSlot,
    /// When the request arrived: its frame must be newer.
    arrived: Instant,
    _place: OwnedSemaphorePermit,
}

/// A request refused before it was queued.
#[derive(Debug)]
pub(crate) struct Refusal {
    pub code: ErrorCode,
    pub text: String,
    /// The planner's rule that refused it, when one did (the request
    /// rules); none for the daemon's own limits (busy, timeout, camera).
    pub rule: Option<&'static Rule>,
}

impl Refusal {
    /// A refusal by the daemon, not by a rule of the planner.
    pub fn new(code: ErrorCode, text: impl Into<String>) -> Self {
        Refusal { code, text: text.into(), rule: None }
    }
}

/// Checks a request that arrived at `arrived`, takes its places and
/// starts its frame wait; a refusal is counted.
pub(crate) fn accept(
    ask: Ask,
    arrived: Instant,
    state: &ServerState,
    places: &Arc<Semaphore>,
) -> Result<Accepted, Refusal> {
    let request_id = ask.request_id;
    check_and_reserve(ask, arrived, state, places).map_err(|refusal| refused(request_id, refusal, state))
}

/// Counts and logs a request refused before it was queued.
pub(crate) fn refused(request_id: u64, refusal: Refusal, state: &ServerState) -> Refusal {
    let Refusal { code, text, rule } = &refusal;
    state.metrics.request_refused(*code);
    if let Some(rule) = rule {
        state.metrics.refused_by(rule);
    }
    let rule = rule.map(|r| r.id);
    warn!(request_id, code = code.name(), outcome = code.name(), rule, "request refused: {text}");
    refusal
}

fn check_and_reserve(
    ask: Ask,
    arrived: Instant,
    state: &ServerState,
    places: &Arc<Semaphore>,
) -> Result<Accepted, Refusal> {
    let s = &state.config.server;
    let bad = |text: String| Refusal::new(ErrorCode::BadRequest, text);
    let Ask { request_id, request, wanted, timeout_ms, camera } = ask;
    if camera.as_deref() == Some("") {
        return Err(bad("camera is an empty name; leave it absent to use any camera".into()));
    }
    let max_timeout = s.max_request_timeout;
    let timeout = match timeout_ms {
        0 => s.fresh_frame_timeout,
        ms if u128::from(ms) > max_timeout.as_millis() => {
            return Err(bad(format!(
                "timeout_ms {ms} is over the daemon's server.max_request_timeout_ms ({})",
                max_timeout.as_millis()
            )));
        }
        ms => Duration::from_millis(ms.into()),
    };
    state.jobs.planner().check_request(&request).map_err(|e| Refusal {
        code: ErrorCode::BadRequest,
        text: e.reason,
        rule: Some(e.rule),
    })?;
    let place = Arc::clone(places).try_acquire_owned().map_err(|_| {
        Refusal::new(
            ErrorCode::Busy,
            format!(
                "this connection already has {} requests waiting or running \
                 (server.max_requests_per_connection); retry when one is answered",
                s.max_requests_per_connection
            ),
        )
    })?;
    let slot = state.jobs.reserve().map_err(|e| Refusal::new(ErrorCode::Busy, e.to_string()))?;
    let wait = state
        .frames
        .request(&FrameRequest::now(wanted, camera))
        .map_err(|e| Refusal::new(frame_error_code(&e), e.to_string()))?;
    Ok(Accepted { request_id, request, wait, timeout, slot, arrived, _place: place })
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
#[derive(Debug)]
pub(crate) struct Failure {
    pub code: ErrorCode,
    /// The whole message, as the binary link sends it: where, then why.
    pub text: String,
    /// Where the failure arose (the frame and the pipeline stage), when
    /// `text` leads with it; a robot's pendant line leads with the cause
    /// instead ([`Failure::cause_first`]).
    pub place: Option<String>,
    /// The planner's rule that refused the plan, when one did; none for a
    /// frame that never came, a shutdown or a fault.
    pub rule: Option<&'static Rule>,
}

impl Failure {
    fn new(code: ErrorCode, text: impl Into<String>) -> Self {
        Failure { code, text: text.into(), place: None, rule: None }
    }

    /// What a robot's pendant shows: the rule's id first (a program can
    /// branch on it: it ends at the first `: `), then the cause, then where
    /// it arose ([`Failure::cause_first`]).
    pub fn pendant_reason(&self) -> String {
        match self.rule {
            Some(rule) => format!("{}: {}", rule.id, self.cause_first()),
            None => self.cause_first(),
        }
    }

    /// The message with the cause first and where it arose after it, in
    /// parentheses: what a pendant's few characters should show first.
    pub fn cause_first(&self) -> String {
        match &self.place {
            Some(place) => {
                let cause = self.text.strip_prefix(place.as_str()).unwrap_or(&self.text);
                // "frame 3: groove stage failed:" is said "(frame 3; groove stage)".
                let label = place.trim_end_matches(" failed:").replace(": ", "; ");
                format!("{} ({label})", cause.trim_start())
            }
            None => self.text.clone(),
        }
    }
}

/// A plan and the frame it was computed from.
#[derive(Debug)]
pub(crate) struct Planned {
    pub frame_id: u64,
    pub plan: Plan,
}

/// One request's life after acceptance: the frame, the plan, the count of
/// its outcome, its place on the operator page's board and the one log
/// line about it. The caller writes the reply.
pub(crate) async fn fulfil(
    accepted: Accepted,
    state: &ServerState,
    stop: StopSignal,
    link: &'static str,
) -> Result<Planned, Failure> {
    fulfil_inner(accepted, state, stop, link, false).await.outcome
}

/// What [`fulfil_traced`] gives back.
pub(crate) struct Fulfilled {
    pub outcome: Result<Planned, Failure>,
    /// The plan's trace, when its pictures are wanted.
    pub trace: Option<PlanTrace>,
    /// The plan's number on the board.
    pub seq: u64,
}

/// [`fulfil`], and the plan's trace when the daemon keeps debug sets
/// (`[debug]`) or serves the page, and no set is being rendered: the
/// caller keeps it after its reply is sent.
pub(crate) async fn fulfil_traced(
    accepted: Accepted,
    state: &ServerState,
    stop: StopSignal,
    link: &'static str,
) -> Fulfilled {
    fulfil_inner(accepted, state, stop, link, true).await
}

async fn fulfil_inner(
    accepted: Accepted,
    state: &ServerState,
    mut stop: StopSignal,
    link: &'static str,
    want_trace: bool,
) -> Fulfilled {
    let Accepted { request_id, request, wait, timeout, slot, arrived, _place } = accepted;
    // The request as asked, before the frame's units are filled in.
    let asked = state.recorder.enabled().then(|| request.clone());
    let fetched = tokio::select! {
        f = wait.wait(timeout) => f,
        _ = stop.stopped() => Err(FrameError::CameraGone),
    };
    let frame_wait = arrived.elapsed();
    let mut log = PlanLog { request_id, joint: request.joint.name(), frame_wait, ..PlanLog::default() };
    let mut traced = None;
    let outcome = match fetched {
        // A camera link closed by the shutdown is not a camera that left.
        Err(_) if stop.is_stopping() => Err(Failure::new(
            ErrorCode::ShuttingDown,
            "the daemon is shutting down; no frame will be planned for this request",
        )),
        Err(e) => Err(Failure::new(frame_error_code(&e), e.to_string())),
        Ok(Handed { frame, ticket }) => {
            log.frame = Some(Arc::clone(&frame));
            state.idle.touch();
            // The frame says which units and frame its points are in.
            let request = PlanRequest { units: frame.input.units, cloud_frame: frame.input.cloud_frame, ..request };
            let cloud = Arc::clone(&frame.cloud);
            let (outcome, times) = match &state.debug {
                debug if want_trace && debug.ready() => {
                    let (outcome, trace, times) = slot.run_traced(ticket, cloud, request).await;
                    traced = trace;
                    (outcome, times)
                }
                _ => slot.run(ticket, cloud, request).await,
            };
            state.idle.touch();
            log.times = times;
            match outcome {
                Ok(plan) => {
                    state.count_plan();
                    Ok(Planned { frame_id: frame.frame_id, plan })
                }
                Err(JobError::Plan(e)) if e.out_of_time => {
                    let place = format!("frame {}: {} stage failed:", frame.frame_id, e.stage);
                    let text = format!(
                        "{place} the plan ran past server.plan_timeout_ms ({} ms) and was stopped; no trajectory \
                         from this frame",
                        state.config.server.plan_timeout.as_millis()
                    );
                    Err(Failure { code: plan_error_code(&e), text, place: Some(place), rule: Some(e.rule) })
                }
                Err(JobError::Plan(e)) => {
                    let place = format!("frame {}: {} stage failed:", frame.frame_id, e.stage);
                    let text = format!("frame {}: {e}", frame.frame_id);
                    let place = text.starts_with(&place).then_some(place);
                    Err(Failure { code: plan_error_code(&e), text, place, rule: Some(e.rule) })
                }
                Err(e @ JobError::Panicked) => {
                    error!(request_id, frame_id = frame.frame_id, "{e}");
                    Err(Failure::new(ErrorCode::Internal, e.to_string()))
                }
            }
        }
    };
    match &outcome {
        Ok(planned) => {
            log.plan = Some(&planned.plan);
            count_findings(request_id, &planned.plan, state);
        }
        Err(Failure { code, text, rule, .. }) => {
            log.failure = Some((*code, text.clone()));
            log.rule = *rule;
            if let Some(rule) = rule {
                state.metrics.refused_by(rule);
            }
        }
    }
    log.latency = arrived.elapsed();
    log.emit();
    state.metrics.plan_answered(outcome.as_ref().map(|_| ()).map_err(|f| f.code), arrived.elapsed());
    let seq = post(&log, link, &outcome, state);
    if let (Some(request), Some(frame)) = (&asked, &log.frame) {
        let recorded = match &outcome {
            Ok(planned) => Outcome::Planned(full_result(&planned.plan, state)),
            Err(f) => Outcome::Refused {
                code: f.code.name().to_string(),
                rule: f.rule.map(|r| r.id.to_string()),
                reason: f.text.clone(),
            },
        };
        let plan = recorder::Plan { seq, link, request_id, request, frame, outcome: recorded };
        state.recorder.keep(plan, &state.metrics);
    }
    Fulfilled { outcome, trace: traced, seq }
}

/// Puts the plan on the operator page's board; returns its number there.
fn post(log: &PlanLog<'_>, link: &'static str, outcome: &Result<Planned, Failure>, state: &ServerState) -> u64 {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let (outcome_name, rule, reason) = match outcome {
        Ok(_) => ("planned", None, None),
        Err(f) => (f.code.name(), f.rule.map(|r| r.id), Some(f.text.clone())),
    };
    let summary = PlanSummary {
        seq: 0,
        time_us: wall_clock_us(),
        link,
        request_id: log.request_id,
        joint: log.joint.to_string(),
        frame_id: log.frame.as_ref().map(|f| f.frame_id),
        camera: log.frame.as_ref().map(|f| f.camera.to_string()),
        points: log.frame.as_ref().map(|f| f.cloud.len()),
        seams: outcome.as_ref().map_or(0, |p| p.plan.seams.len()),
        outcome: outcome_name,
        rule,
        reason,
        plan_ms: ms(log.times.planning),
        latency_ms: ms(log.latency),
        record: None,
        pictures: false,
        sections: false,
        profile: false,
    };
    let result = outcome.as_ref().ok().map(|p| full_result(&p.plan, state));
    state.board.add_plan(summary, result)
}

/// The plan's report with everything it carries: each seam's figures
/// along it and its process too, which the page shows and a record keeps
/// whatever a controller asked for.
fn full_result(plan: &Plan, state: &ServerState) -> weldseam_proto::plan::PlanResult {
    let mut result = plan_result(plan, state.config.euler);
    add_along_seam(&mut result, plan);
    result
}

/// Logs and counts, by rule, each warning of a plan's seams and each joint
/// it left unplanned (a refusal of that joint).
fn count_findings(request_id: u64, plan: &Plan, state: &ServerState) {
    for (k, seam) in plan.seams.iter().enumerate() {
        for warning in &seam.warnings {
            state.metrics.warned_by(warning.rule);
            warn!(
                request_id,
                seam = k + 1,
                rule = warning.rule.id,
                gate = warning.gate.name(),
                "warning: {}",
                warning.message
            );
        }
    }
    for unplanned in &plan.unplanned {
        state.metrics.refused_by(unplanned.reason.rule);
        let joint = unplanned.joint.map(|j| j.name());
        info!(request_id, joint, rule = unplanned.reason.rule.id, "left unplanned: {}", unplanned.reason);
    }
}

/// The one log line per plan request.
#[derive(Default)]
struct PlanLog<'a> {
    request_id: u64,
    joint: std::borrow::Cow<'static, str>,
    frame: Option<Arc<StoredFrame>>,
    frame_wait: Duration,
    times: JobTimes,
    plan: Option<&'a Plan>,
    failure: Option<(ErrorCode, String)>,
    /// The rule that refused the plan, when one did.
    rule: Option<&'static Rule>,
    latency: Duration,
}

impl PlanLog<'_> {
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
                joint = &*self.joint,
                frame_id,
                camera,
                frame_age_ms,
                outcome,
                rule = self.rule.map(|r| r.id),
                times = fields,
                latency_ms = ms(self.latency),
                reason = line,
                "plan"
            );
        } else {
            info!(
                request_id = self.request_id,
                joint = &*self.joint,
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
