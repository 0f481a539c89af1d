//! `plan --json` against committed golden files: every number of every
//! seam (waypoints, ends, normal, fit figures, point counts) of the
//! simulated frame of each joint, to the last digit. A change that moves
//! any waypoint by any amount fails here and must say why in its commit;
//! `WELDSEAM_BLESS=1 cargo test --test tests golden::` rewrites the files
//! after such a change has been checked against the truth (`weldseam eval`).
//!
//! The plans do not depend on the number of threads or the instruction
//! set: the reductions are ordered and the fast paths are exact.

use std::path::PathBuf;
use std::process::Command;

fn weldseam(args: &[&str]) -> Vec<u8> {
    let out = Command::new(env!("CARGO_BIN_EXE_weldseam")).args(args).output().expect("run weldseam");
    assert!(out.status.success(), "weldseam {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out.stdout
}

fn golden_path(joint: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("plan-{joint}.json"))
}

#[test]
fn plan_json_equals_the_golden_file_for_each_joint() {
    let dir = tempfile::tempdir().unwrap();
    let bless = std::env::var_os("WELDSEAM_BLESS").is_some();
    for joint in ["v-butt", "i-butt", "lap"] {
        let pcd = dir.path().join(format!("{joint}.pcd"));
        let truth = dir.path().join(format!("{joint}.json"));
        weldseam(&["simulate", "--joint", joint, "--out", pcd.to_str().unwrap(), "--truth", truth.to_str().unwrap()]);
        let truth: serde_json::Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
        let plan_args = truth["plan_args"].as_str().expect("plan_args");
        let mut args = vec!["plan", "--cloud", pcd.to_str().unwrap(), "--json"];
        args.extend(plan_args.split_whitespace());
        let mut plan: serde_json::Value = serde_json::from_slice(&weldseam(&args)).expect("one JSON object");
        // Timings differ from run to run; everything else must not.
        plan.as_object_mut().unwrap().remove("timing_ms").expect("the plan reports its timings");
        let text = serde_json::to_string_pretty(&plan).unwrap() + "\n";
        let path = golden_path(joint);
        if bless {
            std::fs::write(&path, &text).unwrap();
            continue;
        }
        let golden = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e}; run with WELDSEAM_BLESS=1 to create it", path.display()));
        assert!(text == golden, "{joint}: plan --json differs from {}:\n{text}", path.display());
    }
}
