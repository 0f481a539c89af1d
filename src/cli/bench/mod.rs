//! `weldseam bench`: measures the planner on simulated frames and prints
//! the tables of docs/PERFORMANCE.md: per stage at three standoffs and on
//! the nearest frames voxel-downsampled (a measured cloud), the
//! scaling with frame size, loading and decoding a frame, the peak memory
//! of `weldseam plan`, every variant of a cloud as real tools write it
//! (plan time and peak memory against its raw size), a frame of three
//! workpieces against the same view of one (issue 15), the daemon's
//! trigger-to-reply latency, and its reply times and service order under
//! load.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Context, bail};
use weldseam::camera::CameraModel;
use weldseam::cloud::{self, PointCloud, pcd};
use weldseam::joint::JointType;
use weldseam::joint::RequestedJoint;
use weldseam::mock::load::{self as daemon_load, frame_message, quantile};
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::sim::scenarios::{
    DISTANCES_MM, FRAME_SIZES, MEASURED_VOXEL_MM, SEVERAL_DISTANCE_MM, Scenario, TILT_DEG, VARIANT_JOINT,
    camera_with_size, megapixels, raw_cloud_bytes, raw_frame_bytes, several_workpieces, variants,
};
use weldseam::sim::variants::Variant;
use weldseam::sim::{Simulation, simulate};

use crate::cli::memory;
use crate::cli::table::Table;
use measure::{PlanTimings, Summary, VariantRow, config_for};

pub mod measure;

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// A short smoke run: 2 timed runs, 500 mm only, the 2.3 MP frame only.
    #[arg(long)]
    pub quick: bool,
    /// Timed runs per measurement, each after one discarded warm-up
    /// (default 7, or 2 with --quick).
    #[arg(long, value_name = "N")]
    pub runs: Option<usize>,
    /// Print the tables as Markdown.
    #[arg(long)]
    pub markdown: bool,
    /// How long the load measurement runs, seconds (default 20, or 5
    /// with --quick).
    #[arg(long, value_name = "SECONDS")]
    pub load_seconds: Option<u64>,
    /// Only the per-stage tables: the quick loop while tuning a stage.
    #[arg(long)]
    pub stages_only: bool,
    /// Only this sensor size, WIDTHxHEIGHT pixels, with the paper's field
    /// of view (e.g. 896x560, the smallest of the scaling table).
    #[arg(long, value_name = "WxH", value_parser = parse_frame_size)]
    pub frame: Option<(u32, u32)>,
    /// Internal: run this program with the arguments after `--`, print
    /// the child's peak resident bytes and nothing else.
    #[arg(long, hide = true)]
    pub peak_rss_of_child: bool,
    /// The child's arguments, after `--`.
    #[arg(last = true, hide = true)]
    pub child_args: Vec<String>,
}

/// The joint of the single-scene measurements (scaling, load, memory, daemon).
const JOINT: JointType = JointType::IButt;
/// The standoff of the single-scene measurements: the densest case.
const NEAR_MM: f64 = 500.0;

/// A temporary file removed when dropped.
struct TempFile(PathBuf);

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// How a PCD file's data is stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PcdData {
    Binary,
    /// LZF-compressed, as PCL's tools write it.
    BinaryCompressed,
}

/// Writes `cloud` to `path` as a PCD; returns the file's size in bytes.
fn write_pcd(cloud: &PointCloud, path: &Path, data: PcdData) -> anyhow::Result<u64> {
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut out = BufWriter::new(file);
    match data {
        PcdData::Binary => pcd::write_binary(cloud, &mut out)?,
        PcdData::BinaryCompressed => pcd::write_binary_compressed(cloud, &mut out)?,
    }
    out.flush()?;
    Ok(std::fs::metadata(path)?.len())
}

