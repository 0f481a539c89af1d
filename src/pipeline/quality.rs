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
//! The gates compare the figures with [`QualityParams`]: a seam that fails
//! one is refused with the figure, its value and the limit, and a
//! [`Gate`] code the protocol carries; `quality.warn_only` turns a gate
//! into a warning on the seam instead.

use crate::config::QualityParams;
use crate::geometry::Vec3;
use crate::geometry::fit::Plane;
use crate::joint::JointType;
pub use crate::rules::Gate;
use crate::rules::{Rule, Stage, pending};

use super::SeamCoverage;
use super::fillet::Root;
use super::groove::GrooveProfile;
use super::refit::{Beyond, CurveFit, Step};

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

    // One sigma at an end of each edge's fit, with the boundary's floor.
    let floor = seam.point_spacing_mm / 12f64.sqrt();
    let edge_sigma = seam.fits.each_ref().map(|f| {
        let fitted = f.rms_mm * (seam.degree as f64 + 1.0) / (f.points_used.max(1) as f64).sqrt();
        fitted.hypot(floor)
    });
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

/// A gate a seam failed: the figure's value, the limit it broke, and one
/// sentence that says both and what it means.
#[derive(Debug, Clone, PartialEq)]
pub struct GateFailure {
    /// The rule that failed the seam, from [`crate::rules`].
    pub rule: &'static Rule,
    pub gate: Gate,
    pub value: f64,
    pub limit: f64,
    pub message: String,
}

/// The figures a gate reads that are not in [`SeamQuality`].
#[derive(Debug, Clone, Copy)]
pub struct SeamEvidence<'a> {
    pub joint: JointType,
    pub quality: &'a SeamQuality,
    pub edge_fit_rms_mm: [f64; 2],
    /// Each weld edge's boundary samples beyond its fitted line, towards
    /// the other plate, by more than the fit's trimming limit (weld edges
    /// only: a fillet root's fits are faces).
    pub edge_beyond: Option<[Beyond; 2]>,
    /// Each weld edge's largest step between two runs of its samples
    /// ([`super::refit::largest_step`]), where it has samples enough and
    /// the edge places the weld (both of a butt joint, a lap's upper one).
    pub edge_steps: Option<[Option<Step>; 2]>,
    /// The fraction of the seam each weld edge was seen along (robust
    /// method).
    pub edge_coverage: Option<[f64; 2]>,
    /// How much of the visible joint the seam spans, when both plates are
    /// seen beside it.
    pub coverage: Option<&'a SeamCoverage>,
    /// How far beyond the seam's first and last end both plates are still
    /// seen beside the weld, mm (on the camera's grid).
    pub joint_beyond_ends_mm: Option<[f64; 2]>,
    /// The planned seam's length along its feature axis, mm.
    pub length_mm: f64,
    /// V-butt joints: the groove depth the request gave, if it gave one.
    pub given_groove_depth_mm: Option<f64>,
    /// What the two fits behind `edge_fit_rms_mm` and `edge_coverage` are.
    pub fits: FittedEdges,
}

/// What a seam's two fits are, for the words of a refusal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FittedEdges {
    /// Two weld edges, each a line through its plate's boundary samples.
    WeldEdges,
    /// A fillet root: the web's side face and the flange beside it.
    WebFace,
    /// A fillet root read from the flange's edge against the web (the face
    /// returning no points): that edge's line, under the web top's edge,
    /// and the flange beside it.
    FlangeEdge,
}

impl FittedEdges {
    /// Fit `k`'s name and what a high residual says of it.
    fn fit(self, k: usize) -> (String, &'static str) {
        let plane = "its points do not lie on one plane";
        match (self, k) {
            (FittedEdges::WeldEdges, k) => {
                (format!("weld edge {}", k + 1), "its boundary samples do not lie on one line")
            }
            (FittedEdges::WebFace, 0) => ("the web's side face".into(), plane),
            (FittedEdges::FlangeEdge, 0) => {
                ("the flange's edge against the web".into(), "its innermost points do not lie on one line")
            }
            (_, _) => ("the flange beside the root".into(), plane),
        }
    }

