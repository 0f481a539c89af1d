//! Accuracy against ground truth, as the paper measures it (section 5.2):
//! twelve points evenly spaced on the true seam, end to end, each one's
//! distance to the planned trajectory; plus how far the trajectory's ends
//! are from the seam's.
//!
//! The paper taught its twelve points by hand; here they come from the
//! simulator's geometry, in the robot base frame, so the figure includes
//! the hand-eye and pose transform exactly as a robot would follow it.
//!
//! Each scene's outcome is also judged against its right answer (issue
//! 12, [`Verdict`]): within the bar, refused (the planner said why), or a
//! confident wrong seam (one returned that is no right answer: off the
//! bar, or any seam where the wrong joint was requested), counted apart
//! as the worst outcome. The scene's faults decide what is right
//! (`sim::faults`: the whole seam, a piece of it beside what hides it, or
//! only a refusal).
//!
//! Frames of issue 15 hold more seams than one: a tee's two fillet roots,
//! or the seams of several workpieces. What the planner returns is judged
//! against every seam the frame shows ([`TrueSeam`]): on a tee, each seam
//! returned must lie on a root, within issue 15's bar for a fillet (0.5 mm
//! across, its ends within 1 mm of the root's, or of a stretch of it the
//! camera sees), else it is confident wrong; a root the camera sees along
//! half its length and no seam found is missed, and one it does not see
//! is to be reported as not planned, never invented ([`classify_tee`]); a
//! seam named another joint than the scene's, or any seam on an outside
//! corner (whose weld is refused by name), is confident wrong wherever it
//! lies ([`classify_one_workpiece`]);
//! on several workpieces each seam returned is matched to the nearest true
//! seam, and the seams seen are counted found, missed or extra
//! ([`match_seams`], [`classify_several`]).

pub mod along_seam;
pub mod blocks;
pub mod process;
pub mod real_scans;
mod rule_counts;
pub mod web_near_edge;

pub use rule_counts::{RuleCounts, count_rules};

use crate::camera::CameraModel;
use crate::config::{Config, Method};
use crate::geometry::{Vec3, distance_to_polyline};
use crate::joint::{JointSet, JointType, RequestedJoint};
use crate::pipeline::input::{CloudFrame, Units};
use crate::pipeline::{Plan, PlanError, PlanRequest, Planner, Seam};
use crate::sim::variants::Variant;
use crate::sim::{CornerKind, GroundTruth, SceneSpec, SeamTruth, Simulation, simulate};

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
    /// The largest distance of a waypoint from the true stretch's line: how
    /// far across it the trajectory strays, whatever its ends (a waypoint
    /// past an end is judged by the end's error, not counted again here).
    pub across_mm: f64,
}

/// Issue 15's bar for a fillet root: found within 0.5 mm across, its ends
/// within 1 mm.
pub const FILLET_ACROSS_MM: f64 = 0.5;
pub const FILLET_END_MM: f64 = 1.0;

impl SeamError {
    /// The paper's bar (1 mm) and ours for the ends (2 mm).
    pub fn passes(&self) -> bool {
        self.max_mm < 1.0 && self.start_mm < 2.0 && self.end_mm < 2.0
    }

    /// Issue 15's bar for a fillet root ([`FILLET_ACROSS_MM`],
    /// [`FILLET_END_MM`]).
    pub fn passes_fillet(&self) -> bool {
        self.across_mm < FILLET_ACROSS_MM && self.start_mm < FILLET_END_MM && self.end_mm < FILLET_END_MM
    }

    /// The largest of the error across and the ends' errors, mm: how far a
    /// trajectory is from lying on a stretch, end to end.
    fn largest_mm(&self) -> f64 {
        self.across_mm.max(self.start_mm).max(self.end_mm)
    }
}

/// Compares a planned seam with the truth, both in the robot base frame.
pub fn seam_error(truth: &GroundTruth, seam: &Seam) -> Option<SeamError> {
    path_error(truth, &trajectory(seam))
}

/// A seam's trajectory: its waypoints' positions, in order.
fn trajectory(seam: &Seam) -> Vec<Vec3> {
    seam.waypoints.iter().map(|w| w.position).collect()
}

