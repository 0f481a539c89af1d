//! The frames the daemon holds and the requests waiting for one.
//!
//! Safety rule: a plan never uses a frame captured before its request
//! arrived unless the request names the frame's id. A frame qualifies for
//! a waiting Trigger or NextFrame request only when
//!
//! - its upload's first byte arrived after the request did (a frame that
//!   was already on the wire when the request came was captured before
//!   it, whatever its time stamp says), and
//! - its capture time lies in the fresh window on the daemon's clock: not
//!   before the request's arrival less the tolerance, and not after the
//!   upload's first byte plus the tolerance.
//!
//! A trigger waiter is answered only by a frame carrying its trigger id.
//! Unnamed requests go to every connected camera (the first qualifying
//! frame wins); a request naming a camera goes to the cameras with that
//! Hello name only. Old frames are reachable by id alone. The history is
//! bounded in frames and in bytes.
//!
//! Each request is handed its frame with its place in the serve order
//! ([`super::serve_order`]): frames in the order they became ready, the
//! requests one frame answers in the order they arrived (waiters are kept
//! in arrival order and never reordered).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use tokio::sync::{mpsc, oneshot};

use super::serve_order::{ServeOrder, Ticket};
use crate::cloud::PointCloud;
use crate::convert::from_proto::FrameInput;

/// A frame received from the camera.
#[derive(Debug)]
pub struct StoredFrame {
    pub frame_id: u64,
    /// The trigger it answers, or 0.
    pub trigger_id: u64,
    /// Camera clock, microseconds since the Unix epoch.
    pub capture_time_us: u64,
    /// The Hello name of the camera that sent it.
    pub camera: Arc<str>,
    pub cloud: Arc<PointCloud>,
    /// The units and frame its points are in, as the camera said; every
    /// plan of it is told them.
    pub input: FrameInput,
    /// When the upload's first byte arrived, on the daemon's clocks.
    pub upload_started: Instant,
    pub upload_started_us: u64,
    /// When its last byte arrived.
    pub arrived: Instant,
}

impl StoredFrame {
    /// Bytes of memory its points take.
    pub fn bytes(&self) -> u64 {
        (self.cloud.len() * std::mem::size_of::<crate::cloud::Point>()) as u64
    }
}

/// The daemon's wall clock, microseconds since the Unix epoch.
pub fn wall_clock_us() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_micros() as u64).unwrap_or(0)
}

/// Why no fresh frame can be had.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// No camera (or none of the requested name) is connected.
    #[error("{}", no_camera_text(.wanted, .connected))]
    NoCamera { wanted: Option<String>, connected: Vec<String> },
    /// Every camera asked went away before answering.
    #[error("the camera disconnected before sending the frame")]
    CameraGone,
    /// The wait ran out; `skipped` says why frames that came did not qualify.
    #[error("no fresh frame arrived within {ms} ms{}", skipped_text(.skipped))]
    Timeout { ms: u128, skipped: Option<String> },
    /// The named frame is not in the history and is not expected.
    #[error("frame {0} is not held by the daemon (unknown, or older than the frame history)")]
    UnknownFrame(u64),
    /// The named frame, newer than any received, did not arrive in time.
    #[error("frame {id} is not held by the daemon and did not arrive within {ms} ms")]
    NotArrived { id: u64, ms: u128 },
    /// Every answer to the request's trigger was captured outside the
    /// fresh window.
    #[error("{0}")]
    Stale(String),
}

fn no_camera_text(wanted: &Option<String>, connected: &[String]) -> String {
    match wanted {
        None => "no camera is connected, so no fresh frame can be captured".into(),
        Some(name) if connected.is_empty() => format!("no camera named {name:?} is connected; no camera is"),
        Some(name) => format!("no camera named {name:?} is connected; connected: {connected:?}"),
    }
}

fn skipped_text(skipped: &Option<String>) -> String {
    skipped.as_ref().map(|s| format!("; {s}")).unwrap_or_default()
}

/// What a request waits for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Wanted {
    /// The frame answering a trigger sent for the request.
    Trigger,
    /// The next frame that qualifies.
    NextFrame,
    /// A frame by its camera id, held or still to come.
    FrameId(u64),
}

