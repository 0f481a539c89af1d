//! The `weldseam` binary's command-line contract, run as scripts run it:
//! `simulate` writes a frame, `plan --json` prints exactly one JSON object
//! on stdout with base-frame waypoints, errors exit non-zero naming the
//! failing stage.

use std::path::Path;
use std::process::{Command, Output};

fn weldseam(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_weldseam")).args(args).output().expect("run weldseam")
}

fn simulate(dir: &Path, joint: &str) -> (String, serde_json::Value) {
    let pcd = dir.join(format!("{joint}.pcd"));
    let json = dir.join(format!("{joint}.json"));
    let out =
        weldseam(&["simulate", "--joint", joint, "--out", pcd.to_str().unwrap(), "--truth", json.to_str().unwrap()]);
    assert!(out.status.success(), "simulate: {}", String::from_utf8_lossy(&out.stderr));
    let truth: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    (pcd.to_str().unwrap().to_string(), truth)
}

fn pose_of(truth: &serde_json::Value) -> String {
    let p: Vec<String> = truth["pose"].as_array().expect("pose array").iter().map(|v| v.to_string()).collect();
    p.join(",")
}

#[test]
fn plan_json_honours_the_contract_for_each_joint() {
    let dir = tempfile::tempdir().unwrap();
    for (joint, flag_joint, extra) in
        [("v-butt", "v_butt", vec!["--groove-depth"]), ("i-butt", "i-butt", vec![]), ("lap", "lap", vec![])]
    {
        let (pcd, truth) = simulate(dir.path(), joint);
        let pose = format!("--pose={}", pose_of(&truth));
        let depth = truth["truth"]["groove_depth_mm"].as_f64().map(|d| d.to_string());
        let mut args = vec!["plan", "--cloud", pcd.as_str(), "--joint", flag_joint, pose.as_str(), "--json"];
        if let (Some(flag), Some(d)) = (extra.first(), depth.as_ref()) {
            args.extend([*flag, d.as_str()]);
        }
        let out = weldseam(&args);
        assert!(out.status.success(), "{joint}: {}", String::from_utf8_lossy(&out.stderr));
        let stdout = String::from_utf8(out.stdout).unwrap();
        assert_eq!(stdout.trim().lines().count(), 1, "stdout is exactly one JSON object");
        let v: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON");
        let seam = &v["seams"][0];
        assert_eq!(seam["joint"], joint.replace('-', "_"));
        let wps = seam["waypoints"].as_array().expect("waypoints");
        assert!(wps.len() >= 10);
        for w in wps {
            assert_eq!(w["xyz"].as_array().unwrap().len(), 3);
            assert_eq!(w["rpy_deg"].as_array().unwrap().len(), 3);
        }
        assert!(v["timing_ms"]["total"].as_f64().unwrap() > 0.0);
        assert!(v["timing_ms"]["plane_points"].is_number());
        // The first waypoint lies on the true seam's line, base frame.
        let start: Vec<f64> =
            truth["truth"]["start_base"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let end: Vec<f64> =
            truth["truth"]["end_base"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let first: Vec<f64> = wps[0]["xyz"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let d = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt();
        assert!(
            d(&first, &start).min(d(&first, &end)) < 2.0,
            "{joint}: first waypoint {first:?} vs ends {start:?} {end:?}"
        );
    }
}

#[test]
fn pose_values_starting_with_a_minus_sign_work_in_both_flag_forms() {
    let dir = tempfile::tempdir().unwrap();
    let (pcd, truth) = simulate(dir.path(), "i-butt");
    let pose = pose_of(&truth);
    let separate = weldseam(&["plan", "--cloud", &pcd, "--joint", "i_butt", "--pose", "-1,-2,-3,-4,-5,-6", "--json"]);
    assert!(separate.status.success(), "{}", String::from_utf8_lossy(&separate.stderr));
    let joined = weldseam(&["plan", "--cloud", &pcd, "--joint", "i_butt", &format!("--pose={pose}"), "--json"]);
    assert!(joined.status.success());
    let hand_eye = "1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1";
    let with_matrix = weldseam(&[
        "plan",
        "--cloud",
        &pcd,
        "--joint",
        "i-butt",
        &format!("--pose={pose}"),
        "--hand-eye",
        hand_eye,
        "--step",
        "10",
    ]);
    assert!(with_matrix.status.success(), "{}", String::from_utf8_lossy(&with_matrix.stderr));
    let text = String::from_utf8(with_matrix.stdout).unwrap();
    assert!(text.contains("waypoints every 10 mm"), "{text}");
}

#[test]
fn failures_exit_non_zero_and_say_why() {
    let dir = tempfile::tempdir().unwrap();
    let (pcd, truth) = simulate(dir.path(), "lap");
    let pose = format!("--pose={}", pose_of(&truth));
    // A lap frame planned as a butt joint: no two coplanar plates.
    let out = weldseam(&["plan", "--cloud", &pcd, "--joint", "i-butt", &pose, "--json"]);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty(), "nothing on stdout on failure");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("background stage failed"), "{err}");

    let missing = weldseam(&["plan", "--cloud", "no-such.pcd", "--joint", "lap", "--pose=0,0,0,0,0,0"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no-such.pcd"));

    let bad_joint = weldseam(&["plan", "--cloud", &pcd, "--joint", "fillet", "--pose=0,0,0,0,0,0"]);
    assert!(!bad_joint.status.success());
    assert!(String::from_utf8_lossy(&bad_joint.stderr).contains("unknown joint type"));

    let bad_matrix = weldseam(&[
        "plan",
        "--cloud",
        &pcd,
        "--joint",
        "lap",
        "--pose=0,0,0,0,0,0",
        "--hand-eye",
        "1,0,0,0,0,1,0,0,0,0,1,0,0,0,0",
    ]);
    assert!(!bad_matrix.status.success());
    assert!(String::from_utf8_lossy(&bad_matrix.stderr).contains("16"));

    let no_depth = weldseam(&["plan", "--cloud", &pcd, "--joint", "v-butt", "--pose=0,0,0,0,0,0"]);
    assert!(!no_depth.status.success());
    assert!(String::from_utf8_lossy(&no_depth.stderr).contains("groove depth"));
}

#[test]
fn demo_runs_and_meets_the_bar() {
    let out = weldseam(&["demo", "--brief"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(text.matches("within the 1 mm bar").count(), 3, "{text}");
}

#[test]
fn error_texts_say_each_cause_once_and_name_the_request_not_the_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let (pcd, truth) = simulate(dir.path(), "v-butt");
    let pose = format!("--pose={}", pose_of(&truth));
    let stderr = |out: &Output| String::from_utf8_lossy(&out.stderr).into_owned();

    let missing = weldseam(&["plan", "--cloud", "no-such.pcd", "--joint", "lap", "--pose=0,0,0,0,0,0"]);
    let text = stderr(&missing);
    assert!(!missing.status.success());
    assert_eq!(text.matches("os error 2").count(), 1, "the cause is printed once: {text}");

    // A negative number is a value, refused by the request's own check,
    // not taken for a flag or blamed on the cloud.
    for args in [["--groove-depth", "-1"], ["--step", "-5"]] {
        let mut argv = vec!["plan", "--cloud", pcd.as_str(), "--joint", "v-butt", pose.as_str()];
        argv.extend(args);
        if args[0] == "--step" {
            argv.extend(["--groove-depth", "6"]);
        }
        let out = weldseam(&argv);
        let text = stderr(&out);
        assert!(!out.status.success());
        assert!(text.starts_with("error: invalid request:"), "{args:?}: {text}");
        assert!(!text.contains("no seam found") && !text.contains("unexpected argument"), "{text}");
    }

    let config = dir.path().join("bad-hand-eye.toml");
    let mut rows = weldseam::geometry::pose::PAPER_HAND_EYE;
    rows[4] = -0.353;
    std::fs::write(&config, format!("[robot]\nhand_eye = {rows:?}\n")).unwrap();
    let out = weldseam(&["plan", "--config", config.to_str().unwrap(), "--cloud", &pcd, "--joint", "lap", &pose]);
    let text = stderr(&out);
    assert!(!out.status.success());
    assert_eq!(text.matches("orthonormal").count(), 1, "{text}");
}

#[test]
fn log_lines_carry_no_colour_codes_when_stderr_is_not_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let (pcd, truth) = simulate(dir.path(), "lap");
    let pose = format!("--pose={}", pose_of(&truth));
    let out = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["plan", "--cloud", &pcd, "--joint", "lap", &pose, "--json"])
        .env("RUST_LOG", "info")
        .output()
        .expect("run weldseam");
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("INFO"), "an info line was logged: {text}");
    assert!(!text.contains('\u{1b}'), "no escape codes in a pipe: {text:?}");
}

#[test]
fn eval_runs_as_a_process_and_its_plans_file_repeats_digit_for_digit() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str| {
        let path = dir.path().join(name);
        let out = weldseam(&["eval", "--filter", "i-butt-0", "--limit", "2", "--plans", path.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
        assert!(text.contains("| robust | all | 2 | 2 | 2 |"), "{text}");
        std::fs::read_to_string(path).unwrap()
    };
    let first = run("a.jsonl");
    let lines: Vec<serde_json::Value> = first.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    // Two scenes, each planned by the robust and the paper's method.
    assert_eq!(lines.len(), 4, "{first}");
    assert_eq!(lines[0]["method"], "robust");
    assert_eq!(lines[1]["method"], "paper");
    let waypoints = lines[0]["plan"]["seams"][0]["waypoints"].as_array().expect("the robust plan has waypoints");
    assert!(waypoints.len() >= 10);
    assert!(!first.contains("timing"), "no run-to-run timings in the plans file");
    assert_eq!(first, run("b.jsonl"), "the same suite plans the same, to the last digit");
}

#[test]
fn an_unknown_method_is_refused_before_anything_runs() {
    // `serve` would otherwise bind its ports; clap stops it first.
    let out = weldseam(&["serve", "--method", "fast"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("'fast'") && stderr.contains("possible values: robust, paper"), "{stderr}");
}
