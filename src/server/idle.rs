//! Handing memory back when the cell is idle. The daemon keeps freed
//! memory in the process while it works (see the CLI's memory policy:
//! frame after frame reuses the same buffers), so after a burst of frames
//! and plans the resident size stays at its peak. Once nothing has
//! happened for `server.idle_trim_ms`, the allocator is asked to return
//! its free memory to the system.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::time::Instant;
use tracing::debug;

/// Tracks activity and trims the heap after an idle spell.
#[derive(Debug)]
pub struct IdleTrim {
    idle: Duration,
    /// The last activity, and whether a timer task is running.
    state: Mutex<(Instant, bool)>,
    /// Idle spells that ended in a trim.
    trims: AtomicU64,
}

impl IdleTrim {
    /// Trims after `idle` without activity; zero never trims.
    pub fn new(idle: Duration) -> Arc<Self> {
        Arc::new(IdleTrim { idle, state: Mutex::new((Instant::now(), false)), trims: AtomicU64::new(0) })
    }

    /// Idle spells that ended in a trim so far.
    pub fn trims(&self) -> u64 {
        self.trims.load(Ordering::Relaxed)
    }

    /// Records activity (a frame, a plan). Arms the timer if it is not
    /// running; needs a tokio runtime, and does nothing outside one.
    pub fn touch(self: &Arc<Self>) {
        if self.idle.is_zero() {
            return;
        }
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        state.0 = Instant::now();
        if state.1 {
            return;
        }
        let Ok(runtime) = tokio::runtime::Handle::try_current() else {
            return;
        };
        state.1 = true;
        let this = Arc::clone(self);
        runtime.spawn(async move { this.timer().await });
    }

    async fn timer(self: Arc<Self>) {
        loop {
            let last = self.state.lock().unwrap_or_else(|p| p.into_inner()).0;
            tokio::time::sleep_until(last + self.idle).await;
            let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
            if state.0 == last {
                state.1 = false;
                drop(state);
                let released = trim();
                self.trims.fetch_add(1, Ordering::Relaxed);
                debug!(released, "idle: freed memory handed back to the system");
                return;
            }
        }
    }
}

/// Returns the allocator's free memory to the system; true when some was.
pub fn trim() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: malloc_trim only walks the allocator's own free lists;
        // it is thread-safe and has no preconditions.
        unsafe { libc::malloc_trim(0) == 1 }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn trims_once_per_idle_spell_and_never_while_busy() {
        let busy = IdleTrim::new(Duration::from_secs(10));
        for _ in 0..5 {
            busy.touch();
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        assert_eq!(busy.trims(), 0, "never within the idle time of the last activity");

        let idle = IdleTrim::new(Duration::from_millis(50));
        idle.touch();
        tokio::time::sleep(Duration::from_millis(500)).await;
        assert_eq!(idle.trims(), 1);
        tokio::time::sleep(Duration::from_millis(300)).await;
        assert_eq!(idle.trims(), 1, "one trim per idle spell");
        idle.touch();
        tokio::time::sleep(Duration::from_millis(500)).await;
        assert_eq!(idle.trims(), 2);

        let never = IdleTrim::new(Duration::ZERO);
        never.touch();
        tokio::time::sleep(Duration::from_millis(100)).await;
        assert_eq!(never.trims(), 0);
    }
}
