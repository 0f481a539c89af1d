//! The UR program through every scenario: the flange pose sent whatever
//! the torch; the whole plan fetched and checked before the first motion;
//! each seam welded in one blended process move at weld speed to the
//! poses `plan --json` gives (0.01 mm, 0.01°), with no network between
//! arc on and arc off; a refusal, a too-long line and a daemon stopped
//! during the fetch or before the arc leave the torch at the capture pose
//! with a code and, for a refusal, the cause shown.

use nalgebra::{Translation3, UnitQuaternion};
use weldseam::convert::to_text;
use weldseam::geometry::Isometry3;
use weldseam::geometry::pose::EulerConvention;
use weldseam_proto::text::Dialect;

use super::harness::{Daemon, Scenario, reference, same_pose};
use super::ur::{ARC_OUTPUT, BLEND_RADIUS, Settings, WELD_SPEED, weld_seam};
use super::urscript::{Event, Move, Ur};

/// A torch 350 mm out from the flange, tilted: a program that sent the
/// TCP's pose would be 350 mm off.
fn torch() -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::new(12.0, -30.0, 350.0), UnitQuaternion::from_euler_angles(0.0, 0.35, 0.2))
}

struct Run {
    result: f64,
    ur: Ur,
    capture: Isometry3<f64>,
}

async fn run(scenario: Scenario, dry_run: bool) -> Run {
    let daemon = Daemon::start(scenario).await;
    let capture = scenario.scene().pose.to_isometry(EulerConvention::default());
    let mut ur = Ur::new(capture, torch());
    ur.on_send = Some(daemon.stopper(scenario));
    let settings = Settings {
        daemon_ip: "127.0.0.1".into(),
        daemon_port: f64::from(daemon.text_addr.port()),
        joint: scenario.joint().into(),
        dry_run,
    };
    let (result, ur) = tokio::task::spawn_blocking(move || {
        let result = weld_seam(&mut ur, &settings);
        (result, ur)
    })
    .await
    .unwrap();
    daemon.stop().await;
    Run { result, ur, capture }
}

fn moves(ur: &Ur) -> Vec<&Move> {
    ur.events
        .iter()
        .filter_map(|e| match e {
            Event::Move(m) => Some(m),
            _ => None,
        })
        .collect()
}

/// The pose numbers of the plan line the program sent: the flange's.
fn sent_pose(run: &Run) -> Vec<f64> {
    let trigger = run
        .ur
        .events
        .iter()
        .find_map(|e| match e {
            Event::Sent(line) if line.starts_with("TRIGGER,") => Some(line.clone()),
            _ => None,
        })
        .expect("a plan line sent");
    let numbers: Vec<f64> = trigger
        .split(',')
        .skip(2)
        .map(|f| f.trim().trim_start_matches("p[").trim_end_matches(']').parse().unwrap())
        .collect();
    let flange = to_text::convention(Dialect::Ur).numbers(&run.capture);
    for (sent, flange) in numbers.iter().zip(&flange) {
        assert!((sent - flange).abs() <= 1e-6, "the pose sent {numbers:?} is not the flange's {flange:?}");
    }
    let tcp = to_text::convention(Dialect::Ur).numbers(&(run.capture * run.ur.tcp));
    assert!((numbers[2] - tcp[2]).abs() > 0.1, "the pose sent is the torch's");
    numbers
}

