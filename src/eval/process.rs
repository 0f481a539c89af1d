//! The weld process against the simulator's truth, on the scenes of
//! [`crate::sim::process_scenes`]: at every waypoint of every seam planned
//! with a procedure,
//!
//! - the joint's figures (gap, high-low, a V-groove's area) against the
//!   scene's joint at that place along the seam ([`ProcessScene::gap_at`],
//!   [`ProcessScene::high_low_mm`]);
//! - the metal the arc's settings deposit against the true joint's
//!   cross-section and crown under the procedure (the section the
//!   procedure would weld were every figure measured exactly);
//! - a V-groove's passes: the beads under the crown against the true
//!   groove's area, and each pass's aim point (the wire's tip) inside the
//!   true groove, bevels and root, within [`TIP_TOLERANCE_MM`] (where a
//!   waypoint is cut for its torch alone, the layout the procedure gives
//!   the groove measured there, counted apart);
//! - every pass's torch against the frame's cloud: the traced pass at the
//!   angles the plan cleared, every other pass at its aim point, at its
//!   work angle moved as the traced pass's was, with the traced pass's
//!   travel angle (how a robot program runs the seam once per pass), by
//!   the planner's own torch solid ([`crate::process::clearance::contact`]);
//! - beside a clamp: the waypoints whose torch at the procedure's angles
//!   would touch the true block, each of which is to be re-angled or cut,
//!   and every welded torch against the true block (its faces sampled
//!   every [`BLOCK_SAMPLE_MM`]), which none may touch.
//!
//! Pure computation: the caller simulates and plans.

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Point3};

use super::along_seam::{FigureErrors, JointTruth};
use crate::cloud::is_valid_point;
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;
use crate::pipeline::along_seam::JointFigures;
use crate::pipeline::seam_process::{WaypointProcess, layout_for};
use crate::pipeline::{Plan, PlanError, Seam};
use crate::process::clearance::{Obstacles, Station, contact};
use crate::process::{JointSection, Layout, PassKind, Procedure, VGroove, fillet_section, weld_station};
use crate::rules;
use crate::sim::process_scenes::{ClampBlock, ProcessScene};
use crate::sim::{JointGeometry, Simulation};

/// Issue 50's targets: the gap and high-low within this median and
/// largest error, mm ...
pub const FIGURE_MEDIAN_MM: f64 = 0.2;
pub const FIGURE_MAX_MM: f64 = 0.5;
/// ... and the groove's area, the deposit and a groove's fill within this
/// share.
pub const AREA_SHARE: f64 = 0.10;

/// A pass's aim point this close outside the true groove's faces is on
/// the face: the planner's seam is held to 1 mm, and a wire's tip on a
/// bevel is in the groove.
pub const TIP_TOLERANCE_MM: f64 = 0.5;

/// The spacing of the points the true clamp's faces are sampled with, mm:
/// finer than the torch's margin, so no torch passes between them.
pub const BLOCK_SAMPLE_MM: f64 = 1.0;

/// A clamp's score.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClampScore {
    /// The cloud's points on the block (within a millimetre of it).
    pub seen_points: usize,
    /// Waypoints whose torch at the procedure's angles touches the block.
    pub beside: usize,
    /// Of those, how many the plan re-angled, and how many it cut.
    pub re_angled: usize,
    pub cut: usize,
    /// Welded waypoints whose torch, as planned, touches the true block.
    pub through: usize,
}

