//! Quality figures and gates (issue 12): what the planner knows about how
//! good a seam is, and the limits beyond which it refuses the seam rather
//! than let a robot weld a guess.
//!
//! The paper reports errors after the fact, against a tape measure; a cell
//! has no tape measure, so every figure here is read from the fits the
//! pipeline already made:
//!
//! - each weld edge's least-squares residual (Eq. 17 to 25) and the
//!   samples behind it, the share of them left beyond the fitted line
//!   towards the other plate (a plate's points stop at its edge, so those
//!   samples are the edge itself where the rest was cut short), and the
//!   largest step between two runs of them along the edge (a plate's edge
//!   is one line: on two, one run was cut short);
//! - the distance between the two weld edges across the seam at stations
//!   along it (the gap of an I-butt joint, the top of a V-groove), and
//!   their height difference along the normal (the high-low misalignment
//!   of butt plates, which ISO 5817 limits to 0.15 t and 4 mm at quality
//!   level C for butt welds);
//! - the lap step, the angle between the two plates' planes and, when the
//!   surface the plates rest on is seen, how far behind them it lies (the
//!   plates are at most that thick; on spacers, much thinner);
//! - an estimate of the seam's position uncertainty (one sigma) across it
//!   and along the normal;
//! - for a tee's fillet root ([`measure_fillet`]): the web face's fit
//!   residual and the flange's beside the root (the seam's two "edges"),
//!   the angle between the web's face and the flange (the `plate_angle`
//!   gate holds it square within `quality.max_web_tilt_deg`), and the
//!   root's uncertainty from the face fit ([`super::fillet`]).
//!
//! A polynomial of degree p fitted by least squares to n samples spread
//! evenly along its interval, each with scatter σ, is known at the
//! interval's ends to `σ (p + 1) / √n` (the endpoint variance of a
//! Legendre-basis fit is `(p + 1)² σ² / n`); the ends are where the fit is
//! worst, so that is the figure. On top of it each edge carries the
//! sampling of the boundary itself: a plate ends somewhere between its
//! last point and the next one, a spacing further, which no number of
//! samples averages away if the edge criterion leans one way, so a floor
//! of `spacing / √12` (a uniform spread over one spacing) per edge.
//!
//! The gates ([`check`]) compare the figures with
//! [`crate::config::QualityParams`]: a seam that fails
//! one is refused with the figure, its value and the limit, and a
//! [`Gate`] code the protocol carries; `quality.warn_only` turns a gate
//! into a warning on the seam instead.

mod gates;
#[cfg(test)]
mod tests;

use crate::geometry::Vec3;
use crate::geometry::fit::Plane;
use crate::joint::JointType;
pub use crate::rules::Gate;

use super::fillet::Root;
use super::groove::GrooveProfile;
use super::refit::CurveFit;

pub use gates::{FittedEdges, GateFailure, SeamEvidence, check};

/// How many stations along the seam the gap and the misalignment are read
/// at: enough to see a gap that opens towards one end, few enough to cost
/// nothing.
const STATIONS: usize = 16;

/// A figure's least, mean and greatest value along the seam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

impl Spread {
    fn of(values: impl IntoIterator<Item = f64>) -> Option<Spread> {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
        for v in values {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        (n > 0).then(|| Spread { min, mean: sum / n as f64, max })
    }
}

/// What the fits say about one seam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeamQuality {
    /// The cloud's point spacing at the seam, mm: measured, or the camera's
    /// pixel footprint there.
    pub point_spacing_mm: f64,
    /// Butt joints: the distance between the two weld edges across the
    /// seam, mm: the root gap of an I-butt joint, the top width of a
    /// V-groove.
    pub gap_mm: Option<Spread>,
    /// Butt joints: the largest height difference between the two weld
    /// edges along the plate normal, mm (the linear misalignment).
    pub misalignment_mm: Option<f64>,
    /// Lap joints: how far the lower plate lies below the upper one at the
    /// seam, mm (the upper plate's thickness, as seen).
    pub lap_step_mm: Option<f64>,
    /// How far the surface the plates rest on (a table, a fixture) lies
    /// behind the plates (the butt plates, or the lower lap plate), mm,
    /// when it is seen: the plates are at most that thick.
    pub depth_to_support_mm: Option<f64>,
    /// The angle between the two plates' planes, degrees.
    pub plate_angle_deg: f64,
    /// The seam's position uncertainty (one sigma) across it, in the
    /// plates' plane, and along the plate normal, mm. Both come from the
    /// edge fits' residual, which is one distance, not split by direction,
    /// so today the two are the same estimate.
    pub uncertainty_across_mm: f64,
    pub uncertainty_normal_mm: f64,
    /// V-butt joints: the groove's angle and its depth below the plates'
    /// top, as the groove probe measured them (the depth only where a
    /// bevel face shows the root).
    pub groove_angle_deg: Option<f64>,
    pub groove_depth_mm: Option<f64>,
}

