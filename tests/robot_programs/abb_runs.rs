//! The ABB module through every scenario: the flange pose sent, in
//! pieces within RAPID's 80 characters; the whole plan fetched and
//! checked before the first motion; each seam welded ArcLStart, ArcL in
//! zones at weld speed, ArcLEnd, to the poses `plan --json` gives (0.01
//! mm, 0.01°), with no network between arc on and arc off; a refusal
//! (its cause shown), a too-long line and a daemon stopped during the
//! fetch or before the arc handled by FetchPlan's ERROR handler with the
//! torch at the capture pose.

use weldseam::convert::to_text;
use weldseam::geometry::Isometry3;
use weldseam::geometry::pose::EulerConvention;
use weldseam_proto::text::Dialect;

use super::abb::{Settings, V_WELD, WELD_SPEED, Z_WELD, run as run_module};
use super::harness::{Daemon, Scenario, reference, reference_pieces, same_pose};
use super::rapid::{Event, Move, Rapid};

struct Run {
    result: f64,
    reason: String,
    rapid: Rapid,
    capture: Isometry3<f64>,
}

async fn run(scenario: Scenario, dry_run: bool) -> Run {
    let daemon = Daemon::start(scenario).await;
    let capture = scenario.scene().pose.to_isometry(EulerConvention::default());
    let mut rapid = Rapid::new(capture);
    rapid.on_send = Some(daemon.stopper(scenario));
    let settings = Settings {
        daemon_ip: "127.0.0.1".into(),
        daemon_port: f64::from(daemon.text_addr.port()),
        joint: scenario.joint().into(),
        dry_run,
    };
    let (result, reason, rapid) = tokio::task::spawn_blocking(move || {
        let (result, reason) = run_module(&mut rapid, &settings);
        (result, reason, rapid)
    })
    .await
    .unwrap();
    daemon.stop().await;
    Run { result, reason, rapid, capture }
}

fn moves(rapid: &Rapid) -> Vec<&Move> {
    rapid
        .events
        .iter()
        .filter_map(|e| match e {
            Event::Move(m) => Some(m),
            _ => None,
        })
        .collect()
}

/// The plan line as the daemon received it (its pieces joined), and its
/// pose numbers, which are the flange's.
fn sent_pose(run: &Run) -> Vec<f64> {
    let sent: String = run
        .rapid
        .events
        .iter()
        .filter_map(|e| match e {
            Event::Sent(piece) => Some(piece.as_str()),
            _ => None,
        })
        .collect();
    let trigger = sent.split("\r\n").find(|l| l.starts_with("TRIGGER,")).expect("a plan line sent");
    let numbers: Vec<f64> = trigger.split(',').skip(2).map(|f| f.parse().unwrap()).collect();
    let flange = to_text::convention(Dialect::Abb).numbers(&run.capture);
    for (k, (sent, flange)) in numbers.iter().zip(&flange).enumerate() {
        let decimals = if k < 3 { 0.005 } else { 0.000_000_5 };
        assert!((sent - flange).abs() <= decimals + 1e-9, "the pose sent {numbers:?} is not the flange's {flange:?}");
    }
    numbers
}

fn welded(run: &Run, scenario: Scenario, seams: usize, arc: bool) {
    assert_eq!(run.result, 0.0, "{}: {:?}", run.reason, run.rapid.events.iter().rev().take(5).collect::<Vec<_>>());
    let expected = reference(scenario, Dialect::Abb, &sent_pose(run));
    assert_eq!(expected.len(), seams, "{scenario:?}: seams planned");
    let first_motion = run.rapid.events.iter().position(|e| matches!(e, Event::Move(_))).expect("a motion");
    assert!(
        !run.rapid.events[first_motion..].iter().any(|e| matches!(e, Event::Sent(_) | Event::Read(_))),
        "the network was used after the torch moved"
    );
    let moves = moves(&run.rapid);
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
        assert!(approach.zone.is_none() && retract.zone.is_none() && weld[0].zone.is_none());
        for (j, m) in weld[1..].iter().enumerate() {
            let last = j == weld.len() - 2;
            assert_eq!(m.speed, if arc { WELD_SPEED } else { V_WELD }, "seam {k} move {j}");
            assert_eq!(m.welding, arc, "seam {k} move {j}");
            assert_eq!(m.zone, if last { None } else { Some(Z_WELD) }, "seam {k} move {j}");
            assert_eq!(m.blended, !last, "seam {k} move {j} of {}", weld.len() - 1);
        }
    }
    assert_eq!(at, moves.len(), "no motion beyond the seams'");
    let ons = run.rapid.events.iter().filter(|e| **e == Event::ArcOn).count();
    assert_eq!(ons, if arc { seams } else { 0 }, "arcs struck");
    let mut on = None;
    for (k, e) in run.rapid.events.iter().enumerate() {
        match e {
            Event::ArcOn => on = Some(k),
            Event::ArcOff => {
                let start = on.take().expect("ArcLEnd after ArcLStart");
                let between = &run.rapid.events[start..k];
                assert!(
                    between.iter().all(|e| matches!(e, Event::Statement(_) | Event::Move(_) | Event::ArcOn)),
                    "something other than motion under the arc"
                );
            }
            _ => {}
        }
    }
    assert!(on.is_none(), "the arc left on");
}