/// A run that welded: every seam's moves where `plan --json` puts them,
/// one blended process move at weld speed under the arc, nothing read or
/// sent after the first motion.
fn welded(run: &Run, scenario: Scenario, seams: usize, arc: bool) {
    assert_eq!(run.result, 0.0, "{:?}", run.ur.events.iter().rev().take(5).collect::<Vec<_>>());
    assert!(run.ur.faults.is_empty(), "{:?}", run.ur.faults);
    let expected = reference(scenario, Dialect::Ur, &sent_pose(run));
    assert_eq!(expected.len(), seams, "{scenario:?}: seams planned");
    let first_motion = run.ur.events.iter().position(|e| matches!(e, Event::Move(_))).expect("a motion");
    assert!(
        !run.ur.events[first_motion..].iter().any(|e| matches!(e, Event::Sent(_) | Event::Read(_))),
        "the network was used after the torch moved"
    );
    let moves = moves(&run.ur);
    let mut at = 0;
    for (k, waypoints) in expected.iter().enumerate() {
        let seam = &moves[at..at + waypoints.len() + 2];
        at += waypoints.len() + 2;
        let (approach, weld, retract) = (seam[0], &seam[1..seam.len() - 1], seam[seam.len() - 1]);
        for (j, (m, w)) in weld.iter().zip(waypoints).enumerate() {
            same_pose(&m.target, w).unwrap_or_else(|e| panic!("{scenario:?} seam {k} waypoint {j}: {e}"));
        }
        let back = |m: &Move, w: &Isometry3<f64>| (m.target.translation.vector - w.translation.vector).norm();
        assert!((back(approach, &waypoints[0]) - 50.0).abs() < 0.01, "the approach 50 mm above the start");
        assert!((back(retract, waypoints.last().unwrap()) - 50.0).abs() < 0.01, "the retract 50 mm above the end");
        // On the seam: process moves at weld speed, blended but the last.
        for (j, m) in weld[1..].iter().enumerate() {
            assert!(m.process && m.speed == WELD_SPEED, "seam {k} move {j}: {m:?}");
            let last = j == weld.len() - 2;
            assert_eq!(m.blended, !last, "seam {k} move {j} of {}: blended {}", weld.len() - 1, m.blended);
            // The cell's blend, or a quarter of the shorter move beside
            // the waypoint where that is less.
            let expected = if last {
                0.0
            } else {
                let dist = |a: &Move, b: &Move| (a.target.translation.vector - b.target.translation.vector).norm();
                BLEND_RADIUS.min(0.25 * dist(weld[j], m).min(dist(m, weld[j + 2])) / 1000.0)
            };
            assert!((m.blend - expected).abs() < 1e-9, "seam {k} move {j}: blend {} for {expected}", m.blend);
        }
    }
    assert_eq!(at, moves.len(), "no motion beyond the seams'");
    let mut process_lines: Vec<usize> = moves.iter().filter(|m| m.process).map(|m| m.line).collect();
    process_lines.dedup();
    process_lines.sort_unstable();
    process_lines.dedup();
    assert_eq!(process_lines.len(), 2, "the weld's moves come from the two movep lines: {process_lines:?}");
    // The arc: on at each seam's start, off at its end, nothing but
    // motions in between.
    let mut on = None;
    let mut arcs = 0;
    for (k, e) in run.ur.events.iter().enumerate() {
        match e {
            Event::Output { pin, on: true } if *pin == ARC_OUTPUT => on = Some(k),
            Event::Output { pin, on: false } if *pin == ARC_OUTPUT => {
                if let Some(start) = on.take() {
                    arcs += 1;
                    let between = &run.ur.events[start..k];
                    assert!(
                        between.iter().all(|e| matches!(
                            e,
                            Event::Statement(_) | Event::Move(_) | Event::Output { .. } | Event::Sleep
                        )),
                        "something other than motion under the arc"
                    );
                }
            }
            _ => {}
        }
    }
    assert_eq!(arcs, if arc { seams } else { 0 }, "arcs struck");
}

