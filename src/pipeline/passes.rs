//! The trajectories a robot welds for one seam with its process: one per
//! pass, root first, each cut into the pieces the robot welds with the arc
//! on, every point a base-frame pose with the travel speed and weave of
//! its pass there.
//!
//! A pass's point at a waypoint is the waypoint (the root's aim point)
//! moved across the seam by the pass's `lateral_mm` and up from the root
//! by its `height_mm`, in the seam's frame at that waypoint
//! ([`Station`](crate::process::clearance::Station): along the seam, across it, out of the joint), with the
//! torch turned to the pass's work angle. The torch's clearance is
//! checked for every pass at the waypoint
//! ([`super::seam_process`]); where it had to lean to clear, every pass
//! there leans by as much, so the torch keeps the side it cleared on, and
//! a waypoint where no lean clears them all is cut. The traced pass's
//! points are the seam's waypoints themselves: a seam welded in one pass
//! gives exactly the waypoints the plan carries.
//!
//! The layout is laid out again at every waypoint from the joint measured
//! there, so a groove that deepens or widens along the seam has more
//! passes at one end than at the other. A pass is followed from waypoint
//! to waypoint by what it is in the groove, not by its index in the
//! station's list:
//!
//! - the root (or the single pass) is one pass all along, the seam's
//!   line, whether a station lays the joint in one bead or several;
//! - a fill pass is its layer (from the root up) and its bead within the
//!   layer (from the first plate's side), so a layer that takes another
//!   bead where the groove widens keeps its first beads running on and
//!   starts the new bead there;
//! - a cap pass is its bead of the top layer, whichever layer that is at
//!   each station, so the cap runs on where a deeper groove puts one more
//!   fill layer under it.
//!
//! A pass is welded over each run of consecutive waypoints where it
//! exists: it begins where the groove first needs it and ends where it
//! stops needing it, as a welder adds a bead where a groove grows. A cut
//! stretch ([`super::seam_process::CutStretch`]) has no pass at all, so it
//! splits every pass into the pieces on either side. A run of a single
//! waypoint is no weld (there is nothing to travel), so it is not a
//! piece; it is counted in [`SeamPasses::lone_points`], and the stations
//! beside it weld the joint with their own passes.

use nalgebra::{Unit, UnitQuaternion};

use crate::geometry::Vec3;
use crate::process::weave::Weave;
use crate::process::{ArcSettings, Pass, PassKind};

use super::Seam;
use super::seam_process::WaypointProcess;
use super::trajectory::{Waypoint, torch_orientation};

/// Which pass of a seam a station's pass is, followed along the seam.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PassId {
    /// The root pass, or a joint's single pass: the seam's own line.
    Root,
    /// Fill layer `layer` (1 the first above the root), bead `bead` from
    /// the first plate's side.
    Fill { layer: usize, bead: usize },
    /// Bead `bead` of the cap, the top layer.
    Cap { bead: usize },
}

impl PassId {
    /// The pass a station's `pass` is.
    pub fn of(pass: &Pass) -> PassId {
        match pass.kind {
            PassKind::Root | PassKind::Single => PassId::Root,
            PassKind::Fill => PassId::Fill { layer: pass.layer, bead: pass.bead },
            PassKind::Cap => PassId::Cap { bead: pass.bead },
        }
    }
}

/// One point of a pass: where the torch goes and how it welds there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassPoint {
    /// The seam's waypoint it stands at (index into the seam's waypoints).
    pub waypoint: usize,
    /// The torch's pose, base frame.
    pub pose: Waypoint,
    /// The arc's settings of the pass here (travel speed, wire feed,
    /// voltage, current).
    pub settings: ArcSettings,
    /// The torch's swing across the seam here, if the pass weaves.
    pub weave: Option<Weave>,
}

impl PassPoint {
    /// The travel speed, mm/s.
    pub fn travel_speed_mm_s(&self) -> f64 {
        self.settings.travel_speed_mm_s
    }

    /// The weave's half-swing in mm and frequency in Hz at the travel
    /// speed, both 0 where the pass does not weave.
    pub fn weave_amplitude_frequency(&self) -> (f64, f64) {
        self.weave.map_or((0.0, 0.0), |w| (w.amplitude_mm, w.frequency_hz(self.settings.travel_speed_mm_s)))
    }
}

/// A stretch of one pass welded with the arc on, in travel order.
#[derive(Debug, Clone, PartialEq)]
pub struct PassPiece {
    pub pass: PassId,
    pub points: Vec<PassPoint>,
}

