//! `weldseam simulate --calibration board|spheres`: writes a simulated
//! hand-eye calibration set (`sim::calibration`) as `weldseam calibrate`
//! reads it: the capture file (poses as `zyx`, mm and degrees), one
//! binary PCD per capture for spheres beside it, and the truth.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result, bail};

use weldseam::calibration::Mount;
use weldseam::camera::CameraModel;
use weldseam::convert::calibration::{capture_file, truth};
use weldseam::geometry::conventions::PoseConvention;
use weldseam::geometry::pose::EulerConvention;
use weldseam::sim::calibration::{
    CalibrationSpec, CalibrationTarget, DEFAULT_SPHERE_RADII_MM, SimObservation, TOOLING_BALL_RADIUS_MM,
    simulate_calibration,
};

use crate::cli::simulate::{CalibrationTargetArg, CloudFormat, SimulateArgs, write_cloud, write_truth};

pub fn run(args: &SimulateArgs, target: CalibrationTargetArg) -> Result<()> {
    if !args.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) {
        bail!("{}: with --calibration, --out is the capture file to write (.json)", args.out.display());
    }
    if args.rig && (target != CalibrationTargetArg::Spheres || args.sphere_radii.is_some()) {
        bail!("--rig is a set of spheres of its own radius: give --calibration spheres without --sphere-radii");
    }
    let radii = match (args.rig, &args.sphere_radii) {
        (true, _) => vec![TOOLING_BALL_RADIUS_MM; 3],
        (false, Some(r)) => r.clone(),
        (false, None) => DEFAULT_SPHERE_RADII_MM.to_vec(),
    };
    let target = match target {
        CalibrationTargetArg::Board => CalibrationTarget::Board,
        CalibrationTargetArg::Spheres => CalibrationTarget::Spheres(radii.clone()),
    };
    let mount = if args.eye_to_hand { Mount::EyeToHand } else { Mount::EyeInHand };
    let mut spec = CalibrationSpec::new(target.clone(), mount, args.seed.unwrap_or(1));
    if let Some(n) = args.captures {
        spec.captures = n;
    }
    if let Some(d) = args.distance {
        spec.distance_mm = d;
    }
    spec.wrong_pairing = args.wrong_pairing;
    spec.parallel_axes = args.parallel_axes;
    spec.small_rotations = args.small_rotations;
    spec.rig = args.rig;
    spec.validate()?;
    let set = simulate_calibration(&spec, &CameraModel::default());
    let dir = args.out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut cloud_paths = Vec::new();
    let mut points = 0;
    for (i, capture) in set.captures.iter().enumerate() {
        if let SimObservation::Cloud(cloud) = &capture.observation {
            let name = format!("capture-{i:02}.pcd");
            write_cloud(cloud, CloudFormat::PcdBinary, &dir.join(&name))?;
            points += cloud.len();
            cloud_paths.push(name);
        }
    }
    let euler = EulerConvention::Zyx;
    let radii_written = matches!(target, CalibrationTarget::Spheres(_)).then_some(radii.as_slice());
    let mut file = capture_file(&set, &PoseConvention::config(euler), euler.name(), radii_written, &cloud_paths);
    if spec.rig {
        // The rig's layout as an integrator measures it once.
        let c = &set.sphere_centres;
        let d = [(0, 1), (0, 2), (1, 2)].map(|(a, b)| ((c[a] - c[b]).norm() * 100.0).round() / 100.0);
        file.sphere_distances_mm = Some(d.to_vec());
        // As an integrator writes it: balls of one radius.
        file.sphere_radii_mm = None;
        file.sphere_radius_mm = Some(TOOLING_BALL_RADIUS_MM);
    }
    let write = || -> std::io::Result<()> {
        let mut out = BufWriter::new(File::create(&args.out)?);
        serde_json::to_writer_pretty(&mut out, &file)?;
        writeln!(out)?;
        out.flush()
    };
    write().with_context(|| format!("cannot write the capture file {}", args.out.display()))?;
    if let Some(path) = &args.truth {
        write_truth(&truth(&set, &spec), path)?;
    }
    println!(
        "{} captures of {} ({}){}{} written to {}",
        set.captures.len(),
        match target {
            CalibrationTarget::Board => "a board".to_string(),
            CalibrationTarget::Spheres(r) if spec.rig =>
                format!("a tooling-ball rig of {} balls, {points} points", r.len()),
            CalibrationTarget::Spheres(r) => format!("{} spheres, {points} points", r.len()),
        },
        match mount {
            Mount::EyeInHand => "camera on the flange",
            Mount::EyeToHand => "camera fixed in the cell",
        },
        spec.wrong_pairing.map(|i| format!(", capture {i} paired with the wrong pose")).unwrap_or_default(),
        match (spec.parallel_axes, spec.small_rotations) {
            (true, _) => ", rotations about one axis",
            (false, true) => ", small rotations",
            (false, false) => "",
        },
        args.out.display()
    );
    Ok(())
}
