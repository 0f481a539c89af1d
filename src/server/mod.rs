//! The cell daemon: a camera link that receives frames and sends capture
//! triggers, a controller link that answers plan requests, a frame history
//! and a bounded plan queue on a dedicated rayon pool.
//!
//! [`run`] takes bound listeners and a shutdown future, so tests serve on
//! ephemeral loopback ports. Each accepted connection gets its own task
//! and tracing span carrying the peer address; a per-link semaphore caps
//! the connections; a peer outside the link's allowlist is logged and
//! disconnected. Bad input ends at most its own connection, never the
//! server.

pub mod camera_link;
pub mod connection;
pub mod controller_link;
pub mod frames;
pub mod idle;
pub mod jobs;
pub mod shutdown;

use std::future::Future;
use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use tokio::net::{TcpListener, TcpStream};
use tokio::sync::Semaphore;
use tracing::{Instrument, error, info, warn};
use weldseam_proto::message::{Role, Status};

use crate::config::Config;
use crate::pipeline::Planner;
use frames::{FrameLimits, FrameStore};
use idle::IdleTrim;
use jobs::{Jobs, PoolError};
use shutdown::{Shutdown, ShutdownController};

/// Everything the handlers share.
#[derive(Debug)]
pub struct ServerState {
    pub config: Config,
    pub frames: Arc<FrameStore>,
    pub jobs: Jobs,
    /// Hands freed memory back once the cell is idle.
    pub idle: Arc<IdleTrim>,
    started: Instant,
    frames_received: AtomicU64,
    plans_done: AtomicU64,
}

impl ServerState {
    /// Builds the state, starting the pipeline's pool.
    pub fn new(config: Config) -> Result<Arc<Self>, PoolError> {
        let s = &config.server;
        let jobs = Jobs::new(Planner::new(config.clone()), s.plan_queue_depth, s.pipeline_threads)?;
        Ok(Arc::new(ServerState {
            frames: FrameStore::new(FrameLimits {
                count: s.frame_history,
                bytes: s.frame_history_bytes,
                tolerance: s.capture_time_tolerance,
            }),
            jobs,
            idle: IdleTrim::new(s.idle_trim),
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
        self.frames_received.fetch_add(1, Ordering::Relaxed);
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

/// Serves both links until `shutdown` completes, then stops accepting,
/// tells every handler to stop, and waits for them (plans in flight
/// finish) for at most the configured grace period.
pub async fn run(
    camera: TcpListener,
    controller: TcpListener,
    shutdown: impl Future,
    state: Arc<ServerState>,
) -> Result<Stopped, ServerError> {
    let control = ShutdownController::new();
    let s = &state.config.server;
    let cameras = Acceptor {
        listener: camera,
        role: Role::Camera,
        allow: s.camera_allow.clone(),
        slots: Arc::new(Semaphore::new(s.max_camera_connections)),
        state: Arc::clone(&state),
    };
    let controllers = Acceptor {
        listener: controller,
        role: Role::Controller,
        allow: s.controller_allow.clone(),
        slots: Arc::new(Semaphore::new(s.max_controller_connections)),
        state: Arc::clone(&state),
    };
    let outcome = tokio::select! {
        r = cameras.run(&control) => r,
        r = controllers.run(&control) => r,
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
    outcome.map(|()| stopped)
}

struct Acceptor {
    listener: TcpListener,
    role: Role,
    allow: Vec<IpAddr>,
    slots: Arc<Semaphore>,
    state: Arc<ServerState>,
}

fn allowed(allow: &[IpAddr], peer: &SocketAddr) -> bool {
    let ip = peer.ip().to_canonical();
    allow.is_empty() || allow.iter().any(|a| a.to_canonical() == ip)
}

impl Acceptor {
    async fn run(&self, control: &ShutdownController) -> Result<(), ServerError> {
        let link = self.role.name();
        loop {
            // Waiting for a free slot before accepting leaves further peers
            // in the listen backlog rather than holding sockets open.
            let Ok(permit) = Arc::clone(&self.slots).acquire_owned().await else {
                return Ok(());
            };
            let (stream, peer) = self.accept().await?;
            if !allowed(&self.allow, &peer) {
                warn!(%peer, link, "refused a connection from a peer not in server.{link}_allow");
                drop(stream);
                continue;
            }
            let state = Arc::clone(&self.state);
            let shutdown = control.handle();
            let role = self.role;
            let span = tracing::info_span!("conn", link, %peer);
            tokio::spawn(
                async move {
                    handle(role, stream, peer, state, shutdown).await;
                    drop(permit);
                }
                .instrument(span),
            );
        }
    }

    /// Accepts the next connection, retrying transient errors (such as
    /// running out of file descriptors) with a growing pause.
    async fn accept(&self) -> Result<(TcpStream, SocketAddr), ServerError> {
        let mut backoff = Duration::from_millis(50);
        loop {
            match self.listener.accept().await {
                Ok(ok) => return Ok(ok),
                Err(e) if backoff > Duration::from_secs(5) => {
                    return Err(ServerError::Accept { link: self.role.name(), source: e });
                }
                Err(e) => {
                    warn!(link = self.role.name(), "accept failed: {e}; retrying in {} ms", backoff.as_millis());
                    tokio::time::sleep(backoff).await;
                    backoff *= 2;
                }
            }
        }
    }
}

async fn handle(role: Role, stream: TcpStream, peer: SocketAddr, state: Arc<ServerState>, shutdown: Shutdown) {
    let s = &state.config.server;
    match role {
        Role::Camera => {
            let conn = connection::Connection::new(stream, peer, s.stall_timeout, s.max_frame_bytes);
            camera_link::serve(conn, Arc::clone(&state), shutdown).await
        }
        Role::Controller => {
            let conn = connection::Connection::new(
                stream,
                peer,
                s.stall_timeout,
                weldseam_proto::MAX_CONTROL_MESSAGE_BYTES as u64,
            );
            controller_link::serve(conn, Arc::clone(&state), shutdown).await
        }
    }
}
