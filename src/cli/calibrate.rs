//! `weldseam calibrate`: reads a capture file (robot poses with target
//! poses or sphere clouds, paths relative to the file), solves the
//! hand-eye with `weldseam::calibration`, and prints a report a person can
//! act on or, with `--json`, one JSON object. The result is held to the
//! config's `[calibration]` limits (`calibration::gate`): one that fails
//! them makes the command exit non-zero and is never written, unless
//! `--force`. `--write-config` puts the result into a config file's
//! `robot.hand_eye` with its record (`robot.hand_eye_calibration`), keeping
//! every other key, comment and blank line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use rayon::prelude::*;

use weldseam::calibration::gate::{self, CalibrationRecord};
use weldseam::calibration::prediction::{SphereNaming, calibrate_fitted_spheres};
use weldseam::calibration::sphere::fit_spheres;
use weldseam::calibration::{Calibration, MAX_CAPTURES, Mount, calibrate_targets};
use weldseam::config::Config;
use weldseam::convert::calibration::{Captures, captures, report, rows};
use weldseam::geometry::conventions::PoseConvention;
use weldseam_proto::calibration::CaptureFile;

/// The largest capture file read: a thousand captures fit in far less.
pub const MAX_CAPTURE_FILE_BYTES: u64 = 16 << 20;
/// The largest cloud file read for a capture, bytes.
pub const MAX_CLOUD_FILE_BYTES: u64 = 512 << 20;
/// The most points a capture's cloud may hold: a 5-megapixel frame.
pub const MAX_CLOUD_POINTS: usize = 5_000_000;

#[derive(Debug, Clone, clap::Args)]
pub struct CalibrateArgs {
    /// The capture file (JSON): {"pose_convention": "zyx", "captures":
    /// [{"robot_pose": [...], "camera_T_target": [16 numbers]}, ...]} or,
    /// for spheres, "sphere_radius_mm" (or "sphere_radii_mm") and
    /// "cloud": "path.pcd" per capture.
    #[arg(long, value_name = "FILE.json")]
    pub captures: PathBuf,
    /// The camera is fixed in the cell and the target rides on the
    /// flange: solve Base_T_Camera instead of End_T_Camera.
    #[arg(long)]
    pub eye_to_hand: bool,
    /// Print one JSON object instead of the report.
    #[arg(long)]
    pub json: bool,
    /// Write the result into this config file's robot.hand_eye, keeping
    /// the rest of the file (created if it does not exist).
    #[arg(long, value_name = "FILE.toml")]
    pub write_config: Option<PathBuf>,
    /// The config whose robot.euler_convention reads poses when the
    /// capture file names no pose_convention, and whose [calibration]
    /// section holds the gate's limits (without it, the --write-config
    /// file when it exists, else the built-in defaults).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Write the result even when it fails the gate's limits: the record
    /// beside robot.hand_eye then says it failed and which limits, and the
    /// daemon refuses to start with it unless started with --force.
    #[arg(long)]
    pub force: bool,
}

/// What the sphere search adds to the report.
struct SphereSummary {
    found: Vec<usize>,
    naming: SphereNaming,
}