/// A request for a frame: what, from which camera, and when it arrived.
#[derive(Debug, Clone)]
pub struct FrameRequest {
    pub wanted: Wanted,
    /// A camera's Hello name; any camera when None.
    pub camera: Option<String>,
    pub arrived: Instant,
    /// The daemon's wall clock at arrival, µs since the epoch.
    pub arrived_us: u64,
}

impl FrameRequest {
    /// A request arriving now.
    pub fn now(wanted: Wanted, camera: Option<String>) -> Self {
        FrameRequest { wanted, camera, arrived: Instant::now(), arrived_us: wall_clock_us() }
    }
}

/// A frame handed to a request, with the request's place in the serve
/// order.
#[derive(Debug)]
pub struct Handed {
    pub frame: Arc<StoredFrame>,
    pub ticket: Ticket,
}

type Reply = oneshot::Sender<Result<Handed, FrameError>>;

#[derive(Debug)]
enum WaitKind {
    Next,
    /// The trigger id, and the cameras (registration ids) it went to that
    /// have not answered yet.
    Trigger {
        trigger_id: u64,
        pending: Vec<u64>,
    },
    Id(u64),
}

#[derive(Debug)]
struct Waiter {
    id: u64,
    kind: WaitKind,
    camera: Option<Arc<str>>,
    arrived: Instant,
    arrived_us: u64,
    reply: Reply,
    /// Why the last frame that could have answered it did not qualify.
    skipped: Option<String>,
}

#[derive(Debug)]
struct Camera {
    id: u64,
    name: Arc<str>,
    triggers: mpsc::Sender<u64>,
    /// The newest frame id received on this connection.
    latest_frame_id: Option<u64>,
}

#[derive(Debug, Default)]
struct Inner {
    history: VecDeque<Arc<StoredFrame>>,
    history_bytes: u64,
    waiters: Vec<Waiter>,
    cameras: Vec<Camera>,
    next_camera_id: u64,
    next_trigger_id: u64,
    next_waiter_id: u64,
}

impl Inner {
    fn camera_names(&self) -> Vec<String> {
        self.cameras.iter().map(|c| c.name.to_string()).collect()
    }

    fn matching_cameras<'a>(&'a self, name: Option<&'a str>) -> impl Iterator<Item = &'a Camera> + 'a {
        self.cameras.iter().filter(move |c| name.is_none_or(|n| *c.name == *n))
    }

    fn no_camera(&self, name: Option<&str>) -> FrameError {
        FrameError::NoCamera { wanted: name.map(str::to_string), connected: self.camera_names() }
    }
}

/// Limits of the history and the fresh window.
#[derive(Debug, Clone, Copy)]
pub struct FrameLimits {
    /// Frames held at most.
    pub count: usize,
    /// Bytes of points held at most (the newest frame is always held).
    pub bytes: u64,
    /// Camera/daemon clock skew allowed.
    pub tolerance: Duration,
}

/// What became of an inserted frame, for the camera's acknowledgement.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Delivery {
    /// Waiting requests the frame was handed to.
    pub requests: u32,
    /// Why it qualified for a waiting request that it did not answer.
    pub skipped: Option<String>,
}

/// The frame history and the waiters, shared by the links.
#[derive(Debug)]
pub struct FrameStore {
    limits: FrameLimits,
    inner: Mutex<Inner>,
    /// Tickets are issued under `inner`'s lock, in hand-over order.
    order: Arc<ServeOrder>,
}

/// Keeps a camera registered for triggers while it lives.
#[derive(Debug)]
pub struct CameraRegistration {
    id: u64,
    name: Arc<str>,
    store: Arc<FrameStore>,
}

impl CameraRegistration {
    pub fn name(&self) -> &Arc<str> {
        &self.name
    }

    pub fn id(&self) -> u64 {
        self.id
    }
}

