//! The cell daemon: a camera link that receives frames and sends capture
//! triggers, a controller link that answers plan requests, a text link
//! robot programs speak directly ([`text_link`]), a frame history and a
//! bounded plan queue on a dedicated rayon pool.
//!
//! [`run`] takes bound listeners and a shutdown future, so tests serve on
//! ephemeral loopback ports. Each accepted connection gets its own task
//! and tracing span carrying the peer address; a peer outside the link's
//! allowlist is logged and disconnected. A connection holds one of the
//! link's slots (a semaphore) only from its valid Hello on; a Hello when
//! every slot is taken is answered with a busy error. Before its Hello it
//! holds a pending place, for at most the hello timeout and bounded per
//! address and per link (the rule is at `Pending`), so silent
//! connections cannot keep a real peer out. Bad input ends at most its own
//! connection, never the server; [`metrics`] counts what happened.

pub mod board;
pub mod camera_link;
pub mod connection;
pub mod controller_link;
pub mod debug_sets;
pub mod frames;
pub mod http;
pub mod idle;
pub mod jobs;
pub mod local;
pub mod metrics;
mod planning;
pub mod recorder;
pub mod serve_order;
pub mod shutdown;
pub mod text_link;

use std::collections::{HashMap, VecDeque};
use std::future::Future;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore, oneshot};
use tracing::{Instrument, error, info, warn};
use weldseam_proto::message::{Role, Status};

use crate::config::Config;
use crate::pipeline::Planner;
use connection::{Admission, Connection, MessageDeadline};
use frames::{FrameLimits, FrameStore};
use idle::IdleTrim;
use jobs::{Jobs, PoolError};
use metrics::{Metrics, Refusal};
use shutdown::{Shutdown, ShutdownController};

/// Everything the handlers share.
#[derive(Debug)]
pub struct ServerState {
    pub config: Config,
    pub frames: Arc<FrameStore>,
    pub jobs: Jobs,
    /// Hands freed memory back once the cell is idle.
    pub idle: Arc<IdleTrim>,
    pub metrics: Metrics,
    /// The last plans' pictures and figures, for `[debug]` and the page.
    pub debug: debug_sets::DebugSets,
    /// What the operator page shows.
    pub board: Arc<board::Board>,
    /// The plan records' writer (`[records]`).
    pub recorder: recorder::Recorder,
    started: Instant,
    frames_received: AtomicU64,
    plans_done: AtomicU64,
}

impl ServerState {
    /// Builds the state, starting the pipeline's pool.
    pub fn new(config: Config) -> Result<Arc<Self>, PoolError> {
        Self::with_config_text(config, None)
    }

    /// [`ServerState::new`] for a daemon started from a config file whose
    /// text is `config_text`: plan records keep it, so a replay plans with it.
    pub fn with_config_text(config: Config, config_text: Option<String>) -> Result<Arc<Self>, PoolError> {
        let s = &config.server;
        let board = board::Board::new(s.page_plans);
        let jobs = Jobs::new(Planner::new(config.clone()), s.plan_queue_depth, s.pipeline_threads)?;
        Ok(Arc::new(ServerState {
            frames: FrameStore::new(FrameLimits {
                count: s.frame_history,
                bytes: s.frame_history_bytes,
                tolerance: s.capture_time_tolerance,
            }),
            jobs,
            idle: IdleTrim::new(s.idle_trim),
            metrics: Metrics::new(),
            debug: debug_sets::DebugSets::open(&config.debug, &board),
            recorder: recorder::Recorder::open(&config, config_text, &board),
            board,
            started: Instant::now(),
            frames_received: AtomicU64::new(0),
            plans_done: AtomicU64::new(0),
            config,
        }))
    }

    /// The figures a ping answers with.
    pub fn status(&self) -> Status {
        let cameras = self.frames.cameras() as u32;
        let latest = self.frames.latest();
        Status {
            uptime_ms: self.started.elapsed().as_millis() as u64,
            frames_received: self.frames_received.load(Ordering::Relaxed),
            plans_done: self.plans_done.load(Ordering::Relaxed),
            queue_length: self.jobs.len() as u32,
            camera_connected: cameras > 0,
            cameras,
            latest_frame_id: latest.map(|l| l.0),
            latest_capture_time_us: latest.map(|l| l.1),
        }
    }