pub fn run(args: &CalibrateArgs) -> Result<()> {
    let mount = if args.eye_to_hand { Mount::EyeToHand } else { Mount::EyeInHand };
    if mount == Mount::EyeToHand && args.write_config.is_some() {
        bail!(
            "--write-config with --eye-to-hand: robot.hand_eye holds End_T_Camera for a camera on the flange, not a \
             fixed camera's Base_T_Camera"
        );
    }
    let config_path = args.config.as_deref().or(args.write_config.as_deref().filter(|p| p.exists()));
    let config = Config::load_or_default(config_path)?;
    let file = read_capture_file(&args.captures)?;
    let default = PoseConvention::config(config.euler);
    let input = captures(&file, default).with_context(|| format!("{}", args.captures.display()))?;
    let (calibration, spheres) = match input {
        Captures::Targets(targets) => (calibrate_targets(&targets, mount)?, None),
        Captures::Spheres { radii, distances, captures } => {
            let dir = args.captures.parent().unwrap_or(Path::new("."));
            let (c, summary) = solve_spheres(dir, &radii, distances.as_deref(), &captures, mount)?;
            (c, Some(summary))
        }
    };
    let failures = gate::failures(&calibration, &config.calibration);
    let record = gate::record(&calibration, &failures, args.force);
    if args.json {
        let mut r = report(&calibration, spheres.as_ref().map(|s| s.found.clone()));
        if let Some(s) = &spheres {
            r.spheres_unnamed = s
                .naming
                .left_out()
                .into_iter()
                .map(|(capture, reason)| weldseam_proto::calibration::UnnamedCapture { capture, reason })
                .collect();
            r.spheres_named_by_layout = s.naming.named_by_layout();
            r.spheres_named_by_prediction = s.naming.named_by_prediction();
            r.sphere_prediction_tolerance_mm = s.naming.tolerance_mm;
            r.sphere_distances_mm = s.naming.distances.clone();
        }
        r.gate = weldseam_proto::calibration::GateReport {
            passed: record.passed,
            failures: failures.clone(),
            forced: record.forced,
        };
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        print!("{}", readable(&calibration, spheres.as_ref(), &failures));
    }
    if !failures.is_empty() && !args.force {
        bail!(
            "the calibration cannot be trusted: {}; {} (--force writes it anyway, recorded as failed)",
            failures.join("; "),
            match &args.write_config {
                Some(path) => format!("nothing written to {}", path.display()),
                None => "it was not written".to_string(),
            }
        );
    }
    if !failures.is_empty() {
        eprintln!(
            "--force: the calibration is accepted although {}; {}",
            failures.join("; "),
            if args.write_config.is_some() {
                "the config records it as failed, and the daemon refuses it unless started with --force"
            } else {
                "nothing is written without --write-config"
            }
        );
    }
    if let Some(path) = &args.write_config {
        write_config(path, &calibration, &record)?;
        if !args.json {
            println!("robot.hand_eye written to {} ({})", path.display(), record.summary());
        }
    }
    Ok(())
}

fn read_capture_file(path: &Path) -> Result<CaptureFile> {
    let size = std::fs::metadata(path).with_context(|| format!("cannot read {}", path.display()))?.len();
    if size > MAX_CAPTURE_FILE_BYTES {
        bail!("{}: {size} bytes, above the limit of {MAX_CAPTURE_FILE_BYTES} for a capture file", path.display());
    }
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let file: CaptureFile =
        serde_json::from_slice(&bytes).with_context(|| format!("{} is not a capture file", path.display()))?;
    if file.captures.len() > MAX_CAPTURES {
        bail!("{}: {} captures; at most {MAX_CAPTURES} are accepted", path.display(), file.captures.len());
    }
    Ok(file)
}

/// Fits the spheres in every capture's cloud (in parallel), names them
/// across captures (by the layout, then by the first solution's
/// prediction), and solves.
fn solve_spheres(
    dir: &Path,
    radii: &[f64],
    distances: Option<&[f64]>,
    captures: &[(nalgebra::Isometry3<f64>, String)],
    mount: Mount,
) -> Result<(Calibration, SphereSummary)> {
    weldseam::calibration::sphere::check_radii(radii)?;
    let fitted = captures
        .par_iter()
        .enumerate()
        .map(|(i, (_, name))| {
            let path = dir.join(name);
            let size =
                std::fs::metadata(&path).with_context(|| format!("capture {i}: cloud {}", path.display()))?.len();
            if size > MAX_CLOUD_FILE_BYTES {
                bail!(
                    "capture {i}: cloud {} is {size} bytes, above the limit of {MAX_CLOUD_FILE_BYTES}",
                    path.display()
                );
            }
            let cloud = weldseam::cloud::load(&path).with_context(|| format!("capture {i}: cloud"))?;
            if cloud.len() > MAX_CLOUD_POINTS {
                bail!(
                    "capture {i}: cloud {} has {} points, above the limit of {MAX_CLOUD_POINTS}",
                    path.display(),
                    cloud.len()
                );
            }
            Ok(fit_spheres(cloud.points(), radii, i as u64)?)
        })
        // Every capture's outcome in order, so the error reported is the
        // first capture's that failed, not whichever thread failed first.
        .collect::<Vec<Result<_>>>()
        .into_iter()
        .collect::<Result<Vec<_>>>()?;
    let found: Vec<usize> = fitted.iter().map(Vec::len).collect();
    let poses: Vec<nalgebra::Isometry3<f64>> = captures.iter().map(|(pose, _)| *pose).collect();
    let (calibration, naming) = calibrate_fitted_spheres(&poses, &fitted, radii, distances, mount)?;
    Ok((calibration, SphereSummary { found, naming }))
}

