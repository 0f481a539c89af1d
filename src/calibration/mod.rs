//! Hand-eye calibration: `End_T_Camera` (the paper's Eq. 39 to 42 carry
//! every waypoint through it) from the robot's poses and what the camera
//! saw, or `Base_T_Camera` for a camera fixed in the cell. Pure
//! computation: the captures come in as poses and centres, the result
//! goes out as numbers; reading files and printing are the CLI's.
//!
//! Two kinds of observation:
//! - a target's pose per capture (`Camera_T_Target`, as a board detector
//!   gives it): the target is fixed, so `A_i X B_i = Y` for every capture
//!   `i`, with `A_i = Base_T_End_i`, `X = End_T_Camera`, `B_i =
//!   Camera_T_Target_i` and `Y = Base_T_Target` unknown;
//! - the centres of calibration spheres fixed in the cell, fitted in each
//!   capture's cloud ([`sphere`]): `A_i X c_ij = s_j` with the spheres'
//!   base-frame centres `s_j` unknown.
//!
//! For a camera fixed in the cell (eye-to-hand) the target or the spheres
//! ride on the flange, and the same equations hold with `A_i =
//! End_T_Base_i` (the inverse pose), `X = Base_T_Camera` and `Y` or `s_j`
//! in the flange frame: [`Mount::hand`].
//!
//! The solution runs in four steps, each in its module:
//! 1. a closed-form start ([`closed_form`]: Tsai-Lenz and Park-Martin on
//!    every pair of target captures; for spheres, the linear least
//!    squares of `A_i X c_ij = s_j` in `X`'s nine rotation entries, its
//!    translation and the centres, the rotation then projected on SO(3));
//! 2. a joint refinement over all captures ([`refine`]: rotation and
//!    translation together, Levenberg-Marquardt on a rotation vector, a
//!    Huber loss per capture);
//! 3. outliers: a capture whose residual is far above the others' (a pose
//!    paired with the wrong capture) is removed, one at a time, and the
//!    solution recomputed without it;
//! 4. the report: per-capture residuals, the pose set's conditioning
//!    ([`conditioning`]), and the expected error at the working distance
//!    from the refinement's covariance.

pub mod closed_form;
pub mod conditioning;
pub mod gate;
pub mod naming;
pub mod prediction;
pub mod refine;
pub mod sphere;

use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use self::closed_form::{ClosedForm, procrustes};
use self::conditioning::Conditioning;
use self::refine::{Blocks, RefineError};
use crate::geometry::Vec3;

/// The most captures a set may hold: far more than any calibration needs
/// (15 to 30), and every pair of them is a motion of the closed forms.
pub const MAX_CAPTURES: usize = 500;

/// The fewest captures: two motions with different rotation axes.
pub const MIN_CAPTURES: usize = 3;

/// The nominal noise of a target capture's residual, one sigma: the
/// robot's repeatability (0.05 mm, 0.01°) carried over the arm to the
/// target, and a board detector's pose noise. Only their ratio weighs
/// translation against rotation; the covariance is scaled by the
/// residuals themselves.
pub const TARGET_TRANSLATION_SIGMA_MM: f64 = 0.2;
/// See [`TARGET_TRANSLATION_SIGMA_MM`].
pub const TARGET_ROTATION_SIGMA_DEG: f64 = 0.03;
/// The nominal noise of a sphere centre's residual in the base frame.
pub const SPHERE_SIGMA_MM: f64 = 0.2;

/// A capture is an outlier when its residual (in units of the nominal
/// noise) is above this multiple of the median capture's...
pub const OUTLIER_OVER_MEDIAN: f64 = 4.0;
/// ...and above this many nominal sigmas, so a set fitting to microns
/// does not call its worst capture an outlier.
pub const OUTLIER_FLOOR_SIGMAS: f64 = 3.0;
/// At most this fraction of the captures is removed as outliers.
pub const MAX_OUTLIER_FRACTION: f64 = 0.25;

/// An expected error above this at the working distance is warned about.
pub const EXPECTED_ERROR_WARN_MM: f64 = 0.5;
/// A result whose own translation or rotation is this uncertain (one
/// sigma) is warned about: the bound for a calibration.
pub const HAND_EYE_SIGMA_WARN_MM: f64 = 0.2;
/// See [`HAND_EYE_SIGMA_WARN_MM`].
pub const HAND_EYE_SIGMA_WARN_DEG: f64 = 0.05;

