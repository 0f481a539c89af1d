//! A weave written into the path (part of [`super::to_text`]): for a
//! dialect whose shipped program has no weave function of its own, every
//! weld move whose pass weaves is sent as the points of the woven path,
//! each with the travel speed that keeps the plan's speed along the seam
//! and no weave of its own, so the program welds it as any other move.
//!
//! The woven path of a piece (one pass welded with the arc on, its points
//! P0..Pn) is, at a distance `s` along the piece's polyline from P0:
//!
//! - **where**: the point of the polyline at `s`, moved sideways by the
//!   weave's offset [`Weave::offset`]`(s)`, the weave being the one of the
//!   move the point lies in (the move into Pi weaves as Pi's pass says).
//!   The phase is the piece's: `s` runs from the piece's first point, so a
//!   cycle begun before a waypoint goes on after it.
//! - **sideways**: along `t × z`, `t` the move's direction along the seam
//!   and `z` the torch's axis (the tool's z, from the torch into the
//!   work) at that point: across the seam in the plane the torch swings
//!   in, as a controller's weave function swings in the tool's frame. A
//!   positive offset is to the left of travel seen from behind the torch.
//! - **the torch**: turned as the plan turns it, the orientation
//!   interpolated (slerp) between the two waypoints by the share of the
//!   move travelled.
//! - **where it weaves**: a run of weaving moves weaves from its first
//!   crossing of the seam's line (every half wavelength of `s`) to its
//!   last, so the torch leaves and rejoins the line without a sideways
//!   jump; the rest of the run, under half a wavelength at each end, is
//!   welded on the line. A piece's first and last points are therefore
//!   the plan's own, and the arc starts and ends on the seam.
//! - **how fast**: a woven move is longer than the seam it advances, so
//!   its speed is the plan's travel speed times the move's length over
//!   the seam it advances: the move takes the time the plan gives that
//!   stretch of seam, and the torch travels along the seam at the planned
//!   speed.
//!
//! The points of a cycle are where the pattern turns, so a straight move
//! between two draws it exactly: a triangle's sides and crossings (four a
//! cycle), a trapezoid's four corners and two crossings (six), a sine's
//! [`SINE_POINTS_PER_CYCLE`]. Each waypoint of the plan is kept as a point
//! too (the seam may bend there), and a pattern point closer to a
//! waypoint than [`CLOSEST_POINT_SHARE`] of a wavelength is left out, so no
//! move is too short for the program's blend (deploy/robots/README.md:
//! the shipped programs shrink their blend to what the moves allow).

use crate::config::procedure::WeavePattern;
use crate::geometry::Vec3;
use crate::pipeline::passes::Motion;
use crate::pipeline::trajectory::Waypoint;
use crate::process::weave::Weave;

/// Points of a sine's cycle: chords of an eighth of a cycle stay within
/// `1 - cos(π/8)`, about 8 %, of the half-swing of the curve, and a cycle
/// costs 16 lines of a program's storage (a pose and a process line each).
pub const SINE_POINTS_PER_CYCLE: usize = 8;

/// A pattern point nearer a waypoint of the plan than this share of the
/// wavelength is left out (the waypoint is kept): 0.09 mm at a 3 mm
/// wavelength, short enough that the pattern barely changes, long enough
/// that no move is a sliver the program's blend must shrink to nothing.
pub const CLOSEST_POINT_SHARE: f64 = 1.0 / 32.0;

/// Who lays a weave for a dialect's program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeaveLaidBy {
    /// The controller's own weave function, from the half-swing and
    /// frequency on each process line (ABB ArcWare, FANUC ArcTool).
    Controller,
    /// The daemon, into the path: the woven path's points are sent, each
    /// with a process line whose weave is zero (KUKA, UR).
    Path,
}

/// One point of a piece as the plan gives it: the pose, how the torch
/// travels into it, and the weave of that move (None where it does not
/// weave or the plan has no process).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PiecePoint {
    pub pose: Waypoint,
    pub motion: Option<Motion>,
    pub weave: Option<Weave>,
}

/// The points of the woven path of `piece`, each with its motion (the
/// speed into it, no weave). A piece that weaves nowhere comes back as
/// its points.
pub fn woven(piece: &[PiecePoint]) -> Vec<(Waypoint, Option<Motion>)> {
    let weaves = |k: usize| piece[k].weave.filter(|w| w.amplitude_mm > 0.0 && w.wavelength_mm > 0.0);
    if piece.len() < 2 || !(1..piece.len()).any(|k| weaves(k).is_some()) {
        return piece.iter().map(|p| (p.pose, p.motion)).collect();
    }
    let s = distances(piece);
    let windows = weave_windows(piece.len(), &s, weaves);
    let straight = |m: Option<Motion>| m.map(|m| Motion { weave_amplitude_mm: 0.0, weave_frequency_hz: 0.0, ..m });
    let mut out = vec![(piece[0].pose, straight(piece[0].motion))];
    let mut previous = (0.0, piece[0].pose.position);
    for i in 1..piece.len() {
        let (from, to) = (&piece[i - 1].pose, &piece[i].pose);
        let (s0, s1) = (s[i - 1], s[i]);
        let length = s1 - s0;
        let along = (to.position - from.position) / length.max(f64::MIN_POSITIVE);
        let window = windows[i].zip(weaves(i));
        let mut stations = window.map_or_else(Vec::new, |((start, end), w)| pattern_points(&w, s0, s1, start, end));
        stations.push(s1);
        for station in stations {
            // The waypoint itself is the plan's to the last bit.
            let (orientation, on_seam) = if station == s1 {
                (to.orientation, to.position)
            } else {
                let share = (station - s0) / length;
                (from.orientation.slerp(&to.orientation, share), from.position + (to.position - from.position) * share)
            };
            // The last point is the plan's, on the line.
            let offset = match window {
                Some(((start, end), w))
                    if (i + 1 < piece.len() || station < s1) && station >= start - 1e-9 && station <= end + 1e-9 =>
                {
                    w.offset(station)
                }
                _ => 0.0,
            };
            let position = on_seam + sideways(&along, &orientation) * offset;
            let advanced = station - previous.0;
            let travelled = (position - previous.1).norm();
            let motion = straight(piece[i].motion).map(|m| Motion {
                travel_speed_mm_s: if advanced > 0.0 {
                    m.travel_speed_mm_s * travelled / advanced
                } else {
                    m.travel_speed_mm_s
                },
                ..m
            });
            out.push((Waypoint { position, orientation }, motion));
            previous = (station, position);
        }
    }
    out
}

