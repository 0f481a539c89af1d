use nalgebra::Rotation3;
use proptest::prelude::*;
use weldseam_proto::text::Dialect;

use super::*;
use crate::convert::to_text::weave_laid_by;

/// A torch pointing down (its z along the base's −Z), travel along +X.
fn down() -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vec3::x_axis(), std::f64::consts::PI)
}

fn weave(pattern: WeavePattern, amplitude_mm: f64, dwell_mm: f64) -> Weave {
    Weave { pattern, amplitude_mm, wavelength_mm: 3.0, dwell_mm }
}

fn motion(speed: f64, weave: Option<Weave>) -> Option<Motion> {
    let (weave_amplitude_mm, weave_frequency_hz) =
        weave.map_or((0.0, 0.0), |w| (w.amplitude_mm, w.frequency_hz(speed)));
    Some(Motion { travel_speed_mm_s: speed, weave_amplitude_mm, weave_frequency_hz })
}

/// A piece through `positions`, every move at `speed` weaving with `w`
/// (the first point's move is the approach's: no weave).
fn piece(positions: &[Vec3], orientation: Rotation3<f64>, speed: f64, w: Option<Weave>) -> Vec<PiecePoint> {
    positions
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let weave = if k == 0 { None } else { w };
            PiecePoint { pose: Waypoint { position: *p, orientation }, motion: motion(speed, weave), weave }
        })
        .collect()
}

/// A point of the woven path read back against the piece: the distance
/// along the piece, the signed sideways offset, the move it lies in.
fn read_back(piece: &[PiecePoint], s: &[f64], from: usize, q: &Waypoint) -> (f64, f64, usize) {
    let mut i = from.max(1);
    loop {
        let (a, b) = (piece[i - 1].pose.position, piece[i].pose.position);
        let along = (b - a).normalize();
        let t = (q.position - a).dot(&along);
        if t <= (b - a).norm() + 1e-9 || i + 1 == piece.len() {
            let base = a + along * t;
            let offset = (q.position - base).dot(&sideways(&along, &q.orientation));
            assert!(
                (q.position - base - sideways(&along, &q.orientation) * offset).norm() < 1e-9,
                "off the swing plane"
            );
            return (s[i - 1] + t, offset, i);
        }
        i += 1;
    }
}

/// Every point on the weave's offset (or on the line near the ends of
/// the weave), the phase the piece's, the speed along the seam the
/// plan's, and the ends the plan's; returns the largest offset each side.
fn check(piece: &[PiecePoint], out: &[(Waypoint, Option<Motion>)]) -> (f64, f64) {
    let s = distances(piece);
    assert_eq!(out[0].0, piece[0].pose, "the first point is the plan's");
    assert_eq!(out.last().unwrap().0, piece.last().unwrap().pose, "the last point is the plan's");
    let (mut most, mut least) = (0.0_f64, 0.0_f64);
    let mut at = 1;
    let mut previous = 0.0;
    for (k, (q, m)) in out.iter().enumerate().skip(1) {
        let (station, offset, i) = read_back(piece, &s, at, q);
        at = i;
        let w = piece[i].weave;
        let expected = w.map_or(0.0, |w| w.offset(station));
        let near_end = station < w.map_or(0.0, |w| w.wavelength_mm / 2.0) + 1e-9
            || station > s.last().unwrap() - w.map_or(0.0, |w| w.wavelength_mm / 2.0) - 1e-9;
        assert!(
            (offset - expected).abs() < 1e-9 || (near_end && offset.abs() < 1e-9),
            "point {k} at {station:.4} mm: offset {offset:.5} for {expected:.5}"
        );
        most = most.max(offset);
        least = least.min(offset);
        // The time the move takes at its speed is the time the plan gives
        // the seam it advances.
        let m = m.expect("a motion");
        assert_eq!((m.weave_amplitude_mm, m.weave_frequency_hz), (0.0, 0.0), "a woven point carries no weave");
        let travelled = (q.position - out[k - 1].0.position).norm();
        let planned = piece[i].motion.unwrap().travel_speed_mm_s;
        let along_seam = (station - previous) / (travelled / m.travel_speed_mm_s);
        assert!(
            (along_seam - planned).abs() < 1e-9 * planned,
            "point {k}: {along_seam} mm/s along the seam for {planned}"
        );
        // The torch turned as the plan turns it there.
        let share = (station - s[i - 1]) / (s[i] - s[i - 1]);
        let turned = piece[i - 1].pose.orientation.slerp(&piece[i].pose.orientation, share);
        assert!(turned.angle_to(&q.orientation) < 1e-9, "point {k}: the torch");
        previous = station;
    }
    (most, least)
}