/// The arguments of `weldseam plan --json` on the capture `sim`, made into
/// `variant` and saved at `cloud`: the flags a user gives for it (units,
/// and the cloud's frame) and the config holding the camera, if any.
fn plan_args(
    cloud: &Path,
    joint: JointType,
    sim: &Simulation,
    variant: &Variant,
    config: Option<&Path>,
) -> Vec<String> {
    let p = sim.pose;
    let mut args: Vec<String> = vec![
        "plan".into(),
        "--cloud".into(),
        cloud.to_string_lossy().into_owned(),
        "--joint".into(),
        joint.name().into(),
        format!(
            "--pose={},{},{},{},{},{}",
            p.xyz_mm[0], p.xyz_mm[1], p.xyz_mm[2], p.angles_deg[0], p.angles_deg[1], p.angles_deg[2]
        ),
        "--units".into(),
        if variant.is_raw() { "mm" } else { "auto" }.into(),
        "--json".into(),
    ];
    if let Some(depth) = sim.truth.groove_depth_mm {
        args.push(format!("--groove-depth={depth}"));
    }
    if variant.in_base_frame() {
        args.extend(["--cloud-frame".into(), "base".into()]);
    }
    if let Some(path) = config {
        args.extend(["--config".into(), path.to_string_lossy().into_owned()]);
    }
    args
}

/// One row of the per-variant table: `frame` made into `variant` and
/// saved as a PCD (`data`) in a temporary file, loaded and planned
/// in-process, and planned by `weldseam plan` as a child for its peak
/// memory.
fn measure_variant(
    scenario: &Scenario,
    frame: &Simulation,
    variant: &Variant,
    data: PcdData,
    config: Option<&Path>,
    runs: usize,
) -> anyhow::Result<VariantRow> {
    let path = std::env::temp_dir().join(format!("weldseam-bench-{}-variant.pcd", std::process::id()));
    let file = TempFile(path.clone());
    let sim = variant.apply(frame, scenario.seed());
    write_pcd(&sim.cloud, &path, data)?;
    let raw_bytes = raw_cloud_bytes(&sim.cloud);
    let points = sim.cloud.len();
    let request = measure::request_for_variant(scenario, &sim, variant);
    let args = plan_args(&path, scenario.joint, &sim, variant, config);
    drop(sim);
    let load_ms = measure::time_load(&path, runs)?;
    // What `plan` plans: the cloud as read back from the file.
    let loaded = cloud::load(&path)?;
    let plans = measure::time_request(scenario, &loaded, &request, runs);
    drop(loaded);
    // The heap of a one-shot plan as `weldseam plan` makes it: the file
    // loaded and handed over to the planner.
    let planner = Planner::new(config_for(scenario));
    let (loaded, heap_peak_bytes) = memory::heap_peak_of(|| -> anyhow::Result<()> {
        let _ = planner.plan_owned(cloud::load(&path)?, &request);
        Ok(())
    });
    loaded?;
    let peak_rss_bytes = peak_rss_of(&args)?;
    drop(file);
    let name = match data {
        PcdData::Binary => variant.to_string(),
        PcdData::BinaryCompressed => format!("{variant}, PCD binary_compressed"),
    };
    Ok(VariantRow { name, points, raw_bytes, load_ms, plans, heap_peak_bytes, peak_rss_bytes })
}

struct Printer {
    markdown: bool,
    out: std::io::Stdout,
}

impl Printer {
    fn table(&mut self, table: &Table) -> anyhow::Result<()> {
        let text = if self.markdown { table.to_markdown() } else { table.to_text() };
        let mut out = self.out.lock();
        writeln!(out, "{text}")?;
        out.flush()?;
        Ok(())
    }

    fn line(&mut self, line: &str) -> anyhow::Result<()> {
        let mut out = self.out.lock();
        writeln!(out, "{line}")?;
        out.flush()?;
        Ok(())
    }
}

