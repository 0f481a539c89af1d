//! The text controller link over loopback, as robot programs use it: each
//! dialect end to end against the daemon, its pulled poses the binary
//! link's waypoints after unit and convention conversion; the sessions
//! ROBOTS.md shows, replayed; the URScript example's lines, its replies
//! read as `socket_read_ascii_float` reads them; the RAPID replies held to
//! 80 characters and `StrToVal`'s numbers; malformed lines, a robot that
//! leaves mid-pull, a busy link and a line without its end.
//!
//! `WELDSEAM_BLESS=1 cargo test --test tests text_link::` rewrites the
//! transcripts in ROBOTS.md after a deliberate change of the lines.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use tokio::io::AsyncReadExt;
use tokio::net::TcpStream;
use weldseam::config::Config;
use weldseam::convert::to_text;
use weldseam::geometry::Isometry3;
use weldseam::joint::JointType;
use weldseam::mock::camera::CameraOptions;
use weldseam::mock::controller::{ControllerClient, request_for_simulation};
use weldseam::mock::text_robot::{SeamTally, TextRobot, rapid_num, ur_read_ascii_float};
use weldseam::server::Stopped;
use weldseam::sim::Simulation;
use weldseam_proto::message::{FrameSelect, PlanReply};
use weldseam_proto::text::{ABB_MAX_LINE, Dialect, MAX_ERROR_LINE, UR_MAX_NUMBERS};

use crate::scenes;
use crate::util::Cell;

const WAIT: Duration = Duration::from_secs(120);

/// Short transcripts: a waypoint every 25 mm.
fn config() -> Config {
    let mut c = Config::default();
    c.server.fresh_frame_timeout = Duration::from_secs(10);
    c.server.pipeline_threads = 2;
    c.server.shutdown_grace = Duration::from_secs(60);
    c.trajectory.step_mm = 25.0;
    c.text_link.line_timeout = Duration::from_millis(300);
    c
}

fn text_addr(cell: &Cell) -> String {
    cell.daemon.text_addr.to_string()
}

async fn robot(cell: &Cell) -> TextRobot {
    TextRobot::connect(&text_addr(cell), WAIT).await.unwrap()
}

/// The capture pose's numbers in `dialect`, written with its decimals, and
/// a robot's plan line for them (URScript's as `to_str` writes a pose).
fn trigger_line(dialect: Dialect, sim: &Simulation) -> String {
    trigger_line_for("lap", dialect, sim)
}

/// [`trigger_line`] requesting `joint`.
pub(crate) fn trigger_line_for(joint: &str, dialect: Dialect, sim: &Simulation) -> String {
    let convention = to_text::convention(dialect);
    let numbers = convention.numbers(&sim.pose.to_isometry(Default::default()));
    let (position, rotation) = dialect.decimals();
    let fields: Vec<String> = numbers[..convention.numbers_len()]
        .iter()
        .enumerate()
        .map(|(k, v)| format!("{v:.*}", if k < 3 { position } else { rotation }))
        .collect();
    match dialect {
        Dialect::Ur => format!("TRIGGER,{joint},p[{}]", fields.join(", ")),
        _ => format!("TRIGGER,{joint},{}", fields.join(",")),
    }
}

/// The numbers of a reply line: UR's inside the parentheses.
fn numbers(reply: &str) -> Vec<f64> {
    reply.trim().trim_matches(['(', ')']).split(',').map(|f| f.parse().unwrap()).collect()
}

/// One robot session: hello, trigger, the first waypoint, the trigger
/// again before the rest is pulled (refused), every other waypoint, the
/// seam's check (held against the lines pulled), one pull too many
/// (refused) and its reason.
async fn session(robot: &mut TextRobot, dialect: Dialect, trigger: &str) -> Vec<(String, String)> {
    let mut lines = Vec::new();
    let mut say = async |line: &str| {
        let reply = robot.ask(line).await.unwrap();
        lines.push((line.to_string(), reply.clone()));
        reply
    };
    let hello = say(&format!("HELLO,{}", dialect.name())).await;
    assert_eq!(numbers(&hello)[0], 0.0, "{hello}");
    let ok = say(trigger).await;
    let status = numbers(&ok);
    assert_eq!(&status[..2], &[0.0, 1.0], "one seam planned: {ok}");
    let count = status[2] as usize;
    let mut tally = SeamTally::default();
    let mut count_in = |reply: &str| {
        let n = numbers(reply);
        tally.add([n[3], n[4], n[5]]);
    };
    count_in(&say("NEXT").await);
    let refused = say(trigger).await;
    assert!(refused.trim_start_matches('(').starts_with("-6,"), "{refused}");
    for _ in 1..count {
        count_in(&say("NEXT").await);
    }
    let check = say("CHECK,1").await;
    tally.agrees(&numbers(&check), dialect).unwrap_or_else(|e| panic!("{dialect:?}: {e}: {check}"));
    let over = say("NEXT").await;
    assert!(over.trim_start_matches('(').starts_with("-6"), "{over}");
    say("WHY").await;
    lines
}