/// A run that stopped before any motion, with `code` and the popup.
fn stopped(run: &Run, codes: &[f64]) -> String {
    assert!(codes.contains(&run.result), "result {} not one of {codes:?}", run.result);
    assert!(moves(&run.ur).is_empty(), "the torch moved");
    assert_eq!(run.ur.events.last(), Some(&Event::Halt));
    let popup = run.ur.events.iter().find_map(|e| match e {
        Event::Popup(text) => Some(text.clone()),
        _ => None,
    });
    popup.expect("a popup")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_seam_is_welded_in_one_blended_move() {
    let run = run(Scenario::OneSeam, false).await;
    welded(&run, Scenario::OneSeam, 1, true);
    // DRY_RUN: the same motion, no arc.
    let dry = super::ur_runs::run(Scenario::OneSeam, true).await;
    welded(&dry, Scenario::OneSeam, 1, false);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_250_waypoint_seam_is_stored_checked_and_welded() {
    let run = run(Scenario::LongSeam, false).await;
    welded(&run, Scenario::LongSeam, 1, true);
    assert!(moves(&run.ur).len() >= 252, "{} moves: fewer than 250 waypoints", moves(&run.ur).len());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn several_seams_are_welded_one_after_the_other() {
    let run = run(Scenario::SeveralSeams, false).await;
    welded(&run, Scenario::SeveralSeams, 3, true);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_refusal_shows_its_cause_and_the_torch_stays() {
    let run = run(Scenario::Refusal, false).await;
    sent_pose(&run);
    let popup = stopped(&run, &[-40.0, -46.0, -60.0, -61.0, -62.0, -63.0, -64.0, -65.0, -66.0, -67.0, -68.0, -69.0]);
    let reason = popup.split_once(": ").map(|(_, r)| r).unwrap_or("");
    assert!(!reason.is_empty() && !reason.starts_with("frame"), "the cause first: {popup:?}");
    let too_long = super::ur_runs::run(Scenario::TooLongLine, false).await;
    let popup = stopped(&too_long, &[-5.0]);
    assert!(popup.contains("max_line_bytes"), "{popup}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_daemon_gone_before_the_arc_leaves_the_torch_at_the_capture_pose() {
    for scenario in [Scenario::StopDuringFetch, Scenario::StopBeforeArc] {
        let run = run(scenario, false).await;
        stopped(&run, &[2.0, 3.0]);
        let checks = run.ur.events.iter().filter(|e| matches!(e, Event::Sent(l) if l.starts_with("CHECK"))).count();
        assert_eq!(checks, usize::from(scenario == Scenario::StopBeforeArc), "{scenario:?}");
    }
}

/// A thick V-groove under the example procedure, its root pass weaving:
/// every piece of every pass welded as a seam, each the plan's woven path
/// (URScript has no weaving motion; [`super::woven::check_piece`]: the
/// weave's offsets with the piece's phase, the plan's speed along the
/// seam, the torch's turn), with no blend over a quarter of the shorter
/// move beside it (no movep fault).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ur_each_pass_is_welded_woven_at_its_speeds() {
    let run = run(Scenario::Passes, false).await;
    assert_eq!(run.result, 0.0, "{:?}", run.ur.events.iter().rev().take(5).collect::<Vec<_>>());
    assert!(run.ur.faults.is_empty(), "{:?}", run.ur.faults);
    let pieces = super::woven::plan_pieces(Scenario::Passes, Dialect::Ur, &sent_pose(&run));
    assert!(pieces.len() >= 2, "{} pieces: a 9 mm groove takes several passes", pieces.len());
    let moves = moves(&run.ur);
    let mut at = 0;
    let mut off_the_line = 0;
    for (k, (piece, lines)) in pieces.iter().enumerate() {
        let weld = &moves[at + 1..at + 1 + lines];
        let apart = |a: &Move, b: &Move| (a.target.translation.vector - b.target.translation.vector).norm() / 1000.0;
        for j in 1..weld.len() - 1 {
            let shorter = apart(weld[j - 1], weld[j]).min(apart(weld[j], weld[j + 1]));
            assert!(weld[j].blend <= 0.25 * shorter + 1e-12, "piece {k} move {j}: blend {} m", weld[j].blend);
            assert!(weld[j].process, "piece {k} move {j}");
        }
        // m/s to mm/s.
        let poses: Vec<_> = weld.iter().map(|m| (m.target, m.speed * 1000.0)).collect();
        let woven = super::woven::check_piece(piece, &poses).unwrap_or_else(|e| panic!("UR piece {k}: {e}"));
        off_the_line += woven.off_the_line;
        at += lines + 2;
    }
    assert_eq!(at, moves.len(), "no motion beyond the pieces'");
    assert!(off_the_line > 0, "the root pass weaves, and UR welded it straight");
}
