//! Torch clearance: the torch, as a solid, placed at each station of a
//! pass and checked against the measured cloud.
//!
//! The torch is modelled along its axis from the aim point: nothing up to
//! the nozzle's end (`nozzle_to_work_mm`: the arc, the wire's stick-out),
//! or where the contact tip is extended past the nozzle, up to the tip's
//! end (`contact_tip_to_work_mm`) and the tip, a cylinder of
//! `contact_tip_diameter_mm`, on to the nozzle's end;
//! then the nozzle, a cylinder of `nozzle_diameter_mm` and
//! `nozzle_length_mm`, then the torch's neck and body, a cone widening
//! from the nozzle's radius at `body_half_angle_deg` over `body_length_mm`
//! (0 degrees: a cylinder). A cloud point inside that solid, grown by
//! `margin_mm` for the cloud's noise and the robot's path error, is a
//! contact.
//!
//! Every pass at a station is checked, each aimed where the layout puts
//! it: a cap's torch stands higher and farther across than the root's,
//! and may meet a clamp the root's clears. Where the procedure's angles
//! touch, the work and travel angles are moved within the limits the
//! procedure allows, nearest first, by the same lean for every pass (so
//! the torch keeps the side it cleared on); where no angle clears, the
//! station is unweldable and the contact is reported with its pass.
//!
//! The measure is the cloud, and what the cloud cannot show: a clamp, a
//! high plate or a tee's web blocks the torch where its points are, and
//! where the camera saw a surface the space behind it is taken as solid
//! ([`super::shadow`]), so a torch never passes through a block's faces
//! the camera did not see.

use std::cmp::Ordering;
use std::sync::{Arc, PoisonError, RwLock};

use nalgebra::{Rotation3, Unit, Vector3};
use rayon::prelude::*;

use super::blocks::BlockIndex;
use super::rays::RayIndex;
use super::shadow::{LazyShadows, Shadows};
use crate::config::procedure::Torch;

type Vec3 = Vector3<f64>;

/// The measured cloud, indexed for the torch's solid, and where it was
/// seen from, the space behind its surfaces.
pub struct Obstacles<'a> {
    index: Index<'a>,
    /// The cloud's angular spacing where it is a camera's view (0 for
    /// bare points): how far a seen surface may reach beyond its points
    /// grows with it ([`EDGE_SPACINGS`]).
    spacing_per_mm: f64,
    hidden: Option<HiddenSpace<'a>>,
}

/// How the cloud's points are found round a ball.
enum Index<'a> {
    /// Every point binned by its ray: any cloud, and the reference the
    /// organized frame's index is tested against.
    Rays(RayIndex),
    /// An organized frame by blocks of its pixels: nothing binned.
    Blocks(Arc<BlockIndex<'a>>),
}

impl Index<'_> {
    /// Visits the points within `radius` of `centre`, and possibly some
    /// beyond; an index by blocks passes over the boxes of points `keep`
    /// rejects ([`BlockIndex::near_where`]).
    fn near(
        &self,
        centre: &Vec3,
        radius: f64,
        keep: impl Fn(&[f32; 3], &[f32; 3]) -> bool,
        visit: impl FnMut(&[f32; 3]),
    ) {
        match self {
            Index::Rays(index) => index.near(centre, radius, visit),
            Index::Blocks(index) => index.near_where(centre, radius, keep, visit),
        }
    }

    fn nearest_apart(&self, p: &[f32; 3]) -> (Option<f64>, usize) {
        match self {
            Index::Rays(index) => index.nearest_apart(p),
            Index::Blocks(index) => index.nearest_apart(p),
        }
    }
}

/// The space behind the seen surfaces, over the whole frame or laid tile
/// by tile where the torch asks.
enum Hidden<'a> {
    Grid(Shadows),
    Lazy(LazyShadows<'a>),
}