/// Where the camera is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mount {
    /// On the flange (the paper's cell): the result is `End_T_Camera`.
    #[default]
    EyeInHand,
    /// Fixed in the cell, the target on the flange: `Base_T_Camera`.
    EyeToHand,
}

impl Mount {
    /// The pose `A_i` the equations take for a flange pose `Base_T_End`.
    pub fn hand(self, base_t_end: &Isometry3<f64>) -> Isometry3<f64> {
        match self {
            Mount::EyeInHand => *base_t_end,
            Mount::EyeToHand => base_t_end.inverse(),
        }
    }

    /// The transform solved for, as the report names it.
    pub fn solved_for(self) -> &'static str {
        match self {
            Mount::EyeInHand => "End_T_Camera",
            Mount::EyeToHand => "Base_T_Camera",
        }
    }
}

/// One capture with a target pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetCapture {
    pub base_t_end: Isometry3<f64>,
    pub camera_t_target: Isometry3<f64>,
}

/// One capture of calibration spheres: each given sphere's centre in the
/// camera frame (mm), `None` where it was not seen or not named.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereCapture {
    pub base_t_end: Isometry3<f64>,
    pub centres: Vec<Option<Vec3>>,
}

/// One capture's residual against the result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureResidual {
    pub capture: usize,
    /// Target captures: how far the target appears from where the others
    /// put it. Sphere captures: the RMS distance of its sphere centres
    /// from the spheres' fitted positions.
    pub translation_mm: f64,
    /// The target's rotation likewise; for spheres, the rotation of the
    /// capture's centres against the fitted ones, when it saw three or
    /// more.
    pub rotation_deg: Option<f64>,
}

/// A calibration's result and everything the report says about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    pub mount: Mount,
    /// `End_T_Camera`, or `Base_T_Camera` for [`Mount::EyeToHand`],
    /// computed without the outliers.
    pub hand_eye: Isometry3<f64>,
    /// How it was found: the closed form that started the refinement.
    pub method: String,
    /// The closed forms' own answers on the inliers, for comparison.
    pub closed_forms: Vec<NamedStart>,
    /// Every capture's residual against `hand_eye`, outliers included.
    pub residuals: Vec<CaptureResidual>,
    /// The captures left out, in the order they were removed.
    pub outliers: Vec<usize>,
    /// The result with every capture, when outliers were removed.
    pub hand_eye_with_outliers: Option<Isometry3<f64>>,
    pub conditioning: Conditioning,
    pub warnings: Vec<String>,
    /// The median camera-to-target (or sphere) distance, mm.
    pub working_distance_mm: f64,
    /// One-sigma RMS error of a point at the working distance on the
    /// camera's axis, carried into the flange (or base) frame by the
    /// result, mm; `None` when the captures do not determine it.
    pub expected_error_mm: Option<f64>,
    /// One-sigma uncertainty of the result's translation (mm) and
    /// rotation (degrees), from the same covariance.
    pub translation_sigma_mm: Option<f64>,
    pub rotation_sigma_deg: Option<f64>,
}

/// Why no calibration was computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    #[error("{found} captures; at least {MIN_CAPTURES} are needed")]
    TooFewCaptures { found: usize },
    #[error("{found} captures; at most {MAX_CAPTURES} are accepted")]
    TooManyCaptures { found: usize },
    #[error(
        "the captures do not determine the hand-eye: their rotations are too small or all about one axis \
         ({largest_rotation_deg:.1} degrees at most, axis spread {axis_spread_deg:.1} degrees); add poses that turn \
         the flange about two different axes by 30 degrees or more"
    )]
    Degenerate { largest_rotation_deg: f64, axis_spread_deg: f64 },
    #[error("sphere {sphere} is seen in {captures} captures; each sphere must be seen in at least two")]
    SphereUnseen { sphere: usize, captures: usize },
    #[error("the refinement failed: {0}")]
    Refine(#[from] RefineError),
}

