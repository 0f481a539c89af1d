//! The plan queue: a bounded number of plan jobs, queued or running, on a
//! dedicated rayon pool so the pipeline never runs on tokio's threads.
//! A slot is reserved when a request arrives, so a full queue is reported
//! at once rather than after the frame wait.

use std::panic::AssertUnwindSafe;
use std::sync::Arc;

use tokio::sync::{OwnedSemaphorePermit, Semaphore, oneshot};

use crate::cloud::PointCloud;
use crate::pipeline::{Plan, PlanError, PlanRequest, Planner};

/// Why a plan job did not produce a plan.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The pipeline found no seam.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// The pipeline panicked; a bug, reported as an internal error.
    #[error("the planning pipeline failed internally")]
    Panicked,
}

/// The rayon pool could not be built.
#[derive(Debug, thiserror::Error)]
#[error("cannot start the pipeline's thread pool: {0}")]
pub struct PoolError(String);

/// The queue was full.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the plan queue is full ({depth} plans queued or running); retry later")]
pub struct Busy {
    pub depth: usize,
}

/// The bounded plan queue and its pool.
#[derive(Debug)]
pub struct Jobs {
    pool: Arc<rayon::ThreadPool>,
    planner: Arc<Planner>,
    slots: Arc<Semaphore>,
    depth: usize,
}

/// A reserved place in the queue, released when dropped.
#[derive(Debug)]
pub struct JobSlot {
    permit: OwnedSemaphorePermit,
    pool: Arc<rayon::ThreadPool>,
    planner: Arc<Planner>,
}

impl Jobs {
    /// A queue of `depth` jobs over a pool of `threads` (0 = every core).
    pub fn new(planner: Planner, depth: usize, threads: usize) -> Result<Self, PoolError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("plan-{i}"))
            .build()
            .map_err(|e| PoolError(e.to_string()))?;
        let depth = depth.max(1);
        Ok(Jobs { pool: Arc::new(pool), planner: Arc::new(planner), slots: Arc::new(Semaphore::new(depth)), depth })
    }

    /// Reserves a slot, or says the queue is full.
    pub fn reserve(&self) -> Result<JobSlot, Busy> {
        let permit = Arc::clone(&self.slots).try_acquire_owned().map_err(|_| Busy { depth: self.depth })?;
        Ok(JobSlot { permit, pool: Arc::clone(&self.pool), planner: Arc::clone(&self.planner) })
    }

    /// Jobs queued or running.
    pub fn len(&self) -> usize {
        self.depth - self.slots.available_permits()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn planner(&self) -> &Planner {
        &self.planner
    }
}

impl JobSlot {
    /// Plans `cloud` on the pool; the slot is freed when the plan is done.
    /// The slot is held by the job itself, so it stays taken while the
    /// pipeline runs even if the caller stops waiting.
    pub async fn run(self, cloud: Arc<PointCloud>, request: PlanRequest) -> Result<Plan, JobError> {
        let (tx, rx) = oneshot::channel();
        let JobSlot { permit, pool, planner } = self;
        pool.spawn(move || {
            let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| planner.plan(&cloud, &request)));
            drop(permit);
            let _ = tx.send(outcome);
        });
        let outcome = rx.await.map_err(|_| JobError::Panicked)?;
        match outcome {
            Ok(result) => Ok(result?),
            Err(_) => Err(JobError::Panicked),
        }
    }
}