impl Hidden<'_> {
    /// Whether no point within `radius` of `centre` is hidden, known
    /// without asking point by point: `false` where some may be, and
    /// always over the whole frame's grid, which is asked point by point.
    fn clears_ball(&self, centre: &Vec3, radius: f64) -> bool {
        match self {
            Hidden::Grid(_) => false,
            Hidden::Lazy(shadows) => shadows.clears_ball(centre, radius),
        }
    }

    /// Whether each of `points` in turn is behind a seen surface, handed
    /// to `visit` with its index until it returns `false`: over an organized frame,
    /// a run of points placed before any is looked up
    /// ([`LazyShadows::hides_each`]).
    fn hides_each(&self, points: &[Vec3], mut visit: impl FnMut(usize, bool) -> bool) {
        match self {
            Hidden::Grid(shadows) => {
                for (k, p) in points.iter().enumerate() {
                    if !visit(k, shadows.hides(p)) {
                        return;
                    }
                }
            }
            Hidden::Lazy(shadows) => shadows.hides_each(points, visit),
        }
    }
}

/// How far a surface may reach beyond the points a camera saw on it, in
/// the cloud's own spacing at the point's range: one spacing for the
/// sampling (a face's edge lies anywhere up to the next ray, which missed
/// it) and one for the pixel a depth edge blends away (its return is
/// mixed with what lies behind and leaves the face). The torch keeps its
/// margin from where the surface may be, so a torch that clips a block's
/// edge between the last seen points is a contact.
pub const EDGE_SPACINGS: f64 = 2.0;

/// The space the camera could not see, with the surface of each torch
/// checked against it sampled once: the torch it was indexed for, and
/// any other (a procedure entry's own) the first time it is asked about.
struct HiddenSpace<'a> {
    shadows: Hidden<'a>,
    surfaces: RwLock<Vec<(Torch, Arc<Surface>)>>,
}

impl<'a> HiddenSpace<'a> {
    fn new(shadows: Hidden<'a>, torch: &Torch) -> HiddenSpace<'a> {
        let surface = Surface::of(torch).into();
        HiddenSpace { shadows, surfaces: RwLock::new(vec![(*torch, surface)]) }
    }

    /// The torch's surface samples, nearest the aim point first.
    fn surface(&self, torch: &Torch) -> Arc<Surface> {
        let found =
            |surfaces: &[(Torch, Arc<Surface>)]| surfaces.iter().find(|(t, _)| t == torch).map(|(_, s)| Arc::clone(s));
        if let Some(surface) = found(&self.surfaces.read().unwrap_or_else(PoisonError::into_inner)) {
            return surface;
        }
        let mut surfaces = self.surfaces.write().unwrap_or_else(PoisonError::into_inner);
        found(&surfaces).unwrap_or_else(|| {
            let surface: Arc<Surface> = Surface::of(torch).into();
            surfaces.push((*torch, Arc::clone(&surface)));
            surface
        })
    }
}

/// The points the cloud's angular spacing is estimated on, evenly spread
/// over it, and the fewest it is estimated from.
const SPACING_SAMPLE_POINTS: usize = 2048;
const MIN_SPACING_SAMPLES: usize = 64;

/// The most copies of a sampled point (a voxel grid's or a merged frame's
/// repeats) passed over for the nearest other one; a point repeated more
/// often is no sample of the spacing.
const MAX_REPEATS: usize = 3;

/// The step the torch's surface is sampled with against the hidden
/// space, mm: no coarser than the torch's margin, so a hidden solid the
/// grown torch overlaps by a margin's depth is met.
pub const SURFACE_SAMPLE_STEP_MM: f64 = 2.0;

/// A point of the torch's surface in its own frame: `s` mm up the axis
/// from the aim point and `(a, b)` across it.
#[derive(Debug, Clone, Copy)]
struct SurfaceSample {
    s: f64,
    a: f64,
    b: f64,
}

/// The length of the torch's axis whose surface samples are ruled out
/// against the hidden space together, by one ball, mm: a few sample
/// steps, so a stretch of torch in the air costs one bound rather than a
/// question per sample, while the stretch nearest the workpiece, asked
/// sample by sample, stays short. Speed only: a sample is ruled out only
/// where it cannot be hidden.
const SURFACE_PIECE_MM: f64 = 8.0;

/// How many of a piece's surface samples are placed on the torch and
/// handed to the hidden space together: a few dozen, on the stack. Speed
/// only: they are asked about in order, and the asking stops where the
/// contact is made.
const SURFACE_RUN_SAMPLES: usize = 32;

/// A torch's surface samples, nearest the aim point first, and the
/// pieces they are ruled out by: each a run of samples, the point of the
/// axis `s` mm up it, and the radius round it that holds them all.
struct Surface {
    samples: Vec<SurfaceSample>,
    pieces: Vec<(std::ops::Range<usize>, f64, f64)>,
}

impl Surface {
    fn of(torch: &Torch) -> Surface {
        let samples = surface_samples(torch, SURFACE_SAMPLE_STEP_MM);
        let mut pieces = Vec::new();
        let mut first = 0;
        while first < samples.len() {
            let s0 = samples[first].s;
            let end = first + samples[first..].iter().take_while(|q| q.s - s0 <= SURFACE_PIECE_MM).count();
            let piece = &samples[first..end];
            let mid = (s0 + piece[piece.len() - 1].s) / 2.0;
            let radius = piece.iter().map(|q| ((q.s - mid).powi(2) + q.a * q.a + q.b * q.b).sqrt()).fold(0.0, f64::max);
            // Grown against the rounding of a sample's place, far below a
            // sample's step.
            pieces.push((first..end, mid, radius * (1.0 + 1e-9) + 1e-6));
            first = end;
        }
        Surface { samples, pieces }
    }
}

impl<'a> Obstacles<'a> {
    /// Indexes the finite points of a cloud, mm, in the frame the stations
    /// are given in; only the points are obstacles.
    pub fn new(points: impl IntoIterator<Item = Vec3>) -> Obstacles<'static> {
        Obstacles::of_points(&finite(points))
    }

