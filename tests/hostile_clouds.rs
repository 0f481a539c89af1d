//! Clouds a corrupt transfer, a broken camera or a careless operator can
//! hand the planner: one absurd point, bytes shifted mid-frame, points
//! far denser than any camera gives, and files that are no files. Each is
//! planned by the `weldseam` binary in a child process with its address
//! space capped and a generous deadline, so a runaway shows as a failed
//! test rather than an exhausted machine; each must finish with a plan or
//! a clear error, its resident memory small.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use weldseam::camera::CameraModel;
use weldseam::cloud::{PointCloud, pcd};
use weldseam::joint::JointType;
use weldseam::sim::demo_scene;

use crate::scenes;

/// The address space a child may reserve: far above what planning a small
/// cloud needs (thread stacks and allocator arenas included), far below
/// what the runaways reached.
const ADDRESS_SPACE_BYTES: u64 = 2 << 30;
/// Long enough for a debug build on a busy machine; a runaway takes
/// minutes or never ends.
const DEADLINE: Duration = Duration::from_secs(60);
/// The resident memory a small cloud may cost (the bound).
const PEAK_RSS_BYTES: u64 = 100 << 20;

/// How a bounded run of the binary ended.
#[derive(Debug)]
struct Outcome {
    /// The exit code; `None` when killed at the deadline or by a signal.
    code: Option<i32>,
    timed_out: bool,
    /// The child's resident high-water mark, as last read while it ran.
    peak_rss_bytes: u64,
    stdout: String,
    stderr: String,
}