/// Which of the two problems a capture set is, with what the solver needs
/// of it.
trait Problem {
    fn len(&self) -> usize;
    fn hands(&self) -> Vec<Isometry3<f64>>;
    fn working_distance_mm(&self) -> f64;
    /// Closed-form starts on the captures `use_`, with their names.
    fn starts(&self, use_: &[usize]) -> Vec<NamedStart>;
    /// Refines from `start` on `use_`; the fit can evaluate any capture.
    fn refine(&self, start: &Isometry3<f64>, use_: &[usize]) -> Result<Fit, CalibrationError>;
    /// Capture `i`'s index as the user numbers it.
    fn name(&self, i: usize) -> usize {
        i
    }
}

/// A refined solution on some captures.
#[derive(Debug, Clone)]
struct Fit {
    hand_eye: Isometry3<f64>,
    /// Every capture's residual, and its norm in nominal sigmas.
    residuals: Vec<CaptureResidual>,
    normalised: Vec<f64>,
    /// Covariance of `(δω, δt)` of the hand-eye (radians, mm), if the
    /// captures determine it.
    covariance: Option<nalgebra::Matrix6<f64>>,
    /// The robust cost of the inliers, to pick the better start.
    cost: f64,
}

/// Calibrates from target poses.
pub fn calibrate_targets(captures: &[TargetCapture], mount: Mount) -> Result<Calibration, CalibrationError> {
    check_count(captures.len())?;
    solve(&Targets { captures, mount }, mount)
}

/// Calibrates from sphere centres (`captures[i].centres[j]`: sphere `j`
/// in capture `i`).
pub fn calibrate_spheres(captures: &[SphereCapture], mount: Mount) -> Result<Calibration, CalibrationError> {
    check_count(captures.len())?;
    let spheres = captures.iter().map(|c| c.centres.len()).max().unwrap_or(0);
    for sphere in 0..spheres {
        let seen = captures.iter().filter(|c| c.centres.get(sphere).is_some_and(Option::is_some)).count();
        if seen < 2 {
            return Err(CalibrationError::SphereUnseen { sphere, captures: seen });
        }
    }
    solve(&Spheres { captures, mount, spheres, names: (0..captures.len()).collect() }, mount)
}

/// [`calibrate_spheres`] on the captures where at least one sphere was
/// named; the others (their spheres unseen or not named) are left out, and
/// the result's capture indices are those of `captures`.
pub fn calibrate_named_spheres(captures: &[SphereCapture], mount: Mount) -> Result<Calibration, CalibrationError> {
    let kept: Vec<usize> = (0..captures.len()).filter(|&i| captures[i].centres.iter().any(Option::is_some)).collect();
    let named: Vec<SphereCapture> = kept.iter().map(|&i| captures[i].clone()).collect();
    check_count(named.len())?;
    let spheres = named.iter().map(|c| c.centres.len()).max().unwrap_or(0);
    for sphere in 0..spheres {
        let seen = named.iter().filter(|c| c.centres.get(sphere).is_some_and(Option::is_some)).count();
        if seen < 2 {
            return Err(CalibrationError::SphereUnseen { sphere, captures: seen });
        }
    }
    let mut c = solve(&Spheres { captures: &named, mount, spheres, names: kept.clone() }, mount)?;
    for r in &mut c.residuals {
        r.capture = kept[r.capture];
    }
    for o in &mut c.outliers {
        *o = kept[*o];
    }
    Ok(c)
}

fn check_count(found: usize) -> Result<(), CalibrationError> {
    if found < MIN_CAPTURES {
        return Err(CalibrationError::TooFewCaptures { found });
    }
    if found > MAX_CAPTURES {
        return Err(CalibrationError::TooManyCaptures { found });
    }
    Ok(())
}

