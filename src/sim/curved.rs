//! Curved members: tees whose root is not a line, which the planner must
//! refuse by name ("the root bends ...: not a plane weld") and never plan
//! as straight segments.
//!
//! Each scene is a tee of [`super::tee_suite`]'s range, drawn from its own
//! seeds, whose captured surface is bent after rendering: every point is
//! moved in the workpiece's frame by `κ·(y − y_m)²/2` (`y` along the seam,
//! `y_m` its middle), either across the web in the flange's plane (the web
//! becomes a curved wall, its foot a curve on a flat flange, as a round
//! tube's is) or along the flange's normal (the flange rolled along the
//! seam with the web following it, a plate bent along the joint). The bend
//! of a smooth part moves the surface the camera sees and changes what it
//! occludes by a fraction of a millimetre at these curvatures, which the
//! bent points ignore. The curvature is drawn so that the root bends
//! [`MIN_SAGITTA_MM`] to [`MAX_SAGITTA_MM`] over the seam's physical
//! length (the sagitta `κ·L²/8`): a straight seam through such a root
//! lies millimetres off it.
//!
//! The truth is each root's straight line bent the same way
//! ([`CurvedScene::distance_to_root`]); a planned seam is judged by its
//! waypoints' largest distance from that curve.

use nalgebra::{Isometry3, Point3};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use super::draw::Draw;
use super::suite::{ScenePlan, uniform};
use super::truth::{SeamTruth, seam_truths};
use super::{SceneSpec, Simulation, simulate};
use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::joint::JointType;

/// Scenes of [`curved_suite`], and how many of them (the last) are held
/// out: the documented seeds are the first [`CURVED_SCENES`] −
/// [`CURVED_HOLDOUT`].
pub const CURVED_SCENES: usize = 12;
pub const CURVED_HOLDOUT: usize = 4;
const CURVED_SEED: u64 = 0xc0e1_2026;
const CURVED_HOLDOUT_SEED: u64 = 0xc0e1_0ff5;
/// The suite's steepest camera tilt, degrees (the tee suite's).
const CURVED_MAX_TILT_DEG: f64 = 30.0;
/// Redraws of a scene until the camera sees at least one root.
const MAX_REDRAWS: u64 = 50;

/// The root's bend over the seam's physical length, mm: from what a
/// straight seam clearly misses (a few millimetres) to a tube of about
/// 10 cm across seen over 15 cm or so.
pub const MIN_SAGITTA_MM: f64 = 4.0;
pub const MAX_SAGITTA_MM: f64 = 16.0;

/// Which way a curved member bends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BendAxis {
    /// Across the web in the flange's plane: a curved wall on a flat
    /// flange (a round tube's foot).
    Wall,
    /// Along the flange's normal: the flange rolled along the seam, the
    /// web following it.
    Rolled,
}

/// A tee bent after rendering.
#[derive(Debug, Clone)]
pub struct CurvedScene {
    pub name: String,
    pub spec: SceneSpec,
    pub axis: BendAxis,
    /// The curvature κ, 1/mm.
    pub curvature_per_mm: f64,
}