/// The report for a person.
fn readable(c: &Calibration, spheres: Option<&SphereSummary>, failures: &[String]) -> String {
    use std::fmt::Write as _;
    let spheres_found = spheres.map(|s| s.found.as_slice());
    let mut s = String::new();
    let used = c.residuals.len() - c.outliers.len();
    let _ = writeln!(
        s,
        "{} ({}), from {} captures ({used} used):",
        c.mount.solved_for(),
        match c.mount {
            Mount::EyeInHand => "the camera on the flange",
            Mount::EyeToHand => "the camera fixed in the cell",
        },
        c.residuals.len()
    );
    for row in rows(&c.hand_eye).chunks(4) {
        let _ = writeln!(s, "  {:>10.6} {:>10.6} {:>10.6} {:>11.4}", row[0], row[1], row[2], row[3]);
    }
    let _ = writeln!(s, "method: {}", c.method);
    match (c.expected_error_mm, c.translation_sigma_mm, c.rotation_sigma_deg) {
        (Some(e), Some(t), Some(r)) => {
            let _ = writeln!(
                s,
                "expected error at the working distance ({:.0} mm): {e:.3} mm (one sigma); the matrix's translation \
                 {t:.3} mm, rotation {r:.4} deg",
                c.working_distance_mm
            );
        }
        _ => {
            let _ = writeln!(s, "expected error: not determined (see the warnings)");
        }
    }
    for (name, x) in &c.closed_forms {
        let _ = writeln!(
            s,
            "closed form {name}: {:.3} mm, {:.4} deg from the result",
            (x.translation.vector - c.hand_eye.translation.vector).norm(),
            x.rotation.angle_to(&c.hand_eye.rotation).to_degrees()
        );
    }
    if let Some(with) = &c.hand_eye_with_outliers {
        let _ = writeln!(
            s,
            "with the outliers the result would move by {:.3} mm and {:.4} deg",
            (with.translation.vector - c.hand_eye.translation.vector).norm(),
            with.rotation.angle_to(&c.hand_eye.rotation).to_degrees()
        );
    }
    let _ = writeln!(
        s,
        "rotation between captures: largest {:.1} deg; axis spread {:.1} deg (third axis {:.1} deg)",
        c.conditioning.largest_rotation_deg, c.conditioning.axis_spread_deg, c.conditioning.third_axis_spread_deg
    );
    let _ = writeln!(
        s,
        "residuals:\n  capture  translation mm  rotation deg{}",
        if spheres_found.is_some() { "  spheres" } else { "" }
    );
    for r in &c.residuals {
        let rotation = r.rotation_deg.map_or("-".to_string(), |d| format!("{d:.4}"));
        let spheres = spheres_found.and_then(|f| f.get(r.capture)).map_or(String::new(), |n| format!("  {n:>7}"));
        let flag = if c.outliers.contains(&r.capture) { "  outlier" } else { "" };
        let _ = writeln!(s, "  {:>7}  {:>13.3}  {:>12}{spheres}{flag}", r.capture, r.translation_mm, rotation);
    }
    if let Some(summary) = spheres {
        let naming = &summary.naming;
        if let Some(d) = &naming.distances {
            let list: Vec<String> = d.iter().map(|v| format!("{v:.2}")).collect();
            let _ = writeln!(s, "spheres named by their distances: {} mm", list.join(", "));
        }
        let left_out = naming.left_out();
        let _ = writeln!(
            s,
            "captures named: {} by the layout, {} by the first solution's prediction{}, {} left out",
            naming.named_by_layout().len(),
            naming.named_by_prediction().len(),
            naming.tolerance_mm.map_or(String::new(), |t| format!(
                " (each ball within {t:.2} mm of where it was predicted: {} sigmas)",
                weldseam::calibration::prediction::PREDICTION_SIGMAS
            )),
            left_out.len()
        );
        for (capture, reason) in &left_out {
            let _ = writeln!(s, "capture {capture} left out: {reason}");
        }
    }
    if c.warnings.is_empty() {
        let _ = writeln!(s, "no warnings");
    } else {
        let _ = writeln!(s, "warnings:");
        for w in &c.warnings {
            let _ = writeln!(s, "  - {w}");
        }
    }
    if failures.is_empty() {
        let _ = writeln!(s, "gate: passed (every limit of [calibration] met)");
    } else {
        let _ = writeln!(s, "gate: FAILED");
        for f in failures {
            let _ = writeln!(s, "  - {f}");
        }
    }
    s
}

