//! The daemon driven by mock peers, for measuring it: the latency from a
//! triggered frame's last byte to the reply's, and the reply times and
//! service order while a camera streams and several controllers plan in a
//! loop. An in-process daemon on loopback ports ([`LocalDaemon`]), a camera
//! on a raw socket sending one pre-encoded frame (as a camera with its own
//! encoder would: the measuring process spends no time building frames)
//! and the mock controller. `weldseam bench` prints these figures and the
//! daemon's load test holds them to PROTOCOL.md's bound; nothing here
//! asserts a time.

use std::io;
use std::time::{Duration, Instant};

use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;
use tokio::sync::mpsc;
use weldseam_proto::Message;
use weldseam_proto::frame::{self, DEFAULT_MAX_FRAME_BYTES};
use weldseam_proto::message::{FrameSelect, Hello, Role};

use crate::cloud::PointCloud;
use crate::config::Config;
use crate::joint::JointType;
use crate::mock::ClientError;
use crate::mock::controller::{ControllerClient, request_for_simulation};
use crate::server::connection::MessageReader;
use crate::server::local::LocalDaemon;
use crate::sim::Simulation;

/// The wire encoding of `cloud` as a camera's Frame message (header and
/// payload), millimetres.
pub fn frame_message(cloud: &PointCloud, frame_id: u64, trigger_id: u64) -> Result<Vec<u8>, frame::EncodeError> {
    frame::encode(&Message::Frame(crate::convert::to_proto::frame(cloud, frame_id, trigger_id, 0)))
}