/// Issue 15's speed target: the frame of three workpieces planned against
/// the same view of the first alone (`sim::scenarios::several_workpieces`),
/// each with `auto`, and the ratio of their median plan times.
fn several_workpieces_table(camera: CameraModel, runs: usize) -> Table {
    let scenario = Scenario::new(JointType::VButt, SEVERAL_DISTANCE_MM, camera);
    let mut table = Table::new(
        format!(
            "Several workpieces per frame: three parts and the first alone, {} x {} at {SEVERAL_DISTANCE_MM:.0} mm",
            camera.width_px, camera.height_px
        ),
        &["frame", "seams", "not planned", "total ms", "x one part", "stages (median ms)"],
    );
    let mut one_part_ms = None;
    for count in [1, 3] {
        let sim = simulate(&several_workpieces(count), &camera);
        let request = PlanRequest::new(RequestedJoint::Auto, None, sim.pose);
        let outcome = Planner::new(config_for(&scenario)).plan(&sim.cloud, &request);
        let timings = measure::time_request(&scenario, &sim.cloud, &request, runs);
        let total = timings.total();
        let median = total.map(|t| t.median);
        if count == 1 {
            one_part_ms = median;
        }
        let ratio = match (median, one_part_ms) {
            (Some(m), Some(one)) if one > 0.0 => format!("{:.2}", m / one),
            _ => "-".into(),
        };
        let (seams, unplanned) = match &outcome {
            Ok(plan) => (plan.seams.len().to_string(), plan.unplanned.len().to_string()),
            Err(e) => ("refused".into(), e.to_string()),
        };
        let cell = total.map(|t| t.cell(1)).unwrap_or_else(|| "-".into());
        let stages: Vec<String> = timings
            .stages
            .iter()
            .filter_map(|(stage, _)| Some(format!("{} {:.1}", stage.name(), timings.stage(*stage)?.median)))
            .collect();
        let label = format!("{count} part{}", if count == 1 { "" } else { "s" });
        table.push(vec![label, seams, unplanned, cell, ratio, stages.join(", ")]);
    }
    table.notes.push(format!(
        "median (min-max) of {runs} runs after a discarded warm-up, `auto`; the workpieces are planned side by side \
         after the frame's shared stages (issue 15's target: three in under 1.5 times one)"
    ));
    table
}

fn progress(what: &str) {
    eprintln!("measuring {what}...");
}

/// The CPU model, core count and system, as one Markdown-friendly line each.
pub fn machine_description() -> Vec<String> {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo
        .lines()
        .find_map(|l| l.strip_prefix("model name").and_then(|r| r.split_once(':')).map(|(_, m)| m.trim().to_string()))
        .unwrap_or_else(|| "unknown".into());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease").map(|s| s.trim().to_string()).ok();
    let mut lines = vec![
        format!("CPU: {model}"),
        format!("cores available: {cores} (pipeline threads: {})", rayon::current_num_threads()),
        format!(
            "system: {} {}{}",
            std::env::consts::OS,
            std::env::consts::ARCH,
            kernel.map(|k| format!(", kernel {k}")).unwrap_or_default()
        ),
    ];
    if let Some(load) = load_average() {
        lines.push(format!(
            "load average at start (1, 5, 15 min): {load}; other work on the machine slows every figure"
        ));
    }
    if cfg!(debug_assertions) {
        lines.push("build: debug (unoptimised; use --release for figures worth reporting)".into());
    } else {
        lines.push("build: release".into());
    }
    lines
}

/// Runs this program with `args`, outputs discarded, and returns its peak
/// resident bytes. The kernel's figure for a child is at least the
/// spawning process's own peak at the spawn (the child starts as a view of
/// its memory), so a benchmark that holds several frames cannot spawn the
/// measured child itself: a fresh, small copy of this program does it.
fn peak_rss_of(args: &[String]) -> anyhow::Result<u64> {
    let exe = std::env::current_exe().context("cannot find this program's path")?;
    let output = Command::new(exe)
        .args(["bench", "--peak-rss-of-child", "--"])
        .args(args)
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .context("cannot start the measuring process")?;
    if !output.status.success() {
        bail!("the measured `weldseam {}` failed: {}", args.first().map(String::as_str).unwrap_or(""), output.status);
    }
    let text = String::from_utf8_lossy(&output.stdout);
    text.trim().parse().with_context(|| format!("the measuring process printed {text:?}, not a byte count"))
}

/// The small measuring process: runs the child and prints its peak bytes.
fn measure_child(args: &[String]) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("cannot find this program's path")?;
    let mut command = Command::new(exe);
    command.args(args).stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::null());
    let child = measure::run_measuring_peak_rss(&mut command).context("cannot run the measured command")?;
    if !child.status.success() {
        bail!("the measured command failed: {}", child.status);
    }
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", child.peak_rss_bytes)?;
    Ok(())
}

