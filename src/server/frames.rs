//! The frames the daemon holds and the requests waiting for one.
//!
//! Safety rule: a plan never uses a frame captured before its request
//! arrived unless the request names the frame's id. So a waiter for the
//! *next* frame is only ever resolved by a frame inserted after the waiter
//! was registered, and a trigger waiter only by the frame carrying its
//! trigger id. Old frames are reachable by id alone.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use tokio::sync::{mpsc, oneshot};

use crate::cloud::PointCloud;

/// A frame received from the camera.
#[derive(Debug)]
pub struct StoredFrame {
    pub frame_id: u64,
    /// The trigger it answers, or 0.
    pub trigger_id: u64,
    /// Camera clock, microseconds since the Unix epoch.
    pub capture_time_us: u64,
    pub cloud: Arc<PointCloud>,
    /// When its last byte arrived.
    pub arrived: Instant,
}

/// Why no fresh frame can be had.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// No camera is connected to answer a trigger or push a frame.
    #[error("no camera is connected, so no fresh frame can be captured")]
    NoCamera,
    /// The camera went away before answering.
    #[error("the camera disconnected before sending the frame")]
    CameraGone,
    /// The wait ran out.
    #[error("no fresh frame arrived within {0} ms")]
    Timeout(u128),
    /// The named frame is not in the history.
    #[error("frame {0} is not held by the daemon (unknown, or older than the frame history)")]
    UnknownFrame(u64),
}

type Waiter = oneshot::Sender<Arc<StoredFrame>>;

#[derive(Debug)]
struct Camera {
    id: u64,
    triggers: mpsc::Sender<u64>,
}

#[derive(Debug, Default)]
struct Inner {
    history: VecDeque<Arc<StoredFrame>>,
    next_waiters: Vec<Waiter>,
    trigger_waiters: HashMap<u64, Waiter>,
    cameras: Vec<Camera>,
    next_camera_id: u64,
    next_trigger_id: u64,
}

/// The frame history and the waiters, shared by the links.
#[derive(Debug)]
pub struct FrameStore {
    capacity: usize,
    inner: Mutex<Inner>,
}

/// Keeps a camera registered for triggers while it lives.
#[derive(Debug)]
pub struct CameraRegistration {
    id: u64,
    store: Arc<FrameStore>,
}

impl Drop for CameraRegistration {
    fn drop(&mut self) {
        let mut inner = self.store.lock();
        inner.cameras.retain(|c| c.id != self.id);
        if inner.cameras.is_empty() {
            // Nobody can answer the pending triggers any more.
            inner.trigger_waiters.clear();
            inner.next_waiters.clear();
        }
    }
}

