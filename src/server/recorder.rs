//! The daemon's writer of plan records (`[records]`, [`crate::records`]):
//! after each plan's reply, the frame it planned, the request, the
//! configuration (with the weld procedure's text) and the answer, every
//! field the plan carries, go to the store on a blocking thread.
//!
//! At most [`MAX_WRITES`] records are being written at once, each holding
//! its frame; a plan answered while they are is not recorded, and that is
//! logged and counted, as is a write that fails (a full disk). Neither
//! ever fails or delays a plan. A plan that got no frame has nothing to
//! record: the store holds only what the daemon received.

use std::sync::Arc;

use tokio::sync::Semaphore;
use tracing::{debug, warn};

use super::board::Board;
use super::frames::{StoredFrame, wall_clock_us};
use super::metrics::Metrics;
use crate::config::Config;
use crate::config::procedure::Procedure;
use crate::pipeline::PlanRequest;
use crate::records::{Limits, Outcome, Record, Store};

/// Records written at once; each holds its frame until written.
pub const MAX_WRITES: usize = 2;

/// The daemon's record writer.
#[derive(Debug)]
pub struct Recorder {
    store: Option<Arc<Store>>,
    config_hash: String,
    config_text: Option<Arc<str>>,
    /// The weld procedure's text, kept in every record beside the config.
    procedure_text: Option<Arc<str>>,
    writers: Arc<Semaphore>,
    board: Arc<Board>,
}

/// One plan to record.
pub struct Plan<'a> {
    pub seq: u64,
    pub link: &'static str,
    pub request_id: u64,
    pub request: &'a PlanRequest,
    pub frame: &'a Arc<StoredFrame>,
    pub outcome: Outcome,
}

impl Recorder {
    /// The recorder `config.records` asks for (none when `records.dir` is
    /// empty or cannot be made: logged, the cell plans on without records).
    /// `config_text` is the file the daemon was started with, if any.
    pub fn open(config: &Config, config_text: Option<String>, board: &Arc<Board>) -> Recorder {
        let params = &config.records;
        let limits = Limits { max_bytes: params.max_bytes, max_age: params.max_age() };
        let store = params.directory().and_then(|dir| match Store::open(dir, limits) {
            Ok(store) => Some(Arc::new(store)),
            Err(e) => {
                warn!("no plan records will be kept: {e}");
                None
            }
        });
        let procedure = config.process.procedure.as_ref();
        // The text is what a replay plans with: kept only when it reads
        // back as the procedure the daemon holds.
        let procedure_text = procedure.and_then(|p| match Procedure::from_toml(p.source()) {
            Ok(read) if read == *p => Some(Arc::from(p.source())),
            _ => {
                warn!("the weld procedure differs from its text: records will not hold it, and replays lack it");
                None
            }
        });
        Recorder {
            store,
            config_hash: config.planning_hash(),
            config_text: config_text.map(Arc::from),
            procedure_text,
            writers: Arc::new(Semaphore::new(MAX_WRITES)),
            board: Arc::clone(board),
        }
    }

    /// Whether plans are recorded.
    pub fn enabled(&self) -> bool {
        self.store.is_some()
    }

    /// What the store holds, for the page and the metrics.
    pub fn held(&self) -> Option<crate::records::Held> {
        self.store.as_ref().map(|s| s.held())
    }

    /// Waits, at most `within`, for the records being written; false when
    /// some were still being written then. The daemon calls it as it
    /// stops, so the last plans' records are not lost with the process.
    pub async fn finish(&self, within: std::time::Duration) -> bool {
        let all = self.writers.acquire_many(MAX_WRITES as u32);
        matches!(tokio::time::timeout(within, all).await, Ok(Ok(_)))
    }

    /// Writes `plan`'s record on a blocking thread, unless [`MAX_WRITES`]
    /// are being written (then it is dropped, logged and counted).
    pub fn keep(&self, plan: Plan<'_>, metrics: &Metrics) {
        let Some(store) = &self.store else { return };
        let Ok(turn) = Arc::clone(&self.writers).try_acquire_owned() else {
            metrics.record_dropped();
            warn!(request_id = plan.request_id, "plan not recorded: {MAX_WRITES} records are still being written");
            return;
        };
        let Plan { seq, link, request_id, request, frame, outcome } = plan;
        let request = Record::wire_request(request_id, request);
        let (store, frame, board) = (Arc::clone(store), Arc::clone(frame), Arc::clone(&self.board));
        let (config_hash, config_text) = (self.config_hash.clone(), self.config_text.clone());
        let procedure_text = self.procedure_text.clone();
        let (written, failed, held) = metrics.record_counters();
        tokio::task::spawn_blocking(move || {
            let _turn = turn;
            let (meta, points) = Record::frame_of(
                &frame.cloud,
                frame.input,
                weldseam_proto::message::FrameMeta {
                    frame_id: frame.frame_id,
                    trigger_id: frame.trigger_id,
                    capture_time_us: frame.capture_time_us,
                    width: 0,
                    height: 0,
                    units: 0,
                    cloud_frame: 0,
                },
            );
            let record = Record {
                time_us: wall_clock_us(),
                link: link.to_string(),
                request_id,
                request,
                frame: meta,
                camera: frame.camera.to_string(),
                points,
                config_hash,
                config_text: config_text.map(|t| t.to_string()),
                outcome,
                procedure_text: procedure_text.map(|t| t.to_string()),
                format: crate::records::FORMAT_VERSION,
            };
            drop(frame);
            let (sequence, id) = store.next_id(request_id);
            let saved = record
                .encode()
                .map_err(|e| e.to_string())
                .and_then(|bytes| store.save(sequence, &id, &bytes).map_err(|e| e.to_string()));
            match saved {
                Ok(()) => {
                    written.inc();
                    debug!(request_id, record = %id, "plan recorded");
                    board.attach_record(seq, id);
                }
                Err(e) => {
                    failed.inc();
                    warn!(request_id, "plan not recorded: {e}");
                }
            }
            held(store.held());
        });
    }
}