/// Compares a trajectory (base-frame waypoint positions, in order) with
/// the truth.
pub fn path_error(truth: &GroundTruth, path: &[Vec3]) -> Option<SeamError> {
    segment_error(&[truth.start_base, truth.end_base], path)
}

/// Compares a trajectory with a straight stretch of seam from `ends[0]`
/// to `ends[1]` (robot base frame), as [`path_error`] does with the whole.
pub fn segment_error(ends: &[Vec3; 2], path: &[Vec3]) -> Option<SeamError> {
    let (first, last) = (path.first()?, path.last()?);
    let [start, end] = ends;
    let distances: Vec<f64> = (0..REFERENCE_POINTS)
        .map(|k| {
            let t = k as f64 / (REFERENCE_POINTS - 1) as f64;
            let p = start + (end - start) * t;
            distance_to_polyline(&p, path)
        })
        .collect();
    let direct = ((first - start).norm(), (last - end).norm());
    let swapped = ((first - end).norm(), (last - start).norm());
    let (start_mm, end_mm) = if direct.0 + direct.1 <= swapped.0 + swapped.1 { direct } else { swapped };
    Some(SeamError {
        max_mm: distances.iter().copied().fold(0.0, f64::max),
        mean_mm: distances.iter().sum::<f64>() / REFERENCE_POINTS as f64,
        start_mm,
        end_mm,
        across_mm: path.iter().map(|p| distance_to_line(p, start, end)).fold(0.0, f64::max),
    })
}

/// The distance of `p` from the line through `a` and `b` (from `a` when
/// they coincide).
fn distance_to_line(p: &Vec3, a: &Vec3, b: &Vec3) -> f64 {
    match (b - a).try_normalize(1e-12) {
        Some(u) => {
            let v = p - a;
            (v - u * v.dot(&u)).norm()
        }
        None => (p - a).norm(),
    }
}

/// How each scene's plan is requested: its own joint type (as a person
/// would name it), `auto`, or a wrong type on purpose; the groove depth
/// given, or left to be measured.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EvalRequest {
    pub joint: JointAsk,
    pub groove_depth: DepthAsk,
}

/// The joint a scene's plan request names.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum JointAsk {
    /// The scene's own (or, for a wrong-joint fault, the fault's).
    #[default]
    AsScene,
    /// `auto`: the planner decides; a wrong-joint fault then asks nothing
    /// wrong, and the seam must name the scene's joint.
    Auto,
    /// The type `k` places after the scene's in [`JointType::ALL`] (1 or
    /// 2): the wrong joint, whose only right answer is a refusal.
    Wrong(usize),
    /// This type for every scene, and every workpiece of a frame of
    /// several (issue 15: a type requested applies to each), the groove
    /// depth left to be measured: a scene of another type is only to be
    /// refused, and on several workpieces only the seams of this type
    /// are to be found.
    Type(JointType),
    /// These types for every scene, decided among by the planner (a
    /// fixture's list): as [`JointAsk::Type`], with every type of the set
    /// to be found and a scene of a type outside it only to be refused.
    Set(JointSet),
}

/// The groove depth a V-butt request gives.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DepthAsk {
    /// The scene's depth (or a plausible wrong one for a wrong V-butt).
    #[default]
    Given,
    /// None: the planner measures it.
    Measured,
}

impl EvalRequest {
    /// The joint requested for `spec`.
    pub fn joint_for(&self, spec: &SceneSpec) -> RequestedJoint {
        match self.joint {
            JointAsk::AsScene => spec.requested_joint().into(),
            JointAsk::Auto => RequestedJoint::Auto,
            JointAsk::Wrong(k) => {
                let own = JointType::ALL.iter().position(|j| *j == spec.joint.joint_type()).unwrap_or(0);
                JointType::ALL[(own + k) % JointType::ALL.len()].into()
            }
            JointAsk::Type(joint) => joint.into(),
            JointAsk::Set(set) => RequestedJoint::one_of(set).unwrap_or(RequestedJoint::Auto),
        }
    }

    /// The groove depth requested for `spec`.
    pub fn groove_depth_for(&self, spec: &SceneSpec) -> Option<f64> {
        match (self.groove_depth, self.joint_for(spec)) {
            (DepthAsk::Measured, _) | (_, RequestedJoint::Auto | RequestedJoint::OneOf(_)) => None,
            _ if matches!(self.joint, JointAsk::Type(_) | JointAsk::Set(_)) => None,
            (DepthAsk::Given, RequestedJoint::Type(joint)) => spec.groove_depth_requested_as(joint),
        }
    }

