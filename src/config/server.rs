//! The cell daemon's settings: the `[server]` and `[debug]` sections,
//! their defaults, and the checks that build them from the file.

use std::net::{IpAddr, SocketAddr};
use std::path::Path;
use std::time::Duration;

use serde::Deserialize;

use super::{ConfigError, check, count_in, file};

/// The pictures and figures of the daemon's last plans: the `[debug]`
/// section. Each plan's set (what `weldseam plan --debug DIR` writes: the
/// camera view, the cross-sections and `trace.json`) goes into a directory
/// of its own under `dir`, the oldest beyond `keep_last` deleted. An empty
/// `dir` keeps none.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DebugParams {
    pub dir: String,
    pub keep_last: u32,
}

/// How many plans' sets the daemon keeps by default: the last few minutes
/// of a busy cell, a few megabytes each.
pub const DEFAULT_DEBUG_KEEP_LAST: u32 = 20;

/// `server.plan_timeout_ms` unless configured: a 1920 x 1200 frame plans
/// in about 130 ms and under 300 ms under load (docs/PERFORMANCE.md), a
/// frame of several workpieces in a few times that, so a plan still
/// running after 5 s is stuck on a frame no camera's view gives.
pub const DEFAULT_PLAN_TIMEOUT_MS: u64 = 5_000;

/// The most sets `debug.keep_last` may ask for: about a gigabyte of
/// pictures, beyond which the directory is an archive, not a debug aid.
pub const MAX_DEBUG_KEEP_LAST: u32 = 1000;

impl Default for DebugParams {
    fn default() -> Self {
        DebugParams { dir: String::new(), keep_last: DEFAULT_DEBUG_KEEP_LAST }
    }
}

impl DebugParams {
    /// Where the sets go, when the daemon keeps them.
    pub fn directory(&self) -> Option<&Path> {
        (!self.dir.is_empty()).then(|| Path::new(&self.dir))
    }

    /// Checks the `[debug]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        count_in("debug.keep_last", self.keep_last.into(), 1, MAX_DEBUG_KEEP_LAST.into())?;
        check("debug.dir", !self.dir.contains('\0'), || "must not contain a NUL character".into())
    }
}

/// `server.page_plans` unless configured: the plans of the last minute
/// or so of a busy cell, each with its pictures (a few hundred kilobytes).
pub const DEFAULT_PAGE_PLANS: usize = 20;

/// The most plans `server.page_plans` may keep in memory with their
/// pictures: beyond, the page is an archive, which the record store is.
pub const MAX_PAGE_PLANS: u32 = 200;

/// The shortest `server.http_token`: a token an operator can type but no
/// one can guess by trying.
pub const MIN_HTTP_TOKEN_CHARS: usize = 16;

