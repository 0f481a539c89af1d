//! The measurements of `weldseam bench`: repeated plans of a scenario with
//! the pipeline's own stage clock and the process's CPU time, loading and
//! decoding a frame, and a child process's peak memory; and the tables
//! that summarise them, the per-variant one included. Nothing asserts a time: the figures are for
//! reading, against the targets in docs/PERFORMANCE.md.

use std::io;
use std::path::Path;
use std::process::{Command, ExitStatus};
use std::time::{Duration, Instant};

use weldseam::cloud::{self, PointCloud};
use weldseam::config::Config;
use weldseam::pipeline::{CloudFrame, PlanRequest, Planner, Stage, Units};
use weldseam::server::connection::{MessageReader, ReadError};
use weldseam::sim::Simulation;
use weldseam::sim::scenarios::{Scenario, megapixels};
use weldseam::sim::variants::Variant;
use weldseam_proto::Message;
use weldseam_proto::frame::{self, DEFAULT_MAX_FRAME_BYTES};

use crate::cli::table::Table;

/// The planner's configuration for a scenario: the defaults with the
/// scenario's camera model.
pub fn config_for(scenario: &Scenario) -> Config {
    Config { camera: scenario.camera, ..Config::default() }
}

/// The request a controller would send for the simulated capture.
pub fn request_for(scenario: &Scenario, sim: &Simulation) -> PlanRequest {
    PlanRequest::new(scenario.joint, sim.truth.groove_depth_mm, sim.pose)
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

/// The request for `sim` made into `variant`, as `weldseam eval
/// --variant` and a user of `plan` make it: a raw frame in millimetres, any
/// other cloud's units guessed (`--units auto`), a base-frame cloud
/// brought into the camera frame (`--cloud-frame base`).
pub fn request_for_variant(scenario: &Scenario, sim: &Simulation, variant: &Variant) -> PlanRequest {
    let mut request = request_for(scenario, sim);
    if !variant.is_raw() {
        request.units = Units::Auto;
    }
    if variant.in_base_frame() {
        request.cloud_frame = CloudFrame::Base;
    }
    request
}

/// Plans `sim` `runs` times after one discarded warm-up plan.
pub fn time_plans(scenario: &Scenario, sim: &Simulation, runs: usize) -> PlanTimings {
    time_request(scenario, &sim.cloud, &request_for(scenario, sim), runs)
}

/// Plans `cloud` with `request` `runs` times after one discarded warm-up
/// plan.
pub fn time_request(scenario: &Scenario, cloud: &PointCloud, request: &PlanRequest, runs: usize) -> PlanTimings {
    let planner = Planner::new(config_for(scenario));
    let mut out = PlanTimings {
        scenario: *scenario,
        valid_points: cloud.valid_count(),
        stages: Vec::new(),
        totals: Vec::new(),
        cpu: Vec::new(),
        error: None,
    };
    for run in 0..=runs {
        let cpu_start = process_cpu_ms();
        let result = planner.plan(cloud, request);
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

/// One row of the per-variant table: a cloud as a file, its plan timed
/// in-process and `weldseam plan` run on the file as a child.
#[derive(Debug, Clone)]
pub struct VariantRow {
    /// The cloud, as `--variant` spells it (and the file format if not a
    /// binary PCD).
    pub name: String,
    /// Points the file holds, valid or not.
    pub points: usize,
    /// Its raw size: [`weldseam::sim::scenarios::raw_cloud_bytes`].
    pub raw_bytes: u64,
    /// Milliseconds per [`cloud::load`] of the file.
    pub load_ms: Vec<f64>,
    /// The in-process plans of the cloud.
    pub plans: PlanTimings,
    /// The heap's peak over loading the file and planning it by value
    /// (`Planner::plan_owned`, as `weldseam plan` does), bytes; `None`
    /// unless built with the `heap-count` feature.
    pub heap_peak_bytes: Option<u64>,
    /// The child's peak resident set, bytes.
    pub peak_rss_bytes: u64,
}

impl VariantRow {
    /// The peak resident set over the raw size.
    pub fn peak_ratio(&self) -> f64 {
        self.peak_rss_bytes as f64 / self.raw_bytes.max(1) as f64
    }

    /// The heap's peak over the raw size, if counted.
    pub fn heap_ratio(&self) -> Option<f64> {
        self.heap_peak_bytes.map(|bytes| bytes as f64 / self.raw_bytes.max(1) as f64)
    }
}

/// The memory target: peak under this many times the raw size.
pub const PEAK_OVER_RAW_TARGET: f64 = 4.0;

/// The per-variant table's columns.
pub const VARIANT_COLUMNS: [&str; 12] = [
    "cloud",
    "points",
    "raw MB",
    "load ms",
    "plan ms",
    "cpu ms",
    "heap MB",
    "heap x raw",
    "heap under 4 x",
    "peak RSS MB",
    "RSS x raw",
    "RSS under 4 x",
];

/// One row per variant: points, raw size, load and plan time, the
/// planner's heap peak and the child's peak memory, each with its ratio to
/// the raw size against the target.
pub fn variant_table(title: impl Into<String>, rows: &[VariantRow]) -> Table {
    let mut table = Table::new(title, &VARIANT_COLUMNS);
    let under = |ratio: f64| if ratio < PEAK_OVER_RAW_TARGET { "yes" } else { "no" }.to_string();
    let dash = || "-".to_string();
    for row in rows {
        let ratio = row.peak_ratio();
        table.push(vec![
            row.name.clone(),
            row.points.to_string(),
            format!("{:.1}", row.raw_bytes as f64 / 1e6),
            cell(Summary::of(&row.load_ms), 1),
            cell(row.plans.total(), 1),
            cell(row.plans.cpu(), 1),
            row.heap_peak_bytes.map_or_else(dash, |bytes| format!("{:.2}", bytes as f64 / 1e6)),
            row.heap_ratio().map_or_else(dash, |r| format!("{r:.2}")),
            row.heap_ratio().map_or_else(dash, under),
            format!("{:.1}", row.peak_rss_bytes as f64 / 1e6),
            format!("{ratio:.2}"),
            under(ratio),
        ]);
    }
    if let Some(row) = rows.first() {
        let runs = row.plans.totals.len();
        table.notes.push(format!(
            "median (min-max) ms of {runs} runs after a discarded warm-up; raw MB: 12 bytes (x, y, z as f32) for \
             every point the file holds, an organized frame's invalid pixels included; load: cloud::load of the \
             file, in the page cache; plan: the pipeline's total in-process, warm, and the process's CPU time; \
             heap: the peak of the heap bytes live while the file is loaded and planned by value in-process, one \
             run; peak RSS: `weldseam plan --json` on the file as a child process (load, plan, JSON, and the \
             program's own pages and threads), one run"
        ));
        if row.heap_peak_bytes.is_none() {
            table.notes.push("heap: not counted in this build; build with `--features heap-count`".into());
        }
    }
    for row in rows {
        if let Some(e) = &row.plans.error {
            table.notes.push(format!("{}: a run failed: {e}", row.name));
        }
    }
    table
}

/// Median ms of [`cloud::load`] on `path`.
pub fn time_load(path: &Path, runs: usize) -> Result<Vec<f64>, cloud::LoadError> {
    cloud::load(path)?;
    Ok(time_ms(runs, || cloud::load(path)))
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
    drop(child);
    // Linux reports ru_maxrss in KiB, macOS in bytes.
    let unit = if cfg!(target_os = "macos") { 1 } else { 1024 };
    let peak_rss_bytes = u64::try_from(usage.ru_maxrss).unwrap_or(0) * unit;
    Ok(ChildRun { status: ExitStatus::from_raw(status), peak_rss_bytes })
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
