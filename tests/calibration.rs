//! Hand-eye calibration on simulated sets of 15 captures with the
//! simulator's noise (robot 0.05 mm and 0.01 degrees per axis, the board's
//! pose or the sphere clouds' sensor noise): the issue's bound of 0.2 mm
//! and 0.05 degrees for target poses, spheres and a camera fixed in the
//! cell; one pose paired with the wrong capture flagged and the result
//! within the bound without it; near-parallel rotation axes warned. Seeds
//! 1 to 10 and, for spheres, 101 were looked at while the solver and the
//! simulated pose sets were written; the others (102 to 108) were added
//! unseen.

use nalgebra::Isometry3;
use weldseam::calibration::prediction::{SphereNaming, calibrate_fitted_spheres};
use weldseam::calibration::sphere::{FittedSphere, fit_spheres};
use weldseam::calibration::{Calibration, Mount, TargetCapture, calibrate_targets};
use weldseam::camera::CameraModel;
use weldseam::sim::calibration::{
    CalibrationSet, CalibrationSpec, CalibrationTarget, DEFAULT_SPHERE_RADII_MM, SimObservation,
    TOOLING_BALL_RADIUS_MM, simulate_calibration,
};

const BOUND_MM: f64 = 0.2;
const BOUND_DEG: f64 = 0.05;

fn simulate(
    target: CalibrationTarget,
    mount: Mount,
    seed: u64,
    tweak: impl Fn(&mut CalibrationSpec),
) -> CalibrationSet {
    let mut spec = CalibrationSpec::new(target, mount, seed);
    tweak(&mut spec);
    spec.validate().unwrap();
    simulate_calibration(&spec, &CameraModel::default())
}

fn target_captures(set: &CalibrationSet) -> Vec<TargetCapture> {
    set.captures
        .iter()
        .map(|c| match &c.observation {
            SimObservation::TargetPose(b) => TargetCapture { base_t_end: c.base_t_end, camera_t_target: *b },
            SimObservation::Cloud(_) => panic!("a board set"),
        })
        .collect()
}

fn solve_targets(set: &CalibrationSet, mount: Mount) -> Calibration {
    calibrate_targets(&target_captures(set), mount).unwrap()
}

fn solve_spheres(set: &CalibrationSet, radii: &[f64], mount: Mount) -> Calibration {
    solve_spheres_named(set, radii, mount, None).0
}

/// Fits the spheres of every capture of a sphere set.
fn fit_set(set: &CalibrationSet, radii: &[f64]) -> Vec<Vec<FittedSphere>> {
    set.captures
        .iter()
        .enumerate()
        .map(|(i, c)| match &c.observation {
            SimObservation::Cloud(cloud) => fit_spheres(cloud.points(), radii, i as u64).unwrap(),
            SimObservation::TargetPose(_) => panic!("a sphere set"),
        })
        .collect()
}

/// Fits, names (by `distances` when given) and solves a sphere set.
fn solve_spheres_named(
    set: &CalibrationSet,
    radii: &[f64],
    mount: Mount,
    distances: Option<&[f64]>,
) -> (Calibration, SphereNaming) {
    solve_fitted(set, &fit_set(set, radii), radii, mount, distances)
}

/// Names (by `distances` when given, then by the first solution's
/// prediction) and solves fitted spheres.
fn solve_fitted(
    set: &CalibrationSet,
    fitted: &[Vec<FittedSphere>],
    radii: &[f64],
    mount: Mount,
    distances: Option<&[f64]>,
) -> (Calibration, SphereNaming) {
    let poses: Vec<Isometry3<f64>> = set.captures.iter().map(|c| c.base_t_end).collect();
    calibrate_fitted_spheres(&poses, fitted, radii, distances, mount).unwrap()
}

/// Translation (mm) and rotation (degrees) between two transforms.
fn error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    ((a.translation.vector - b.translation.vector).norm(), a.rotation.angle_to(&b.rotation).to_degrees())
}

fn assert_within(c: &Calibration, truth: &Isometry3<f64>, what: &str) {
    let (mm, deg) = error(&c.hand_eye, truth);
    assert!(mm < BOUND_MM && deg < BOUND_DEG, "{what}: {mm:.4} mm, {deg:.4} deg off the truth; {c:#?}");
}

