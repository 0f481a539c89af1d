//! The eval's unit tests: the paper's metric, the verdicts and the
//! matching of returned seams to the true ones.

use super::*;

/// A 100 mm seam along x, hidden from 40 to 60 mm.
fn answer(refuse: bool, with_pieces: bool) -> ScoredAnswer {
    let at = |x: f64| Vec3::new(x, 0.0, 0.0);
    ScoredAnswer {
        refuse,
        whole: [at(0.0), at(100.0)],
        whole_allowed: !refuse,
        pieces: if with_pieces { vec![[at(0.0), at(40.0)], [at(60.0), at(100.0)]] } else { Vec::new() },
        fillet: false,
    }
}

fn path(from: f64, to: f64, off: f64) -> Vec<Vec3> {
    (0..=10).map(|k| Vec3::new(from + (to - from) * k as f64 / 10.0, off, 0.0)).collect()
}

fn wrong_by(verdict: &Verdict) -> f64 {
    match verdict {
        Verdict::ConfidentWrong { error: Some(e), .. } => e.max_mm,
        other => panic!("not a confident wrong seam: {other:?}"),
    }
}

#[test]
fn outcomes_are_within_the_bar_refused_or_confident_wrong() {
    let clean = answer(false, false);
    assert_eq!(classify(&clean, Ok(&[path(0.0, 100.0, 0.3)])), Verdict::WithinBar);
    // Either way round.
    assert_eq!(classify(&clean, Ok(&[path(100.0, 0.0, 0.0)])), Verdict::WithinBar);
    let refused = classify(&clean, Err("weld_edges stage failed: no pair"));
    assert_eq!(refused, Verdict::Refused { reason: "weld_edges stage failed: no pair".into() });
    assert_eq!(classify(&clean, Ok(&[])), Verdict::Refused { reason: "no seam".into() });
    // 1.5 mm beside the seam, and a seam stopping 60 mm short.
    assert!((wrong_by(&classify(&clean, Ok(&[path(0.0, 100.0, 1.5)]))) - 1.5).abs() < 1e-9);
    assert!(wrong_by(&classify(&clean, Ok(&[path(0.0, 40.0, 0.0)]))) > 50.0);
    // Every seam returned must be right.
    let one_bad = [path(0.0, 100.0, 0.0), path(0.0, 100.0, 5.0)];
    assert!((wrong_by(&classify(&clean, Ok(&one_bad))) - 5.0).abs() < 1e-9);
}

#[test]
fn pieces_are_right_where_a_fault_hides_part_of_the_seam() {
    let hidden = answer(false, true);
    assert_eq!(classify(&hidden, Ok(&[path(0.0, 40.0, 0.2)])), Verdict::WithinBar);
    assert_eq!(classify(&hidden, Ok(&[path(99.5, 60.5, 0.0)])), Verdict::WithinBar);
    assert_eq!(classify(&hidden, Ok(&[path(0.0, 100.0, 0.0)])), Verdict::WithinBar);
    assert_eq!(classify(&hidden, Ok(&[path(0.0, 40.0, 0.0), path(60.0, 100.0, 0.0)])), Verdict::WithinBar);
    // Running 10 mm into the hidden stretch is a piece's end 10 mm off.
    let verdict = classify(&hidden, Ok(&[path(0.0, 50.0, 0.0)]));
    assert!(matches!(verdict, Verdict::ConfidentWrong { error: Some(e), .. } if (e.end_mm - 10.0).abs() < 1e-9));
    // A whole seam 1.5 mm off is reported against the whole, not
    // against the piece it lies along but overruns by 60 mm.
    let verdict = classify(&hidden, Ok(&[path(0.0, 100.0, 1.5)]));
    assert!(
        matches!(verdict, Verdict::ConfidentWrong { error: Some(e), .. } if e.start_mm < 2.0 && e.end_mm < 2.0),
        "{verdict:?}"
    );
}

/// A 100 mm seam along x at `y` mm across, seen from 0 to `seen_to`.
fn true_seam(y: f64, joint: JointType, seen_to: f64) -> TrueSeam {
    let at = |x: f64| Vec3::new(x, y, 0.0);
    TrueSeam {
        label: format!("seam at {y}"),
        joint,
        whole: [at(0.0), at(100.0)],
        seen: if seen_to > 0.0 { vec![[at(0.0), at(seen_to)]] } else { Vec::new() },
        seen_share: seen_to / 100.0,
        seen_enough: seen_to >= 50.0,
    }
}

#[test]
fn on_a_tee_a_seam_is_right_only_on_a_root() {
    // Roots 8 mm apart; the camera sees the second.
    let roots = [true_seam(0.0, JointType::TFillet, 0.0), true_seam(8.0, JointType::TFillet, 100.0)];
    assert_eq!(classify_tee(&roots, Ok(&[path(0.0, 100.0, 8.3)])), Verdict::WithinBar);
    // 0.6 mm off the root: within the paper's bar, not a fillet's; and
    // a root stopping 1.5 mm short of a root seen whole.
    let verdict = classify_tee(&roots, Ok(&[path(0.0, 100.0, 8.6)]));
    assert!(matches!(verdict, Verdict::ConfidentWrong { error: Some(e), .. } if e.across_mm > 0.5), "{verdict:?}");
    assert!(matches!(classify_tee(&roots, Ok(&[path(0.0, 98.5, 8.0)])), Verdict::ConfidentWrong { .. }));
    assert_eq!(classify_tee(&roots, Ok(&[path(0.0, 99.5, 8.0)])), Verdict::WithinBar);
    // 0.7 mm past the root's end, on its line: an end's error within
    // its bar, not an error across.
    assert_eq!(classify_tee(&roots, Ok(&[path(0.0, 100.7, 8.0)])), Verdict::WithinBar);
    assert!(matches!(classify_tee(&roots, Ok(&[path(0.0, 101.5, 8.0)])), Verdict::ConfidentWrong { .. }));
    // Between the roots (on the web's foot, a 'butt joint's midline').
    let verdict = classify_tee(&roots, Ok(&[path(0.0, 100.0, 4.0)]));
    assert!((wrong_by(&verdict) - 4.0).abs() < 1e-9, "{verdict:?}");
    // On the hidden root: invented, not seen.
    let verdict = classify_tee(&roots, Ok(&[path(0.0, 100.0, 0.0)]));
    assert!(matches!(verdict, Verdict::ConfidentWrong { .. }), "{verdict:?}");
    let reason = "groove stage failed: ... this looks like a tee joint (a web standing on a flange)";
    assert_eq!(classify_tee(&roots, Err(reason)), Verdict::Refused { reason: reason.into() });
    assert!(names_a_tee(reason) && names_a_tee("t_fillet planning is not built yet"));
    assert!(!names_a_tee("background stage failed: no two layers 1 to 30 mm apart for a lap joint"));
}

