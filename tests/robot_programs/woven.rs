//! What a program without a weave function (KUKA, UR) must do with a
//! weaving pass: weld the woven path the daemon lays, read back from the
//! moves the program made against the plan's own pass points and weaves,
//! not against the daemon's lines. A move's place is projected onto the
//! plan's pass (the distance along the piece and the sideways offset,
//! across the seam in the plane the torch swings in, `t × z`), and held
//! to [`Weave::offset`] at that distance from the piece's start (so a
//! phase begun again at a waypoint fails), within 0.01 mm; its speed to
//! the plan's travel speed along the seam; a weaving move of the plan that
//! is welded straight fails.

use nalgebra::Vector3;
use weldseam::convert::to_text;
use weldseam::convert::woven::sideways;
use weldseam::geometry::Isometry3;
use weldseam::process::weave::Weave;
use weldseam_proto::text::Dialect;

use super::harness::{Scenario, same_pose};

/// One point of a piece of a pass as the plan gives it.
#[derive(Debug, Clone, Copy)]
pub struct PlanPoint {
    pub pose: Isometry3<f64>,
    pub speed_mm_s: f64,
    /// The weave of the move into this point.
    pub weave: Option<Weave>,
}

/// The plan's pieces for the scenario (as the program's plan line asks)
/// and, for each, how many weld lines the link sends for it in `dialect`
/// (only to split the program's moves into pieces).
pub fn plan_pieces(scenario: Scenario, dialect: Dialect, pose_numbers: &[f64]) -> Vec<(Vec<PlanPoint>, usize)> {
    let config = scenario.config();
    let line = weldseam_proto::text::PlanLine {
        joint: scenario.joint().into(),
        pose: pose_numbers.to_vec(),
        groove_depth: None,
    };
    let request = weldseam::convert::from_proto::text_plan_request(&line, dialect, config.euler).unwrap();
    let plan = weldseam::pipeline::Planner::new(config).plan(&scenario.scene().cloud, &request).unwrap();
    let mut pieces = Vec::new();
    for seam in &plan.seams {
        let passes = weldseam::pipeline::passes::pass_trajectories(seam).expect("a procedure is configured");
        let sent = to_text::link_pieces(seam, dialect, true);
        for (piece, lines) in passes.pieces.iter().zip(sent) {
            let points = piece
                .points
                .iter()
                .map(|p| PlanPoint {
                    pose: Isometry3::from_parts(p.pose.position.into(), p.pose.orientation.into()),
                    speed_mm_s: p.travel_speed_mm_s(),
                    weave: p.weave,
                })
                .collect();
            pieces.push((points, lines.len()));
        }
    }
    pieces
}

/// What a piece's moves showed.
#[derive(Debug, Default)]
pub struct Woven {
    /// Moves off the seam's line by more than 0.01 mm.
    pub off_the_line: usize,
}

/// Holds the weld moves of one piece (its first weld point to its last,
/// each a pose and the speed into it, mm/s) to the plan's woven path.
pub fn check_piece(piece: &[PlanPoint], moves: &[(Isometry3<f64>, f64)]) -> Result<Woven, String> {
    let position = |p: &Isometry3<f64>| p.translation.vector;
    let mut s = vec![0.0];
    for k in 1..piece.len() {
        s.push(s[k - 1] + (position(&piece[k].pose) - position(&piece[k - 1].pose)).norm());
    }
    same_pose(&moves[0].0, &piece[0].pose).map_err(|e| format!("the first weld point: {e}"))?;
    let last = moves.len() - 1;
    same_pose(&moves[last].0, &piece.last().unwrap().pose).map_err(|e| format!("the last weld point: {e}"))?;
    let weaves = |i: usize| piece[i].weave.filter(|w| w.amplitude_mm > 0.0);
    // Where the weave may be 0 rather than its offset: within half a
    // wavelength of the ends of a run of weaving moves.
    let near_run_end = |i: usize, station: f64| {
        let half = weaves(i).map_or(0.0, |w| w.wavelength_mm / 2.0) + 0.01;
        let mut start = i;
        while start > 1 && weaves(start - 1).is_some() {
            start -= 1;
        }
        let mut end = i;
        while end + 1 < piece.len() && weaves(end + 1).is_some() {
            end += 1;
        }
        station < s[start - 1] + half || station > s[end] - half
    };
    let mut woven = Woven::default();
    let mut widest = vec![0.0_f64; piece.len()];
    let mut i = 1;
    let mut previous = (0.0, position(&moves[0].0));
    for (k, (pose, speed)) in moves.iter().enumerate().skip(1) {
        // The plan's move this one lies in: the first whose end it does
        // not pass.
        let (station, offset) = loop {
            let (a, b) = (position(&piece[i - 1].pose), position(&piece[i].pose));
            let along: Vector3<f64> = (b - a).normalize();
            let t = (position(pose) - a).dot(&along);
            if t <= (b - a).norm() + 0.01 || i + 1 == piece.len() {
                let across = sideways(&along, &pose.rotation.to_rotation_matrix());
                let off = position(pose) - (a + along * t);
                if (off - across * off.dot(&across)).norm() > 0.01 {
                    return Err(format!("move {k}: {:.3} mm off the plane the torch swings in", off.norm()));
                }
                break (s[i - 1] + t, off.dot(&across));
            }
            i += 1;
        };
        let expected = weaves(i).map_or(0.0, |w| w.offset(station));
        let straight_allowed = near_run_end(i, station);
        if (offset - expected).abs() > 0.01 && !(straight_allowed && offset.abs() <= 0.01) {
            return Err(format!("move {k} at {station:.3} mm: {offset:.4} mm across for the weave's {expected:.4}"));
        }
        woven.off_the_line += usize::from(offset.abs() > 0.01);
        widest[i] = widest[i].max(offset.abs());
        // The seam advanced in the move's time at its speed: the plan's
        // travel speed.
        let time = (position(pose) - previous.1).norm() / speed;
        let along_seam = (station - previous.0) / time;
        let planned = piece[i].speed_mm_s;
        if (along_seam - planned).abs() > 0.01 * planned {
            return Err(format!("move {k}: {along_seam:.3} mm/s along the seam for the plan's {planned:.3}"));
        }
        // The torch turned as the plan turns it there.
        let share = (station - s[i - 1]) / (s[i] - s[i - 1]);
        let turned = piece[i - 1].pose.rotation.slerp(&piece[i].pose.rotation, share.clamp(0.0, 1.0));
        let angle = turned.angle_to(&pose.rotation).to_degrees();
        if angle > 0.01 {
            return Err(format!("move {k}: the torch {angle:.4}° from the plan's"));
        }
        previous = (station, position(pose));
    }
    // Every weaving move of the plan two wavelengths long or more swings
    // to its half-swing: none is welded straight.
    for i in 1..piece.len() {
        if let Some(w) = weaves(i)
            && s[i] - s[i - 1] >= 2.0 * w.wavelength_mm
            && widest[i] < 0.9 * w.amplitude_mm
        {
            return Err(format!(
                "move into point {i} weaves {} mm in the plan, {:.3} mm welded",
                w.amplitude_mm, widest[i]
            ));
        }
    }
    Ok(woven)
}