#[test]
fn board_poses_give_the_hand_eye_within_the_bound() {
    for seed in [1, 2, 3, 101, 102, 103, 104, 107, 108] {
        let set = simulate(CalibrationTarget::Board, Mount::EyeInHand, seed, |_| {});
        let c = solve_targets(&set, Mount::EyeInHand);
        assert_within(&c, &set.hand_eye, &format!("board seed {seed}"));
        assert!(c.outliers.is_empty() && c.warnings.is_empty(), "seed {seed}: {:?} {:?}", c.outliers, c.warnings);
        let expected = c.expected_error_mm.unwrap();
        assert!(expected > 0.0 && expected < 0.5, "seed {seed}: expected error {expected}");
    }
}

#[test]
fn a_camera_fixed_in_the_cell_is_found_within_the_bound() {
    for seed in [1, 2, 101, 102] {
        let set = simulate(CalibrationTarget::Board, Mount::EyeToHand, seed, |_| {});
        let c = solve_targets(&set, Mount::EyeToHand);
        assert_within(&c, &set.hand_eye, &format!("eye-to-hand board seed {seed}"));
    }
    let radii = DEFAULT_SPHERE_RADII_MM.to_vec();
    let set = simulate(CalibrationTarget::Spheres(radii.clone()), Mount::EyeToHand, 103, |_| {});
    assert_within(&solve_spheres(&set, &radii, Mount::EyeToHand), &set.hand_eye, "eye-to-hand spheres seed 103");
}

#[test]
fn sphere_clouds_give_the_hand_eye_within_the_bound() {
    let radii = DEFAULT_SPHERE_RADII_MM.to_vec();
    for seed in [1, 101, 105, 106] {
        let set = simulate(CalibrationTarget::Spheres(radii.clone()), Mount::EyeInHand, seed, |_| {});
        let c = solve_spheres(&set, &radii, Mount::EyeInHand);
        assert_within(&c, &set.hand_eye, &format!("spheres seed {seed}"));
        assert!(c.outliers.is_empty(), "seed {seed}: {:?}", c.outliers);
    }
}

#[test]
fn equal_spheres_are_told_apart_by_their_distances() {
    let radii = vec![15.0; 3];
    let set = simulate(CalibrationTarget::Spheres(radii.clone()), Mount::EyeInHand, 104, |_| {});
    assert_within(&solve_spheres(&set, &radii, Mount::EyeInHand), &set.hand_eye, "equal spheres seed 104");
}

/// The tooling-ball rig: three balls of 19.05 mm on posts over a table,
/// stray returns, every capture's cloud the whole rig.
fn rig(seed: u64) -> CalibrationSet {
    let radii = vec![TOOLING_BALL_RADIUS_MM; 3];
    simulate(CalibrationTarget::Spheres(radii), Mount::EyeInHand, seed, |s| s.rig = true)
}

/// The rig's three distances, as the capture file gives them.
fn rig_distances(set: &CalibrationSet) -> Vec<f64> {
    let c = &set.sphere_centres;
    [(0, 1), (0, 2), (1, 2)].iter().map(|&(a, b)| (c[a] - c[b]).norm()).collect()
}