    fn of_points(points: &[[f32; 3]]) -> Obstacles<'static> {
        Obstacles { index: Index::Rays(RayIndex::new(points)), spacing_per_mm: 0.0, hidden: None }
    }

    /// Indexes the finite points of a camera-frame cloud (the camera at
    /// the origin, looking along `+z`), mm, for `torch`: the points are
    /// obstacles, and so is the space behind every surface the camera
    /// saw.
    pub fn seen_from_camera(points: impl IntoIterator<Item = Vec3>, torch: &Torch) -> Obstacles<'static> {
        Obstacles::seen_in_frame(&finite(points), torch)
    }

    /// [`Obstacles::seen_from_camera`] for a frame's points as it holds
    /// them: single precision, an empty pixel's not finite (left out).
    pub fn seen_in_frame(points: &[[f32; 3]], torch: &Torch) -> Obstacles<'static> {
        let mut obstacles = Obstacles::of_points(points);
        let Index::Rays(index) = &obstacles.index else { unreachable!("indexed by rays") };
        let shadows = obstacles.angular_spacing(points).and_then(|spacing| Shadows::new(index.binned(), spacing));
        obstacles.spacing_per_mm = shadows.as_ref().map_or(0.0, Shadows::spacing);
        obstacles.hidden = shadows.map(|shadows| HiddenSpace::new(Hidden::Grid(shadows), torch));
        obstacles
    }

    /// [`Obstacles::seen_in_frame`] for an organized frame of `width`
    /// pixels a row, indexed by its own blocks of pixels, with the hidden
    /// space laid where the torch asks: the same answers to every
    /// question, at the cost of the rays the torch reaches rather than
    /// the frame's.
    pub fn seen_in_organized_frame(points: &'a [[f32; 3]], width: usize, torch: &Torch) -> Obstacles<'a> {
        let blocks = Arc::new(BlockIndex::new(points, width));
        let mut obstacles = Obstacles { index: Index::Blocks(Arc::clone(&blocks)), spacing_per_mm: 0.0, hidden: None };
        let shadows = obstacles.angular_spacing(points).and_then(|spacing| LazyShadows::new(blocks, spacing));
        obstacles.spacing_per_mm = shadows.as_ref().map_or(0.0, LazyShadows::spacing);
        obstacles.hidden = shadows.map(|shadows| HiddenSpace::new(Hidden::Lazy(shadows), torch));
        obstacles
    }

    /// The same points with nothing taken as hidden and no surface
    /// reaching past them: what the cloud itself touches.
    pub fn seen_only(mut self) -> Obstacles<'a> {
        self.hidden = None;
        self.spacing_per_mm = 0.0;
        self
    }

    /// The cloud's median angular spacing, in `(x / z, y / z)`, from the
    /// camera at the origin: for points sampled evenly over it, the
    /// distance to the nearest other point over the point's range (a
    /// camera's neighbouring rays meet a surface that far apart), or
    /// `None` with too few points in front of the camera.
    fn angular_spacing(&self, points: &[[f32; 3]]) -> Option<f64> {
        let stride = (points.len() / SPACING_SAMPLE_POINTS).max(1);
        let samples: Vec<&[f32; 3]> =
            points.iter().step_by(stride).filter(|p| p[2] > 0.0 && p.iter().all(|c| c.is_finite())).collect();
        // Each sample's query stands alone, and the median does not
        // depend on the order the gaps are gathered in.
        let mut gaps: Vec<f64> = samples
            .into_par_iter()
            .filter_map(|p| {
                let (gap, repeats) = self.index.nearest_apart(p);
                // The point itself is one of its repeats.
                let gap = gap.filter(|_| repeats <= MAX_REPEATS + 1)?;
                let range = p.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt();
                Some(gap / range)
            })
            .collect();
        if gaps.len() < MIN_SPACING_SAMPLES {
            return None;
        }
        let mid = gaps.len() / 2;
        let (_, median, _) = gaps.select_nth_unstable_by(mid, f64::total_cmp);
        Some(*median)
    }

    /// Whether the space behind the seen surfaces is an obstacle too.
    pub fn takes_hidden_space(&self) -> bool {
        self.hidden.is_some()
    }

    /// Visits the points within `radius` of `centre` whose distance up
    /// `axis` (unit) from `from` lies within `[s0, s1]`, and possibly
    /// some others.
    fn near_in_stretch(
        &self,
        centre: &Vec3,
        radius: f64,
        (from, axis, s0, s1): (&Vec3, &Vec3, f64, f64),
        mut visit: impl FnMut(Vec3),
    ) {
        // The distances up the axis a box's points may have lie within
        // its centre's, give or take its half-extents along the axis.
        let keep = |min: &[f32; 3], max: &[f32; 3]| {
            let (mut mid, mut half) = (0.0, 0.0);
            for k in 0..3 {
                let (lo, hi) = (f64::from(min[k]) - from[k], f64::from(max[k]) - from[k]);
                mid += (lo + hi) / 2.0 * axis[k];
                half += (hi - lo) / 2.0 * axis[k].abs();
            }
            mid + half >= s0 - STRETCH_SLACK_MM && mid - half <= s1 + STRETCH_SLACK_MM
        };
        self.index.near(centre, radius, keep, |p| visit(Vec3::new(p[0].into(), p[1].into(), p[2].into())));
    }
}