/// What [`measure`] reads the figures from.
#[derive(Debug, Clone, Copy)]
pub struct SeamFits<'a> {
    pub joint: JointType,
    /// The two weld edges' fits, on shared axes (`a` across the seam, `b`
    /// along the normal); for a lap the upper plate's edge first.
    pub fits: &'a [CurveFit; 2],
    /// The fits' polynomial degree.
    pub degree: usize,
    pub planes: [&'a Plane; 2],
    /// The planned stretch along the seam's feature axis, mm.
    pub span: (f64, f64),
    pub point_spacing_mm: f64,
    pub depth_to_support_mm: Option<f64>,
    /// Lap joints: the plate step at the seam
    /// ([`super::weld_equation::lap_step`]).
    pub lap_step_mm: Option<f64>,
    /// What lies between a butt joint's edges, when it was probed.
    pub groove: Option<&'a GrooveProfile>,
}

/// Reads a seam's quality figures from its fits.
pub fn measure(seam: &SeamFits) -> SeamQuality {
    let [e1, e2] = seam.fits.each_ref().map(|f| &f.curve);
    let axes = &e1.axes;
    let (s0, s1) = seam.span;
    let stations = (0..STATIONS).map(|k| s0 + (s1 - s0) * (k as f64 + 0.5) / STATIONS as f64);
    let offsets: Vec<Vec3> = stations.map(|s| e2.at(s) - e1.at(s)).collect();
    let butt = seam.joint != JointType::Lap;
    let v_butt = seam.joint == JointType::VButt;
    let gap_mm = if butt { Spread::of(offsets.iter().map(|d| d.dot(&axes.a).abs())) } else { None };
    let misalignment_mm = if butt { offsets.iter().map(|d| d.dot(&axes.b).abs()).reduce(f64::max) } else { None };
    let lap_step_mm = seam.lap_step_mm.filter(|_| !butt);
    let cos = seam.planes[0].normal.dot(&seam.planes[1].normal).clamp(-1.0, 1.0);

    let edge_sigma = seam.fits.each_ref().map(|f| edge_sigma(f, seam.degree, seam.point_spacing_mm));
    // A butt weld lies midway between the edges (Eq. 32, 36); a lap weld
    // at the root under the upper plate's edge (Eq. 38).
    let uncertainty = if butt { 0.5 * edge_sigma[0].hypot(edge_sigma[1]) } else { edge_sigma[0] };
    SeamQuality {
        point_spacing_mm: seam.point_spacing_mm,
        gap_mm,
        misalignment_mm,
        lap_step_mm,
        depth_to_support_mm: seam.depth_to_support_mm,
        plate_angle_deg: cos.acos().to_degrees(),
        uncertainty_across_mm: uncertainty,
        uncertainty_normal_mm: uncertainty,
        groove_angle_deg: seam.groove.and_then(GrooveProfile::groove_angle_deg).filter(|_| v_butt),
        groove_depth_mm: seam.groove.and_then(GrooveProfile::depth_mm).filter(|_| v_butt),
    }
}

/// One sigma of a weld edge's fit of `degree` at an end of its interval
/// (the module's `σ (p + 1) / √n`), with the boundary's floor of a
/// `point_spacing_mm / √12`, mm.
pub fn edge_sigma(fit: &CurveFit, degree: usize, point_spacing_mm: f64) -> f64 {
    let floor = point_spacing_mm / 12f64.sqrt();
    let fitted = fit.rms_mm * (degree as f64 + 1.0) / (fit.points_used.max(1) as f64).sqrt();
    fitted.hypot(floor)
}

/// A fillet root's quality figures: the angle between the web's face and
/// the flange as the plate angle, the root's own uncertainty, and the
/// surface behind the flange when it is seen.
pub fn measure_fillet(root: &Root, point_spacing_mm: f64, depth_to_support_mm: Option<f64>) -> SeamQuality {
    SeamQuality {
        point_spacing_mm,
        gap_mm: None,
        misalignment_mm: None,
        lap_step_mm: None,
        depth_to_support_mm,
        plate_angle_deg: root.web_angle_deg,
        uncertainty_across_mm: root.uncertainty_across_mm,
        uncertainty_normal_mm: root.uncertainty_normal_mm,
        groove_angle_deg: None,
        groove_depth_mm: None,
    }
}