    pub(crate) fn count_frame(&self) {
        self.metrics.frame_received();
        self.frames_received.fetch_add(1, Ordering::Relaxed);
    }

    /// The record store's state, for the page; None when records are off.
    pub fn records_state(&self) -> Option<crate::records::Held> {
        self.recorder.held()
    }

    pub(crate) fn count_plan(&self) {
        self.plans_done.fetch_add(1, Ordering::Relaxed);
    }
}

/// Why the server stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// A listener failed in a way that retrying cannot fix.
    #[error("the {link} listener failed: {source}")]
    Accept {
        link: &'static str,
        #[source]
        source: std::io::Error,
    },
}

/// How the server ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stopped {
    /// Every handler finished within the grace period.
    Clean,
    /// The grace period ran out with work still in flight.
    GraceExpired,
}

/// The bound listeners of the daemon's links.
#[derive(Debug)]
pub struct Listeners {
    pub camera: TcpListener,
    pub controller: TcpListener,
    /// The text controller link; None leaves it off.
    pub text: Option<TcpListener>,
}

/// Serves every link until `shutdown` completes, then stops accepting,
/// tells every handler to stop, and waits for them (plans in flight
/// finish) for at most the configured grace period.
pub async fn run(listeners: Listeners, shutdown: impl Future, state: Arc<ServerState>) -> Result<Stopped, ServerError> {
    let control = ShutdownController::new();
    let cameras = Acceptor::new(listeners.camera, Role::Camera, &state);
    let controllers = Acceptor::new(listeners.controller, Role::Controller, &state);
    let texts = async {
        match listeners.text {
            Some(listener) => text_link::accept_loop(listener, Arc::clone(&state), &control).await,
            None => std::future::pending().await,
        }
    };
    let outcome = tokio::select! {
        r = cameras.run(&control) => r,
        r = controllers.run(&control) => r,
        r = texts => r,
        _ = shutdown => {
            info!("shutdown requested: no new connections; waiting for plans in flight");
            Ok(())
        }
    };
    if let Err(e) = &outcome {
        error!("{e}; stopping");
    }
    let grace = state.config.server.shutdown_grace;
    let stopped = if control.shutdown(grace).await {
        info!("every connection closed; stopped");
        Stopped::Clean
    } else {
        warn!(grace_ms = grace.as_millis() as u64, "work was still in flight when the shutdown grace ran out");
        Stopped::GraceExpired
    };
    // The last plans' records are written after their replies: let them land.
    if !state.recorder.finish(grace).await {
        warn!(grace_ms = grace.as_millis() as u64, "plan records were still being written when the grace ran out");
    }
    outcome.map(|()| stopped)
}

struct Acceptor {
    listener: TcpListener,
    role: Role,
    allow: Vec<IpAddr>,
    /// Connections past their Hello; taken when a valid Hello arrives.
    slots: Arc<Semaphore>,
    pending: Arc<Pending>,
    state: Arc<ServerState>,
    /// Keeps a flood of refusals from flooding the log as well.
    refusal_log: Arc<Throttle>,
}

fn allowed(allow: &[IpAddr], peer: &SocketAddr) -> bool {
    let ip = peer.ip().to_canonical();
    allow.is_empty() || allow.iter().any(|a| a.to_canonical() == ip)
}

impl Acceptor {
    fn new(listener: TcpListener, role: Role, state: &Arc<ServerState>) -> Self {
        let s = &state.config.server;
        let (allow, slots) = match role {
            Role::Camera => (s.camera_allow.clone(), s.max_camera_connections),
            Role::Controller => (s.controller_allow.clone(), s.max_controller_connections),
        };
        Acceptor {
            listener,
            role,
            allow,
            slots: Arc::new(Semaphore::new(slots)),
            pending: Arc::new(Pending::new(s.max_pending_connections, s.max_pending_per_address)),
            state: Arc::clone(state),
            refusal_log: Arc::default(),
        }
    }