/// What a rig seed must give, with its layout given and found (from one
/// radius, as an integrator writes the capture file): every ball it names
/// named right (within 2 mm of where the truth puts it in the camera, and
/// the layout found within 0.2 mm of the truth), the captures it leaves
/// out reported and never used, and a calibration the default gate lets
/// be written; with `issue_bound`, also within the issue's 0.2 mm and 0.05
/// degrees.
fn check_rig(seed: u64, issue_bound: bool) {
    let set = rig(seed);
    let given = rig_distances(&set);
    let fitted = fit_set(&set, &[TOOLING_BALL_RADIUS_MM]);
    for distances in [Some(given.as_slice()), None] {
        let (c, naming) = solve_fitted(&set, &fitted, &[TOOLING_BALL_RADIUS_MM], Mount::EyeInHand, distances);
        let (mm, deg) = error(&c.hand_eye, &set.hand_eye);
        let used = c.residuals.len() - c.outliers.len();
        let left_out: Vec<usize> = naming.left_out().iter().map(|u| u.0).collect();
        eprintln!(
            "rig seed {seed}, layout {}: {mm:.4} mm {deg:.4} deg off the truth; {used} captures used ({} named by \
             the layout, {} by prediction within {:.3} mm), left out {left_out:?}, outliers {:?}, expected error \
             {:.4} mm",
            if distances.is_some() { "given" } else { "found" },
            naming.named_by_layout().len(),
            naming.named_by_prediction().len(),
            naming.tolerance_mm.unwrap_or(f64::NAN),
            c.outliers,
            c.expected_error_mm.unwrap_or(f64::NAN)
        );
        let failures = weldseam::calibration::gate::failures(&c, &Default::default());
        assert!(failures.is_empty(), "seed {seed}: the default gate refuses it: {failures:?}");
        if issue_bound {
            assert_within(&c, &set.hand_eye, &format!("rig seed {seed}"));
            assert!(used >= 8, "seed {seed}: {used} captures used; {:?}", naming.left_out());
        }
        assert!(c.residuals.iter().all(|r| !left_out.contains(&r.capture)), "seed {seed}");
        // A layout found from the captures names the balls in an order of
        // its own: one relabelling of the truth's balls must hold for every
        // capture, each named ball within 2 mm of where the truth puts it.
        let offset = |i: usize, truth_ball: usize, centre: &nalgebra::Vector3<f64>| {
            let camera_t_target = (set.captures[i].base_t_end * set.hand_eye).inverse() * set.target_pose;
            (camera_t_target * nalgebra::Point3::from(set.sphere_centres[truth_ball])).coords.metric_distance(centre)
        };
        let relabellings = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
        let worst = |labels: &[usize; 3]| {
            naming
                .centres
                .iter()
                .enumerate()
                .flat_map(|(i, centres)| {
                    centres.iter().enumerate().filter_map(move |(ball, c)| c.as_ref().map(|c| (i, ball, c)))
                })
                .map(|(i, ball, c)| offset(i, labels[ball], c))
                .fold(0.0_f64, f64::max)
        };
        let best = relabellings.iter().min_by(|a, b| worst(a).total_cmp(&worst(b))).expect("six relabellings");
        for (i, centres) in naming.centres.iter().enumerate() {
            for (ball, centre) in centres.iter().enumerate() {
                let Some(centre) = centre else { continue };
                let off = offset(i, best[ball], centre);
                assert!(off < 2.0, "seed {seed}: capture {i}'s ball {ball} named {off:.1} mm from the truth");
            }
        }
        let mut found = naming.distances.unwrap();
        let mut truth = given.clone();
        found.sort_by(f64::total_cmp);
        truth.sort_by(f64::total_cmp);
        for (f, g) in found.iter().zip(&truth) {
            assert!((f - g).abs() < 0.2, "seed {seed}: layout {found:?}, truth {truth:?}");
        }
    }
}

/// Seeds 1 and 2 were looked at while the sphere search and the naming
/// by prediction were written.
#[test]
fn the_tooling_ball_rig_gives_the_hand_eye_within_the_bound() {
    check_rig(1, true);
    check_rig(2, true);
}

/// Held out: 301 and 302 were run before the naming by prediction was
/// written, but not while it was; 303 and 304 had never run before this
/// test first ran.
#[test]
fn the_tooling_ball_rig_held_out_seeds_are_within_the_bound() {
    for seed in [301, 302, 303, 304] {
        check_rig(seed, true);
    }
}

#[test]
fn a_pose_paired_with_the_wrong_capture_is_flagged_and_left_out() {
    for (seed, wrong) in [(2, 6), (101, 0), (102, 14)] {
        let set = simulate(CalibrationTarget::Board, Mount::EyeInHand, seed, |s| s.wrong_pairing = Some(wrong));
        let c = solve_targets(&set, Mount::EyeInHand);
        assert_eq!(c.outliers, vec![wrong], "seed {seed}: {:#?}", c.residuals);
        assert_within(&c, &set.hand_eye, &format!("board seed {seed} without capture {wrong}"));
        let with = c.hand_eye_with_outliers.unwrap();
        assert!(error(&with, &c.hand_eye).0 > 0.0);
    }
    let radii = DEFAULT_SPHERE_RADII_MM.to_vec();
    let set = simulate(CalibrationTarget::Spheres(radii.clone()), Mount::EyeInHand, 103, |s| s.wrong_pairing = Some(4));
    let c = solve_spheres(&set, &radii, Mount::EyeInHand);
    assert_eq!(c.outliers, vec![4], "{:#?}", c.residuals);
    assert_within(&c, &set.hand_eye, "spheres seed 103 without capture 4");
}

#[test]
fn small_rotations_are_warned() {
    let set = simulate(CalibrationTarget::Board, Mount::EyeInHand, 109, |s| s.small_rotations = true);
    let c = solve_targets(&set, Mount::EyeInHand);
    assert!(c.warnings.iter().any(|w| w.contains("ill-posed") && w.contains("larger rotations")), "{:?}", c.warnings);
}