fn stopped(run: &Run, codes: &[f64]) {
    assert!(codes.contains(&run.result), "result {} ({}) not one of {codes:?}", run.result, run.reason);
    assert!(moves(&run.rapid).is_empty(), "the torch moved");
    let last = run.rapid.events.iter().rfind(|e| !matches!(e, Event::Statement(_)));
    assert_eq!(last, Some(&Event::Stop), "the program stops");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abb_one_seam_is_welded_in_zones_between_arc_start_and_end() {
    let welding = run(Scenario::OneSeam, false).await;
    welded(&welding, Scenario::OneSeam, 1, true);
    let dry = run(Scenario::OneSeam, true).await;
    welded(&dry, Scenario::OneSeam, 1, false);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abb_a_250_waypoint_seam_and_several_seams_are_welded() {
    let long = run(Scenario::LongSeam, false).await;
    welded(&long, Scenario::LongSeam, 1, true);
    assert!(moves(&long.rapid).len() >= 252, "{} moves: fewer than 250 waypoints", moves(&long.rapid).len());
    let several = run(Scenario::SeveralSeams, false).await;
    welded(&several, Scenario::SeveralSeams, 3, true);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abb_a_refusal_shows_its_cause_and_a_too_long_line_is_refused() {
    let refused = run(Scenario::Refusal, false).await;
    sent_pose(&refused);
    stopped(&refused, &[-40.0, -46.0, -60.0, -61.0, -62.0, -63.0, -64.0, -65.0, -66.0, -67.0, -68.0, -69.0]);
    assert!(!refused.reason.is_empty() && !refused.reason.starts_with("frame"), "the cause first: {}", refused.reason);
    assert!(refused.rapid.events.contains(&Event::TpWrite(refused.reason.clone())), "the reason shown");
    let too_long = run(Scenario::TooLongLine, false).await;
    stopped(&too_long, &[-5.0]);
    assert!(too_long.reason.contains("max_line_bytes"), "{}", too_long.reason);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abb_a_daemon_gone_before_the_arc_is_an_error_handled_off_the_seam() {
    for scenario in [Scenario::StopDuringFetch, Scenario::StopBeforeArc] {
        let run = run(scenario, false).await;
        stopped(&run, &[2.0]);
    }
}

/// A thick V-groove under the example procedure: every piece of every
/// pass welded as a seam, each move into a weld waypoint at the travel
/// speed the plan gives there and with ArcWare's weave set from its
/// half-swing and frequency.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abb_each_pass_is_welded_at_its_speeds_and_weave() {
    let run = run(Scenario::Passes, false).await;
    assert_eq!(run.result, 0.0, "{}", run.reason);
    let expected = reference_pieces(Scenario::Passes, Dialect::Abb, &sent_pose(&run));
    assert!(expected.len() >= 2, "{} pieces: a 9 mm groove takes several passes", expected.len());
    let moves = moves(&run.rapid);
    let mut at = 0;
    let mut woven = 0;
    for (k, piece) in expected.iter().enumerate() {
        let weld = &moves[at + 1..at + 1 + piece.len()];
        at += piece.len() + 2;
        for (j, (m, (pose, [speed, amplitude, frequency]))) in weld.iter().zip(piece).enumerate().skip(1) {
            same_pose(&m.target, pose).unwrap_or_else(|e| panic!("piece {k} waypoint {j}: {e}"));
            // The line's two decimals.
            assert!((m.speed - speed).abs() <= 0.005 + 1e-9, "piece {k} move {j}: {} for {speed}", m.speed);
            match m.weave {
                None => assert!(*amplitude < 0.005, "piece {k} move {j}: no weave for {amplitude} mm"),
                Some([width, length]) => {
                    woven += 1;
                    assert!((width - 2.0 * amplitude).abs() <= 0.011, "{width} for {amplitude}");
                    let wavelength = speed / frequency;
                    assert!((length - wavelength).abs() / wavelength < 0.01, "{length} for {wavelength}");
                }
            }
        }
    }
    assert_eq!(at, moves.len(), "no motion beyond the pieces'");
    eprintln!("{} pieces, {woven} woven moves", expected.len());
}
