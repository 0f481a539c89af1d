//! Tests of the evaluation suite's draws and framing measures.

use super::*;

#[test]
fn the_suite_is_stratified_fair_and_fixed() {
    let suite = eval_suite(Draw::Documented);
    assert_eq!(suite.len(), 3 * SCENES_PER_JOINT);
    assert_eq!(suite, eval_suite(Draw::Documented), "the suite is the same on every call");
    let names: std::collections::HashSet<_> = suite.iter().map(|(n, _)| n).collect();
    assert_eq!(names.len(), suite.len(), "scene names are unique");
    let cam = CameraModel::default();
    let mut fill = 0;
    let mut clipped = 0;
    let mut off_across = 0;
    let mut staggered = 0;
    for joint in JointType::ALL {
        let scenes: Vec<_> = suite.iter().filter(|(_, s)| s.joint.joint_type() == joint).collect();
        assert_eq!(scenes.len(), SCENES_PER_JOINT);
        let distances: Vec<f64> = scenes.iter().map(|(_, s)| s.placement.distance_mm).collect();
        let tilts: Vec<f64> = scenes.iter().map(|(_, s)| s.placement.tilt_deg).collect();
        for ends in [[500.0, 1000.0], [0.0, 30.0]] {
            let values = if ends[0] == 500.0 { &distances } else { &tilts };
            assert!(values.contains(&ends[0]) && values.contains(&ends[1]));
            assert!(values.iter().all(|v| (ends[0]..=ends[1]).contains(v)));
            // Stratified: every twenty-first of the range once.
            let mut steps: Vec<i64> =
                values.iter().map(|v| ((v - ends[0]) / (ends[1] - ends[0]) * 21.0).round() as i64).collect();
            steps.sort();
            assert_eq!(steps, (0..22).collect::<Vec<_>>());
        }
    }
    let mut narrow_gaps = 0;
    let (mut upper, mut lower) = (0, 0);
    for (name, spec) in &suite {
        assert_eq!(spec.validate(), Ok(()), "{name}");
        let f = framing(spec, &cam);
        assert!(f.observed_seam_mm >= MIN_OBSERVED_SEAM_MM, "{name}: {f:?}");
        assert!(f.plate_in_view_mm.iter().all(|w| *w >= MIN_PLATE_IN_VIEW_MM), "{name}: {f:?}");
        fill += usize::from(!f.background_visible);
        clipped += usize::from(f.seam_clipped);
        off_across += usize::from(f.plate_runs_off_across);
        staggered += usize::from(spec.plate_a.offset_mm != spec.plate_b.offset_mm);
        assert!((20.0..=60.0).contains(&spec.spacer_height_mm));
        for p in [&spec.plate_a, &spec.plate_b] {
            assert!((60.0..=250.0).contains(&p.width_mm), "{name}");
            assert!((120.0..=400.0).contains(&p.length_mm), "{name}");
        }
        match spec.joint {
            JointGeometry::IButt { gap_mm, .. } => {
                assert!((0.5..=3.0).contains(&gap_mm));
                narrow_gaps += usize::from(gap_mm <= 0.8);
            }
            JointGeometry::VButt { thickness_mm: t, groove_angle_deg: a, groove_depth_mm: d, root_gap_mm: r } => {
                assert!((6.0..=12.0).contains(&t) && (40.0..=70.0).contains(&a));
                assert!((3.0..=t - 1.0).contains(&d) && (0.0..=2.0).contains(&r));
            }
            JointGeometry::Lap { lower_thickness_mm: t1, upper_thickness_mm: t2, overlap_mm: o } => {
                assert!((3.0..=10.0).contains(&t1) && (3.0..=10.0).contains(&t2));
                assert!((20.0..=60.0).contains(&o));
                let on_upper_side = spec.placement.target_offset_mm[0] < 0.0;
                assert_eq!(on_upper_side, name.ends_with("-upper-side"), "{name}");
                if on_upper_side {
                    upper += 1;
                } else {
                    lower += 1;
                }
            }
            JointGeometry::Tee { .. } | JointGeometry::Corner { .. } => {
                panic!("{name}: the eval suite has no tee or corner")
            }
        }
    }
    assert!(narrow_gaps >= 6, "{narrow_gaps} narrow gaps");
    assert_eq!((upper, lower), (11, 11));
    assert!(fill >= 4, "{fill} scenes fill the view");
    assert!(clipped >= 6 && off_across >= 6, "{clipped} clipped, {off_across} wide");
    assert!(staggered >= 10, "{staggered} staggered");
}

#[test]
fn a_fresh_draw_of_the_suite_keeps_its_strata_and_framing() {
    let cam = CameraModel::default();
    let documented = eval_suite(Draw::Documented);
    let fresh = eval_suite(Draw::Fresh(1));
    assert_eq!(fresh.len(), documented.len());
    for ((name, spec), (documented_name, documented_spec)) in fresh.iter().zip(&documented) {
        // The name holds the joint, stratum and framing asked for.
        assert_eq!(name, &format!("{documented_name}-fresh1"));
        assert_eq!(spec.placement.distance_mm, documented_spec.placement.distance_mm, "{name}");
        assert_eq!(spec.placement.tilt_deg, documented_spec.placement.tilt_deg, "{name}");
        assert_ne!(spec.joint, documented_spec.joint, "{name}: the joint is redrawn");
        assert_eq!(spec.validate(), Ok(()), "{name}");
        let f = framing(spec, &cam);
        assert!(f.observed_seam_mm >= MIN_OBSERVED_SEAM_MM, "{name}: {f:?}");
        assert!(f.plate_in_view_mm.iter().all(|w| *w >= MIN_PLATE_IN_VIEW_MM), "{name}: {f:?}");
    }
}

