//! What the operator page shows ([`super::http`]): who is connected, the
//! last frame, and the daemon's last plans, each with its outcome, the
//! refusal's rule and reason, its waypoints and, when the page is on, its
//! pictures (the camera view and the sections of [`crate::report`]).
//!
//! Everything here is bounded: the plans are the last
//! `server.page_plans`, the oldest dropped as a new one comes; the peers
//! are the links' connections, themselves bounded by the links' slots.
//! Nothing here changes the cell: the links write, the page only reads.

use std::collections::VecDeque;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use serde::Serialize;
use weldseam_proto::plan::PlanResult;

use super::frames::wall_clock_us;

/// One plan as the page lists it.
#[derive(Debug, Clone, Serialize)]
pub struct PlanSummary {
    /// The entry's number on the board, rising by one per plan.
    pub seq: u64,
    /// When the plan was answered, microseconds since the Unix epoch.
    pub time_us: u64,
    /// The link the request came on: `controller` or `text`.
    pub link: &'static str,
    pub request_id: u64,
    /// The joint asked for (`auto` leaves it to the planner).
    pub joint: String,
    /// The frame planned, when one came.
    pub frame_id: Option<u64>,
    pub camera: Option<String>,
    /// The frame's points, valid or not.
    pub points: Option<usize>,
    pub seams: usize,
    /// `planned`, or the name of the error code answered.
    pub outcome: &'static str,
    /// The planner's rule that refused the plan, when one did.
    pub rule: Option<&'static str>,
    /// Why it was refused, as the reply said.
    pub reason: Option<String>,
    /// The pipeline's time, ms.
    pub plan_ms: f64,
    /// Request to reply, ms.
    pub latency_ms: f64,
    /// The plan's record in the record store, when it was written.
    pub record: Option<String>,
    /// Whether its pictures are held (`/api/plans/SEQ/camera.png`).
    pub pictures: bool,
    /// Whether it has a sections picture.
    pub sections: bool,
}

/// One plan's pictures and figures, encoded, as [`crate::report::debug_set`] makes them.
#[derive(Debug, Clone)]
pub struct PlanPictures {
    pub camera_png: Vec<u8>,
    pub sections_png: Option<Vec<u8>>,
    /// The figures of every stage, `trace.json`.
    pub figures_json: Vec<u8>,
}

impl PlanPictures {
    /// The pictures of a debug set's files.
    pub fn from_set(set: &crate::report::DebugSet) -> Option<PlanPictures> {
        let file = |name: &str| set.files.iter().find(|(n, _)| *n == name).map(|(_, bytes)| bytes.clone());
        Some(PlanPictures {
            camera_png: file(crate::report::CAMERA_VIEW_FILE)?,
            sections_png: file(crate::report::SECTIONS_FILE),
            figures_json: file(crate::report::FIGURES_FILE).unwrap_or_default(),
        })
    }
}

/// One plan on the board.
#[derive(Debug, Clone)]
pub struct PlanEntry {
    pub summary: PlanSummary,
    /// The plan as the reply carried it (seams, waypoints, figures).
    pub result: Option<PlanResult>,
    pub pictures: Option<Arc<PlanPictures>>,
}

/// A connection past its Hello, as the page shows it.
#[derive(Debug, Clone, Serialize)]
pub struct PeerSummary {
    pub link: &'static str,
    /// The name it gave in its Hello.
    pub name: String,
    pub address: String,
    /// Since when, microseconds since the Unix epoch.
    pub since_us: u64,
    #[serde(skip)]
    id: u64,
}

/// The last frame received, as the page shows it.
#[derive(Debug, Clone, Serialize)]
pub struct FrameSummary {
    pub frame_id: u64,
    pub camera: String,
    /// The camera's capture time, microseconds since the Unix epoch.
    pub capture_time_us: u64,
    /// When the daemon had it whole, microseconds since the Unix epoch.
    pub received_us: u64,
    pub points: usize,
}

#[derive(Debug, Default)]
struct Inner {
    plans: VecDeque<PlanEntry>,
    peers: Vec<PeerSummary>,
    last_frame: Option<FrameSummary>,
}

/// The daemon's board: what the page reads.
#[derive(Debug)]
pub struct Board {
    keep: usize,
    /// Whether plans' pictures are rendered for the page: from when the
    /// page is served on.
    pictures: AtomicBool,
    next_seq: AtomicU64,
    next_peer: AtomicU64,
    inner: Mutex<Inner>,
}

/// Keeps a peer on the board while it lives.
#[derive(Debug)]
pub struct PeerGuard {
    board: Arc<Board>,
    id: u64,
}

impl Drop for PeerGuard {
    fn drop(&mut self) {
        self.board.lock().peers.retain(|p| p.id != self.id);
    }
}

