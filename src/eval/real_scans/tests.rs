//! The reference measure and the scoring on constructed clouds (CI has no
//! real scans): a tee whose root is the x axis at z = 500 mm, and a
//! V-groove with a flat root land.

use super::reference::{cloud_points, differs, measure_root, rounded};
use super::*;
use crate::cloud::PointCloud;
use crate::geometry::Vec3;

/// A tee in metres: the flange z = 0.5 for y in 2..30 mm, the web y = 0
/// standing towards the camera for z in 470..498 mm, x in -50..50 mm.
fn tee_cloud() -> PointCloud {
    let mut points = Vec::new();
    for i in -50..=50 {
        let x = i as f32 * 1e-3;
        for j in 2..=30 {
            points.push([x, j as f32 * 1e-3, 0.5]);
        }
        for k in 2..=30 {
            points.push([x, 0.0, 0.5 - k as f32 * 1e-3]);
        }
    }
    PointCloud::unorganized(points)
}

fn axis_box(min: [f64; 3], max: [f64; 3]) -> AxisBox {
    AxisBox { min, max }
}

fn tee_root() -> RootReference {
    RootReference {
        name: "root".into(),
        kind: RootKind::Meet,
        checks: Vec::new(),
        faces: vec![
            FaceBox { name: "web".into(), boxes: vec![axis_box([-0.06, -0.001, 0.46], [0.06, 0.001, 0.495])] },
            FaceBox { name: "flange".into(), boxes: vec![axis_box([-0.06, 0.005, 0.499], [0.06, 0.04, 0.501])] },
        ],
        alternative: Vec::new(),
        measured: None,
    }
}

fn tee_reference() -> ScanReference {
    let points = cloud_points(&tee_cloud());
    let mut root = tee_root();
    root.measured = Some(rounded(&measure_root(&points, &root, 1000.0).expect("the tee's root is measured")));
    ScanReference {
        id: "constructed/tee".into(),
        joint: JointType::TFillet,
        expect: Expect::Planned,
        how: None,
        roots: vec![root],
        refusal: None,
    }
}

/// Waypoints along the x axis from `from` to `to` mm, `off` mm from the
/// root along y.
fn path(from: f64, to: f64, off: f64) -> Vec<Vec3> {
    let n = ((to - from) / 5.0).round() as usize;
    (0..=n).map(|k| Vec3::new(from + 5.0 * k as f64, off, 500.0)).collect()
}

#[test]
fn a_tee_root_is_the_line_where_the_fitted_planes_meet_and_its_visible_stretch_is_where_both_faces_are_seen() {
    let reference = tee_reference();
    let m = reference.roots[0].measured.as_ref().unwrap();
    let (along, off) = m.along_and_off(&Vec3::new(10.0, 0.0, 500.0));
    assert!(off < 1e-3, "the root lies {off} mm off the true one");
    assert!((along - 10.0).abs() < 1e-3 || (along + 10.0).abs() < 1e-3);
    assert!(m.direction[0].abs() > 0.999_999, "direction {:?}", m.direction);
    assert!(m.planes.iter().all(|p| p.rms_mm < 1e-3), "{:?}", m.planes);
    assert!((m.visible_length_mm() - 100.0).abs() < 1e-3, "visible {:?}", m.visible_mm);
    assert_eq!(m.seen_share, 1.0);
}

#[test]
fn a_recomputed_root_equals_the_committed_one_and_a_moved_box_is_caught() {
    let reference = tee_reference();
    let committed = reference.roots[0].measured.as_ref().unwrap();
    let points = cloud_points(&tee_cloud());
    let again = rounded(&measure_root(&points, &tee_root(), 1000.0).unwrap());
    assert_eq!(differs(committed, &again), None);
    // The flange's box shortened to half the root: the plane is the same,
    // but fewer points and a shorter visible stretch.
    let mut shorter = tee_root();
    shorter.faces[1].boxes[0].max[0] = 0.0;
    let moved = rounded(&measure_root(&points, &shorter, 1000.0).unwrap());
    assert!(differs(committed, &moved).is_some());
}