/// The reply times and service order of [`daemon_load::daemon_under_load`].
fn load_table(figures: &daemon_load::LoadFigures, load: &daemon_load::Load) -> Table {
    let (replies, plans) = (figures.reply_ms(), figures.plan_ms());
    let q = |v: &[f64], p: f64| quantile(v, p).map(|x| format!("{x:.0}")).unwrap_or_else(|| "-".into());
    let mut t = Table::new(
        format!(
            "The daemon under load: {JOINT} at {NEAR_MM:.0} mm, camera streaming, {} controllers planning in a loop",
            load.controllers
        ),
        &["figure", "value"],
    );
    let seconds = load.duration.as_secs_f64();
    t.push(vec!["requests answered with a plan".into(), replies.len().to_string()]);
    let errors: Vec<String> = figures.errors.iter().map(|(name, n)| format!("{n} {name}")).collect();
    t.push(vec!["requests refused".into(), if errors.is_empty() { "0".into() } else { errors.join(", ") }]);
    t.push(vec!["plans per second".into(), format!("{:.2}", replies.len() as f64 / seconds)]);
    t.push(vec![
        "reply time p50 / p99 / max, ms".into(),
        format!("{} / {} / {}", q(&replies, 0.5), q(&replies, 0.99), q(&replies, 1.0)),
    ]);
    t.push(vec!["plan time p50 / max, ms".into(), format!("{} / {}", q(&plans, 0.5), q(&plans, 1.0))]);
    let bound = quantile(&plans, 1.0).map(|p| p * load.queue_depth as f64);
    t.push(vec![
        format!("queue depth x longest plan, ms (bound less the frame wait)"),
        bound.map(|b| format!("{b:.0}")).unwrap_or_else(|| "-".into()),
    ]);
    t.push(vec!["plans overtaken by a plan of a later frame".into(), figures.overtaken().to_string()]);
    t.notes.push(format!(
        "{seconds:.0} s; camera free-running at up to {:.0} Hz and answering triggers; each controller keeps one \
         request in flight, alternating Trigger and NextFrame; server.plan_queue_depth {}; reply time from the \
         request written to the reply read",
        load.camera_hz, load.queue_depth
    ));
    t
}

/// `WIDTHxHEIGHT` in pixels, each at least 16 and at most 8192.
fn parse_frame_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("{text:?} is not WIDTHxHEIGHT, e.g. 896x560"))?;
    let side = |s: &str| -> Result<u32, String> {
        let v: u32 = s.trim().parse().map_err(|_| format!("{s:?} in {text:?} is not a whole number of pixels"))?;
        if (16..=8192).contains(&v) { Ok(v) } else { Err(format!("{v} px is outside 16 to 8192")) }
    };
    Ok((side(w)?, side(h)?))
}

