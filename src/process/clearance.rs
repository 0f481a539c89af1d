//! Torch clearance: the torch, as a solid, placed at each station of a
//! pass and checked against the measured cloud.
//!
//! The torch is modelled along its axis from the aim point: nothing up to
//! the nozzle's end (`nozzle_to_work_mm`: the arc, the wire's stick-out),
//! then the nozzle, a cylinder of `nozzle_diameter_mm` and
//! `nozzle_length_mm`, then the torch's neck and body, a cone widening
//! from the nozzle's radius at `body_half_angle_deg` over `body_length_mm`
//! (0 degrees: a cylinder). A cloud point inside that solid, grown by
//! `margin_mm` for the cloud's noise and the robot's path error, is a
//! contact.
//!
//! Where the procedure's angles touch, the work and travel angles are
//! moved within the limits the procedure allows, nearest first; where no
//! angle clears, the station is unweldable and the contact is reported.
//! The measure is the cloud itself: a clamp, a high plate or a tee's web
//! blocks the torch only where its points are.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Rotation3, Unit, Vector3};

use crate::config::procedure::Torch;

type Vec3 = Vector3<f64>;

/// The measured cloud, indexed for the torch's solid.
pub struct Obstacles {
    tree: ImmutableKdTree<f32, 3>,
    points: Vec<[f32; 3]>,
}

impl Obstacles {
    /// Indexes the finite points of a cloud, mm, in the frame the stations
    /// are given in.
    pub fn new(points: impl IntoIterator<Item = Vec3>) -> Obstacles {
        let points: Vec<[f32; 3]> = points
            .into_iter()
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect();
        // Only an empty slice fails to build; a far point answers every
        // query with nothing.
        let tree = ImmutableKdTree::new_from_slice(&points)
            .unwrap_or_else(|_| ImmutableKdTree::new_from_slice(&[[f32::MAX; 3]]).expect("one point builds"));
        Obstacles { tree, points }
    }

    fn near(&self, centre: &Vec3, radius: f64) -> impl Iterator<Item = Vec3> + '_ {
        let q = [centre.x as f32, centre.y as f32, centre.z as f32];
        let reach = (radius * radius) as f32;
        self.tree
            .query(&q)
            .within::<SquaredEuclidean<f32>>(reach)
            .unsorted()
            .execute()
            .into_iter()
            .filter_map(|n| self.points.get(n.item as usize))
            .map(|p| Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
    }
}

/// Where along a pass the torch stands, and the joint's own directions
/// there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Station {
    /// The aim point, mm.
    pub point: Vec3,
    /// Along the seam, in the direction of travel (unit).
    pub along: Vec3,
    /// The joint's bisector, out of the joint towards the torch (unit,
    /// across `along`): the torch's axis at zero work and travel angle.
    pub bisector: Vec3,
}

impl Station {
    /// The torch's axis (from the aim point towards the torch) at a work
    /// angle (a tilt about the seam, positive towards `along × bisector`)
    /// and a travel angle (a push: the torch leans back against the
    /// direction of travel).
    pub fn axis(&self, work_angle_deg: f64, travel_angle_deg: f64) -> Vec3 {
        let along = Unit::new_normalize(self.along);
        let across = Unit::new_normalize(self.along.cross(&self.bisector));
        let worked = Rotation3::from_axis_angle(&along, -work_angle_deg.to_radians()) * self.bisector;
        Rotation3::from_axis_angle(&across, -travel_angle_deg.to_radians()) * worked
    }
}

/// The torch's radius, grown by its margin, `s` mm up its axis from the
/// aim point, or `None` below the nozzle's end and beyond the body.
fn radius_at(torch: &Torch, s: f64) -> Option<f64> {
    let nozzle_end = torch.nozzle_to_work_mm;
    let body_start = nozzle_end + torch.nozzle_length_mm;
    let nozzle = torch.nozzle_diameter_mm / 2.0;
    let r = if s < nozzle_end {
        return None;
    } else if s <= body_start {
        nozzle
    } else if s <= body_start + torch.body_length_mm {
        nozzle + (s - body_start) * torch.body_half_angle_deg.to_radians().tan()
    } else {
        return None;
    };
    Some(r + torch.margin_mm)
}

/// The fewest cloud points inside the torch that make a contact: a
/// surface the torch could touch returns many points at the cloud's
/// spacing, while a structured-light camera's sparse outliers (about one
/// pixel in ten thousand, tens of millimetres off any surface) put a lone
/// point in the air, which is no matter to avoid.
pub const MIN_CONTACT_POINTS: usize = 3;

