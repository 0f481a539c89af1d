//! V-grooves whose width varies along the seam ([`groove_width_suite`]):
//! a groove cut by hand, or by a torch that wandered, is wider over part of
//! its length, so one plate's top edge steps back from the other plate
//! there while the groove's root (a flat land, as in
//! [`super::root_land`]) runs straight on. The top edge then lies on two
//! runs a few millimetres apart, and what lies between them is the plate's
//! own bevel, not a dropout: the planner must not take the step for an
//! edge cut short, and must weld the root, which did not move.
//!
//! Each scene is a root-land groove of [`super::root_land`]'s range, drawn
//! from its own seeds, whose captured surface is re-cut after rendering:
//! over the stretch of the seam from a point in its middle third to its
//! end, every point of one plate's bevel is moved across the seam, in the
//! workpiece's frame, onto the bevel that runs from the same foot on the
//! land to a top edge [`MIN_WIDEN_MM`] to [`MAX_WIDEN_MM`] further back
//! (the same height up the bevel), and the points of the plate's top that
//! the wider groove cut away are removed; the step is ramped over
//! [`RAMP_MM`], as a hand-cut groove's is. The camera would see the
//! shallower bevel a little more densely and a little more of it; the
//! re-cut points ignore that (a fraction of a millimetre of the view).
//!
//! The truth is the straight root the scene was drawn with (the land's
//! centre at its height): the re-cut leaves the land and the bevels' feet
//! where they were.

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use super::draw::Draw;
use super::root_land::reshape_to_land;
use super::suite::{ScenePlan, uniform};
use super::{JointGeometry, SceneSpec, Simulation, simulate};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::joint::JointType;

/// Scenes of [`groove_width_suite`], and how many of them (the last) are
/// held out: the documented seeds are the first [`GROOVE_WIDTH_SCENES`] −
/// [`GROOVE_WIDTH_HOLDOUT`].
pub const GROOVE_WIDTH_SCENES: usize = 12;
pub const GROOVE_WIDTH_HOLDOUT: usize = 4;
const GROOVE_WIDTH_SEED: u64 = 0x91d7_2026;
const GROOVE_WIDTH_HOLDOUT_SEED: u64 = 0x91d7_0ff5;

/// The tilt range of the eval suite's strata the scenes take.
const MAX_TILT_DEG: f64 = 30.0;
/// The framings of the eval suite's plan that fill the view (its first
/// four scenes): the scenes take them in turn.
const FILL_PLANS: usize = 4;

/// How much further back the re-cut top edge lies, mm: the hand-cut
/// groove of real scan coboweld/barpoints steps about 7 mm.
pub const MIN_WIDEN_MM: f64 = 3.0;
pub const MAX_WIDEN_MM: f64 = 8.0;
/// The length of seam over which the edge steps back, mm.
pub const RAMP_MM: f64 = 3.0;

/// A root-land groove re-cut wider along part of its seam.
#[derive(Debug, Clone)]
pub struct WidenedGroove {
    pub name: String,
    pub spec: SceneSpec,
    /// Which plate's bevel is re-cut: -1 for plate A (x < 0), +1 for B.
    pub side: f64,
    /// Where along the seam (workpiece y, mm) the step begins; the groove
    /// is wider from there to the seam's end.
    pub from_mm: f64,
    pub widen_mm: f64,
}

/// The family's scenes, named like `groove-width-03-d548-t14-w6.2` (index,
/// standoff, tilt, how much wider); the last [`GROOVE_WIDTH_HOLDOUT`] are
/// `-holdout`, drawn from their own seed, not to be run until the
/// planner is frozen.
pub fn groove_width_suite(draw: Draw) -> Vec<WidenedGroove> {
    let camera = CameraModel::default();
    (0..GROOVE_WIDTH_SCENES)
        .map(|k| {
            let plan = ScenePlan::new(JointType::VButt, 0, k % FILL_PLANS, MAX_TILT_DEG);
            let holdout = k >= GROOVE_WIDTH_SCENES - GROOVE_WIDTH_HOLDOUT;
            let base_seed = draw.seed(if holdout { GROOVE_WIDTH_HOLDOUT_SEED } else { GROOVE_WIDTH_SEED });
            let spec = plan.draw_framed_reshaped(base_seed, k as u64, &camera, reshape_to_land);
            let mut rng = ChaCha8Rng::seed_from_u64(base_seed ^ (k as u64).wrapping_mul(0x9e37_79b9));
            let widen_mm = uniform(&mut rng, MIN_WIDEN_MM, MAX_WIDEN_MM);
            let [y0, y1] = spec.seam_range();
            let from_mm = uniform(&mut rng, y0 + (y1 - y0) / 3.0, y1 - (y1 - y0) / 3.0);
            let side = if k % 2 == 0 { 1.0 } else { -1.0 };
            let (distance, tilt) = (spec.placement.distance_mm, spec.placement.tilt_deg);
            let name = format!("groove-width-{k:02}-d{distance:.0}-t{tilt:.0}-w{widen_mm:.1}{}", draw.suffix(holdout));
            WidenedGroove { name, spec, side, from_mm, widen_mm }
        })
        .collect()
}