#[test]
fn each_pattern_is_drawn_to_its_amplitude_with_the_pieces_phase_and_speed() {
    // Waypoints every 10 mm, not a multiple of the 3 mm wavelength: a
    // phase begun again at a waypoint would be seen.
    let positions: Vec<Vec3> = (0..=6).map(|k| Vec3::new(10.0 * k as f64, 0.0, 0.0)).collect();
    for pattern in [WeavePattern::Triangle, WeavePattern::Sine, WeavePattern::Trapezoid] {
        let w = weave(pattern, 1.5, if pattern == WeavePattern::Trapezoid { 0.5 } else { 0.0 });
        let p = piece(&positions, down(), 6.0, Some(w));
        let out = woven(&p);
        let (most, least) = check(&p, &out);
        assert!((most - 1.5).abs() < 1e-9 && (least + 1.5).abs() < 1e-9, "{pattern:?}: {least} to {most}");
        // Down with travel along +X: the positive side is +Y.
        let first_side = out.iter().map(|(q, _)| q.position.y).find(|y| y.abs() > 1e-6).unwrap();
        assert!(first_side > 0.0, "{pattern:?} swings to t × z first");
        // The pattern's points: a cycle's turns, and the waypoints.
        let per_cycle = cycle_points(&w).len();
        assert!(out.len() >= 60 / 3 * per_cycle - per_cycle, "{pattern:?}: {} points", out.len());
    }
}

#[test]
fn a_trapezoid_holds_each_side_for_its_dwell() {
    let positions = [Vec3::zeros(), Vec3::new(30.0, 0.0, 0.0)];
    let w = weave(WeavePattern::Trapezoid, 2.0, 0.6);
    let out = woven(&piece(&positions, down(), 6.0, Some(w)));
    // Consecutive points both at a side, 0.6 mm apart along the seam.
    let dwells = out
        .windows(2)
        .filter(|q| {
            (q[0].0.position.y.abs() - 2.0).abs() < 1e-9 && (q[1].0.position.y - q[0].0.position.y).abs() < 1e-9
        })
        .map(|q| q[1].0.position.x - q[0].0.position.x)
        .collect::<Vec<_>>();
    assert!(dwells.len() >= 18, "{dwells:?}");
    assert!(dwells.iter().all(|d| (d - 0.6).abs() < 1e-9), "{dwells:?}");
}

#[test]
fn a_weave_starts_and_stops_on_the_seams_line() {
    // The middle moves weave, the first and last do not: the torch leaves
    // the line at a crossing and rejoins it at one, never with a jump.
    let positions: Vec<Vec3> = (0..=4).map(|k| Vec3::new(7.0 * k as f64, 0.0, 0.0)).collect();
    let w = weave(WeavePattern::Sine, 1.0, 0.0);
    let mut p = piece(&positions, down(), 5.0, Some(w));
    for k in [1, 4] {
        p[k].weave = None;
        p[k].motion = motion(5.0, None);
    }
    let out = woven(&p);
    let lateral: Vec<(f64, f64)> = out.iter().map(|(q, _)| (q.position.x, q.position.y)).collect();
    for (x, y) in &lateral {
        if *x <= 7.5 - 1e-9 || *x >= 21.0 + 1e-9 {
            assert!(y.abs() < 1e-12, "woven outside the weaving moves' crossings: {x} {y}");
        } else {
            assert!((y - w.offset(*x)).abs() < 1e-9, "{x}: {y}");
        }
    }
    assert!(lateral.iter().any(|(_, y)| (y - 1.0).abs() < 1e-9), "it weaves in between");
}

