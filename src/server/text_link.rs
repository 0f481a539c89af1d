//! The text controller link: robot programs (UR, ABB, KUKA, FANUC) talk to
//! the daemon in lines of ASCII they read with their own primitives (the
//! lines are [`weldseam_proto::text`]'s; ROBOTS.md documents sessions).
//!
//! A session takes one of the link's slots when it is accepted (there is
//! no hello to wait for); a connection when all are taken is told busy and
//! closed. Each request line gets exactly one reply line. A line may be at
//! most `text_link.max_line_bytes` long and must end within
//! `text_link.line_timeout_ms` of its first byte: a longer or unfinished
//! one, like any malformed line, gets an error line and the session goes
//! on. A session without a whole line for `text_link.idle_timeout_ms` is
//! closed. Plan and trigger lines go the binary controller link's plan
//! path ([`super::planning`]), one request at a time per session; a robot
//! that disconnects while its plan runs cancels it. The session keeps its
//! last plan's per-seam check values for `CHECK` until its next plan line.
//! An error line leads with its cause; where it arose (frame, stage) comes
//! after it, where a pendant's 80 characters may cut it off.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bytes::BytesMut;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio_util::codec::{AnyDelimiterCodec, Decoder};
use tracing::{Instrument, info, warn};
use weldseam_proto::ErrorCode;
use weldseam_proto::text::{
    self, CHECK_NUMBERS, Dialect, LineError, OK_NUMBERS, PlanLine, Reply, Request, TEXT_PROTOCOL_VERSION,
    parse_request, seam_checks,
};

use super::frames::Wanted;
use super::planning::{Ask, Planned, Refusal, accept, fulfil, refused};
use super::shutdown::{Shutdown, ShutdownController};
use super::{ServerError, ServerState, Throttle, accept_with_backoff, allowed};
use crate::config::TextLinkConfig;
use crate::convert::from_proto::{TextRequestError, text_plan_request};
use crate::convert::to_text::waypoint_lines;

/// The link's name in logs and metrics.
const LINK: &str = "text";

/// Accepts robot sessions until the listener fails for good.
pub(crate) async fn accept_loop(
    listener: TcpListener,
    state: Arc<ServerState>,
    control: &ShutdownController,
) -> Result<(), ServerError> {
    let config = &state.config.text_link;
    let slots = Arc::new(Semaphore::new(config.max_connections));
    // A flood of refused connections must not flood the log as well.
    let refusals = Throttle::default();
    loop {
        let (stream, peer) = accept_with_backoff(&listener, LINK).await?;
        if !allowed(&config.allow, &peer) {
            if let Some(unlogged) = refusals.admit() {
                warn!(%peer, link = LINK, unlogged, "refused a connection from a peer not in text_link.allow");
            }
            continue;
        }
        let span = tracing::info_span!("conn", link = LINK, %peer);
        let state = Arc::clone(&state);
        let shutdown = control.handle();
        match Arc::clone(&slots).try_acquire_owned() {
            Ok(slot) => {
                tokio::spawn(serve(stream, state, shutdown, slot).instrument(span));
            }
            Err(_) => {
                if let Some(unlogged) = refusals.admit() {
                    let _entered = span.enter();
                    warn!(
                        unlogged,
                        "all {} text link sessions are in use (text_link.max_connections)", config.max_connections
                    );
                }
                tokio::spawn(refuse_busy(stream, state).instrument(span));
            }
        }
    }
}

/// Tells a connection beyond `text_link.max_connections` to come back
/// later, then closes it.
async fn refuse_busy(mut stream: TcpStream, state: Arc<ServerState>) {
    let config = &state.config.text_link;
    let reason = format!(
        "all {} text link sessions are in use (text_link.max_connections); try again later",
        config.max_connections
    );
    let reply = Reply::Error { code: ErrorCode::Busy.code(), reason, numbers: OK_NUMBERS };
    if let Ok(line) = reply.format(config.dialect.unwrap_or(NEUTRAL)) {
        let _ = tokio::time::timeout(config.line_timeout, stream.write_all(line.as_bytes())).await;
    }
}

/// How lines are written before the session's dialect is known: `-code,reason`
/// within 80 characters, CR LF, which every text dialect can read.
const NEUTRAL: Dialect = Dialect::Abb;