    /// The scene's right answer under this request: a wrong joint asked
    /// on purpose is only to be refused; `auto` asks nothing wrong.
    fn right_answer(&self, spec: &SceneSpec, sim: &Simulation) -> ScoredAnswer {
        let mut answer = ScoredAnswer::of(spec, sim);
        match self.joint {
            JointAsk::Wrong(_) => answer.refuse = true,
            JointAsk::Type(joint) if joint != spec.joint.joint_type() => answer.refuse = true,
            JointAsk::Set(set) if !set.contains(spec.joint.joint_type()) => answer.refuse = true,
            JointAsk::Auto if spec.faults.iter().all(|f| f.kind() == crate::sim::faults::FaultKind::WrongJoint) => {
                answer.refuse = false;
                answer.whole_allowed = true;
            }
            _ => {}
        }
        answer
    }
}

/// What happened to one scene.
#[derive(Debug, Clone)]
pub struct SceneOutcome {
    pub name: String,
    /// The joint the plan request named.
    pub requested: RequestedJoint,
    /// The method that planned it.
    pub method: Method,
    pub spec: SceneSpec,
    pub truth: GroundTruth,
    /// The error against the truth and the plan it was measured on.
    pub result: Result<(SeamError, Plan), PlanError>,
    /// The outcome as issue 12 counts it, against the scene's right
    /// answer (which its faults decide).
    pub verdict: Verdict,
    /// On a tee or several workpieces: every true seam, and the seams
    /// returned matched to them.
    pub seams: Option<(Vec<TrueSeam>, SeamMatches)>,
}

/// One scene's outcome against its right answer.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Every seam returned meets the bar against the seam, or against a
    /// piece of it where the scene's faults allow pieces.
    WithinBar,
    /// No seam: the planner said why.
    Refused { reason: String },
    /// A seam returned (the planner exits 0) that is not a right answer:
    /// the worst outcome, counted apart. `error` is the seam's error
    /// against the nearest right answer (or the whole seam).
    ConfidentWrong { error: Option<SeamError>, why: String },
}

impl Verdict {
    /// `within the bar`, `refused` or `confident wrong`.
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::WithinBar => "within the bar",
            Verdict::Refused { .. } => "refused",
            Verdict::ConfidentWrong { .. } => "confident wrong",
        }
    }
}

/// A scene's right answer in the robot base frame, where plans are scored.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoredAnswer {
    /// Only a refusal is right.
    pub refuse: bool,
    /// The observed seam's ends.
    pub whole: [Vec3; 2],
    /// The whole seam is a right answer.
    pub whole_allowed: bool,
    /// The ends of the pieces a seam may be returned for instead.
    pub pieces: Vec<[Vec3; 2]>,
    /// Judged by the fillet root's bar ([`SeamError::passes_fillet`]), not
    /// the paper's.
    pub fillet: bool,
}

impl ScoredAnswer {
    fn passes(&self, e: &SeamError) -> bool {
        if self.fillet { e.passes_fillet() } else { e.passes() }
    }
}

impl ScoredAnswer {
    /// The right answer of a simulated scene, in the base frame.
    pub fn of(spec: &SceneSpec, sim: &Simulation) -> Self {
        let seam_z = spec.joint.seam_z();
        let at = |y: f64| spec.base_from_workpiece.transform_point(&Vec3::new(0.0, y, seam_z).into()).coords;
        ScoredAnswer {
            refuse: sim.answer.refuse,
            whole: [sim.truth.start_base, sim.truth.end_base],
            whole_allowed: sim.answer.whole_seam,
            pieces: sim.answer.pieces_mm.iter().map(|[a, b]| [at(*a), at(*b)]).collect(),
            fillet: false,
        }
    }
}