#[test]
fn near_parallel_rotation_axes_are_warned() {
    for seed in [1, 101] {
        let set = simulate(CalibrationTarget::Board, Mount::EyeInHand, seed, |s| s.parallel_axes = true);
        let captures = target_captures(&set);
        match calibrate_targets(&captures, Mount::EyeInHand) {
            Ok(c) => assert!(
                c.warnings.iter().any(|w| w.contains("nearly parallel") && w.contains("add poses")),
                "seed {seed}: {:?}",
                c.warnings
            ),
            Err(e) => assert!(e.to_string().contains("about one axis"), "seed {seed}: {e}"),
        }
    }
}

/// The `weldseam` binary, run as a script runs it.
fn weldseam(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_weldseam")).args(args).output().expect("run weldseam")
}

/// `weldseam calibrate --json` on the capture file `set`, writing the
/// hand-eye into the config file `config` if the calibration passes.
fn calibrate_writing(set: &std::path::Path, config: &std::path::Path) -> std::process::Output {
    weldseam(&["calibrate", "--captures", set.to_str().unwrap(), "--json", "--write-config", config.to_str().unwrap()])
}

fn matrix(values: &serde_json::Value) -> Isometry3<f64> {
    let v: Vec<f64> = values.as_array().expect("16 numbers").iter().map(|x| x.as_f64().unwrap()).collect();
    let rows: [f64; 16] = v.try_into().expect("16 numbers");
    weldseam::geometry::pose::hand_eye_from_rows(&rows).unwrap()
}