#[test]
fn the_hard_suite_is_stratified_noisy_and_fixed() {
    let suite = hard_suite(Draw::Documented);
    assert_eq!(suite.len(), 3 * SCENES_PER_JOINT);
    assert_eq!(suite, hard_suite(Draw::Documented), "the suite is the same on every call");
    let names: std::collections::HashSet<_> = suite.iter().map(|(n, _)| n).collect();
    assert_eq!(names.len(), suite.len(), "scene names are unique");
    let cam = CameraModel::default();
    let eval_names: Vec<String> = eval_suite(Draw::Documented).into_iter().map(|(n, _)| n).collect();
    for joint in JointType::ALL {
        let scenes: Vec<_> = suite.iter().filter(|(_, s)| s.joint.joint_type() == joint).collect();
        assert_eq!(scenes.len(), SCENES_PER_JOINT);
        let holdouts = scenes.iter().filter(|(n, _)| n.ends_with("-holdout")).count();
        assert_eq!(holdouts, HARD_HOLDOUT_PER_JOINT, "{joint}");
        let tilts: Vec<f64> = scenes.iter().map(|(_, s)| s.placement.tilt_deg).collect();
        let sigmas: Vec<f64> =
            scenes.iter().map(|(_, s)| cam.depth_sigma(s.placement.distance_mm) * s.noise.depth_noise_scale).collect();
        let dropouts: Vec<f64> = scenes.iter().map(|(_, s)| s.noise.dropout_rate).collect();
        for (values, [lo, hi]) in
            [(&tilts, [0.0, HARD_MAX_TILT_DEG]), (&sigmas, HARD_DEPTH_SIGMA_MM), (&dropouts, HARD_DROPOUT_RATE)]
        {
            assert!(values.iter().all(|v| (lo - 1e-9..=hi + 1e-9).contains(v)), "{joint}: {values:?}");
            let reaches = |end: f64| values.iter().any(|v| (v - end).abs() < 1e-9);
            assert!(reaches(lo) && reaches(hi), "{joint}: {values:?} misses {lo} or {hi}");
        }
    }
    for (name, spec) in &suite {
        assert_eq!(spec.validate(), Ok(()), "{name}");
        // The eval suite's strata and framings, renamed.
        let stem = name.strip_prefix("hard-").unwrap();
        assert!(eval_names.iter().any(|n| stem.starts_with(&n[..n.find("-d").unwrap()])), "{name}");
        let f = framing(spec, &cam);
        assert!(f.observed_seam_mm >= MIN_OBSERVED_SEAM_MM, "{name}: {f:?}");
        assert!(f.plate_in_view_mm.iter().all(|w| *w >= MIN_PLATE_IN_VIEW_MM), "{name}: {f:?}");
        assert!(spec.faults.is_empty());
    }
}

#[test]
fn the_fault_suite_has_every_fault_on_every_joint_fair_and_fixed() {
    let suite = fault_suite(Draw::Documented);
    assert_eq!(suite.len(), FaultKind::ALL.len() * 3 * FAULT_SCENES_PER_JOINT);
    assert_eq!(suite, fault_suite(Draw::Documented), "the suite is the same on every call");
    let names: std::collections::HashSet<_> = suite.iter().map(|(n, _)| n).collect();
    assert_eq!(names.len(), suite.len(), "scene names are unique");
    let cam = CameraModel::default();
    for kind in FaultKind::ALL {
        for joint in JointType::ALL {
            let scenes: Vec<_> =
                suite.iter().filter(|(_, s)| s.joint.joint_type() == joint && s.fault_kind() == Some(kind)).collect();
            assert_eq!(scenes.len(), FAULT_SCENES_PER_JOINT, "{kind} {joint}");
            let holdouts = scenes.iter().filter(|(n, _)| n.ends_with("-holdout")).count();
            assert_eq!(holdouts, FAULT_HOLDOUT_PER_JOINT, "{kind} {joint}");
            if kind == FaultKind::WrongJoint {
                let requested: std::collections::HashSet<_> = scenes.iter().map(|(_, s)| s.requested_joint()).collect();
                assert_eq!(requested.len(), 2, "{joint}: both other joints are requested");
                assert!(!requested.contains(&joint));
            }
        }
    }
    let distances: Vec<f64> = suite.iter().map(|(_, s)| s.placement.distance_mm).collect();
    let tilts: Vec<f64> = suite.iter().map(|(_, s)| s.placement.tilt_deg).collect();
    for (values, [lo, hi]) in [(&distances, [500.0, 1000.0]), (&tilts, [0.0, 30.0])] {
        assert!(values.iter().all(|v| (lo..=hi).contains(v)));
        assert!(values.contains(&lo) && values.contains(&hi));
    }
    for (name, spec) in &suite {
        assert_eq!(spec.validate(), Ok(()), "{name}");
        assert_eq!(spec.faults.len(), 1, "{name}");
        assert!(name.starts_with(&format!("fault-{}-", spec.faults[0].kind())), "{name}");
        assert!(fault_framing_ok(spec, &cam), "{name}: {:?}", framing(spec, &cam));
    }
}