#[test]
fn on_a_corner_a_seam_must_name_a_fillet_and_on_an_outside_corner_none_is_right() {
    let corners = crate::sim::corner_suite(crate::sim::Draw::Documented);
    let (inside, outside) = (&corners[0].1, &corners[1].1);
    assert_eq!(inside.joint.corner_kind(), Some(CornerKind::Inside));
    assert_eq!(outside.joint.corner_kind(), Some(CornerKind::Outside));
    let root = [true_seam(0.0, JointType::TFillet, 100.0)];
    let on_root = |joint| vec![(path(0.0, 100.0, 0.1), joint)];
    assert_eq!(classify_one_workpiece(inside, &root, &on_root(JointType::TFillet)), Verdict::WithinBar);
    // On the root, but named a lap: a lap's torch path on a fillet.
    let verdict = classify_one_workpiece(inside, &root, &on_root(JointType::Lap));
    assert!(
        matches!(&verdict, Verdict::ConfidentWrong { error: Some(e), why } if e.max_mm < 0.2 && why.contains("lap")),
        "{verdict:?}"
    );
    // An outside corner is refused by name; a seam on its weld, of any
    // type, is a weld the planner does not plan.
    for joint in [JointType::TFillet, JointType::IButt, JointType::Lap] {
        let verdict = classify_one_workpiece(outside, &root, &on_root(joint));
        assert!(matches!(verdict, Verdict::ConfidentWrong { .. }), "{joint}: {verdict:?}");
    }
    assert!(matches!(classify_one_workpiece(outside, &root, &[]), Verdict::Refused { .. }));
}

#[test]
fn several_seams_are_found_missed_or_extra() {
    let truths = [
        true_seam(0.0, JointType::IButt, 100.0),
        true_seam(200.0, JointType::Lap, 100.0),
        true_seam(400.0, JointType::TFillet, 30.0),
    ];
    let on = |y: f64, joint: JointType| (path(0.0, 100.0, y), joint);
    let m = match_seams(&truths, &[on(200.2, JointType::Lap)]);
    assert_eq!(m.found, [SeamMatch { returned: 0, truth: 1 }]);
    assert_eq!((m.missed.clone(), m.extra.len(), m.seen), (vec![0], 0, 2));
    assert_eq!(classify_several(Ok(&m), &truths), Verdict::WithinBar);
    // The same seam twice: the second is extra; one 5 mm off is extra.
    let m = match_seams(&truths, &[on(0.0, JointType::IButt), on(0.1, JointType::IButt), on(205.0, JointType::Lap)]);
    assert_eq!((m.found.len(), m.extra.len(), m.missed.clone()), (1, 2, vec![1]));
    assert!((m.extra[1].error.unwrap().max_mm - 5.0).abs() < 1e-9);
    assert_eq!((m.extra[0].nearest, m.extra[1].nearest), (Some(0), Some(1)));
    assert!(matches!(classify_several(Ok(&m), &truths), Verdict::ConfidentWrong { .. }));
    // Found, but named another joint.
    let m = match_seams(&truths, &[on(0.0, JointType::Lap)]);
    assert_eq!(m.wrong_type.len(), 1);
    let verdict = classify_several(Ok(&m), &truths);
    assert!(matches!(&verdict, Verdict::ConfidentWrong { why, .. } if why.contains("seam at 0")), "{verdict:?}");
    assert_eq!(classify_several(Err("refused"), &truths), Verdict::Refused { reason: "refused".into() });
}

#[test]
fn any_seam_for_the_wrong_joint_is_confident_wrong() {
    let wrong_joint = answer(true, false);
    let verdict = classify(&wrong_joint, Ok(&[path(0.0, 100.0, 0.0)]));
    assert!(matches!(&verdict, Verdict::ConfidentWrong { why, .. } if why.contains("joint")), "{verdict:?}");
    assert!(wrong_by(&verdict) < 1e-9);
    let reason = "the requested lap joint does not fit: plates coplanar";
    assert_eq!(classify(&wrong_joint, Err(reason)), Verdict::Refused { reason: reason.into() });
}

#[test]
fn a_type_asked_of_every_scene_is_that_type_with_the_depth_measured() {
    let ask = EvalRequest { joint: JointAsk::Type(JointType::VButt), groove_depth: DepthAsk::Given };
    for joint in JointType::ALL {
        let spec = crate::sim::demo_scene(joint);
        assert_eq!(ask.joint_for(&spec), RequestedJoint::Type(JointType::VButt));
        assert_eq!(ask.groove_depth_for(&spec), None, "{joint}: the depth is measured");
    }
}