    /// Accepts connections until the listener fails for good. A connection
    /// holds no slot until its Hello: before, it holds a pending place,
    /// bounded per address and per link, for at most the hello timeout.
    async fn run(&self, control: &ShutdownController) -> Result<(), ServerError> {
        let link = self.role.name();
        loop {
            let (stream, peer) = self.accept().await?;
            if !allowed(&self.allow, &peer) {
                self.refuse(&peer, Refusal::NotAllowed, || {
                    format!("refused a connection from a peer not in server.{link}_allow")
                });
                drop(stream);
                continue;
            }
            let (ticket, evicted) = self.pending.register(peer);
            for victim in &evicted {
                self.refuse(victim, Refusal::Evicted, || {
                    format!(
                        "closed a connection from {victim} that had not said Hello, to make room (at most {} per \
                         address, server.max_pending_per_address; {} per link, server.max_pending_connections)",
                        self.pending.max_per_address, self.pending.max_total
                    )
                });
            }
            let span = tracing::info_span!("conn", link, %peer);
            let task = Connected {
                role: self.role,
                peer,
                ticket,
                pending: Arc::clone(&self.pending),
                slots: Arc::clone(&self.slots),
                state: Arc::clone(&self.state),
                refusal_log: Arc::clone(&self.refusal_log),
                shutdown: control.handle(),
            };
            tokio::spawn(task.serve(stream).instrument(span));
        }
    }

    /// Counts a refused connection and logs it, at most once a second per
    /// link with the number left out since.
    fn refuse(&self, peer: &SocketAddr, why: Refusal, message: impl FnOnce() -> String) {
        refuse(&self.state, &self.refusal_log, self.role, peer, why, message);
    }

    async fn accept(&self) -> Result<(TcpStream, SocketAddr), ServerError> {
        accept_with_backoff(&self.listener, self.role.name()).await
    }
}

/// Accepts the next connection on `link`, retrying transient errors (such
/// as running out of file descriptors) with a growing pause.
async fn accept_with_backoff(
    listener: &TcpListener,
    link: &'static str,
) -> Result<(TcpStream, SocketAddr), ServerError> {
    let mut backoff = Duration::from_millis(50);
    loop {
        match listener.accept().await {
            Ok(ok) => return Ok(ok),
            Err(e) if backoff > Duration::from_secs(5) => return Err(ServerError::Accept { link, source: e }),
            Err(e) => {
                warn!(link, "accept failed: {e}; retrying in {} ms", backoff.as_millis());
                tokio::time::sleep(backoff).await;
                backoff *= 2;
            }
        }
    }
}

/// Counts a connection closed unserved and logs it, at most one line a
/// second per link (with the number held back since), so a flood of
/// connections does not become a flood of log lines.
fn refuse(
    state: &ServerState,
    log: &Throttle,
    role: Role,
    peer: &SocketAddr,
    why: Refusal,
    message: impl FnOnce() -> String,
) {
    state.metrics.peer_refused(role, why);
    if let Some(unlogged) = log.admit() {
        warn!(%peer, link = role.name(), reason = why.name(), unlogged, "{}", message());
    }
}

/// Lets one log line through per second and counts the ones held back.
#[derive(Debug, Default)]
struct Throttle {
    last: Mutex<Option<Instant>>,
    held_back: AtomicU64,
}

