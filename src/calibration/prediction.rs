//! A sphere set solved in two passes, so that captures the layout cannot
//! name still count.
//!
//! Balls of one radius are named by their distances ([`super::naming`]),
//! which takes three of them in view: a capture where one ball hides
//! another or is cut by the view shows two, whose one distance reads the
//! same either way round, and the layout cannot say which is which. Yet
//! once the hand-eye is known, each ball's place in the camera is known
//! too. So:
//!
//! 1. the captures the layout names are solved ([`calibrate_named_spheres`]):
//!    the first hand-eye `X₁` and, from it, each ball's centre `s_j` in the
//!    base frame (the mean over the captures used);
//! 2. in each capture the layout left out, each ball's centre is
//!    predicted in the camera, `(A_i X₁)⁻¹ s_j`, and each sphere found there
//!    is named by the nearest prediction when it lies within the
//!    tolerance; a sphere within the tolerance of two predictions, or two
//!    spheres within the tolerance of one, are ambiguous and left unnamed;
//! 3. every named capture is solved again, outliers removed as always (a
//!    sphere named wrong shows up there as a residual of centimetres).
//!
//! **The tolerance** is derived from the first solution's own figures, not
//! set by hand: a prediction is off by the first hand-eye's error at the
//! working distance (its expected error, one sigma) and by this capture's
//! own noise (the robot's pose and the sphere's fit: the first solution's
//! RMS capture residual), so its sigma is the root sum of their squares,
//! and the tolerance is [`PREDICTION_SIGMAS`] of it. A first solution whose
//! tolerance would be over [`MAX_PREDICTION_TOLERANCE_MM`] names nothing
//! (its captures are too few or too noisy to predict from), and the report
//! says so.

use nalgebra::{Isometry3, Point3};

use super::naming::{Naming, NamingError, name_spheres};
use super::sphere::FittedSphere;
use super::{Calibration, CalibrationError, Mount, SphereCapture, calibrate_named_spheres};
use crate::geometry::Vec3;

/// A found sphere is named by a prediction within this many of the
/// prediction's sigmas: a true ball with normal errors lies further out
/// less than once in a million captures, while another ball of the rig
/// lies tens of millimetres away.
pub const PREDICTION_SIGMAS: f64 = 5.0;

/// The widest tolerance the prediction names by, mm: the layout itself
/// names a ball only when its distances agree within
/// [`DISTANCE_MATCH_MM`](super::naming::DISTANCE_MATCH_MM); a first
/// solution that cannot predict a ball as closely is not trusted more than
/// the layout.
pub const MAX_PREDICTION_TOLERANCE_MM: f64 = super::naming::DISTANCE_MATCH_MM;

/// How a capture's spheres were named.
#[derive(Debug, Clone, PartialEq)]
pub enum CaptureNaming {
    /// By the layout's distances (or by radius).
    Layout,
    /// By the first solution's prediction: this many balls.
    Prediction { balls: usize },
    /// Not named, with why; the capture is left out.
    LeftOut(String),
}

/// Every capture's spheres named, and how.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereNaming {
    /// `centres[capture][sphere]`, as in [`Naming::centres`].
    pub centres: Vec<Vec<Option<Vec3>>>,
    /// How each capture was named.
    pub how: Vec<CaptureNaming>,
    /// The layout's distances the spheres were named by, when distances
    /// named them.
    pub distances: Option<Vec<f64>>,
    /// The tolerance the prediction named by, mm, when a first solution
    /// was made.
    pub tolerance_mm: Option<f64>,
}

impl SphereNaming {
    /// The captures left out, with why.
    pub fn left_out(&self) -> Vec<(usize, String)> {
        self.how
            .iter()
            .enumerate()
            .filter_map(|(i, h)| match h {
                CaptureNaming::LeftOut(reason) => Some((i, reason.clone())),
                _ => None,
            })
            .collect()
    }

    /// The captures named one way.
    pub fn named_by_layout(&self) -> Vec<usize> {
        (0..self.how.len()).filter(|&i| self.how[i] == CaptureNaming::Layout).collect()
    }

    /// The captures named by the first solution's prediction.
    pub fn named_by_prediction(&self) -> Vec<usize> {
        (0..self.how.len()).filter(|&i| matches!(self.how[i], CaptureNaming::Prediction { .. })).collect()
    }
}

