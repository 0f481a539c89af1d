//! The plan queue: a bounded number of plan jobs, queued or running, on a
//! dedicated rayon pool so the pipeline never runs on tokio's threads.
//! A slot is reserved when a request arrives, so a full queue is reported
//! at once rather than after the frame wait.
//!
//! Fair order: plans run one at a time on the whole pool, in the order
//! their frames became ready (first in, first out). Handing every ready
//! plan to the pool at once starved old requests: the pipeline's own
//! parallel loops make a pool thread wait for its helpers, and a waiting
//! rayon thread runs any other job meanwhile, including a younger plan
//! from the pool's queue. The older plan cannot resume until that younger
//! one (and whatever it picked up in turn) has finished, so under steady
//! load a plan could be buried for seconds while younger ones were
//! answered. With one plan in the pool at a time there is nothing else to
//! pick up, every thread helps the plan at the head of the queue, and a
//! request waits for at most the plans whose frames were ready before its
//! own: no more than `server.plan_queue_depth - 1` of them.

use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::{OwnedSemaphorePermit, Semaphore, oneshot};

use crate::cloud::PointCloud;
use crate::pipeline::{Plan, PlanError, PlanRequest, PlanTrace, Planner};

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
    /// One permit: the plan on the pool. Tokio's semaphore hands permits
    /// out in the order they were asked for, which is the fair order.
    turn: Arc<Semaphore>,
    depth: usize,
}

/// A reserved place in the queue, released when dropped.
#[derive(Debug)]
pub struct JobSlot {
    permit: OwnedSemaphorePermit,
    pool: Arc<rayon::ThreadPool>,
    planner: Arc<Planner>,
    turn: Arc<Semaphore>,
}

/// How long a job waited for its turn and how long it ran.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JobTimes {
    /// From its frame being ready to its plan starting.
    pub queued: Duration,
    /// The plan itself, on the pool.
    pub planning: Duration,
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
        Ok(Jobs {
            pool: Arc::new(pool),
            planner: Arc::new(planner),
            slots: Arc::new(Semaphore::new(depth)),
            turn: Arc::new(Semaphore::new(1)),
            depth,
        })
    }

    /// Reserves a slot, or says the queue is full.
    pub fn reserve(&self) -> Result<JobSlot, Busy> {
        let permit = Arc::clone(&self.slots).try_acquire_owned().map_err(|_| Busy { depth: self.depth })?;
        Ok(JobSlot {
            permit,
            pool: Arc::clone(&self.pool),
            planner: Arc::clone(&self.planner),
            turn: Arc::clone(&self.turn),
        })
    }

    /// The queue's depth.
    pub fn depth(&self) -> usize {
        self.depth
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
    /// Plans `cloud` on the pool once every plan whose frame was ready
    /// earlier has run; the slot is freed when the plan is done. Once
    /// started the job holds its slot itself, so it stays taken while the
    /// pipeline runs even if the caller stops waiting; a caller that stops
    /// waiting before the job's turn frees the slot at once. A frame only
    /// this job still holds is planned by value, converted in place
    /// ([`Planner::plan_owned`]); one the frame store keeps is borrowed.
    pub async fn run(self, cloud: Arc<PointCloud>, request: PlanRequest) -> (Result<Plan, JobError>, JobTimes) {
        let planner = Arc::clone(&self.planner);
        let plan = move || match Arc::try_unwrap(cloud) {
            Ok(owned) => planner.plan_owned(owned, &request),
            Err(shared) => planner.plan(&shared, &request),
        };
        let (outcome, times) = self.execute(plan).await;
        (outcome.and_then(|r| Ok(r?)), times)
    }

    /// [`JobSlot::run`], recording what each stage found; the trace is
    /// lost only when the pipeline panicked.
    pub async fn run_traced(
        self,
        cloud: Arc<PointCloud>,
        request: PlanRequest,
    ) -> (Result<Plan, JobError>, Option<PlanTrace>, JobTimes) {
        let planner = Arc::clone(&self.planner);
        let (outcome, times) = self.execute(move || planner.plan_traced(&cloud, &request)).await;
        match outcome {
            Ok((result, trace)) => (result.map_err(JobError::from), Some(trace), times),
            Err(e) => (Err(e), None, times),
        }
    }

    /// Runs `work` on the pool in its turn, holding the slot until done.
    async fn execute<T: Send + 'static>(
        self,
        work: impl FnOnce() -> T + Send + 'static,
    ) -> (Result<T, JobError>, JobTimes) {
        let ready = Instant::now();
        let JobSlot { permit, pool, turn, .. } = self;
        // The semaphore is never closed, so the acquire cannot fail.
        let Ok(turn) = turn.acquire_owned().await else {
            return (Err(JobError::Panicked), JobTimes::default());
        };
        let started = Instant::now();
        let (tx, rx) = oneshot::channel();
        pool.spawn(move || {
            let outcome = std::panic::catch_unwind(AssertUnwindSafe(work));
            drop(turn);
            drop(permit);
            let _ = tx.send(outcome);
        });
        let outcome = rx.await.map_err(|_| JobError::Panicked).and_then(|r| r.map_err(|_| JobError::Panicked));
        (outcome, JobTimes { queued: started - ready, planning: started.elapsed() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use rayon::prelude::*;
    use std::time::Duration;

    /// A job that spends its time in rayon joins, as the pipeline does:
    /// its threads wait on each other and look for other work meanwhile.
    fn parallel_work() -> u64 {
        (0..48u64)
            .into_par_iter()
            .map(|i| {
                std::thread::sleep(Duration::from_millis(4));
                i
            })
            .sum()
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn plans_finish_in_the_order_their_frames_became_ready() {
        let jobs = Jobs::new(Planner::new(Config::default()), 16, 2).unwrap();
        let (done_tx, mut done_rx) = tokio::sync::mpsc::unbounded_channel();
        let mut tasks = Vec::new();
        for k in 0..8 {
            let slot = jobs.reserve().unwrap();
            let done = done_tx.clone();
            tasks.push(tokio::spawn(async move {
                slot.execute(parallel_work).await.0.unwrap();
                let _ = done.send(k);
            }));
            // Each frame becomes ready a little after the one before.
            tokio::time::sleep(Duration::from_millis(15)).await;
        }
        for t in tasks {
            t.await.unwrap();
        }
        drop(done_tx);
        let mut order = Vec::new();
        while let Some(k) = done_rx.recv().await {
            order.push(k);
        }
        assert_eq!(order, (0..8).collect::<Vec<_>>(), "a plan was overtaken by younger ones");
        assert!(jobs.is_empty());
    }
}