impl Drop for CameraRegistration {
    fn drop(&mut self) {
        let mut inner = self.store.lock();
        inner.cameras.retain(|c| c.id != self.id);
        let Inner { waiters, cameras, .. } = &mut *inner;
        // Waiters nobody can answer any more end now.
        waiters.retain_mut(|w| {
            let answerable = match &mut w.kind {
                WaitKind::Trigger { pending, .. } => {
                    pending.retain(|&c| c != self.id);
                    !pending.is_empty()
                }
                WaitKind::Next | WaitKind::Id(_) => {
                    cameras.iter().any(|c| w.camera.as_ref().is_none_or(|n| **n == *c.name))
                }
            };
            if !answerable {
                let error = match (&w.kind, w.skipped.take()) {
                    (WaitKind::Trigger { .. }, Some(reason)) => FrameError::Stale(reason),
                    _ => FrameError::CameraGone,
                };
                let (reply, _) = oneshot::channel();
                let _ = std::mem::replace(&mut w.reply, reply).send(Err(error));
            }
            answerable
        });
    }
}

impl FrameStore {
    pub fn new(limits: FrameLimits) -> Arc<Self> {
        let limits = FrameLimits { count: limits.count.max(1), ..limits };
        Arc::new(FrameStore { limits, inner: Mutex::new(Inner::default()), order: ServeOrder::new() })
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A panic while holding this lock cannot leave the maps half-updated
        // in a harmful way, so a poisoned lock is still usable.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Registers a camera by its Hello name; trigger ids to send it arrive
    /// on the returned receiver.
    pub fn attach_camera(self: &Arc<Self>, name: &str) -> (CameraRegistration, mpsc::Receiver<u64>) {
        let (tx, rx) = mpsc::channel(16);
        let name: Arc<str> = Arc::from(name);
        let mut inner = self.lock();
        inner.next_camera_id += 1;
        let id = inner.next_camera_id;
        inner.cameras.push(Camera { id, name: Arc::clone(&name), triggers: tx, latest_frame_id: None });
        (CameraRegistration { id, name, store: Arc::clone(self) }, rx)
    }

    pub fn cameras(&self) -> usize {
        self.lock().cameras.len()
    }

    /// The newest frame held: its id and capture time.
    pub fn latest(&self) -> Option<(u64, u64)> {
        self.lock().history.back().map(|f| (f.frame_id, f.capture_time_us))
    }

    /// Frames and bytes held now.
    pub fn held(&self) -> (usize, u64) {
        let inner = self.lock();
        (inner.history.len(), inner.history_bytes)
    }

    /// Checks a frame's capture time against the daemon's clock before it
    /// is stored: a time beyond the upload's start plus the tolerance is a
    /// camera clock that cannot be trusted.
    pub fn capture_time_problem(&self, capture_time_us: u64, upload_started_us: u64) -> Option<String> {
        let tolerance = self.limits.tolerance.as_micros() as u64;
        let ahead = capture_time_us.saturating_sub(upload_started_us);
        (ahead > tolerance).then(|| {
            format!(
                "its capture time is {} ms ahead of the daemon's clock (tolerance {} ms, \
                 server.capture_time_tolerance_ms); synchronise the camera's clock",
                ahead / 1000,
                tolerance / 1000
            )
        })
    }

    /// Why `frame` is not fresh for a request that arrived at
    /// `arrived`/`arrived_us`, if it is not.
    fn staleness(&self, frame: &StoredFrame, arrived: Instant, arrived_us: u64) -> Option<String> {
        let tolerance = self.limits.tolerance.as_micros() as u64;
        let id = frame.frame_id;
        if frame.upload_started <= arrived {
            return Some(format!("frame {id} was already uploading when the request arrived"));
        }
        if frame.capture_time_us.saturating_add(tolerance) < arrived_us {
            let before_ms = (arrived_us - frame.capture_time_us) / 1000;
            return Some(format!(
                "frame {id}'s capture time is {before_ms} ms before the request arrived (tolerance {} ms); \
                 a capture time of 0 means the camera sent none",
                tolerance / 1000
            ));
        }
        if frame.capture_time_us > frame.upload_started_us.saturating_add(tolerance) {
            let ahead_ms = (frame.capture_time_us - frame.upload_started_us) / 1000;
            return Some(format!(
                "frame {id}'s capture time is {ahead_ms} ms ahead of the daemon's clock (tolerance {} ms)",
                tolerance / 1000
            ));
        }
        None
    }

    /// Adds a received frame, hands it to the waiters it qualifies for,
    /// and says what became of it.
    pub fn insert(&self, camera_id: u64, frame: StoredFrame) -> Delivery {
        let frame = Arc::new(frame);
        let mut inner = self.lock();
        if let Some(c) = inner.cameras.iter_mut().find(|c| c.id == camera_id) {
            c.latest_frame_id = Some(frame.frame_id);
        }
        let mut delivery = Delivery::default();
        // In arrival order: each ticket is issued as the frame is handed.
        let mut waiters = std::mem::take(&mut inner.waiters);
        waiters.retain_mut(|w| {
            if w.reply.is_closed() {
                return false;
            }
            let from_wanted_camera = w.camera.as_ref().is_none_or(|n| *n == frame.camera);
            let verdict = match &mut w.kind {
                WaitKind::Id(id) => (*id == frame.frame_id && from_wanted_camera).then_some(None),
                WaitKind::Next => from_wanted_camera.then(|| self.staleness(&frame, w.arrived, w.arrived_us)),
                WaitKind::Trigger { trigger_id, pending } => {
                    if frame.trigger_id != *trigger_id || !pending.contains(&camera_id) {
                        None
                    } else {
                        pending.retain(|&c| c != camera_id);
                        match self.staleness(&frame, w.arrived, w.arrived_us) {
                            None => Some(None),
                            // Other cameras triggered may still answer fresh.
                            Some(reason) if !pending.is_empty() => Some(Some(reason)),
                            Some(reason) => {
                                let (reply, _) = oneshot::channel();
                                let _ = std::mem::replace(&mut w.reply, reply).send(Err(FrameError::Stale(format!(
                                    "the frame answering the request's trigger is not fresh: {reason}"
                                ))));
                                delivery.skipped = Some(reason);
                                return false;
                            }
                        }
                    }
                }
            };
            match verdict {
                Some(None) => {
                    let (reply, _) = oneshot::channel();
                    let handed = Handed { frame: Arc::clone(&frame), ticket: self.order.issue() };
                    // A request gone meanwhile drops its ticket with the
                    // message, giving its turn up.
                    let _ = std::mem::replace(&mut w.reply, reply).send(Ok(handed));
                    delivery.requests += 1;
                    false
                }
                Some(Some(reason)) => {
                    delivery.skipped = Some(reason.clone());
                    w.skipped = Some(reason);
                    true
                }
                None => true,
            }
        });
        inner.waiters = waiters;
        inner.history_bytes += frame.bytes();
        inner.history.push_back(frame);
        while inner.history.len() > 1
            && (inner.history.len() > self.limits.count || inner.history_bytes > self.limits.bytes)
        {
            if let Some(old) = inner.history.pop_front() {
                inner.history_bytes -= old.bytes();
            }
        }
        delivery
    }

    /// A frame answering `trigger_id` from `camera_id` was refused before
    /// it could be stored (its capture time cannot be trusted): that
    /// camera's answer to the trigger is spent.
    pub fn refused_answer(&self, camera_id: u64, trigger_id: u64, reason: &str) {
        if trigger_id == 0 {
            return;
        }
        let mut inner = self.lock();
        inner.waiters.retain_mut(|w| {
            let WaitKind::Trigger { trigger_id: t, pending } = &mut w.kind else { return true };
            if *t != trigger_id || !pending.contains(&camera_id) {
                return true;
            }
            pending.retain(|&c| c != camera_id);
            w.skipped = Some(reason.to_string());
            if !pending.is_empty() {
                return true;
            }
            let (reply, _) = oneshot::channel();
            let text = format!("the frame answering the request's trigger was refused: {reason}");
            let _ = std::mem::replace(&mut w.reply, reply).send(Err(FrameError::Stale(text)));
            false
        });
    }

    /// Starts the wait for `request`'s frame: a held frame by id at once,
    /// else a registered waiter (sending the triggers a Trigger request
    /// needs).
    pub fn request(self: &Arc<Self>, request: &FrameRequest) -> Result<FrameWait, FrameError> {
        let mut inner = self.lock();
        inner.waiters.retain(|w| !w.reply.is_closed());
        let name = request.camera.as_deref();
        let kind = match request.wanted {
            Wanted::FrameId(id) => {
                let held =
                    inner.history.iter().rev().find(|f| f.frame_id == id && name.is_none_or(|n| *f.camera == *n));
                if let Some(frame) = held {
                    let frame = Arc::clone(frame);
                    return Ok(FrameWait::ready(Handed { frame, ticket: self.order.issue() }));
                }
                // A frame newer than every one a matching camera has sent
                // may be on its way (still uploading): wait for it.
                let expected = inner.matching_cameras(name).any(|c| c.latest_frame_id.is_none_or(|latest| id > latest));
                if !expected {
                    return Err(FrameError::UnknownFrame(id));
                }
                WaitKind::Id(id)
            }
            Wanted::NextFrame => {
                if inner.matching_cameras(name).next().is_none() {
                    return Err(inner.no_camera(name));
                }
                WaitKind::Next
            }
            Wanted::Trigger => {
                let targets: Vec<(u64, mpsc::Sender<u64>)> =
                    inner.matching_cameras(name).map(|c| (c.id, c.triggers.clone())).collect();
                if targets.is_empty() {
                    return Err(inner.no_camera(name));
                }
                inner.next_trigger_id += 1;
                let trigger_id = inner.next_trigger_id;
                // A camera whose trigger queue is full or closed is skipped;
                // the others can still answer.
                let pending: Vec<u64> =
                    targets.into_iter().filter(|(_, tx)| tx.try_send(trigger_id).is_ok()).map(|(id, _)| id).collect();
                if pending.is_empty() {
                    return Err(FrameError::CameraGone);
                }
                WaitKind::Trigger { trigger_id, pending }
            }
        };
        let (trigger_id, frame_id) = match &kind {
            WaitKind::Trigger { trigger_id, .. } => (Some(*trigger_id), None),
            WaitKind::Id(id) => (None, Some(*id)),
            WaitKind::Next => (None, None),
        };
        inner.next_waiter_id += 1;
        let id = inner.next_waiter_id;
        let (tx, rx) = oneshot::channel();
        inner.waiters.push(Waiter {
            id,
            kind,
            camera: request.camera.as_deref().map(Arc::from),
            arrived: request.arrived,
            arrived_us: request.arrived_us,
            reply: tx,
            skipped: None,
        });
        Ok(FrameWait { state: WaitState::Pending { rx, store: Arc::clone(self), waiter: id }, trigger_id, frame_id })
    }

    /// Removes a waiter, returning why frames were skipped for it.
    fn cancel(&self, waiter: u64) -> Option<String> {
        let mut inner = self.lock();
        let at = inner.waiters.iter().position(|w| w.id == waiter)?;
        // `remove`, not `swap_remove`: the others keep their arrival order.
        inner.waiters.remove(at).skipped
    }

    /// Requests waiting for a frame.
    pub fn waiting(&self) -> usize {
        self.lock().waiters.len()
    }
}

#[derive(Debug)]
enum WaitState {
    Ready(Handed),
    Pending { rx: oneshot::Receiver<Result<Handed, FrameError>>, store: Arc<FrameStore>, waiter: u64 },
    Done,
}

/// A pending wait for a frame; dropping it withdraws the request at once.
#[derive(Debug)]
pub struct FrameWait {
    state: WaitState,
    /// The trigger sent, if any.
    pub trigger_id: Option<u64>,
    /// The frame id awaited, for a request naming one.
    frame_id: Option<u64>,
}

impl FrameWait {
    fn ready(handed: Handed) -> Self {
        FrameWait { state: WaitState::Ready(handed), trigger_id: None, frame_id: None }
    }

