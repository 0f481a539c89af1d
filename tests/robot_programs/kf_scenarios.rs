//! The KUKA and FANUC programs through every scenario of
//! [`Scenario`], each on its emulation against the daemon: the flange
//! pose sent whatever the torch; every seam fetched and checked before the
//! first motion; one move per waypoint line, where `plan --json` puts it
//! (0.01 mm, 0.01°), the approach and retract 50 mm back along the torch;
//! each seam one bead at weld speed that blends to its end (C_DIS in the
//! advance run, CNT) with nothing sent or read under the arc; a refusal, a
//! too-long line and a daemon stopped during the fetch or before the arc
//! leave the torch at the capture pose with a code the program branches
//! on and the cause shown; under a weld procedure, each pass welded as a
//! seam, every move into a weld waypoint at the plan's travel speed there.

use nalgebra::{Translation3, UnitQuaternion, Vector3};
use weldseam::geometry::Isometry3;
use weldseam::geometry::conventions::PoseConvention;
use weldseam::geometry::pose::EulerConvention;
use weldseam_proto::text::Dialect;

use super::harness::{Daemon, Scenario, reference, same_pose};
use super::karel::Controller;
use super::krl::Krl;
use super::robot::{Event, Move, Trace};
use super::{fanuc, fanuc_tp, kuka, kuka_dat};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Vendor {
    Kuka,
    Fanuc,
}

impl Vendor {
    fn dialect(self) -> Dialect {
        match self {
            Vendor::Kuka => Dialect::Kuka,
            Vendor::Fanuc => Dialect::Fanuc,
        }
    }

    fn convention(self) -> PoseConvention {
        weldseam::convert::to_text::convention(self.dialect())
    }
}

/// The joint the program's setting names: the scenario's, but for the
/// too-long line a set long enough that this dialect's plan line passes
/// the 80 bytes the scenario's daemon takes.
fn joint(scenario: Scenario) -> &'static str {
    match scenario {
        Scenario::TooLongLine => "v_butt+i_butt+lap+t_fillet",
        _ => scenario.joint(),
    }
}

/// A torch 350 mm out from the flange, tilted: a program that sent the
/// TCP's pose would be 350 mm off.
fn torch() -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::new(12.0, -30.0, 350.0), UnitQuaternion::from_euler_angles(0.0, 0.35, 0.2))
}

/// One run: the program's result code, the record, the pendant's
/// messages, the TP alarms, the flange at capture.
struct Run {
    result: i32,
    trace: Trace,
    messages: Vec<String>,
    alarms: Vec<usize>,
    capture: Isometry3<f64>,
    /// FANUC: the weave ArcTool lays on each move, (mm, Hz) (none
    /// recorded for KUKA).
    weave: Vec<Option<[f64; 2]>>,
    /// KUKA: `$APO.CDIS` at each move, mm (0 without C_DIS; none
    /// recorded for FANUC).
    cdis: Vec<f32>,
}

async fn run(vendor: Vendor, scenario: Scenario, dry_run: bool) -> Run {
    run_with(vendor, scenario, dry_run, fanuc::Overrides::default()).await
}

/// A run whose FANUC helper has the CONST block `fanuc` sets (its joint
/// is the scenario's).
async fn run_with(vendor: Vendor, scenario: Scenario, dry_run: bool, fanuc: fanuc::Overrides) -> Run {
    let daemon = Daemon::start(scenario).await;
    let capture = scenario.scene().pose.to_isometry(EulerConvention::default());
    let hook = daemon.stopper(scenario);
    let address = daemon.text_addr.to_string();
    let joint = joint(scenario).to_string();
    let run = tokio::task::spawn_blocking(move || match vendor {
        Vendor::Kuka => {
            let (_, xml) = super::transcription::program("kuka/WeldSeam.xml");
            let mut k = Krl::new(&xml, &address, capture, torch());
            k.on_send = Some(hook);
            let mut dat = kuka_dat::data_list(&mut k);
            let ov = kuka::Overrides { joint: Some(joint), reply_timeout_ms: None, dry_run: Some(dry_run) };
            let result = kuka::weld_seam(&mut k, &mut dat, &ov);
            let cdis = k.cdis_at_moves;
            Run { result, trace: k.trace, messages: k.messages, alarms: Vec::new(), capture, weave: Vec::new(), cdis }
        }
        Vendor::Fanuc => {
            let mut tp = Controller::new(&address, capture, torch());
            tp.on_send = Some(hook);
            let mut helper = fanuc::load_program(&mut tp, &fanuc::Overrides { joint: Some(joint), ..fanuc });
            fanuc_tp::weld_seam(&mut tp, &mut helper, dry_run);
            let result = tp.r[9].int();
            let weave = tp.weave_at_moves;
            Run { result, trace: tp.trace, messages: tp.tperror, alarms: tp.alarms, capture, weave, cdis: Vec::new() }
        }
    })
    .await
    .unwrap();
    daemon.stop().await;
    run
}

