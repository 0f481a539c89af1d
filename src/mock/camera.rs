//! A mock camera: connects to the camera link, says hello, and sends
//! frames from a list in turn, either answering each trigger (the frame
//! carries the trigger's id) or free-running at a rate, each stamped with
//! this machine's clock as its capture time. It counts the daemon's frame
//! acknowledgements. When the daemon goes away it reconnects with a
//! growing pause, a bounded number of times.

use std::future::Future;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::net::TcpStream;
use tokio::sync::mpsc;
use tracing::{info, warn};
use weldseam_proto::Message;
use weldseam_proto::frame::DEFAULT_MAX_FRAME_BYTES;
use weldseam_proto::message::{Hello, Role};

use super::ClientError;
use crate::cloud::PointCloud;
use crate::server::connection::{Connection, MessageWriter};

/// How the mock camera behaves.
#[derive(Debug, Clone)]
pub struct CameraOptions {
    /// The name in the hello.
    pub name: String,
    /// Push frames at this rate without triggers; triggers are answered too.
    pub free_run_hz: Option<f64>,
    /// Stop after sending this many frames.
    pub max_frames: Option<u64>,
    /// Reconnection attempts in a row before giving up.
    pub reconnect_attempts: u32,
    /// The first pause before reconnecting; doubles up to 5 s.
    pub reconnect_delay: Duration,
    /// The id of the first frame sent.
    pub first_frame_id: u64,
}

impl Default for CameraOptions {
    fn default() -> Self {
        CameraOptions {
            name: "mock-camera".into(),
            free_run_hz: None,
            max_frames: None,
            reconnect_attempts: 10,
            reconnect_delay: Duration::from_millis(200),
            first_frame_id: 1,
        }
    }
}

/// What the mock camera did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CameraSummary {
    pub frames_sent: u64,
    pub triggers_answered: u64,
    /// Frames the daemon acknowledged as held, and as refused.
    pub frames_held: u64,
    pub frames_refused: u64,
    pub connections: u32,
}

/// A mock camera serving `frames` in turn.
#[derive(Debug, Clone)]
pub struct MockCamera {
    addr: String,
    frames: Vec<Arc<PointCloud>>,
    options: CameraOptions,
}

const STALL: Duration = Duration::from_secs(30);
const MAX_DELAY: Duration = Duration::from_secs(5);

enum Ended {
    /// The frame budget is spent or shutdown was asked for.
    Done,
    /// The connection was lost.
    Lost(ClientError),
}

impl MockCamera {
    pub fn new(addr: impl Into<String>, frames: Vec<Arc<PointCloud>>, options: CameraOptions) -> Self {
        MockCamera { addr: addr.into(), frames, options }
    }

    /// Runs until the frame budget is spent, `shutdown` completes, or the
    /// daemon stays unreachable for every reconnection attempt.
    pub async fn run(self, shutdown: impl Future) -> Result<CameraSummary, ClientError> {
        let mut summary = CameraSummary::default();
        let mut next_id = self.options.first_frame_id;
        let mut failures = 0u32;
        let mut delay = self.options.reconnect_delay;
        tokio::pin!(shutdown);
        loop {
            let session = self.session(&mut summary, &mut next_id, &mut failures);
            let ended = tokio::select! {
                e = session => e,
                _ = &mut shutdown => Ended::Done,
            };
            match ended {
                Ended::Done => return Ok(summary),
                Ended::Lost(e) => {
                    failures += 1;
                    if failures > self.options.reconnect_attempts {
                        return Err(e);
                    }
                    warn!("camera link lost: {e}; reconnecting in {} ms", delay.as_millis());
                    tokio::select! {
                        _ = tokio::time::sleep(delay) => {}
                        _ = &mut shutdown => return Ok(summary),
                    }
                    delay = (delay * 2).min(MAX_DELAY);
                }
            }
        }
    }