fn transcript(lines: &[(String, String)]) -> String {
    lines.iter().map(|(sent, reply)| format!("> {sent}\n< {}\n", reply.trim_end())).collect()
}

fn robots_md() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("proto/ROBOTS.md")
}

/// The transcript block of `dialect` in ROBOTS.md: the lines after its
/// marker, inside the fence.
fn documented(doc: &str, dialect: Dialect) -> Option<(usize, usize)> {
    let marker = format!("<!-- transcript:{} -->", dialect.name());
    let at = doc.find(&marker)?;
    let start = at + doc[at..].find("```text\n")? + "```text\n".len();
    let end = start + doc[start..].find("```")?;
    Some((start, end))
}

/// Two transcripts agree: the same lines, numbers within one unit of
/// their last printed decimal (the last digit may round either way on
/// another machine), text exactly.
fn same_transcript(a: &str, b: &str) -> Result<(), String> {
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    if la.len() != lb.len() {
        return Err(format!("{} lines documented, {} replayed", la.len(), lb.len()));
    }
    for (x, y) in la.iter().zip(&lb) {
        let fx: Vec<&str> = x.split([',', '(', ')', '[', ']']).collect();
        let fy: Vec<&str> = y.split([',', '(', ')', '[', ']']).collect();
        let agree = fx.len() == fy.len()
            && fx.iter().zip(&fy).all(|(p, q)| match (p.trim().parse::<f64>(), q.trim().parse::<f64>()) {
                (Ok(u), Ok(v)) => {
                    let decimals = p.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
                    (u - v).abs() <= 1.01 * 10f64.powi(-decimals)
                }
                _ => p == q,
            });
        if !agree {
            return Err(format!("documented {x:?}, replayed {y:?}"));
        }
    }
    Ok(())
}

/// Every waypoint line of a session: (kind, seam, remaining, pose).
fn pulled(lines: &[(String, String)]) -> Vec<(u8, u32, u64, Vec<f64>)> {
    lines
        .iter()
        .filter(|(sent, reply)| sent == "NEXT" && !reply.trim_start_matches('(').starts_with('-'))
        .map(|(_, reply)| {
            let n = numbers(reply);
            (n[0] as u8, n[1] as u32, n[2] as u64, n[3..].to_vec())
        })
        .collect()
}