/// The finite points, in single precision.
fn finite(points: impl IntoIterator<Item = Vec3>) -> Vec<[f32; 3]> {
    points
        .into_iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect()
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
/// aim point, or `None` below the solid's start (the nozzle's end, or an
/// extended contact tip's) and beyond the body.
fn radius_at(torch: &Torch, s: f64) -> Option<f64> {
    let nozzle_end = torch.nozzle_to_work_mm;
    let body_start = nozzle_end + torch.nozzle_length_mm;
    let nozzle = torch.nozzle_diameter_mm / 2.0;
    let r = if s < nozzle_end {
        match torch.extended_tip() {
            Some((_, tip_diameter)) if s >= torch.contact_tip_to_work_mm => tip_diameter / 2.0,
            _ => return None,
        }
    } else if s <= body_start {
        nozzle
    } else if s <= body_start + torch.body_length_mm {
        nozzle + (s - body_start) * torch.body_half_angle_deg.to_radians().tan()
    } else {
        return None;
    };
    Some(r + torch.margin_mm)
}

/// How far a box of points is kept beyond a piece of the torch's stretch
/// of axis, mm, against the rounding of the distances up the axis: far
/// above a double's error over metres, far below a point's spacing.
const STRETCH_SLACK_MM: f64 = 1e-3;

/// The fewest cloud points inside the torch that make a contact: a
/// surface the torch could touch returns many points at the cloud's
/// spacing, while a structured-light camera's sparse outliers (about one
/// pixel in ten thousand, tens of millimetres off any surface) put a lone
/// point in the air, which is no matter to avoid.
pub const MIN_CONTACT_POINTS: usize = 3;

/// Where the torch meets something.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Contact {
    /// A cloud point inside the torch.
    Seen(Vec3),
    /// A point of the torch's surface behind a surface the camera saw.
    Hidden(Vec3),
}

impl Contact {
    pub fn point(&self) -> Vec3 {
        match self {
            Contact::Seen(p) | Contact::Hidden(p) => *p,
        }
    }
}