#[test]
fn a_box_with_too_few_points_is_named() {
    let mut root = tee_root();
    root.faces[0].boxes[0] = axis_box([1.0, 1.0, 1.0], [2.0, 2.0, 2.0]);
    let err = measure_root(&cloud_points(&tee_cloud()), &root, 1000.0).unwrap_err();
    assert!(matches!(err, MeasureError::TooFewPoints { ref name, points: 0 } if name == "web"), "{err}");
}

#[test]
fn a_plan_on_the_root_over_most_of_it_is_right_and_a_short_one_falls_short() {
    let reference = tee_reference();
    let on = [path(-47.5, 47.5, 0.3)];
    let s = score(&reference, Ok(&on)).unwrap();
    assert_eq!(s.verdict, Verdict::Right, "{s:?}");
    assert!((s.roots[0].coverage - 0.95).abs() < 1e-3, "{s:?}");
    assert!((s.seams[0].max_mm - 0.3).abs() < 1e-9);
    let half = [path(-45.0, 0.0, 0.3)];
    let s = score(&reference, Ok(&half)).unwrap();
    assert_eq!(s.verdict, Verdict::ShortOfBar, "{s:?}");
    assert!((s.roots[0].coverage - 0.45).abs() < 1e-3, "{s:?}");
    // 1.5 mm off: within 2 mm, but nothing within the tee's 1 mm bar.
    let off = [path(-45.0, 45.0, 1.5)];
    let s = score(&reference, Ok(&off)).unwrap();
    assert_eq!(s.verdict, Verdict::ShortOfBar, "{s:?}");
    assert_eq!(s.roots[0].coverage, 0.0);
}

/// A root whose alternative boxes put it 0.4 mm aside: a seam is judged
/// by the farther of the two lines, so one within the bar of the first
/// line only is not right, and one between them is.
#[test]
fn a_root_with_an_alternative_line_judges_the_plan_against_both() {
    use super::reference::RootLine;
    let mut reference = tee_reference();
    let m = reference.roots[0].measured.as_mut().unwrap();
    m.alternative = Some(RootLine { point_mm: [0.0, -0.4, 500.0], direction: [1.0, 0.0, 0.0] });
    m.box_choice_mm = Some(0.4);
    let between = [path(-47.5, 47.5, -0.2)];
    let s = score(&reference, Ok(&between)).unwrap();
    assert_eq!(s.verdict, Verdict::Right, "{s:?}");
    assert!((s.seams[0].max_mm - 0.2).abs() < 1e-9, "{s:?}");
    // 0.8 mm from the first line: within its bar, 1.2 mm from the second.
    let aside = [path(-47.5, 47.5, 0.8)];
    let s = score(&reference, Ok(&aside)).unwrap();
    assert_eq!(s.verdict, Verdict::ShortOfBar, "{s:?}");
    assert!((s.seams[0].max_mm - 1.2).abs() < 1e-9, "{s:?}");
    assert_eq!(s.roots[0].coverage, 0.0);
}

#[test]
fn a_seam_more_than_two_mm_off_anywhere_is_confident_wrong() {
    let reference = tee_reference();
    let mut bent = path(-45.0, 45.0, 0.0);
    bent.last_mut().unwrap().y = 2.5;
    let s = score(&reference, Ok(&[bent])).unwrap();
    assert!(matches!(s.verdict, Verdict::ConfidentWrong { .. }), "{s:?}");
}

