//! The quality gates: each figure of a seam against its configured limit
//! ([`QualityParams`]), one rule of [`crate::rules::quality`] per check,
//! and the sentence a refusal or a warning says.

use crate::config::QualityParams;
use crate::joint::JointType;
use crate::rules::Rule;
use crate::rules::quality as rules;

use super::{Gate, SeamQuality};
use crate::pipeline::SeamCoverage;
use crate::pipeline::refit::{Beyond, Step};
use crate::pipeline::straightness::{self, RootBend};

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
    /// ([`crate::pipeline::refit::largest_step`]), where it has samples enough and
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
    /// How far the seam's root bends from straight, where its samples
    /// fill stations enough to tell ([`crate::pipeline::straightness`]).
    pub root_bend: Option<RootBend>,
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
    /// A V-groove's root read from its two flanks station by station (its
    /// top edges ragged): both figures are the root line's.
    GrooveRoot,
}

impl FittedEdges {
    /// Fit `k`'s name and what a high residual says of it.
    fn fit(self, k: usize) -> (String, &'static str) {
        let plane = "its points do not lie on one plane";
        match (self, k) {
            (FittedEdges::WeldEdges, k) => {
                (format!("weld edge {}", k + 1), "its boundary samples do not lie on one line")
            }
            (FittedEdges::GrooveRoot, _) => (
                "the groove's root, read from its two flanks station by station,".into(),
                "the flanks' feet do not run along one line",
            ),
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
                rule: &rules::EDGE_SAMPLES_BEYOND_LINE,
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
    // The root's samples, or an edge's, and what two lines of them say.
    let (samples, of, cut) = match seam.fits {
        FittedEdges::GrooveRoot => (
            "the groove's root, read from its two flanks station by station, lies".to_string(),
            "the seam",
            "a flank's foot may be cut short along one of them (a dropout, or spatter on the flank), and which \
             line is the root is not clear"
                .to_string(),
        ),
        _ => (
            format!("weld edge {}'s boundary samples lie", edge + 1),
            "the edge",
            format!("the edge may be cut short along one of them {unclear}"),
        ),
    };
    (spacings > limits.max_edge_step_spacings).then(|| GateFailure {
        rule: &rules::EDGE_SAMPLES_ON_TWO_LINES,
        gate: Gate::EdgeCutShort,
        value: spacings,
        limit: limits.max_edge_step_spacings,
        message: format!(
            "{samples} on two lines {:.2} mm apart ({spacings:.1} point spacings of {spacing:.2} mm, above \
             {:.1}), {:.0} % of them on the shorter, split {:+.0} mm from the middle of {of}: {cut}",
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
    let mut fail = |rule: &'static Rule, value: f64, limit: f64, message: String| {
        let gate = rule.gate.expect("a quality rule has a gate");
        failed.push(GateFailure { rule, gate, value, limit, message });
    };

    let tee = seam.joint == JointType::TFillet;

    let edge = larger(seam.edge_fit_rms_mm);
    let rms = seam.edge_fit_rms_mm[edge];
    let (name, fitted) = seam.fits.fit(edge);
    let rms_limit = limits.max_edge_fit_rms_spacings * q.point_spacing_mm;
    if rms > rms_limit {
        fail(
            &rules::EDGE_FIT_RESIDUAL,
            rms,
            rms_limit,
            format!(
                "{name}'s fit residual is {rms:.2} mm, above {rms_limit:.2} mm ({} point spacings of {:.2} mm): \
                 {fitted}",
                limits.max_edge_fit_rms_spacings, q.point_spacing_mm
            ),
        );
    }

    // A bent root: the fits' residual over the whole stretch is the
    // camera's noise, but their samples station by station follow a curve.
    // A root shorter than the fewest stations of a spacing each cannot
    // show a curve at all: planned, it would be a chord of whatever the
    // joint is, its straightness unchecked (a round tube's foot seen where
    // both faces meet over a few millimetres only).
    let shortest_mm = straightness::shortest_checkable_mm(q.point_spacing_mm);
    if seam.length_mm < shortest_mm && rms <= rms_limit {
        fail(
            &rules::EDGE_FIT_RESIDUAL,
            seam.length_mm,
            shortest_mm,
            format!(
                "the root is seen over {:.1} mm only, under the {shortest_mm:.1} mm ({} stations of a point \
                 spacing of {:.2} mm) that tell a straight root from a bent one: not checked as a plane weld",
                seam.length_mm,
                straightness::MIN_STATIONS,
                q.point_spacing_mm
            ),
        );
    }
    if let Some(bend) = seam.root_bend.filter(RootBend::is_curved)
        && rms <= rms_limit
    {
        fail(
            &rules::EDGE_FIT_RESIDUAL,
            bend.deviation_mm,
            bend.explained_mm,
            format!(
                "the root bends by {:.1} mm over {:.0} mm: not a plane weld ({} leaves the straight root \
                 station by station; the cloud's noise and resolution explain {:.1} mm)",
                bend.deviation_mm, bend.over_mm, bend.evidence, bend.explained_mm
            ),
        );
    }

    if let Some(e) = seam.edge_coverage {
        let (edge, seen) = if e[0] <= e[1] { (0, e[0]) } else { (1, e[1]) };
        if seen < limits.min_edge_coverage {
            let figures = percents_that_differ(seen, limits.min_edge_coverage);
            let message = if seam.fits == FittedEdges::GrooveRoot {
                format!(
                    "both flanks of the groove show its root along {} % of the seam's {:.0} mm, below {} %: the \
                     root is not seen along the stretch planned",
                    figures.0, seam.length_mm, figures.1,
                )
            } else if tee {
                format!(
                    "{} is seen along {} % of the root's {:.0} mm, below {} %: the root is not seen along \
                     the stretch planned",
                    seam.fits.fillet_evidence(edge),
                    figures.0,
                    seam.length_mm,
                    figures.1,
                )
            } else {
                format!(
                    "weld edge {} is seen along {} % of the seam's {:.0} mm, below {} %: the plates' \
                     boundary is not resolved there (a gap narrower than about two point spacings, {:.2} mm, \
                     cannot be seen)",
                    edge + 1,
                    figures.0,
                    seam.length_mm,
                    figures.1,
                    2.0 * q.point_spacing_mm,
                )
            };
            fail(&rules::EDGE_COVERAGE, seen, limits.min_edge_coverage, message);
        }
    }
    if let Some(c) = seam.coverage
        && c.joint < limits.min_joint_coverage
    {
        fail(&rules::JOINT_COVERAGE, c.joint, limits.min_joint_coverage, {
            let (share, limit) = percents_that_differ(c.joint, limits.min_joint_coverage);
            format!(
                "the seam spans {share} % of the {:.0} mm of joint both plates are seen beside, below {limit} %: \
                     its edges were found along part of the joint only",
                c.visible_joint_mm,
            )
        });
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
            fail(&rules::STOPS_SHORT_OF_JOINT, mm, limit, message);
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
                &rules::MISALIGNMENT,
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
            &rules::GAP_WIDTH,
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
                &rules::GAP_UNRESOLVED,
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
                &rules::WEB_TILT,
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
            &rules::PLATE_ANGLE,
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
                &rules::GROOVE_DEPTH_DIFFERENCE,
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
            &rules::POSITION_UNCERTAINTY,
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

/// The most decimals a share is printed with, as a percentage: a figure
/// and its limit closer than 0.0001 % are the same to anyone reading.
const MAX_PERCENT_DECIMALS: usize = 4;

/// A share and its limit as percentages, with the fewest decimals (none
/// at best) that make them differ as printed: a refusal never reads
/// "80 % of the joint, below 80 %".
fn percents_that_differ(share: f64, limit: f64) -> (String, String) {
    let pair = |decimals: usize| (format!("{:.decimals$}", 100.0 * share), format!("{:.decimals$}", 100.0 * limit));
    (0..MAX_PERCENT_DECIMALS).map(pair).find(|(a, b)| a != b).unwrap_or_else(|| pair(MAX_PERCENT_DECIMALS))
}

#[cfg(test)]
mod percent_tests {
    use super::percents_that_differ;

    #[test]
    fn a_share_just_below_its_limit_is_printed_with_the_digits_that_show_it_below() {
        assert_eq!(percents_that_differ(0.7996, 0.8), ("79.96".to_string(), "80.00".to_string()));
        assert_eq!(percents_that_differ(0.79, 0.8), ("79".to_string(), "80".to_string()));
        assert_eq!(percents_that_differ(0.39, 0.8), ("39".to_string(), "80".to_string()));
        assert_eq!(percents_that_differ(0.7999996, 0.8), ("80.0000".to_string(), "80.0000".to_string()));
    }
}