/// Where the torch standing at `point` along `axis` meets the obstacles,
/// if it does: the cloud point inside it nearest the aim point, when at
/// least [`MIN_CONTACT_POINTS`] are inside; else, where the obstacles
/// take the hidden space, the point of its surface nearest the aim point
/// behind a seen surface, when at least as many are.
pub fn contact(torch: &Torch, obstacles: &Obstacles, point: &Vec3, axis: &Vec3) -> Option<Contact> {
    seen_contact(torch, obstacles, point, axis)
        .map(Contact::Seen)
        .or_else(|| hidden_contact(torch, obstacles, point, axis).map(Contact::Hidden))
}

/// The torch's surface behind a seen surface, nearest the aim point
/// first.
fn hidden_contact(torch: &Torch, obstacles: &Obstacles, point: &Vec3, axis: &Vec3) -> Option<Vec3> {
    let hidden = obstacles.hidden.as_ref()?;
    let surface = hidden.surface(torch);
    let axis = axis.normalize();
    let e1 = axis.cross(&if axis.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() }).normalize();
    let e2 = axis.cross(&e1);
    let mut first = None;
    let mut behind = 0;
    for (samples, mid, radius) in &surface.pieces {
        // A piece none of whose samples can be hidden adds nothing.
        if hidden.shadows.clears_ball(&(point + axis * *mid), *radius) {
            continue;
        }
        // The samples a run at a time, each run placed on the torch
        // before the hidden space is asked about any of it.
        for run in surface.samples[samples.clone()].chunks(SURFACE_RUN_SAMPLES) {
            let mut at = [Vec3::zeros(); SURFACE_RUN_SAMPLES];
            for (p, q) in at.iter_mut().zip(run) {
                *p = point + axis * q.s + e1 * q.a + e2 * q.b;
            }
            let at = &at[..run.len()];
            hidden.shadows.hides_each(at, |k, hides| {
                if hides {
                    first.get_or_insert(at[k]);
                    behind += 1;
                }
                behind < MIN_CONTACT_POINTS
            });
            if behind >= MIN_CONTACT_POINTS {
                return first;
            }
        }
    }
    None
}

/// The torch's surface (its side, and the nozzle's and the body's end
/// faces), grown by its margin, sampled every `step` mm, nearest the aim
/// point first.
fn surface_samples(torch: &Torch, step: f64) -> Vec<SurfaceSample> {
    let start = torch.solid_start_mm();
    let end = torch.solid_end_mm();
    let mut out = Vec::new();
    let mut ring = |s: f64, r: f64| {
        let n = ((std::f64::consts::TAU * r / step).ceil() as usize).max(1);
        for k in 0..n {
            let angle = std::f64::consts::TAU * k as f64 / n as f64;
            out.push(SurfaceSample { s, a: r * angle.cos(), b: r * angle.sin() });
        }
    };
    let rings = ((end - start) / step).ceil().max(1.0) as usize;
    for k in 0..=rings {
        let s = start + (end - start) * k as f64 / rings as f64;
        if let Some(r) = radius_at(torch, s) {
            ring(s, r);
        }
    }
    // The end faces: the solid's start and end, and where an extended tip
    // leaves it, the nozzle's end round the tip.
    let nozzle_end = torch.extended_tip().map(|_| torch.nozzle_to_work_mm);
    for s in [Some(start), nozzle_end, Some(end)].into_iter().flatten() {
        if let Some(r) = radius_at(torch, s) {
            let discs = (r / step).floor() as usize;
            (0..discs).for_each(|k| ring(s, k as f64 * step));
        }
    }
    out.sort_by(|x, y| x.s.total_cmp(&y.s));
    out
}