impl WidenedGroove {
    /// A point of the workpiece's frame moved onto the re-cut groove, or
    /// None where the re-cut took it away.
    fn recut(&self, p: &Vec3) -> Option<Vec3> {
        let JointGeometry::VButt { thickness_mm: top, root_gap_mm: land, .. } = self.spec.joint else {
            return Some(*p);
        };
        let widen = self.widen_mm * ((p.y - self.from_mm) / RAMP_MM).clamp(0.0, 1.0);
        let across = self.side * p.x;
        let (foot, edge) = (0.5 * land, self.spec.joint.seam_edge_half_width());
        // Only this plate's bevel and the strip of its top the re-cut takes.
        if widen <= 0.0 || across <= foot || across > edge + widen + 0.5 {
            return Some(*p);
        }
        // The top (within a few tenths of it, for the noise) past the old
        // edge: cut away where the new bevel runs under it.
        let up = (p.z / top).clamp(0.0, 1.0);
        if across >= edge && p.z > top - 0.3 {
            return (across > edge + widen).then_some(*p);
        }
        // On the bevel: the same height up the wider one.
        let moved = foot + up * (edge + widen - foot);
        Some(Vec3::new(self.side * moved, p.y, p.z))
    }

    /// The scene captured and re-cut: the cloud's points moved or removed,
    /// the truth the scene's.
    pub fn simulate(&self, camera: &CameraModel) -> Simulation {
        let mut sim = simulate(&self.spec, camera);
        sim.reshape_in_workpiece_frame(&self.spec, |p| self.recut(p));
        sim
    }