impl Board {
    /// A board keeping the last `keep` plans (at least one), without
    /// pictures until [`Board::show_pictures`].
    pub fn new(keep: usize) -> Arc<Board> {
        Arc::new(Board {
            keep: keep.max(1),
            pictures: AtomicBool::new(false),
            next_seq: AtomicU64::new(1),
            next_peer: AtomicU64::new(1),
            inner: Mutex::default(),
        })
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // Each change is one push or retain: a panic cannot leave it half-made.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Whether plans' pictures are rendered for the page.
    pub fn wants_pictures(&self) -> bool {
        self.pictures.load(Ordering::Relaxed)
    }

    /// Renders the plans' pictures from now on: the page is served.
    pub fn show_pictures(&self) {
        self.pictures.store(true, Ordering::Relaxed);
    }

    /// Puts a connection past its Hello on the board until the guard drops.
    pub fn peer_joined(self: &Arc<Self>, link: &'static str, address: SocketAddr, name: &str) -> PeerGuard {
        let id = self.next_peer.fetch_add(1, Ordering::Relaxed);
        // A Hello's name is bounded by the protocol; the page shows it as text.
        let peer =
            PeerSummary { link, name: name.to_string(), address: address.to_string(), since_us: wall_clock_us(), id };
        self.lock().peers.push(peer);
        PeerGuard { board: Arc::clone(self), id }
    }

    /// Notes the frame just stored.
    pub fn frame_received(&self, frame: FrameSummary) {
        self.lock().last_frame = Some(frame);
    }

    /// Adds a plan, dropping the oldest beyond the board's size; returns
    /// its number, filled into `summary.seq`.
    pub fn add_plan(&self, mut summary: PlanSummary, result: Option<PlanResult>) -> u64 {
        let seq = self.next_seq.fetch_add(1, Ordering::Relaxed);
        summary.seq = seq;
        let mut inner = self.lock();
        inner.plans.push_back(PlanEntry { summary, result, pictures: None });
        while inner.plans.len() > self.keep {
            inner.plans.pop_front();
        }
        seq
    }

    /// Attaches pictures to plan `seq`, if it is still on the board.
    pub fn attach_pictures(&self, seq: u64, pictures: PlanPictures) {
        let mut inner = self.lock();
        if let Some(entry) = inner.plans.iter_mut().find(|e| e.summary.seq == seq) {
            entry.summary.pictures = true;
            entry.summary.sections = pictures.sections_png.is_some();
            entry.pictures = Some(Arc::new(pictures));
        }
    }

    /// Names plan `seq`'s record, if it is still on the board.
    pub fn attach_record(&self, seq: u64, record: String) {
        let mut inner = self.lock();
        if let Some(entry) = inner.plans.iter_mut().find(|e| e.summary.seq == seq) {
            entry.summary.record = Some(record);
        }
    }

    /// Plan `seq`, if it is still on the board.
    pub fn plan(&self, seq: u64) -> Option<PlanEntry> {
        self.lock().plans.iter().find(|e| e.summary.seq == seq).cloned()
    }

    /// The plans, newest first; the peers; the last frame.
    pub fn snapshot(&self) -> (Vec<PlanSummary>, Vec<PeerSummary>, Option<FrameSummary>) {
        let inner = self.lock();
        (inner.plans.iter().rev().map(|e| e.summary.clone()).collect(), inner.peers.clone(), inner.last_frame.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(request_id: u64) -> PlanSummary {
        PlanSummary {
            seq: 0,
            time_us: 0,
            link: "controller",
            request_id,
            joint: "lap".into(),
            frame_id: None,
            camera: None,
            points: None,
            seams: 0,
            outcome: "planned",
            rule: None,
            reason: None,
            plan_ms: 0.0,
            latency_ms: 0.0,
            record: None,
            pictures: false,
            sections: false,
        }
    }

    #[test]
    fn the_board_keeps_the_last_plans_newest_first_and_forgets_peers_that_leave() {
        let board = Board::new(2);
        let seqs: Vec<u64> = (1..=3).map(|r| board.add_plan(summary(r), None)).collect();
        let (plans, _, _) = board.snapshot();
        assert_eq!(plans.iter().map(|p| p.request_id).collect::<Vec<_>>(), vec![3, 2]);
        assert!(board.plan(seqs[0]).is_none(), "the oldest plan is dropped");
        board.attach_pictures(
            seqs[2],
            PlanPictures { camera_png: vec![1], sections_png: None, figures_json: Vec::new() },
        );
        assert!(board.plan(seqs[2]).unwrap().summary.pictures);
        let guard = board.peer_joined("camera", SocketAddr::from(([127, 0, 0, 1], 9)), "cam");
        assert_eq!(board.snapshot().1.len(), 1);
        drop(guard);
        assert!(board.snapshot().1.is_empty());
    }
}