impl FrameStore {
    /// A store keeping the `capacity` most recent frames.
    pub fn new(capacity: usize) -> Arc<Self> {
        Arc::new(FrameStore { capacity: capacity.max(1), inner: Mutex::new(Inner::default()) })
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A panic while holding this lock cannot leave the maps half-updated
        // in a harmful way, so a poisoned lock is still usable.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Registers a camera; trigger ids to send it arrive on the returned
    /// receiver. The newest camera gets the triggers.
    pub fn attach_camera(self: &Arc<Self>) -> (CameraRegistration, mpsc::Receiver<u64>) {
        let (tx, rx) = mpsc::channel(16);
        let mut inner = self.lock();
        inner.next_camera_id += 1;
        let id = inner.next_camera_id;
        inner.cameras.push(Camera { id, triggers: tx });
        (CameraRegistration { id, store: Arc::clone(self) }, rx)
    }

    pub fn camera_connected(&self) -> bool {
        !self.lock().cameras.is_empty()
    }

    /// Adds a received frame and hands it to the waiters it satisfies.
    pub fn insert(&self, frame: StoredFrame) {
        let frame = Arc::new(frame);
        let mut inner = self.lock();
        if frame.trigger_id != 0
            && let Some(w) = inner.trigger_waiters.remove(&frame.trigger_id)
        {
            let _ = w.send(Arc::clone(&frame));
        }
        for w in inner.next_waiters.drain(..) {
            let _ = w.send(Arc::clone(&frame));
        }
        inner.history.push_back(frame);
        while inner.history.len() > self.capacity {
            inner.history.pop_front();
        }
    }

    /// The held frame with this id (the newest, if a camera reused it).
    pub fn by_id(&self, frame_id: u64) -> Result<Arc<StoredFrame>, FrameError> {
        let inner = self.lock();
        inner.history.iter().rev().find(|f| f.frame_id == frame_id).cloned().ok_or(FrameError::UnknownFrame(frame_id))
    }

    /// Waits for the first frame inserted after this call.
    pub fn next_frame(&self) -> Result<FrameWait, FrameError> {
        let mut inner = self.lock();
        if inner.cameras.is_empty() {
            return Err(FrameError::NoCamera);
        }
        let (tx, rx) = oneshot::channel();
        inner.next_waiters.retain(|w| !w.is_closed());
        inner.next_waiters.push(tx);
        Ok(FrameWait { rx, trigger_id: None })
    }

    /// Sends a trigger to the camera and waits for the frame answering it.
    pub fn trigger(&self) -> Result<FrameWait, FrameError> {
        let mut inner = self.lock();
        inner.trigger_waiters.retain(|_, w| !w.is_closed());
        let Some(camera) = inner.cameras.last() else {
            return Err(FrameError::NoCamera);
        };
        let sender = camera.triggers.clone();
        inner.next_trigger_id += 1;
        let trigger_id = inner.next_trigger_id;
        let (tx, rx) = oneshot::channel();
        inner.trigger_waiters.insert(trigger_id, tx);
        if sender.try_send(trigger_id).is_err() {
            inner.trigger_waiters.remove(&trigger_id);
            return Err(FrameError::CameraGone);
        }
        Ok(FrameWait { rx, trigger_id: Some(trigger_id) })
    }
}

/// A pending wait for a fresh frame.
#[derive(Debug)]
pub struct FrameWait {
    rx: oneshot::Receiver<Arc<StoredFrame>>,
    /// The trigger sent, if any.
    pub trigger_id: Option<u64>,
}

impl FrameWait {
    /// The frame, or why none came within `timeout`.
    pub async fn wait(self, timeout: std::time::Duration) -> Result<Arc<StoredFrame>, FrameError> {
        match tokio::time::timeout(timeout, self.rx).await {
            Ok(Ok(frame)) => Ok(frame),
            Ok(Err(_)) => Err(FrameError::CameraGone),
            Err(_) => Err(FrameError::Timeout(timeout.as_millis())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(id: u64, trigger: u64) -> StoredFrame {
        let cloud = PointCloud::organized(1, 1, vec![[1.0, 2.0, 3.0]]).unwrap();
        StoredFrame {
            frame_id: id,
            trigger_id: trigger,
            capture_time_us: 0,
            cloud: Arc::new(cloud),
            arrived: Instant::now(),
        }
    }

    #[tokio::test]
    async fn next_frame_ignores_frames_from_before_the_request() {
        let store = FrameStore::new(2);
        let (_cam, _rx) = store.attach_camera();
        store.insert(frame(1, 0));
        let wait = store.next_frame().unwrap();
        store.insert(frame(2, 0));
        assert_eq!(wait.wait(std::time::Duration::from_secs(1)).await.unwrap().frame_id, 2);
    }

    #[tokio::test]
    async fn triggers_are_answered_only_by_their_frame() {
        let store = FrameStore::new(2);
        let (_cam, mut rx) = store.attach_camera();
        let wait = store.trigger().unwrap();
        let id = rx.recv().await.unwrap();
        store.insert(frame(5, 0));
        store.insert(frame(6, id));
        assert_eq!(wait.wait(std::time::Duration::from_secs(1)).await.unwrap().frame_id, 6);
    }

    #[tokio::test]
    async fn history_is_bounded_and_cameras_are_needed() {
        let store = FrameStore::new(2);
        assert_eq!(store.trigger().unwrap_err(), FrameError::NoCamera);
        assert_eq!(store.next_frame().unwrap_err(), FrameError::NoCamera);
        for id in 1..=3 {
            store.insert(frame(id, 0));
        }
        assert_eq!(store.by_id(1).unwrap_err(), FrameError::UnknownFrame(1));
        assert_eq!(store.by_id(3).unwrap().frame_id, 3);
        let (cam, _rx) = store.attach_camera();
        let wait = store.trigger().unwrap();
        drop(cam);
        assert_eq!(wait.wait(std::time::Duration::from_secs(1)).await.unwrap_err(), FrameError::CameraGone);
    }
}