/// Classifies what the planner gave for a scene: the trajectories of the
/// seams it returned (base-frame waypoint positions), or why it refused.
pub fn classify(answer: &ScoredAnswer, planned: Result<&[Vec<Vec3>], &str>) -> Verdict {
    let paths = match planned {
        Err(reason) => return Verdict::Refused { reason: reason.to_string() },
        Ok([]) => return Verdict::Refused { reason: "no seam".into() },
        Ok(paths) => paths,
    };
    let whole_errors: Vec<Option<SeamError>> = paths.iter().map(|p| segment_error(&answer.whole, p)).collect();
    if answer.refuse {
        let why = "a seam returned for a joint the scene does not show".to_string();
        return Verdict::ConfidentWrong { error: whole_errors[0], why };
    }
    for (path, whole) in paths.iter().zip(&whole_errors) {
        let whole_passes = whole.is_some_and(|e| answer.passes(&e));
        if answer.whole_allowed && whole_passes {
            continue;
        }
        let piece_errors: Vec<SeamError> = answer.pieces.iter().filter_map(|ends| segment_error(ends, path)).collect();
        if piece_errors.iter().any(|e| answer.passes(e)) {
            continue;
        }
        // The nearest right answer: the one the seam misses by the least,
        // each figure against its own bar (1 mm across, 2 mm at the ends).
        let miss = |e: &SeamError| e.max_mm.max(e.start_mm / 2.0).max(e.end_mm / 2.0);
        let nearest = piece_errors.iter().chain(answer.whole_allowed.then_some(whole.as_ref()).flatten());
        let error = nearest.min_by(|a, b| miss(a).total_cmp(&miss(b))).copied().or(*whole);
        let why = if answer.whole_allowed || answer.pieces.is_empty() {
            "the seam misses the bar"
        } else {
            "the seam matches no piece of the seam in view"
        };
        return Verdict::ConfidentWrong { error, why: why.to_string() };
    }
    Verdict::WithinBar
}

/// One seam of a frame as the tee and several-workpiece judging sees it,
/// in the robot base frame.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueSeam {
    /// `workpiece 2 lap`, `workpiece 1 t-fillet root -x`.
    pub label: String,
    pub joint: JointType,
    /// Its stretch in the image.
    pub whole: [Vec3; 2],
    /// The stretches the camera sees.
    pub seen: Vec<[Vec3; 2]>,
    /// Their length over the seam's whole length.
    pub seen_share: f64,
    /// The camera sees at least half of it: a planner is to find it.
    pub seen_enough: bool,
}

impl TrueSeam {
    pub fn of(spec: &SceneSpec, seam: &SeamTruth) -> Self {
        TrueSeam {
            label: seam.label(),
            joint: seam.truth.joint,
            whole: [seam.truth.start_base, seam.truth.end_base],
            seen: seam.seen_base(spec),
            seen_share: seam.seen_share,
            seen_enough: seam.is_seen(),
        }
    }

    /// A trajectory against this seam: within the bar of the whole seam
    /// (when enough of it is seen) or of a stretch seen, or the error
    /// against the nearest of them. A fillet root's bar is issue 15's
    /// ([`SeamError::passes_fillet`]).
    fn judge(&self, path: &[Vec3]) -> Verdict {
        let answer = ScoredAnswer {
            refuse: false,
            whole: self.whole,
            whole_allowed: self.seen_enough,
            pieces: self.seen.clone(),
            fillet: self.joint == JointType::TFillet,
        };
        classify(&answer, Ok(std::slice::from_ref(&path.to_vec())))
    }
}

impl TrueSeam {
    /// A trajectory's error against this seam: against the whole seam
    /// (when enough of it is seen) or the stretch seen it misses by the
    /// least.
    pub fn best_error(&self, path: &[Vec3]) -> Option<SeamError> {
        let whole = self.seen_enough.then(|| segment_error(&self.whole, path)).flatten();
        let pieces = self.seen.iter().filter_map(|ends| segment_error(ends, path));
        whole.into_iter().chain(pieces).min_by(|a, b| a.largest_mm().total_cmp(&b.largest_mm()))
    }

    /// The seam of `truths` a trajectory lies nearest, and its error
    /// against it ([`TrueSeam::best_error`]).
    pub fn nearest<'a>(truths: &'a [TrueSeam], path: &[Vec3]) -> Option<(&'a TrueSeam, SeamError)> {
        truths
            .iter()
            .filter_map(|t| t.best_error(path).map(|e| (t, e)))
            .min_by(|a, b| a.1.largest_mm().total_cmp(&b.1.largest_mm()))
    }
}