/// What the robot sent next.
#[derive(Debug, PartialEq)]
enum LineEvent {
    Line(String),
    /// Longer than `text_link.max_line_bytes`; dropped up to its terminator.
    TooLong,
    /// Begun but not ended within `text_link.line_timeout_ms`; dropped.
    Unfinished,
    /// No whole line for `text_link.idle_timeout_ms`.
    Idle,
    Closed,
}

/// Splits the robot's bytes into lines at CR or LF, bounded in length and
/// in time.
struct LineReader<R> {
    stream: R,
    codec: AnyDelimiterCodec,
    buffer: BytesMut,
    max_line: usize,
    line_timeout: Duration,
    idle_timeout: Duration,
    /// When the line being read began (or, after one too long, when its
    /// dropping began).
    begun: Option<Instant>,
    last_line: Instant,
}

impl<R: AsyncRead + Unpin> LineReader<R> {
    fn new(stream: R, config: &TextLinkConfig) -> Self {
        LineReader {
            stream,
            codec: Self::codec(config.max_line_bytes),
            buffer: BytesMut::with_capacity(config.max_line_bytes + 64),
            max_line: config.max_line_bytes,
            line_timeout: config.line_timeout,
            idle_timeout: config.idle_timeout,
            begun: None,
            last_line: Instant::now(),
        }
    }

    /// The limit counts the terminator, the codec's chunk does not.
    fn codec(max_line_bytes: usize) -> AnyDelimiterCodec {
        AnyDelimiterCodec::new_with_max_length(b"\r\n".to_vec(), Vec::new(), max_line_bytes.saturating_sub(1))
    }

    async fn next(&mut self) -> std::io::Result<LineEvent> {
        loop {
            match self.codec.decode(&mut self.buffer) {
                Ok(Some(line)) => {
                    self.begun = None;
                    self.last_line = Instant::now();
                    return Ok(LineEvent::Line(String::from_utf8_lossy(&line).into_owned()));
                }
                Err(_) => {
                    // The codec drops the rest up to the terminator, which
                    // must come within the line time like any line's.
                    self.begun = Some(Instant::now());
                    return Ok(LineEvent::TooLong);
                }
                Ok(None) => {}
            }
            if !self.buffer.is_empty() && self.begun.is_none() {
                self.begun = Some(Instant::now());
            }
            let deadline = match self.begun {
                Some(begun) => Some(begun + self.line_timeout),
                None if self.idle_timeout.is_zero() => None,
                None => Some(self.last_line + self.idle_timeout),
            };
            let read = self.stream.read_buf(&mut self.buffer);
            let read = match deadline {
                Some(at) => match tokio::time::timeout_at(at.into(), read).await {
                    Ok(read) => read,
                    Err(_) if self.begun.is_some() => {
                        // Drop the unfinished line and start afresh.
                        self.buffer.clear();
                        self.codec = Self::codec(self.max_line);
                        self.begun = None;
                        return Ok(LineEvent::Unfinished);
                    }
                    Err(_) => return Ok(LineEvent::Idle),
                },
                None => read.await,
            };
            if read? == 0 {
                return Ok(LineEvent::Closed);
            }
        }
    }

    /// Completes when the robot closes the connection (or it fails), while
    /// a plan runs. Lines sent meanwhile are kept for later, at most one
    /// line's worth; beyond that the robot's bytes wait in the socket.
    async fn closed(&mut self) {
        loop {
            if self.buffer.len() >= self.max_line {
                std::future::pending::<()>().await;
            }
            match self.stream.read_buf(&mut self.buffer).await {
                Ok(0) | Err(_) => return,
                Ok(_) => {}
            }
        }
    }
}

/// One robot session's state.
struct Session {
    dialect: Option<Dialect>,
    /// Whether the robot's `HELLO` asked for a process line after each
    /// weld waypoint line.
    process_lines: bool,
    /// The waypoint lines of the last plan not yet pulled, formatted.
    pending: VecDeque<String>,
    /// The last plan's `CHECK` replies, one per seam; None before a plan,
    /// after a failed one and from a plan line on until its answer.
    checks: Option<Vec<Reply>>,
    /// The last error line's whole reason, for `WHY`.
    last_error: Option<String>,
    /// One request at a time: the robot waits for each reply.
    places: Arc<Semaphore>,
    requests: u64,
}

/// What a request line leads to.
enum Outcome {
    Reply(Reply),
    /// A waypoint line formatted when its plan came.
    Line(String),
    /// The robot left while its plan ran.
    Gone,
}