#[test]
fn a_refusal_is_right_only_where_one_is_expected_and_by_a_rule_of_its_class() {
    let planned = tee_reference();
    let s = score(&planned, Err("tee.no_root_seen")).unwrap();
    assert_eq!(s.verdict, Verdict::Refused { rule: "tee.no_root_seen" });
    let refused = ScanReference {
        id: "constructed/flanks".into(),
        joint: JointType::VButt,
        expect: Expect::Refused,
        how: None,
        roots: Vec::new(),
        refusal: Some(ExpectedRefusal {
            class: RefusalClass::NoPlateTop,
            rules: vec!["workpiece.fewer_than_two_planes".into()],
            why: "flanks only".into(),
        }),
    };
    assert_eq!(score(&refused, Err("workpiece.fewer_than_two_planes")).unwrap().verdict, Verdict::Right);
    assert_eq!(
        score(&refused, Err("tee.web_face_without_top")).unwrap().verdict,
        Verdict::Refused { rule: "tee.web_face_without_top" }
    );
    let any = [path(-45.0, 45.0, 0.0)];
    assert!(matches!(score(&refused, Ok(&any)).unwrap().verdict, Verdict::ConfidentWrong { .. }));
}

#[test]
fn a_groove_with_a_root_land_has_its_root_in_the_middle_of_the_land() {
    // Flanks at 45 degrees from z = 0.5 (the tops' height) down to the
    // land at z = 0.51, which spans y = 1..5 mm: the root is y = 3 mm.
    let mut points = Vec::new();
    for i in -40..=40 {
        let x = i as f32 * 1e-3;
        for k in 0..=20 {
            let h = k as f32 * 0.5e-3;
            points.push([x, 1e-3 - 10e-3 + h, 0.5 + h]);
            points.push([x, 5e-3 + 10e-3 - h, 0.5 + h]);
        }
        for j in 0..=8 {
            points.push([x, 1e-3 + j as f32 * 0.5e-3, 0.51]);
        }
    }
    let points = cloud_points(&PointCloud::unorganized(points));
    let root = RootReference {
        name: "groove".into(),
        kind: RootKind::LandCentre,
        checks: Vec::new(),
        faces: vec![
            FaceBox { name: "-y".into(), boxes: vec![axis_box([-0.05, -0.02, 0.501], [0.05, 0.0, 0.508])] },
            FaceBox { name: "+y".into(), boxes: vec![axis_box([-0.05, 0.006, 0.501], [0.05, 0.02, 0.508])] },
            FaceBox { name: "land".into(), boxes: vec![axis_box([-0.05, 0.002, 0.5095], [0.05, 0.004, 0.5105])] },
        ],
        alternative: Vec::new(),
        measured: None,
    };
    let m = measure_root(&points, &root, 1000.0).unwrap();
    let (_, off) = m.along_and_off(&Vec3::new(0.0, 3.0, 510.0));
    assert!(off < 1e-3, "the root lies {off} mm from the land's middle: {m:?}");
    assert!((m.visible_length_mm() - 80.0).abs() < 1e-3, "{m:?}");
}

#[test]
fn a_references_file_names_what_each_scan_expects() {
    let planned_without_root =
        "mm_per_unit = 1000.0\n[[scan]]\nid = \"a\"\njoint = \"t_fillet\"\nexpect = \"planned\"\n";
    assert!(matches!(parse_references(planned_without_root), Err(ParseProblem::Invalid(_))));
    let refused = "mm_per_unit = 1000.0\n[[scan]]\nid = \"a\"\njoint = \"v-butt\"\nexpect = \"refused\"\n\
                   [scan.refusal]\nclass = \"curved_root\"\nwhy = \"a tube on a cylinder\"\n";
    let parsed = parse_references(refused).unwrap();
    assert_eq!(parsed.scans[0].joint, JointType::VButt);
    assert!(parsed.scans[0].refusal.as_ref().unwrap().rules.is_empty());
    let unknown_key = "mm_per_unit = 1000.0\nextra = 1\n";
    assert!(matches!(parse_references(unknown_key), Err(ParseProblem::Toml(_))));
}

