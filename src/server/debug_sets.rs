//! The daemon's debug sets (`[debug]`): for its last plans, the pictures
//! and figures `weldseam plan --debug` writes, each plan's in a directory
//! of its own, the oldest beyond `debug.keep_last` deleted.
//!
//! A set is rendered and written after the plan's reply has been sent, on
//! a blocking thread, one set at a time: while one is being written the
//! next plans are not traced at all, so a burst of plans never holds more
//! than one traced frame beside the one planning, and nothing here delays
//! a reply. A failure to render or write is logged; it never fails a plan.

use std::sync::Arc;

use tokio::sync::Semaphore;
use tracing::{debug, warn};
use weldseam_proto::plan::PlanResult;

use crate::config::DebugParams;
use crate::debug_dir::DebugStore;
use crate::pipeline::PlanTrace;
use crate::report;

/// Where the daemon keeps its debug sets, and the one writer's turn.
#[derive(Debug)]
pub struct DebugSets {
    store: Arc<DebugStore>,
    writer: Arc<Semaphore>,
}

impl DebugSets {
    /// The debug sets `params` asks for, or None when `debug.dir` is empty
    /// or cannot be made (logged: the cell plans on without them).
    pub fn open(params: &DebugParams) -> Option<DebugSets> {
        let dir = params.directory()?;
        match DebugStore::open(dir, params.keep_last as usize) {
            Ok(store) => Some(DebugSets { store: Arc::new(store), writer: Arc::new(Semaphore::new(1)) }),
            Err(e) => {
                warn!("no debug sets will be kept: {e}");
                None
            }
        }
    }

    /// Whether the next plan should be traced: no set is being written.
    pub fn ready(&self) -> bool {
        self.writer.available_permits() > 0
    }

    /// Renders and writes the set of request `request_id`'s plan on a
    /// blocking thread, unless a set is being written already (then it is
    /// dropped, and logged). `report` is the plan as the reply carried it.
    pub fn keep(&self, request_id: u64, trace: PlanTrace, report: Option<PlanResult>) {
        let Ok(turn) = Arc::clone(&self.writer).try_acquire_owned() else {
            warn!(request_id, "debug set dropped: the previous one is still being written");
            return;
        };
        let store = Arc::clone(&self.store);
        tokio::task::spawn_blocking(move || {
            let _turn = turn;
            let written = report::debug_set(&trace, report)
                .map_err(|e| e.to_string())
                .and_then(|set| store.save(&format!("r{request_id}"), &set).map_err(|e| e.to_string()));
            match written {
                Ok(path) => debug!(request_id, path = %path.display(), "debug set written"),
                Err(e) => warn!(request_id, "debug set not written: {e}"),
            }
        });
    }
}