impl Throttle {
    /// Some(lines held back since the last one) when a line may be logged.
    fn admit(&self) -> Option<u64> {
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let now = Instant::now();
        if last.is_some_and(|t| now.duration_since(t) < Duration::from_secs(1)) {
            self.held_back.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        *last = Some(now);
        Some(self.held_back.swap(0, Ordering::Relaxed))
    }
}

/// The connections of one link that have not yet said Hello.
///
/// The rule: each address has at most `max_per_address` of them and the
/// link at most `max_total`. A new connection always gets a place; when
/// its address is at its cap, that address's oldest pending connection is
/// closed, and when the link is full, the oldest of the address holding
/// the most is. A flood from one address therefore only ever closes its
/// own connections (or those of an address flooding as hard), a peer that
/// says Hello at once is never held up by it, and a connection past its
/// Hello is never closed to make room.
#[derive(Debug)]
struct Pending {
    max_total: usize,
    max_per_address: usize,
    places: Mutex<Places>,
}

#[derive(Debug, Default)]
struct Places {
    next_ticket: u64,
    total: usize,
    /// Oldest first; the sender closes the connection when sent to.
    by_address: HashMap<IpAddr, VecDeque<(u64, SocketAddr, oneshot::Sender<()>)>>,
}

/// A pending connection's place; its receiver fires when it is evicted.
struct Ticket {
    ip: IpAddr,
    id: u64,
    evicted: oneshot::Receiver<()>,
}

impl Pending {
    fn new(max_total: usize, max_per_address: usize) -> Self {
        Pending { max_total, max_per_address, places: Mutex::new(Places::default()) }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Places> {
        self.places.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Gives a new connection a place and closes the pending connections
    /// it displaces; returns their addresses.
    fn register(&self, peer: SocketAddr) -> (Ticket, Vec<SocketAddr>) {
        let ip = peer.ip().to_canonical();
        let mut places = self.lock();
        let own = places.by_address.get(&ip).map_or(0, VecDeque::len);
        let victim = if own >= self.max_per_address {
            Some(ip)
        } else if places.total >= self.max_total {
            places.by_address.iter().max_by_key(|(_, queue)| queue.len()).map(|(address, _)| *address)
        } else {
            None
        };
        let mut evicted = Vec::new();
        if let Some(victim) = victim
            && let Some(queue) = places.by_address.get_mut(&victim)
            && let Some((_, address, close)) = queue.pop_front()
        {
            if queue.is_empty() {
                places.by_address.remove(&victim);
            }
            places.total -= 1;
            // The receiver may be gone already if its task just ended.
            let _ = close.send(());
            evicted.push(address);
        }
        let id = places.next_ticket;
        places.next_ticket += 1;
        let (close, closed) = oneshot::channel();
        places.by_address.entry(ip).or_default().push_back((id, peer, close));
        places.total += 1;
        (Ticket { ip, id, evicted: closed }, evicted)
    }

    /// Removes a connection's place; false when it had none left (evicted).
    fn remove(&self, ip: IpAddr, id: u64) -> bool {
        let mut places = self.lock();
        let Some(queue) = places.by_address.get_mut(&ip) else { return false };
        let Some(at) = queue.iter().position(|(t, _, _)| *t == id) else { return false };
        queue.remove(at);
        if queue.is_empty() {
            places.by_address.remove(&ip);
        }
        places.total -= 1;
        true
    }
}

/// One accepted connection's task: the pending phase under the hello
/// deadline and eviction, then the link's handler.
struct Connected {
    role: Role,
    peer: SocketAddr,
    ticket: Ticket,
    pending: Arc<Pending>,
    slots: Arc<Semaphore>,
    state: Arc<ServerState>,
    refusal_log: Arc<Throttle>,
    shutdown: Shutdown,
}

/// What a connection holds once admitted: its slot, counted in the metrics.
struct Admitted {
    _slot: OwnedSemaphorePermit,
    _counted: metrics::GaugeGuard,
}

impl Connected {
    async fn serve(self, stream: TcpStream) {
        let Connected { role, peer, ticket, pending, slots, state, refusal_log, shutdown } = self;
        let Ticket { ip, id, mut evicted } = ticket;
        let s = &state.config.server;
        let hello_deadline = tokio::time::sleep(s.hello_timeout);
        let hello_timeout = s.hello_timeout;
        let pending_counted = state.metrics.pending_opened(role);
        // Filled by the admission when the Hello is valid; lives as long
        // as this task.
        let admitted: Arc<OnceLock<Admitted>> = Arc::new(OnceLock::new());
        let admission = {
            let (pending, admitted, state) = (Arc::clone(&pending), Arc::clone(&admitted), Arc::clone(&state));
            Admission::new(move || {
                let Ok(slot) = slots.try_acquire_owned() else {
                    state.metrics.peer_refused(role, Refusal::LinkFull);
                    let s = &state.config.server;
                    let (key, max) = match role {
                        Role::Camera => ("server.max_camera_connections", s.max_camera_connections),
                        Role::Controller => ("server.max_controller_connections", s.max_controller_connections),
                    };
                    return Err(format!("all {max} {} connections are in use ({key}); try again later", role.name()));
                };
                if !pending.remove(ip, id) {
                    return Err("the connection was closed to make room for newer ones".into());
                }
                let _ = admitted.set(Admitted { _slot: slot, _counted: state.metrics.connection_opened(role) });
                Ok(())
            })
        };
        let conn = make_connection(role, stream, peer, &state).with_admission(admission);
        let served = handle(role, conn, Arc::clone(&state), shutdown);
        tokio::pin!(served, hello_deadline);
        // The admission runs inside `served`, on this task, so `admitted`
        // cannot change while a branch below is deciding.
        // The handshake bounds its own wait for the Hello by the same
        // time, so both can be due at once: polled first, the deadline
        // is the one that refuses, logs and counts the late peer.
        let admitted_in_time = tokio::select! {
            biased;
            () = &mut hello_deadline => {
                let late = admitted.get().is_none();
                if late && pending.remove(ip, id) {
                    let ms = hello_timeout.as_millis();
                    refuse(&state, &refusal_log, role, &peer, Refusal::HelloTimeout, || {
                        format!("closed a connection with no Hello within {ms} ms (server.hello_timeout_ms)")
                    });
                }
                !late
            }
            // An error means the place was given up by the admission.
            closed = &mut evicted => {
                // The acceptor has counted and logged the eviction.
                closed.is_err()
            }
            () = &mut served => false,
        };
        drop(pending_counted);
        if admitted_in_time {
            served.await;
        } else {
            // Ended, evicted or late: the place goes, the socket closes.
            pending.remove(ip, id);
        }
    }
}

/// The connection of `role` with the link's limits.
fn make_connection(role: Role, stream: TcpStream, peer: SocketAddr, state: &ServerState) -> Connection {
    let s = &state.config.server;
    let max_frame_bytes = match role {
        Role::Camera => s.max_frame_bytes,
        Role::Controller => weldseam_proto::MAX_CONTROL_MESSAGE_BYTES as u64,
    };
    let deadline = MessageDeadline { base: s.message_timeout, min_bytes_per_s: s.min_transfer_bytes_per_s };
    Connection::new(stream, peer, s.stall_timeout, max_frame_bytes)
        .with_deadline(deadline)
        .with_byte_counter(state.metrics.bytes_counter(role))
}

async fn handle(role: Role, conn: Connection, state: Arc<ServerState>, shutdown: Shutdown) {
    match role {
        Role::Camera => camera_link::serve(conn, state, shutdown).await,
        Role::Controller => controller_link::serve(conn, state, shutdown).await,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peer(ip: [u8; 4], port: u16) -> SocketAddr {
        SocketAddr::from((ip, port))
    }

    #[test]
    fn a_flooding_address_displaces_only_its_own_pending_connections() {
        let pending = Pending::new(4, 2);
        let (_a1, none) = pending.register(peer([10, 0, 0, 1], 1));
        assert!(none.is_empty());
        let (_b1, _) = pending.register(peer([10, 0, 0, 2], 1));
        let (_b2, _) = pending.register(peer([10, 0, 0, 2], 2));
        // B is at its cap of 2: its oldest goes.
        let (_b3, evicted) = pending.register(peer([10, 0, 0, 2], 3));
        assert_eq!(evicted, vec![peer([10, 0, 0, 2], 1)]);
        let (_c1, none) = pending.register(peer([10, 0, 0, 3], 1));
        assert!(none.is_empty());
        // The link is full (4): the address holding most (B) gives way.
        let (_d1, evicted) = pending.register(peer([10, 0, 0, 4], 1));
        assert_eq!(evicted, vec![peer([10, 0, 0, 2], 2)]);
    }

    #[test]
    fn an_evicted_connection_is_told_and_an_admitted_one_is_not() {
        let pending = Pending::new(8, 1);
        let (mut first, _) = pending.register(peer([10, 0, 0, 1], 1));
        let (mut second, _) = pending.register(peer([10, 0, 0, 1], 2));
        assert_eq!(first.evicted.try_recv(), Ok(()));
        // Admission gives the place up: the receiver sees the sender go.
        assert!(pending.remove(second.ip, second.id));
        assert!(matches!(second.evicted.try_recv(), Err(oneshot::error::TryRecvError::Closed)));
        assert!(!pending.remove(first.ip, first.id), "an evicted connection has no place left");
    }
}
