//! Measuring the planner: per-stage timings on simulated frames, loading
//! and decoding a frame, the peak memory of a planning process, the
//! daemon's latency from a triggered frame to its reply, and its reply
//! times and service order under load (a camera streaming, several
//! controllers planning in a loop).
//!
//! Everything here measures and summarises; it prints nothing. The
//! `weldseam bench` subcommand prepares the inputs (temporary files, the
//! child command line) and prints the [`Table`]s. Nothing asserts a time:
//! the figures are for reading, against the targets in docs/PERFORMANCE.md.

use std::io;
use std::path::Path;
use std::process::{Command, ExitStatus};
use std::time::{Duration, Instant};

use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;
use tokio::sync::mpsc;
use weldseam_proto::frame::{self, DEFAULT_MAX_FRAME_BYTES};
use weldseam_proto::message::{FrameSelect, Hello, Role};
use weldseam_proto::{Message, PROTOCOL_VERSION};

use crate::camera::CameraModel;
use crate::cloud::{self, PointCloud};
use crate::config::Config;
use crate::joint::JointType;
use crate::mock::ClientError;
use crate::mock::controller::{ControllerClient, request_for_simulation};
use crate::pipeline::{PlanRequest, Planner, Stage};
use crate::server::connection::{MessageReader, ReadError};
use crate::server::local::LocalDaemon;
use crate::sim::{SceneSpec, Simulation, demo_scene, simulate};

/// The frame sizes of the scaling table: the paper's 1920 x 1200 sensor
/// (2.3 MP) and smaller and larger ones of the same 16:10 shape, all with
/// the same field of view.
pub const FRAME_SIZES: [(u32, u32); 4] = [(896, 560), (1280, 800), (1920, 1200), (2880, 1800)];

/// The camera standoffs of the per-stage tables, mm.
pub const DISTANCES_MM: [f64; 3] = [500.0, 750.0, 1000.0];

/// The camera tilt of every benchmark scene, degrees.
pub const TILT_DEG: f64 = 10.0;

/// The paper's camera with another sensor size: same field of view at the
/// same distance, so only the pixel density changes.
pub fn camera_with_size(width_px: u32, height_px: u32) -> CameraModel {
    CameraModel { width_px, height_px, ..CameraModel::default() }
}

/// Megapixels of a camera, for labels.
pub fn megapixels(camera: &CameraModel) -> f64 {
    camera.width_px as f64 * camera.height_px as f64 / 1e6
}

/// Bytes of a frame's raw points: three f32 per pixel.
pub fn raw_frame_bytes(camera: &CameraModel) -> u64 {
    camera.width_px as u64 * camera.height_px as u64 * 12
}

/// The median and range of a set of samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    pub count: usize,
}

impl Summary {
    /// Summarises `samples`; `None` when there are none (or any is NaN).
    pub fn of(samples: &[f64]) -> Option<Summary> {
        if samples.is_empty() || samples.iter().any(|s| s.is_nan()) {
            return None;
        }
        let mut sorted = samples.to_vec();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 { sorted[n / 2] } else { (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0 };
        Some(Summary { median, min: sorted[0], max: sorted[n - 1], count: n })
    }

    /// `median (min-max)` with `decimals` places.
    pub fn cell(&self, decimals: usize) -> String {
        if self.count == 1 {
            return format!("{:.*}", decimals, self.median);
        }
        format!("{:.*} ({:.*}-{:.*})", decimals, self.median, decimals, self.min, decimals, self.max)
    }
}

/// Times `f` `runs` times after one discarded warm-up call; milliseconds.
pub fn time_ms<T>(runs: usize, mut f: impl FnMut() -> T) -> Vec<f64> {
    std::hint::black_box(f());
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect()
}

/// One simulated capture to plan: a demo scene of `joint` seen from
/// `distance_mm` at [`TILT_DEG`] by `camera`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scenario {
    pub joint: JointType,
    pub distance_mm: f64,
    pub tilt_deg: f64,
    pub camera: CameraModel,
}

impl Scenario {
    pub fn new(joint: JointType, distance_mm: f64, camera: CameraModel) -> Self {
        Scenario { joint, distance_mm, tilt_deg: TILT_DEG, camera }
    }

    pub fn spec(&self) -> SceneSpec {
        let mut spec = demo_scene(self.joint);
        spec.placement.distance_mm = self.distance_mm;
        spec.placement.tilt_deg = self.tilt_deg;
        spec
    }

    pub fn simulate(&self) -> Simulation {
        simulate(&self.spec(), &self.camera)
    }