/// How far a verdict's seam misses its bar: each figure against its own
/// (1 mm across, 2 mm at the ends); infinite without an error.
fn miss(verdict: &Verdict) -> f64 {
    match verdict {
        Verdict::ConfidentWrong { error: Some(e), .. } => e.max_mm.max(e.start_mm / 2.0).max(e.end_mm / 2.0),
        Verdict::WithinBar => 0.0,
        _ => f64::INFINITY,
    }
}

/// Whether a refusal's reason names a tee joint.
pub fn names_a_tee(reason: &str) -> bool {
    let reason = reason.to_ascii_lowercase();
    ["tee joint", "t_fillet", "t-fillet", "t-joint"].iter().any(|name| reason.contains(name))
}

/// Whether a refusal's reason names a corner joint.
pub fn names_a_corner(reason: &str) -> bool {
    reason.contains("corner joint")
}

/// A tee scene's outcome: a refusal is a refusal (whether it names the tee
/// is [`names_a_tee`]'s to say); a seam is right only within the fillet's
/// bar on a root (the whole root, or a stretch of it the camera sees),
/// else confident wrong, reported against the nearest root; a seam on a
/// root the camera does not see is invented, and so confident wrong.
pub fn classify_tee(roots: &[TrueSeam], planned: Result<&[Vec<Vec3>], &str>) -> Verdict {
    let paths = match planned {
        Err(reason) => return Verdict::Refused { reason: reason.to_string() },
        Ok([]) => return Verdict::Refused { reason: "no seam".into() },
        Ok(paths) => paths,
    };
    for path in paths {
        let verdicts: Vec<Verdict> = roots.iter().map(|root| root.judge(path)).collect();
        if verdicts.contains(&Verdict::WithinBar) {
            continue;
        }
        let error = verdicts.iter().min_by(|a, b| miss(a).total_cmp(&miss(b))).and_then(|v| match v {
            Verdict::ConfidentWrong { error, .. } => *error,
            _ => None,
        });
        return Verdict::ConfidentWrong { error, why: "a seam on no root of the tee".into() };
    }
    Verdict::WithinBar
}

/// A seam returned, matched to a true one within the bar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeamMatch {
    /// Index into the seams returned, and into the true seams.
    pub returned: usize,
    pub truth: usize,
}

/// The seams returned for a frame of several seams against the true ones.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeamMatches {
    /// Returned seams within the bar of a true seam, each true seam once.
    pub found: Vec<SeamMatch>,
    /// True seams seen (at least half their length) that no seam found.
    pub missed: Vec<usize>,
    /// Returned seams matching no true seam (or one already found).
    pub extra: Vec<ExtraSeam>,
    /// Found seams whose joint type is not their true seam's.
    pub wrong_type: Vec<SeamMatch>,
    /// The true seams seen.
    pub seen: usize,
}

/// A returned seam on no true seam: its index, the nearest true seam and
/// the error against it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtraSeam {
    pub returned: usize,
    pub nearest: Option<usize>,
    pub error: Option<SeamError>,
}

/// Matches each returned seam (its trajectory and joint type) to the
/// nearest true seam within the bar that no earlier one took.
pub fn match_seams(truths: &[TrueSeam], returned: &[(Vec<Vec3>, JointType)]) -> SeamMatches {
    let mut m = SeamMatches { seen: truths.iter().filter(|t| t.seen_enough).count(), ..SeamMatches::default() };
    let mut taken = vec![false; truths.len()];
    for (r, (path, joint)) in returned.iter().enumerate() {
        let verdicts: Vec<Verdict> = truths.iter().map(|t| t.judge(path)).collect();
        let nearest_free =
            (0..truths.len()).filter(|t| !taken[*t] && verdicts[*t] == Verdict::WithinBar).min_by(|a, b| {
                let error = |t: usize| segment_error(&truths[t].whole, path).map_or(f64::INFINITY, |e| e.mean_mm);
                error(*a).total_cmp(&error(*b))
            });
        match nearest_free {
            Some(t) => {
                taken[t] = true;
                let found = SeamMatch { returned: r, truth: t };
                m.found.push(found);
                if truths[t].joint != *joint {
                    m.wrong_type.push(found);
                }
            }
            None => {
                let nearest = (0..truths.len()).min_by(|a, b| miss(&verdicts[*a]).total_cmp(&miss(&verdicts[*b])));
                let error = match nearest.map(|t| &verdicts[t]) {
                    Some(Verdict::ConfidentWrong { error, .. }) => *error,
                    // Within the bar of a seam an earlier one took.
                    _ => nearest.and_then(|t| segment_error(&truths[t].whole, path)),
                };
                m.extra.push(ExtraSeam { returned: r, nearest, error });
            }
        }
    }
    m.missed = (0..truths.len()).filter(|t| truths[*t].seen_enough && !taken[*t]).collect();
    m
}