/// Rewrites `robot.hand_eye` of the TOML file at `path` (creating the
/// file or the table if missing), four numbers a line, and its record
/// `robot.hand_eye_calibration`, every other key and comment kept; the
/// result is checked as a config before it replaces the file.
fn write_config(path: &Path, c: &Calibration, record: &CalibrationRecord) -> Result<()> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
    };
    let mut doc: toml_edit::DocumentMut =
        text.parse().with_context(|| format!("{} is not a TOML file", path.display()))?;
    let robot = doc
        .entry("robot")
        .or_insert_with(|| toml_edit::Item::Table(toml_edit::Table::new()))
        .as_table_like_mut()
        .with_context(|| format!("{}: robot is not a table", path.display()))?;
    let mut array = toml_edit::Array::new();
    for (k, v) in rows(&c.hand_eye).into_iter().enumerate() {
        // Rotation to 1e-7, translation to 1e-5 mm: far below what the
        // calibration resolves, and short to read.
        let digits = if k % 4 == 3 { 1e5 } else { 1e7 };
        let mut value = toml_edit::Value::from((v * digits).round() / digits + 0.0);
        value.decor_mut().set_prefix(if k % 4 == 0 { "\n    " } else { " " });
        array.push_formatted(value);
    }
    array.set_trailing("\n");
    array.set_trailing_comma(true);
    match robot.get_mut("hand_eye") {
        Some(item) => *item = toml_edit::value(array),
        None => {
            robot.insert("hand_eye", toml_edit::value(array));
        }
    }
    let record_value = record_table(record);
    match robot.get_mut("hand_eye_calibration") {
        Some(item) => *item = toml_edit::value(record_value),
        None => {
            robot.insert("hand_eye_calibration", toml_edit::value(record_value));
        }
    }
    let updated = doc.to_string();
    Config::parse(&updated, &path.display().to_string()).with_context(|| {
        format!("the config with the new robot.hand_eye is not valid; {} left as it was", path.display())
    })?;
    let temporary = path.with_extension("toml.calibrate-tmp");
    std::fs::write(&temporary, updated).with_context(|| format!("cannot write {}", temporary.display()))?;
    std::fs::rename(&temporary, path).with_context(|| format!("cannot replace {}", path.display()))?;
    Ok(())
}

/// The record as an inline TOML table, figures rounded to what they
/// resolve.
fn record_table(r: &CalibrationRecord) -> toml_edit::InlineTable {
    let round = |v: f64, digits: f64| (v * digits).round() / digits + 0.0;
    let mut t = toml_edit::InlineTable::new();
    t.insert("passed", r.passed.into());
    t.insert("forced", r.forced.into());
    let failures: toml_edit::Array = r.failures.iter().map(String::as_str).collect();
    t.insert("failures", failures.into());
    let figures = [
        ("expected_error_mm", r.expected_error_mm, 1e4),
        ("translation_sigma_mm", r.translation_sigma_mm, 1e4),
        ("rotation_sigma_deg", r.rotation_sigma_deg, 1e5),
        ("worst_residual_mm", Some(r.worst_residual_mm), 1e4),
        ("worst_residual_deg", r.worst_residual_deg, 1e5),
        ("working_distance_mm", Some(r.working_distance_mm), 10.0),
    ];
    for (key, value, digits) in figures {
        if let Some(v) = value {
            t.insert(key, round(v, digits).into());
        }
    }
    t.insert("captures", i64::from(r.captures).into());
    t.insert("captures_used", i64::from(r.captures_used).into());
    t
}