/// The binary link's reply for the pose the daemon read from `trigger`.
async fn binary_plan(
    ctl: &mut ControllerClient,
    id: u64,
    dialect: Dialect,
    trigger: &str,
    sim: &Simulation,
) -> PlanReply {
    let convention = to_text::convention(dialect);
    let fields: Vec<f64> = trigger
        .split(',')
        .skip(2)
        .map(|f| f.trim().trim_start_matches("p[").trim_end_matches(']').parse().unwrap())
        .collect();
    let pose = convention.to_robot_pose(&fields, Default::default()).unwrap();
    let mut request = request_for_simulation(id, JointType::Lap, sim, FrameSelect::Trigger);
    let [x, y, z] = pose.xyz_mm;
    let [rx, ry, rz] = pose.angles_deg;
    request.pose = [x, y, z, rx, ry, rz];
    ctl.plan(request, WAIT).await.unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_dialect_pulls_the_binary_links_waypoints_as_robots_md_shows() {
    let sim = scenes::demo(JointType::Lap);
    let cell = Cell::start(config()).await;
    let (stop_camera, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut ctl = ControllerClient::connect(&cell.controller, "test").await.unwrap();
    ctl.wait_for_camera(Duration::from_secs(5)).await.unwrap();
    let offset = cell.daemon.state.config.text_link.approach_offset_mm;
    let bless = std::env::var_os("WELDSEAM_BLESS").is_some();
    let mut doc = std::fs::read_to_string(robots_md()).unwrap();
    for (k, dialect) in Dialect::ALL.into_iter().enumerate() {
        let trigger = trigger_line(dialect, sim);
        let mut robot = robot(&cell).await;
        let lines = session(&mut robot, dialect, &trigger).await;
        let binary = binary_plan(&mut ctl, k as u64 + 1, dialect, &trigger, sim).await;
        let convention = to_text::convention(dialect);

        // The pulled poses are the binary link's waypoints, converted.
        let points = pulled(&lines);
        let waypoints = &binary.result.seams[0].waypoints;
        assert_eq!(points.len(), waypoints.len() + 2, "{dialect:?}: approach, the waypoints, retract");
        let (position, rotation) = dialect.decimals();
        for (j, (kind, seam, remaining, pose)) in points.iter().enumerate() {
            assert_eq!((*seam, *remaining), (1, (points.len() - 1 - j) as u64));
            let expected_kind = match j {
                0 => 1,
                j if j == points.len() - 1 => 3,
                _ => 2,
            };
            assert_eq!(*kind, expected_kind, "{dialect:?} line {j}");
            let w = &waypoints[j.clamp(1, waypoints.len()) - 1];
            let zyx = weldseam::geometry::pose::RobotPose { xyz_mm: w.xyz, angles_deg: w.rpy_deg };
            let iso: Isometry3<f64> = zyx.to_isometry(Default::default());
            let mut expected = convention.numbers(&iso)[..convention.numbers_len()].to_vec();
            if expected_kind != 2 {
                // Backed off along the torch axis (tool z, into the work).
                let back = iso.rotation * nalgebra::Vector3::z() * (offset / convention.length.mm());
                for (e, b) in expected.iter_mut().zip(back.iter()) {
                    *e -= b;
                }
            }
            for (i, (got, want)) in pose.iter().zip(&expected).enumerate() {
                let decimals = if i < 3 { position } else { rotation };
                let tolerance = 0.5 * 10f64.powi(-(decimals as i32)) + 1e-6;
                assert!((got - want).abs() <= tolerance, "{dialect:?} line {j} number {i}: {got} vs {want}");
            }
        }

        // What each language can read.
        for (sent, reply) in &lines {
            match dialect {
                Dialect::Ur if sent != "WHY" => {
                    let n = match sent.as_str() {
                        "NEXT" => 9,
                        s if s.starts_with("CHECK") => 5,
                        _ => 3,
                    };
                    let read = ur_read_ascii_float(reply, n);
                    assert_eq!(read[0] as usize, n, "socket_read_ascii_float({n}) fails on {reply:?}");
                    assert!(read.len() - 1 <= UR_MAX_NUMBERS);
                }
                Dialect::Abb => {
                    assert!(reply.len() <= ABB_MAX_LINE, "{reply:?}");
                    let body = reply.trim_end_matches("\r\n");
                    let error = body.starts_with('-');
                    if sent != "WHY" {
                        let fields: Vec<&str> = body.split(',').collect();
                        let numeric = if error { &fields[..1] } else { &fields[..] };
                        assert!(numeric.iter().all(|f| rapid_num(f)), "StrToVal cannot read {reply:?}");
                    }
                }
                _ => {}
            }
            if reply.trim_start_matches('(').starts_with('-') {
                assert!(reply.len() <= MAX_ERROR_LINE, "{reply:?}");
            }
            assert!(reply.ends_with(dialect.terminator()), "{dialect:?}: {reply:?}");
            assert!(!reply[..reply.len() - dialect.terminator().len()].contains(['\r', '\n']), "{reply:?}");
        }

        // The session ROBOTS.md shows for this dialect.
        let replayed = transcript(&lines);
        let (start, end) =
            documented(&doc, dialect).unwrap_or_else(|| panic!("ROBOTS.md has no {dialect:?} transcript"));
        if bless {
            doc.replace_range(start..end, &replayed);
        } else if let Err(e) = same_transcript(&doc[start..end], &replayed) {
            panic!("ROBOTS.md's {dialect:?} transcript differs from the daemon's: {e}\nreplayed:\n{replayed}");
        }
    }
    if bless {
        std::fs::write(robots_md(), doc).unwrap();
    }

    play_the_urscript_example(&cell, sim).await;

    // A robot that leaves mid-pull leaves the daemon clean: a new session
    // plans, and nothing waits in the queue.
    let mut leaving = robot(&cell).await;
    leaving.ask("HELLO,kuka").await.unwrap();
    let ok = leaving.ask(&trigger_line(Dialect::Kuka, sim)).await.unwrap();
    assert!(ok.starts_with("0,1,"), "{ok}");
    leaving.ask("NEXT").await.unwrap();
    drop(leaving);
    let mut next = robot(&cell).await;
    assert_eq!(next.ask("HELLO,fanuc").await.unwrap(), "0,2,0\n");
    assert_eq!(next.ask("PING").await.unwrap(), "0,1,0\n", "one camera, an empty queue");
    drop(next);
    let _ = stop_camera.send(());
    camera.await.unwrap();
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

/// deploy/robots/ur/weld_seam.script, played: the lines it sends (checked
/// against its text), its replies read as `socket_read_ascii_float` reads
/// them, and its loop's decisions.
async fn play_the_urscript_example(cell: &Cell, sim: &Simulation) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("deploy/robots/ur/weld_seam.script");
    let script = std::fs::read_to_string(path).unwrap();
    for sent in [
        r#"socket_send_line("HELLO,ur,PROCESS", "weldseam")"#,
        r#"JOINT = "lap""#,
        r#"socket_send_line(str_cat(str_cat("TRIGGER,", JOINT), str_cat(",", to_str(capture))), "weldseam")"#,
        r#"socket_send_line("NEXT", "weldseam")"#,
        r#"socket_send_line("WHY", "weldseam")"#,
        "socket_read_ascii_float(3,",
        "socket_read_ascii_float(9,",
    ] {
        assert!(script.contains(sent), "the URScript example no longer has {sent}");
    }
    let mut robot = robot(cell).await;
    let hello = ur_read_ascii_float(&robot.ask("HELLO,ur,PROCESS").await.unwrap(), 3);
    assert_eq!(&hello[..2], &[3.0, 0.0]);
    assert_eq!(hello[3], 1.0, "process lines come");
    // to_str of a pose: p[x, y, z, rx, ry, rz].
    let capture = trigger_line(Dialect::Ur, sim).replace("TRIGGER,lap,", "");
    let status = ur_read_ascii_float(&robot.ask(&format!("TRIGGER,lap,{capture}")).await.unwrap(), 3);
    assert_eq!(&status[..2], &[3.0, 0.0], "the example would stop on {status:?}");
    let mut lines = status[3];
    let mut moves = Vec::new();
    while lines > 0.0 {
        let w = ur_read_ascii_float(&robot.ask("NEXT").await.unwrap(), 9);
        assert!(w[0] == 9.0 && w[1] > 0.0, "the example would stop on {w:?}");
        // A process line (no procedure here: speed and weave 0) after
        // each weld line: the example keeps it beside its waypoint.
        if w[1] != 4.0 {
            moves.push(w[1] as u8);
        }
        lines = w[3];
    }
    assert_eq!(moves.first(), Some(&1));
    assert_eq!(moves.last(), Some(&3));
    assert!(moves[1..moves.len() - 1].iter().all(|k| *k == 2));
}

#[tokio::test]
async fn malformed_lines_get_an_error_line_and_the_session_goes_on() {
    let cell = Cell::start(config()).await;
    // Another robot's session, open all along, is not disturbed.
    let mut bystander = robot(&cell).await;
    assert_eq!(bystander.ask("HELLO,abb").await.unwrap(), "0,2,0\r\n");
    let mut robot = robot(&cell).await;
    let code = |reply: &str| reply.split(',').next().unwrap().trim_start_matches('(').to_string();
    // Before the dialect: a plan line is refused, in the neutral form.
    assert_eq!(code(&robot.ask("PLAN,lap,1,2,3,4,5,6").await.unwrap()), "-6");
    assert_eq!(robot.ask("HELLO,kuka").await.unwrap(), "0,2,0\r\n");
    let long = format!("PLAN,lap,{}", "1,".repeat(200));
    for (line, expected) in [
        ("FETCH,1", "-3"),                        // unknown command
        ("PLAN,lap,1,2,3", "-4"),                 // wrong number of fields
        ("PLAN,lap,800,0,500,180,O,0", "-4"),     // a letter where a number belongs
        ("PLAN,lap,800,0,NaN,180,0,0", "-4"),     // not finite
        ("PLAN,fillet,800,0,500,180,0,0", "-41"), // unknown joint
        ("PLAN,lap,99999,0,500,180,0,0", "-40"),  // beyond the reach
        ("NEXT", "-6"),                           // nothing to pull
        ("CHECK,1", "-6"),                        // no plan to check
        ("CHECK,one", "-4"),                      // not a seam number
        (long.as_str(), "-5"),                    // too long
    ] {
        let reply = robot.ask(line).await.unwrap();
        assert_eq!(code(&reply), expected, "{line:?} got {reply:?}");
        assert!(reply.len() <= MAX_ERROR_LINE, "{reply:?}");
    }
    let why = robot.ask("WHY").await.unwrap();
    assert!(why.contains("max_line_bytes"), "{why}");
    // A plan line with no camera connected: an error, then on as before.
    assert_eq!(code(&robot.ask("TRIGGER,lap,800,0,500,180,0,0").await.unwrap()), "-43");
    assert_eq!(robot.ask("PING").await.unwrap(), "0,0,0\r\n");
    // UR replies keep their shape: a waypoint's nine numbers, code first.
    assert_eq!(robot.ask("HELLO,ur").await.unwrap(), "(0,2,0)\n");
    assert_eq!(robot.ask("NEXT").await.unwrap(), "(-6,0,0,0,0,0,0,0,0)\n");
    assert_eq!(robot.ask("CHECK,1").await.unwrap(), "(-6,0,0,0,0)\n");
    assert_eq!(ur_read_ascii_float(&robot.ask("PLAN,lap,1").await.unwrap(), 3), vec![3.0, -4.0, 0.0, 0.0]);
    // A line without its end: an error line within the line time, then on.
    robot.send("PING", "").await.unwrap();
    assert_eq!(robot.recv().await.unwrap(), "(-4,0,0)\n");
    assert_eq!(robot.ask("PING").await.unwrap(), "(0,0,0)\n");
    assert_eq!(bystander.ask("PING").await.unwrap(), "0,0,0\r\n");
    drop((robot, bystander));
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

#[tokio::test]
async fn a_full_link_says_busy_and_a_freed_slot_serves_again() {
    let mut c = config();
    c.text_link.max_connections = 1;
    c.text_link.dialect = Some(Dialect::Fanuc);
    let cell = Cell::start(c).await;
    let mut first = robot(&cell).await;
    assert_eq!(first.ask("PING").await.unwrap(), "0,0,0\n", "the configured dialect applies");
    let mut second = TcpStream::connect(text_addr(&cell)).await.unwrap();
    let mut refusal = String::new();
    second.read_to_string(&mut refusal).await.unwrap();
    assert!(refusal.starts_with("-45,all 1 text link sessions are in use"), "{refusal}");
    drop(first);
    // The slot is free once the session has ended.
    let mut third = None;
    for _ in 0..100 {
        let mut robot = robot(&cell).await;
        match robot.ask("PING").await {
            Ok(reply) if reply == "0,0,0\n" => {
                third = Some(robot);
                break;
            }
            _ => tokio::time::sleep(Duration::from_millis(20)).await,
        }
    }
    assert!(third.is_some(), "the freed slot serves a new session");
    drop(third);
    assert_eq!(cell.shutdown().await, Stopped::Clean);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_line_may_leave_the_joint_to_the_daemon() {
    let sim = scenes::demo(JointType::Lap);
    let cell = Cell::start(config()).await;
    let (stop_camera, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut ctl = ControllerClient::connect(&cell.controller, "test").await.unwrap();
    ctl.wait_for_camera(Duration::from_secs(5)).await.unwrap();
    let mut robot = robot(&cell).await;
    let hello = robot.ask("HELLO,kuka").await.unwrap();
    assert_eq!(numbers(&hello)[0], 0.0, "{hello}");
    let auto = trigger_line(Dialect::Kuka, sim).replacen("TRIGGER,lap,", "TRIGGER,auto,", 1);
    assert!(auto.starts_with("TRIGGER,auto,"), "{auto}");
    let ok = robot.ask(&auto).await.unwrap();
    assert_eq!(&numbers(&ok)[..2], &[0.0, 1.0], "the lap found and planned: {ok}");
    // The plan's check stays until the next plan line, pulled or not.
    let check = numbers(&robot.ask("CHECK,1").await.unwrap());
    assert_eq!(&check[..2], &[0.0, numbers(&ok)[2]], "{check:?}");
    let beyond = robot.ask("CHECK,2").await.unwrap();
    assert!(beyond.starts_with("-40,seam 2 out of range"), "{beyond}");
    assert_eq!(robot.ask("DROP").await.unwrap(), format!("0,{},0\r\n", check[1]));
    assert_eq!(numbers(&robot.ask("CHECK,1").await.unwrap()), check);
    // A refused plan: the error line leads with the cause, not the frame
    // and stage, which WHY's text puts last; no plan is left to check.
    let tee = trigger_line(Dialect::Kuka, sim).replacen("TRIGGER,lap,", "TRIGGER,t_fillet,", 1);
    let refused = robot.ask(&tee).await.unwrap();
    assert!(refused.starts_with('-') && !refused.contains("frame") && !refused.contains("stage failed"), "{refused}");
    assert!(refused.len() <= MAX_ERROR_LINE && !refused.ends_with(" \r\n"), "{refused:?}");
    // The reason leads with the id of the rule that refused, up to the
    // first ": ", where a program can branch on it.
    let reason = refused.split_once(',').unwrap().1;
    let (rule, cause) = reason.split_once(": ").unwrap_or_else(|| panic!("no rule id first: {refused:?}"));
    // No web's top over the lap's plates, and nothing stands on the
    // nearest plane as a web's face would.
    assert_eq!(rule, "tee.nothing_stands_on_flange", "{refused:?}");
    assert!(!cause.trim().is_empty(), "{refused:?}");
    let why = robot.ask("WHY").await.unwrap();
    let cause = refused.split_once(',').unwrap().1.trim_end();
    assert!(why.starts_with(cause), "the pendant line {refused:?} is the start of WHY's {why:?}");
    assert!(robot.ask("CHECK,1").await.unwrap().starts_with("-6,"));
    drop(robot);
    let _ = stop_camera.send(());
    camera.await.unwrap();
    cell.shutdown().await;
}

/// A frame of three workpieces (an I-butt, a lap and a tee): the ok line
/// counts the three seams planned (the tee's root facing the camera among
/// them), the waypoint lines carry seam numbers 1 to 3, each seam from
/// approach to retract, and WHY names the tee's root not planned (the one
/// its web hides).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn several_seams_are_served_seam_by_seam_and_why_names_the_unplanned() {
    let (name, spec) = scenes::multi_scene("multi-01");
    let sim = scenes::by_default_camera(&spec);
    let cell = Cell::start(config()).await;
    let (stop_camera, camera) = cell.camera(vec![Arc::new(sim.cloud.clone())], CameraOptions::default());
    let mut ctl = ControllerClient::connect(&cell.controller, "test").await.unwrap();
    ctl.wait_for_camera(Duration::from_secs(5)).await.unwrap();
    let mut robot = robot(&cell).await;
    robot.ask("HELLO,kuka").await.unwrap();
    let auto = trigger_line(Dialect::Kuka, sim).replacen("TRIGGER,lap,", "TRIGGER,auto,", 1);
    let ok = robot.ask(&auto).await.unwrap();
    let status = numbers(&ok);
    assert_eq!(&status[..2], &[0.0, 3.0], "{name}: three seams planned: {ok}");
    let mut kinds_by_seam: Vec<(u32, Vec<u8>)> = Vec::new();
    for _ in 0..status[2] as usize {
        let line = numbers(&robot.ask("NEXT").await.unwrap());
        let (kind, seam) = (line[0] as u8, line[1] as u32);
        match kinds_by_seam.last_mut() {
            Some((s, kinds)) if *s == seam => kinds.push(kind),
            _ => kinds_by_seam.push((seam, vec![kind])),
        }
    }
    assert_eq!(kinds_by_seam.iter().map(|(s, _)| *s).collect::<Vec<_>>(), [1, 2, 3], "{name}");
    for (seam, kinds) in &kinds_by_seam {
        assert!(kinds.len() >= 3 && kinds[0] == 1 && kinds[kinds.len() - 1] == 3, "seam {seam}: {kinds:?}");
        assert!(kinds[1..kinds.len() - 1].iter().all(|k| *k == 2), "seam {seam}: {kinds:?}");
    }
    let why = robot.ask("WHY").await.unwrap();
    // The joint, its code and the id of the rule that left it unplanned,
    // then where it lies.
    assert!(why.starts_with("3 seams planned; 1 not: t_fillet (-46 "), "{name}: {why}");
    let named = why.split_once("(-46 ").and_then(|(_, rest)| rest.split_once(") at (")).map(|(rule, _)| rule);
    assert_eq!(named, Some("tee.flange_edge_at_shadow"), "{name}: {why}");
    drop(robot);
    let _ = stop_camera.send(());
    camera.await.unwrap();
    cell.shutdown().await;
}
