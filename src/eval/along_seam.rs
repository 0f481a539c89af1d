//! The joint's figures along the seam against the simulator's truth: at
//! every waypoint of the first seam of a butt or lap scene, the measured
//! gap, high-low, V-groove cross-section and lap step against the scene's
//! geometry at that place along the seam.
//!
//! The truth is the scene's cross-section: an I-butt's gap, a V-groove's
//! opening at the top `r + 2 d tan(α/2)` and its area down to the bevels'
//! foot `d (W + r) / 2` (root gap `r`, bevel depth `d`, angle `α`), a lap's
//! upper plate's thickness, and no high-low (the simulated plates lie
//! level). Errors are absolute, mm, except the groove's area, a share of
//! the true area. A figure the plan leaves out (`None`) is counted as
//! missing, not scored.

use crate::joint::JointType;
use crate::pipeline::along_seam::{JointFigures, Measured};
use crate::sim::{JointGeometry, SceneSpec};

use super::SceneOutcome;

/// The true figures of a scene's joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointTruth {
    pub gap_mm: Option<f64>,
    pub high_low_mm: Option<f64>,
    pub groove_area_mm2: Option<f64>,
    pub lap_step_mm: Option<f64>,
}

impl JointTruth {
    /// The scene's joint's figures (the same all along its seam).
    pub fn of(spec: &SceneSpec) -> Option<JointTruth> {
        let none = JointTruth { gap_mm: None, high_low_mm: None, groove_area_mm2: None, lap_step_mm: None };
        match spec.joint {
            JointGeometry::IButt { gap_mm, .. } => {
                Some(JointTruth { gap_mm: Some(gap_mm), high_low_mm: Some(0.0), ..none })
            }
            JointGeometry::VButt { groove_depth_mm: d, root_gap_mm: r, .. } => {
                let opening = 2.0 * spec.joint.seam_edge_half_width();
                Some(JointTruth {
                    gap_mm: Some(opening),
                    high_low_mm: Some(0.0),
                    groove_area_mm2: Some(d * (opening + r) / 2.0),
                    ..none
                })
            }
            JointGeometry::Lap { upper_thickness_mm, .. } => {
                Some(JointTruth { lap_step_mm: Some(upper_thickness_mm), ..none })
            }
            JointGeometry::Tee { .. } | JointGeometry::Corner { .. } => None,
        }
    }
}

/// One figure's errors over the waypoints scored, and how many waypoints
/// had no value for it: where the cloud shows the joint (missing), and
/// where it shows nothing of it (unseen; counted only by scorers that
/// look, [`FigureErrors::add_unseen`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FigureErrors {
    pub errors: Vec<f64>,
    pub missing: usize,
    /// Waypoints with no value where no point of the cloud lies at the
    /// joint: hidden from the camera, nothing could be read there.
    pub unseen: usize,
    /// How many errors were within two of the figure's own standard errors
    /// (about 95 % if the standard errors are honest).
    pub within_two_sigma: usize,
}

impl FigureErrors {
    pub(super) fn add(&mut self, measured: Option<Measured>, truth: Option<f64>, relative: bool) {
        let Some(truth) = truth else { return };
        let Some(m) = measured else {
            self.missing += 1;
            return;
        };
        let error = (m.value - truth).abs();
        self.within_two_sigma += usize::from(error <= 2.0 * m.sigma);
        self.errors.push(if relative && truth > 0.0 { error / truth } else { error });
    }

    /// A waypoint where the cloud shows nothing of the joint: no value is
    /// expected there, of a figure the joint has (`truth`).
    pub(super) fn add_unseen(&mut self, truth: Option<f64>) {
        self.unseen += usize::from(truth.is_some());
    }

    /// The median error, or `None` without one.
    pub fn median(&self) -> Option<f64> {
        let mut sorted = self.errors.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        (n > 0).then(|| if n % 2 == 1 { sorted[n / 2] } else { 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]) })
    }

    /// The largest error, or `None` without one.
    pub fn max(&self) -> Option<f64> {
        self.errors.iter().copied().reduce(f64::max)
    }
}

/// The figures along the seam of one joint type's scenes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AlongSeamScore {
    pub scenes: usize,
    pub waypoints: usize,
    pub gap: FigureErrors,
    pub high_low: FigureErrors,
    /// A share of the true area.
    pub groove_area: FigureErrors,
    pub lap_step: FigureErrors,
}

/// Scores the first seam of each outcome of `joint`'s scenes that planned
/// one of that joint type.
pub fn score(outcomes: &[SceneOutcome], joint: JointType) -> AlongSeamScore {
    let mut score = AlongSeamScore::default();
    for o in outcomes.iter().filter(|o| o.spec.joint.joint_type() == joint) {
        let (Some(truth), Ok((_, plan))) = (JointTruth::of(&o.spec), &o.result) else { continue };
        let Some(seam) = plan.seams.first().filter(|s| s.joint == joint) else { continue };
        score.scenes += 1;
        for f in &seam.along_seam {
            score.add(f, &truth);
        }
    }
    score
}

impl AlongSeamScore {
    fn add(&mut self, f: &JointFigures, truth: &JointTruth) {
        self.waypoints += 1;
        self.gap.add(f.gap_mm, truth.gap_mm, false);
        self.high_low.add(f.high_low_mm, truth.high_low_mm, false);
        self.groove_area.add(f.groove_area_mm2, truth.groove_area_mm2, true);
        self.lap_step.add(f.lap_step_mm, truth.lap_step_mm, false);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_scored_against_the_truth_and_gaps_in_the_figures_counted() {
        let truth = JointTruth { gap_mm: Some(2.0), high_low_mm: Some(0.0), groove_area_mm2: None, lap_step_mm: None };
        let mut score = AlongSeamScore::default();
        let m = |value, sigma| Some(Measured { value, sigma });
        for gap in [m(2.1, 0.1), m(1.7, 0.1), None, m(2.0, 0.1)] {
            score.add(&JointFigures { gap_mm: gap, high_low_mm: m(0.05, 0.1), ..JointFigures::default() }, &truth);
        }
        assert_eq!(score.waypoints, 4);
        assert_eq!((score.gap.errors.len(), score.gap.missing, score.gap.within_two_sigma), (3, 1, 2));
        assert!((score.gap.median().unwrap() - 0.1).abs() < 1e-9);
        assert!((score.gap.max().unwrap() - 0.3).abs() < 1e-9);
        assert_eq!(score.groove_area, FigureErrors::default(), "no truth, nothing scored");
    }

    #[test]
    fn a_v_grooves_truth_is_its_opening_and_its_area_to_the_bevels_foot() {
        // The demo's groove: 10 mm plates, 60 degrees, 6 mm deep, 1 mm root gap.
        let spec = crate::sim::demo_scene(JointType::VButt);
        let t = JointTruth::of(&spec).unwrap();
        let opening = 1.0 + 12.0 * 30f64.to_radians().tan();
        assert!((t.gap_mm.unwrap() - opening).abs() < 1e-12);
        // A rectangle of the root gap and two triangles.
        let area = 6.0 * 1.0 + 36.0 * 30f64.to_radians().tan();
        assert!((t.groove_area_mm2.unwrap() - area).abs() < 1e-9);
    }
}