/// One scene's process against its truth.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProcessScore {
    /// The rule that refused the plan, when it was refused.
    pub refused: Option<&'static str>,
    pub seams: usize,
    pub waypoints: usize,
    /// Waypoints cut, per rule id.
    pub cut: BTreeMap<&'static str, usize>,
    /// Of the waypoints cut by `process.outside_procedure`, those where
    /// the true joint lies outside the procedure too: the procedure asks
    /// for that cut, so it does not count against welding all along.
    pub cut_outside_in_truth: usize,
    pub gap: FigureErrors,
    pub high_low: FigureErrors,
    /// A share of the true area.
    pub groove_area: FigureErrors,
    /// Per welded waypoint, the deposit's error against the true
    /// cross-section and crown, a share.
    pub deposit: Vec<f64>,
    /// The most passes at a waypoint.
    pub max_passes: usize,
    /// Per welded waypoint of several passes, the beads under the crown
    /// against the true groove's area, and against the area measured
    /// there, shares.
    pub fill: Vec<f64>,
    pub fill_measured: Vec<f64>,
    /// Passes whose aim point lies outside the true groove, of those checked.
    pub tips_outside: usize,
    pub tips_checked: usize,
    /// Of the waypoints with several passes scored, how many were cut for
    /// the torch alone: their layout is the one the procedure gives the
    /// joint measured there ([`crate::pipeline::seam_process::layout_for`]),
    /// scored as the welded ones' are, though no torch lays it.
    pub layouts_where_blocked: usize,
    /// For each stretch cut for the torch, where it touched the cloud
    /// from the stretch's first waypoint, workpiece frame, mm: across the
    /// seam, along it, up.
    pub blocked_contacts: Vec<Vec3>,
    /// Torches (a pass at a waypoint) inside the cloud, of those checked.
    pub torches_in_cloud: usize,
    pub torches_checked: usize,
    pub clamp: Option<ClampScore>,
}

/// The largest of some shares or errors, None without one.
pub fn worst(values: &[f64]) -> Option<f64> {
    values.iter().copied().reduce(f64::max)
}

impl ProcessScore {
    /// Gap and high-low within the targets' median and largest error, a
    /// groove's area within its share; None when no figure was scored.
    pub fn figures_met(&self) -> Option<bool> {
        let within = |f: &FigureErrors| {
            f.median().is_none_or(|m| m <= FIGURE_MEDIAN_MM) && f.max().is_none_or(|m| m <= FIGURE_MAX_MM)
        };
        let scored =
            [&self.gap, &self.high_low, &self.groove_area].iter().any(|f| !f.errors.is_empty() || f.missing > 0);
        let missing = self.gap.missing + self.high_low.missing + self.groove_area.missing;
        scored.then(|| {
            within(&self.gap)
                && within(&self.high_low)
                && self.groove_area.max().is_none_or(|m| m <= AREA_SHARE)
                && missing == 0
        })
    }

    /// The deposit within its share at every waypoint, none cut but where
    /// the true joint is outside the procedure.
    pub fn deposit_met(&self) -> Option<bool> {
        let cut: usize = self.cut.values().sum();
        (self.refused.is_none() && self.waypoints > 0)
            .then(|| cut == self.cut_outside_in_truth && worst(&self.deposit).is_some_and(|w| w <= AREA_SHARE))
    }

    /// A multi-pass layout filling the true groove within its share, no
    /// tip outside it; None where no waypoint took several passes.
    pub fn passes_met(&self) -> Option<bool> {
        (!self.fill.is_empty()).then(|| worst(&self.fill).is_some_and(|w| w <= AREA_SHARE) && self.tips_outside == 0)
    }

    /// The clamp seen, every waypoint beside it re-angled or cut, none
    /// welded through it.
    pub fn clamp_met(&self) -> Option<bool> {
        self.clamp
            .as_ref()
            .map(|c| self.refused.is_none() && c.seen_points > 0 && c.through == 0 && c.re_angled + c.cut == c.beside)
    }

    /// No torch of any pass inside the cloud.
    pub fn clearance_met(&self) -> Option<bool> {
        (self.torches_checked > 0).then_some(self.torches_in_cloud == 0)
    }
}

/// Scores the plan (or refusal) of one scene's capture `sim` under
/// `procedure`.
pub fn score(
    scene: &ProcessScene,
    sim: &Simulation,
    plan: &Result<Plan, PlanError>,
    procedure: &Procedure,
) -> ProcessScore {
    let mut score = ProcessScore::default();
    let plan = match plan {
        Ok(plan) => plan,
        Err(e) => {
            score.refused = Some(e.rule.id);
            return score;
        }
    };
    let block = scene.clamp.map(|b| Obstacles::new(block_faces(&b)));
    if let Some(b) = &scene.clamp {
        score.clamp = Some(ClampScore { seen_points: seen_on_block(scene, sim, b), ..ClampScore::default() });
    }
    for seam in &plan.seams {
        score.seams += 1;
        score_seam(&mut score, scene, sim, seam, procedure, block.as_ref());
    }
    score
}