/// The cloud point inside the torch nearest the aim point, when at least
/// [`MIN_CONTACT_POINTS`] are inside; the torch grown, for each point, by
/// how far its surface may reach past it ([`EDGE_SPACINGS`]).
fn seen_contact(torch: &Torch, obstacles: &Obstacles, point: &Vec3, axis: &Vec3) -> Option<Vec3> {
    let axis = axis.normalize();
    let edge_per_mm = EDGE_SPACINGS * obstacles.spacing_per_mm;
    let start = torch.solid_start_mm();
    let end = torch.solid_end_mm();
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
        // The farthest a point the grown piece holds can be from the
        // camera bounds its growth.
        let reach = reach + edge_per_mm * (centre.norm() + 2.0 * reach);
        obstacles.near_in_stretch(&centre, reach, (point, &axis, s0, s1), |q| {
            let d = q - point;
            let s = d.dot(&axis);
            if s < s0 || s > s1 || (s == s1 && !last_piece) {
                return;
            }
            let inside = radius_at(torch, s)
                .map(|r| r + edge_per_mm * q.norm())
                .is_some_and(|r| (d - axis * s).norm_squared() < r * r);
            if inside {
                inside_count += 1;
                // Nearest the aim point, and of points as near, the least
                // by their coordinates: the same point whatever order an
                // index reads them in.
                let before = |(best, at): (f64, Vec3)| {
                    s.total_cmp(&best)
                        .then_with(|| q.iter().zip(&at).fold(Ordering::Equal, |o, (a, b)| o.then(a.total_cmp(b))))
                        == Ordering::Less
                };
                if first.is_none_or(before) {
                    first = Some((s, q));
                }
            }
        });
        s0 = s1;
    }
    first.filter(|_| inside_count >= MIN_CONTACT_POINTS).map(|(_, q)| q)
}

/// One pass's torch at a station: its aim point, across the seam and up
/// out of the joint from the station's point (the frame
/// [`Station::axis`] tilts in), and its work angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aim {
    pub across_mm: f64,
    pub up_mm: f64,
    pub work_angle_deg: f64,
}

impl Aim {
    /// The torch aimed at the station's point itself.
    pub fn at_point(work_angle_deg: f64) -> Aim {
        Aim { across_mm: 0.0, up_mm: 0.0, work_angle_deg }
    }

    /// The aim point, in the station's frame.
    pub fn point(&self, station: &Station) -> Vec3 {
        let across = station.along.cross(&station.bisector).normalize();
        station.point + across * self.across_mm + station.bisector.normalize() * self.up_mm
    }
}

/// The torch angles at a station: the procedure's, or the nearest within
/// its limits that clear every pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Clearance {
    /// Every pass clears leaning `lean_deg` from its own work angle at
    /// `travel_angle_deg`; `moved` when these are not the procedure's.
    Clear { lean_deg: f64, travel_angle_deg: f64, moved: bool },
    /// No angle within the limits clears; the first pass (its index in
    /// the aims) that touched at the procedure's angles, and where.
    Blocked { pass: usize, contact: Contact },
}

/// The step of the search for angles that clear, degrees: finer than a
/// robot's teach resolution matters for clearance, coarse enough that a
/// blocked station costs a few hundred checks at most.
pub const ANGLE_SEARCH_STEP_DEG: f64 = 2.5;

/// The first of the `aims` whose torch, leaning `lean_deg` at
/// `travel_angle_deg`, meets the obstacles, and where.
fn first_contact(
    torch: &Torch,
    obstacles: &Obstacles,
    station: &Station,
    aims: &[Aim],
    lean_deg: f64,
    travel_angle_deg: f64,
) -> Option<(usize, Contact)> {
    aims.iter().enumerate().find_map(|(k, aim)| {
        let axis = station.axis(aim.work_angle_deg + lean_deg, travel_angle_deg);
        contact(torch, obstacles, &aim.point(station), &axis).map(|c| (k, c))
    })
}

/// The torch's angles at one station for every pass of it (`aims`, the
/// pass the waypoints trace first), at the procedure's travel angle.
pub fn clear_station(
    torch: &Torch,
    obstacles: &Obstacles,
    station: &Station,
    aims: &[Aim],
    travel_angle_deg: f64,
) -> Clearance {
    let Some((pass, blocked_at)) = first_contact(torch, obstacles, station, aims, 0.0, travel_angle_deg) else {
        return Clearance::Clear { lean_deg: 0.0, travel_angle_deg, moved: false };
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
                candidates.push((i as f64 * step, travel));
            }
        }
    }
    candidates.sort_by(|a, b| {
        let off = |c: &(f64, f64)| c.0.abs() + (c.1 - travel_angle_deg).abs();
        off(a).total_cmp(&off(b))
    });
    candidates
        .into_iter()
        .find(|&(lean, travel)| first_contact(torch, obstacles, station, aims, lean, travel).is_none())
        .map(|(lean_deg, travel_angle_deg)| Clearance::Clear { lean_deg, travel_angle_deg, moved: true })
        .unwrap_or(Clearance::Blocked { pass, contact: blocked_at })
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
