//! `weldseam bench` at its smallest, run as a process: one timed run of the
//! smallest frame and a one-second load, checked for shape (every table
//! and every row is there and has a figure, the load's replies are in
//! order), never for speed. The daemon-driving code it measures with
//! (`mock::load`), on its own. And issue 11's memory bound on the variant
//! that missed it, measured as the bench measures it.

use std::process::Command;

use weldseam::camera::CameraModel;
use weldseam::cloud::pcd;
use weldseam::config::Config;
use weldseam::joint::JointType;
use weldseam::mock::load::{self, Load};
use weldseam::pipeline::Stage;
use weldseam::sim::scenarios::{FRAME_SIZES, Scenario, VARIANT_JOINT, VARIANTS, camera_with_size, raw_cloud_bytes};
use weldseam::sim::variants::Variant;

use crate::scenes;
use crate::util::write_temp;

fn smallest() -> Scenario {
    let (w, h) = FRAME_SIZES[0];
    Scenario::new(JointType::IButt, 500.0, camera_with_size(w, h))
}

/// The cells of the Markdown row whose first cell is `first`.
fn row<'a>(markdown: &'a str, first: &str) -> Option<Vec<&'a str>> {
    markdown.lines().find_map(|line| {
        let cells: Vec<&str> = line.strip_prefix('|')?.strip_suffix('|')?.split(" | ").map(str::trim).collect();
        (cells.first() == Some(&first)).then_some(cells)
    })
}

/// A cell that holds a measured figure: a number first, not `-`.
fn is_figure(cell: &str) -> bool {
    cell.split_whitespace().next().is_some_and(|n| n.parse::<f64>().is_ok_and(f64::is_finite))
}