/// The frames a seam's waypoints are scored in.
struct Frames {
    workpiece_from_base: Isometry3<f64>,
    camera_from_base: Isometry3<f64>,
}

fn score_seam(
    score: &mut ProcessScore,
    scene: &ProcessScene,
    sim: &Simulation,
    seam: &Seam,
    procedure: &Procedure,
    block: Option<&Obstacles>,
) {
    let frames = Frames {
        workpiece_from_base: scene.spec.base_from_workpiece.inverse(),
        camera_from_base: sim.base_from_camera.inverse(),
    };
    let in_workpiece: Vec<Vec3> =
        seam.waypoints.iter().map(|w| (frames.workpiece_from_base * Point3::from(w.position)).coords).collect();
    let in_camera: Vec<Vec3> =
        seam.waypoints.iter().map(|w| (frames.camera_from_base * Point3::from(w.position)).coords).collect();
    let truth = JointTruth::of(&scene.spec);
    let thickness = scene.plate_thickness_mm();
    // What the torches touch in the cloud itself: the space the planner
    // also keeps clear behind the seen surfaces is no part of the target.
    let obstacles = Obstacles::new(sim.cloud.points().iter().filter(|p| is_valid_point(p)).map(vec3));
    // Out of the joint towards the torch: against the plate normal, which
    // points into the workpiece.
    let bisector = -seam.normal_camera.normalize();
    let mut blocked = vec![false; seam.waypoints.len()];
    for c in seam.process.iter().flat_map(|p| &p.cut).filter(|c| c.rule.id == rules::process::TORCH_BLOCKED.id) {
        blocked.iter_mut().take(c.last + 1).skip(c.first).for_each(|b| *b = true);
    }
    let in_view = joint_in_view(sim, seam, &in_camera);
    for (k, w) in in_workpiece.iter().enumerate() {
        score.waypoints += 1;
        let y = w.y;
        if let (Some(f), Some(t)) = (seam.along_seam.get(k), truth) {
            let butt = matches!(scene.spec.joint, JointGeometry::IButt { .. } | JointGeometry::VButt { .. });
            let gap = butt.then(|| scene.gap_at(y)).flatten();
            let high_low = butt.then_some(scene.high_low_mm);
            let unread = (f.gap_mm.is_none() && gap.is_some())
                || (f.high_low_mm.is_none() && high_low.is_some())
                || (f.groove_area_mm2.is_none() && t.groove_area_mm2.is_some());
            if unread && !in_view[k] {
                score.gap.add_unseen(gap);
                score.high_low.add_unseen(high_low);
                score.groove_area.add_unseen(t.groove_area_mm2);
            } else {
                score.gap.add(f.gap_mm, gap, false);
                score.high_low.add(f.high_low_mm, high_low, false);
                score.groove_area.add(f.groove_area_mm2, t.groove_area_mm2, true);
            }
        }
        let along = along_at(&in_camera, k);
        let station = Station { point: in_camera[k], along, bisector };
        let entry = procedure.entry(scene.case.joint(), thickness);
        let at_procedure = entry.map(|e| station.axis(e.work_angle_deg, e.travel_angle_deg));
        // The torch the planner checks for this joint: the entry's own.
        let torch = entry.map_or(procedure.torch, |e| procedure.torch_for(e));
        let touches_block = |point: &Vec3, axis: &Vec3| {
            block.is_some_and(|b| {
                contact(&torch, b, &(frames.workpiece_from_camera(point)), &frames.workpiece_axis(axis)).is_some()
            })
        };
        let beside = at_procedure.is_some_and(|axis| touches_block(&in_camera[k], &axis));
        let welded = seam.process.as_ref().and_then(|p| p.waypoints.get(k)).and_then(Option::as_ref);
        if let (Some(c), true) = (score.clamp.as_mut(), beside) {
            c.beside += 1;
            match welded {
                Some(wp) if wp.re_angled => c.re_angled += 1,
                Some(_) => {}
                None => c.cut += 1,
            }
        }
        let blocked = blocked.get(k).copied().unwrap_or(false);
        let layout = match (welded, blocked, seam.along_seam.get(k)) {
            (Some(wp), _, _) => Some(wp.layout.clone()),
            (None, true, Some(f)) => layout_for(procedure, scene.case.joint(), Some(thickness), f).ok(),
            _ => None,
        };
        if let Some(layout) = layout.as_ref().filter(|l| l.passes.len() > 1) {
            score.layouts_where_blocked += usize::from(welded.is_none());
            score_passes(score, scene, layout, seam.along_seam.get(k), &station, &frames);
        }
        let Some(wp) = welded else { continue };
        score.max_passes = score.max_passes.max(wp.layout.passes.len());
        if let Some(wanted) = true_weld_area(scene, procedure, y, thickness) {
            score.deposit.push((wp.layout.deposited_area_mm2() - wanted).abs() / wanted);
        }
        let mut through = false;
        for (aim, axis) in pass_torches(wp, &station) {
            score.torches_checked += 1;
            score.torches_in_cloud += usize::from(contact(&torch, &obstacles, &aim, &axis).is_some());
            through |= touches_block(&aim, &axis);
        }
        if let (Some(c), true) = (score.clamp.as_mut(), through) {
            c.through += 1;
        }
    }
    if let Some(p) = &seam.process {
        for c in &p.cut {
            *score.cut.entry(c.rule.id).or_default() += c.last + 1 - c.first;
            if c.rule.id == rules::process::OUTSIDE_PROCEDURE.id {
                score.cut_outside_in_truth += (c.first..=c.last)
                    .filter_map(|k| in_workpiece.get(k))
                    .filter(|w| true_joint_outside(scene, procedure, w.y, thickness))
                    .count();
            }
            if let (Some(contact), Some(w)) = (c.contact_camera, in_workpiece.get(c.first)) {
                score.blocked_contacts.push(frames.workpiece_from_camera(&contact) - w);
            }
        }
    }
}