/// The cell daemon's network and scheduling settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// Where the camera (or its bridge) connects.
    pub camera_listen: SocketAddr,
    /// Where the robot controller connects.
    pub controller_listen: SocketAddr,
    /// Peers allowed on each link; empty allows any.
    pub camera_allow: Vec<IpAddr>,
    pub controller_allow: Vec<IpAddr>,
    /// Connections served at once per link; more wait to be accepted.
    pub max_camera_connections: usize,
    pub max_controller_connections: usize,
    /// A peer that sends nothing for this long in the middle of a message
    /// is dropped.
    pub stall_timeout: Duration,
    /// A connection must complete its Hello this soon after it is accepted.
    pub hello_timeout: Duration,
    /// Every message must arrive whole within this time from its first
    /// byte, plus its length at [`Self::min_transfer_bytes_per_s`]; a peer
    /// that trickles bytes is dropped even though it is never silent.
    pub message_timeout: Duration,
    /// The slowest transfer rate a large message (a frame) is allowed.
    pub min_transfer_bytes_per_s: u64,
    /// Connections per link that have not yet said Hello; a further one
    /// closes the oldest of the address that holds the most.
    pub max_pending_connections: usize,
    /// Connections from one address per link that have not yet said Hello;
    /// a further one closes that address's oldest.
    pub max_pending_per_address: usize,
    /// Where the HTTP listener serves the Prometheus metrics and the
    /// operator page; None is off.
    pub metrics_listen: Option<SocketAddr>,
    /// The bearer token every request to the HTTP listener must carry when
    /// it is not on loopback; None when the file leaves it empty.
    pub http_token: Option<String>,
    /// The last plans the operator page shows, pictures included.
    pub page_plans: usize,
    /// The largest frame payload accepted, bytes.
    pub max_frame_bytes: u64,
    /// Plan jobs queued or running at once; a request beyond gets Busy.
    pub plan_queue_depth: usize,
    /// Threads of the pipeline's pool; 0 uses every core.
    pub pipeline_threads: usize,
    /// How long a request waits for a fresh frame unless it says otherwise.
    pub fresh_frame_timeout: Duration,
    /// How long shutdown waits for plans in flight.
    pub shutdown_grace: Duration,
    /// The longest one plan may run; a plan still running then is stopped
    /// and refused (`plan_timeout`), and the next plan starts.
    pub plan_timeout: Duration,
    /// Recent frames kept for requests that name a frame id.
    pub frame_history: usize,
    /// The most bytes of points the frame history holds; the oldest
    /// frames go first when a new one would exceed it.
    pub frame_history_bytes: u64,
    /// How far a frame's capture time may lie outside the fresh window
    /// (before its request, or after its upload began) on the daemon's
    /// clock: the clock skew allowed between camera and daemon.
    pub capture_time_tolerance: Duration,
    /// The longest frame wait a request may ask for; longer is refused.
    pub max_request_timeout: Duration,
    /// Requests one controller connection may have waiting or running.
    pub max_requests_per_connection: usize,
    /// After this long without frames or plans the daemon hands freed
    /// memory back to the system; zero never does.
    pub idle_trim: Duration,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            camera_listen: SocketAddr::from(([127, 0, 0, 1], 7301)),
            controller_listen: SocketAddr::from(([127, 0, 0, 1], 7302)),
            camera_allow: Vec::new(),
            controller_allow: Vec::new(),
            max_camera_connections: 2,
            max_controller_connections: 8,
            stall_timeout: Duration::from_millis(5_000),
            hello_timeout: Duration::from_millis(2_000),
            message_timeout: Duration::from_millis(10_000),
            min_transfer_bytes_per_s: 1 << 20,
            max_pending_connections: 64,
            max_pending_per_address: 4,
            metrics_listen: None,
            http_token: None,
            page_plans: DEFAULT_PAGE_PLANS,
            max_frame_bytes: weldseam_proto::frame::DEFAULT_MAX_FRAME_BYTES,
            plan_queue_depth: 4,
            pipeline_threads: 0,
            fresh_frame_timeout: Duration::from_millis(5_000),
            shutdown_grace: Duration::from_millis(10_000),
            plan_timeout: Duration::from_millis(DEFAULT_PLAN_TIMEOUT_MS),
            frame_history: 8,
            frame_history_bytes: 128 << 20,
            capture_time_tolerance: Duration::from_millis(200),
            max_request_timeout: Duration::from_millis(30_000),
            max_requests_per_connection: 2,
            idle_trim: Duration::from_millis(10_000),
        }
    }
}

pub(super) fn socket_addr(key: &'static str, text: &str) -> Result<SocketAddr, ConfigError> {
    text.parse().map_err(|_| ConfigError::Invalid {
        key,
        message: format!("{text:?} is not an address with a port, such as \"127.0.0.1:7301\""),
    })
}

pub(super) fn ip_list(key: &'static str, list: &[String]) -> Result<Vec<IpAddr>, ConfigError> {
    list.iter()
        .map(|t| {
            t.parse().map_err(|_| ConfigError::Invalid {
                key,
                message: format!("{t:?} is not an IP address, such as \"192.168.0.10\""),
            })
        })
        .collect()
}