#[test]
fn bench_prints_every_table_with_a_figure_in_every_row() {
    let (w, h) = FRAME_SIZES[0];
    let frame = format!("{w}x{h}");
    let out = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["bench", "--quick", "--runs", "1", "--load-seconds", "1", "--markdown", "--frame", &frame])
        .output()
        .expect("run weldseam bench");
    let md = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{md}\n{}", String::from_utf8_lossy(&out.stderr));

    assert!(md.contains(&format!("**Per stage at 500 mm, {w} x {h} (0.5 MP), tilt 10°**")), "{md}");
    // The measured-cloud table: the same frames voxel-downsampled, planned
    // without a pixel grid, with a figure for every joint.
    let measured = format!("**Per stage, measured cloud: the 500 mm frames ({w} x {h}) voxel-downsampled at 1 mm**");
    let after = md.split(&measured).nth(1).unwrap_or_else(|| panic!("no measured-cloud table in\n{md}"));
    let total = row(after, "total").unwrap_or_else(|| panic!("no total in the measured-cloud table\n{md}"));
    assert!(total[1..].iter().all(|c| is_figure(c)), "{total:?}");
    assert_eq!(
        row(&md, "stage"),
        Some(vec!["stage", "v_butt ms", "i_butt ms", "lap ms"]),
        "one column per joint type in\n{md}"
    );
    let rows = Stage::IN_ORDER.iter().map(|s| s.name()).chain(["total", "cpu time, all threads", "valid points"]);
    for name in rows {
        let cells = row(&md, name).unwrap_or_else(|| panic!("no {name} row in\n{md}"));
        assert!(cells[1..].iter().all(|c| is_figure(c)), "{name}: {cells:?}");
    }
    assert!(!md.contains("a run failed"), "{md}");

    let scaling = row(&md, &format!("{w} x {h}")).unwrap_or_else(|| panic!("no scaling row in\n{md}"));
    assert!(scaling[1..].iter().all(|c| is_figure(c)), "{scaling:?}");
    for op in [
        "load binary PCD (cloud::load)",
        "decode Frame, camera link reader",
        "decode Frame, link reader to organized cloud",
        "decode Frame, in-memory decoder",
    ] {
        let cells = row(&md, op).unwrap_or_else(|| panic!("no {op} row in\n{md}"));
        assert!(is_figure(cells[1]) && is_figure(cells[2]), "{cells:?}");
    }
    // The child's peak holds at least its frame: 12 bytes a pixel.
    let memory = row(&md, "weldseam plan").unwrap_or_else(|| panic!("no memory row in\n{md}"));
    let peak_mb: f64 = memory[1].trim_end_matches(" MB").parse().expect("peak RSS in MB");
    assert!(peak_mb * 1e6 >= (w * h * 12) as f64, "{memory:?}");
    // The per-variant table: a row per variant and the compressed PCD,
    // every cell a figure, the ratio the peak over the raw size.
    let title = format!("**Per variant: v_butt at 500 mm ({w} x {h}), plan time and peak memory**");
    let variants = md.split(&title).nth(1).unwrap_or_else(|| panic!("no per-variant table in\n{md}"));
    assert_eq!(
        row(variants, "cloud"),
        Some(vec![
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
            "RSS under 4 x"
        ]),
        "{md}"
    );
    let names = VARIANTS.iter().map(|v| v.to_string()).chain(["raw, PCD binary_compressed".to_string()]);
    for name in names {
        let cells = row(variants, &name).unwrap_or_else(|| panic!("no {name} row in the per-variant table\n{md}"));
        assert!(cells[1..6].iter().chain(&cells[9..11]).all(|c| is_figure(c)), "{name}: {cells:?}");
        // The child holds its cloud at least once.
        let [raw_mb, peak_mb, ratio]: [f64; 3] = [2, 9, 10].map(|k| cells[k].parse().unwrap());
        assert!(peak_mb >= raw_mb && ratio >= 1.0, "{name}: {cells:?}");
        // The verdict is read from the unrounded ratio: where the printed
        // one rounds to the bound itself, either verdict fits it.
        if (ratio - 4.0).abs() >= 0.005 {
            assert_eq!(cells[11], if ratio < 4.0 { "yes" } else { "no" }, "{name}: {cells:?}");
        }
        // The heap is counted only in a build with the counting allocator;
        // it holds the loaded cloud at least once.
        if cfg!(feature = "heap-count") {
            let [heap_mb, heap_ratio]: [f64; 2] = [6, 7].map(|k| cells[k].parse().unwrap());
            assert!(heap_mb >= raw_mb && heap_ratio >= 1.0, "{name}: {cells:?}");
            if (heap_ratio - 4.0).abs() >= 0.005 {
                assert_eq!(cells[8], if heap_ratio < 4.0 { "yes" } else { "no" }, "{name}: {cells:?}");
            }
        } else {
            assert_eq!(cells[6..9], ["-", "-", "-"], "{name}: {cells:?}");
        }
    }
    let latency = row(&md, "frame's last byte written to reply's last byte read").expect("a daemon latency row");
    assert!(is_figure(latency[1]), "{latency:?}");
    let answered = row(&md, "requests answered with a plan").expect("a load row");
    assert!(answered[1].parse::<usize>().is_ok_and(|n| n > 0), "{answered:?}");
    assert_eq!(row(&md, "requests refused").map(|r| r[1]), Some("0"), "{md}");
}

#[test]
fn the_daemon_latency_gives_one_sample_per_run() {
    let scenario = smallest();
    let sim = scenes::scenario(&scenario);
    let config = Config { camera: scenario.camera, ..Config::default() };
    let latency = load::daemon_latency(config, scenario.joint, sim, 2).unwrap();
    assert_eq!(latency.len(), 2);
    // Not a speed target: a bound that only a lost or stuck reply (or a
    // sample in the wrong unit) breaks, since the pipeline's own time on
    // this frame is a fraction of it.
    assert!(latency.iter().all(|&ms| ms > 0.0 && ms < 120_000.0), "{latency:?} ms");
}