/// A V-groove's passes at one waypoint: the beads under the crown against
/// the true groove's area and the area measured there, and each pass's
/// aim point against the true groove.
fn score_passes(
    score: &mut ProcessScore,
    scene: &ProcessScene,
    layout: &Layout,
    figures: Option<&JointFigures>,
    station: &Station,
    frames: &Frames,
) {
    let JointGeometry::VButt { .. } = scene.spec.joint else { return };
    let beads = layout.deposited_area_mm2() - layout.crown_area_mm2;
    if let Some(groove) = true_groove(scene) {
        score.fill.push((beads - groove.area()).abs() / groove.area());
    }
    if let Some(measured) = figures.and_then(|f| f.groove_area_mm2) {
        score.fill_measured.push((beads - measured.value).abs() / measured.value);
    }
    let across = station.along.cross(&station.bisector).normalize();
    for p in &layout.passes {
        let aim = station.point + across * p.lateral_mm + station.bisector * p.height_mm;
        score.tips_checked += 1;
        score.tips_outside += usize::from(!tip_in_groove(scene, &frames.workpiece_from_camera(&aim)));
    }
}

impl Frames {
    fn workpiece_from_camera(&self, p: &Vec3) -> Vec3 {
        (self.workpiece_from_base * self.camera_from_base.inverse() * Point3::from(*p)).coords
    }

    fn workpiece_axis(&self, v: &Vec3) -> Vec3 {
        (self.workpiece_from_base * self.camera_from_base.inverse()).rotation * v
    }
}

/// The direction of travel at waypoint `k`: along its neighbours.
fn along_at(points: &[Vec3], k: usize) -> Vec3 {
    let (a, b) = (points[k.saturating_sub(1)], points[(k + 1).min(points.len() - 1)]);
    (b - a).try_normalize(1e-12).unwrap_or_else(Vec3::y)
}

/// Every pass's torch at a waypoint, camera frame: its aim point and its
/// axis (from the aim point towards the torch).
fn pass_torches(wp: &WaypointProcess, station: &Station) -> Vec<(Vec3, Vec3)> {
    let traced = wp.layout.passes.iter().find(|p| matches!(p.kind, PassKind::Single | PassKind::Root));
    let turned = traced.map_or(0.0, |p| wp.work_angle_deg - p.work_angle_deg);
    let across = station.along.cross(&station.bisector).normalize();
    wp.layout
        .passes
        .iter()
        .map(|p| {
            if matches!(p.kind, PassKind::Single | PassKind::Root) {
                return (station.point, wp.torch_axis_camera);
            }
            let aim = station.point + across * p.lateral_mm + station.bisector * p.height_mm;
            let at = Station { point: aim, ..*station };
            (aim, at.axis(p.work_angle_deg + turned, wp.travel_angle_deg))
        })
        .collect()
}