    /// The frame and the request's place in the serve order, or why no
    /// frame came within `timeout`.
    pub async fn wait(mut self, timeout: Duration) -> Result<Handed, FrameError> {
        match std::mem::replace(&mut self.state, WaitState::Done) {
            WaitState::Ready(handed) => Ok(handed),
            WaitState::Done => Err(FrameError::CameraGone),
            WaitState::Pending { rx, store, waiter } => match tokio::time::timeout(timeout, rx).await {
                Ok(Ok(result)) => result,
                Ok(Err(_)) => Err(FrameError::CameraGone),
                Err(_) => {
                    let skipped = store.cancel(waiter);
                    match self.frame_id {
                        Some(id) => Err(FrameError::NotArrived { id, ms: timeout.as_millis() }),
                        None => Err(FrameError::Timeout { ms: timeout.as_millis(), skipped }),
                    }
                }
            },
        }
    }
}

impl Drop for FrameWait {
    fn drop(&mut self) {
        if let WaitState::Pending { store, waiter, .. } = &self.state {
            store.cancel(*waiter);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: FrameLimits = FrameLimits { count: 2, bytes: 1 << 20, tolerance: Duration::from_millis(200) };

    fn frame_at(id: u64, trigger: u64, points: usize, upload_started: Instant, capture_time_us: u64) -> StoredFrame {
        let cloud = PointCloud::organized(points, 1, vec![[1.0, 2.0, 3.0]; points]).unwrap();
        StoredFrame {
            frame_id: id,
            trigger_id: trigger,
            capture_time_us,
            camera: Arc::from("cam"),
            cloud: Arc::new(cloud),
            input: FrameInput::default(),
            upload_started,
            upload_started_us: wall_clock_us(),
            arrived: Instant::now(),
        }
    }

    /// A frame captured and uploaded now.
    fn frame(id: u64, trigger: u64) -> StoredFrame {
        frame_at(id, trigger, 1, Instant::now(), wall_clock_us())
    }

    const SECOND: Duration = Duration::from_secs(1);

    #[tokio::test]
    async fn next_frame_ignores_frames_from_before_the_request() {
        let store = FrameStore::new(LIMITS);
        let (cam, _rx) = store.attach_camera("cam");
        store.insert(cam.id(), frame(1, 0));
        let wait = store.request(&FrameRequest::now(Wanted::NextFrame, None)).unwrap();
        store.insert(cam.id(), frame(2, 0));
        assert_eq!(wait.wait(SECOND).await.unwrap().frame.frame_id, 2);
    }

    #[tokio::test]
    async fn a_frame_uploading_when_the_request_came_does_not_qualify() {
        let store = FrameStore::new(LIMITS);
        let (cam, _rx) = store.attach_camera("cam");
        let upload_started = Instant::now();
        let request = FrameRequest::now(Wanted::NextFrame, None);
        let wait = store.request(&request).unwrap();
        let delivery = store.insert(cam.id(), frame_at(1, 0, 1, upload_started, request.arrived_us + 1000));
        assert_eq!(delivery.requests, 0);
        assert!(delivery.skipped.unwrap().contains("already uploading"));
        let e = wait.wait(Duration::from_millis(20)).await.unwrap_err();
        assert!(matches!(&e, FrameError::Timeout { skipped: Some(s), .. } if s.contains("already uploading")), "{e}");
    }

    #[tokio::test]
    async fn capture_times_outside_the_window_do_not_qualify() {
        let store = FrameStore::new(LIMITS);
        let (cam, mut rx) = store.attach_camera("cam");
        let now = wall_clock_us();
        for stamp in [0, now - 60_000_000, now - 300_000] {
            let wait = store.request(&FrameRequest::now(Wanted::Trigger, None)).unwrap();
            let trigger = rx.recv().await.unwrap();
            store.insert(cam.id(), frame_at(trigger, trigger, 1, Instant::now(), stamp));
            let e = wait.wait(SECOND).await.unwrap_err();
            assert!(matches!(&e, FrameError::Stale(s) if s.contains("before the request")), "{stamp}: {e}");
        }
        assert!(store.capture_time_problem(now + 3_600_000_000, now).unwrap().contains("ahead"));
        assert_eq!(store.capture_time_problem(now + 100_000, now), None);
        // Within the tolerance is fresh.
        let wait = store.request(&FrameRequest::now(Wanted::Trigger, None)).unwrap();
        let trigger = rx.recv().await.unwrap();
        store.insert(cam.id(), frame_at(9, trigger, 1, Instant::now(), wall_clock_us() - 150_000));
        assert_eq!(wait.wait(SECOND).await.unwrap().frame.frame_id, 9);
    }

    #[tokio::test]
    async fn triggers_are_answered_only_by_their_frame() {
        let store = FrameStore::new(LIMITS);
        let (cam, mut rx) = store.attach_camera("cam");
        let wait = store.request(&FrameRequest::now(Wanted::Trigger, None)).unwrap();
        let id = rx.recv().await.unwrap();
        store.insert(cam.id(), frame(5, 0));
        store.insert(cam.id(), frame(6, id));
        assert_eq!(wait.wait(SECOND).await.unwrap().frame.frame_id, 6);
    }

    #[tokio::test]
    async fn unnamed_triggers_go_to_every_camera_and_named_ones_to_that_camera() {
        let store = FrameStore::new(LIMITS);
        let (left, mut left_rx) = store.attach_camera("left");
        let (_right, mut right_rx) = store.attach_camera("right");
        let wait = store.request(&FrameRequest::now(Wanted::Trigger, None)).unwrap();
        let t = left_rx.recv().await.unwrap();
        assert_eq!(right_rx.recv().await.unwrap(), t, "both cameras got the trigger");
        store.insert(left.id(), frame(1, t));
        assert_eq!(wait.wait(SECOND).await.unwrap().frame.frame_id, 1);

        let named = store.request(&FrameRequest::now(Wanted::Trigger, Some("right".into()))).unwrap();
        assert!(right_rx.recv().await.is_some());
        assert!(left_rx.try_recv().is_err(), "the left camera was not triggered");
        drop(named);
        let e = store.request(&FrameRequest::now(Wanted::Trigger, Some("top".into()))).unwrap_err();
        assert!(e.to_string().contains("\"top\"") && e.to_string().contains("left"), "{e}");
    }

    #[tokio::test]
    async fn a_trigger_survives_one_camera_leaving_while_another_can_answer() {
        let store = FrameStore::new(LIMITS);
        let (a, mut a_rx) = store.attach_camera("a");
        let (b, _b_rx) = store.attach_camera("b");
        let wait = store.request(&FrameRequest::now(Wanted::Trigger, None)).unwrap();
        let t = a_rx.recv().await.unwrap();
        drop(b);
        store.insert(a.id(), frame(3, t));
        assert_eq!(wait.wait(SECOND).await.unwrap().frame.frame_id, 3);
        let wait = store.request(&FrameRequest::now(Wanted::Trigger, None)).unwrap();
        drop(a);
        assert_eq!(wait.wait(SECOND).await.unwrap_err(), FrameError::CameraGone);
    }

    #[tokio::test]
    async fn history_is_bounded_in_count_and_bytes_and_ids_may_be_awaited() {
        let store = FrameStore::new(LIMITS);
        assert!(matches!(store.request(&FrameRequest::now(Wanted::Trigger, None)), Err(FrameError::NoCamera { .. })));
        assert!(matches!(store.request(&FrameRequest::now(Wanted::NextFrame, None)), Err(FrameError::NoCamera { .. })));
        let (cam, _rx) = store.attach_camera("cam");
        for id in 1..=3 {
            store.insert(cam.id(), frame(id, 0));
        }
        assert_eq!(store.held().0, 2);
        let by_id = |id| store.request(&FrameRequest::now(Wanted::FrameId(id), None));
        assert_eq!(by_id(1).unwrap_err(), FrameError::UnknownFrame(1));
        assert_eq!(by_id(3).unwrap().wait(SECOND).await.unwrap().frame.frame_id, 3);
        // A newer id than the camera has sent is awaited.
        let later = by_id(4).unwrap();
        store.insert(cam.id(), frame(4, 0));
        assert_eq!(later.wait(SECOND).await.unwrap().frame.frame_id, 4);
        // 40,000 points of 12 bytes: 480 kB each, two of them fill 1 MiB.
        for id in 5..=7 {
            store.insert(cam.id(), frame_at(id, 0, 40_000, Instant::now(), wall_clock_us()));
        }
        assert_eq!(store.held(), (2, 960_000));
        assert_eq!(store.latest().map(|l| l.0), Some(7));
    }

    #[tokio::test]
    async fn a_dropped_wait_is_withdrawn_at_once() {
        let store = FrameStore::new(LIMITS);
        let (_cam, _rx) = store.attach_camera("cam");
        let wait = store.request(&FrameRequest::now(Wanted::NextFrame, None)).unwrap();
        assert_eq!(store.waiting(), 1);
        drop(wait);
        assert_eq!(store.waiting(), 0);
    }
}