    /// The planner's configuration for this camera: the defaults with the
    /// scenario's camera model.
    pub fn config(&self) -> Config {
        Config { camera: self.camera, ..Config::default() }
    }

    /// The request a controller would send for the simulated capture.
    pub fn request(&self, sim: &Simulation) -> PlanRequest {
        PlanRequest::new(self.joint, sim.truth.groove_depth_mm, sim.pose)
    }

    /// `v_butt 500 mm 2.3 MP`
    pub fn label(&self) -> String {
        format!("{} {:.0} mm {:.1} MP", self.joint, self.distance_mm, megapixels(&self.camera))
    }
}

/// Repeated plans of one frame.
#[derive(Debug, Clone)]
pub struct PlanTimings {
    pub scenario: Scenario,
    pub valid_points: usize,
    /// Milliseconds per run of each stage, in run order.
    pub stages: Vec<(Stage, Vec<f64>)>,
    /// Milliseconds per run of the whole pipeline (the stages' sum).
    pub totals: Vec<f64>,
    /// CPU milliseconds of this process (every thread) per run: unlike
    /// wall time, barely changed by other work sharing the cores.
    pub cpu: Vec<f64>,
    /// The pipeline's error, if a run failed; failed runs have no timings.
    pub error: Option<String>,
}

impl PlanTimings {
    pub fn total(&self) -> Option<Summary> {
        Summary::of(&self.totals)
    }

    pub fn cpu(&self) -> Option<Summary> {
        Summary::of(&self.cpu)
    }

    pub fn stage(&self, stage: Stage) -> Option<Summary> {
        self.stages.iter().find(|(s, _)| *s == stage).and_then(|(_, ms)| Summary::of(ms))
    }

    /// Valid points over the median total time.
    pub fn points_per_second(&self) -> Option<f64> {
        self.total().map(|t| self.valid_points as f64 / (t.median / 1e3))
    }
}

/// Plans `sim` `runs` times after one discarded warm-up plan.
pub fn time_plans(scenario: &Scenario, sim: &Simulation, runs: usize) -> PlanTimings {
    let planner = Planner::new(scenario.config());
    let request = scenario.request(sim);
    let mut out = PlanTimings {
        scenario: *scenario,
        valid_points: sim.cloud.valid_count(),
        stages: Vec::new(),
        totals: Vec::new(),
        cpu: Vec::new(),
        error: None,
    };
    for run in 0..=runs {
        let cpu_start = process_cpu_ms();
        let result = planner.plan(&sim.cloud, &request);
        let cpu_ms = process_cpu_ms() - cpu_start;
        let plan = match result {
            Ok(plan) => plan,
            Err(e) => {
                out.error = Some(e.to_string());
                continue;
            }
        };
        if run == 0 {
            continue;
        }
        for &(stage, ms) in &plan.timings.stages {
            match out.stages.iter_mut().find(|(s, _)| *s == stage) {
                Some((_, samples)) => samples.push(ms),
                None => out.stages.push((stage, vec![ms])),
            }
        }
        out.totals.push(plan.timings.total_ms());
        out.cpu.push(cpu_ms);
    }
    out
}

/// CPU time of this process so far, user and system, every thread; ms.
#[cfg(unix)]
pub fn process_cpu_ms() -> f64 {
    // SAFETY: rusage is plain old data; an all-zero value is valid.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: the pointer is to a live local of the right type.
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return f64::NAN;
    }
    let ms = |t: libc::timeval| t.tv_sec as f64 * 1e3 + t.tv_usec as f64 / 1e3;
    ms(usage.ru_utime) + ms(usage.ru_stime)
}

/// CPU time is not measured off Unix.
#[cfg(not(unix))]
pub fn process_cpu_ms() -> f64 {
    f64::NAN
}

/// Simulates and times one scenario.
pub fn bench_scenario(scenario: &Scenario, runs: usize) -> PlanTimings {
    time_plans(scenario, &scenario.simulate(), runs)
}

/// A table of text cells, printed as aligned text or as Markdown.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    pub title: String,
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
    /// Sentences printed under the table.
    pub notes: Vec<String>,
}