#[test]
fn the_load_measurement_answers_requests_in_order() {
    let scenario = smallest();
    let sim = scenes::scenario(&scenario);
    let config = Config { camera: scenario.camera, ..Config::default() };
    let load = Load { duration: std::time::Duration::from_secs(2), controllers: 2, camera_hz: 10.0, queue_depth: 2 };
    let figures = load::daemon_under_load(config, scenario.joint, sim, load).unwrap();
    assert!(!figures.replies.is_empty(), "no request was answered: {:?}", figures.errors);
    // A reply time runs from the request written to the reply read, so it
    // holds the pipeline's time for that plan; a mixed-up sample breaks it.
    for r in &figures.replies {
        assert!(r.plan_ms > 0.0 && r.reply_ms >= r.plan_ms, "{r:?}");
    }
    let frames: Vec<u64> = figures.replies.iter().map(|r| r.frame_id).collect();
    assert!(frames.iter().all(|&id| id > 0), "every plan names the camera's frame: {frames:?}");
}

/// Issue 11's memory target on the variants of the bench's table whose
/// clouds are large enough for it to be about the cloud (the smaller ones
/// are mostly the program itself): a one-shot `weldseam plan` of the
/// 500 mm V-butt frame without its grid (2.2 M points, 26.2 MB of raw
/// points), in metres and in the base frame (2.3 MP, 27.6 MB) peaks under
/// 4 times its raw size. Without its grid it peaked at 4.1 times while
/// `plan` kept freed memory as the daemon does (`cli::memory`), and the
/// converted ones at 3.7 times while the planner copied the cloud it
/// converts (`Planner::plan_owned` converts it in place). Measured
/// through the bench's small measuring process, with two pipeline threads
/// so that the figure does not grow with the machine's cores.
#[test]
fn a_one_shot_plan_of_a_large_variant_peaks_under_four_times_its_raw_size() {
    let scenario = Scenario::new(VARIANT_JOINT, 500.0, CameraModel::default());
    let frame = scenes::scenario(&scenario);
    for text in ["unorganized", "metres", "base"] {
        let variant = Variant::parse(text).unwrap();
        let (peak, raw) = one_shot_peak(&variant.apply(frame, scenario.seed()), variant.in_base_frame());
        let ratio = peak as f64 / raw as f64;
        assert!(
            ratio < 4.0,
            "{text}: peak {:.1} MB is {ratio:.2} times the raw {:.1} MB",
            peak as f64 / 1e6,
            raw as f64 / 1e6
        );
    }
}

/// The peak resident bytes of `weldseam plan --json` on `sim`'s cloud
/// written as a binary PCD (units guessed, in the base frame if `base`),
/// and the cloud's raw size.
fn one_shot_peak(sim: &weldseam::sim::Simulation, base: bool) -> (u64, u64) {
    let mut bytes = Vec::new();
    pcd::write_binary(&sim.cloud, &mut bytes).unwrap();
    let (_dir, path) = write_temp("cloud.pcd", &bytes);
    drop(bytes);
    let raw = raw_cloud_bytes(&sim.cloud);
    let (p, depth) = (sim.pose, sim.truth.groove_depth_mm.expect("a V-butt has a groove depth"));
    let pose = format!(
        "--pose={},{},{},{},{},{}",
        p.xyz_mm[0], p.xyz_mm[1], p.xyz_mm[2], p.angles_deg[0], p.angles_deg[1], p.angles_deg[2]
    );
    let out = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["bench", "--peak-rss-of-child", "--", "plan", "--cloud"])
        .arg(&path)
        .args(["--joint", "v-butt", &format!("--groove-depth={depth}"), &pose, "--json"])
        .args(["--cloud-frame", if base { "base" } else { "camera" }])
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .expect("run weldseam bench --peak-rss-of-child");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    (text.trim().parse().unwrap_or_else(|_| panic!("not a byte count: {text:?}")), raw)
}