/// A closed form's name and its answer.
pub type NamedStart = (&'static str, Isometry3<f64>);

/// The best refined fit on `use_` from any of the closed-form starts.
fn best_fit(problem: &dyn Problem, use_: &[usize]) -> Result<(Fit, String, Vec<NamedStart>), CalibrationError> {
    let starts = problem.starts(use_);
    let mut best: Option<(Fit, &'static str)> = None;
    let mut last_error = None;
    for (name, start) in &starts {
        match problem.refine(start, use_) {
            Ok(fit) if best.as_ref().is_none_or(|(b, _)| fit.cost < b.cost) => best = Some((fit, name)),
            Ok(_) => {}
            Err(e) => last_error = Some(e),
        }
    }
    match best {
        Some((fit, name)) => Ok((fit, name.to_string(), starts)),
        None => Err(last_error.unwrap_or_else(|| degenerate(&problem.hands()))),
    }
}

fn degenerate(hands: &[Isometry3<f64>]) -> CalibrationError {
    let c = Conditioning::of(hands);
    CalibrationError::Degenerate { largest_rotation_deg: c.largest_rotation_deg, axis_spread_deg: c.axis_spread_deg }
}

fn solve(problem: &dyn Problem, mount: Mount) -> Result<Calibration, CalibrationError> {
    let n = problem.len();
    let mut inliers: Vec<usize> = (0..n).collect();
    let (first, first_method, first_starts) = best_fit(problem, &inliers)?;
    let (mut fit, mut method, mut starts) = (first.clone(), first_method, first_starts);
    let mut outliers = Vec::new();
    let max_removed = ((n as f64) * MAX_OUTLIER_FRACTION).floor() as usize;
    while outliers.len() < max_removed && inliers.len() > MIN_CAPTURES {
        let Some(worst) = worst_outlier(&fit, &inliers) else { break };
        let remaining: Vec<usize> = inliers.iter().copied().filter(|&i| i != worst).collect();
        let Ok(next) = best_fit(problem, &remaining) else { break };
        inliers = remaining;
        outliers.push(worst);
        (fit, method, starts) = next;
    }
    let hands = problem.hands();
    let inlier_hands: Vec<Isometry3<f64>> = inliers.iter().map(|&i| hands[i]).collect();
    let conditioning = Conditioning::of(&inlier_hands);
    let mut warnings = conditioning.warnings();
    let working_distance_mm = problem.working_distance_mm();
    let (expected_error_mm, translation_sigma_mm, rotation_sigma_deg) = match fit.covariance {
        Some(cov) => {
            let (e, t, r) = uncertainty(&cov, &fit.hand_eye, working_distance_mm);
            (Some(e), Some(t), Some(r))
        }
        None => {
            warnings.push(
                "the captures do not determine every degree of freedom of the hand-eye (the refinement's normal \
                 matrix is singular); add poses with rotations about other axes"
                    .into(),
            );
            (None, None, None)
        }
    };
    if let (Some(t), Some(r)) = (translation_sigma_mm, rotation_sigma_deg)
        && (t > HAND_EYE_SIGMA_WARN_MM || r > HAND_EYE_SIGMA_WARN_DEG)
    {
        warnings.push(format!(
            "the captures determine the hand-eye only to {t:.2} mm and {r:.3} degrees (one sigma; {HAND_EYE_SIGMA_WARN_MM} \
             mm and {HAND_EYE_SIGMA_WARN_DEG} degrees wanted): the set is ill-posed for its noise; add poses with \
             larger rotations (30 degrees or more) about different axes"
        ));
    }
    if let Some(e) = expected_error_mm.filter(|e| *e > EXPECTED_ERROR_WARN_MM) {
        warnings.push(format!(
            "the expected error at the working distance ({working_distance_mm:.0} mm) is {e:.2} mm, above \
             {EXPECTED_ERROR_WARN_MM} mm: add captures, with larger rotations between them"
        ));
    }
    if !outliers.is_empty() {
        let list: Vec<String> = outliers.iter().map(|&i| problem.name(i).to_string()).collect();
        let which = match outliers.len() {
            1 => format!("capture {} looks like an outlier", list[0]),
            _ => format!("captures {} look like outliers", list.join(", ")),
        };
        warnings.push(format!(
            "{which} (a robot pose paired with the wrong capture, a target that moved, a bad detection) and \
             {} left out of the result; check and capture again",
            if outliers.len() > 1 { "were" } else { "was" },
        ));
    }
    Ok(Calibration {
        mount,
        hand_eye: fit.hand_eye,
        method: format!("{method} start, levenberg-marquardt refinement (huber loss)"),
        closed_forms: starts,
        residuals: fit.residuals,
        outliers: outliers.clone(),
        hand_eye_with_outliers: (!outliers.is_empty()).then_some(first.hand_eye),
        conditioning,
        warnings,
        working_distance_mm,
        expected_error_mm,
        translation_sigma_mm,
        rotation_sigma_deg,
    })
}

/// The inlier furthest above the outlier threshold, if any is.
fn worst_outlier(fit: &Fit, inliers: &[usize]) -> Option<usize> {
    let norms: Vec<f64> = inliers.iter().map(|&i| fit.normalised[i]).collect();
    let threshold = (OUTLIER_OVER_MEDIAN * refine::median(&norms)).max(OUTLIER_FLOOR_SIGMAS);
    inliers
        .iter()
        .copied()
        .filter(|&i| fit.normalised[i] > threshold)
        .max_by(|&a, &b| fit.normalised[a].total_cmp(&fit.normalised[b]))
}

/// The expected error at `distance` along the camera's axis, and the
/// translation and rotation sigmas, from the covariance of `(δω, δt)`:
/// a point `q` seen by the camera lands at `R q + t`, which moves by
/// `δω × (R q) + δt`.
fn uncertainty(cov: &nalgebra::Matrix6<f64>, hand_eye: &Isometry3<f64>, distance: f64) -> (f64, f64, f64) {
    let arm = hand_eye.rotation * Vector3::new(0.0, 0.0, distance);
    let skew = Matrix3::new(0.0, -arm.z, arm.y, arm.z, 0.0, -arm.x, -arm.y, arm.x, 0.0);
    let mut jac = nalgebra::Matrix3x6::zeros();
    jac.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew));
    jac.fixed_view_mut::<3, 3>(0, 3).copy_from(&Matrix3::identity());
    let point = jac * cov * jac.transpose();
    let rotation = cov.fixed_view::<3, 3>(0, 0).trace().max(0.0).sqrt().to_degrees();
    let translation = cov.fixed_view::<3, 3>(3, 3).trace().max(0.0).sqrt();
    (point.trace().max(0.0).sqrt(), translation, rotation)
}