/// The pose numbers of the plan line sent, checked to be the flange's (to
/// the line's decimals) and not the torch's.
fn sent_pose(vendor: Vendor, run: &Run) -> Vec<f64> {
    let line = run.trace.sent().into_iter().find(|l| l.starts_with("TRIGGER,")).expect("a plan line sent");
    let numbers: Vec<f64> = line.trim_end().split(',').skip(2).map(|f| f.trim().parse().unwrap()).collect();
    let sent = vendor.convention().to_isometry(&numbers).unwrap();
    same_pose(&sent, &run.capture).unwrap_or_else(|e| panic!("{vendor:?}: the pose sent is not the flange's: {e}"));
    numbers
}

/// The pose a move's six numbers stand for.
fn target(vendor: Vendor, m: &Move) -> Isometry3<f64> {
    vendor.convention().to_isometry(&m.pose).unwrap()
}

/// A run that welded `seams` seams where `plan --json` puts them, one
/// bead each, nothing on the network once the torch moved.
fn welded(vendor: Vendor, scenario: Scenario, run: &Run, seams: usize, arc: bool) {
    assert_eq!(
        run.result,
        0,
        "{vendor:?}: {:?} after {:?}",
        run.messages,
        run.trace.reads().iter().rev().take(3).collect::<Vec<_>>()
    );
    let expected = reference(scenario, vendor.dialect(), &sent_pose(vendor, run));
    assert_eq!(expected.len(), seams, "{vendor:?} {scenario:?}: seams planned");
    let checks = run.trace.sent().iter().filter(|l| l.starts_with("CHECK,")).count();
    assert_eq!(checks, seams, "{vendor:?}: every seam checked");
    let first_motion = run.trace.events.iter().position(|e| matches!(e, Event::Move(_))).expect("a motion");
    let network_after = run.trace.events[first_motion..].iter().any(|e| matches!(e, Event::Sent(_) | Event::Read(_)));
    assert!(!network_after, "{vendor:?}: the network was used after the torch moved");
    let moves = run.trace.moves();
    let mut at = 0;
    for (s, waypoints) in expected.iter().enumerate() {
        let seam = &moves[at..at + waypoints.len() + 2];
        at += waypoints.len() + 2;
        let back = |w: &Isometry3<f64>| {
            Isometry3::from_parts(
                Translation3::from(w.translation.vector - w.rotation * Vector3::z() * 50.0),
                w.rotation,
            )
        };
        same_pose(&target(vendor, seam[0]), &back(&waypoints[0]))
            .unwrap_or_else(|e| panic!("{vendor:?} seam {s} approach: {e}"));
        let last = seam.len() - 1;
        same_pose(&target(vendor, seam[last]), &back(waypoints.last().unwrap()))
            .unwrap_or_else(|e| panic!("{vendor:?} seam {s} retract: {e}"));
        for (j, (m, w)) in seam[1..last].iter().zip(waypoints).enumerate() {
            same_pose(&target(vendor, m), w).unwrap_or_else(|e| panic!("{vendor:?} seam {s} waypoint {j}: {e}"));
        }
        // From the seam's start: weld speed, blended but the last.
        for (j, m) in seam[2..last].iter().enumerate() {
            assert!((m.speed_mm_s - 8.0).abs() < 1e-3, "{vendor:?} seam {s} move {j}: {m:?}");
            assert_eq!(m.blended, j + 3 < last, "{vendor:?} seam {s} move {j} of {}: {m:?}", last - 2);
        }
    }
    assert_eq!(at, moves.len(), "{vendor:?}: no motion beyond the seams'");
    // Without a procedure no line carries a weave: FANUC lays none.
    assert!(run.weave.iter().all(Option::is_none), "{vendor:?}: a weave laid where no line has one: {:?}", run.weave);
    let welds = run.trace.welds().unwrap_or_else(|e| panic!("{vendor:?}: {e}"));
    assert_eq!(welds.len(), if arc { seams } else { 0 }, "{vendor:?}: arcs struck");
    for (w, waypoints) in welds.iter().zip(&expected) {
        assert_eq!(w.network, 0, "{vendor:?}: a line sent or read under the arc");
        assert!(
            w.continuous(),
            "{vendor:?}: the bead stops: {:?}",
            w.moves.iter().map(|m| m.blended).collect::<Vec<_>>()
        );
        assert_eq!(w.moves.len(), waypoints.len() - 1, "{vendor:?}: the arc burns from the seam's start to its end");
    }
}