/// An error line for a request, in the shape of the reply it replaces.
fn error(code: ErrorCode, reason: impl Into<String>, numbers: usize) -> Reply {
    Reply::Error { code: code.code(), reason: reason.into(), numbers }
}

/// Serves one robot session until the robot leaves, the session idles out
/// or the daemon stops (a plan in flight is answered first), holding its
/// slot of the link throughout.
async fn serve(stream: TcpStream, state: Arc<ServerState>, mut shutdown: Shutdown, slot: OwnedSemaphorePermit) {
    let _slot = slot;
    let _counted = state.metrics.link_connection_opened(LINK);
    let _on_board = stream.peer_addr().ok().map(|peer| state.board.peer_joined(LINK, peer, "robot"));
    let config = &state.config.text_link;
    info!("robot connected");
    let (read, mut write) = stream.into_split();
    let mut lines = LineReader::new(read, config);
    let mut session = Session {
        dialect: config.dialect,
        process_lines: false,
        pending: VecDeque::new(),
        checks: None,
        last_error: None,
        places: Arc::new(Semaphore::new(1)),
        requests: 0,
    };
    loop {
        let event = tokio::select! {
            e = lines.next() => e,
            _ = shutdown.recv() => break,
        };
        let reply = match event {
            Ok(LineEvent::Line(line)) if line.trim().is_empty() => continue,
            Ok(LineEvent::Line(line)) => match session.handle(&line, &state, &shutdown, &mut lines).await {
                Outcome::Reply(reply) => reply,
                Outcome::Line(line) => {
                    if let Err(e) = send(&mut write, &line, config.line_timeout).await {
                        warn!("cannot reply: {e}");
                        break;
                    }
                    continue;
                }
                Outcome::Gone => {
                    info!("robot disconnected while its plan ran; the request is cancelled");
                    break;
                }
            },
            Ok(LineEvent::TooLong) => error(
                ErrorCode::TooLarge,
                format!("line over {} bytes (text_link.max_line_bytes); dropped", config.max_line_bytes),
                OK_NUMBERS,
            ),
            Ok(LineEvent::Unfinished) => error(
                ErrorCode::Malformed,
                format!("no CR or LF within {} ms (text_link.line_timeout_ms)", config.line_timeout.as_millis()),
                OK_NUMBERS,
            ),
            Ok(LineEvent::Idle) => {
                info!(
                    idle_ms = config.idle_timeout.as_millis() as u64,
                    "closed an idle session (text_link.idle_timeout_ms)"
                );
                break;
            }
            Ok(LineEvent::Closed) => {
                info!("robot disconnected");
                break;
            }
            Err(e) => {
                warn!("connection error: {e}");
                break;
            }
        };
        if let Reply::Error { code, reason, .. } = &reply {
            warn!(code, "error line: {reason}");
            session.last_error = Some(reason.clone());
        }
        if let Err(e) = send(&mut write, &session.format(&reply), config.line_timeout).await {
            warn!("cannot reply: {e}");
            break;
        }
    }
    let _ = write.shutdown().await;
}

/// Writes one line, within the line time: a robot that reads nothing
/// cannot hold the session.
async fn send<W: AsyncWrite + Unpin>(write: &mut W, line: &str, within: Duration) -> std::io::Result<()> {
    match tokio::time::timeout(within, write.write_all(line.as_bytes())).await {
        Ok(written) => written,
        Err(_) => Err(std::io::Error::new(std::io::ErrorKind::TimedOut, "the robot read nothing for the line time")),
    }
}

impl Session {
    /// The line for `reply` in the session's dialect; a reply the dialect
    /// cannot hold becomes an error line.
    fn format(&self, reply: &Reply) -> String {
        let dialect = self.dialect.unwrap_or(NEUTRAL);
        reply.format(dialect).unwrap_or_else(|e| {
            let fallback = error(ErrorCode::Internal, e.to_string(), OK_NUMBERS);
            fallback.format(dialect).unwrap_or_else(|_| "-48\r\n".into())
        })
    }

    /// How many numbers the reply to `line` has in the session's dialect.
    fn reply_numbers(&self, line: &str) -> usize {
        let command = line.trim().split(',').next().unwrap_or("").trim().to_ascii_uppercase();
        match (command.as_str(), self.dialect) {
            ("NEXT", Some(dialect)) => text::waypoint_numbers(dialect),
            ("CHECK", _) => CHECK_NUMBERS,
            _ => OK_NUMBERS,
        }
    }