/// The first three fields of /proc/loadavg.
fn load_average() -> Option<String> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let fields: Vec<&str> = text.split_whitespace().take(3).collect();
    (fields.len() == 3).then(|| fields.join(" "))
}

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    if args.peak_rss_of_child {
        return measure_child(&args.child_args);
    }
    let runs = args.runs.unwrap_or(if args.quick { 2 } else { 7 }).max(1);
    let mut printer = Printer { markdown: args.markdown, out: std::io::stdout() };
    let machine = machine_description();
    if args.markdown {
        for line in &machine {
            printer.line(&format!("- {line}"))?;
        }
    } else {
        for line in &machine {
            printer.line(line)?;
        }
    }
    printer.line("")?;

    let camera = args.frame.map(|(w, h)| camera_with_size(w, h)).unwrap_or_default();
    let distances: &[f64] = if args.quick { &DISTANCES_MM[..1] } else { &DISTANCES_MM };
    let mut near_timings: Option<PlanTimings> = None;
    for &distance in distances {
        progress(&format!("every stage at {distance:.0} mm"));
        let timings = measure::bench_all(&Scenario::each_joint(distance, camera), runs);
        let title = format!(
            "Per stage at {distance:.0} mm, {} x {} ({:.1} MP), tilt {:.0}°",
            camera.width_px,
            camera.height_px,
            megapixels(&camera),
            TILT_DEG
        );
        printer.table(&measure::stage_table(title, &timings))?;
        if distance == NEAR_MM {
            near_timings = timings.into_iter().find(|t| t.scenario.joint == JOINT);
        }
    }

    // Measured clouds: the nearest frame voxel-downsampled, planned on the
    // path without a pixel grid (issue 11's 100 ms target). The I-butt's
    // gap is narrower than two voxels, which no cloud that coarse shows:
    // the planner refuses it, by design, so it has no time to measure.
    progress(&format!("every stage, {MEASURED_VOXEL_MM} mm voxels at {NEAR_MM:.0} mm"));
    let voxelized: Vec<Scenario> = Scenario::each_joint(NEAR_MM, camera)
        .into_iter()
        .filter(|s| s.joint != JointType::IButt)
        .map(|s| s.voxelized(MEASURED_VOXEL_MM))
        .collect();
    let title = format!(
        "Per stage, measured cloud: the {NEAR_MM:.0} mm frames ({} x {}) voxel-downsampled at {MEASURED_VOXEL_MM} mm",
        camera.width_px, camera.height_px
    );
    printer.table(&measure::stage_table(title, &measure::bench_all(&voxelized, runs)))?;

    progress("several workpieces in one frame");
    printer.table(&several_workpieces_table(camera, runs))?;

    if args.stages_only {
        return Ok(());
    }

    progress("scaling with frame size");
    let mut scaling = Vec::new();
    for (w, h) in FRAME_SIZES {
        let cam = camera_with_size(w, h);
        if (args.quick || args.frame.is_some()) && cam != camera {
            continue;
        }
        match near_timings.as_ref().filter(|t| t.scenario.camera == cam) {
            Some(t) => scaling.push(t.clone()),
            None => scaling.push(measure::bench_scenario(&Scenario::new(JOINT, NEAR_MM, cam), runs)),
        }
    }
    if scaling.is_empty() {
        // A --frame outside the scaling table's sizes: its one row.
        scaling.extend(near_timings.clone());
    }
    let title = format!("Scaling with frame size: {JOINT} at {NEAR_MM:.0} mm, tilt {TILT_DEG:.0}°");
    printer.table(&measure::scaling_table(title, &scaling))?;

    let scenario = Scenario::new(JOINT, NEAR_MM, camera);
    let sim = scenario.simulate();
    let raw = raw_frame_bytes(&camera);

    progress("loading and decoding a frame");
    let pcd_path = std::env::temp_dir().join(format!("weldseam-bench-{}.pcd", std::process::id()));
    let pcd_file = TempFile(pcd_path.clone());
    let pcd_bytes = write_pcd(&sim.cloud, &pcd_path, PcdData::Binary)?;
    let load = measure::time_load(&pcd_path, runs)?;
    let message = frame_message(&sim.cloud, 1, 0)?;
    let decode = measure::time_frame_decode(&message, runs)?;
    let mut io_table = Table::new(
        format!("Loading and decoding a {} x {} frame", camera.width_px, camera.height_px),
        &["operation", "bytes", "ms"],
    );
    let mb = |b: u64| format!("{:.1} MB", b as f64 / 1e6);
    let ms = |s: &[f64]| Summary::of(s).map(|s| s.cell(1)).unwrap_or_else(|| "-".into());
    io_table.push(vec!["load binary PCD (cloud::load)".into(), mb(pcd_bytes), ms(&load)]);
    io_table.push(vec!["decode Frame, camera link reader".into(), mb(message.len() as u64), ms(&decode.link_reader)]);
    io_table.push(vec![
        "decode Frame, link reader to organized cloud".into(),
        mb(message.len() as u64),
        ms(&decode.link_to_cloud),
    ]);
    io_table.push(vec!["decode Frame, in-memory decoder".into(), mb(message.len() as u64), ms(&decode.in_memory)]);
    io_table
        .notes
        .push(format!("median (min-max) of {runs} runs after a discarded warm-up; the PCD file is in the page cache"));
    printer.table(&io_table)?;

    progress("peak memory of `weldseam plan`");
    // A sensor other than the paper's needs its size in the child's config.
    let config_file = if camera == CameraModel::default() {
        None
    } else {
        let path = std::env::temp_dir().join(format!("weldseam-bench-{}.toml", std::process::id()));
        let toml = format!("[camera]\nwidth_px = {}\nheight_px = {}\n", camera.width_px, camera.height_px);
        std::fs::write(&path, toml).with_context(|| format!("cannot write {}", path.display()))?;
        Some(TempFile(path))
    };
    let config_path = config_file.as_ref().map(|TempFile(path)| path.as_path());
    let plan_args = plan_args(&pcd_path, JOINT, &sim, &Variant::raw(), config_path);
    let started = std::time::Instant::now();
    let peak = peak_rss_of(&plan_args)?;
    let wall = started.elapsed();
    drop(pcd_file);
    let mut memory = Table::new(
        format!("Peak memory of `weldseam plan --json` on the {JOINT} frame at {NEAR_MM:.0} mm"),
        &["process", "peak RSS", "x raw frame", "wall ms"],
    );
    memory.push(vec![
        "weldseam plan".into(),
        mb(peak),
        format!("{:.2}", peak as f64 / raw as f64),
        format!("{:.0}", wall.as_secs_f64() * 1e3),
    ]);
    memory.notes.push(format!(
        "raw frame: {} x {} x 12 bytes = {}; one run (load, plan, JSON); wall time includes starting two processes",
        camera.width_px,
        camera.height_px,
        mb(raw)
    ));
    printer.table(&memory)?;

    progress("every variant: plan time and peak memory");
    let variant_scenario = Scenario::new(VARIANT_JOINT, NEAR_MM, camera);
    let frame = variant_scenario.simulate();
    let mut rows = Vec::new();
    for variant in variants()? {
        rows.push(measure_variant(&variant_scenario, &frame, &variant, PcdData::Binary, config_path, runs)?);
    }
    let compressed = PcdData::BinaryCompressed;
    rows.push(measure_variant(&variant_scenario, &frame, &Variant::raw(), compressed, config_path, runs)?);
    drop((frame, config_file));
    let title = format!(
        "Per variant: {VARIANT_JOINT} at {NEAR_MM:.0} mm ({} x {}), plan time and peak memory",
        camera.width_px, camera.height_px
    );
    printer.table(&measure::variant_table(title, &rows))?;

    progress("the daemon, trigger to reply");
    let latency = daemon_load::daemon_latency(config_for(&scenario), JOINT, &sim, runs)?;
    let mut daemon = Table::new(
        format!("The daemon: {JOINT} at {NEAR_MM:.0} mm in trigger mode over loopback TCP"),
        &["interval", "ms"],
    );
    daemon.push(vec!["frame's last byte written to reply's last byte read".into(), ms(&latency)]);
    daemon.notes.push(format!(
        "median (min-max) of {runs} requests after a discarded warm-up; daemon, camera and controller in one process"
    ));
    printer.table(&daemon)?;

    let seconds = args.load_seconds.unwrap_or(if args.quick { 5 } else { 20 }).clamp(1, 3600);
    progress(&format!("the daemon under load for {seconds} s"));
    let load = daemon_load::Load {
        duration: std::time::Duration::from_secs(seconds),
        controllers: 4,
        camera_hz: 30.0,
        queue_depth: weldseam::config::ServerConfig::default().plan_queue_depth,
    };
    let figures = daemon_load::daemon_under_load(config_for(&scenario), JOINT, &sim, load)?;
    printer.table(&load_table(&figures, &load))?;
    if let Some(load) = load_average() {
        printer.line(&format!("load average at the end (1, 5, 15 min): {load}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::parse_frame_size;

    #[test]
    fn frame_sizes_parse_with_their_limits_named() {
        assert_eq!(parse_frame_size("896x560"), Ok((896, 560)));
        assert!(parse_frame_size("896").unwrap_err().contains("WIDTHxHEIGHT"));
        assert!(parse_frame_size("8x560").unwrap_err().contains("16 to 8192"));
        assert!(parse_frame_size("ax560").unwrap_err().contains("whole number"));
    }
}