fn json_file(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn simulate_then_calibrate_round_trips_through_files() {
    let dir = tempfile::tempdir().unwrap();
    for (target, extra) in [("board", vec!["--wrong-pairing", "5"]), ("spheres", vec!["--eye-to-hand"])] {
        let set = dir.path().join(format!("{target}/set.json"));
        std::fs::create_dir_all(set.parent().unwrap()).unwrap();
        let truth = dir.path().join(format!("{target}-truth.json"));
        let mut args = vec!["simulate", "--calibration", target, "--seed", "11", "--out", set.to_str().unwrap()];
        args.extend(["--truth", truth.to_str().unwrap()]);
        args.extend(&extra);
        let out = weldseam(&args);
        assert!(out.status.success(), "simulate: {}", String::from_utf8_lossy(&out.stderr));
        let mut args = vec!["calibrate", "--captures", set.to_str().unwrap(), "--json"];
        if target == "spheres" {
            args.push("--eye-to-hand");
        }
        let out = weldseam(&args);
        assert!(out.status.success(), "calibrate: {}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
        let truth = json_file(&truth);
        let (mm, deg) = error(&matrix(&report["hand_eye"]), &matrix(&truth["hand_eye"]));
        assert!(mm < BOUND_MM && deg < BOUND_DEG, "{target}: {mm} mm {deg} deg");
        assert_eq!(report["residuals"].as_array().unwrap().len(), 15);
        let outliers: Vec<u64> = report["outliers"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
        match target {
            "board" => {
                assert_eq!(outliers, vec![5]);
                assert_eq!(report["solved_for"], "End_T_Camera");
            }
            _ => {
                assert!(outliers.is_empty(), "{outliers:?}");
                assert_eq!(report["solved_for"], "Base_T_Camera");
                // A sphere hidden behind another or out of view is missed
                // in a capture or two, never invented.
                let found: Vec<u64> =
                    report["spheres_found"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
                assert!(found.iter().all(|n| *n <= 3) && found.iter().filter(|n| **n == 3).count() >= 12, "{found:?}");
            }
        }
        assert!(report["expected_error_mm"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn write_config_replaces_only_the_hand_eye() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("set.json");
    let out = weldseam(&["simulate", "--calibration", "board", "--seed", "12", "--out", set.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let shipped = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/weldseam.toml")).unwrap();
    let original = shipped.replace("max_reach_mm = 3500.0", "max_reach_mm = 2800.0  # our cell's robot");
    let config = dir.path().join("cell.toml");
    std::fs::write(&config, &original).unwrap();
    let out = calibrate_writing(&set, &config);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let written = std::fs::read_to_string(&config).unwrap();
    // Every line outside the hand-eye's four rows is as it was, the
    // comments above it and the edited key included.
    let outside = |text: &str| -> Vec<String> {
        let mut in_matrix = false;
        text.lines()
            .filter(|line| !line.starts_with("hand_eye_calibration = {"))
            .filter(|line| {
                if line.starts_with("hand_eye = [") {
                    in_matrix = true;
                }
                let keep = !in_matrix;
                if in_matrix && line.trim() == "]" {
                    in_matrix = false;
                }
                keep
            })
            .map(str::to_string)
            .collect()
    };
    assert_eq!(outside(&written), outside(&original));
    assert!(written.contains("# End_T_Camera from the hand-eye calibration") && written.contains("# our cell's robot"));
    let loaded = weldseam::config::Config::load(&config).unwrap();
    assert_eq!(loaded.robot_limits.max_reach_mm, 2800.0);
    // The calibration's figures are recorded beside it.
    let record = loaded.hand_eye_calibration.as_ref().expect("a record beside robot.hand_eye");
    assert!(record.passed && !record.forced && record.failures.is_empty(), "{record:?}");
    let expected = report["expected_error_mm"].as_f64().unwrap();
    assert!((record.expected_error_mm.unwrap() - expected).abs() < 1e-3, "{record:?}");
    let outliers = report["outliers"].as_array().unwrap().len() as u32;
    assert_eq!((record.captures, record.captures_used), (15, 15 - outliers));
    let (mm, deg) = error(&loaded.hand_eye, &matrix(&report["hand_eye"]));
    assert!(mm < 1e-4 && deg < 1e-4, "{mm} mm {deg} deg");
    // A fixed camera's Base_T_Camera is not End_T_Camera.
    let out = weldseam(&[
        "calibrate",
        "--captures",
        set.to_str().unwrap(),
        "--eye-to-hand",
        "--write-config",
        config.to_str().unwrap(),
    ]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("End_T_Camera"));
}

#[test]
fn a_bad_capture_file_is_refused_naming_the_capture_and_the_field() {
    let target = "[1,0,0,0, 0,1,0,0, 0,0,1,500, 0,0,0,1]";
    let cases = [
        (
            format!(r#"{{"captures": [{{"robot_pose": [0,0,0,0,0,0], "camera_T_target": {target}}}, {{"robot_pose": [0,0,0,0,0], "camera_T_target": {target}}}]}}"#),
            "capture 1: robot_pose: a extrinsic_xyz (mm, deg) pose has 6 numbers, got 5",
        ),
        (
            r#"{"captures": [{"robot_pose": [0,0,0,0,0,0], "camera_T_target": [1,0,0]}]}"#.to_string(),
            "capture 0: camera_T_target needs 16 numbers",
        ),
        (r#"{"captures": [{"robot_pose": [0,0,0,0,0,0], "cloud": "a.pcd"}]}"#.to_string(), "sphere_radius_mm"),
        (r#"{"captures": [], "colour": 1}"#.to_string(), "unknown field `colour`"),
        (
            format!(r#"{{"captures": [{}]}}"#, vec![format!(r#"{{"robot_pose": [0,0,0,0,0,0], "camera_T_target": {target}}}"#); 501].join(",")),
            "501 captures; at most 500",
        ),
        (
            r#"{"sphere_radius_mm": 20, "captures": [{"robot_pose": [0,0,0,0,0,0], "cloud": "missing.pcd"}, {"robot_pose": [0,0,0,0,0,0], "cloud": "missing.pcd"}, {"robot_pose": [0,0,0,0,0,0], "cloud": "missing.pcd"}]}"#.to_string(),
            "capture 0: cloud",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (text, expected) in cases {
        let path = dir.path().join("captures.json");
        std::fs::write(&path, &text).unwrap();
        let out = weldseam(&["calibrate", "--captures", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(expected), "{expected}: {stderr}");
    }
}

/// A board set whose rotations are all about one axis (seed 3: the
/// translation along it known to 7 mm), and a copy of the shipped config.
fn untrustworthy_set(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let set = dir.join("set.json");
    let args = ["simulate", "--calibration", "board", "--parallel-axes", "--seed", "3", "--out"];
    let out = weldseam(&[&args[..], &[set.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let config = dir.join("cell.toml");
    std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/config/weldseam.toml"), &config).unwrap();
    (set, config)
}

#[test]
fn an_untrustworthy_calibration_is_never_written() {
    let dir = tempfile::tempdir().unwrap();
    let (set, config) = untrustworthy_set(dir.path());
    let before = std::fs::read(&config).unwrap();
    let out = calibrate_writing(&set, &config);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot be trusted") && stderr.contains("nothing written") && stderr.contains("--force"),
        "{stderr}"
    );
    assert!(stderr.contains("calibration.max_expected_error_mm (0.5 mm)"), "{stderr}");
    assert_eq!(std::fs::read(&config).unwrap(), before, "the config file changed");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("the report still printed");
    assert_eq!(report["gate"]["passed"], false);
    assert!(!report["gate"]["failures"].as_array().unwrap().is_empty());
    // Without --write-config the command fails all the same.
    let out = weldseam(&["calibrate", "--captures", set.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("gate: FAILED"));
    // Limits are the config's: loosened far enough, the same set passes.
    let loose = dir.path().join("loose.toml");
    std::fs::write(&loose, "[calibration]\nmax_expected_error_mm = 100.0\nmax_translation_sigma_mm = 100.0\nmax_rotation_sigma_deg = 10.0\nmin_axis_spread_deg = 0.0\n").unwrap();
    let out = weldseam(&["calibrate", "--captures", set.to_str().unwrap(), "--config", loose.to_str().unwrap()]);
    assert!(out.status.success(), "{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
}

#[test]
fn force_writes_a_failed_calibration_that_the_daemon_then_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let (set, config) = untrustworthy_set(dir.path());
    let out = weldseam(&[
        "calibrate",
        "--captures",
        set.to_str().unwrap(),
        "--force",
        "--write-config",
        config.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--force: the calibration is accepted although") && stderr.contains("records it as failed"),
        "{stderr}"
    );
    let loaded = weldseam::config::Config::load(&config).unwrap();
    let record = loaded.hand_eye_calibration.expect("a record");
    assert!(!record.passed && record.forced && !record.failures.is_empty(), "{record:?}");
    // The daemon refuses to start with it, before it binds anything.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_weldseam"))
        .args(["serve", "--config", config.to_str().unwrap()])
        .args(["--camera-listen", "127.0.0.1:0", "--controller-listen", "127.0.0.1:0", "--text-listen", "127.0.0.1:0"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() > deadline {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("the daemon started with a failed calibration");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    assert!(!status.success(), "{stderr}");
    assert!(
        stderr.contains("robot.hand_eye comes from a calibration that failed its gate")
            && stderr.contains("--force was not given"),
        "{stderr}"
    );
}

#[test]
fn the_rig_through_files_names_its_balls_and_reports_the_captures_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("set.json");
    let truth = dir.path().join("truth.json");
    let out = weldseam(&[
        "simulate",
        "--calibration",
        "spheres",
        "--rig",
        "--seed",
        "1",
        "--out",
        set.to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let file = json_file(&set);
    assert_eq!(file["sphere_radius_mm"], 19.05);
    let config = dir.path().join("cell.toml");
    let out = calibrate_writing(&set, &config);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (mm, deg) = error(&matrix(&report["hand_eye"]), &matrix(&json_file(&truth)["hand_eye"]));
    assert!(mm < BOUND_MM && deg < BOUND_DEG, "{mm} mm {deg} deg");
    assert_eq!(report["gate"]["passed"], true);
    let used: Vec<u64> =
        report["residuals"].as_array().unwrap().iter().map(|r| r["capture"].as_u64().unwrap()).collect();
    let list = |key: &str| -> Vec<u64> {
        report[key].as_array().map_or(Vec::new(), |a| a.iter().map(|v| v.as_u64().unwrap()).collect())
    };
    let (by_layout, by_prediction) = (list("spheres_named_by_layout"), list("spheres_named_by_prediction"));
    // Seed 1 has captures seeing two balls of the three: the layout cannot
    // name them, the first solution's prediction does.
    assert!(!by_prediction.is_empty(), "{report}");
    assert!(report["sphere_prediction_tolerance_mm"].as_f64().unwrap() > 0.0, "{report}");
    let unnamed = report["spheres_unnamed"].as_array().map_or(&[][..], Vec::as_slice);
    for u in unnamed {
        let capture = u["capture"].as_u64().unwrap();
        assert!(!used.contains(&capture) && !u["reason"].as_str().unwrap().is_empty(), "{u}");
    }
    assert_eq!(by_layout.len() + by_prediction.len() + unnamed.len(), 15, "{report}");
    for capture in &used {
        assert!(by_layout.contains(capture) || by_prediction.contains(capture), "capture {capture}: {report}");
    }
    assert!(weldseam::config::Config::load(&config).unwrap().hand_eye_calibration.unwrap().passed);
}