/// A several-workpiece scene's outcome: refused, confident wrong when a
/// seam matches no true seam or names another joint than its own, else
/// within the bar (seams missed are counted in [`SeamMatches`], not here).
pub fn classify_several(matches: Result<&SeamMatches, &str>, truths: &[TrueSeam]) -> Verdict {
    let m = match matches {
        Err(reason) => return Verdict::Refused { reason: reason.to_string() },
        Ok(m) if m.found.is_empty() && m.extra.is_empty() => return Verdict::Refused { reason: "no seam".into() },
        Ok(m) => m,
    };
    if let Some(extra) = m.extra.first() {
        let nearest = extra.nearest.map_or(String::new(), |t| format!(" (the nearest is the {})", truths[t].label));
        let why = format!("a seam on no seam of the frame, or on one found already{nearest}");
        return Verdict::ConfidentWrong { error: extra.error, why };
    }
    if let Some(w) = m.wrong_type.first() {
        let why = format!("a seam of another joint type returned on the {}", truths[w.truth].label);
        return Verdict::ConfidentWrong { error: None, why };
    }
    Verdict::WithinBar
}

impl SceneOutcome {
    pub fn passes(&self) -> bool {
        matches!(&self.result, Ok((e, _)) if e.passes())
    }
}

/// Plans a simulated scene and measures the result.
pub fn evaluate_simulation(planner: &Planner, name: &str, spec: &SceneSpec, sim: &Simulation) -> SceneOutcome {
    evaluate_variant(planner, name, spec, sim, &Variant::default(), &EvalRequest::default())
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
    ask: &EvalRequest,
) -> SceneOutcome {
    // The planner's log lines name the scene they are about.
    let _scene = tracing::info_span!("scene", name).entered();
    let requested = ask.joint_for(spec);
    let mut request = PlanRequest::new(requested, ask.groove_depth_for(spec), sim.pose);
    if !variant.is_raw() {
        request.units = Units::Auto;
    }
    if variant.in_base_frame() {
        request.cloud_frame = CloudFrame::Base;
    }
    let result = planner.plan(&sim.cloud, &request).and_then(|plan| {
        // A plan holds a seam of two waypoints at least: the planner
        // refuses a frame with none (`workpiece.none_in_view`), as here.
        let err = plan.seams.first().and_then(|seam| seam_error(&sim.truth, seam)).ok_or_else(|| {
            PlanError::by(&crate::rules::background::NO_WORKPIECE_IN_VIEW, "the plan holds no seam with a waypoint")
        })?;
        Ok((err, plan))
    });
    let several_seams = spec.joint.joint_type() == JointType::TFillet || !spec.others.is_empty();
    let returned: Vec<(Vec<Vec3>, JointType)> = match &result {
        Ok((_, plan)) => plan.seams.iter().map(|s| (trajectory(s), s.joint)).collect(),
        Err(_) => Vec::new(),
    };
    let seams = several_seams.then(|| {
        let truths: Vec<TrueSeam> = sim.seams.iter().map(|s| TrueSeam::of(spec, s)).collect();
        let matches = match_seams(&truths, &returned);
        (truths, matches)
    });
    let answer = ask.right_answer(spec, sim);
    let verdict = match (&result, &seams) {
        (Err(e), Some(_)) => Verdict::Refused { reason: e.to_string() },
        (Ok(_), Some((truths, _))) if spec.others.is_empty() => classify_one_workpiece(spec, truths, &returned),
        (Ok(_), Some((truths, matches))) => classify_several(Ok(matches), truths),
        (result, None) => plain_verdict(result, spec, sim, &answer),
    };
    SceneOutcome {
        name: name.to_string(),
        requested,
        method: planner.config().pipeline.method,
        spec: spec.clone(),
        truth: sim.truth.clone(),
        result,
        verdict,
        seams,
    }
}

