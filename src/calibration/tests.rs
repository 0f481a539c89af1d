//! The solver on small exact and noisy sets made here (the simulator's
//! sets are tested in tests/calibration.rs).

use nalgebra::{Isometry3, Point3, Vector3};

use super::*;

fn pose(t: [f64; 3], r_deg: [f64; 3]) -> Isometry3<f64> {
    Isometry3::new(Vector3::from(t), Vector3::from(r_deg.map(f64::to_radians)))
}

fn hand_eye() -> Isometry3<f64> {
    pose([40.0, -80.0, 100.0], [3.0, -5.0, 90.0])
}

/// Eight flange poses turning about several axes.
fn hands() -> Vec<Isometry3<f64>> {
    [
        ([400.0, 0.0, 600.0], [180.0, 0.0, 0.0]),
        ([420.0, 30.0, 580.0], [160.0, 10.0, 20.0]),
        ([380.0, -40.0, 610.0], [190.0, -15.0, -30.0]),
        ([410.0, 50.0, 590.0], [170.0, 20.0, 45.0]),
        ([395.0, -20.0, 620.0], [200.0, 5.0, 10.0]),
        ([405.0, 10.0, 600.0], [175.0, -20.0, -15.0]),
        ([390.0, 25.0, 595.0], [185.0, 12.0, 35.0]),
        ([415.0, -35.0, 585.0], [165.0, -8.0, -40.0]),
    ]
    .iter()
    .map(|(t, r)| pose(*t, *r))
    .collect()
}

fn target_captures(x: &Isometry3<f64>, y: &Isometry3<f64>) -> Vec<TargetCapture> {
    hands().into_iter().map(|a| TargetCapture { base_t_end: a, camera_t_target: (a * x).inverse() * y }).collect()
}

fn close(a: &Isometry3<f64>, b: &Isometry3<f64>, mm: f64, deg: f64) -> bool {
    (a.translation.vector - b.translation.vector).norm() < mm && a.rotation.angle_to(&b.rotation).to_degrees() < deg
}

#[test]
fn exact_target_captures_give_the_hand_eye() {
    let y = pose([450.0, 10.0, 0.0], [0.0, 0.0, 30.0]);
    let c = calibrate_targets(&target_captures(&hand_eye(), &y), Mount::EyeInHand).unwrap();
    assert!(close(&c.hand_eye, &hand_eye(), 1e-6, 1e-6), "{:?}", c.hand_eye);
    assert!(c.outliers.is_empty() && c.warnings.is_empty(), "{:?} {:?}", c.outliers, c.warnings);
    assert_eq!(c.closed_forms.len(), 2);
    assert!(c.residuals.iter().all(|r| r.translation_mm < 1e-6));
}

#[test]
fn a_capture_paired_with_the_wrong_pose_is_flagged_and_left_out() {
    let y = pose([450.0, 10.0, 0.0], [0.0, 0.0, 30.0]);
    let mut captures = target_captures(&hand_eye(), &y);
    captures[3].base_t_end = pose([405.0, 5.0, 600.0], [178.0, -3.0, 25.0]);
    let c = calibrate_targets(&captures, Mount::EyeInHand).unwrap();
    assert_eq!(c.outliers, vec![3]);
    assert!(close(&c.hand_eye, &hand_eye(), 1e-6, 1e-6), "{:?}", c.hand_eye);
    assert!(c.residuals[3].translation_mm > 1.0, "{:?}", c.residuals[3]);
    assert!(c.hand_eye_with_outliers.is_some());
    assert!(c.warnings.iter().any(|w| w.contains("capture 3 looks like an outlier")), "{:?}", c.warnings);
}

#[test]
fn eye_to_hand_is_the_same_problem_with_the_poses_inverted() {
    // Camera fixed in the cell, target on the flange.
    let base_t_camera = pose([900.0, -400.0, 800.0], [120.0, -20.0, 15.0]);
    let end_t_target = pose([10.0, -5.0, 150.0], [0.0, 0.0, 12.0]);
    let captures: Vec<TargetCapture> = hands()
        .into_iter()
        .map(|a| TargetCapture { base_t_end: a, camera_t_target: base_t_camera.inverse() * a * end_t_target })
        .collect();
    let c = calibrate_targets(&captures, Mount::EyeToHand).unwrap();
    assert!(close(&c.hand_eye, &base_t_camera, 1e-6, 1e-6), "{:?}", c.hand_eye);
}

#[test]
fn exact_sphere_centres_give_the_hand_eye() {
    let spheres = [Vec3::new(450.0, 10.0, 0.0), Vec3::new(520.0, -60.0, 20.0), Vec3::new(480.0, 70.0, 10.0)];
    let x = hand_eye();
    let captures: Vec<SphereCapture> = hands()
        .into_iter()
        .map(|a| SphereCapture {
            base_t_end: a,
            centres: spheres.iter().map(|s| Some((a * x).inverse() * Point3::from(*s)).map(|p| p.coords)).collect(),
        })
        .collect();
    let c = calibrate_spheres(&captures, Mount::EyeInHand).unwrap();
    assert!(close(&c.hand_eye, &x, 1e-6, 1e-6), "{:?}", c.hand_eye);
    assert!(c.residuals.iter().all(|r| r.rotation_deg.is_some_and(|d| d < 1e-4)), "{:?}", c.residuals);
    // One sphere alone determines it too, with rotations.
    let one: Vec<SphereCapture> =
        captures.iter().map(|c| SphereCapture { base_t_end: c.base_t_end, centres: vec![c.centres[0]] }).collect();
    let c = calibrate_spheres(&one, Mount::EyeInHand).unwrap();
    assert!(close(&c.hand_eye, &x, 1e-6, 1e-6), "{:?}", c.hand_eye);
    assert!(c.residuals.iter().all(|r| r.rotation_deg.is_none()));
}

#[test]
fn too_few_captures_and_unseen_spheres_are_refused() {
    let y = pose([450.0, 10.0, 0.0], [0.0, 0.0, 30.0]);
    let two = &target_captures(&hand_eye(), &y)[..2];
    assert_eq!(calibrate_targets(two, Mount::EyeInHand), Err(CalibrationError::TooFewCaptures { found: 2 }));
    let captures: Vec<SphereCapture> = hands()
        .into_iter()
        .enumerate()
        .map(|(i, a)| SphereCapture {
            base_t_end: a,
            centres: vec![Some(Vec3::new(0.0, 0.0, 500.0)), (i == 0).then(Vec3::zeros)],
        })
        .collect();
    assert_eq!(
        calibrate_spheres(&captures, Mount::EyeInHand),
        Err(CalibrationError::SphereUnseen { sphere: 1, captures: 1 })
    );
}

#[test]
fn rotations_about_one_axis_are_refused_as_degenerate() {
    let y = pose([450.0, 10.0, 0.0], [0.0, 0.0, 30.0]);
    let captures: Vec<TargetCapture> = [0.0, 20.0, 45.0, 70.0]
        .iter()
        .map(|angle| {
            let a = pose([400.0, 0.0, 600.0], [0.0, 0.0, *angle]);
            TargetCapture { base_t_end: a, camera_t_target: (a * hand_eye()).inverse() * y }
        })
        .collect();
    assert!(matches!(calibrate_targets(&captures, Mount::EyeInHand), Err(CalibrationError::Degenerate { .. })));
}