    /// What evidence `k` of a fillet root is, for its coverage.
    fn fillet_evidence(self, k: usize) -> &'static str {
        match (self, k) {
            (FittedEdges::FlangeEdge, 0) => "the web top's edge above the root",
            (FittedEdges::FlangeEdge, _) => "the flange's edge against the web",
            (_, 0) => "the web's face down to the flange",
            (_, _) => "the flange up to the web",
        }
    }
}

/// Which of two edges' figures is the larger (the first on a tie): the
/// one a gate names.
fn larger(values: [f64; 2]) -> usize {
    if values[0] >= values[1] { 0 } else { 1 }
}

/// The `edge_cut_short` gate: the share of an edge's samples beyond its
/// line first (the edge's true line where most of it was cut short), then
/// a step between two runs of them (a fit between the two lines, or
/// following one with the other's run just inside that share).
fn cut_short(seam: &SeamEvidence, limits: &QualityParams) -> Option<GateFailure> {
    let unclear = "(a dropout or a shadow over the joint), and which line is the plate's edge is not clear";
    if let Some(beyond) = seam.edge_beyond {
        let edge = larger(beyond.map(|b| b.share()));
        let b = beyond[edge];
        if b.share() > limits.max_edge_samples_beyond {
            return Some(GateFailure {
                rule: pending::for_stage(Stage::Quality),
                gate: Gate::EdgeCutShort,
                value: b.share(),
                limit: limits.max_edge_samples_beyond,
                message: format!(
                    "weld edge {}: {} of its {} boundary samples ({:.0} %, above {:.0} %) lie beyond the line the \
                     rest fit, {:.1} mm on average towards the other plate: the edge may be cut short along the \
                     rest {unclear}",
                    edge + 1,
                    b.count,
                    b.of,
                    100.0 * b.share(),
                    100.0 * limits.max_edge_samples_beyond,
                    b.mean_mm,
                ),
            });
        }
    }
    let spacing = seam.quality.point_spacing_mm;
    let steps = seam.edge_steps?;
    let edge = larger(steps.map(|s| s.map_or(0.0, |s| s.size_mm.abs())));
    let step = steps[edge]?;
    let spacings = step.size_mm.abs() / spacing;
    (spacings > limits.max_edge_step_spacings).then(|| GateFailure {
        rule: pending::for_stage(Stage::Quality),
        gate: Gate::EdgeCutShort,
        value: spacings,
        limit: limits.max_edge_step_spacings,
        message: format!(
            "weld edge {}'s boundary samples lie on two lines {:.2} mm apart ({spacings:.1} point spacings of \
             {spacing:.2} mm, above {:.1}), {:.0} % of them on the shorter, split {:+.0} mm from the middle of \
             the edge: the edge may be cut short along one of them {unclear}",
            edge + 1,
            step.size_mm.abs(),
            limits.max_edge_step_spacings,
            100.0 * step.shorter_share,
            step.at_mm,
        ),
    })
}

