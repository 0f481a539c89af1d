//! The plan queue: a bounded number of plan jobs, queued or running, on a
//! dedicated rayon pool so the pipeline never runs on tokio's threads.
//! A slot is reserved when a request arrives, so a full queue is reported
//! at once rather than after the frame wait.
//!
//! Fair order: plans run one at a time on the whole pool, in the order
//! their frames became ready (first in, first out), and the requests one
//! frame answers in the order they arrived: each job waits for its
//! [`Ticket`]'s turn, the place the frame store gave it when it handed
//! the frame over ([`super::serve_order`]). Handing every ready
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

use std::borrow::Cow;
use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::{OwnedSemaphorePermit, Semaphore, oneshot};

use super::serve_order::Ticket;
use crate::cloud::PointCloud;
use crate::pipeline::{Deadline, Plan, PlanError, PlanRequest, PlanTrace, Planner};

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
        Ok(Jobs { pool: Arc::new(pool), planner: Arc::new(planner), slots: Arc::new(Semaphore::new(depth)), depth })
    }

    /// Reserves a slot, or says the queue is full.
    pub fn reserve(&self) -> Result<JobSlot, Busy> {
        let permit = Arc::clone(&self.slots).try_acquire_owned().map_err(|_| Busy { depth: self.depth })?;
        Ok(JobSlot { permit, pool: Arc::clone(&self.pool), planner: Arc::clone(&self.planner) })
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
    /// Plans `cloud` on the pool at `ticket`'s turn, once every plan
    /// before it in the serve order has run; the slot is freed when the
    /// plan is done. Once
    /// started the job holds its slot itself, so it stays taken while the
    /// pipeline runs even if the caller stops waiting; a caller that stops
    /// waiting before the job's turn frees the slot at once. A frame only
    /// this job still holds is planned by value, converted in place
    /// ([`Planner::plan_owned`]); one the frame store keeps is borrowed.
    pub async fn run(
        self,
        ticket: Ticket,
        cloud: Arc<PointCloud>,
        request: PlanRequest,
    ) -> (Result<Plan, JobError>, JobTimes) {
        let planner = Arc::clone(&self.planner);
        let plan = move |deadline| match Arc::try_unwrap(cloud) {
            Ok(owned) => planner.plan_until(Cow::Owned(owned), &request, deadline),
            Err(shared) => planner.plan_until(Cow::Borrowed(&*shared), &request, deadline),
        };
        let (outcome, times) = self.execute(ticket, plan).await;
        (outcome.and_then(|r| Ok(r?)), times)
    }

    /// [`JobSlot::run`], recording what each stage found; the trace is
    /// lost only when the pipeline panicked.
    pub async fn run_traced(
        self,
        ticket: Ticket,
        cloud: Arc<PointCloud>,
        request: PlanRequest,
    ) -> (Result<Plan, JobError>, Option<PlanTrace>, JobTimes) {
        let planner = Arc::clone(&self.planner);
        let (outcome, times) =
            self.execute(ticket, move |deadline| planner.plan_traced_until(&cloud, &request, deadline)).await;
        match outcome {
            Ok((result, trace)) => (result.map_err(JobError::from), Some(trace), times),
            Err(e) => (Err(e), None, times),
        }
    }

    /// Runs `work` on the pool at `ticket`'s turn, holding the slot (and
    /// the turn) until done. Its deadline, `server.plan_timeout_ms` on from
    /// the start, is the pipeline's to keep: it stops at its next check
    /// once the time is up, so the turn passes on without a computation
    /// left running beside the next plan.
    async fn execute<T: Send + 'static>(
        self,
        ticket: Ticket,
        work: impl FnOnce(Deadline) -> T + Send + 'static,
    ) -> (Result<T, JobError>, JobTimes) {
        let ready = Instant::now();
        let JobSlot { permit, pool, planner } = self;
        ticket.turn().await;
        let turn = ticket;
        let started = Instant::now();
        let deadline = Deadline::after(planner.config().server.plan_timeout);
        let (tx, rx) = oneshot::channel();
        pool.spawn(move || {
            let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| work(deadline)));
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
    use crate::server::serve_order::ServeOrder;
    use rayon::prelude::*;
    use std::time::Duration;

    /// A job that spends its time in rayon joins, as the pipeline does:
    /// its threads wait on each other and look for other work meanwhile.
    fn parallel_work(_: Deadline) -> u64 {
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
        let order = ServeOrder::new();
        let (done_tx, mut done_rx) = tokio::sync::mpsc::unbounded_channel();
        let mut tasks = Vec::new();
        for k in 0..8 {
            let slot = jobs.reserve().unwrap();
            let ticket = order.issue();
            let done = done_tx.clone();
            tasks.push(tokio::spawn(async move {
                slot.execute(ticket, parallel_work).await.0.unwrap();
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