/// Every piece of every pass of a seam, in the order they are welded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeamPasses {
    /// Root first, then the fill layers from the root up (each layer's
    /// beads from the first plate's side), then the cap's beads; a pass's
    /// pieces in travel order.
    pub pieces: Vec<PassPiece>,
    /// Stations where a pass exists at that waypoint alone, (pass,
    /// waypoint): no piece welds them.
    pub lone_points: Vec<(PassId, usize)>,
}

/// The passes the robot welds for `seam`, or `None` where the seam has
/// no process (no procedure configured; [`seam_pieces`] says what a link
/// sends then).
pub fn pass_trajectories(seam: &Seam) -> Option<SeamPasses> {
    let process = seam.process.as_ref()?;
    let rotation = process.base_from_camera.rotation;
    // Each station's passes, as points, by pass.
    let mut by_pass: std::collections::BTreeMap<PassId, Vec<PassPoint>> = Default::default();
    for (k, (w, p)) in seam.waypoints.iter().zip(&process.waypoints).enumerate() {
        let Some(p) = p else { continue };
        for pass in &p.layout.passes {
            let pose = pass_pose(w, p, pass, &rotation);
            let point = PassPoint { waypoint: k, pose, settings: pass.settings, weave: pass.weave };
            by_pass.entry(PassId::of(pass)).or_default().push(point);
        }
    }
    let mut passes = SeamPasses::default();
    for (id, points) in by_pass {
        // Runs of consecutive waypoints: a gap (a cut, or a station
        // without this pass) ends a piece.
        let mut runs: Vec<Vec<PassPoint>> = Vec::new();
        for point in points {
            match runs.last_mut() {
                Some(run) if run.last().is_some_and(|last| last.waypoint + 1 == point.waypoint) => run.push(point),
                _ => runs.push(vec![point]),
            }
        }
        for run in runs {
            match run.as_slice() {
                [lone] => passes.lone_points.push((id, lone.waypoint)),
                _ => passes.pieces.push(PassPiece { pass: id, points: run }),
            }
        }
    }
    Some(passes)
}

/// The torch's pose for `pass` at waypoint `w` with its process `p`.
fn pass_pose(w: &Waypoint, p: &WaypointProcess, pass: &Pass, base_from_camera: &UnitQuaternion<f64>) -> Waypoint {
    if PassId::of(pass) == PassId::Root {
        // The traced pass: the waypoint itself, aimed and cleared.
        return *w;
    }
    let station = &p.station;
    let along = station.along.normalize();
    let up = station.bisector.normalize();
    let across = Unit::new_normalize(along.cross(&up)).into_inner();
    let offset: Vec3 = across * pass.lateral_mm + up * pass.height_mm;
    // The lean every pass needed to clear, read off the root's angle.
    let traced = p.layout.passes.iter().find(|q| PassId::of(q) == PassId::Root).map_or(0.0, |q| q.work_angle_deg);
    let lean = p.work_angle_deg - traced;
    let axis = station.axis(pass.work_angle_deg + lean, p.travel_angle_deg);
    Waypoint {
        position: w.position + base_from_camera * offset,
        orientation: torch_orientation(&(base_from_camera * station.along), &(base_from_camera * -axis), 0.0, 0.0),
    }
}

/// How the torch travels into one point of a welded piece: what a robot
/// link sends beside the pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    pub travel_speed_mm_s: f64,
    /// The weave's half-swing, mm, and its frequency, Hz; 0 and 0 where
    /// the pass does not weave.
    pub weave_amplitude_mm: f64,
    pub weave_frequency_hz: f64,
}

/// What a robot link sends for a seam: the pieces the robot welds, each
/// its points with how the torch travels into them; where the seam has no
/// process (no procedure configured), one piece of its waypoints with no
/// motion, as planned.
pub fn seam_pieces(seam: &Seam) -> Vec<Vec<(Waypoint, Option<Motion>)>> {
    let Some(passes) = pass_trajectories(seam) else {
        return vec![seam.waypoints.iter().map(|w| (*w, None)).collect()];
    };
    passes.pieces.iter().map(|piece| piece.points.iter().map(|p| (p.pose, Some(motion(p)))).collect()).collect()
}

/// The motion of the move into a pass point: its travel speed and weave.
pub fn motion(p: &PassPoint) -> Motion {
    let (weave_amplitude_mm, weave_frequency_hz) = p.weave_amplitude_frequency();
    Motion { travel_speed_mm_s: p.travel_speed_mm_s(), weave_amplitude_mm, weave_frequency_hz }
}

#[cfg(test)]
#[path = "passes_tests.rs"]
mod tests;
