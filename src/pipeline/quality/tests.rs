//! The quality figures read from constructed fits, and each gate's rule
//! firing and holding on them.

use super::*;
use crate::config::QualityParams;
use crate::pipeline::SeamCoverage;
use crate::pipeline::refit::{Beyond, SeamAxes, SeamCurve, Step};
use crate::pipeline::straightness::RootBend;

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

/// The ids of the rules `failed` names, in order.
fn ids(failed: &[GateFailure]) -> Vec<&'static str> {
    failed.iter().map(|f| f.rule.id).collect()
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
        root_bend: None,
    }
}

/// A fillet root whose web face follows a tube's foot, bending 6 mm over
/// 60 mm, its fits' residual within the limit: refused by name; bending
/// less than the noise and the resolution explain, planned.
#[test]
fn a_bent_root_is_refused_by_its_sagitta_not_its_residual() {
    let limits = QualityParams::default();
    let flat = plane(0.0, 500.0);
    let fits = [edge(0.0, 0.0, 0.1, 2000), edge(0.0, 0.0, 0.05, 60)];
    // A square web on the flange.
    let q = SeamQuality { plate_angle_deg: 90.0, ..measured(JointType::TFillet, &fits, [&flat, &flat]) };
    let bend = |sagitta_mm: f64| RootBend {
        deviation_mm: sagitta_mm,
        over_mm: 60.0,
        explained_mm: 1.5,
        evidence: "the web's face",
    };
    let tee = |sagitta_mm| SeamEvidence {
        fits: FittedEdges::WebFace,
        root_bend: Some(bend(sagitta_mm)),
        ..evidence(JointType::TFillet, &q, [0.1, 0.05])
    };
    let failed = check(&tee(6.0), &limits);
    assert_eq!(ids(&failed), ["seam.edge_fit_residual"], "{failed:?}");
    assert_eq!(failed[0].gate, Gate::EdgeFitResidual);
    assert!(
        failed[0].message.starts_with("the root bends by 6.0 mm over 60 mm: not a plane weld"),
        "{}",
        failed[0].message
    );
    assert_eq!((failed[0].value, failed[0].limit), (6.0, 1.5));
    let held = check(&tee(1.2), &limits);
    assert!(!ids(&held).contains(&"seam.edge_fit_residual"), "{held:?}");
}

/// A root seen over a few spacings only (a round tube's foot where both
/// faces are seen together over 6 mm of a coarse cloud) shows no curve
/// whatever the joint is: refused as unchecked, with the length it needs;
/// one as long as that is checked as any other.
#[test]
fn a_root_too_short_to_show_a_bend_is_refused_as_unchecked() {
    let limits = QualityParams::default();
    let flat = plane(0.0, 500.0);
    let fits = [edge(0.0, 0.0, 0.1, 40), edge(0.0, 0.0, 0.05, 8)];
    let q = SeamQuality {
        plate_angle_deg: 90.0,
        point_spacing_mm: 1.48,
        ..measured(JointType::TFillet, &fits, [&flat, &flat])
    };
    let tee = |length_mm| SeamEvidence {
        fits: FittedEdges::WebFace,
        length_mm,
        ..evidence(JointType::TFillet, &q, [0.1, 0.05])
    };
    let failed = check(&tee(6.3), &limits);
    assert_eq!(ids(&failed), ["seam.edge_fit_residual"], "{failed:?}");
    assert!(
        failed[0].message.starts_with("the root is seen over 6.3 mm only, under the 8.9 mm (6 stations"),
        "{}",
        failed[0].message
    );
    assert_eq!(failed[0].value, 6.3);
    assert!((failed[0].limit - 6.0 * 1.48).abs() < 1e-12);
    let held = check(&tee(8.9), &limits);
    assert!(!ids(&held).contains(&"seam.edge_fit_residual"), "{held:?}");
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
    let dense = measured(JointType::IButt, &[edge(-1.0, 0.0, 0.5, 1000), edge(1.0, 0.0, 0.5, 1000)], [&flat, &flat]);
    assert!(sparse.uncertainty_across_mm > 2.0 * dense.uncertainty_across_mm);
    let exact = measured(JointType::IButt, &[edge(-1.0, 0.0, 0.0, 1000), edge(1.0, 0.0, 0.0, 1000)], [&flat, &flat]);
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
    assert_eq!(ids(&failed), ["butt.gap_unresolved"]);
    assert_eq!(failed[0].gate, Gate::GapUnresolved);
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
    assert_eq!(ids(&failed), ["butt.misalignment"]);
    assert!((failed[0].limit - 1.5).abs() < 1e-9, "{failed:?}");
    assert!(failed[0].message.contains("2.00 mm") && failed[0].message.contains("1.50 mm"), "{}", failed[0].message);

    // A scattered edge, a wide gap, tilted plates.
    let tilted = plane(20.0, 500.0);
    let fits = [edge(-3.0, 0.0, 3.0, 20), edge(3.0, 0.0, 0.05, 300)];
    let q = measured(JointType::IButt, &fits, [&flat, &tilted]);
    let failed = check(&evidence(JointType::IButt, &q, [3.0, 0.05]), &limits);
    assert_eq!(
        ids(&failed),
        ["seam.edge_fit_residual", "butt.gap_width", "seam.plate_angle", "seam.position_uncertainty"]
    );
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
    assert_eq!(ids(&failed), ["edge.coverage", "seam.joint_coverage"]);
    assert!(failed[0].message.starts_with("weld edge 2 is seen along 30 %"), "{}", failed[0].message);

    // The plates still seen side by side 28 mm beyond the last end:
    // refused; a millimetre beyond the first is the rim, not a joint.
    let seam = SeamEvidence { joint_beyond_ends_mm: Some([1.0, 28.0]), ..evidence(JointType::IButt, &q, [0.05, 0.05]) };
    let failed = check(&seam, &limits);
    assert_eq!(ids(&failed), ["seam.stops_short_of_joint"]);
    assert_eq!(failed[0].gate, Gate::JointCoverage);
    assert!(failed[0].message.contains("28.0 mm beyond the seam's last end"), "{}", failed[0].message);
    let seam = SeamEvidence { joint_beyond_ends_mm: Some([1.0, 1.9]), ..evidence(JointType::IButt, &q, [0.05, 0.05]) };
    assert!(check(&seam, &limits).is_empty());
    // A fillet root: the web and the flange go on past it, its face
    // not seen there; the refusal says so, not that a plate goes on.
    let seam = SeamEvidence {
        joint_beyond_ends_mm: Some([38.9, 0.0]),
        fits: FittedEdges::WebFace,
        ..evidence(JointType::TFillet, &q, [0.05, 0.05])
    };
    // (The butt joint's figures fail the web's angle too.)
    let failed = check(&seam, &limits);
    assert_eq!(ids(&failed), ["seam.stops_short_of_joint", "tee.web_tilt"]);
    assert!(
        failed[0].message.starts_with(
            "the web's top and the flange up to the root are seen for 38.9 mm beyond the root's first end"
        ) && failed[0].message.contains("side face is not seen down to the flange"),
        "{}",
        failed[0].message
    );
}