    /// One connection: hello, then frames until it breaks or ends.
    async fn session(&self, summary: &mut CameraSummary, next_id: &mut u64, failures: &mut u32) -> Ended {
        let stream = match TcpStream::connect(&self.addr).await {
            Ok(s) => s,
            Err(source) => return Ended::Lost(ClientError::Connect { addr: self.addr.clone(), source }),
        };
        let peer = match stream.peer_addr() {
            Ok(p) => p,
            Err(source) => return Ended::Lost(ClientError::Connect { addr: self.addr.clone(), source }),
        };
        let Connection { mut reader, mut writer, .. } = Connection::new(stream, peer, STALL, DEFAULT_MAX_FRAME_BYTES);
        let hello = Hello::new(Role::Camera, self.options.name.clone(), 0);
        if let Err(e) = writer.send(&Message::Hello(hello)).await {
            return Ended::Lost(e.into());
        }
        match reader.read().await {
            Ok(Some(r)) => match r.message {
                Message::HelloAck(ack) => info!(server = %ack.server, "camera link up"),
                Message::Error(e) => return Ended::Lost(ClientError::Refused(e)),
                other => return Ended::Lost(ClientError::Unexpected(other.tag().name())),
            },
            Ok(None) => return Ended::Lost(ClientError::Closed),
            Err(e) => return Ended::Lost(e.into()),
        }
        summary.connections += 1;
        *failures = 0;

        // Incoming messages arrive through a task, so a tick never
        // interrupts a half-read message.
        let (tx, mut incoming) = mpsc::channel(16);
        let read_task = tokio::spawn(async move {
            loop {
                let r = reader.read().await;
                let stop = !matches!(r, Ok(Some(_)));
                if tx.send(r).await.is_err() || stop {
                    break;
                }
            }
        });
        let mut ticker = self.options.free_run_hz.filter(|hz| *hz > 0.0).map(|hz| {
            let mut t = tokio::time::interval(Duration::from_secs_f64(1.0 / hz));
            t.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            t
        });
        let ended = loop {
            if self.options.max_frames.is_some_and(|max| summary.frames_sent >= max) {
                break Ended::Done;
            }
            let trigger_id = tokio::select! {
                msg = incoming.recv() => match msg {
                    Some(Ok(Some(r))) => match r.message {
                        Message::Trigger(t) => t.trigger_id,
                        Message::FrameAck(ack) => {
                            match ack.refusal() {
                                None => summary.frames_held += 1,
                                Some(code) => {
                                    summary.frames_refused += 1;
                                    warn!(frame_id = ack.frame_id, code = %code, "frame refused: {}", ack.message);
                                }
                            }
                            continue;
                        }
                        Message::Error(e) => {
                            warn!(code = %e.code, "the daemon reported: {}", e.message);
                            continue;
                        }
                        other => {
                            warn!("ignored an unexpected {} message", other.tag().name());
                            continue;
                        }
                    },
                    Some(Ok(None)) | None => break Ended::Lost(ClientError::Closed),
                    Some(Err(e)) => break Ended::Lost(e.into()),
                },
                _ = tick(&mut ticker) => 0,
            };
            let index = summary.frames_sent as usize;
            if let Err(e) = self.send_frame(&mut writer, index, *next_id, trigger_id).await {
                break Ended::Lost(e);
            }
            *next_id += 1;
            summary.frames_sent += 1;
            if trigger_id != 0 {
                summary.triggers_answered += 1;
            }
        };
        read_task.abort();
        writer.shutdown().await;
        ended
    }

    async fn send_frame(
        &self,
        writer: &mut MessageWriter<tokio::net::tcp::OwnedWriteHalf>,
        index: usize,
        frame_id: u64,
        trigger_id: u64,
    ) -> Result<(), ClientError> {
        if self.frames.is_empty() {
            return Err(ClientError::Unexpected("(no frames to send)"));
        }
        let cloud = &self.frames[index % self.frames.len()];
        let capture_time_us = SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_micros() as u64).unwrap_or(0);
        let frame = crate::convert::to_proto::frame(cloud, frame_id, trigger_id, capture_time_us);
        let meta = frame.meta;
        writer.send(&Message::Frame(frame)).await?;
        info!(frame_id, trigger_id, width = meta.width, height = meta.height, "frame sent");
        Ok(())
    }
}

async fn tick(ticker: &mut Option<tokio::time::Interval>) {
    match ticker {
        Some(t) => {
            t.tick().await;
        }
        None => std::future::pending().await,
    }
}