/// Curved members over the tee suite's working range: [`CURVED_SCENES`]
/// scenes, walls and rolled flanges in turn, named like
/// `curved-wall-03-d612-t14` (the tee's name after `curved-wall-`); the
/// last [`CURVED_HOLDOUT`] are `-holdout`, drawn from their own seed, not
/// to be run until the planner is frozen.
pub fn curved_suite(draw: Draw) -> Vec<CurvedScene> {
    let camera = CameraModel::default();
    (0..CURVED_SCENES)
        .map(|k| {
            let axis = if k % 2 == 0 { BendAxis::Wall } else { BendAxis::Rolled };
            let plan = ScenePlan::new(JointType::TFillet, 3, k, CURVED_MAX_TILT_DEG);
            let holdout = k >= CURVED_SCENES - CURVED_HOLDOUT;
            let base_seed = draw.seed(if holdout { CURVED_HOLDOUT_SEED } else { CURVED_SEED });
            let mut spec = plan.draw_framed(base_seed, k as u64, &camera);
            for attempt in 1..MAX_REDRAWS {
                if seam_truths(&spec, &camera).iter().any(SeamTruth::is_seen) {
                    break;
                }
                spec = plan.draw_framed(base_seed, k as u64 + attempt * CURVED_SCENES as u64, &camera);
            }
            let mut rng = ChaCha8Rng::seed_from_u64(base_seed ^ (k as u64).wrapping_mul(0x9e37_79b9));
            let sagitta_mm = uniform(&mut rng, MIN_SAGITTA_MM, MAX_SAGITTA_MM);
            let [y0, y1] = spec.seam_range();
            let length = (y1 - y0).max(1.0);
            let curvature_per_mm = 8.0 * sagitta_mm / (length * length);
            let kind = match axis {
                BendAxis::Wall => "wall",
                BendAxis::Rolled => "rolled",
            };
            let tee_name = plan.name();
            let tail = tee_name.strip_prefix("t-fillet-").unwrap_or(&tee_name);
            CurvedScene { name: format!("curved-{kind}-{tail}{}", draw.suffix(holdout)), spec, axis, curvature_per_mm }
        })
        .collect()
}

impl CurvedScene {
    /// The bend of a point in the workpiece's frame.
    fn bend(&self, p: &Vec3) -> Vec3 {
        let [y0, y1] = self.spec.seam_range();
        let d = p.y - 0.5 * (y0 + y1);
        let shift = 0.5 * self.curvature_per_mm * d * d;
        match self.axis {
            BendAxis::Wall => Vec3::new(p.x + shift, p.y, p.z),
            // The workpiece's z rises towards the camera: the flange rolls
            // away from it at the seam's ends.
            BendAxis::Rolled => Vec3::new(p.x, p.y, p.z - shift),
        }
    }

    /// The scene captured, its surface bent: the cloud's points moved, the
    /// truth as the straight scene's (see [`Self::distance_to_root`]).
    pub fn simulate(&self, camera: &CameraModel) -> Simulation {
        let mut sim = simulate(&self.spec, camera);
        sim.reshape_in_workpiece_frame(&self.spec, |p| Some(self.bend(p)));
        sim
    }