    async fn handle<R: AsyncRead + Unpin>(
        &mut self,
        line: &str,
        state: &ServerState,
        shutdown: &Shutdown,
        lines: &mut LineReader<R>,
    ) -> Outcome {
        let numbers = self.reply_numbers(line);
        let request = match parse_request(line, self.dialect) {
            Ok(request) => request,
            Err(e) => return Outcome::Reply(error(e.code(), e.to_string(), numbers)),
        };
        let busy_pulling = |pending: usize| {
            error(
                ErrorCode::UnexpectedMessage,
                format!("{pending} waypoint lines are left to pull: NEXT them or DROP them first"),
                numbers,
            )
        };
        Outcome::Reply(match request {
            Request::Hello { .. } | Request::Plan(_) | Request::Trigger(_) if !self.pending.is_empty() => {
                busy_pulling(self.pending.len())
            }
            Request::Hello { dialect, process } => {
                self.dialect = Some(dialect);
                self.process_lines = process;
                // Check values are written in the dialect of their plan.
                self.checks = None;
                info!(dialect = dialect.name(), process, "robot named its dialect");
                Reply::Ok(TEXT_PROTOCOL_VERSION.into(), process.into())
            }
            Request::Plan(plan) => return self.plan(plan, Wanted::NextFrame, state, shutdown, lines).await,
            Request::Trigger(plan) => return self.plan(plan, Wanted::Trigger, state, shutdown, lines).await,
            Request::Next => match self.pending.pop_front() {
                Some(line) => return Outcome::Line(line),
                None => error(ErrorCode::UnexpectedMessage, "nothing to pull: send PLAN or TRIGGER first", numbers),
            },
            Request::Check(seam) => match &self.checks {
                None => error(
                    ErrorCode::UnexpectedMessage,
                    "no plan to check: CHECK follows a plan's ok line until the next plan line",
                    numbers,
                ),
                Some(checks) => match checks.get((seam as usize).wrapping_sub(1)) {
                    Some(check) => check.clone(),
                    None => error(
                        ErrorCode::BadRequest,
                        format!("seam {seam} out of range: the last plan has seams 1 to {}", checks.len()),
                        numbers,
                    ),
                },
            },
            Request::Drop => {
                let dropped = self.pending.len() as u64;
                self.pending.clear();
                Reply::Ok(dropped, 0)
            }
            Request::Why => Reply::Text(self.last_error.clone().unwrap_or_else(|| "no error".into())),
            Request::Ping => {
                let status = state.status();
                Reply::Ok(status.cameras.into(), status.queue_length.into())
            }
        })
    }

    /// A plan or trigger line: the shared plan path, then the waypoint
    /// lines formatted at once, so a plan any line of which the dialect
    /// cannot hold is an error line rather than a broken pull.
    async fn plan<R: AsyncRead + Unpin>(
        &mut self,
        line: PlanLine,
        wanted: Wanted,
        state: &ServerState,
        shutdown: &Shutdown,
        lines: &mut LineReader<R>,
    ) -> Outcome {
        let Some(dialect) = self.dialect else {
            return Outcome::Reply(error(LineError::NoDialect.code(), LineError::NoDialect.to_string(), OK_NUMBERS));
        };
        let arrived = Instant::now();
        self.checks = None;
        self.requests += 1;
        let request_id = self.requests;
        let request = match text_plan_request(&line, dialect, state.config.euler) {
            Ok(request) => request,
            Err(e) => {
                let code = match e {
                    TextRequestError::Joint(_) => ErrorCode::UnknownJoint,
                    TextRequestError::Pose(_) => ErrorCode::BadRequest,
                };
                let refusal = refused(request_id, Refusal::new(code, e.to_string()), state);
                return Outcome::Reply(error(refusal.code, refusal.text, OK_NUMBERS));
            }
        };
        let ask = Ask { request_id, request, wanted, timeout_ms: 0, camera: None };
        let accepted = match accept(ask, arrived, state, &self.places) {
            Ok(accepted) => accepted,
            Err(refusal) => return Outcome::Reply(error(refusal.code, pendant_refusal(&refusal), OK_NUMBERS)),
        };
        let outcome = tokio::select! {
            outcome = fulfil(accepted, state, shutdown.stop_signal(), "text") => outcome,
            () = lines.closed() => return Outcome::Gone,
        };
        Outcome::Reply(match outcome {
            Ok(Planned { frame_id, plan }) => {
                let offset = state.config.text_link.approach_offset_mm;
                let replies = waypoint_lines(&plan, dialect, offset, self.process_lines);
                let formatted: Result<VecDeque<String>, _> = replies.iter().map(|r| r.format(dialect)).collect();
                match formatted {
                    Ok(formatted) => {
                        let count = formatted.len() as u64;
                        self.pending = formatted;
                        let checks = seam_checks(&replies, dialect);
                        // The ok line counts the seams sent (each piece of
                        // a pass welded is one); WHY names the workpieces
                        // in view that were not planned.
                        let seams = checks.len() as u64;
                        self.checks = Some(checks);
                        if !plan.unplanned.is_empty() {
                            self.last_error = Some(not_planned(&plan));
                        }
                        Reply::Ok(seams, count)
                    }
                    Err(e) => error(
                        ErrorCode::PlanFailed,
                        format!("a waypoint cannot be sent: {e} (frame {frame_id})"),
                        OK_NUMBERS,
                    ),
                }
            }
            Err(failure) => error(failure.code, failure.pendant_reason(), OK_NUMBERS),
        })
    }
}