/// The cloud point inside the torch standing at `point` along `axis`
/// nearest the aim point, when at least [`MIN_CONTACT_POINTS`] are inside.
pub fn contact(torch: &Torch, obstacles: &Obstacles, point: &Vec3, axis: &Vec3) -> Option<Vec3> {
    let axis = axis.normalize();
    let start = torch.nozzle_to_work_mm;
    let end = start + torch.nozzle_length_mm + torch.body_length_mm;
    // Spheres along the axis, each covering a piece of the solid as long
    // as the nozzle is wide: fine enough that the spheres stay near the
    // solid, coarse enough to be few.
    let piece = (torch.nozzle_diameter_mm / 2.0).max(1.0);
    let mut s0 = start;
    let mut first: Option<(f64, Vec3)> = None;
    let mut inside_count = 0;
    // Piece by piece up the axis, each piece's points all counted (a
    // point on a boundary in the piece below it only), until enough are
    // inside: the nearest of them is then the nearest of all.
    while s0 < end && inside_count < MIN_CONTACT_POINTS {
        let s1 = (s0 + piece).min(end);
        let last_piece = s1 >= end;
        let widest = radius_at(torch, s1).or(radius_at(torch, s0)).unwrap_or(0.0);
        let centre = point + axis * ((s0 + s1) / 2.0);
        let reach = (widest * widest + ((s1 - s0) / 2.0).powi(2)).sqrt();
        for q in obstacles.near(&centre, reach) {
            let d = q - point;
            let s = d.dot(&axis);
            if s < s0 || s > s1 || (s == s1 && !last_piece) {
                continue;
            }
            let inside = radius_at(torch, s).is_some_and(|r| (d - axis * s).norm_squared() < r * r);
            if inside {
                inside_count += 1;
                if first.is_none_or(|(best, _)| s < best) {
                    first = Some((s, q));
                }
            }
        }
        s0 = s1;
    }
    first.filter(|_| inside_count >= MIN_CONTACT_POINTS).map(|(_, q)| q)
}

/// The torch angles at a station: the procedure's, or the nearest within
/// its limits that clear the cloud.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Clearance {
    /// The angles clear, `moved` when they are not the procedure's.
    Clear { work_angle_deg: f64, travel_angle_deg: f64, moved: bool },
    /// No angle within the limits clears; the contact at the procedure's.
    Blocked { contact: Vec3 },
}

/// The step of the search for angles that clear, degrees: finer than a
/// robot's teach resolution matters for clearance, coarse enough that a
/// blocked station costs a few hundred checks at most.
pub const ANGLE_SEARCH_STEP_DEG: f64 = 2.5;

/// The torch's angles at one station.
pub fn clear_station(
    torch: &Torch,
    obstacles: &Obstacles,
    station: &Station,
    work_angle_deg: f64,
    travel_angle_deg: f64,
) -> Clearance {
    let Some(blocked_at) = contact(torch, obstacles, &station.point, &station.axis(work_angle_deg, travel_angle_deg))
    else {
        return Clearance::Clear { work_angle_deg, travel_angle_deg, moved: false };
    };
    // Candidates within the torch's limits, nearest the procedure's
    // angles first.
    let step = ANGLE_SEARCH_STEP_DEG;
    let [travel_min, travel_max] = torch.travel_angle_range_deg;
    let steps = |span: f64| (span / step).floor() as i64;
    let mut candidates = Vec::new();
    for i in -steps(torch.work_deviation_deg)..=steps(torch.work_deviation_deg) {
        for j in -steps(travel_max - travel_min)..=steps(travel_max - travel_min) {
            let travel = travel_angle_deg + j as f64 * step;
            if (i, j) != (0, 0) && (travel_min..=travel_max).contains(&travel) {
                candidates.push((work_angle_deg + i as f64 * step, travel));
            }
        }
    }
    candidates.sort_by(|a, b| {
        let off = |c: &(f64, f64)| (c.0 - work_angle_deg).abs() + (c.1 - travel_angle_deg).abs();
        off(a).total_cmp(&off(b))
    });
    candidates
        .into_iter()
        .find(|&(w, t)| contact(torch, obstacles, &station.point, &station.axis(w, t)).is_none())
        .map(|(w, t)| Clearance::Clear { work_angle_deg: w, travel_angle_deg: t, moved: true })
        .unwrap_or(Clearance::Blocked { contact: blocked_at })
}

/// The stretches of a pass, in station indices `[first, last]`, where no
/// angle clears: each is cut from the pass and reported.
pub fn blocked_stretches(clearances: &[Clearance]) -> Vec<[usize; 2]> {
    let mut out: Vec<[usize; 2]> = Vec::new();
    for (k, c) in clearances.iter().enumerate() {
        if matches!(c, Clearance::Blocked { .. }) {
            match out.last_mut() {
                Some(last) if last[1] + 1 == k => last[1] = k,
                _ => out.push([k, k]),
            }
        }
    }
    out
}

#[cfg(test)]
#[path = "clearance_tests.rs"]
mod tests;