/// The scene's true V-groove, as the procedure's section reads one.
fn true_groove(scene: &ProcessScene) -> Option<VGroove> {
    match scene.spec.joint {
        JointGeometry::VButt { thickness_mm, groove_angle_deg, groove_depth_mm, root_gap_mm } => Some(VGroove {
            thickness_mm,
            included_angle_deg: groove_angle_deg,
            root_gap_mm,
            root_face_mm: thickness_mm - groove_depth_mm,
        }),
        _ => None,
    }
}

/// The true joint's cross-section and crown at `y` under the procedure,
/// mm², or None where the procedure has no entry for it.
fn true_weld_area(scene: &ProcessScene, procedure: &Procedure, y: f64, thickness_mm: f64) -> Option<f64> {
    let entry = procedure.entry(scene.case.joint(), thickness_mm)?;
    let allowance = entry.leg_gap_allowance_mm.unwrap_or(0.0);
    Some(true_section(scene, procedure, y, thickness_mm)?.weld_area(procedure, allowance))
}

/// Whether the procedure refuses the true joint at `y` (no entry for it,
/// or a figure outside the entry's ranges): there a cut by
/// `process.outside_procedure` is what the procedure asks for.
fn true_joint_outside(scene: &ProcessScene, procedure: &Procedure, y: f64, thickness_mm: f64) -> bool {
    true_section(scene, procedure, y, thickness_mm)
        .is_none_or(|section| weld_station(procedure, scene.case.joint(), thickness_mm, &section).is_err())
}

/// The true joint's cross-section at `y`, as the procedure's section
/// reads one, or None where the scene's joint has none there.
fn true_section(scene: &ProcessScene, procedure: &Procedure, y: f64, thickness_mm: f64) -> Option<JointSection> {
    let joint = scene.case.joint();
    let section = match scene.spec.joint {
        JointGeometry::IButt { .. } => JointSection::SquareButt { thickness_mm, gap_mm: scene.gap_at(y)? },
        JointGeometry::VButt { .. } => JointSection::VGroove(true_groove(scene)?),
        _ => fillet_section(procedure, joint, thickness_mm, 0.0)?,
    };
    let section = match (section, joint) {
        (JointSection::Fillet { leg_mm, gap_mm }, JointType::Lap) => {
            JointSection::Fillet { leg_mm: leg_mm.min(thickness_mm), gap_mm }
        }
        (s, _) => s,
    };
    Some(section)
}

/// Whether a point (workpiece frame) lies in the scene's true V-groove,
/// between its bevels (and the root gap's faces) from its foot to the
/// plates' top, within [`TIP_TOLERANCE_MM`].
fn tip_in_groove(scene: &ProcessScene, p: &Vec3) -> bool {
    let JointGeometry::VButt { thickness_mm: t, groove_angle_deg: a, groove_depth_mm: d, root_gap_mm: r } =
        scene.spec.joint
    else {
        return true;
    };
    let tol = TIP_TOLERANCE_MM;
    let foot = t - d;
    if p.z < -tol || p.z > t + tol {
        return false;
    }
    // Half the groove's width at the point's height: the root gap below
    // the bevels' foot, the bevels above; a face is crossed when the point
    // lies beyond it by more than the tolerance, measured square to it.
    let half_angle = (a / 2.0).to_radians();
    let beyond_bevel = (p.x.abs() - r / 2.0 - (p.z - foot).max(0.0) * half_angle.tan()) * half_angle.cos();
    let beyond_gap = p.x.abs() - r / 2.0;
    if p.z < foot { beyond_gap <= tol } else { beyond_bevel <= tol }
}

/// The cloud's points on the block (workpiece frame, within a millimetre).
/// How near the joint's place at a waypoint the cloud's points are
/// counted, mm: the plates' edges beside a root gap of a few millimetres
/// lie within it.
const JOINT_BALL_MM: f64 = 4.0;