    /// The largest distance, mm, of `points` (base frame) from the nearest
    /// root of the bent tee: each root's straight line in the workpiece's
    /// frame, bent, sampled every half millimetre over the seam's length.
    pub fn distance_to_root(&self, sim: &Simulation, points: &[Vec3]) -> f64 {
        let workpiece_from_base: Isometry3<f64> = self.spec.base_from_workpiece.inverse();
        let roots: Vec<Vec<Vec3>> = sim
            .seams
            .iter()
            .map(|seam| {
                let [a, b] = [seam.truth.start_base, seam.truth.end_base]
                    .map(|p| (workpiece_from_base * Point3::from(p)).coords);
                let [y0, y1] = self.spec.seam_range();
                let steps = ((y1 - y0) / 0.5).ceil().max(1.0) as usize;
                let dir = b - a;
                (0..=steps)
                    .filter_map(|i| {
                        let y = y0 + (y1 - y0) * i as f64 / steps as f64;
                        (dir.y.abs() > 1e-9).then(|| self.bend(&(a + dir * ((y - a.y) / dir.y))))
                    })
                    .collect()
            })
            .collect();
        points
            .iter()
            .map(|p| {
                let q = (workpiece_from_base * Point3::from(*p)).coords;
                roots.iter().flatten().map(|r| (r - q).norm()).fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }
}

/// What the planner made of one curved scene under one request: the
/// largest distance of a planned seam's waypoints from the bent root, or
/// the rule that refused.
#[derive(Debug, Clone, PartialEq)]
pub enum CurvedOutcome {
    /// Seams planned, and the worst one's largest distance from the root, mm.
    Planned {
        seams: usize,
        worst_mm: f64,
    },
    Refused {
        rule: &'static str,
    },
}

impl CurvedScene {
    /// Plans the scene's capture under `joint` at default settings.
    pub fn plan(&self, joint: crate::joint::RequestedJoint) -> CurvedOutcome {
        let planner = crate::pipeline::Planner::new(crate::config::Config::default());
        self.plan_with(&planner, &CameraModel::default(), joint)
    }

    /// Plans the scene's capture by `camera` under `joint` with `planner`'s
    /// configuration (`weldseam eval --suite curved`).
    pub fn plan_with(
        &self,
        planner: &crate::pipeline::Planner,
        camera: &CameraModel,
        joint: crate::joint::RequestedJoint,
    ) -> CurvedOutcome {
        let sim = self.simulate(camera);
        let request = crate::pipeline::PlanRequest::new(joint, None, sim.pose);
        match planner.plan(&sim.cloud, &request) {
            Ok(plan) => {
                let worst_mm = plan
                    .seams
                    .iter()
                    .map(|s| {
                        let points: Vec<Vec3> = s.waypoints.iter().map(|w| w.position).collect();
                        self.distance_to_root(&sim, &points)
                    })
                    .fold(0.0, f64::max);
                CurvedOutcome::Planned { seams: plan.seams.len(), worst_mm }
            }
            Err(e) => CurvedOutcome::Refused { rule: e.rule.id },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::RequestedJoint;

    /// A seam within this of the bent root is a stretch short enough to be
    /// straight, not a curved root planned as a line: the eval's fillet bar.
    const WITHIN_MM: f64 = 1.0;

    /// The documented seeds, under `t_fillet` and `auto`: no curved root is
    /// planned as a straight seam; the scenes the planner reads as tees
    /// are refused with the root's bend named.
    #[test]
    fn no_curved_root_is_planned_on_the_documented_seeds() {
        let suite = curved_suite(Draw::Documented);
        let mut bent = 0;
        for scene in suite.iter().take(CURVED_SCENES - CURVED_HOLDOUT) {
            for joint in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto] {
                let outcome = scene.plan(joint);
                eprintln!("{} {joint}: {outcome:?}", scene.name);
                if let CurvedOutcome::Planned { worst_mm, .. } = outcome {
                    assert!(
                        worst_mm <= WITHIN_MM,
                        "{} {joint}: planned {worst_mm:.1} mm off the curved root",
                        scene.name
                    );
                }
                bent += usize::from(outcome == CurvedOutcome::Refused { rule: "seam.edge_fit_residual" });
            }
        }
        assert!(bent > 0, "no scene refused for its bend");
    }

    /// The held-out seeds, run once when the planner is frozen: the
    /// outcomes are printed for the report, never tuned on.
    #[test]
    #[ignore = "held-out seeds: run once, at the end, and reported apart"]
    fn held_out_seeds() {
        let suite = curved_suite(Draw::Documented);
        for scene in suite.iter().skip(CURVED_SCENES - CURVED_HOLDOUT) {
            for joint in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto] {
                eprintln!("{} {joint}: {:?}", scene.name, scene.plan(joint));
            }
        }
    }

    /// The family's straight counterpart (no bend) is planned within the
    /// bar: the bend, not the scene, makes the refusals.
    #[test]
    fn the_same_tees_unbent_are_planned() {
        let suite = curved_suite(Draw::Documented);
        let straight = CurvedScene { curvature_per_mm: 0.0, ..suite[0].clone() };
        match straight.plan(RequestedJoint::Type(JointType::TFillet)) {
            CurvedOutcome::Planned { worst_mm, .. } => assert!(worst_mm <= WITHIN_MM, "{worst_mm}"),
            refused => panic!("{}: {refused:?}", straight.name),
        }
    }
}