/// Every gate `seam` fails, in [`Gate::ALL`]'s order.
pub fn check(seam: &SeamEvidence, limits: &QualityParams) -> Vec<GateFailure> {
    let q = seam.quality;
    let mut failed: Vec<GateFailure> = cut_short(seam, limits).into_iter().collect();
    let mut fail = |gate, value: f64, limit: f64, message: String| {
        failed.push(GateFailure { rule: pending::for_stage(Stage::Quality), gate, value, limit, message });
    };

    let tee = seam.joint == JointType::TFillet;

    let edge = larger(seam.edge_fit_rms_mm);
    let rms = seam.edge_fit_rms_mm[edge];
    let (name, fitted) = seam.fits.fit(edge);
    let rms_limit = limits.max_edge_fit_rms_spacings * q.point_spacing_mm;
    if rms > rms_limit {
        fail(
            Gate::EdgeFitResidual,
            rms,
            rms_limit,
            format!(
                "{name}'s fit residual is {rms:.2} mm, above {rms_limit:.2} mm ({} point spacings of {:.2} mm): \
                 {fitted}",
                limits.max_edge_fit_rms_spacings, q.point_spacing_mm
            ),
        );
    }

    if let Some(e) = seam.edge_coverage {
        let (edge, seen) = if e[0] <= e[1] { (0, e[0]) } else { (1, e[1]) };
        if seen < limits.min_edge_coverage {
            let message = if tee {
                format!(
                    "{} is seen along {:.0} % of the root's {:.0} mm, below {:.0} %: the root is not seen along \
                     the stretch planned",
                    seam.fits.fillet_evidence(edge),
                    100.0 * seen,
                    seam.length_mm,
                    100.0 * limits.min_edge_coverage,
                )
            } else {
                format!(
                    "weld edge {} is seen along {:.0} % of the seam's {:.0} mm, below {:.0} %: the plates' \
                     boundary is not resolved there (a gap narrower than about two point spacings, {:.2} mm, \
                     cannot be seen)",
                    edge + 1,
                    100.0 * seen,
                    seam.length_mm,
                    100.0 * limits.min_edge_coverage,
                    2.0 * q.point_spacing_mm,
                )
            };
            fail(Gate::EdgeCoverage, seen, limits.min_edge_coverage, message);
        }
    }
    if let Some(c) = seam.coverage
        && c.joint < limits.min_joint_coverage
    {
        fail(
            Gate::JointCoverage,
            c.joint,
            limits.min_joint_coverage,
            format!(
                "the seam spans {:.0} % of the {:.0} mm of joint both plates are seen beside, below {:.0} %: \
                     its edges were found along part of the joint only",
                100.0 * c.joint,
                c.visible_joint_mm,
                100.0 * limits.min_joint_coverage,
            ),
        );
    }

    if let Some(beyond) = seam.joint_beyond_ends_mm {
        let (end, mm) = if beyond[0] >= beyond[1] { ("first", beyond[0]) } else { ("last", beyond[1]) };
        if mm > limits.max_joint_beyond_seam_mm {
            let limit = limits.max_joint_beyond_seam_mm;
            let message = if seam.joint == JointType::TFillet {
                format!(
                    "the web's top and the flange up to the root are seen for {mm:.1} mm beyond the root's {end} \
                     end, more than {limit:.1} mm, where the web's side face is not seen down to the flange \
                     (turned nearly edge-on to the camera or the projector, or covered); the seam would stop \
                     short of the root"
                )
            } else {
                format!(
                    "both plates are seen beside the joint for {mm:.1} mm beyond the seam's {end} end, more than \
                     {limit:.1} mm: a weld edge was lost there while its plate goes on (a streak, spatter or a \
                     reflection over the edge); the seam would stop short of the joint"
                )
            };
            fail(Gate::JointCoverage, mm, limit, message);
        }
    }

    if let Some(h) = q.misalignment_mm {
        // The thickness is not seen, only its ceiling (the plates may lie on
        // spacers): the fraction of that ceiling never refuses a seam the
        // real thickness would pass.
        let (limit, why) = match q.depth_to_support_mm {
            Some(t) if limits.max_misalignment_of_thickness * t < limits.max_misalignment_mm => (
                limits.max_misalignment_of_thickness * t,
                format!(
                    "{} of the plates' thickness, at most the {t:.1} mm to the surface they rest on",
                    limits.max_misalignment_of_thickness
                ),
            ),
            _ => (limits.max_misalignment_mm, "quality.max_misalignment_mm".to_string()),
        };
        if h > limit {
            fail(
                Gate::Misalignment,
                h,
                limit,
                format!("the plates' edges are misaligned by {h:.2} mm along the normal, above {limit:.2} mm ({why})"),
            );
        }
    }

    if let (JointType::IButt, Some(gap)) = (seam.joint, q.gap_mm)
        && gap.max > limits.max_gap_mm
    {
        fail(
            Gate::GapWidth,
            gap.max,
            limits.max_gap_mm,
            format!(
                "the gap between the plates opens to {:.2} mm (mean {:.2} mm), wider than {:.2} mm",
                gap.max, gap.mean, limits.max_gap_mm
            ),
        );
    }

    // A gap is measured between two fitted edges, each a plate's last
    // points, a spacing or so short of where the plate ends: a gap under
    // a spacing is not measured but guessed (plates touching measure a
    // few tenths), and a joint as narrow elsewhere would leave its two
    // plates one cluster, so the plates paired here may not be the joint's.
    if let (JointType::IButt, Some(gap)) = (seam.joint, q.gap_mm) {
        let limit = limits.min_gap_spacings * q.point_spacing_mm;
        if gap.max < limit {
            fail(
                Gate::GapUnresolved,
                gap.max,
                limit,
                format!(
                    "the gap between the plates measures {:.2} mm at its widest, under {limit:.2} mm, {} times \
                     the cloud's {:.2} mm point spacing (quality.min_gap_spacings): the cloud does not resolve a \
                     gap this narrow, so it cannot show where plates part, here or across a plate it sees whole; \
                     plan from a finer cloud (voxels under half the narrowest gap)",
                    gap.max, limits.min_gap_spacings, q.point_spacing_mm
                ),
            );
        }
    }

    if seam.joint == JointType::TFillet {
        let tilt = (q.plate_angle_deg - 90.0).abs();
        if tilt > limits.max_web_tilt_deg {
            fail(
                Gate::PlateAngle,
                tilt,
                limits.max_web_tilt_deg,
                format!(
                    "the web's side face meets the flange at {:.1}°, {tilt:.1}° off square, above {:.1}° \
                     (quality.max_web_tilt_deg): the face fitted is not a web standing on the flange",
                    q.plate_angle_deg, limits.max_web_tilt_deg
                ),
            );
        }
    } else if q.plate_angle_deg > limits.max_plate_angle_deg {
        fail(
            Gate::PlateAngle,
            q.plate_angle_deg,
            limits.max_plate_angle_deg,
            format!(
                "the two plates' planes meet at {:.1}°, above {:.1}°: they are not the parallel plates of a {} joint",
                q.plate_angle_deg, limits.max_plate_angle_deg, seam.joint
            ),
        );
    }

    if let (Some(given), Some(measured)) = (seam.given_groove_depth_mm, q.groove_depth_mm) {
        let difference = (given - measured).abs();
        if difference > limits.max_groove_depth_difference_mm {
            fail(
                Gate::GrooveDepth,
                difference,
                limits.max_groove_depth_difference_mm,
                format!(
                    "the groove depth given, {given:.2} mm, differs from the {measured:.2} mm measured by \
                     {difference:.2} mm, above {:.2} mm: the weld would lie that far off the root",
                    limits.max_groove_depth_difference_mm
                ),
            );
        }
    }

    let uncertainty = q.uncertainty_across_mm.max(q.uncertainty_normal_mm);
    if uncertainty > limits.max_position_uncertainty_mm {
        fail(
            Gate::PositionUncertainty,
            uncertainty,
            limits.max_position_uncertainty_mm,
            format!(
                "the seam's position is known to {uncertainty:.2} mm (one sigma), above {:.2} mm",
                limits.max_position_uncertainty_mm
            ),
        );
    }
    failed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::refit::{SeamAxes, SeamCurve};

    fn edge(across: f64, height: f64, rms: f64, samples: usize) -> CurveFit {
        let axes = SeamAxes { origin: Vec3::zeros(), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() };
        CurveFit {
            curve: SeamCurve { axes, coef_a: vec![across, 0.0], coef_b: vec![height, 0.0], s_min: -50.0, s_max: 50.0 },
            rms_mm: rms,
            points_used: samples,
            points_dropped: 0,
        }
    }

    fn plane(tilt_deg: f64, offset: f64) -> Plane {
        let t = tilt_deg.to_radians();
        Plane { normal: Vec3::new(t.sin(), 0.0, t.cos()), offset }
    }

    fn measured(joint: JointType, fits: &[CurveFit; 2], planes: [&Plane; 2]) -> SeamQuality {
        measure(&SeamFits {
            joint,
            fits,
            degree: 1,
            planes,
            span: (-50.0, 50.0),
            point_spacing_mm: 0.3,
            depth_to_support_mm: Some(10.0),
            lap_step_mm: crate::pipeline::weld_equation::lap_step(&fits[0].curve, planes[1], &planes[0].normal, 0.0),
            groove: None,
        })
    }

    fn evidence<'a>(joint: JointType, q: &'a SeamQuality, rms: [f64; 2]) -> SeamEvidence<'a> {
        SeamEvidence {
            joint,
            quality: q,
            edge_fit_rms_mm: rms,
            edge_beyond: None,
            edge_steps: None,
            edge_coverage: None,
            coverage: None,
            joint_beyond_ends_mm: None,
            length_mm: 100.0,
            given_groove_depth_mm: None,
            fits: FittedEdges::WeldEdges,
        }
    }

    #[test]
    fn the_gap_and_the_misalignment_are_read_across_and_along_the_normal() {
        // The first edge lies on the flat plate, the second on the high one.
        let (flat, high) = (plane(0.0, 0.0), plane(0.0, 1.5));
        let fits = [edge(-1.0, 0.0, 0.05, 300), edge(1.5, 1.5, 0.05, 300)];
        let q = measured(JointType::IButt, &fits, [&flat, &high]);
        let gap = q.gap_mm.unwrap();
        assert!((gap.min - 2.5).abs() < 1e-9 && (gap.max - 2.5).abs() < 1e-9);
        assert!((q.misalignment_mm.unwrap() - 1.5).abs() < 1e-9);
        assert_eq!(q.lap_step_mm, None);
        let lap = measured(JointType::Lap, &fits, [&flat, &high]);
        assert_eq!((lap.gap_mm, lap.misalignment_mm), (None, None));
        assert!((lap.lap_step_mm.unwrap() - 1.5).abs() < 1e-9);
    }

    #[test]
    fn the_uncertainty_falls_with_samples_and_never_below_the_boundary_floor() {
        let flat = plane(0.0, 500.0);
        let sparse = measured(JointType::IButt, &[edge(-1.0, 0.0, 0.5, 10), edge(1.0, 0.0, 0.5, 10)], [&flat, &flat]);
        let dense =
            measured(JointType::IButt, &[edge(-1.0, 0.0, 0.5, 1000), edge(1.0, 0.0, 0.5, 1000)], [&flat, &flat]);
        assert!(sparse.uncertainty_across_mm > 2.0 * dense.uncertainty_across_mm);
        let exact =
            measured(JointType::IButt, &[edge(-1.0, 0.0, 0.0, 1000), edge(1.0, 0.0, 0.0, 1000)], [&flat, &flat]);
        let floor = 0.5 * std::f64::consts::SQRT_2 * 0.3 / 12f64.sqrt();
        assert!((exact.uncertainty_across_mm - floor).abs() < 1e-12);
    }

    #[test]
    fn a_good_seam_passes_every_gate() {
        let flat = plane(0.0, 500.0);
        let fits = [edge(-1.0, 0.0, 0.05, 300), edge(1.0, 0.1, 0.06, 300)];
        let q = measured(JointType::IButt, &fits, [&flat, &flat]);
        assert_eq!(check(&evidence(JointType::IButt, &q, [0.05, 0.06]), &QualityParams::default()), vec![]);
    }

    #[test]
    fn an_i_butt_gap_under_a_point_spacing_is_not_resolved() {
        // The points lie 0.3 mm apart (`measured`).
        let flat = plane(0.0, 500.0);
        let gates = |gap: f64, joint: JointType, limits: &QualityParams| {
            let fits = [edge(-gap / 2.0, 0.0, 0.05, 300), edge(gap / 2.0, 0.0, 0.05, 300)];
            let q = measured(joint, &fits, [&flat, &flat]);
            check(&evidence(joint, &q, [0.05, 0.05]), limits)
        };
        let limits = QualityParams::default();
        let failed = gates(0.2, JointType::IButt, &limits);
        assert_eq!(failed.iter().map(|f| f.gate).collect::<Vec<_>>(), vec![Gate::GapUnresolved]);
        let message = &failed[0].message;
        assert!(message.contains("0.20 mm at its widest, under 0.30 mm"), "{message}");
        assert!((failed[0].value - 0.2).abs() < 1e-9 && (failed[0].limit - 0.3).abs() < 1e-9);
        // A gap of a spacing and more is resolved.
        assert_eq!(gates(0.31, JointType::IButt, &limits), vec![]);
        // A V-groove's edges are its top, not a root gap.
        assert_eq!(gates(0.2, JointType::VButt, &limits), vec![]);
        // Turned off.
        assert_eq!(gates(0.2, JointType::IButt, &QualityParams { min_gap_spacings: 0.0, ..limits }), vec![]);
    }

    #[test]
    fn each_gate_names_its_figure_value_and_limit() {
        let limits = QualityParams::default();
        let flat = plane(0.0, 500.0);
        // Misaligned by 2 mm on 10 mm plates: the limit is 0.15 t = 1.5 mm.
        let fits = [edge(-1.0, 0.0, 0.05, 300), edge(1.0, 2.0, 0.05, 300)];
        let q = measured(JointType::IButt, &fits, [&flat, &flat]);
        let failed = check(&evidence(JointType::IButt, &q, [0.05, 0.05]), &limits);
        assert_eq!(failed.iter().map(|f| f.gate).collect::<Vec<_>>(), vec![Gate::Misalignment]);
        assert!((failed[0].limit - 1.5).abs() < 1e-9, "{failed:?}");
        assert!(
            failed[0].message.contains("2.00 mm") && failed[0].message.contains("1.50 mm"),
            "{}",
            failed[0].message
        );

        // A scattered edge, a wide gap, tilted plates.
        let tilted = plane(20.0, 500.0);
        let fits = [edge(-3.0, 0.0, 3.0, 20), edge(3.0, 0.0, 0.05, 300)];
        let q = measured(JointType::IButt, &fits, [&flat, &tilted]);
        let failed = check(&evidence(JointType::IButt, &q, [3.0, 0.05]), &limits);
        let gates: Vec<Gate> = failed.iter().map(|f| f.gate).collect();
        assert_eq!(gates, vec![Gate::EdgeFitResidual, Gate::GapWidth, Gate::PlateAngle, Gate::PositionUncertainty]);
        assert!(failed[0].message.starts_with("weld edge 1's fit residual is 3.00 mm"), "{}", failed[0].message);

        // Coverage: an edge seen along a third of the seam, a seam over
        // third of the visible joint.
        let coverage = SeamCoverage { edge: [0.9, 0.3], joint: 0.3, visible_joint_mm: 200.0, beyond_mm: 0.0 };
        let fits = [edge(-1.0, 0.0, 0.05, 300), edge(1.0, 0.0, 0.05, 300)];
        let q = measured(JointType::IButt, &fits, [&flat, &flat]);
        let seam = SeamEvidence {
            edge_coverage: Some(coverage.edge),
            coverage: Some(&coverage),
            ..evidence(JointType::IButt, &q, [0.05, 0.05])
        };
        let failed = check(&seam, &limits);
        assert_eq!(failed.iter().map(|f| f.gate).collect::<Vec<_>>(), vec![Gate::EdgeCoverage, Gate::JointCoverage]);
        assert!(failed[0].message.starts_with("weld edge 2 is seen along 30 %"), "{}", failed[0].message);

        // The plates still seen side by side 28 mm beyond the last end:
        // refused; a millimetre beyond the first is the rim, not a joint.
        let seam =
            SeamEvidence { joint_beyond_ends_mm: Some([1.0, 28.0]), ..evidence(JointType::IButt, &q, [0.05, 0.05]) };
        let failed = check(&seam, &limits);
        assert_eq!(failed.iter().map(|f| f.gate).collect::<Vec<_>>(), vec![Gate::JointCoverage]);
        assert!(failed[0].message.contains("28.0 mm beyond the seam's last end"), "{}", failed[0].message);
        let seam =
            SeamEvidence { joint_beyond_ends_mm: Some([1.0, 1.9]), ..evidence(JointType::IButt, &q, [0.05, 0.05]) };
        assert!(check(&seam, &limits).is_empty());
        // A fillet root: the web and the flange go on past it, its face
        // not seen there; the refusal says so, not that a plate goes on.
        let seam = SeamEvidence {
            joint_beyond_ends_mm: Some([38.9, 0.0]),
            fits: FittedEdges::WebFace,
            ..evidence(JointType::TFillet, &q, [0.05, 0.05])
        };
        // (The butt joint's figures fail the web's angle too.)
        let failed: Vec<_> = check(&seam, &limits).into_iter().filter(|f| f.gate == Gate::JointCoverage).collect();
        assert_eq!(failed.len(), 1);
        assert!(
            failed[0].message.starts_with(
                "the web's top and the flange up to the root are seen for 38.9 mm beyond the root's first end"
            ) && failed[0].message.contains("side face is not seen down to the flange"),
            "{}",
            failed[0].message
        );

        // A lap's upper edge with 30 of its 200 samples 2 mm beyond the
        // line the rest fit: cut short along the rest. 19 of 200 pass.
        let beyond = |count| Beyond { count, of: 200, mean_mm: 2.04 };
        let seam = SeamEvidence {
            edge_beyond: Some([Beyond { count: 0, of: 180, mean_mm: 0.0 }, beyond(30)]),
            ..evidence(JointType::Lap, &q, [0.05, 0.05])
        };
        let failed = check(&seam, &limits);
        assert_eq!(failed.iter().map(|f| f.gate).collect::<Vec<_>>(), vec![Gate::EdgeCutShort]);
        assert_eq!((failed[0].value, failed[0].limit), (0.15, 0.1));
        assert!(
            failed[0].message.starts_with("weld edge 2: 30 of its 200 boundary samples (15 %, above 10 %)")
                && failed[0].message.contains("2.0 mm on average"),
            "{}",
            failed[0].message
        );
        let seam = SeamEvidence { edge_beyond: Some([beyond(19), beyond(0)]), ..seam };
        assert!(check(&seam, &limits).is_empty());

        // Its samples on two lines 1.2 mm apart (4 spacings of 0.3 mm),
        // split half and half: the fit runs between them. 0.5 mm apart
        // (1.7 spacings) passes.
        let step = |size_mm| Some(Step { size_mm, at_mm: -12.0, shorter_share: 0.48 });
        let seam = SeamEvidence { edge_steps: Some([None, step(-1.2)]), ..seam };
        let failed = check(&seam, &limits);
        assert_eq!(failed.iter().map(|f| f.gate).collect::<Vec<_>>(), vec![Gate::EdgeCutShort]);
        assert!((failed[0].value - 4.0).abs() < 1e-9 && failed[0].limit == 2.0, "{failed:?}");
        assert!(
            failed[0].message.starts_with("weld edge 2's boundary samples lie on two lines 1.20 mm apart")
                && failed[0].message.contains("48 % of them on the shorter, split -12 mm from the middle of the edge"),
            "{}",
            failed[0].message
        );
        let seam = SeamEvidence { edge_steps: Some([step(0.5), step(-0.3)]), ..seam };
        assert!(check(&seam, &limits).is_empty());
    }

    #[test]
    fn gate_names_round_trip() {
        for gate in Gate::ALL {
            assert_eq!(Gate::from_name(gate.name()), Some(gate));
        }
        assert_eq!(Gate::from_name("gap"), None);
    }
}
