//! The `weldseam` binary's command-line contract, run as scripts run it:
//! `simulate` writes a frame, `plan --json` prints exactly one JSON object
//! on stdout with base-frame waypoints and the joint's figures along the
//! seam, errors exit non-zero naming the
//! failing stage; `serve`, `camera` and `controller` make a cell of three
//! processes, and `bench --quick` runs to its table.

use std::path::Path;
use std::process::{Command, Output};

/// `weldseam` run with `args`, its output collected.
pub fn weldseam(args: &[&str]) -> Output {
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
        // The joint's figures, one entry per waypoint, each with its
        // standard error (a lap's step, a butt joint's gap).
        let figures = seam["along_seam"].as_array().expect("along_seam");
        assert_eq!(figures.len(), wps.len(), "{joint}");
        let figure = if joint == "lap" { "lap_step_mm" } else { "gap_mm" };
        let measured = figures.iter().filter(|f| f[figure]["value"].is_number()).count();
        assert!(measured * 10 >= wps.len() * 9, "{joint}: {figure} at {measured} of {} waypoints", wps.len());
        assert!(figures.iter().all(|f| f[figure].is_null() || f[figure]["sigma"].as_f64().unwrap() > 0.0));
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

/// With a weld procedure configured (named relative to the config file),
/// `plan --json` gives each seam its process: per waypoint the passes and
/// their arc settings, null where a stretch is cut, and the cuts with
/// their rule ids.
#[test]
fn plan_json_carries_the_process_of_a_configured_procedure() {
    let dir = tempfile::tempdir().unwrap();
    let (pcd, truth) = simulate(dir.path(), "i-butt");
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/procedures/gmaw-mild-steel.toml");
    std::fs::copy(&shipped, dir.path().join("wps.toml")).unwrap();
    let config = dir.path().join("cell.toml");
    std::fs::write(&config, "[process]\nprocedure = \"wps.toml\"\nplate_thickness_mm = 6.0\n").unwrap();
    let pose = format!("--pose={}", pose_of(&truth));
    let args = ["plan", "--config", config.to_str().unwrap(), "--cloud", &pcd, "--joint", "i-butt", &pose, "--json"];
    let out = weldseam(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
    let seam = &v["seams"][0];
    let process = &seam["process"];
    let waypoints = process["waypoints"].as_array().expect("a process per waypoint");
    assert_eq!(waypoints.len(), seam["waypoints"].as_array().unwrap().len());
    let welded: Vec<&serde_json::Value> = waypoints.iter().filter(|w| !w.is_null()).collect();
    assert!(welded.len() * 10 >= waypoints.len() * 9, "{}", process["cut"]);
    for w in welded {
        let pass = &w["passes"][0];
        assert!(pass["wire_feed_m_min"].as_f64().unwrap() > 0.0 && pass["travel_speed_mm_s"].as_f64().unwrap() > 0.0);
    }
    for cut in process["cut"].as_array().expect("the cut stretches") {
        assert!(cut["rule"].as_str().unwrap().starts_with("process."), "{cut}");
    }
    // Without a procedure there is no process.
    let bare = weldseam(&["plan", "--cloud", &pcd, "--joint", "i-butt", &pose, "--json"]);
    let bare: serde_json::Value = serde_json::from_slice(&bare.stdout).expect("valid JSON");
    assert!(bare["seams"][0]["process"].is_null());
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
    // A lap frame planned as a butt joint: no two coplanar plates, but a
    // lap's step. With --json the refusal is on stdout too, as one object
    // (no trajectory in it), for scripts to read the code.
    let out = weldseam(&["plan", "--cloud", &pcd, "--joint", "i-butt", &pose, "--json"]);
    assert!(!out.status.success());
    let refusal: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    assert_eq!(refusal["error"]["stage"].as_str(), Some("background"), "{refusal}");
    assert_eq!(refusal["error"]["code"].as_str(), Some("joint_mismatch"), "{refusal}");
    assert!(refusal.get("seams").is_none(), "{refusal}");
    // The rule that refused: one of the catalogue's, of the stage that
    // refused, the one that reads a lap's step under a butt request.
    let rule = refusal["error"]["rule"].as_str().unwrap_or_else(|| panic!("no rule: {refusal}"));
    let known = weldseam::rules::by_id(rule).unwrap_or_else(|| panic!("{rule}: not in the catalogue"));
    assert_eq!((rule, known.stage.name()), ("joint.looks_like_lap", "background"), "{refusal}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("background stage failed"), "{err}");
    assert!(err.contains(&format!("(rule {rule})")), "the error names its rule: {err}");

    // The same frame under a set of types without the lap: decided as a
    // lap, and refused for not being one of them.
    let set = weldseam(&["plan", "--cloud", &pcd, "--joint", "v-butt+i-butt", &pose, "--json"]);
    assert!(!set.status.success());
    let refusal: serde_json::Value = serde_json::from_slice(&set.stdout).expect("one JSON object on stdout");
    assert_eq!(refusal["error"]["code"].as_str(), Some("joint_mismatch"), "{refusal}");
    assert_eq!(refusal["error"]["rule"].as_str(), Some("joint.not_requested"), "{refusal}");
    // The refusal names the set asked for.
    let err = String::from_utf8_lossy(&set.stderr);
    assert!(err.contains("not one of the joints requested (v_butt+i_butt)"), "{err}");
    let with_lap = weldseam(&["plan", "--cloud", &pcd, "--joint", "v-butt+lap", &pose, "--json"]);
    assert!(with_lap.status.success(), "{}", String::from_utf8_lossy(&with_lap.stderr));

    let missing = weldseam(&["plan", "--cloud", "no-such.pcd", "--joint", "lap", "--pose=0,0,0,0,0,0"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no-such.pcd"));

    let bad_joint = weldseam(&["plan", "--cloud", &pcd, "--joint", "fillet", "--pose=0,0,0,0,0,0"]);
    assert!(!bad_joint.status.success());
    assert!(String::from_utf8_lossy(&bad_joint.stderr).contains("unknown joint type"));
    let bad_set = weldseam(&["plan", "--cloud", &pcd, "--joint", "lap+auto", "--pose=0,0,0,0,0,0"]);
    assert!(!bad_set.status.success());
    assert!(String::from_utf8_lossy(&bad_set.stderr).contains("types joined by + such as v-butt+lap"));

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

    let deep = weldseam(&["plan", "--cloud", &pcd, "--joint", "v-butt", "--groove-depth", "500", "--pose=0,0,0,0,0,0"]);
    assert!(!deep.status.success());
    assert!(String::from_utf8_lossy(&deep.stderr).contains("groove depth 500 mm is outside"));
}

#[test]
fn demo_runs_and_meets_the_bar() {
    let out = weldseam(&["demo", "--brief"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    // One seam of each joint, then the three of the frame of several parts.
    assert_eq!(text.matches("within the 1 mm bar").count(), 6, "{text}");
    assert!(text.contains("3 seams, 0 not planned"), "{text}");
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
        let out = weldseam(&[
            "eval",
            "--filter",
            "i-butt-0",
            "--limit",
            "2",
            "--markdown",
            "--plans",
            path.to_str().unwrap(),
        ]);
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

/// `eval` prints aligned text for a terminal and Markdown for the
/// documents when asked: the same rows either way.
#[test]
fn eval_prints_text_by_default_and_markdown_with_the_flag() {
    let run = |extra: &[&str]| {
        let args: Vec<&str> =
            ["eval", "--filter", "lap-0", "--limit", "1", "--robust-only"].iter().chain(extra).copied().collect();
        let out = weldseam(&args);
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
        text
    };
    let text = run(&[]);
    assert!(!text.lines().any(|l| l.starts_with('|')), "no Markdown row without --markdown:\n{text}");
    let summary =
        text.lines().find(|l| l.starts_with("robust") && l.contains(" all ")).unwrap_or_else(|| panic!("{text}"));
    let words: Vec<&str> = summary.split_whitespace().collect();
    assert_eq!(words[..5], ["robust", "all", "1", "1", "1"], "{summary}");
    assert!(text.lines().any(|l| l.starts_with("lap-0") && l.contains("pass")), "{text}");
    // The lap's step along the seam against the scene's upper plate: one
    // scene, every waypoint measured, within 0.2 mm at the median.
    let step = text.lines().find(|l| l.contains("lap step")).unwrap_or_else(|| panic!("{text}"));
    let words: Vec<&str> = step.split_whitespace().collect();
    assert_eq!(words[..4], ["lap", "lap", "step", "1"], "{step}");
    assert!(words[4].parse::<usize>().unwrap() >= 10 && words[5] == "0", "{step}");
    assert!(words[6].parse::<f64>().unwrap() < 0.2 && words[7] == "mm", "{step}");

    let markdown = run(&["--markdown"]);
    assert!(markdown.contains("| robust | all | 1 | 1 | 1 |"), "{markdown}");
    assert!(markdown.lines().any(|l| l.starts_with("| lap-0") && l.contains("| pass |")), "{markdown}");
    assert!(markdown.contains("| --- | ---: |"), "a Markdown rule row:\n{markdown}");
}

#[test]
fn an_unknown_method_is_refused_before_anything_runs() {
    // `serve` would otherwise bind its ports; clap stops it first.
    let out = weldseam(&["serve", "--method", "fast"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("'fast'") && stderr.contains("possible values: robust, paper"), "{stderr}");
}

/// A `weldseam serve` child on 127.0.0.1 port 0, killed when dropped so a
/// failing test leaves no daemon behind.
struct ServeProcess {
    child: std::process::Child,
    camera: String,
    controller: String,
    text: String,
}

impl ServeProcess {
    /// Starts the daemon and learns its ports from its "listening" log line.
    fn start() -> ServeProcess {
        use std::io::BufRead;
        let mut child = Command::new(env!("CARGO_BIN_EXE_weldseam"))
            .args(["--log-format", "json", "serve", "--camera-listen", "127.0.0.1:0"])
            .args(["--controller-listen", "127.0.0.1:0", "--text-listen", "127.0.0.1:0"])
            .env_remove("RUST_LOG")
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("start weldseam serve");
        let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
        let (tx, rx) = std::sync::mpsc::channel();
        // Reads every log line, so the daemon never blocks on a full pipe.
        std::thread::spawn(move || {
            for line in stderr.lines().map_while(Result::ok) {
                let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) else { continue };
                let fields = &v["fields"];
                if fields["message"] == "listening" {
                    let addr = |k: &str| fields[k].as_str().unwrap_or_default().to_string();
                    let _ = tx.send((addr("camera"), addr("controller"), addr("text")));
                }
            }
        });
        let (camera, controller, text) = match rx.recv_timeout(std::time::Duration::from_secs(60)) {
            Ok(addrs) => addrs,
            Err(_) => {
                let _ = child.kill();
                panic!("serve logged no listening line within 60 s: {:?}", child.wait());
            }
        };
        assert!(camera.starts_with("127.0.0.1:") && !camera.ends_with(":0"), "{camera}");
        assert!(controller.starts_with("127.0.0.1:") && !controller.ends_with(":0"), "{controller}");
        assert!(text.starts_with("127.0.0.1:") && !text.ends_with(":0"), "{text}");
        ServeProcess { child, camera, controller, text }
    }

    /// SIGTERM, then the exit status within a generous deadline.
    fn terminate(mut self) -> std::process::ExitStatus {
        let pid = libc::pid_t::try_from(self.child.id()).unwrap();
        // SAFETY: signals our own child, which is not yet reaped.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGTERM) }, 0);
        wait_at_most(&mut self.child, std::time::Duration::from_secs(60)).expect("serve stops on SIGTERM")
    }
}

impl Drop for ServeProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The child's status once it exits, or None after `limit`.
fn wait_at_most(child: &mut std::process::Child, limit: std::time::Duration) -> Option<std::process::ExitStatus> {
    let deadline = std::time::Instant::now() + limit;
    while std::time::Instant::now() < deadline {
        if let Some(status) = child.try_wait().expect("poll the child") {
            return Some(status);
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    None
}

/// The cell as three processes: `serve` on ephemeral ports, a `camera`
/// serving a simulated frame on trigger, and `controller` asking for its
/// plan and pinging, on the binary link and as a robot program on the
/// text link; then SIGTERM stops the daemon cleanly.
#[test]
fn serve_camera_and_controller_run_as_processes() {
    let dir = tempfile::tempdir().unwrap();
    let (_, truth) = simulate(dir.path(), "i-butt");
    let serve = ServeProcess::start();

    let mut camera = Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["camera", "--connect", &serve.camera, "--simulate", "i-butt", "--name", "cli-camera"])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start weldseam camera");
    // The camera simulates its frame before it connects: wait for it.
    let mut connected = false;
    for _ in 0..600 {
        let ping = weldseam(&["controller", "--connect", &serve.controller, "--ping", "--json"]);
        assert!(ping.status.success(), "ping: {}", String::from_utf8_lossy(&ping.stderr));
        let status: serde_json::Value = serde_json::from_slice(&ping.stdout).expect("ping --json prints JSON");
        if status["cameras"] == 1 {
            connected = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(connected, "the camera process never connected");

    let pose = format!("--pose={}", pose_of(&truth));
    let plan = weldseam(&["controller", "--connect", &serve.controller, "--joint", "i_butt", &pose, "--json"]);
    let text =
        weldseam(&["controller", "--text", "--dialect", "kuka", "--connect", &serve.text, "--joint", "i_butt", &pose]);
    let _ = camera.kill();
    let _ = camera.wait();
    assert!(plan.status.success(), "controller: {}", String::from_utf8_lossy(&plan.stderr));
    let reply: serde_json::Value = serde_json::from_slice(&plan.stdout).expect("controller --json prints JSON");
    assert_eq!(reply["request_id"], 1);
    let seam = &reply["result"]["seams"][0];
    assert_eq!(seam["joint"], "i_butt");
    assert!(seam["waypoints"].as_array().is_some_and(|w| w.len() >= 10), "{reply}");
    // Asked for along_seam: the figures at every waypoint (no procedure
    // configured, so no process).
    assert_eq!(seam["along_seam"].as_array().map(Vec::len), seam["waypoints"].as_array().map(Vec::len), "{reply}");
    assert!(seam["process"].is_null(), "{reply}");
    // The text session: hello, trigger, every waypoint line pulled,
    // approach first and retract last, and the seam's check.
    let session = String::from_utf8_lossy(&text.stdout);
    assert!(text.status.success(), "controller --text: {session}{}", String::from_utf8_lossy(&text.stderr));
    let lines: Vec<&str> = session.lines().collect();
    assert_eq!(lines[..2], ["> HELLO,kuka", "< 0,2,0"], "{session}");
    assert!(lines[2].starts_with("> TRIGGER,i_butt,") && lines[3].starts_with("< 0,1,"), "{session}");
    let pulled: Vec<&str> =
        lines.iter().filter(|l| l.starts_with("< ") && l.matches(',').count() == 8).copied().collect();
    assert_eq!(pulled.len(), seam["waypoints"].as_array().unwrap().len() + 2, "{session}");
    assert!(pulled[0].starts_with("< 1,1,") && pulled[pulled.len() - 1].starts_with("< 3,1,0,"), "{session}");
    // The seam held against the daemon's check: its count and mean position.
    let check = lines.iter().position(|l| *l == "> CHECK,1").expect("the seam checked");
    assert!(lines[check + 1].starts_with(&format!("< 0,{},", pulled.len())), "{session}");

    let status = serve.terminate();
    assert!(status.success(), "serve exited with {status}");
}

/// `bench` at its smallest runs to the end and prints the per-stage table
/// with a row per stage and a total.
#[test]
fn bench_quick_runs_as_a_process() {
    let out = weldseam(&["bench", "--quick", "--stages-only", "--runs", "1"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("Per stage at 500 mm"), "{text}");
    for row in ["plane_points", "total", "valid points", "Mpoints/s"] {
        assert!(text.lines().any(|l| l.starts_with(row)), "no {row} row in\n{text}");
    }
}

/// `simulate --variant` writes the capture as a tool would (here without
/// its grid, as PLY, and downsampled, as PCD), and says so in the truth.
#[test]
fn simulate_writes_variants_as_ply_and_pcd() {
    let dir = tempfile::tempdir().unwrap();
    let run = |variant: &str, file: &str| {
        let (out, json) = (dir.path().join(file), dir.path().join(format!("{file}.json")));
        let args = ["simulate", "--joint", "i-butt", "--variant", variant, "--out", out.to_str().unwrap()];
        let status = weldseam(&[&args[..], &["--truth", json.to_str().unwrap()]].concat());
        assert!(status.status.success(), "{variant}: {}", String::from_utf8_lossy(&status.stderr));
        let truth: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (weldseam::cloud::load(&out).expect("the written cloud loads"), truth)
    };
    let (unorganized, truth) = run("unorganized", "frame.ply");
    assert!(!unorganized.is_organized());
    assert_eq!(truth["variant"]["points"].as_u64(), Some(unorganized.len() as u64));
    assert_eq!(unorganized.valid_count(), unorganized.len(), "valid points only");
    let (voxel, truth) = run("voxel:2", "voxel.pcd");
    assert_eq!(truth["variant"]["name"], "voxel:2");
    assert!(voxel.len() > 1000 && voxel.len() * 4 < unorganized.len(), "{} of {}", voxel.len(), unorganized.len());

    let bad = weldseam(&["simulate", "--joint", "lap", "--variant", "voxel:0", "--out", "x.pcd"]);
    assert!(!bad.status.success());
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(stderr.contains("voxel:0 is outside 0.05 to 50 mm"), "{stderr}");
}

/// `eval --variant` plans the suite on the variant and reports each scene,
/// planned or refused, without crashing.
#[test]
fn eval_runs_its_suite_on_a_variant() {
    let out = weldseam(&["eval", "--filter", "i-butt-00", "--limit", "1", "--robust-only", "--variant", "voxel:2"]);
    let text = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // A scene that misses the bar makes eval exit 1 with that message; a
    // crash or a refused argument would not.
    assert!(out.status.success() || stderr.contains("miss the bar"), "{text}\n{stderr}");
    assert!(text.contains("1 scenes as voxel:2 frames"), "{text}");
    let row = text.lines().find(|l| l.starts_with("i-butt-00")).unwrap_or_else(|| panic!("no scene row in\n{text}"));
    assert!(row.contains("pass") || row.contains("FAIL"), "{row}");
}

#[test]
fn plan_reads_a_compressed_cloud_in_metres_and_refuses_it_as_millimetres() {
    use weldseam::cloud::{PointCloud, load, pcd};
    let dir = tempfile::tempdir().unwrap();
    let (frame, truth) = simulate(dir.path(), "lap");
    let pose = format!("--pose={}", pose_of(&truth));
    let cloud = load(Path::new(&frame)).unwrap();
    let metres: Vec<_> = cloud.points().iter().map(|p| p.map(|c| c * 1e-3)).collect();
    let metres = PointCloud::organized(cloud.width(), cloud.height(), metres).unwrap();
    let path = dir.path().join("lap_metres.pcd");
    let mut bytes = Vec::new();
    pcd::write_binary_compressed(&metres, &mut bytes).unwrap();
    std::fs::write(&path, bytes).unwrap();
    let path = path.to_str().unwrap();
    let first_waypoint = |args: &[&str]| {
        let out = weldseam(args);
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let xyz = v["seams"][0]["waypoints"][0]["xyz"].as_array().unwrap().clone();
        xyz.iter().map(|x| x.as_f64().unwrap()).collect::<Vec<f64>>()
    };
    let in_mm = first_waypoint(&["plan", "--cloud", &frame, "--joint", "lap", &pose, "--json"]);
    for units in ["auto", "m"] {
        let in_m = first_waypoint(&["plan", "--cloud", path, "--joint", "lap", &pose, "--units", units, "--json"]);
        let d: f64 = in_mm.iter().zip(&in_m).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        assert!(d < 0.05, "--units {units}: {in_m:?} vs {in_mm:?}");
    }
    let as_mm = weldseam(&["plan", "--cloud", path, "--joint", "lap", &pose, "--units", "mm"]);
    assert!(!as_mm.status.success());
    assert!(
        String::from_utf8_lossy(&as_mm.stderr).contains("millimetres"),
        "{}",
        String::from_utf8_lossy(&as_mm.stderr)
    );
}

/// `inspect` tells a raw frame from the same capture voxel-downsampled in
/// metres, as text and as JSON, and names a file it cannot read.
#[test]
fn inspect_tells_a_raw_frame_from_a_downsampled_cloud_in_metres() {
    let dir = tempfile::tempdir().unwrap();
    let (frame, _) = simulate(dir.path(), "v-butt");
    let voxel = dir.path().join("voxel.ply");
    let out =
        weldseam(&["simulate", "--joint", "v-butt", "--variant", "voxel:1,metres", "--out", voxel.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let inspect = |file: &str| {
        let out = weldseam(&["inspect", file, "--json"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let raw = inspect(&frame);
    assert_eq!(raw["organized"]["width"], 1920);
    assert_eq!(raw["units"]["guess"], "mm");
    assert_eq!(raw["density"], "camera");
    assert!(raw["intrinsics"]["fx"].as_f64().unwrap() > 0.0);
    let voxel = inspect(voxel.to_str().unwrap());
    assert!(voxel["organized"].is_null());
    assert_eq!(voxel["units"]["guess"], "m");
    assert_eq!(voxel["density"], "measured");
    assert_eq!(voxel["regrid"]["raw_frame"], false);
    let spacing = voxel["spacing_mm"].as_f64().unwrap();
    assert!((0.7..1.4).contains(&spacing), "a 1 mm voxel grid measured at {spacing} mm");
    assert!(voxel["depth_mm"][0].as_f64().unwrap() > 100.0, "depth in mm: {}", voxel["depth_mm"]);

    let text = weldseam(&["inspect", &frame]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("1920 x 1200") && text.contains("camera model"), "{text}");
    let missing = weldseam(&["inspect", "no-such-file.pcd"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no-such-file.pcd"));
}

/// `simulate --fault` and `--suite-scene` write one fault or hard scene
/// for a person to look at, with its right answer in the truth.
#[test]
fn simulate_writes_fault_and_hard_scenes_with_their_right_answer() {
    let dir = tempfile::tempdir().unwrap();
    let write = |args: &[&str], stem: &str| -> serde_json::Value {
        let (pcd, json) = (dir.path().join(format!("{stem}.pcd")), dir.path().join(format!("{stem}.json")));
        let mut all = vec!["simulate", "--out", pcd.to_str().unwrap(), "--truth", json.to_str().unwrap()];
        all.extend(args);
        let out = weldseam(&all);
        assert!(out.status.success(), "{stem}: {}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap()
    };
    let clamp = write(&["--joint", "lap", "--fault", "clamp"], "clamp");
    assert_eq!(clamp["right_answer"]["pieces_mm"].as_array().map(Vec::len), Some(2), "{clamp}");
    assert!(clamp["parameters"]["faults"][0].as_str().unwrap().starts_with("Clamp"), "{clamp}");
    let wrong = write(&["--joint", "i-butt", "--fault", "wrong-joint"], "wrong");
    assert_eq!(wrong["right_answer"]["refuse"], true);
    assert!(wrong["plan_args"].as_str().unwrap().starts_with("--joint lap "), "{wrong}");
    let fault_name = weldseam::sim::fault_suite(weldseam::sim::Draw::Documented)
        .into_iter()
        .find(|(n, _)| n.contains("streaks"))
        .unwrap()
        .0;
    let streaks = write(&["--suite-scene", &fault_name], "streaks");
    assert_eq!(streaks["scene"], fault_name.as_str());
    let hard_name = weldseam::sim::hard_suite(weldseam::sim::Draw::Documented).swap_remove(30).0;
    let hard = write(&["--suite-scene", &hard_name], "hard");
    assert!(hard["parameters"]["noise"]["depth_noise_scale"].as_f64().unwrap() > 1.0, "{hard}");
    let out = weldseam(&["simulate", "--joint", "lap", "--fault", "rust", "--out", "x.pcd"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown fault"), "{out:?}");
}

/// The width and height of a PNG file.
fn png_size(path: &Path) -> (u32, u32) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let reader = png::Decoder::new(file).read_info().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let info = reader.info();
    (info.width, info.height)
}

#[test]
fn plan_debug_writes_pictures_and_figures_that_match_plan_json() {
    let dir = tempfile::tempdir().unwrap();
    let (pcd, truth) = simulate(dir.path(), "i-butt");
    let pose = format!("--pose={}", pose_of(&truth));
    let plan = |joint: &str, debug: Option<&Path>| {
        let mut args = vec!["plan", "--cloud", pcd.as_str(), "--joint", joint, pose.as_str(), "--json"];
        if let Some(dir) = debug {
            args.extend(["--debug", dir.to_str().unwrap()]);
        }
        let out = weldseam(&args);
        let stdout: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
        (out.status.success(), stdout)
    };

    let debug = dir.path().join("debug/i-butt");
    let (planned, printed) = plan("i-butt", Some(&debug));
    assert!(planned, "{printed}");
    let (_, plain) = plan("i-butt", None);
    assert_eq!(printed["seams"], plain["seams"], "--debug changes nothing about the plan");
    let figures: serde_json::Value = serde_json::from_slice(&std::fs::read(debug.join("trace.json")).unwrap()).unwrap();
    // The figures hold the plan exactly as printed, timings and all.
    assert_eq!(figures["plan"], printed, "trace.json's plan is what --json printed");
    assert!(figures["error"].is_null());
    assert_eq!(figures["points"]["plates"], printed["points"]["plates"]);
    assert_eq!(figures["points"]["edges"], printed["points"]["edges"]);
    let waypoints = printed["seams"][0]["waypoints"].as_array().unwrap().len();
    assert_eq!(figures["waypoints_camera"].as_array().unwrap().len(), waypoints);
    let picked = figures["edge_lines"].as_array().unwrap().iter().filter(|l| l["picked"] == true).count();
    assert_eq!(picked, 2);
    let (width, height) = png_size(&debug.join("camera.png"));
    assert!(width == 960 && (600..900).contains(&height), "camera.png is {width} x {height}");
    let (width, height) = png_size(&debug.join("sections.png"));
    assert!(width == 960 && (660..900).contains(&height), "sections.png is {width} x {height}");

    // A refusal: the camera view and the figures, with the error as printed.
    let refused = dir.path().join("debug/as-lap");
    let (planned, printed) = plan("lap", Some(&refused));
    assert!(!planned);
    let figures: serde_json::Value =
        serde_json::from_slice(&std::fs::read(refused.join("trace.json")).unwrap()).unwrap();
    assert_eq!(figures["error"], printed["error"], "{printed}");
    assert!(figures["plan"].is_null() && figures["weld"].is_null());
    assert_eq!(png_size(&refused.join("camera.png")).0, 960);
    assert!(!refused.join("sections.png").exists(), "no weld, no sections");
}

#[test]
fn rules_lists_the_catalogue_prints_one_and_refuses_an_unknown_id() {
    let list = weldseam(&["rules"]);
    assert!(list.status.success(), "{}", String::from_utf8_lossy(&list.stderr));
    let text = String::from_utf8_lossy(&list.stdout);
    let rows: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(rows.len(), weldseam::rules::all().count(), "one line a rule:\n{text}");
    for (row, rule) in rows.iter().zip(weldseam::rules::all()) {
        let fields: Vec<&str> = row.split("  ").filter(|f| !f.is_empty()).map(str::trim).collect();
        assert_eq!(fields.first(), Some(&rule.id), "{row}");
        assert_eq!(fields.get(1), Some(&rule.stage.name()), "{row}");
        assert!(row.ends_with(rule.summary), "{row}");
    }

    let one = weldseam(&["rules", "frame.no_valid_point"]);
    assert!(one.status.success());
    let text = String::from_utf8_lossy(&one.stdout);
    let rule = weldseam::rules::by_id("frame.no_valid_point").unwrap();
    assert!(text.starts_with("frame.no_valid_point\n"), "{text}");
    assert!(text.contains(rule.reason) && text.contains("camera.min_depth_mm"), "{text}");
    assert!(text.contains("tests/pipeline.rs::bad_requests_are_refused_before_any_work"), "{text}");

    let markdown = weldseam(&["rules", "--markdown"]);
    assert!(markdown.status.success());
    assert_eq!(String::from_utf8_lossy(&markdown.stdout), weldseam::rules::markdown());

    let unknown = weldseam(&["rules", "lap.no_such_rule"]);
    assert!(!unknown.status.success());
    assert!(unknown.stdout.is_empty());
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("\"lap.no_such_rule\""), "{unknown:?}");
}