/// The share of the points a waypoint's ball holds where the figures are
/// read (their median) below which the joint there is taken as out of
/// view: a clamp or the workpiece hides it from the camera, or shows only
/// a sliver of it, and no figure can be read there.
const IN_VIEW_SHARE: f64 = 0.5;

/// The most waypoints whose figures were read that are counted for the
/// median: enough to know the frame's density along the seam, few enough
/// that a scan of the frame per waypoint stays cheap.
const READ_WAYPOINTS_COUNTED: usize = 16;

/// For each waypoint of `seam` (`in_camera`, camera frame), whether the
/// joint there is in the cloud's view: its ball of [`JOINT_BALL_MM`] holds
/// at least [`IN_VIEW_SHARE`] of the points the balls hold where the
/// figures were read. Counted only where a figure is not read (the rest
/// are in view) and at a few read waypoints for the median; where none
/// was read, every waypoint counts as in view, so a figure not read is
/// missing.
fn joint_in_view(sim: &Simulation, seam: &Seam, in_camera: &[Vec3]) -> Vec<bool> {
    let read = |k: usize| seam.along_seam.get(k).is_some_and(|f| f.gap_mm.is_some() || f.lap_step_mm.is_some());
    let unread: Vec<usize> = (0..in_camera.len()).filter(|&k| !read(k)).collect();
    let mut in_view = vec![true; in_camera.len()];
    if unread.is_empty() {
        return in_view;
    }
    let read_at: Vec<usize> = (0..in_camera.len()).filter(|&k| read(k)).collect();
    let stride = read_at.len().div_ceil(READ_WAYPOINTS_COUNTED).max(1);
    let mut counts: Vec<usize> = read_at.iter().step_by(stride).map(|&k| points_near(sim, &in_camera[k])).collect();
    if counts.is_empty() {
        return in_view;
    }
    let middle = counts.len() / 2;
    let (_, &mut median, _) = counts.select_nth_unstable(middle);
    for k in unread {
        in_view[k] = points_near(sim, &in_camera[k]) as f64 >= IN_VIEW_SHARE * median as f64;
    }
    in_view
}

/// The capture's valid points within [`JOINT_BALL_MM`] of `at`.
fn points_near(sim: &Simulation, at: &Vec3) -> usize {
    let r2 = JOINT_BALL_MM * JOINT_BALL_MM;
    sim.cloud.points().iter().filter(|p| is_valid_point(p) && (vec3(p) - at).norm_squared() <= r2).count()
}

fn seen_on_block(scene: &ProcessScene, sim: &Simulation, b: &ClampBlock) -> usize {
    let workpiece_from_camera = scene.spec.workpiece_from_camera();
    let grown = Vec3::repeat(1.0);
    sim.cloud
        .points()
        .iter()
        .filter(|p| crate::cloud::is_valid_point(p))
        .map(|p| (workpiece_from_camera * Point3::from(crate::geometry::vec3(p))).coords)
        .filter(|w| (0..3).all(|i| w[i] >= b.min[i] - grown[i] && w[i] <= b.max[i] + grown[i]))
        .count()
}

/// The block's faces sampled every [`BLOCK_SAMPLE_MM`] (workpiece frame).
fn block_faces(b: &ClampBlock) -> Vec<Vec3> {
    let steps = |lo: f64, hi: f64| ((hi - lo) / BLOCK_SAMPLE_MM).ceil().max(1.0) as usize;
    let at = |lo: f64, hi: f64, i: usize, n: usize| lo + (hi - lo) * i as f64 / n as f64;
    let mut points = Vec::new();
    let n = [steps(b.min.x, b.max.x), steps(b.min.y, b.max.y), steps(b.min.z, b.max.z)];
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for face in [b.min[axis], b.max[axis]] {
            for i in 0..=n[u] {
                for j in 0..=n[v] {
                    let mut p = Vec3::zeros();
                    p[axis] = face;
                    p[u] = at(b.min[u], b.max[u], i, n[u]);
                    p[v] = at(b.min[v], b.max[v], j, n[v]);
                    points.push(p);
                }
            }
        }
    }
    points
}

#[cfg(test)]
#[path = "process_tests.rs"]
mod tests;
