//! Graceful shutdown: one broadcast tells every handler to stop, and each
//! handler holds a completion guard so the server can wait until all of
//! them have finished their work in flight.
//!
//! A [`StopSignal`] is set before the broadcast goes out, so a request
//! whose frame wait ends because the camera link closed for the shutdown
//! can tell that apart from a camera that left on its own, and answer
//! "shutting down" rather than "camera disconnected".

use tokio::sync::{broadcast, mpsc, watch};

/// A handler's view of the shutdown signal.
#[derive(Debug)]
pub struct Shutdown {
    signalled: bool,
    notify: broadcast::Receiver<()>,
    stopping: StopSignal,
    /// Dropped when the handler ends; the server waits for all of them.
    _done: mpsc::Sender<()>,
}

/// Whether the server is stopping; cheap to clone into request tasks.
#[derive(Debug, Clone)]
pub struct StopSignal(watch::Receiver<bool>);

impl StopSignal {
    /// True once the shutdown has begun.
    pub fn is_stopping(&self) -> bool {
        *self.0.borrow()
    }

    /// Completes once the shutdown has begun (or the server is gone).
    pub async fn stopped(&mut self) {
        let _ = self.0.wait_for(|stopping| *stopping).await;
    }
}

impl Shutdown {
    pub fn new(notify: broadcast::Receiver<()>, stopping: StopSignal, done: mpsc::Sender<()>) -> Self {
        Shutdown { signalled: false, notify, stopping, _done: done }
    }

    /// The stop flag, for tasks that outlive one `recv`.
    pub fn stop_signal(&self) -> StopSignal {
        self.stopping.clone()
    }

    pub fn is_signalled(&self) -> bool {
        self.signalled
    }

    /// Waits for the signal; returns at once if it was already received.
    pub async fn recv(&mut self) {
        if self.signalled {
            return;
        }
        // Either a message or the sender's drop means "stop".
        let _ = self.notify.recv().await;
        self.signalled = true;
    }
}

/// The server's side: signals the handlers and waits for them.
#[derive(Debug)]
pub struct ShutdownController {
    notify: broadcast::Sender<()>,
    stopping: watch::Sender<bool>,
    done_tx: mpsc::Sender<()>,
    done_rx: mpsc::Receiver<()>,
}

impl Default for ShutdownController {
    fn default() -> Self {
        Self::new()
    }
}

impl ShutdownController {
    pub fn new() -> Self {
        let (notify, _) = broadcast::channel(1);
        let (stopping, _) = watch::channel(false);
        let (done_tx, done_rx) = mpsc::channel(1);
        ShutdownController { notify, stopping, done_tx, done_rx }
    }

    /// A handle for one more handler.
    pub fn handle(&self) -> Shutdown {
        Shutdown::new(self.notify.subscribe(), StopSignal(self.stopping.subscribe()), self.done_tx.clone())
    }

    /// Signals every handler, then waits until all have ended or `grace`
    /// passes; returns false when the grace ran out.
    pub async fn shutdown(self, grace: std::time::Duration) -> bool {
        let ShutdownController { notify, stopping, done_tx, mut done_rx } = self;
        // The flag first: every handler sees it by the time it hears the
        // broadcast (or a camera link closed by it).
        stopping.send_replace(true);
        let _ = notify.send(());
        drop(notify);
        drop(done_tx);
        tokio::time::timeout(grace, done_rx.recv()).await.is_ok()
    }
}