impl Table {
    pub fn new(title: impl Into<String>, headers: &[&str]) -> Self {
        Table { title: title.into(), headers: headers.iter().map(|h| h.to_string()).collect(), ..Table::default() }
    }

    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }

    /// The row whose first cell is `first`.
    pub fn row(&self, first: &str) -> Option<&[String]> {
        self.rows.iter().find(|r| r.first().is_some_and(|c| c == first)).map(Vec::as_slice)
    }

    /// Columns padded to their widest cell; the first left-aligned, the
    /// rest right-aligned.
    pub fn to_text(&self) -> String {
        let columns = self.headers.len().max(self.rows.iter().map(Vec::len).max().unwrap_or(0));
        let cell = |row: &[String], c: usize| row.get(c).map(String::as_str).unwrap_or("").to_string();
        let widths: Vec<usize> = (0..columns)
            .map(|c| {
                std::iter::once(&self.headers).chain(&self.rows).map(|r| cell(r, c).chars().count()).max().unwrap_or(0)
            })
            .collect();
        let line = |row: &[String]| {
            let cells: Vec<String> = (0..columns)
                .map(|c| {
                    let text = cell(row, c);
                    if c == 0 { format!("{text:<w$}", w = widths[c]) } else { format!("{text:>w$}", w = widths[c]) }
                })
                .collect();
            cells.join("  ").trim_end().to_string()
        };
        let mut out = format!("{}\n", self.title);
        out.push_str(&line(&self.headers));
        out.push('\n');
        let rule: Vec<String> = widths.iter().map(|w| "-".repeat(*w)).collect();
        out.push_str(&rule.join("  "));
        out.push('\n');
        for row in &self.rows {
            out.push_str(&line(row));
            out.push('\n');
        }
        for note in &self.notes {
            out.push_str(note);
            out.push('\n');
        }
        out
    }

    /// A Markdown heading-less table: the title in bold, then the table.
    pub fn to_markdown(&self) -> String {
        let escape = |s: &str| s.replace('|', "\\|");
        let row =
            |cells: &[String]| format!("| {} |\n", cells.iter().map(|c| escape(c)).collect::<Vec<_>>().join(" | "));
        let mut out = format!("**{}**\n\n", self.title);
        out.push_str(&row(&self.headers));
        let align: Vec<String> =
            (0..self.headers.len()).map(|c| if c == 0 { "---".into() } else { "---:".into() }).collect();
        out.push_str(&format!("| {} |\n", align.join(" | ")));
        for r in &self.rows {
            out.push_str(&row(r));
        }
        if !self.notes.is_empty() {
            out.push('\n');
            for note in &self.notes {
                out.push_str(note);
                out.push('\n');
            }
        }
        out
    }
}

fn mpts(points_per_second: Option<f64>) -> String {
    points_per_second.map(|p| format!("{:.1}", p / 1e6)).unwrap_or_else(|| "-".into())
}

fn cell(summary: Option<Summary>, decimals: usize) -> String {
    summary.map(|s| s.cell(decimals)).unwrap_or_else(|| "-".into())
}

/// Per-stage table of several plans of the same distance (one column per
/// plan): a row per stage, in run order, then the total, the valid points
/// and the throughput. Cells are `median (min-max)` ms.
pub fn stage_table(title: impl Into<String>, timings: &[PlanTimings]) -> Table {
    let mut headers = vec!["stage".to_string()];
    headers.extend(timings.iter().map(|t| format!("{} ms", t.scenario.joint)));
    let mut table = Table { title: title.into(), headers, ..Table::default() };
    let mut stages: Vec<Stage> = Vec::new();
    for t in timings {
        for (s, _) in &t.stages {
            if !stages.contains(s) {
                stages.push(*s);
            }
        }
    }
    for stage in stages {
        let mut row = vec![stage.name().to_string()];
        row.extend(timings.iter().map(|t| cell(t.stage(stage), 1)));
        table.push(row);
    }
    let mut total = vec!["total".to_string()];
    total.extend(timings.iter().map(|t| cell(t.total(), 1)));
    table.push(total);
    let mut cpu = vec!["cpu time, all threads".to_string()];
    cpu.extend(timings.iter().map(|t| cell(t.cpu(), 1)));
    table.push(cpu);
    let mut points = vec!["valid points".to_string()];
    points.extend(timings.iter().map(|t| t.valid_points.to_string()));
    table.push(points);
    let mut rate = vec!["Mpoints/s".to_string()];
    rate.extend(timings.iter().map(|t| mpts(t.points_per_second())));
    table.push(rate);
    if let Some(t) = timings.first() {
        let runs = t.totals.len();
        table.notes.push(format!(
            "median (min-max) ms of {runs} runs after a discarded warm-up; wall time per stage and in total, \
             then the process's CPU time per plan (over the total, the cores kept busy)"
        ));
    }
    for t in timings {
        if let Some(e) = &t.error {
            table.notes.push(format!("{}: a run failed: {e}", t.scenario.label()));
        }
    }
    table
}