/// A tee's or a corner's outcome, from the seams returned and their joint
/// types: a seam named another joint type is welded with the wrong torch
/// path wherever it lies, and an outside corner's weld is one the planner
/// does not plan (it is refused by name), so any seam returned on one is
/// confident wrong; else [`classify_tee`].
pub fn classify_one_workpiece(spec: &SceneSpec, truths: &[TrueSeam], returned: &[(Vec<Vec3>, JointType)]) -> Verdict {
    let scene_joint = spec.joint.joint_type();
    let wrong = |path: &[Vec3], why: String| Verdict::ConfidentWrong {
        error: TrueSeam::nearest(truths, path).map(|(_, error)| error),
        why,
    };
    if let (Some((path, joint)), Some(CornerKind::Outside)) = (returned.first(), spec.joint.corner_kind()) {
        return wrong(path, format!("a seam named {joint} returned for an outside corner, whose weld is not planned"));
    }
    if let Some((path, joint)) = returned.iter().find(|(_, joint)| *joint != scene_joint) {
        return wrong(path, format!("a seam named {joint} returned for a {scene_joint} joint"));
    }
    let paths: Vec<Vec<Vec3>> = returned.iter().map(|(path, _)| path.clone()).collect();
    classify_tee(truths, Ok(&paths))
}

/// A scene of one seam's outcome against its right answer.
fn plain_verdict(
    result: &Result<(SeamError, Plan), PlanError>,
    spec: &SceneSpec,
    sim: &Simulation,
    answer: &ScoredAnswer,
) -> Verdict {
    match result {
        Ok((_, plan)) => {
            let paths: Vec<Vec<Vec3>> = plan.seams.iter().map(trajectory).collect();
            let scene_joint = spec.joint.joint_type();
            match plan.seams.iter().find(|s| s.joint != scene_joint) {
                // A seam of another joint type is welded with the wrong
                // torch path, wherever it lies.
                Some(other) if !answer.refuse => Verdict::ConfidentWrong {
                    error: seam_error(&sim.truth, other),
                    why: format!("a seam named {} returned for a {scene_joint} joint", other.joint),
                },
                _ => classify(answer, Ok(&paths)),
            }
        }
        Err(e) => classify(answer, Err(&e.to_string())),
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
    progress: impl FnMut(usize, &[SceneOutcome]),
) -> Vec<Vec<SceneOutcome>> {
    run_suite_asking(scenes, camera, variant, configs, &EvalRequest::default(), progress)
}

/// [`run_suite`] with each plan requested as `ask` says.
pub fn run_suite_asking(
    scenes: &[(String, SceneSpec)],
    camera: &CameraModel,
    variant: &Variant,
    configs: &[Config],
    ask: &EvalRequest,
    mut progress: impl FnMut(usize, &[SceneOutcome]),
) -> Vec<Vec<SceneOutcome>> {
    let planners: Vec<Planner> = configs.iter().cloned().map(Planner::new).collect();
    let mut out: Vec<Vec<SceneOutcome>> = vec![Vec::new(); planners.len()];
    for (k, (name, spec)) in scenes.iter().enumerate() {
        let rendered = simulate(spec, camera);
        let sim = if variant.is_raw() { rendered } else { variant.apply(&rendered, spec.seed) };
        let outcomes: Vec<SceneOutcome> =
            planners.iter().map(|p| evaluate_variant(p, name, spec, &sim, variant, ask)).collect();
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

/// How many outcomes were within the bar, refused and confidently wrong.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct VerdictCounts {
    pub scenes: usize,
    pub within_bar: usize,
    pub refused: usize,
    pub confident_wrong: usize,
}

/// Counts the verdicts of `outcomes`.
pub fn count_verdicts<'a>(outcomes: impl IntoIterator<Item = &'a SceneOutcome>) -> VerdictCounts {
    let mut c = VerdictCounts::default();
    for o in outcomes {
        c.scenes += 1;
        match o.verdict {
            Verdict::WithinBar => c.within_bar += 1,
            Verdict::Refused { .. } => c.refused += 1,
            Verdict::ConfidentWrong { .. } => c.confident_wrong += 1,
        }
    }
    c
}

#[cfg(test)]
mod tests;