#[test]
fn a_piece_that_does_not_weave_is_its_points() {
    let positions = [Vec3::zeros(), Vec3::new(5.0, 1.0, 0.0), Vec3::new(10.0, 1.0, 0.0)];
    let p = piece(&positions, down(), 6.0, None);
    let out = woven(&p);
    assert_eq!(out, p.iter().map(|q| (q.pose, q.motion)).collect::<Vec<_>>());
}

#[test]
fn abb_and_fanuc_weave_on_the_controller_kuka_and_ur_in_the_path() {
    assert_eq!(weave_laid_by(Dialect::Abb), WeaveLaidBy::Controller);
    assert_eq!(weave_laid_by(Dialect::Fanuc), WeaveLaidBy::Controller);
    assert_eq!(weave_laid_by(Dialect::Kuka), WeaveLaidBy::Path);
    assert_eq!(weave_laid_by(Dialect::Ur), WeaveLaidBy::Path);
}

/// The distance from `q` to the polyline through `points`.
fn to_polyline(points: &[PiecePoint], q: &Vec3) -> f64 {
    points
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].pose.position, w[1].pose.position);
            let t = ((q - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
            (q - (a + (b - a) * t)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

proptest! {
    /// On a bending seam with a turning torch, every point of the woven
    /// path lies within the half-swing of the seam's line, and the
    /// piece's ends are the plan's.
    #[test]
    fn every_woven_point_lies_within_the_amplitude_and_the_ends_are_the_plans(
        bends in proptest::collection::vec((1.0f64..12.0, -0.4f64..0.4, -0.2f64..0.2, -0.3f64..0.3), 1..8),
        pattern in 0usize..3,
        amplitude in 0.2f64..3.0,
        wavelength in 1.0f64..8.0,
        dwell_share in 0.0f64..0.25,
        speed in 2.0f64..15.0,
    ) {
        let pattern = [WeavePattern::Triangle, WeavePattern::Sine, WeavePattern::Trapezoid][pattern];
        let dwell_mm = if pattern == WeavePattern::Trapezoid { dwell_share * wavelength } else { 0.0 };
        let w = Weave { pattern, amplitude_mm: amplitude, wavelength_mm: wavelength, dwell_mm };
        let mut position = Vec3::new(100.0, -20.0, 5.0);
        let mut heading = 0.0_f64;
        let mut p = Vec::new();
        for (k, &(step, turn, climb, tilt)) in std::iter::once(&(0.0, 0.0, 0.0, 0.0)).chain(&bends).enumerate() {
            heading += turn;
            position += Vec3::new(heading.cos(), heading.sin(), climb) * step;
            let orientation = Rotation3::from_euler_angles(std::f64::consts::PI + tilt, 0.0, heading);
            let weave = (k > 0).then_some(w);
            p.push(PiecePoint { pose: Waypoint { position, orientation }, motion: motion(speed, weave), weave });
        }
        let out = woven(&p);
        prop_assert_eq!(out[0].0, p[0].pose);
        prop_assert_eq!(out.last().unwrap().0, p.last().unwrap().pose);
        for (q, m) in &out {
            let d = to_polyline(&p, &q.position);
            prop_assert!(d <= amplitude + 1e-9, "{} mm off the seam for a {} mm half-swing", d, amplitude);
            prop_assert!(m.unwrap().travel_speed_mm_s > 0.0);
        }
    }
}
