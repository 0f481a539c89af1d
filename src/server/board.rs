//! What the operator page shows ([`super::http`]): who is connected, the
//! last frame, and the daemon's last plans, each with its outcome, the
//! refusal's rule and reason, its waypoints, per seam its weld process in
//! brief ([`ProcessSummary`]: the passes, the stretches cut with their
//! rule and reason, the waypoints re-angled) and, when the page is on, its
//! pictures (the camera view, the sections and the profile along the seam
//! of [`crate::report`]).
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
    /// Whether it has a profile picture (the figures along the seam).
    pub profile: bool,
}

/// One seam's weld process in brief, for an operator asking why a stretch
/// was not welded: the procedure, each pass with the waypoints it welds
/// and its travel speeds, each stretch cut with its rule and reason, and
/// the runs of waypoints whose torch was re-angled to clear the workpiece.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessSummary {
    pub procedure: String,
    pub waypoints: usize,
    /// The waypoints welded (not cut).
    pub welded: usize,
    pub passes: Vec<PassSummary>,
    pub cut: Vec<weldseam_proto::along_seam::CutStretch>,
    /// First and last waypoint of each run re-angled, in order.
    pub re_angled: Vec<[usize; 2]>,
}

/// One pass of a seam's layout, over the waypoints that have it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassSummary {
    pub kind: weldseam_proto::along_seam::PassKind,
    pub layer: u32,
    pub bead: u32,
    /// The waypoints with this pass.
    pub waypoints: usize,
    /// Its travel speed's least and greatest value there, mm/s.
    pub speed_mm_s: [f64; 2],
    /// Its weave's greatest half-swing, mm (0: no weave).
    pub weave_mm: f64,
}

impl ProcessSummary {
    /// The summary of `process`, None without one.
    pub fn of(process: Option<&weldseam_proto::along_seam::SeamProcess>) -> Option<ProcessSummary> {
        let process = process?;
        let mut passes: Vec<PassSummary> = Vec::new();
        let mut re_angled: Vec<[usize; 2]> = Vec::new();
        for (i, at) in process.waypoints.iter().enumerate() {
            let Some(at) = at else { continue };
            if at.re_angled {
                match re_angled.last_mut() {
                    Some(run) if run[1] + 1 == i => run[1] = i,
                    _ => re_angled.push([i, i]),
                }
            }
            for pass in &at.passes {
                let weave = pass.weave.map_or(0.0, |w| w.amplitude_mm);
                let speed = pass.travel_speed_mm_s;
                match passes.iter_mut().find(|p| (p.kind, p.layer, p.bead) == (pass.kind, pass.layer, pass.bead)) {
                    Some(p) => {
                        p.waypoints += 1;
                        p.speed_mm_s = [p.speed_mm_s[0].min(speed), p.speed_mm_s[1].max(speed)];
                        p.weave_mm = p.weave_mm.max(weave);
                    }
                    None => passes.push(PassSummary {
                        kind: pass.kind,
                        layer: pass.layer,
                        bead: pass.bead,
                        waypoints: 1,
                        speed_mm_s: [speed, speed],
                        weave_mm: weave,
                    }),
                }
            }
        }
        // Root first, then layer by layer, each layer's beads in order.
        passes.sort_by_key(|p| (p.layer, p.bead));
        Some(ProcessSummary {
            procedure: process.procedure.clone(),
            waypoints: process.waypoints.len(),
            welded: process.waypoints.iter().flatten().count(),
            passes,
            cut: process.cut.clone(),
            re_angled,
        })
    }
}

/// One plan's pictures and figures, encoded, as [`crate::report::debug_set`] makes them.
#[derive(Debug, Clone)]
pub struct PlanPictures {
    pub camera_png: Vec<u8>,
    pub sections_png: Option<Vec<u8>>,
    /// The figures along each seam, with the stretches cut shaded.
    pub profile_png: Option<Vec<u8>>,
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
            profile_png: file(crate::report::PROFILE_FILE),
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
            entry.summary.profile = pictures.profile_png.is_some();
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
            profile: false,
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
            PlanPictures {
                camera_png: vec![1],
                sections_png: None,
                profile_png: Some(vec![2]),
                figures_json: Vec::new(),
            },
        );
        let shown = board.plan(seqs[2]).unwrap().summary;
        assert!(shown.pictures && shown.profile && !shown.sections);
        let guard = board.peer_joined("camera", SocketAddr::from(([127, 0, 0, 1], 9)), "cam");
        assert_eq!(board.snapshot().1.len(), 1);
        drop(guard);
        assert!(board.snapshot().1.is_empty());
    }

    #[test]
    fn a_process_summary_names_each_pass_the_cut_stretches_and_the_runs_re_angled() {
        use weldseam_proto::along_seam::{CutStretch, Pass, PassKind, SeamProcess, WaypointProcess};
        let pass = |kind, layer, bead, speed| Pass {
            kind,
            layer,
            bead,
            lateral_mm: 0.0,
            height_mm: 0.0,
            work_angle_deg: 0.0,
            travel_speed_mm_s: speed,
            wire_feed_m_min: 0.0,
            voltage_v: 0.0,
            current_a: 0.0,
            target_area_mm2: 0.0,
            deposited_area_mm2: 0.0,
            weave: None,
        };
        let at = |re_angled, speed| {
            Some(WaypointProcess {
                thickness_mm: 12.0,
                joint_area_mm2: 0.0,
                crown_area_mm2: 0.0,
                work_angle_deg: 0.0,
                travel_angle_deg: 0.0,
                re_angled,
                passes: vec![pass(PassKind::Cap, 1, 0, speed + 1.0), pass(PassKind::Root, 0, 0, speed)],
            })
        };
        let cut = CutStretch {
            first: 2,
            last: 3,
            rule: "process.torch_blocked".into(),
            reason: "r".into(),
            contact_camera_mm: None,
        };
        let process = SeamProcess {
            procedure: "p".into(),
            waypoints: vec![at(true, 5.0), at(true, 6.0), None, None, at(false, 4.0), at(true, 5.0)],
            cut: vec![cut.clone()],
        };
        let summary = ProcessSummary::of(Some(&process)).unwrap();
        assert_eq!((summary.waypoints, summary.welded), (6, 4));
        assert_eq!(summary.re_angled, vec![[0, 1], [5, 5]]);
        assert_eq!(summary.cut, vec![cut]);
        let passes: Vec<_> = summary.passes.iter().map(|p| (p.kind, p.waypoints, p.speed_mm_s)).collect();
        assert_eq!(passes, vec![(PassKind::Root, 4, [4.0, 6.0]), (PassKind::Cap, 4, [5.0, 7.0])]);
        assert_eq!(ProcessSummary::of(None), None);
    }
}