impl file::ServerSection {
    /// Checks the `[server]` section and builds its typed values.
    pub fn validate(&self) -> Result<ServerConfig, ConfigError> {
        let s = self;
        const MAX_CONNECTIONS: u32 = 1024;
        check("server.max_camera_connections", (1..=MAX_CONNECTIONS).contains(&s.max_camera_connections), || {
            format!("must lie in [1, {MAX_CONNECTIONS}], got {}", s.max_camera_connections)
        })?;
        check(
            "server.max_controller_connections",
            (1..=MAX_CONNECTIONS).contains(&s.max_controller_connections),
            || format!("must lie in [1, {MAX_CONNECTIONS}], got {}", s.max_controller_connections),
        )?;
        check("server.stall_timeout_ms", (10..=3_600_000).contains(&s.stall_timeout_ms), || {
            format!("must lie in [10, 3600000] ms, got {}", s.stall_timeout_ms)
        })?;
        check("server.hello_timeout_ms", (10..=60_000).contains(&s.hello_timeout_ms), || {
            format!("must lie in [10, 60000] ms, got {}", s.hello_timeout_ms)
        })?;
        check("server.message_timeout_ms", (10..=3_600_000).contains(&s.message_timeout_ms), || {
            format!("must lie in [10, 3600000] ms, got {}", s.message_timeout_ms)
        })?;
        const MIN_RATE: u64 = 1 << 10;
        const MAX_RATE: u64 = 1 << 30;
        check("server.min_transfer_bytes_per_s", (MIN_RATE..=MAX_RATE).contains(&s.min_transfer_bytes_per_s), || {
            format!("must lie in [{MIN_RATE}, {MAX_RATE}] bytes per second, got {}", s.min_transfer_bytes_per_s)
        })?;
        const MAX_PENDING: u32 = 4096;
        check("server.max_pending_connections", (1..=MAX_PENDING).contains(&s.max_pending_connections), || {
            format!("must lie in [1, {MAX_PENDING}], got {}", s.max_pending_connections)
        })?;
        check(
            "server.max_pending_per_address",
            (1..=s.max_pending_connections).contains(&s.max_pending_per_address),
            || {
                format!(
                    "must lie in [1, server.max_pending_connections = {}], got {}",
                    s.max_pending_connections, s.max_pending_per_address
                )
            },
        )?;
        let metrics_listen = match s.metrics_listen.as_str() {
            "" => None,
            text => Some(socket_addr("server.metrics_listen", text)?),
        };
        let http_token = (!s.http_token.is_empty()).then(|| s.http_token.clone());
        if let Some(token) = &http_token {
            check(
                "server.http_token",
                token.len() >= MIN_HTTP_TOKEN_CHARS && token.chars().all(|c| c.is_ascii_graphic()),
                || format!("must be at least {MIN_HTTP_TOKEN_CHARS} printable ASCII characters without spaces"),
            )?;
        }
        if let Some(addr) = metrics_listen {
            check("server.http_token", addr.ip().is_loopback() || http_token.is_some(), || {
                format!(
                    "must be set: server.metrics_listen ({addr}) is not a loopback address, and the operator page \
                     and the metrics are served beyond this machine only to a request carrying the token"
                )
            })?;
        }
        count_in("server.page_plans", s.page_plans.into(), 1, MAX_PAGE_PLANS.into())?;
        const MIN_FRAME: u64 = 1 << 10;
        const MAX_FRAME: u64 = 4 << 30;
        check("server.max_frame_bytes", (MIN_FRAME..=MAX_FRAME).contains(&s.max_frame_bytes), || {
            format!("must lie in [{MIN_FRAME}, {MAX_FRAME}] bytes, got {}", s.max_frame_bytes)
        })?;
        check("server.plan_queue_depth", (1..=1024).contains(&s.plan_queue_depth), || {
            format!("must lie in [1, 1024], got {}", s.plan_queue_depth)
        })?;
        check("server.pipeline_threads", s.pipeline_threads <= 1024, || {
            format!("must be 0 (every core) to 1024, got {}", s.pipeline_threads)
        })?;
        check("server.fresh_frame_timeout_ms", (1..=600_000).contains(&s.fresh_frame_timeout_ms), || {
            format!("must lie in [1, 600000] ms, got {}", s.fresh_frame_timeout_ms)
        })?;
        check("server.shutdown_grace_ms", s.shutdown_grace_ms <= 3_600_000, || {
            format!("must be at most 3600000 ms, got {}", s.shutdown_grace_ms)
        })?;
        check("server.plan_timeout_ms", (1..=600_000).contains(&s.plan_timeout_ms), || {
            format!("must lie in [1, 600000] ms, got {}", s.plan_timeout_ms)
        })?;
        check("server.frame_history", (1..=1024).contains(&s.frame_history), || {
            format!("must lie in [1, 1024] frames, got {}", s.frame_history)
        })?;
        const MAX_HISTORY_BYTES: u64 = 64 << 30;
        check(
            "server.frame_history_bytes",
            (s.max_frame_bytes..=MAX_HISTORY_BYTES).contains(&s.frame_history_bytes),
            || {
                format!(
                    "must lie in [server.max_frame_bytes = {}, {MAX_HISTORY_BYTES}] bytes, so the newest frame always fits, got {}",
                    s.max_frame_bytes, s.frame_history_bytes
                )
            },
        )?;
        check("server.capture_time_tolerance_ms", s.capture_time_tolerance_ms <= 5_000, || {
            format!("must lie in [0, 5000] ms, got {}", s.capture_time_tolerance_ms)
        })?;
        check("server.max_request_timeout_ms", (1..=600_000).contains(&s.max_request_timeout_ms), || {
            format!("must lie in [1, 600000] ms, got {}", s.max_request_timeout_ms)
        })?;
        check("server.fresh_frame_timeout_ms", s.fresh_frame_timeout_ms <= s.max_request_timeout_ms, || {
            format!(
                "must not exceed server.max_request_timeout_ms ({}), got {}",
                s.max_request_timeout_ms, s.fresh_frame_timeout_ms
            )
        })?;
        check(
            "server.max_requests_per_connection",
            (1..=s.plan_queue_depth).contains(&s.max_requests_per_connection),
            || {
                format!(
                    "must lie in [1, server.plan_queue_depth = {}], got {}",
                    s.plan_queue_depth, s.max_requests_per_connection
                )
            },
        )?;
        check("server.idle_trim_ms", s.idle_trim_ms <= 86_400_000, || {
            format!("must lie in [0 (never), 86400000] ms, got {}", s.idle_trim_ms)
        })?;
        Ok(ServerConfig {
            camera_listen: socket_addr("server.camera_listen", &s.camera_listen)?,
            controller_listen: socket_addr("server.controller_listen", &s.controller_listen)?,
            camera_allow: ip_list("server.camera_allow", &s.camera_allow)?,
            controller_allow: ip_list("server.controller_allow", &s.controller_allow)?,
            max_camera_connections: s.max_camera_connections as usize,
            max_controller_connections: s.max_controller_connections as usize,
            stall_timeout: Duration::from_millis(s.stall_timeout_ms),
            hello_timeout: Duration::from_millis(s.hello_timeout_ms),
            message_timeout: Duration::from_millis(s.message_timeout_ms),
            min_transfer_bytes_per_s: s.min_transfer_bytes_per_s,
            max_pending_connections: s.max_pending_connections as usize,
            max_pending_per_address: s.max_pending_per_address as usize,
            metrics_listen,
            http_token,
            page_plans: s.page_plans as usize,
            max_frame_bytes: s.max_frame_bytes,
            plan_queue_depth: s.plan_queue_depth as usize,
            pipeline_threads: s.pipeline_threads as usize,
            fresh_frame_timeout: Duration::from_millis(s.fresh_frame_timeout_ms),
            shutdown_grace: Duration::from_millis(s.shutdown_grace_ms),
            plan_timeout: Duration::from_millis(s.plan_timeout_ms),
            frame_history: s.frame_history as usize,
            frame_history_bytes: s.frame_history_bytes,
            capture_time_tolerance: Duration::from_millis(s.capture_time_tolerance_ms),
            max_request_timeout: Duration::from_millis(s.max_request_timeout_ms),
            max_requests_per_connection: s.max_requests_per_connection as usize,
            idle_trim: Duration::from_millis(s.idle_trim_ms),
        })
    }
}