/// One row per frame size: pixels, valid points, total ms and throughput.
pub fn scaling_table(title: impl Into<String>, timings: &[PlanTimings]) -> Table {
    let mut table = Table::new(
        title,
        &["frame", "megapixels", "valid points", "total ms", "cpu ms", "ms per valid Mpoint", "Mpoints/s"],
    );
    for t in timings {
        let cam = &t.scenario.camera;
        let total = t.total();
        let per_mpoint = total
            .filter(|_| t.valid_points > 0)
            .map(|s| format!("{:.1}", s.median / (t.valid_points as f64 / 1e6)))
            .unwrap_or_else(|| "-".into());
        table.push(vec![
            format!("{} x {}", cam.width_px, cam.height_px),
            format!("{:.2}", megapixels(cam)),
            t.valid_points.to_string(),
            cell(total, 1),
            cell(t.cpu(), 1),
            per_mpoint,
            mpts(t.points_per_second()),
        ]);
        if let Some(e) = &t.error {
            table.notes.push(format!("{}: a run failed: {e}", t.scenario.label()));
        }
    }
    if let Some(t) = timings.first() {
        let runs = t.totals.len();
        table.notes.insert(
            0,
            format!("median (min-max) ms of {runs} runs after a discarded warm-up; throughput at the median total"),
        );
    }
    table
}

/// Median ms of [`cloud::load`] on `path`.
pub fn time_load(path: &Path, runs: usize) -> Result<Vec<f64>, cloud::LoadError> {
    cloud::load(path)?;
    Ok(time_ms(runs, || cloud::load(path)))
}

/// The wire encoding of `cloud` as a camera's Frame message (header and
/// payload), millimetres.
pub fn frame_message(cloud: &PointCloud, frame_id: u64, trigger_id: u64) -> Result<Vec<u8>, frame::EncodeError> {
    frame::encode(&Message::Frame(crate::convert::to_proto::frame(cloud, frame_id, trigger_id, 0)))
}

/// Reads one message from `bytes` as the daemon's camera link does: the
/// link's reader, in chunks, into the frame's point buffer.
pub async fn read_like_the_link(bytes: &[u8]) -> Result<Message, ReadError> {
    let mut reader = MessageReader::new(bytes, Duration::from_secs(5), DEFAULT_MAX_FRAME_BYTES);
    match reader.read().await? {
        Some(received) => Ok(received.message),
        None => Err(ReadError::Truncated),
    }
}

/// Decoding timings of one encoded frame, ms per run.
#[derive(Debug, Clone, Default)]
pub struct DecodeTimings {
    /// The camera link's reader, up to the decoded Frame message.
    pub link_reader: Vec<f64>,
    /// The link's reader and then the organized cloud the daemon stores.
    pub link_to_cloud: Vec<f64>,
    /// The proto crate's in-memory decoder, [`frame::decode`].
    pub in_memory: Vec<f64>,
}

/// Times decoding `bytes`, one encoded Frame message.
pub fn time_frame_decode(bytes: &[u8], runs: usize) -> io::Result<DecodeTimings> {
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    let read = || rt.block_on(read_like_the_link(bytes)).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e));
    let Message::Frame(_) = read()? else {
        return Err(io::Error::new(io::ErrorKind::InvalidData, "the bytes are not a frame message"));
    };
    let link_reader = time_ms(runs, read);
    let link_to_cloud = time_ms(runs, || {
        if let Ok(Message::Frame(f)) = read() {
            let cloud = PointCloud::organized(f.meta.width as usize, f.meta.height as usize, f.points);
            cloud.map(|c| c.valid_count())
        } else {
            None
        }
    });
    let in_memory = time_ms(runs, || frame::decode(bytes, DEFAULT_MAX_FRAME_BYTES));
    Ok(DecodeTimings { link_reader, link_to_cloud, in_memory })
}

/// A finished child process and its peak resident memory.
#[derive(Debug, Clone, Copy)]
pub struct ChildRun {
    pub status: ExitStatus,
    /// The child's own peak resident set, bytes.
    pub peak_rss_bytes: u64,
    pub wall: Duration,
}