#[test]
fn an_edge_cut_short_is_refused_by_its_samples_beyond_or_on_two_lines() {
    let limits = QualityParams::default();
    let flat = plane(0.0, 500.0);
    let fits = [edge(-1.0, 0.0, 0.05, 300), edge(1.0, 0.0, 0.05, 300)];
    let q = measured(JointType::Lap, &fits, [&flat, &flat]);
    // A lap's upper edge with 30 of its 200 samples 2 mm beyond the
    // line the rest fit: cut short along the rest. 19 of 200 pass.
    let beyond = |count| Beyond { count, of: 200, mean_mm: 2.04 };
    let seam = SeamEvidence {
        edge_beyond: Some([Beyond { count: 0, of: 180, mean_mm: 0.0 }, beyond(30)]),
        ..evidence(JointType::Lap, &q, [0.05, 0.05])
    };
    let failed = check(&seam, &limits);
    assert_eq!(ids(&failed), ["edge.samples_beyond_line"]);
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
    assert_eq!(ids(&failed), ["edge.samples_on_two_lines"]);
    assert_eq!(failed[0].gate, Gate::EdgeCutShort);
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
fn a_fillet_roots_web_is_square_to_its_flange() {
    let limits = QualityParams::default();
    let flat = plane(0.0, 500.0);
    let fits = [edge(-1.0, 0.0, 0.05, 300), edge(1.0, 0.0, 0.05, 300)];
    let root = |web_angle_deg| SeamQuality {
        plate_angle_deg: web_angle_deg,
        ..measured(JointType::IButt, &fits, [&flat, &flat])
    };
    let tee = |q| SeamEvidence { fits: FittedEdges::WebFace, ..evidence(JointType::TFillet, q, [0.05, 0.05]) };
    // 9° off square passes (a butt joint's plates are held to 5°); 12°
    // off does not.
    let (square_enough, tilted) = (root(99.0), root(78.0));
    assert!(check(&tee(&square_enough), &limits).is_empty());
    let failed = check(&tee(&tilted), &limits);
    assert_eq!(ids(&failed), ["tee.web_tilt"]);
    assert_eq!((failed[0].gate, failed[0].limit), (Gate::PlateAngle, 10.0));
    assert!((failed[0].value - 12.0).abs() < 1e-9, "{failed:?}");
}

#[test]
fn a_groove_depth_given_is_held_to_the_one_measured() {
    let limits = QualityParams::default();
    let flat = plane(0.0, 500.0);
    let fits = [edge(-4.0, 0.0, 0.05, 300), edge(4.0, 0.0, 0.05, 300)];
    let q = SeamQuality { groove_depth_mm: Some(6.0), ..measured(JointType::VButt, &fits, [&flat, &flat]) };
    let given =
        |depth| SeamEvidence { given_groove_depth_mm: Some(depth), ..evidence(JointType::VButt, &q, [0.05, 0.05]) };
    assert!(check(&given(6.8), &limits).is_empty());
    let failed = check(&given(4.5), &limits);
    assert_eq!(ids(&failed), ["butt.groove_depth_difference"]);
    assert_eq!((failed[0].gate, failed[0].value, failed[0].limit), (Gate::GrooveDepth, 1.5, 1.0));
    // No depth measured, nothing to hold the one given to.
    let unmeasured = SeamQuality { groove_depth_mm: None, ..q };
    let seam = SeamEvidence { quality: &unmeasured, ..given(4.5) };
    assert!(check(&seam, &limits).is_empty());
}

#[test]
fn gate_names_round_trip() {
    for gate in Gate::ALL {
        assert_eq!(Gate::from_name(gate.name()), Some(gate));
    }
    assert_eq!(Gate::from_name("gap"), None);
}