/// A request's refusal as a pendant shows it: the rule's id first, when a
/// rule of the planner refused it.
fn pendant_refusal(refusal: &Refusal) -> String {
    match refusal.rule {
        Some(rule) => format!("{}: {}", rule.id, refusal.text),
        None => refusal.text.clone(),
    }
}

/// What `WHY` answers after a plan that left joints in view unplanned:
/// how many, and each one's joint, place (camera frame), error code and
/// rule.
fn not_planned(plan: &crate::pipeline::Plan) -> String {
    let each: Vec<String> = plan
        .unplanned
        .iter()
        .map(|u| {
            let joint = u.joint.map_or("a joint".to_string(), |j| j.name().to_string());
            let place = u.near_camera.map_or(String::new(), |p| format!(" at ({:.0} {:.0} {:.0}) mm", p.x, p.y, p.z));
            let code = u16::from(crate::convert::to_proto::plan_error_code(&u.reason));
            // The rule before the place: the 80 characters may end early.
            format!("{joint} (-{code} {}){place}: {}", u.reason.rule.id, u.reason.reason)
        })
        .collect();
    // No commas: a text line's commas would split it for the robot.
    format!("{} seams planned; {} not: {}", plan.seams.len(), plan.unplanned.len(), each.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(max_line_bytes: usize, line_timeout_ms: u64) -> TextLinkConfig {
        TextLinkConfig {
            max_line_bytes,
            line_timeout: Duration::from_millis(line_timeout_ms),
            idle_timeout: Duration::from_secs(60),
            ..TextLinkConfig::default()
        }
    }

    #[tokio::test]
    async fn lines_end_at_cr_or_lf_and_a_long_one_is_dropped_whole() {
        let (mut robot, daemon) = tokio::io::duplex(1024);
        let mut reader = LineReader::new(daemon, &config(16, 60_000));
        robot.write_all(b"PING\r\nNEXT\rWHY\n").await.unwrap();
        robot.write_all(&[b'x'; 40]).await.unwrap();
        robot.write_all(b"tail\nPING\n").await.unwrap();
        drop(robot);
        let mut events = Vec::new();
        loop {
            let event = reader.next().await.unwrap();
            let done = event == LineEvent::Closed;
            events.push(event);
            if done {
                break;
            }
        }
        let line = |s: &str| LineEvent::Line(s.into());
        // CR LF ends a line and leaves an empty one, which the session skips.
        assert_eq!(
            events,
            [line("PING"), line(""), line("NEXT"), line("WHY"), LineEvent::TooLong, line("PING"), LineEvent::Closed]
        );
    }

    #[tokio::test]
    async fn a_line_without_an_end_is_bounded_in_time() {
        let (mut robot, daemon) = tokio::io::duplex(1024);
        let mut reader = LineReader::new(daemon, &config(256, 50));
        robot.write_all(b"PLAN,lap,1,2").await.unwrap();
        assert_eq!(reader.next().await.unwrap(), LineEvent::Unfinished);
        // The part line is gone; the next line reads whole.
        robot.write_all(b"PING\n").await.unwrap();
        assert_eq!(reader.next().await.unwrap(), LineEvent::Line("PING".into()));
    }
}