/// Why the daemon could not be driven.
#[derive(Debug, thiserror::Error)]
pub enum DriveError {
    #[error("cannot set up the daemon: {0}")]
    Setup(String),
    #[error("the controller's exchange failed: {0}")]
    Client(#[from] ClientError),
    #[error("the camera failed: {0}")]
    Camera(String),
    #[error(transparent)]
    Start(#[from] crate::server::local::StartError),
    #[error("the daemon did not stop cleanly: {0}")]
    Stop(#[from] crate::server::local::StopError),
    #[error(transparent)]
    Io(#[from] io::Error),
}

/// Byte offsets, in an encoded Frame message, of the frame and trigger
/// ids: after the 16-byte header, the payload starts with them.
const FRAME_ID_AT: usize = frame::HEADER_BYTES;
const TRIGGER_ID_AT: usize = frame::HEADER_BYTES + 8;
const CAPTURE_TIME_AT: usize = frame::HEADER_BYTES + 16;

/// A camera on a raw socket: answers each trigger with `message` (a
/// pre-encoded frame whose ids it patches) and reports the instant the
/// frame's last byte was written.
async fn raw_camera(
    addr: String,
    mut message: Vec<u8>,
    written: mpsc::UnboundedSender<Instant>,
) -> Result<(), DriveError> {
    let stream = TcpStream::connect(&addr).await?;
    stream.set_nodelay(true)?;
    let (read, mut write) = stream.into_split();
    let mut reader = MessageReader::new(read, Duration::from_secs(30), DEFAULT_MAX_FRAME_BYTES);
    let hello = Hello::new(Role::Camera, "bench-camera", 0);
    let hello = frame::encode(&Message::Hello(hello)).map_err(|e| DriveError::Camera(e.to_string()))?;
    write.write_all(&hello).await?;
    let mut frame_id = 0u64;
    loop {
        let received = match reader.read().await {
            Ok(Some(r)) => r,
            Ok(None) => return Ok(()),
            Err(e) => return Err(DriveError::Camera(e.to_string())),
        };
        let trigger_id = match received.message {
            Message::Trigger(t) => t.trigger_id,
            Message::HelloAck(_) | Message::Status(_) | Message::FrameAck(_) => continue,
            Message::Error(e) => return Err(DriveError::Camera(e.message)),
            other => return Err(DriveError::Camera(format!("unexpected {} message", other.tag().name()))),
        };
        frame_id += 1;
        message[FRAME_ID_AT..FRAME_ID_AT + 8].copy_from_slice(&frame_id.to_le_bytes());
        message[TRIGGER_ID_AT..TRIGGER_ID_AT + 8].copy_from_slice(&trigger_id.to_le_bytes());
        let captured = crate::server::frames::wall_clock_us();
        message[CAPTURE_TIME_AT..CAPTURE_TIME_AT + 8].copy_from_slice(&captured.to_le_bytes());
        write.write_all(&message).await?;
        write.flush().await?;
        if written.send(Instant::now()).is_err() {
            return Ok(());
        }
    }
}

/// The daemon's latency, ms per request: an in-process daemon on loopback
/// ports running `config`, a camera answering triggers with `sim`'s frame
/// and a controller asking for trigger-mode plans of `joint` on it, `runs` times after one warm-up.
/// Each sample runs from the instant the camera has written the frame's
/// last byte to the instant the controller has read the reply's last byte.
pub fn daemon_latency(config: Config, joint: JointType, sim: &Simulation, runs: usize) -> Result<Vec<f64>, DriveError> {
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    rt.block_on(daemon_latency_async(config, joint, sim, runs))
}

async fn daemon_latency_async(
    config: Config,
    joint: JointType,
    sim: &Simulation,
    runs: usize,
) -> Result<Vec<f64>, DriveError> {
    let daemon = LocalDaemon::start(config).await?;
    let (camera_addr, controller_addr) = (daemon.camera_addr.to_string(), daemon.controller_addr.to_string());

    let message = frame_message(&sim.cloud, 0, 0).map_err(|e| DriveError::Setup(e.to_string()))?;
    let (written_tx, mut written) = mpsc::unbounded_channel();
    let camera = tokio::spawn(raw_camera(camera_addr, message, written_tx));

    let result = async {
        let mut controller = ControllerClient::connect(&controller_addr, "bench-controller").await?;
        // A trigger request needs the camera attached first.
        controller
            .wait_for_camera(Duration::from_secs(10))
            .await
            .map_err(|_| DriveError::Setup("the camera did not connect within 10 s".into()))?;
        let mut samples = Vec::with_capacity(runs);
        for id in 0..=runs as u64 {
            let request = request_for_simulation(id + 1, joint, sim, FrameSelect::Trigger);
            controller.plan(request, Duration::from_secs(60)).await?;
            let replied = Instant::now();
            let sent =
                written.try_recv().map_err(|_| DriveError::Camera("a reply came without a frame written".into()))?;
            if id > 0 {
                samples.push(replied.duration_since(sent).as_secs_f64() * 1e3);
            }
        }
        Ok(samples)
    }
    .await;

    daemon.stop().await?;
    camera.abort();
    result
}

/// How the daemon was loaded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Load {
    /// How long the controllers keep asking.
    pub duration: Duration,
    /// Controllers planning in a loop, one request in flight each,
    /// alternating Trigger and NextFrame requests.
    pub controllers: usize,
    /// The camera's free-running rate (it answers triggers as well).
    pub camera_hz: f64,
    /// `server.plan_queue_depth` of the daemon.
    pub queue_depth: usize,
}

/// What the daemon did under a [`Load`].
#[derive(Debug, Clone, Default)]
pub struct LoadFigures {
    /// Each answered request, in the order the replies arrived: the frame
    /// it was planned from, the reply time (request written to reply read)
    /// and the pipeline's own time, ms.
    pub replies: Vec<LoadReply>,
    /// Requests answered with an error, by the error's name.
    pub errors: std::collections::BTreeMap<String, usize>,
}

/// One answered request under load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadReply {
    pub frame_id: u64,
    pub reply_ms: f64,
    pub plan_ms: f64,
}

impl LoadFigures {
    pub fn reply_ms(&self) -> Vec<f64> {
        self.replies.iter().map(|r| r.reply_ms).collect()
    }

    pub fn plan_ms(&self) -> Vec<f64> {
        self.replies.iter().map(|r| r.plan_ms).collect()
    }

    /// Replies that came after a reply planned from a later frame: plans
    /// overtaken by plans whose frames became ready after theirs. The
    /// camera's ids increase in the order its frames reach the daemon, so
    /// in first-in-first-out order this is 0.
    pub fn overtaken(&self) -> usize {
        let mut newest = 0;
        let mut overtaken = 0;
        for r in &self.replies {
            if r.frame_id < newest {
                overtaken += 1;
            }
            newest = newest.max(r.frame_id);
        }
        overtaken
    }
}

/// The `q` quantile (0 to 1) of `samples`, by the nearest rank.
pub fn quantile(samples: &[f64], q: f64) -> Option<f64> {
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len().max(1));
    sorted.get(rank - 1).copied()
}

/// Runs an in-process daemon on loopback ports with a mock camera pushing
/// `sim`'s frame at `load.camera_hz` and `load.controllers` controllers
/// planning `joint` on it in a loop for `load.duration`, and collects every
/// reply. The daemon runs with `config`, its queue depth set to the load's.
pub fn daemon_under_load(
    config: Config,
    joint: JointType,
    sim: &Simulation,
    load: Load,
) -> Result<LoadFigures, DriveError> {
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    rt.block_on(daemon_under_load_async(config, joint, sim, load))
}

/// [`daemon_under_load`] inside a runtime the caller owns.
pub async fn daemon_under_load_async(
    mut config: Config,
    joint: JointType,
    sim: &Simulation,
    load: Load,
) -> Result<LoadFigures, DriveError> {
    use std::sync::{Arc, Mutex};

    config.server.plan_queue_depth = load.queue_depth.max(1);
    config.server.max_requests_per_connection = config.server.max_requests_per_connection.min(load.queue_depth.max(1));
    let daemon = LocalDaemon::start(config).await?;
    let (camera_addr, controller_addr) = (daemon.camera_addr.to_string(), daemon.controller_addr.to_string());
    let message = frame_message(&sim.cloud, 0, 0).map_err(|e| DriveError::Setup(e.to_string()))?;
    let camera = tokio::spawn(streaming_camera(camera_addr, message, load.camera_hz));

    let result = async {
        let mut probe = ControllerClient::connect(&controller_addr, "bench-probe").await?;
        probe
            .wait_for_camera(Duration::from_secs(10))
            .await
            .map_err(|_| DriveError::Setup("the camera did not connect within 10 s".into()))?;
        let figures = Arc::new(Mutex::new(LoadFigures::default()));
        let until = tokio::time::Instant::now() + load.duration;
        let mut tasks = Vec::new();
        for k in 0..load.controllers as u64 {
            let mut client = ControllerClient::connect(&controller_addr, &format!("bench-controller-{k}")).await?;
            let figures = Arc::clone(&figures);
            let sim = sim.clone();
            tasks.push(tokio::spawn(async move {
                let mut id = k << 32;
                while tokio::time::Instant::now() < until {
                    id += 1;
                    let select = if id % 2 == 0 { FrameSelect::Trigger } else { FrameSelect::NextFrame };
                    let started = Instant::now();
                    let reply =
                        client.plan(request_for_simulation(id, joint, &sim, select), Duration::from_secs(120)).await;
                    let reply_ms = started.elapsed().as_secs_f64() * 1e3;
                    let mut f = figures.lock().unwrap_or_else(|p| p.into_inner());
                    match reply {
                        Ok(r) => f.replies.push(LoadReply {
                            frame_id: r.frame_id,
                            reply_ms,
                            plan_ms: r.result.timing_ms.get("total").copied().unwrap_or(f64::NAN),
                        }),
                        Err(ClientError::Refused(e)) => *f.errors.entry(e.code.name().to_string()).or_default() += 1,
                        Err(e) => return Err(DriveError::Client(e)),
                    }
                }
                Ok(())
            }));
        }
        for t in tasks {
            t.await.map_err(|e| DriveError::Setup(e.to_string()))??;
        }
        let figures = figures.lock().unwrap_or_else(|p| p.into_inner()).clone();
        Ok(figures)
    }
    .await;

    camera.abort();
    daemon.stop().await?;
    result
}

/// A camera on a raw socket streaming `message` (a pre-encoded frame whose
/// ids and capture time it patches) at up to `hz`, answering triggers
/// first, as a camera with its own encoder would: the measuring
/// process spends no time building frames, only sending them.
async fn streaming_camera(addr: String, mut message: Vec<u8>, hz: f64) -> Result<(), DriveError> {
    let stream = TcpStream::connect(&addr).await?;
    stream.set_nodelay(true)?;
    let (read, mut write) = stream.into_split();
    let hello = Hello::new(Role::Camera, "bench-camera", 0);
    let hello = frame::encode(&Message::Hello(hello)).map_err(|e| DriveError::Camera(e.to_string()))?;
    write.write_all(&hello).await?;
    let (trigger_tx, mut triggers) = mpsc::unbounded_channel();
    let reader = tokio::spawn(async move {
        let mut reader = MessageReader::new(read, Duration::from_secs(30), DEFAULT_MAX_FRAME_BYTES);
        while let Ok(Some(received)) = reader.read().await {
            if let Message::Trigger(t) = received.message
                && trigger_tx.send(t.trigger_id).is_err()
            {
                break;
            }
        }
    });
    let mut ticker = tokio::time::interval(Duration::from_secs_f64(1.0 / hz.clamp(0.1, 1000.0)));
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut frame_id = 0u64;
    let result = loop {
        let trigger_id = match triggers.try_recv() {
            Ok(id) => id,
            Err(mpsc::error::TryRecvError::Disconnected) => break Ok(()),
            Err(mpsc::error::TryRecvError::Empty) => tokio::select! {
                id = triggers.recv() => match id {
                    Some(id) => id,
                    None => break Ok(()),
                },
                _ = ticker.tick() => 0,
            },
        };
        frame_id += 1;
        message[FRAME_ID_AT..FRAME_ID_AT + 8].copy_from_slice(&frame_id.to_le_bytes());
        message[TRIGGER_ID_AT..TRIGGER_ID_AT + 8].copy_from_slice(&trigger_id.to_le_bytes());
        let captured = crate::server::frames::wall_clock_us();
        message[CAPTURE_TIME_AT..CAPTURE_TIME_AT + 8].copy_from_slice(&captured.to_le_bytes());
        if let Err(e) = write.write_all(&message).await {
            break Err(e.into());
        }
    };
    reader.abort();
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overtaken_plans_and_quantiles_are_counted() {
        let reply = |frame_id| LoadReply { frame_id, reply_ms: 1.0, plan_ms: 1.0 };
        let fifo = LoadFigures { replies: [1, 2, 2, 5].map(reply).to_vec(), ..LoadFigures::default() };
        assert_eq!(fifo.overtaken(), 0);
        let unfair = LoadFigures { replies: [1, 4, 2, 5, 3].map(reply).to_vec(), ..LoadFigures::default() };
        assert_eq!(unfair.overtaken(), 2);
        let samples: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(
            (quantile(&samples, 0.5), quantile(&samples, 0.99), quantile(&samples, 1.0)),
            (Some(50.0), Some(99.0), Some(100.0))
        );
        assert_eq!(quantile(&[], 0.5), None);
    }

    #[test]
    fn frame_ids_sit_where_the_camera_patches_them() {
        let cloud = PointCloud::organized(2, 1, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]).unwrap();
        let bytes = frame_message(&cloud, 0x0102, 0x0304).unwrap();
        assert_eq!(u64::from_le_bytes(bytes[FRAME_ID_AT..FRAME_ID_AT + 8].try_into().unwrap()), 0x0102);
        assert_eq!(u64::from_le_bytes(bytes[TRIGGER_ID_AT..TRIGGER_ID_AT + 8].try_into().unwrap()), 0x0304);
    }
}