/// The covariance of the first six parameters of a weighted least-squares
/// fit: `s² (JᵀJ)⁻¹` with `s²` the weighted residuals' variance per
/// degree of freedom.
fn covariance(params: &[f64], weighted_residuals: &dyn Fn(&[f64]) -> Vec<f64>) -> Option<nalgebra::Matrix6<f64>> {
    let r = weighted_residuals(params);
    let dof = r.len().checked_sub(params.len()).filter(|d| *d > 0)?;
    let s2 = r.iter().map(|v| v * v).sum::<f64>() / dof as f64;
    let jac = refine::jacobian(params, weighted_residuals);
    let normal = jac.transpose() * &jac;
    // A normal matrix this close to singular leaves a direction free.
    let eigen = normal.clone().symmetric_eigen();
    let (lo, hi) = eigen.eigenvalues.iter().fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    if lo.is_nan() || lo <= hi * 1e-12 {
        return None;
    }
    let inverse = normal.try_inverse()?;
    Some(inverse.fixed_view::<6, 6>(0, 0).into_owned() * s2)
}

/// The robust fit of the parameters `p0` (the hand-eye's six first, then
/// the target's or the spheres') over the captures `use_`, and every one
/// of the `captures` evaluated against it: `residual` gives a capture's
/// residuals in nominal sigmas for the hand-eye and the rest as `unpack`
/// makes them, `report` its [`CaptureResidual`] and its norm.
fn fit_captures<T, R: AsRef<[f64]>>(
    p0: &[f64],
    use_: &[usize],
    captures: usize,
    unpack: impl Fn(&[f64]) -> (Isometry3<f64>, T),
    residual: impl Fn(usize, &Isometry3<f64>, &T) -> R,
    report: impl Fn(usize, &Isometry3<f64>, &T, &[f64]) -> (CaptureResidual, f64),
) -> Result<Fit, CalibrationError> {
    let blocks = |p: &[f64]| -> Blocks {
        let (x, rest) = unpack(p);
        use_.iter().map(|&i| residual(i, &x, &rest)).collect()
    };
    let fit = refine::robust_fit(p0, &blocks)?;
    let (x, rest) = unpack(&fit.params);
    let weighted = |p: &[f64]| refine::weighted(&blocks(p), &fit.weights);
    let cost = weighted(&fit.params).iter().map(|v| v * v).sum();
    let (residuals, normalised) = (0..captures).map(|i| report(i, &x, &rest, residual(i, &x, &rest).as_ref())).unzip();
    let covariance = covariance(&fit.params, &weighted);
    Ok(Fit { hand_eye: x, residuals, normalised, covariance, cost })
}

