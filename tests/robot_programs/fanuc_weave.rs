//! FANUC's weave on process lines a scripted daemon serves: lines the
//! planner seldom gives in one scene (a weave that stops and starts again
//! along a seam, a half-swing or frequency past the helper's limits) are
//! written here, served as the daemon writes them (`Reply::format`), and
//! the KAREL helper and the TP program of `fanuc.rs` and `fanuc_tp.rs` run
//! on them.

use std::io::{Read, Write};
use std::net::TcpListener;

use nalgebra::{Translation3, UnitQuaternion};
use weldseam::geometry::Isometry3;
use weldseam_proto::text::{Dialect, PointKind, Reply, seam_checks};

use super::fanuc;
use super::fanuc_tp;
use super::karel::Controller;

/// One weld waypoint of the script: its X (mm) along a straight seam and
/// its process line's speed (mm/s), half-swing (mm) and frequency (Hz).
type Weld = (f64, [f64; 3]);

/// The lines of one seam as the daemon numbers them: approach, each weld
/// waypoint followed by its process line, retract.
fn seam_lines(welds: &[Weld]) -> Vec<Reply> {
    let pose = |x: f64, z: f64| vec![x, 0.0, z, 180.0, 0.0, 0.0];
    let mut lines = vec![(PointKind::Approach as u8, pose(welds[0].0, 350.0), [0.0; 3])];
    for (x, motion) in welds {
        lines.push((PointKind::Weld as u8, pose(*x, 300.0), [0.0; 3]));
        lines.push((4, Vec::new(), *motion));
    }
    lines.push((PointKind::Retract as u8, pose(welds[welds.len() - 1].0, 350.0), [0.0; 3]));
    let total = lines.len() as u64;
    lines
        .into_iter()
        .zip(1u64..)
        .map(|((kind, pose, motion), pulled)| {
            let remaining = total - pulled;
            match kind {
                4 => Reply::Process { seam: 1, remaining, motion },
                1 => Reply::Waypoint { kind: PointKind::Approach, seam: 1, remaining, pose },
                2 => Reply::Waypoint { kind: PointKind::Weld, seam: 1, remaining, pose },
                _ => Reply::Waypoint { kind: PointKind::Retract, seam: 1, remaining, pose },
            }
        })
        .collect()
}

/// Serves one session of the script on loopback: HELLO, the plan's ok
/// line, each NEXT its line, CHECK the seam's check; returns the address.
fn serve(lines: Vec<Reply>) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        let Ok((mut stream, _)) = listener.accept() else { return };
        let check = seam_checks(&lines, Dialect::Fanuc);
        let mut next = lines.iter();
        let mut request = Vec::new();
        let mut byte = [0u8; 1];
        while stream.read(&mut byte).unwrap_or(0) == 1 {
            if byte[0] != b'\r' {
                request.push(byte[0]);
                continue;
            }
            let text = String::from_utf8_lossy(&request).into_owned();
            request.clear();
            let reply = match text.split(',').next().unwrap_or("") {
                "HELLO" => Reply::Ok(2, 1),
                "TRIGGER" => Reply::Ok(1, lines.len() as u64),
                "NEXT" => next.next().expect("no NEXT past the plan").clone(),
                "CHECK" => check[0].clone(),
                other => panic!("the helper sent {other:?}"),
            };
            if stream.write_all(reply.format(Dialect::Fanuc).unwrap().as_bytes()).is_err() {
                return;
            }
        }
    });
    address
}

/// Runs WELD_SEAM against the script: the result code, the weave laid on
/// each move, the pendant's messages.
fn run(welds: &[Weld], ov: fanuc::Overrides) -> (i32, Vec<Option<[f64; 2]>>, Vec<String>) {
    let address = serve(seam_lines(welds));
    let flange = Isometry3::from_parts(Translation3::new(400.0, 0.0, 600.0), UnitQuaternion::identity());
    let mut tp = Controller::new(&address, flange, Isometry3::identity());
    let mut helper = fanuc::load_program(&mut tp, &ov);
    fanuc_tp::weld_seam(&mut tp, &mut helper, false);
    (tp.r[9].int(), tp.weave_at_moves, tp.tperror)
}

/// A weave that stops along the seam and starts again: each move into a
/// weld waypoint weaves with its own line's half-swing and frequency, and
/// not at all where its line has none (ArcTool's `Weave End` before it);
/// nothing weaves before the arc or on the way off the seam.
#[test]
fn fanuc_weaves_each_move_as_its_line_says_and_stops_where_it_says_none() {
    let welds = [
        (500.0, [8.0, 0.0, 0.0]),
        (510.0, [8.0, 1.2, 2.5]),
        (520.0, [8.0, 1.2, 2.5]),
        (530.0, [8.0, 0.0, 0.0]),
        (540.0, [7.0, 0.0, 0.0]),
        (550.0, [6.0, 1.5, 2.0]),
        (560.0, [6.0, 0.8, 4.0]),
    ];
    let (result, weave, messages) = run(&welds, fanuc::Overrides::default());
    assert_eq!(result, 0, "{messages:?}");
    let laid = |a: f64, f: f64| Some([a, f]);
    // Approach, the move to the seam's start before the arc, a move into
    // each further weld waypoint, retract.
    let expected = [None, None, laid(1.2, 2.5), laid(1.2, 2.5), None, None, laid(1.5, 2.0), laid(0.8, 4.0), None];
    assert_eq!(weave.len(), expected.len(), "{weave:?}");
    for (k, (got, want)) in weave.iter().zip(&expected).enumerate() {
        let same = match (got, want) {
            (None, None) => true,
            (Some(g), Some(w)) => g.iter().zip(w).all(|(a, b)| (a - b).abs() < 1e-4),
            _ => false,
        };
        assert!(same, "move {k}: weave {got:?} for {want:?}");
    }
}

/// A process line's weave the TP program's schedules may not take is
/// refused by the helper before the torch moves, the limit named: a
/// half-swing over WEAVE_MM or below 0, a woven frequency of 0 or over
/// WEAVE_HZ; never cut to fit.
#[test]
fn fanuc_refuses_a_bad_weave_before_the_torch_moves() {
    let cases: [([f64; 3], i32, &str); 4] = [
        ([8.0, 5.5, 2.0], 11, "weave half-swing over WEAVE_MM 5.00 mm"),
        ([8.0, -0.5, 2.0], 11, "weave half-swing over WEAVE_MM 5.00 mm"),
        ([8.0, 1.0, 0.0], 12, "weave Hz not over 0, up to WEAVE_HZ 5.00"),
        ([8.0, 1.0, 6.0], 12, "weave Hz not over 0, up to WEAVE_HZ 5.00"),
    ];
    for (motion, code, message) in cases {
        let welds = [(500.0, [8.0, 0.0, 0.0]), (510.0, motion), (520.0, [8.0, 0.0, 0.0])];
        let (result, weave, messages) = run(&welds, fanuc::Overrides::default());
        assert_eq!(result, code, "{motion:?}: {messages:?}");
        assert!(weave.is_empty(), "{motion:?}: the torch moved");
        assert_eq!(messages.last().map(String::as_str), Some(message), "{motion:?}");
    }
}