/// A box section's top seen as a sliver: the standing face y = 0 rising
/// towards the camera (z 470..498 mm), the top z = 500 mm from y = 2 to
/// 20 mm with its depths tilted 5° across its width (a stereo camera's
/// smear towards the faces beside it) and scattered ±1 mm, the section's
/// side face y = 22 mm from z = 505 to 540 mm (turned `side_turn_deg` about
/// x). The true root is the x axis at z = 500 mm.
fn sliver_cloud(side_turn_deg: f64) -> PointCloud {
    let mut state = 12345_u64;
    let mut noise = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 2.0
    };
    let (sin, cos) = side_turn_deg.to_radians().sin_cos();
    let mut points = Vec::new();
    for i in -60..=60 {
        let x = i as f64;
        for k in 2..=30 {
            points.push([x, noise(), 500.0 - k as f64]);
        }
        for j in 2..=20 {
            let y = j as f64;
            points.push([x, y, 500.0 + (y - 11.0) * 5f64.to_radians().tan() + noise()]);
        }
        for k in 5..=40 {
            let k = k as f64;
            points.push([x, 22.0 + k * sin + 0.3 * noise(), 500.0 + k * cos]);
        }
    }
    PointCloud::unorganized(points.into_iter().map(|p| p.map(|v| (v / 1000.0) as f32)).collect())
}

fn sliver_faces(from_x: f64) -> Vec<FaceBox> {
    let face = |name: &str, min: [f64; 3], max: [f64; 3]| FaceBox {
        name: name.into(),
        boxes: vec![axis_box([from_x, min[1], min[2]], [-from_x, max[1], max[2]])],
    };
    vec![
        face("standing face", [0.0, -0.003, 0.468], [0.0, 0.003, 0.496]),
        face("sliver", [0.0, 0.001, 0.495], [0.0, 0.021, 0.505]),
        face("side face", [0.0, 0.015, 0.506], [0.0, 0.06, 0.542]),
    ]
}

#[test]
fn a_narrow_noisy_sliver_tilts_a_free_fit_but_not_a_top_fitted_square_to_the_standing_face() {
    let points = cloud_points(&sliver_cloud(0.0));
    let truth = Vec3::new(0.0, 0.0, 500.0);
    let free = RootReference {
        name: "root".into(),
        kind: RootKind::Meet,
        faces: sliver_faces(-0.055)[..2].to_vec(),
        alternative: Vec::new(),
        checks: Vec::new(),
        measured: None,
    };
    let free = measure_root(&points, &free, 1000.0).unwrap();
    let (_, free_off) = free.along_and_off(&truth);
    assert!(free_off > 0.5, "the free fit's root lies only {free_off} mm off");
    let square = RootReference {
        name: "root".into(),
        kind: RootKind::SquareTop,
        faces: sliver_faces(-0.055),
        alternative: sliver_faces(-0.045),
        checks: vec![sliver_faces(-0.055)[1].clone()],
        measured: None,
    };
    let m = measure_root(&points, &square, 1000.0).unwrap();
    let (_, off) = m.along_and_off(&truth);
    assert!(off < 0.1, "the square top's root lies {off} mm off: {m:?}");
    let s = m.square_top.unwrap();
    assert!((s.free_tilt_deg - 5.0).abs() < 1.0, "{s:?}");
    assert!(s.side_off_square_deg < 0.5 && s.sigma_mm < 0.2 && s.square_to_side_mm < 0.05, "{s:?}");
    assert!(m.box_choice_mm.unwrap() < 0.1, "{m:?}");
    // The sliver checked against the top it fixed: on it, in the median.
    assert!(m.checks.len() == 1 && m.checks[0].median_mm.abs() < 0.2, "{:?}", m.checks);
    assert!(m.visible_length_mm() > 100.0, "{m:?}");
    // A side face 5° off square to the standing face: the assumption fails.
    let err = measure_root(&cloud_points(&sliver_cloud(5.0)), &square, 1000.0).unwrap_err();
    assert!(matches!(err, MeasureError::NotSquare { .. }), "{err}");
}