/// The rotation's parameters and the translation of an isometry, as the
/// first six refinement parameters (zero rotation offset).
fn isometry_params(x: &Isometry3<f64>) -> [f64; 6] {
    let t = x.translation.vector;
    [0.0, 0.0, 0.0, t.x, t.y, t.z]
}

/// The isometry of six refinement parameters around `reference`.
fn params_isometry(reference: &Rotation3<f64>, p: &[f64]) -> Isometry3<f64> {
    let rotation = refine::perturbed(reference, &p[..3]);
    Isometry3::from_parts(Translation3::new(p[3], p[4], p[5]), UnitQuaternion::from_rotation_matrix(&rotation))
}

/// The target captures as a problem.
struct Targets<'a> {
    captures: &'a [TargetCapture],
    mount: Mount,
}

impl Targets<'_> {
    fn pair(&self, i: usize) -> (Isometry3<f64>, Isometry3<f64>) {
        (self.mount.hand(&self.captures[i].base_t_end), self.captures[i].camera_t_target)
    }

    /// Capture `i`'s residual for `X` and `Y`: `Y⁻¹ A_i X B_i` as
    /// rotation vector over its sigma and translation over its sigma.
    fn residual(&self, i: usize, x: &Isometry3<f64>, y: &Isometry3<f64>) -> [f64; 6] {
        let (a, b) = self.pair(i);
        let seen = a * x * b;
        let rot = (seen.rotation * y.rotation.inverse()).scaled_axis() / TARGET_ROTATION_SIGMA_DEG.to_radians();
        let t = (seen.translation.vector - y.translation.vector) / TARGET_TRANSLATION_SIGMA_MM;
        [rot.x, rot.y, rot.z, t.x, t.y, t.z]
    }

    /// The target pose `Y` the captures `use_` imply for `x`: the one
    /// closest to the others (a medoid, so an outlier does not drag it).
    fn medoid_target(&self, x: &Isometry3<f64>, use_: &[usize]) -> Isometry3<f64> {
        let implied: Vec<Isometry3<f64>> = use_
            .iter()
            .map(|&i| {
                let (a, b) = self.pair(i);
                a * x * b
            })
            .collect();
        let spread = |y: &Isometry3<f64>| -> f64 {
            implied
                .iter()
                .map(|z| {
                    (z.translation.vector - y.translation.vector).norm() / TARGET_TRANSLATION_SIGMA_MM
                        + z.rotation.angle_to(&y.rotation) / TARGET_ROTATION_SIGMA_DEG.to_radians()
                })
                .sum()
        };
        implied.iter().copied().min_by(|a, b| spread(a).total_cmp(&spread(b))).unwrap_or_else(Isometry3::identity)
    }
}

impl Problem for Targets<'_> {
    fn len(&self) -> usize {
        self.captures.len()
    }

    fn hands(&self) -> Vec<Isometry3<f64>> {
        (0..self.len()).map(|i| self.pair(i).0).collect()
    }

    fn working_distance_mm(&self) -> f64 {
        let d: Vec<f64> = self.captures.iter().map(|c| c.camera_t_target.translation.vector.norm()).collect();
        refine::median(&d)
    }

    fn starts(&self, use_: &[usize]) -> Vec<NamedStart> {
        let pairs: Vec<_> = use_.iter().map(|&i| self.pair(i)).collect();
        let motions = closed_form::motions(&pairs);
        ClosedForm::ALL.iter().filter_map(|form| Some((form.name(), form.solve(&motions)?))).collect()
    }

    fn refine(&self, start: &Isometry3<f64>, use_: &[usize]) -> Result<Fit, CalibrationError> {
        let y0 = self.medoid_target(start, use_);
        let (rx, ry) = (start.rotation.to_rotation_matrix(), y0.rotation.to_rotation_matrix());
        let mut p0 = isometry_params(start).to_vec();
        p0.extend(isometry_params(&y0));
        let unpack = |p: &[f64]| (params_isometry(&rx, &p[..6]), params_isometry(&ry, &p[6..]));
        fit_captures(
            &p0,
            use_,
            self.len(),
            unpack,
            |i, x, y| self.residual(i, x, y),
            |i, _, _, r| {
                let rot = Vector3::new(r[0], r[1], r[2]) * TARGET_ROTATION_SIGMA_DEG;
                let t = Vector3::new(r[3], r[4], r[5]) * TARGET_TRANSLATION_SIGMA_MM;
                (
                    CaptureResidual { capture: i, translation_mm: t.norm(), rotation_deg: Some(rot.norm()) },
                    refine::norm(r),
                )
            },
        )
    }
}