/// The resident high-water mark of a running process: VmHWM belongs to
/// the program's own address space, so unlike `wait4`'s figure it does
/// not start from the (large) test process that spawned it.
fn high_water_bytes(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Runs `weldseam args...` with its address space capped, killing it at
/// the deadline.
fn run_bounded(dir: &Path, args: &[&str]) -> Outcome {
    use std::os::unix::process::CommandExt;
    let (out_path, err_path) = (dir.join("stdout.txt"), dir.join("stderr.txt"));
    let mut command = Command::new(env!("CARGO_BIN_EXE_weldseam"));
    command
        .args(args)
        .env("NO_COLOR", "1")
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap());
    // SAFETY: setrlimit is async-signal-safe and touches nothing of the
    // parent's; the limit only applies to the child about to exec.
    unsafe {
        command.pre_exec(|| {
            let limit = libc::rlimit { rlim_cur: ADDRESS_SPACE_BYTES, rlim_max: ADDRESS_SPACE_BYTES };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let mut child = command.spawn().expect("spawn weldseam");
    let started = Instant::now();
    let mut peak_rss_bytes = 0;
    let mut timed_out = false;
    let status = loop {
        if let Some(bytes) = high_water_bytes(child.id()) {
            peak_rss_bytes = peak_rss_bytes.max(bytes);
        }
        if let Some(status) = child.try_wait().expect("wait for weldseam") {
            break status;
        }
        if started.elapsed() > DEADLINE {
            timed_out = true;
            child.kill().expect("kill the runaway child");
            break child.wait().expect("reap the killed child");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Outcome {
        code: status.code(),
        timed_out,
        peak_rss_bytes,
        stdout: std::fs::read_to_string(out_path).unwrap_or_default(),
        stderr: std::fs::read_to_string(err_path).unwrap_or_default(),
    }
}

/// Plans `cloud` with the demo V-butt request.
fn plan(dir: &Path, cloud: &Path) -> Outcome {
    let cloud = cloud.to_str().expect("a UTF-8 path");
    run_bounded(
        dir,
        &["plan", "--cloud", cloud, "--joint", "v-butt", "--groove-depth", "6", "--pose=800,0,500,180,0,0", "--json"],
    )
}

/// Asserts the run finished in bounds with a plan or a clear error, and
/// returns it.
fn assert_bounded(what: &str, outcome: Outcome) -> Outcome {
    assert!(!outcome.timed_out, "{what}: still running after {DEADLINE:?}: {}", outcome.stderr);
    assert!(
        matches!(outcome.code, Some(0 | 1)),
        "{what}: ended by {:?} (an abort is an allocation past the cap): {}",
        outcome.code,
        outcome.stderr
    );
    assert!(outcome.peak_rss_bytes < PEAK_RSS_BYTES, "{what}: {} MB resident", outcome.peak_rss_bytes >> 20);
    if outcome.code == Some(1) {
        assert!(outcome.stderr.contains("error:"), "{what}: a failure says why: {}", outcome.stderr);
    }
    outcome
}

/// The waypoints of a `--json` plan, or the error line of a failed one:
/// what must not change when invalid points are added to a cloud.
fn result_of(outcome: &Outcome) -> String {
    if outcome.code == Some(0) {
        let v: serde_json::Value = serde_json::from_str(outcome.stdout.trim()).expect("one JSON object");
        v["seams"][0]["waypoints"].to_string()
    } else {
        let line = outcome.stderr.lines().find(|l| l.contains("error:")).unwrap_or_default();
        // The file name differs between the runs compared.
        line.split(".pcd").last().unwrap_or_default().to_string()
    }
}

/// A `w x h` crop of the middle of the demo V-butt frame at 600 mm.
fn middle_crop(w: usize, h: usize) -> PointCloud {
    let camera = CameraModel::default();
    let mut spec = demo_scene(JointType::VButt);
    spec.placement.distance_mm = 600.0;
    let sim = scenes::rendered(&spec, &camera);
    let (c0, r0) = ((camera.width_px as usize - w) / 2, (camera.height_px as usize - h) / 2);
    let full = sim.cloud.points();
    let points = (r0..r0 + h).flat_map(|r| full[r * sim.cloud.width() + c0..][..w].to_vec()).collect();
    PointCloud::organized(w, h, points).expect("crop")
}

fn with_point(cloud: &PointCloud, col: usize, row: usize, point: [f32; 3]) -> PointCloud {
    let mut points = cloud.points().to_vec();
    points[row * cloud.width() + col] = point;
    PointCloud::organized(cloud.width(), cloud.height(), points).expect("same size")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write the cloud");
    path
}

fn binary_pcd(cloud: &PointCloud) -> Vec<u8> {
    let mut bytes = Vec::new();
    pcd::write_binary(cloud, &mut bytes).expect("encode");
    bytes
}

fn ascii_pcd(cloud: &PointCloud) -> Vec<u8> {
    let mut bytes = Vec::new();
    pcd::write_ascii(cloud, &mut bytes).expect("encode");
    bytes
}

#[test]
fn one_absurd_point_neither_runs_away_nor_changes_the_plan() {
    let dir = tempfile::tempdir().unwrap();
    let clean = middle_crop(160, 140);
    let clean_path = write(dir.path(), "clean.pcd", &binary_pcd(&clean));
    let expected = assert_bounded("clean crop", plan(dir.path(), &clean_path));
    // Far off the axis at a plausible depth, where the pixel window and
    // the full plane's ellipse of the point grow without bound; on the
    // first column, where the point starts a block of the plane criterion.
    for (name, col, row, point) in [
        ("far-off-axis", 0, 0, [-1e20, -1e20, 817.0]),
        ("far-off-axis-mid", 0, 70, [-1e20, -1e20, 817.0]),
        ("huge-y", 0, 0, [10.0, 1e20, 600.0]),
        ("far-away", 40, 60, [0.0, 0.0, 1e30]),
    ] {
        let cloud = with_point(&clean, col, row, point);
        let outcome = assert_bounded(name, plan(dir.path(), &write(dir.path(), "corrupt.pcd", &binary_pcd(&cloud))));
        assert_eq!(result_of(&outcome), result_of(&expected), "{name}: the plan ignores the point");
        assert!(outcome.stderr.contains("invalid points"), "{name}: the point is reported: {}", outcome.stderr);
    }
}

#[test]
fn one_absurd_point_in_a_small_ascii_file_is_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let crop = middle_crop(20, 15);
    for y in [1e20, -3e25, 1e38] {
        let cloud = with_point(&crop, 0, 0, [1.0, y, 600.0]);
        let path = write(dir.path(), "small.pcd", &ascii_pcd(&cloud));
        assert_bounded(&format!("y = {y}"), plan(dir.path(), &path));
    }
}

#[test]
fn bytes_inserted_mid_frame_are_refused_or_planned_in_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = binary_pcd(&middle_crop(160, 140));
    // Two bytes inserted half way shift every later float by two bytes;
    // the file then holds two bytes more than the header promises, which
    // the parser ignores as trailing data.
    for at in [bytes.len() / 2, bytes.len() / 3 + 1] {
        let mut shifted = bytes.clone();
        shifted.splice(at..at, [0x3a, 0x7f]);
        let path = write(dir.path(), "shifted.pcd", &shifted);
        assert_bounded(&format!("shifted at byte {at}"), plan(dir.path(), &path));
    }
}

#[test]
fn a_dense_cube_of_points_is_planned_in_bounds() {
    let dir = tempfile::tempdir().unwrap();
    // 50,000 points inside a 0.6 mm cube: every point is every other
    // point's neighbour. A fixed pseudo-random sequence keeps it stable.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 * 0.6
    };
    let points = (0..50_000).map(|_| [10.0 + next(), 20.0 + next(), 600.0 + next()]).collect();
    let cube = PointCloud::unorganized(points);
    let path = write(dir.path(), "cube.pcd", &binary_pcd(&cube));
    assert_bounded("dense cube", plan(dir.path(), &path));
    // The same points all on one spot: duplicates are the worst case of a
    // tree that prunes by distance.
    let spot = PointCloud::unorganized(vec![[10.0, 20.0, 600.0]; 50_000]);
    let path = write(dir.path(), "spot.pcd", &binary_pcd(&spot));
    assert_bounded("one spot", plan(dir.path(), &path));
}

#[test]
fn special_files_are_refused_without_reading_them() {
    let dir = tempfile::tempdir().unwrap();
    let zero = dir.path().join("zero.pcd");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let folder = dir.path().join("folder.pcd");
    std::fs::create_dir(&folder).unwrap();
    for path in [zero, folder] {
        let outcome = assert_bounded(&path.display().to_string(), plan(dir.path(), &path));
        assert_eq!(outcome.code, Some(1));
        assert!(outcome.stderr.contains("not a regular file"), "{}", outcome.stderr);
    }
}