/// Why a sphere set could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SphereSetError {
    #[error(transparent)]
    Naming(#[from] NamingError),
    #[error(transparent)]
    Calibration(#[from] CalibrationError),
}

/// Names the spheres fitted in every capture (`fitted[i]` seen at the
/// flange pose `base_t_end[i]`), by the layout and then by the first
/// solution's prediction, and solves the hand-eye on every capture named.
pub fn calibrate_fitted_spheres(
    base_t_end: &[Isometry3<f64>],
    fitted: &[Vec<FittedSphere>],
    radii: &[f64],
    distances: Option<&[f64]>,
    mount: Mount,
) -> Result<(Calibration, SphereNaming), SphereSetError> {
    let naming = name_spheres(fitted, radii, distances)?;
    let first = calibrate_named_spheres(&captures(base_t_end, &naming.centres), mount)?;
    let result = predicted_naming(base_t_end, fitted, &naming, &first, mount);
    if result.named_by_prediction().is_empty() {
        return Ok((first, result));
    }
    let second = calibrate_named_spheres(&captures(base_t_end, &result.centres), mount)?;
    Ok((second, result))
}

fn captures(base_t_end: &[Isometry3<f64>], centres: &[Vec<Option<Vec3>>]) -> Vec<SphereCapture> {
    base_t_end.iter().zip(centres).map(|(pose, c)| SphereCapture { base_t_end: *pose, centres: c.clone() }).collect()
}

/// The naming with the captures the layout left out named, where they
/// can be, by the first solution's prediction.
fn predicted_naming(
    base_t_end: &[Isometry3<f64>],
    fitted: &[Vec<FittedSphere>],
    naming: &Naming,
    first: &Calibration,
    mount: Mount,
) -> SphereNaming {
    let mut how: Vec<CaptureNaming> = vec![CaptureNaming::Layout; naming.centres.len()];
    for (i, reason) in &naming.unnamed {
        how[*i] = CaptureNaming::LeftOut(reason.clone());
    }
    let mut result =
        SphereNaming { centres: naming.centres.clone(), how, distances: naming.distances.clone(), tolerance_mm: None };
    if naming.unnamed.is_empty() {
        return result;
    }
    let tolerance = match tolerance_mm(first) {
        Ok(t) => t,
        Err(why) => {
            for h in &mut result.how {
                if let CaptureNaming::LeftOut(reason) = h {
                    *reason = format!("{reason}; {why}");
                }
            }
            return result;
        }
    };
    result.tolerance_mm = Some(tolerance);
    let spheres = naming.centres.first().map_or(0, Vec::len);
    let used: Vec<usize> = first.residuals.iter().map(|r| r.capture).filter(|i| !first.outliers.contains(i)).collect();
    let base_centres = base_frame_centres(base_t_end, &naming.centres, &used, &first.hand_eye, mount, spheres);
    for (i, reason) in &naming.unnamed {
        let camera_t_base = (mount.hand(&base_t_end[*i]) * first.hand_eye).inverse();
        let predicted: Vec<Option<Vec3>> =
            base_centres.iter().map(|s| s.map(|s| (camera_t_base * Point3::from(s)).coords)).collect();
        match name_by_prediction(&fitted[*i], &predicted, tolerance) {
            Ok(named) => {
                let balls = named.iter().flatten().count();
                result.centres[*i] = named;
                result.how[*i] = CaptureNaming::Prediction { balls };
            }
            Err(why) => result.how[*i] = CaptureNaming::LeftOut(format!("{reason}; {why}")),
        }
    }
    result
}

/// The prediction's tolerance from the first solution, or why it cannot
/// predict.
fn tolerance_mm(first: &Calibration) -> Result<f64, String> {
    let Some(expected) = first.expected_error_mm else {
        return Err("the captures named by the layout do not determine the hand-eye to predict the balls from".into());
    };
    let used: Vec<f64> =
        first.residuals.iter().filter(|r| !first.outliers.contains(&r.capture)).map(|r| r.translation_mm).collect();
    let rms = (used.iter().map(|r| r * r).sum::<f64>() / used.len().max(1) as f64).sqrt();
    let tolerance = PREDICTION_SIGMAS * expected.hypot(rms);
    if !tolerance.is_finite() || tolerance > MAX_PREDICTION_TOLERANCE_MM {
        return Err(format!(
            "the first solution predicts the balls only within {tolerance:.2} mm ({PREDICTION_SIGMAS} sigmas), over \
             the {MAX_PREDICTION_TOLERANCE_MM} mm the balls are named by"
        ));
    }
    Ok(tolerance)
}

/// Each sphere's centre in the base frame (the flange frame for a camera
/// fixed in the cell) as the first hand-eye puts it: the mean over the
/// captures `used` that named it.
fn base_frame_centres(
    base_t_end: &[Isometry3<f64>],
    centres: &[Vec<Option<Vec3>>],
    used: &[usize],
    hand_eye: &Isometry3<f64>,
    mount: Mount,
    spheres: usize,
) -> Vec<Option<Vec3>> {
    (0..spheres)
        .map(|j| {
            let seen: Vec<Vec3> = used
                .iter()
                .filter_map(|&i| {
                    let c = centres[i].get(j)?.as_ref()?;
                    Some((mount.hand(&base_t_end[i]) * hand_eye * Point3::from(*c)).coords)
                })
                .collect();
            (!seen.is_empty()).then(|| seen.iter().sum::<Vec3>() / seen.len() as f64)
        })
        .collect()
}

/// One capture's spheres named by the nearest prediction within
/// `tolerance`, or why none can be.
fn name_by_prediction(
    found: &[FittedSphere],
    predicted: &[Option<Vec3>],
    tolerance: f64,
) -> Result<Vec<Option<Vec3>>, String> {
    let mut named: Vec<Option<Vec3>> = vec![None; predicted.len()];
    let mut claims = vec![0usize; predicted.len()];
    let mut ambiguous = 0usize;
    let mut choice: Vec<Option<usize>> = Vec::with_capacity(found.len());
    for sphere in found {
        let near: Vec<usize> = (0..predicted.len())
            .filter(|&j| predicted[j].is_some_and(|p| (p - sphere.centre).norm() <= tolerance))
            .collect();
        match near.as_slice() {
            [j] => {
                claims[*j] += 1;
                choice.push(Some(*j));
            }
            [] => choice.push(None),
            _ => {
                ambiguous += 1;
                choice.push(None);
            }
        }
    }
    for (sphere, j) in found.iter().zip(&choice) {
        match j {
            Some(j) if claims[*j] == 1 => named[*j] = Some(sphere.centre),
            Some(_) => ambiguous += 1,
            None => {}
        }
    }
    if named.iter().any(Option::is_some) {
        return Ok(named);
    }
    Err(if ambiguous > 0 {
        format!("{ambiguous} of its spheres lie within {tolerance:.2} mm of more than one predicted ball or share one")
    } else {
        format!(
            "none of its {} spheres lies within {tolerance:.2} mm of where the first solution predicts a ball",
            found.len()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::naming::tests::sphere;

    #[test]
    fn spheres_are_named_by_the_nearest_prediction_within_the_tolerance() {
        let predicted = [Some(Vec3::new(0.0, 0.0, 500.0)), Some(Vec3::new(150.0, 0.0, 500.0)), None];
        let found = [sphere(Vec3::new(150.3, 0.1, 500.0)), sphere(Vec3::new(60.0, 0.0, 520.0))];
        let named = name_by_prediction(&found, &predicted, 0.8).unwrap();
        assert_eq!(named, vec![None, Some(found[0].centre), None]);
        let e = name_by_prediction(&found[1..], &predicted, 0.8).unwrap_err();
        assert!(e.contains("none of its 1 spheres lies within 0.80 mm"), "{e}");
    }

    #[test]
    fn two_spheres_on_one_prediction_are_ambiguous_and_left_unnamed() {
        let predicted = [Some(Vec3::new(0.0, 0.0, 500.0)), Some(Vec3::new(150.0, 0.0, 500.0))];
        let found = [sphere(Vec3::new(0.3, 0.0, 500.0)), sphere(Vec3::new(-0.3, 0.0, 500.0))];
        let e = name_by_prediction(&found, &predicted, 0.8).unwrap_err();
        assert!(e.contains("2 of its spheres"), "{e}");
        // A wide tolerance covering two predictions is ambiguous too.
        let found = [sphere(Vec3::new(75.0, 0.0, 500.0))];
        let e = name_by_prediction(&found, &predicted, 80.0).unwrap_err();
        assert!(e.contains("more than one predicted ball"), "{e}");
    }
}