/// The sphere captures as a problem.
struct Spheres<'a> {
    captures: &'a [SphereCapture],
    mount: Mount,
    spheres: usize,
    /// Each capture's index in the set the user gave.
    names: Vec<usize>,
}

impl Spheres<'_> {
    fn observations(&self, i: usize) -> impl Iterator<Item = (usize, &Vec3)> {
        self.captures[i].centres.iter().enumerate().filter_map(|(j, c)| Some((j, c.as_ref()?)))
    }

    /// The linear start: `R_A (R_X c) + R_A t_X - s_j = -t_A` is linear in
    /// `R_X`'s nine entries, `t_X` and the centres `s_j`; solved by least
    /// squares, `R_X` projected on SO(3), then `t_X` and `s_j` solved again
    /// with it fixed.
    fn linear_start(&self, use_: &[usize]) -> Option<Isometry3<f64>> {
        let rows: usize = use_.iter().map(|&i| 3 * self.observations(i).count()).sum();
        let cols = 12 + 3 * self.spheres;
        let mut m = DMatrix::zeros(rows, cols);
        let mut y = DVector::zeros(rows);
        let mut row = 0;
        for &i in use_ {
            let a = self.mount.hand(&self.captures[i].base_t_end);
            let ra = a.rotation.to_rotation_matrix().into_inner();
            for (j, c) in self.observations(i) {
                // R_X c = Σ_k c_k R_X[:, k]: the column-major entries of R_X.
                for k in 0..3 {
                    m.fixed_view_mut::<3, 3>(row, 3 * k).copy_from(&(ra * c[k]));
                }
                m.fixed_view_mut::<3, 3>(row, 9).copy_from(&ra);
                m.fixed_view_mut::<3, 3>(row, 12 + 3 * j).copy_from(&(-Matrix3::identity()));
                y.fixed_rows_mut::<3>(row).copy_from(&(-a.translation.vector));
                row += 3;
            }
        }
        let svd = m.clone().svd(true, true);
        let s = &svd.singular_values;
        let largest = s.iter().copied().fold(0.0, f64::max);
        if s.iter().copied().fold(f64::INFINITY, f64::min) <= largest * 1e-10 {
            return None;
        }
        let solution = svd.solve(&y, 0.0).ok()?;
        let raw = Matrix3::from_column_slice(&solution.as_slice()[..9]);
        let columns: Vec<(Vector3<f64>, Vector3<f64>)> =
            (0..3).map(|k| (raw.column(k).into_owned(), Vector3::ith(k, 1.0))).collect();
        let rotation = procrustes(&columns)?;
        // With R_X fixed: (R_A t_X - s_j) = -t_A - R_A R_X c.
        let mut rest = DMatrix::zeros(rows, 3 + 3 * self.spheres);
        let mut rhs = DVector::zeros(rows);
        let mut row = 0;
        for &i in use_ {
            let a = self.mount.hand(&self.captures[i].base_t_end);
            let ra = a.rotation.to_rotation_matrix().into_inner();
            for (j, c) in self.observations(i) {
                rest.fixed_view_mut::<3, 3>(row, 0).copy_from(&ra);
                rest.fixed_view_mut::<3, 3>(row, 3 + 3 * j).copy_from(&(-Matrix3::identity()));
                rhs.fixed_rows_mut::<3>(row).copy_from(&(-a.translation.vector - ra * (rotation * c)));
                row += 3;
            }
        }
        let t = rest.svd(true, true).solve(&rhs, 0.0).ok()?;
        Some(Isometry3::from_parts(
            Translation3::new(t[0], t[1], t[2]),
            UnitQuaternion::from_rotation_matrix(&rotation),
        ))
    }

    /// The base-frame (or flange-frame) sphere centres `x` implies: each
    /// sphere's median over the captures `use_`, coordinate by coordinate.
    fn centres_for(&self, x: &Isometry3<f64>, use_: &[usize]) -> Vec<Vec3> {
        (0..self.spheres)
            .map(|j| {
                let seen: Vec<Vec3> = use_
                    .iter()
                    .filter_map(|&i| {
                        let c = self.captures[i].centres.get(j)?.as_ref()?;
                        Some(self.mount.hand(&self.captures[i].base_t_end) * (x * nalgebra::Point3::from(*c)).coords)
                    })
                    .collect();
                let axis = |k: usize| refine::median(&seen.iter().map(|p| p[k]).collect::<Vec<_>>());
                Vec3::new(axis(0), axis(1), axis(2))
            })
            .collect()
    }

    /// Capture `i`'s residuals (mm over the nominal sigma), sphere by
    /// sphere, for `x` and the centres `s`.
    fn residual(&self, i: usize, x: &Isometry3<f64>, s: &[Vec3]) -> Vec<f64> {
        let a = self.mount.hand(&self.captures[i].base_t_end);
        self.observations(i)
            .flat_map(|(j, c)| {
                let p = a * (x * nalgebra::Point3::from(*c));
                ((p.coords - s[j]) / SPHERE_SIGMA_MM).iter().copied().collect::<Vec<_>>()
            })
            .collect()
    }

    /// The rotation between capture `i`'s centres carried into the base
    /// frame and the fitted centres, degrees, when it saw three or more.
    fn rotation_residual(&self, i: usize, x: &Isometry3<f64>, s: &[Vec3]) -> Option<f64> {
        let a = self.mount.hand(&self.captures[i].base_t_end);
        let pairs: Vec<(Vec3, Vec3)> =
            self.observations(i).map(|(j, c)| (s[j], (a * (x * nalgebra::Point3::from(*c))).coords)).collect();
        if pairs.len() < 3 {
            return None;
        }
        let n = pairs.len() as f64;
        let (to_mean, from_mean) =
            pairs.iter().fold((Vec3::zeros(), Vec3::zeros()), |(t, f), (a, b)| (t + a / n, f + b / n));
        let centred: Vec<(Vec3, Vec3)> = pairs.iter().map(|(a, b)| (a - to_mean, b - from_mean)).collect();
        Some(UnitQuaternion::from_rotation_matrix(&procrustes(&centred)?).angle().to_degrees())
    }
}