/// A run that stopped before any motion with one of `codes`, the TP
/// program branching on it, and a reason on the pendant.
fn stopped(vendor: Vendor, run: &Run, codes: &[i32]) -> String {
    assert!(codes.contains(&run.result), "{vendor:?}: result {} not one of {codes:?}: {:?}", run.result, run.messages);
    assert!(run.trace.moves().is_empty(), "{vendor:?}: the torch moved");
    assert!(!run.trace.events.contains(&Event::ArcOn), "{vendor:?}: the arc went on");
    if vendor == Vendor::Fanuc {
        assert_eq!(run.alarms, [if run.result < 0 { 1 } else { 2 }], "the TP program branched on R[9]");
    }
    run.messages.last().cloned().expect("a reason on the pendant")
}

const VENDORS: [Vendor; 2] = [Vendor::Kuka, Vendor::Fanuc];

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_weld_one_seam_in_one_blended_bead() {
    for vendor in VENDORS {
        welded(vendor, Scenario::OneSeam, &run(vendor, Scenario::OneSeam, false).await, 1, true);
        // The dry run: the same motion, no arc.
        welded(vendor, Scenario::OneSeam, &run(vendor, Scenario::OneSeam, true).await, 1, false);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_store_check_and_weld_a_250_waypoint_seam() {
    for vendor in VENDORS {
        let done = run(vendor, Scenario::LongSeam, false).await;
        welded(vendor, Scenario::LongSeam, &done, 1, true);
        assert!(done.trace.moves().len() >= 252, "{vendor:?}: {} moves", done.trace.moves().len());
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_weld_several_seams_one_bead_each() {
    for vendor in VENDORS {
        welded(vendor, Scenario::SeveralSeams, &run(vendor, Scenario::SeveralSeams, false).await, 3, true);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_show_a_refusals_cause_and_the_torch_stays() {
    for vendor in VENDORS {
        let refused = run(vendor, Scenario::Refusal, false).await;
        sent_pose(vendor, &refused);
        let reason = stopped(vendor, &refused, &[-40, -46, -60, -61, -62, -63, -64, -65, -66, -67, -68, -69]);
        // KUKA shows the error line as it came (-code,cause); FANUC its
        // cause alone.
        let cause = reason.split_once(',').map_or(reason.as_str(), |(code, cause)| {
            assert!(vendor == Vendor::Kuka && code.starts_with('-'), "{vendor:?}: {reason}");
            cause
        });
        assert!(!cause.is_empty() && !cause.starts_with("frame"), "{vendor:?}: the cause first: {reason:?}");
        let too_long = run(vendor, Scenario::TooLongLine, false).await;
        let reason = stopped(vendor, &too_long, &[-5]);
        assert!(reason.contains("max_line_bytes"), "{vendor:?}: {reason}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_leave_the_torch_at_the_capture_pose_when_the_daemon_stops_before_the_arc() {
    for vendor in VENDORS {
        for scenario in [Scenario::StopDuringFetch, Scenario::StopBeforeArc] {
            let gone = run(vendor, scenario, false).await;
            stopped(vendor, &gone, &[2, 3, -47]);
            let checks = gone.trace.sent().iter().filter(|l| l.starts_with("CHECK")).count();
            assert_eq!(checks, usize::from(scenario == Scenario::StopBeforeArc), "{vendor:?} {scenario:?}");
        }
    }
}

/// KUKA and FANUC on a thick V-groove under the example procedure (its
/// root pass weaving, `Scenario::Passes`): every
/// piece of every pass welded as a seam, each move into a weld waypoint at
/// the travel speed the plan gives there (KUKA's $VEL.CP, FANUC's R[7]
/// register speed, from the line's mm/s); FANUC weaves each move with
/// ArcTool's `Weave Sine` at the plan's half-swing and frequency there,
/// and not at all where the plan lays no weave. KUKA welds the woven path
/// ([`kuka_welds_the_woven_path`]).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kuka_and_fanuc_weld_each_pass_at_its_speeds() {
    for vendor in VENDORS {
        let run = run(vendor, Scenario::Passes, false).await;
        assert_eq!(run.result, 0, "{vendor:?}: {:?}", run.messages);
        if vendor == Vendor::Kuka {
            kuka_welds_the_woven_path(&run);
            continue;
        }
        let expected = super::harness::reference_pieces(Scenario::Passes, vendor.dialect(), &sent_pose(vendor, &run));
        assert!(expected.len() >= 2, "{} pieces: a 9 mm groove takes several passes", expected.len());
        let moves = run.trace.moves();
        let mut at = 0;
        let mut woven = 0;
        for (k, piece) in expected.iter().enumerate() {
            let weld = &moves[at + 1..at + 1 + piece.len()];
            if vendor == Vendor::Fanuc {
                // ArcTool's weave on each move into a weld waypoint is the
                // line's (to its three decimals through a 32-bit REAL), and
                // none where the line has none: not on the approach, the
                // move to the seam's start (before the arc), nor the retract.
                let weave = &run.weave[at..at + piece.len() + 2];
                let last = weave.len() - 1;
                assert!(weave[0].is_none() && weave[1].is_none() && weave[last].is_none(), "piece {k}: {weave:?}");
                for (j, (laid, (_, [_, a, f]))) in weave[1..last].iter().zip(piece).enumerate().skip(1) {
                    match laid {
                        None => assert_eq!(*a, 0.0, "piece {k} move {j}: no weave for {a} mm {f} Hz"),
                        Some([amplitude, frequency]) => {
                            let held = (amplitude - a).abs() < 2e-3 && (frequency - f).abs() < 2e-3;
                            assert!(held, "piece {k} move {j}: weave {amplitude} mm {frequency} Hz for {a} mm {f} Hz");
                            woven += 1;
                        }
                    }
                }
            }
            at += piece.len() + 2;
            for (j, (m, (pose, [speed, ..]))) in weld.iter().zip(piece).enumerate().skip(1) {
                same_pose(&target(vendor, m), pose)
                    .unwrap_or_else(|e| panic!("{vendor:?} piece {k} waypoint {j}: {e}"));
                // The line's three decimals, through a 32-bit REAL.
                assert!(
                    (m.speed_mm_s - speed).abs() < 2e-3,
                    "{vendor:?} piece {k} move {j}: {} for {speed}",
                    m.speed_mm_s
                );
            }
        }
        assert_eq!(at, moves.len(), "{vendor:?}: no motion beyond the pieces'");
        let welds = run.trace.welds().unwrap();
        assert_eq!(welds.len(), expected.len(), "{vendor:?}: one bead a piece");
        assert!(welds.iter().all(|w| w.continuous()), "{vendor:?}: a bead stops between its waypoints");
        if vendor == Vendor::Fanuc {
            assert!(woven > 0, "the passes weave somewhere, or the weave's registers are not tested");
        }
    }
}

/// KUKA's program has no weave function: each piece's moves are the
/// plan's woven path ([`super::woven::check_piece`]: the weave's offsets
/// with the piece's phase, the plan's speed along the seam, the torch's
/// turn), one bead a piece, each C_DIS at most a quarter of the shorter
/// move beside it, so the weave is not smoothed away.
fn kuka_welds_the_woven_path(run: &Run) {
    let pieces = super::woven::plan_pieces(Scenario::Passes, Dialect::Kuka, &sent_pose(Vendor::Kuka, run));
    let moves = run.trace.moves();
    let mut at = 0;
    let mut off_the_line = 0;
    for (k, (piece, lines)) in pieces.iter().enumerate() {
        let weld = &moves[at + 1..at + 1 + lines];
        let cdis = &run.cdis[at + 1..at + 1 + lines];
        let apart = |a: &Move, b: &Move| {
            (target(Vendor::Kuka, a).translation.vector - target(Vendor::Kuka, b).translation.vector).norm()
        };
        for j in 1..weld.len() - 1 {
            let shorter = apart(weld[j - 1], weld[j]).min(apart(weld[j], weld[j + 1]));
            let limit = (0.25 * shorter).min(1.0);
            assert!(
                f64::from(cdis[j]) <= limit + 1e-3,
                "piece {k} move {j}: C_DIS {} mm for moves of {shorter:.3}",
                cdis[j]
            );
        }
        let poses: Vec<_> = weld.iter().map(|m| (target(Vendor::Kuka, m), m.speed_mm_s)).collect();
        let woven = super::woven::check_piece(piece, &poses).unwrap_or_else(|e| panic!("KUKA piece {k}: {e}"));
        off_the_line += woven.off_the_line;
        at += lines + 2;
    }
    assert_eq!(at, moves.len(), "KUKA: no motion beyond the pieces'");
    assert!(off_the_line > 0, "the root pass weaves, and KUKA welded it straight");
    let welds = run.trace.welds().unwrap();
    assert_eq!(welds.len(), pieces.len(), "KUKA: one bead a piece");
    assert!(welds.iter().all(|w| w.continuous()), "KUKA: a bead stops between its points");
}

/// FANUC's helper refuses a weave its TP program's schedules may not
/// take (a half-swing over `WEAVE_MM`, a frequency over `WEAVE_HZ`)
/// before the torch moves, naming the limit; never cut to fit.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fanuc_refuses_a_weave_over_its_schedules_limits() {
    let swing = fanuc::Overrides { weave_mm: Some(0.05), ..fanuc::Overrides::default() };
    let refused = run_with(Vendor::Fanuc, Scenario::Passes, false, swing).await;
    let reason = stopped(Vendor::Fanuc, &refused, &[11]);
    assert_eq!(reason, "weave half-swing over WEAVE_MM 0.05 mm");
    let hertz = fanuc::Overrides { weave_hz: Some(0.05), ..fanuc::Overrides::default() };
    let refused = run_with(Vendor::Fanuc, Scenario::Passes, false, hertz).await;
    let reason = stopped(Vendor::Fanuc, &refused, &[12]);
    assert_eq!(reason, "weave Hz not over 0, up to WEAVE_HZ 0.05");
}

/// FANUC without a weld procedure: the helper still asks for the process
/// lines, each says speed 0, and every move into a weld waypoint is made
/// at the TP program's own weld speed R[20] (`welded` holds them to 8
/// mm/s).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fanuc_welds_at_its_own_speed_where_the_process_lines_say_0() {
    let run = run(Vendor::Fanuc, Scenario::OneSeam, false).await;
    let process: Vec<&str> = run.trace.reads().into_iter().filter(|l| l.starts_with("4,")).collect();
    let moves = run.trace.moves();
    // One process line a weld waypoint: every move but approach and retract.
    assert_eq!(process.len(), moves.len() - 2, "{process:?}");
    for line in &process {
        let speed: f64 = line.split(',').nth(3).unwrap().trim().parse().unwrap();
        assert_eq!(speed, 0.0, "{line}");
    }
    welded(Vendor::Fanuc, Scenario::OneSeam, &run, 1, true);
}
