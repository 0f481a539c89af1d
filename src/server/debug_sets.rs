//! The pictures of the daemon's last plans: the debug sets of `[debug]`
//! (for each plan, the pictures and figures `weldseam plan --debug`
//! writes, in a directory of its own, the oldest beyond `debug.keep_last`
//! deleted) and the operator page's pictures ([`super::board`]), rendered
//! once for both.
//!
//! A set is rendered after the plan's reply has been sent, on a blocking
//! thread, one set at a time: while one is being rendered the next plans
//! are not traced at all, so a burst of plans never holds more than one
//! traced frame beside the one planning, and nothing here delays a reply.
//! A failure to render or write is logged; it never fails a plan.

use std::sync::Arc;

use tokio::sync::Semaphore;
use tracing::{debug, warn};
use weldseam_proto::plan::PlanResult;

use super::board::{Board, PlanPictures};
use crate::config::DebugParams;
use crate::debug_dir::DebugStore;
use crate::pipeline::PlanTrace;
use crate::report;

/// Where the daemon keeps its debug sets and pictures, and the one
/// renderer's turn.
#[derive(Debug)]
pub struct DebugSets {
    /// The `[debug]` directory; None when `debug.dir` is empty.
    store: Option<Arc<DebugStore>>,
    board: Arc<Board>,
    writer: Arc<Semaphore>,
}

impl DebugSets {
    /// The debug sets `params` asks for (none when `debug.dir` is empty or
    /// cannot be made: logged, the cell plans on without them) and the
    /// page's pictures on `board`.
    pub fn open(params: &DebugParams, board: &Arc<Board>) -> DebugSets {
        let store = params.directory().and_then(|dir| match DebugStore::open(dir, params.keep_last as usize) {
            Ok(store) => Some(Arc::new(store)),
            Err(e) => {
                warn!("no debug sets will be kept: {e}");
                None
            }
        });
        DebugSets { store, board: Arc::clone(board), writer: Arc::new(Semaphore::new(1)) }
    }

    /// Whether the next plan should be traced: its pictures are wanted and
    /// no set is being rendered.
    pub fn ready(&self) -> bool {
        (self.store.is_some() || self.board.wants_pictures()) && self.writer.available_permits() > 0
    }

    /// Renders request `request_id`'s set on a blocking thread, writes it
    /// to the debug directory and gives its pictures to the board's plan
    /// `seq`, unless a set is being rendered already (then it is dropped,
    /// and logged). `report` is the plan as the reply carried it.
    pub fn keep(&self, request_id: u64, seq: u64, trace: PlanTrace, report: Option<PlanResult>) {
        let Ok(turn) = Arc::clone(&self.writer).try_acquire_owned() else {
            warn!(request_id, "pictures dropped: the previous plan's are still being rendered");
            return;
        };
        let store = self.store.clone();
        let board = self.board.wants_pictures().then(|| Arc::clone(&self.board));
        tokio::task::spawn_blocking(move || {
            let _turn = turn;
            let set = match report::debug_set(&trace, report) {
                Ok(set) => set,
                Err(e) => return warn!(request_id, "pictures not rendered: {e}"),
            };
            if let Some(board) = board
                && let Some(pictures) = PlanPictures::from_set(&set)
            {
                board.attach_pictures(seq, pictures);
            }
            if let Some(store) = store {
                match store.save(&format!("r{request_id}"), &set) {
                    Ok(path) => debug!(request_id, path = %path.display(), "debug set written"),
                    Err(e) => warn!(request_id, "debug set not written: {e}"),
                }
            }
        });
    }
}
