//! Graceful shutdown: one broadcast tells every handler to stop, and each
//! handler holds a completion guard so the server can wait until all of
//! them have finished their work in flight.

use tokio::sync::{broadcast, mpsc};

/// A handler's view of the shutdown signal.
#[derive(Debug)]
pub struct Shutdown {
    signalled: bool,
    notify: broadcast::Receiver<()>,
    /// Dropped when the handler ends; the server waits for all of them.
    _done: mpsc::Sender<()>,
}

impl Shutdown {
    pub fn new(notify: broadcast::Receiver<()>, done: mpsc::Sender<()>) -> Self {
        Shutdown { signalled: false, notify, _done: done }
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
        let (done_tx, done_rx) = mpsc::channel(1);
        ShutdownController { notify, done_tx, done_rx }
    }

    /// A handle for one more handler.
    pub fn handle(&self) -> Shutdown {
        Shutdown::new(self.notify.subscribe(), self.done_tx.clone())
    }

    /// Signals every handler, then waits until all have ended or `grace`
    /// passes; returns false when the grace ran out.
    pub async fn shutdown(self, grace: std::time::Duration) -> bool {
        let ShutdownController { notify, done_tx, mut done_rx } = self;
        let _ = notify.send(());
        drop(notify);
        drop(done_tx);
        tokio::time::timeout(grace, done_rx.recv()).await.is_ok()
    }
}
