//! Accuracy against ground truth, as the paper measures it (section 5.2):
//! twelve points evenly spaced on the true seam, end to end, each one's
//! distance to the planned trajectory; plus how far the trajectory's ends
//! are from the seam's.
//!
//! The paper taught its twelve points by hand; here they come from the
//! simulator's geometry, in the robot base frame, so the figure includes
//! the hand-eye and pose transform exactly as a robot would follow it.

use crate::camera::CameraModel;
use crate::config::{Config, Method};
use crate::geometry::{Vec3, distance_to_polyline};
use crate::pipeline::input::{CloudFrame, Units};
use crate::pipeline::{Plan, PlanError, PlanRequest, Planner, Seam};
use crate::sim::variants::Variant;
use crate::sim::{GroundTruth, SceneSpec, Simulation, simulate};

/// The number of reference points on the true seam (the paper's 12).
pub const REFERENCE_POINTS: usize = 12;

/// Errors of one planned seam against the truth, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeamError {
    /// Largest distance of a reference point to the trajectory.
    pub max_mm: f64,
    pub mean_mm: f64,
    /// Distance of the trajectory's first and last waypoints from the
    /// true seam ends (matched in whichever order is closer).
    pub start_mm: f64,
    pub end_mm: f64,
}

impl SeamError {
    /// The paper's bar (1 mm) and ours for the ends (2 mm).
    pub fn passes(&self) -> bool {
        self.max_mm < 1.0 && self.start_mm < 2.0 && self.end_mm < 2.0
    }
}

/// Compares a planned seam with the truth, both in the robot base frame.
pub fn seam_error(truth: &GroundTruth, seam: &Seam) -> Option<SeamError> {
    let path: Vec<Vec3> = seam.waypoints.iter().map(|w| w.position).collect();
    path_error(truth, &path)
}

/// Compares a trajectory (base-frame waypoint positions, in order) with
/// the truth.
pub fn path_error(truth: &GroundTruth, path: &[Vec3]) -> Option<SeamError> {
    let (first, last) = (path.first()?, path.last()?);
    let distances: Vec<f64> = (0..REFERENCE_POINTS)
        .map(|k| {
            let t = k as f64 / (REFERENCE_POINTS - 1) as f64;
            let p = truth.start_base + (truth.end_base - truth.start_base) * t;
            distance_to_polyline(&p, path)
        })
        .collect();
    let direct = ((first - truth.start_base).norm(), (last - truth.end_base).norm());
    let swapped = ((first - truth.end_base).norm(), (last - truth.start_base).norm());
    let (start_mm, end_mm) = if direct.0 + direct.1 <= swapped.0 + swapped.1 { direct } else { swapped };
    Some(SeamError {
        max_mm: distances.iter().copied().fold(0.0, f64::max),
        mean_mm: distances.iter().sum::<f64>() / REFERENCE_POINTS as f64,
        start_mm,
        end_mm,
    })
}

/// What happened to one scene.
#[derive(Debug, Clone)]
pub struct SceneOutcome {
    pub name: String,
    /// The method that planned it.
    pub method: Method,
    pub spec: SceneSpec,
    pub truth: GroundTruth,
    /// The error against the truth and the plan it was measured on.
    pub result: Result<(SeamError, Plan), PlanError>,
}

impl SceneOutcome {
    pub fn passes(&self) -> bool {
        matches!(&self.result, Ok((e, _)) if e.passes())
    }
}

/// Plans a simulated scene and measures the result.
pub fn evaluate_simulation(planner: &Planner, name: &str, spec: &SceneSpec, sim: &Simulation) -> SceneOutcome {
    evaluate_variant(planner, name, spec, sim, &Variant::default())
}

/// [`evaluate_simulation`] of a frame made into `variant`, requested as a
/// user of `plan` would: units guessed (`--units auto`, the command line's
/// default) and, for a base-frame cloud, `--cloud-frame base`.
pub fn evaluate_variant(
    planner: &Planner,
    name: &str,
    spec: &SceneSpec,
    sim: &Simulation,
    variant: &Variant,
) -> SceneOutcome {
    let mut request = PlanRequest::new(spec.joint.joint_type(), spec.joint.groove_depth_mm(), sim.pose);
    if !variant.is_raw() {
        request.units = Units::Auto;
    }
    if variant.in_base_frame() {
        request.cloud_frame = CloudFrame::Base;
    }
    let result = planner.plan(&sim.cloud, &request).and_then(|plan| {
        let seam = plan.seams.first().ok_or_else(|| PlanError::at(crate::pipeline::Stage::Trajectory, "no seam"))?;
        let err = seam_error(&sim.truth, seam)
            .ok_or_else(|| PlanError::at(crate::pipeline::Stage::Trajectory, "the trajectory has no waypoint"))?;
        Ok((err, plan))
    });
    SceneOutcome {
        name: name.to_string(),
        method: planner.config().pipeline.method,
        spec: spec.clone(),
        truth: sim.truth.clone(),
        result,
    }
}

/// Simulates and plans every scene with each of `configs`; returns one
/// outcome list per config. Scenes are rendered once, made into `variant`
/// (the truth stays in the camera frame, mm, where plans are scored) and
/// shared. Scenes run one at a time; each plan uses the whole rayon pool.
pub fn run_suite(
    scenes: &[(String, SceneSpec)],
    camera: &CameraModel,
    variant: &Variant,
    configs: &[Config],
    mut progress: impl FnMut(usize, &[SceneOutcome]),
) -> Vec<Vec<SceneOutcome>> {
    let planners: Vec<Planner> = configs.iter().cloned().map(Planner::new).collect();
    let mut out: Vec<Vec<SceneOutcome>> = vec![Vec::new(); planners.len()];
    for (k, (name, spec)) in scenes.iter().enumerate() {
        let rendered = simulate(spec, camera);
        let sim = if variant.is_raw() { rendered } else { variant.apply(&rendered, spec.seed) };
        let outcomes: Vec<SceneOutcome> =
            planners.iter().map(|p| evaluate_variant(p, name, spec, &sim, variant)).collect();
        progress(k, &outcomes);
        for (list, o) in out.iter_mut().zip(outcomes) {
            list.push(o);
        }
    }
    out
}

/// Per-joint summary figures.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Summary {
    pub scenes: usize,
    pub found: usize,
    pub passed: usize,
    pub worst_max_mm: f64,
    pub mean_max_mm: f64,
    pub worst_end_mm: f64,
    pub median_total_ms: f64,
}

/// Summarises outcomes (all of one joint type, or all).
pub fn summarise<'a>(outcomes: impl IntoIterator<Item = &'a SceneOutcome>) -> Summary {
    let mut s = Summary::default();
    let mut maxes = Vec::new();
    let mut totals = Vec::new();
    for o in outcomes {
        s.scenes += 1;
        if let Ok((e, plan)) = &o.result {
            s.found += 1;
            s.passed += e.passes() as usize;
            maxes.push(e.max_mm);
            s.worst_end_mm = s.worst_end_mm.max(e.start_mm).max(e.end_mm);
            totals.push(plan.timings.total_ms());
        }
    }
    s.worst_max_mm = maxes.iter().copied().fold(0.0, f64::max);
    s.mean_max_mm = if maxes.is_empty() { 0.0 } else { maxes.iter().sum::<f64>() / maxes.len() as f64 };
    totals.sort_by(f64::total_cmp);
    s.median_total_ms = totals.get(totals.len() / 2).copied().unwrap_or(0.0);
    s
}