    /// Plans the scene's capture under `joint` at default settings: the
    /// largest distance of a planned seam's waypoints from the root, mm,
    /// or the rule that refused.
    pub fn plan(&self, joint: crate::joint::RequestedJoint) -> Result<f64, &'static str> {
        let planner = crate::pipeline::Planner::new(crate::config::Config::default());
        self.plan_with(&planner, &CameraModel::default(), joint)
    }

    /// [`Self::plan`] with a given planner and camera (`eval --suite
    /// groove-width` plans at the config's settings).
    pub fn plan_with(
        &self,
        planner: &crate::pipeline::Planner,
        camera: &CameraModel,
        joint: crate::joint::RequestedJoint,
    ) -> Result<f64, &'static str> {
        let sim = self.simulate(camera);
        let request = crate::pipeline::PlanRequest::new(joint, None, sim.pose);
        let plan = planner.plan(&sim.cloud, &request).map_err(|e| e.rule.id)?;
        let truth = &sim.seams.first().ok_or("no seam in the scene")?.truth;
        let (a, b) = (truth.start_base, truth.end_base);
        let off = |p: &Vec3| {
            let d = (b - a).normalize();
            let v = p - a;
            (v - d * v.dot(&d)).norm()
        };
        Ok(plan.seams.iter().flat_map(|s| s.waypoints.iter().map(|w| off(&w.position))).fold(0.0, f64::max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::RequestedJoint;

    /// A V-groove's bar: within this of the root.
    const WITHIN_MM: f64 = 1.0;
    /// Further than this from the root is a confident wrong seam.
    const CONFIDENT_WRONG_MM: f64 = 2.0;

    #[test]
    fn the_recut_moves_the_bevel_back_and_leaves_the_land_and_the_far_plate() {
        let suite = groove_width_suite(Draw::Documented);
        let scene = &suite[0];
        let JointGeometry::VButt { thickness_mm: top, root_gap_mm: land, .. } = scene.spec.joint else {
            panic!("not a V-groove");
        };
        let edge = scene.spec.joint.seam_edge_half_width();
        let past = scene.from_mm + RAMP_MM + 1.0;
        let s = scene.side;
        // Halfway up the bevel, past the step: moved back by half the widening.
        let moved = scene.recut(&Vec3::new(s * 0.5 * (0.5 * land + edge), past, 0.5 * top)).unwrap();
        assert!((s * moved.x - 0.5 * (0.5 * land + edge + scene.widen_mm)).abs() < 1e-9, "{moved:?}");
        // The top the wider groove took is gone; beyond it, kept.
        assert_eq!(scene.recut(&Vec3::new(s * (edge + 0.5 * scene.widen_mm), past, top)), None);
        let beyond = Vec3::new(s * (edge + scene.widen_mm + 1.0), past, top);
        assert_eq!(scene.recut(&beyond), Some(beyond));
        // Before the step, on the land and on the other plate: untouched.
        for p in [Vec3::new(s * 0.5 * edge, scene.from_mm - 1.0, 0.5 * top), Vec3::new(0.0, past, 0.0)] {
            assert_eq!(scene.recut(&p), Some(p));
        }
        let other = Vec3::new(-s * 0.5 * edge, past, 0.5 * top);
        assert_eq!(scene.recut(&other), Some(other));
    }

    /// The documented seeds, under `v_butt` and `auto`: no seam further
    /// than a confident wrong one's distance from the root; the outcomes
    /// printed (`cargo test --lib groove_width -- --nocapture`).
    #[test]
    fn no_widened_groove_is_planned_off_its_root_on_the_documented_seeds() {
        let suite = groove_width_suite(Draw::Documented);
        let mut within = 0;
        for scene in suite.iter().take(GROOVE_WIDTH_SCENES - GROOVE_WIDTH_HOLDOUT) {
            for joint in [RequestedJoint::Type(JointType::VButt), RequestedJoint::Auto] {
                let outcome = scene.plan(joint);
                eprintln!("{} {joint}: {outcome:?}", scene.name);
                if let Ok(worst_mm) = outcome {
                    assert!(worst_mm <= CONFIDENT_WRONG_MM, "{} {joint}: {worst_mm:.2} mm off the root", scene.name);
                    within += usize::from(worst_mm <= WITHIN_MM);
                }
            }
        }
        eprintln!("{within} of {} plans within {WITHIN_MM} mm", 2 * (GROOVE_WIDTH_SCENES - GROOVE_WIDTH_HOLDOUT));
    }

    /// Tuning scenes whose re-cut top edge fails the gates that read a top
    /// edge (its samples beyond its line, its run seen along part of the
    /// joint only: `edge.samples_beyond_line`, `seam.stops_short_of_joint`
    /// before the root was read from the flanks) are welded on the root
    /// the flanks place (`groove.weld_on_bevel_midline`), within the bar.
    #[test]
    fn a_groove_cut_back_along_part_of_its_seam_is_welded_on_its_root() {
        let suite = groove_width_suite(Draw::Documented);
        for k in [4, 5, 7] {
            let scene = &suite[k];
            match scene.plan(RequestedJoint::Type(JointType::VButt)) {
                Ok(worst_mm) => assert!(worst_mm <= WITHIN_MM, "{}: {worst_mm:.2} mm off the root", scene.name),
                Err(rule) => panic!("{} refused by {rule}", scene.name),
            }
        }
    }

    /// The held-out seeds, run once when the planner is frozen: the
    /// outcomes are printed for the report, never tuned on.
    #[test]
    #[ignore = "held-out seeds: run once, at the end, and reported apart"]
    fn held_out_seeds() {
        let suite = groove_width_suite(Draw::Documented);
        for scene in suite.iter().skip(GROOVE_WIDTH_SCENES - GROOVE_WIDTH_HOLDOUT) {
            for joint in [RequestedJoint::Type(JointType::VButt), RequestedJoint::Auto] {
                eprintln!("{} {joint}: {:?}", scene.name, scene.plan(joint));
            }
        }
    }
}