impl Problem for Spheres<'_> {
    fn len(&self) -> usize {
        self.captures.len()
    }

    fn name(&self, i: usize) -> usize {
        self.names[i]
    }

    fn hands(&self) -> Vec<Isometry3<f64>> {
        self.captures.iter().map(|c| self.mount.hand(&c.base_t_end)).collect()
    }

    fn working_distance_mm(&self) -> f64 {
        let d: Vec<f64> = self.captures.iter().flat_map(|c| c.centres.iter().flatten().map(|p| p.norm())).collect();
        refine::median(&d)
    }

    fn starts(&self, use_: &[usize]) -> Vec<NamedStart> {
        self.linear_start(use_).map(|x| ("linear", x)).into_iter().collect()
    }

    fn refine(&self, start: &Isometry3<f64>, use_: &[usize]) -> Result<Fit, CalibrationError> {
        let rx = start.rotation.to_rotation_matrix();
        let mut p0 = isometry_params(start).to_vec();
        p0.extend(self.centres_for(start, use_).iter().flat_map(|c| [c.x, c.y, c.z]));
        let unpack = |p: &[f64]| {
            let centres: Vec<Vec3> = p[6..].chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
            (params_isometry(&rx, &p[..6]), centres)
        };
        fit_captures(
            &p0,
            use_,
            self.len(),
            unpack,
            |i, x, s| self.residual(i, x, s),
            |i, x, s, r| {
                let spheres = (r.len() / 3).max(1) as f64;
                let rms = refine::norm(r) / spheres.sqrt();
                let residual = CaptureResidual {
                    capture: i,
                    translation_mm: rms * SPHERE_SIGMA_MM,
                    rotation_deg: self.rotation_residual(i, x, s),
                };
                (residual, rms)
            },
        )
    }
}

#[cfg(test)]
mod tests;