/// Runs `command` to completion and reads its peak resident memory from
/// the kernel's accounting of that one child (`wait4`), so that other
/// children of this process, earlier or concurrent, do not count.
///
/// The figure is at least this process's own peak at the spawn: the child
/// starts as a view of the parent's memory, and the kernel keeps the
/// larger of that and the program's own peak. Call it from a process that
/// is small next to what it measures.
#[cfg(unix)]
pub fn run_measuring_peak_rss(command: &mut Command) -> io::Result<ChildRun> {
    use std::os::unix::process::ExitStatusExt;

    let start = Instant::now();
    let child = command.spawn()?;
    let pid = libc::pid_t::try_from(child.id()).map_err(|_| io::Error::other("the child's pid is out of range"))?;
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain old data; an all-zero value is valid.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    loop {
        // SAFETY: both pointers are to live locals of the right types;
        // `pid` is our own child, not yet reaped (we never call
        // `Child::wait`), so this reaps exactly it.
        let r = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
        if r == pid {
            break;
        }
        let e = io::Error::last_os_error();
        if e.kind() != io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
    let wall = start.elapsed();
    drop(child);
    // Linux reports ru_maxrss in KiB, macOS in bytes.
    let unit = if cfg!(target_os = "macos") { 1 } else { 1024 };
    let peak_rss_bytes = u64::try_from(usage.ru_maxrss).unwrap_or(0) * unit;
    Ok(ChildRun { status: ExitStatus::from_raw(status), peak_rss_bytes, wall })
}

/// Why the daemon could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum DaemonBenchError {
    #[error("cannot set up the daemon: {0}")]
    Setup(String),
    #[error("the controller's exchange failed: {0}")]
    Client(#[from] ClientError),
    #[error("the camera failed: {0}")]
    Camera(String),
    #[error(transparent)]
    Start(#[from] crate::server::local::StartError),
    #[error("the daemon did not stop cleanly: {0}")]
    Stop(#[from] crate::server::local::StopError),
    #[error(transparent)]
    Io(#[from] io::Error),
}

/// Byte offsets, in an encoded Frame message, of the frame and trigger
/// ids: after the 16-byte header, the payload starts with them.
const FRAME_ID_AT: usize = frame::HEADER_BYTES;
const TRIGGER_ID_AT: usize = frame::HEADER_BYTES + 8;
const CAPTURE_TIME_AT: usize = frame::HEADER_BYTES + 16;

/// A camera on a raw socket: answers each trigger with `message` (a
/// pre-encoded frame whose ids it patches) and reports the instant the
/// frame's last byte was written.
async fn raw_camera(
    addr: String,
    mut message: Vec<u8>,
    written: mpsc::UnboundedSender<Instant>,
) -> Result<(), DaemonBenchError> {
    let stream = TcpStream::connect(&addr).await?;
    stream.set_nodelay(true)?;
    let (read, mut write) = stream.into_split();
    let mut reader = MessageReader::new(read, Duration::from_secs(30), DEFAULT_MAX_FRAME_BYTES);
    let hello = Hello { protocol_version: PROTOCOL_VERSION, role: Role::Camera, name: "bench-camera".into() };
    let hello = frame::encode(&Message::Hello(hello)).map_err(|e| DaemonBenchError::Camera(e.to_string()))?;
    write.write_all(&hello).await?;
    let mut frame_id = 0u64;
    loop {
        let received = match reader.read().await {
            Ok(Some(r)) => r,
            Ok(None) => return Ok(()),
            Err(e) => return Err(DaemonBenchError::Camera(e.to_string())),
        };
        let trigger_id = match received.message {
            Message::Trigger(t) => t.trigger_id,
            Message::HelloAck(_) | Message::Status(_) | Message::FrameAck(_) => continue,
            Message::Error(e) => return Err(DaemonBenchError::Camera(e.message)),
            other => return Err(DaemonBenchError::Camera(format!("unexpected {} message", other.tag().name()))),
        };
        frame_id += 1;
        message[FRAME_ID_AT..FRAME_ID_AT + 8].copy_from_slice(&frame_id.to_le_bytes());
        message[TRIGGER_ID_AT..TRIGGER_ID_AT + 8].copy_from_slice(&trigger_id.to_le_bytes());
        let captured = crate::server::frames::wall_clock_us();
        message[CAPTURE_TIME_AT..CAPTURE_TIME_AT + 8].copy_from_slice(&captured.to_le_bytes());
        write.write_all(&message).await?;
        write.flush().await?;
        if written.send(Instant::now()).is_err() {
            return Ok(());
        }
    }
}

/// The daemon's latency, ms per request: an in-process daemon on loopback
/// ports, a camera answering triggers with `sim`'s frame and a controller
/// asking for trigger-mode plans of it, `runs` times after one warm-up.
/// Each sample runs from the instant the camera has written the frame's
/// last byte to the instant the controller has read the reply's last byte.
pub fn daemon_latency(scenario: &Scenario, sim: &Simulation, runs: usize) -> Result<Vec<f64>, DaemonBenchError> {
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    rt.block_on(daemon_latency_async(scenario, sim, runs))
}

async fn daemon_latency_async(
    scenario: &Scenario,
    sim: &Simulation,
    runs: usize,
) -> Result<Vec<f64>, DaemonBenchError> {
    let daemon = LocalDaemon::start(scenario.config()).await?;
    let (camera_addr, controller_addr) = (daemon.camera_addr.to_string(), daemon.controller_addr.to_string());

    let message = frame_message(&sim.cloud, 0, 0).map_err(|e| DaemonBenchError::Setup(e.to_string()))?;
    let (written_tx, mut written) = mpsc::unbounded_channel();
    let camera = tokio::spawn(raw_camera(camera_addr, message, written_tx));

    let result = async {
        let mut controller = ControllerClient::connect(&controller_addr, "bench-controller").await?;
        // A trigger request needs the camera attached first.
        controller
            .wait_for_camera(Duration::from_secs(10))
            .await
            .map_err(|_| DaemonBenchError::Setup("the camera did not connect within 10 s".into()))?;
        let mut samples = Vec::with_capacity(runs);
        for id in 0..=runs as u64 {
            let request = request_for_simulation(id + 1, scenario.joint, sim, FrameSelect::Trigger);
            controller.plan(request, Duration::from_secs(60)).await?;
            let replied = Instant::now();
            let sent = written
                .try_recv()
                .map_err(|_| DaemonBenchError::Camera("a reply came without a frame written".into()))?;
            if id > 0 {
                samples.push(replied.duration_since(sent).as_secs_f64() * 1e3);
            }
        }
        Ok(samples)
    }
    .await;

    daemon.stop().await?;
    camera.abort();
    result
}

/// How the daemon was loaded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Load {
    /// How long the controllers keep asking.
    pub duration: Duration,
    /// Controllers planning in a loop, one request in flight each,
    /// alternating Trigger and NextFrame requests.
    pub controllers: usize,
    /// The camera's free-running rate (it answers triggers as well).
    pub camera_hz: f64,
    /// `server.plan_queue_depth` of the daemon.
    pub queue_depth: usize,
}

/// What the daemon did under a [`Load`].
#[derive(Debug, Clone, Default)]
pub struct LoadFigures {
    /// Each answered request, in the order the replies arrived: the frame
    /// it was planned from, the reply time (request written to reply read)
    /// and the pipeline's own time, ms.
    pub replies: Vec<LoadReply>,
    /// Requests answered with an error, by the error's name.
    pub errors: std::collections::BTreeMap<String, usize>,
}

/// One answered request under load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadReply {
    pub frame_id: u64,
    pub reply_ms: f64,
    pub plan_ms: f64,
}

impl LoadFigures {
    pub fn reply_ms(&self) -> Vec<f64> {
        self.replies.iter().map(|r| r.reply_ms).collect()
    }

    pub fn plan_ms(&self) -> Vec<f64> {
        self.replies.iter().map(|r| r.plan_ms).collect()
    }

    /// Replies that came after a reply planned from a later frame: plans
    /// overtaken by plans whose frames became ready after theirs. The
    /// camera's ids increase in the order its frames reach the daemon, so
    /// in first-in-first-out order this is 0.
    pub fn overtaken(&self) -> usize {
        let mut newest = 0;
        let mut overtaken = 0;
        for r in &self.replies {
            if r.frame_id < newest {
                overtaken += 1;
            }
            newest = newest.max(r.frame_id);
        }
        overtaken
    }
}

/// The `q` quantile (0 to 1) of `samples`, by the nearest rank.
pub fn quantile(samples: &[f64], q: f64) -> Option<f64> {
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len().max(1));
    sorted.get(rank - 1).copied()
}

/// Runs an in-process daemon on loopback ports with a mock camera pushing
/// `sim`'s frame at `load.camera_hz` and `load.controllers` controllers
/// planning it in a loop for `load.duration`, and collects every reply.
pub fn daemon_under_load(scenario: &Scenario, sim: &Simulation, load: Load) -> Result<LoadFigures, DaemonBenchError> {
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    rt.block_on(daemon_under_load_async(scenario, sim, load))
}

/// [`daemon_under_load`] inside a runtime the caller owns.
pub async fn daemon_under_load_async(
    scenario: &Scenario,
    sim: &Simulation,
    load: Load,
) -> Result<LoadFigures, DaemonBenchError> {
    use std::sync::{Arc, Mutex};

    let mut config = scenario.config();
    config.server.plan_queue_depth = load.queue_depth.max(1);
    config.server.max_requests_per_connection = config.server.max_requests_per_connection.min(load.queue_depth.max(1));
    let daemon = LocalDaemon::start(config).await?;
    let (camera_addr, controller_addr) = (daemon.camera_addr.to_string(), daemon.controller_addr.to_string());
    let message = frame_message(&sim.cloud, 0, 0).map_err(|e| DaemonBenchError::Setup(e.to_string()))?;
    let camera = tokio::spawn(streaming_camera(camera_addr, message, load.camera_hz));

    let result = async {
        let mut probe = ControllerClient::connect(&controller_addr, "bench-probe").await?;
        probe
            .wait_for_camera(Duration::from_secs(10))
            .await
            .map_err(|_| DaemonBenchError::Setup("the camera did not connect within 10 s".into()))?;
        let figures = Arc::new(Mutex::new(LoadFigures::default()));
        let until = tokio::time::Instant::now() + load.duration;
        let mut tasks = Vec::new();
        for k in 0..load.controllers as u64 {
            let mut client = ControllerClient::connect(&controller_addr, &format!("bench-controller-{k}")).await?;
            let figures = Arc::clone(&figures);
            let sim = sim.clone();
            let joint = scenario.joint;
            tasks.push(tokio::spawn(async move {
                let mut id = k << 32;
                while tokio::time::Instant::now() < until {
                    id += 1;
                    let select = if id % 2 == 0 { FrameSelect::Trigger } else { FrameSelect::NextFrame };
                    let started = Instant::now();
                    let reply =
                        client.plan(request_for_simulation(id, joint, &sim, select), Duration::from_secs(120)).await;
                    let reply_ms = started.elapsed().as_secs_f64() * 1e3;
                    let mut f = figures.lock().unwrap_or_else(|p| p.into_inner());
                    match reply {
                        Ok(r) => f.replies.push(LoadReply {
                            frame_id: r.frame_id,
                            reply_ms,
                            plan_ms: r.result.timing_ms.get("total").copied().unwrap_or(f64::NAN),
                        }),
                        Err(ClientError::Refused(e)) => *f.errors.entry(e.code.name().to_string()).or_default() += 1,
                        Err(e) => return Err(DaemonBenchError::Client(e)),
                    }
                }
                Ok(())
            }));
        }
        for t in tasks {
            t.await.map_err(|e| DaemonBenchError::Setup(e.to_string()))??;
        }
        let figures = figures.lock().unwrap_or_else(|p| p.into_inner()).clone();
        Ok(figures)
    }
    .await;

    camera.abort();
    daemon.stop().await?;
    result
}

/// A camera on a raw socket streaming `message` (a pre-encoded frame whose
/// ids and capture time it patches) at up to `hz`, answering triggers
/// first, as a camera with its own encoder would: the bench's process
/// spends no time building frames, only sending them.
async fn streaming_camera(addr: String, mut message: Vec<u8>, hz: f64) -> Result<(), DaemonBenchError> {
    let stream = TcpStream::connect(&addr).await?;
    stream.set_nodelay(true)?;
    let (read, mut write) = stream.into_split();
    let hello = Hello { protocol_version: PROTOCOL_VERSION, role: Role::Camera, name: "bench-camera".into() };
    let hello = frame::encode(&Message::Hello(hello)).map_err(|e| DaemonBenchError::Camera(e.to_string()))?;
    write.write_all(&hello).await?;
    let (trigger_tx, mut triggers) = mpsc::unbounded_channel();
    let reader = tokio::spawn(async move {
        let mut reader = MessageReader::new(read, Duration::from_secs(30), DEFAULT_MAX_FRAME_BYTES);
        while let Ok(Some(received)) = reader.read().await {
            if let Message::Trigger(t) = received.message
                && trigger_tx.send(t.trigger_id).is_err()
            {
                break;
            }
        }
    });
    let mut ticker = tokio::time::interval(Duration::from_secs_f64(1.0 / hz.clamp(0.1, 1000.0)));
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut frame_id = 0u64;
    let result = loop {
        let trigger_id = match triggers.try_recv() {
            Ok(id) => id,
            Err(mpsc::error::TryRecvError::Disconnected) => break Ok(()),
            Err(mpsc::error::TryRecvError::Empty) => tokio::select! {
                id = triggers.recv() => match id {
                    Some(id) => id,
                    None => break Ok(()),
                },
                _ = ticker.tick() => 0,
            },
        };
        frame_id += 1;
        message[FRAME_ID_AT..FRAME_ID_AT + 8].copy_from_slice(&frame_id.to_le_bytes());
        message[TRIGGER_ID_AT..TRIGGER_ID_AT + 8].copy_from_slice(&trigger_id.to_le_bytes());
        let captured = crate::server::frames::wall_clock_us();
        message[CAPTURE_TIME_AT..CAPTURE_TIME_AT + 8].copy_from_slice(&captured.to_le_bytes());
        if let Err(e) = write.write_all(&message).await {
            break Err(e.into());
        }
    };
    reader.abort();
    result
}

/// The per-stage scenarios: one scene per joint type at `distance_mm`,
/// with `camera`.
pub fn joint_scenarios(distance_mm: f64, camera: CameraModel) -> Vec<Scenario> {
    JointType::ALL.iter().map(|&j| Scenario::new(j, distance_mm, camera)).collect()
}

/// Convenience for tables: every scenario timed.
pub fn bench_all(scenarios: &[Scenario], runs: usize) -> Vec<PlanTimings> {
    scenarios.iter().map(|s| bench_scenario(s, runs)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries_take_the_middle_and_the_range() {
        let s = Summary::of(&[5.0, 1.0, 3.0]).unwrap();
        assert_eq!((s.median, s.min, s.max, s.count), (3.0, 1.0, 5.0, 3));
        assert_eq!(Summary::of(&[4.0, 1.0, 2.0, 3.0]).unwrap().median, 2.5);
        assert_eq!(Summary::of(&[]), None);
        assert_eq!(Summary::of(&[1.0, f64::NAN]), None);
        assert_eq!(s.cell(1), "3.0 (1.0-5.0)");
        assert_eq!(Summary::of(&[2.25]).unwrap().cell(2), "2.25");
    }

    #[test]
    fn tables_align_text_and_escape_markdown() {
        let mut t = Table::new("T", &["name", "ms"]);
        t.push(vec!["a|b".into(), "1.0".into()]);
        t.push(vec!["longer".into(), "12.5".into()]);
        let text = t.to_text();
        assert!(text.contains("\na|b      1.0\n"), "{text}");
        assert!(text.contains("\nlonger  12.5\n"), "{text}");
        let md = t.to_markdown();
        assert!(md.contains("| a\\|b | 1.0 |"), "{md}");
        assert!(md.contains("| --- | ---: |"), "{md}");
        assert_eq!(t.row("longer").map(|r| r[1].as_str()), Some("12.5"));
    }

    #[test]
    fn overtaken_plans_and_quantiles_are_counted() {
        let reply = |frame_id| LoadReply { frame_id, reply_ms: 1.0, plan_ms: 1.0 };
        let fifo = LoadFigures { replies: [1, 2, 2, 5].map(reply).to_vec(), ..LoadFigures::default() };
        assert_eq!(fifo.overtaken(), 0);
        let unfair = LoadFigures { replies: [1, 4, 2, 5, 3].map(reply).to_vec(), ..LoadFigures::default() };
        assert_eq!(unfair.overtaken(), 2);
        let samples: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(
            (quantile(&samples, 0.5), quantile(&samples, 0.99), quantile(&samples, 1.0)),
            (Some(50.0), Some(99.0), Some(100.0))
        );
        assert_eq!(quantile(&[], 0.5), None);
    }

    #[test]
    fn frame_ids_sit_where_the_camera_patches_them() {
        let cloud = PointCloud::organized(2, 1, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]).unwrap();
        let bytes = frame_message(&cloud, 0x0102, 0x0304).unwrap();
        assert_eq!(u64::from_le_bytes(bytes[FRAME_ID_AT..FRAME_ID_AT + 8].try_into().unwrap()), 0x0102);
        assert_eq!(u64::from_le_bytes(bytes[TRIGGER_ID_AT..TRIGGER_ID_AT + 8].try_into().unwrap()), 0x0304);
    }

    #[cfg(unix)]
    #[test]
    fn a_child_is_reaped_with_its_status_and_memory() {
        // The shell holds 32 MB in a variable: its own peak, not this
        // process's, must be at least that.
        const HELD: u64 = 32 << 20;
        let script = format!("x=$(head -c {HELD} /dev/zero | tr '\\0' a); exit 3");
        let run = run_measuring_peak_rss(Command::new("sh").args(["-c", &script])).unwrap();
        assert_eq!(run.status.code(), Some(3));
        assert!(run.peak_rss_bytes >= HELD, "{} bytes", run.peak_rss_bytes);
    }
}