/// The sideways direction at a point of a move along `along` with the
/// torch turned `orientation`: `along × z`, z the torch's axis. Zero
/// where the torch points along the seam (no plane to swing in).
pub fn sideways(along: &Vec3, orientation: &nalgebra::Rotation3<f64>) -> Vec3 {
    let axis = orientation * Vec3::z();
    along.cross(&axis).try_normalize(1e-9).unwrap_or_else(Vec3::zeros)
}

/// Distance along the piece's polyline to each of its points, mm.
pub fn distances(piece: &[PiecePoint]) -> Vec<f64> {
    let mut s = Vec::with_capacity(piece.len());
    let mut total = 0.0;
    for (k, p) in piece.iter().enumerate() {
        if k > 0 {
            total += (p.pose.position - piece[k - 1].pose.position).norm();
        }
        s.push(total);
    }
    s
}

/// For each move (index of the point it goes into), the stretch of `s`
/// its run of weaving moves weaves over: from the run's first crossing of
/// the seam's line to its last. None for a move that does not weave or a
/// run too short to hold half a cycle.
fn weave_windows(n: usize, s: &[f64], weaves: impl Fn(usize) -> Option<Weave>) -> Vec<Option<(f64, f64)>> {
    let mut windows = vec![None; n];
    let mut i = 1;
    while i < n {
        let Some(first) = weaves(i) else {
            i += 1;
            continue;
        };
        let mut last = i;
        while last + 1 < n && weaves(last + 1).is_some() {
            last += 1;
        }
        let last_weave = weaves(last).unwrap_or(first);
        let start = crossing_at_or_after(&first, s[i - 1]);
        let end = crossing_at_or_before(&last_weave, s[last]);
        if end > start {
            windows[i..=last].fill(Some((start, end)));
        }
        i = last + 1;
    }
    windows
}

/// The first crossing of the seam's line (a multiple of half the
/// wavelength) at or after `s`.
fn crossing_at_or_after(w: &Weave, s: f64) -> f64 {
    let half = w.wavelength_mm / 2.0;
    let k = (s / half - 1e-9).ceil();
    k * half
}

/// The last crossing at or before `s`.
fn crossing_at_or_before(w: &Weave, s: f64) -> f64 {
    let half = w.wavelength_mm / 2.0;
    let k = (s / half + 1e-9).floor();
    k * half
}

/// Where the pattern turns within a cycle, as shares of it: the points a
/// straight move between two draws the pattern from.
pub fn cycle_points(w: &Weave) -> Vec<f64> {
    match w.pattern {
        WeavePattern::Triangle => vec![0.0, 0.25, 0.5, 0.75],
        WeavePattern::Sine => (0..SINE_POINTS_PER_CYCLE).map(|k| k as f64 / SINE_POINTS_PER_CYCLE as f64).collect(),
        WeavePattern::Trapezoid => {
            // As Weave::offset lays it: a swing, then the dwell around
            // each side's quarter.
            let swing = 0.25 - w.dwell_mm / w.wavelength_mm / 2.0;
            let mut points = vec![0.0, swing, 0.5 - swing, 0.5, 0.5 + swing, 1.0 - swing];
            points.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
            points
        }
    }
}

/// The pattern's points strictly inside the move from `s0` to `s1` and
/// within the weave's stretch `start..=end`, without those too near the
/// move's ends ([`CLOSEST_POINT_SHARE`]).
fn pattern_points(w: &Weave, s0: f64, s1: f64, start: f64, end: f64) -> Vec<f64> {
    let lambda = w.wavelength_mm;
    let keep_off = lambda * CLOSEST_POINT_SHARE;
    let shares = cycle_points(w);
    let first_cycle = (s0.max(start) / lambda).floor() as i64;
    let last_cycle = (s1.min(end) / lambda).ceil() as i64;
    let mut points = Vec::new();
    for cycle in first_cycle..=last_cycle {
        for share in &shares {
            let s = (cycle as f64 + share) * lambda;
            let inside = s > s0 + keep_off && s < s1 - keep_off;
            if inside && s >= start - 1e-9 && s <= end + 1e-9 {
                points.push(s);
            }
        }
    }
    points
}

#[cfg(test)]
#[path = "woven_tests.rs"]
mod tests;
