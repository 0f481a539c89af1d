//! `weldseam simulate`: renders a simulated capture to an organized PCD
//! file (or, with `--variant`, the capture as a real tool would write it:
//! unorganized, downsampled, cropped, in metres or in the base frame, as
//! PCD, PCL's compressed PCD, or PLY) and writes its ground truth, pose
//! and scene as JSON, with
//! the arguments that run the planner on it. `--camera consumer` renders
//! with a RealSense-class depth camera instead of the paper's. `--fault`
//! adds one of the fault suite's faults to the scene, and `--suite-scene`
//! finds scenes of the fault, hard, tee, multi, corner, root-land, weld
//! process, blocks, web-near-edge, curved and groove-width suites by name
//! too, so a person can write one out and look at it (a family's scene
//! rendered with its own solids: a process scene's plates turned or raised
//! and its clamp, blocks, a curved member).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use nalgebra::Isometry3;
use serde_json::{Value, json};

use weldseam::camera::CameraModel;
use weldseam::cloud::{PointCloud, pcd, ply};
use weldseam::geometry::Vec3;
use weldseam::joint::JointType;
use weldseam::sim::consumer::{consumer_demo_scene, consumer_far_suite};
use weldseam::sim::faults::frame_barely_in_view;
use weldseam::sim::variants::Variant;
use weldseam::sim::{
    BlockScene, CameraPreset, CurvedScene, Draw, Fault, FaultKind, JointGeometry, NoiseSpec, PlateExtent, ProcessScene,
    SceneSpec, Simulation, WebNearEdge, WidenedGroove, blocks_suite, consumer_suite, corner_suite, curved_suite,
    demo_scene, eval_suite, fault_suite, groove_width_suite, hard_suite, multi_suite, process_suite, root_land_suite,
    simulate, tee_suite, web_near_edge_suite,
};

use crate::cli::args::CameraArg;

#[derive(Debug, Clone, clap::Args)]
pub struct SimulateArgs {
    /// Joint type: v-butt, i-butt, lap or t-fillet (a tee: a web standing
    /// on a flange, its two fillet roots in the truth's `seams`). Optional
    /// with --suite-scene.
    #[arg(long)]
    pub joint: Option<JointType>,
    /// Camera standoff along the optical axis to the target, mm.
    #[arg(long, value_name = "MM")]
    pub distance: Option<f64>,
    /// Angle between the optical axis and the plate normal, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub tilt: Option<f64>,
    /// Direction the camera leans towards, about the plate normal, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub azimuth: Option<f64>,
    /// Rotation of the camera about its optical axis, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub roll: Option<f64>,
    /// Seed of the sensor noise.
    #[arg(long, value_name = "N")]
    pub seed: Option<u64>,
    /// The camera that renders the frame: `industrial` (the paper's, the
    /// default) or `consumer` (RealSense-class, 1280 x 720 px, 87 x 58
    /// degrees, with its noise). With `consumer`, --joint starts from a
    /// scene at 375 mm (for v-butt, a groove 30 mm wide and 10 mm deep) and
    /// --suite-scene looks in the consumer suites of `eval --suite
    /// consumer` and `--suite consumer-far` (its names start `consumer-far`).
    #[arg(long, value_enum, default_value_t)]
    pub camera: CameraArg,
    /// Start from a scene of the evaluation suite, by name or index, or of
    /// the fault, hard, tee, multi, corner, root-land, process, blocks,
    /// web-near-edge, curved or groove-width suite (`eval --suite ...`) by
    /// name.
    #[arg(long, value_name = "NAME_OR_INDEX")]
    pub suite_scene: Option<String>,
    /// Add a fault to the scene, at the seam's middle: wrong-joint,
    /// seam-dropout, clamp, tack-welds, spatter, streaks, barely-in-view,
    /// touching-part or edge-glare (for wrong-joint, the truth's plan_args
    /// name the wrong joint).
    #[arg(long, value_name = "KIND")]
    pub fault: Option<FaultKind>,
    /// Render an exact frame: no depth noise, dropouts, mixed pixels or
    /// outliers.
    #[arg(long)]
    pub no_noise: bool,
    /// Write the capture as this variant: unorganized, voxel:MM, metres,
    /// base, cropped:MM, masked:MM (the crop on the frame's grid),
    /// compressed (PCD DATA binary_compressed), or
    /// several joined by commas (e.g. cropped:25,voxel:1,metres). The truth
    /// stays in the camera frame, mm.
    #[arg(long, value_name = "VARIANT")]
    pub variant: Option<Variant>,
    /// The cloud file to write: binary PCD (`.pcd`, organized unless the
    /// variant drops the grid; LZF-compressed with the `compressed`
    /// variant) or binary little-endian PLY (`.ply`); with --calibration,
    /// the capture file (`.json`).
    #[arg(long, value_name = "FILE.pcd|FILE.ply")]
    pub out: PathBuf,
    /// The ground-truth JSON file to write.
    #[arg(long, value_name = "FILE.json")]
    pub truth: Option<PathBuf>,
    /// Write a hand-eye calibration set instead of a frame: `board` (each
    /// capture a target pose) or `spheres` (each capture a point cloud of
    /// calibration spheres, written beside --out as capture-NN.pcd).
    /// --out is then the capture file (JSON) for `weldseam calibrate`, and
    /// --truth gets the true hand-eye.
    #[arg(long, value_enum, value_name = "TARGET")]
    pub calibration: Option<CalibrationTargetArg>,
    /// Calibration set: the camera fixed in the cell, the target on the flange.
    #[arg(long, requires = "calibration")]
    pub eye_to_hand: bool,
    /// Calibration set: how many captures (default 15).
    #[arg(long, value_name = "N", requires = "calibration")]
    pub captures: Option<usize>,
    /// Calibration set: the spheres' radii, mm (default 20,15,10).
    #[arg(long, value_name = "MM,...", value_delimiter = ',', requires = "calibration")]
    pub sphere_radii: Option<Vec<f64>>,
    /// Calibration set: pair this capture's robot pose with an
    /// observation taken elsewhere (an outlier to find).
    #[arg(long, value_name = "INDEX", requires = "calibration")]
    pub wrong_pairing: Option<usize>,
    /// Calibration set: turn the camera only about its axis, so the
    /// rotation axes are nearly parallel (an ill-posed set).
    #[arg(long, requires = "calibration")]
    pub parallel_axes: bool,
    /// Calibration set: tilt the camera only 3 to 8 degrees and roll it
    /// within 8 (a set with too little rotation).
    #[arg(long, requires = "calibration")]
    pub small_rotations: bool,
    /// Calibration set of spheres: the tooling-ball rig (three balls of
    /// 19.05 mm on posts over a table, the whole rig in view with stray
    /// returns); the capture file gives the balls' distances.
    #[arg(long, requires = "calibration")]
    pub rig: bool,
}

/// `--calibration`: what the calibration set's camera sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CalibrationTargetArg {
    Board,
    Spheres,
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    if let Some(target) = args.calibration {
        return crate::cli::simulate_calibration::run(args, target);
    }
    let (name, spec) = scene_from_args(args)?;
    let variant = args.variant.clone().unwrap_or_default();
    let format = CloudFormat::of(&args.out, variant.is_compressed())?;
    let camera = CameraPreset::from(args.camera).camera();
    let started = Instant::now();
    // A family's scene renders its own solids (a process scene's plates
    // turned or raised and its clamp, blocks, a web near the flange's
    // edge, a curved member, a widened groove) with the spec the arguments
    // left.
    let family = match (CameraPreset::from(args.camera), name.as_deref()) {
        (CameraPreset::Industrial, Some(key)) => family_scene(key),
        _ => None,
    };
    let rendered = match family {
        Some(scene) => scene.render(spec.clone(), &camera),
        None => simulate(&spec, &camera),
    };
    let sim = variant.apply(&rendered, spec.seed);
    let elapsed = started.elapsed();
    write_cloud(&sim.cloud, format, &args.out)?;
    if let Some(path) = &args.truth {
        let mut json = truth_json(name.as_deref(), &spec, &camera, &sim);
        json["variant"] = json!({
            "name": variant.to_string(),
            "units": if variant.in_metres() { "m" } else { "mm" },
            "cloud_frame": if variant.in_base_frame() { "base" } else { "camera" },
            "organized": sim.cloud.is_organized(),
            "points": sim.cloud.len(),
        });
        write_truth(&json, path)?;
    }
    println!(
        "{}{}: {} points ({} of {} pixels valid in the frame), {:.1} mm of seam in view{}; made in {:.0} ms",
        name.as_deref().unwrap_or(spec.joint.joint_type().name()),
        if variant.is_raw() { String::new() } else { format!(" as {variant}") },
        sim.cloud.valid_count(),
        rendered.cloud.valid_count(),
        rendered.cloud.len(),
        sim.truth.length_mm,
        if sim.truth.clipped_start || sim.truth.clipped_end { " (clipped)" } else { "" },
        elapsed.as_secs_f64() * 1e3,
    );
    Ok(())
}

/// The scene the arguments ask for, and its suite name if it has one.
fn scene_from_args(args: &SimulateArgs) -> Result<(Option<String>, SceneSpec)> {
    let preset = CameraPreset::from(args.camera);
    let (name, mut spec) = match (&args.suite_scene, args.joint) {
        (Some(key), joint) => {
            let (name, spec) = find_suite_scene(preset, key)?;
            if let Some(joint) = joint
                && joint != spec.joint.joint_type()
            {
                bail!(
                    "suite scene {name} is a {} joint, not {}",
                    spec.joint.joint_type().dashed_name(),
                    joint.dashed_name()
                );
            }
            (Some(name), spec)
        }
        (None, Some(joint)) => match preset {
            CameraPreset::Industrial => (None, demo_scene(joint)),
            CameraPreset::Consumer => (None, consumer_demo_scene(joint)),
        },
        (None, None) => bail!("give --joint (v-butt, i-butt, lap or t-fillet) or --suite-scene"),
    };
    let placement = &mut spec.placement;
    let overrides = [
        (args.distance, &mut placement.distance_mm),
        (args.tilt, &mut placement.tilt_deg),
        (args.azimuth, &mut placement.tilt_azimuth_deg),
        (args.roll, &mut placement.roll_deg),
    ];
    for (value, field) in overrides {
        if let Some(v) = value {
            *field = v;
        }
    }
    if let Some(seed) = args.seed {
        spec.seed = seed;
    }
    if args.no_noise {
        spec.noise = NoiseSpec::none();
    }
    if let Some(kind) = args.fault {
        spec.faults.push(Fault::example(kind, &spec));
        frame_barely_in_view(&mut spec, &preset.camera())?;
    }
    spec.validate()?;
    Ok((name, spec))
}

fn find_suite_scene(preset: CameraPreset, key: &str) -> Result<(String, SceneSpec)> {
    // A fresh draw's scene names its draw (`-freshN`); an index is the
    // documented suite's.
    let draw = Draw::of_scene(key);
    let mut suite = match preset {
        CameraPreset::Industrial => eval_suite(draw),
        CameraPreset::Consumer if key.starts_with("consumer-far") => consumer_far_suite(draw),
        CameraPreset::Consumer => consumer_suite(draw),
    };
    if preset == CameraPreset::Industrial {
        let other = match key.split('-').next() {
            Some("fault") => Some(fault_suite(draw)),
            Some("hard") => Some(hard_suite(draw)),
            Some("t") => Some(tee_suite(draw)),
            Some("multi") => Some(multi_suite(draw)),
            Some("corner") => Some(corner_suite(draw)),
            Some("root") => Some(root_land_suite(draw)),
            _ => None,
        };
        if let Some(found) = other.into_iter().flatten().find(|(name, _)| name == key) {
            return Ok(found);
        }
        if let Some(scene) = family_scene(key) {
            return Ok(scene.named());
        }
    }
    let count = suite.len();
    let position = match key.parse::<usize>() {
        Ok(index) => (index < count).then_some(index),
        Err(_) => suite.iter().position(|(name, _)| name == key),
    };
    match position {
        Some(i) => Ok(suite.swap_remove(i)),
        None => bail!(
            "no suite scene {key:?}: give an index below {count} or a name such as {}",
            suite.first().map_or("", |(name, _)| name.as_str())
        ),
    }
}

/// A scene of a family whose solids the plain scene model does not draw.
enum FamilyScene {
    Process(ProcessScene),
    Blocks(BlockScene),
    WebNearEdge(WebNearEdge),
    Curved(CurvedScene),
    GrooveWidth(WidenedGroove),
}

impl FamilyScene {
    /// Its name and scene.
    fn named(self) -> (String, SceneSpec) {
        match self {
            FamilyScene::Process(s) => (s.name, s.spec),
            FamilyScene::Blocks(s) => (s.name, s.spec),
            FamilyScene::WebNearEdge(s) => (s.name, s.spec),
            FamilyScene::Curved(s) => (s.name, s.spec),
            FamilyScene::GrooveWidth(s) => (s.name, s.spec),
        }
    }

    /// The capture of the family's solids under `spec` (the arguments'
    /// overrides applied to the scene's own).
    fn render(self, spec: SceneSpec, camera: &CameraModel) -> Simulation {
        match self {
            FamilyScene::Process(s) => ProcessScene { spec, ..s }.simulate(camera),
            FamilyScene::Blocks(s) => BlockScene { spec, ..s }.simulate(camera).sim,
            FamilyScene::WebNearEdge(s) => WebNearEdge { spec, ..s }.simulate(camera),
            FamilyScene::Curved(s) => CurvedScene { spec, ..s }.simulate(camera),
            FamilyScene::GrooveWidth(s) => WidenedGroove { spec, ..s }.simulate(camera),
        }
    }
}

/// The family scene named `key` (`process-`, `blocks-`, `web-edge-`,
/// `curved-` or `groove-width-...`), of the draw its name gives.
fn family_scene(key: &str) -> Option<FamilyScene> {
    let draw = Draw::of_scene(key);
    let prefix = |p: &str| key.starts_with(p);
    if prefix("process-") {
        process_suite(draw).into_iter().find(|s| s.name == key).map(FamilyScene::Process)
    } else if prefix("blocks-") {
        blocks_suite(draw).into_iter().find(|s| s.name == key).map(FamilyScene::Blocks)
    } else if prefix("web-edge-") {
        web_near_edge_suite(draw).into_iter().find(|s| s.name == key).map(FamilyScene::WebNearEdge)
    } else if prefix("curved-") {
        curved_suite(draw).into_iter().find(|s| s.name == key).map(FamilyScene::Curved)
    } else if prefix("groove-width-") {
        groove_width_suite(draw).into_iter().find(|s| s.name == key).map(FamilyScene::GrooveWidth)
    } else {
        None
    }
}

/// The file formats `simulate` writes, chosen by the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum CloudFormat {
    /// PCD, DATA binary.
    PcdBinary,
    /// PCD, DATA binary_compressed (LZF), as PCL's tools write it.
    PcdBinaryCompressed,
    /// PLY, binary little endian.
    PlyBinary,
}

impl CloudFormat {
    /// The format of a file named `path`; `compressed` (the `compressed`
    /// variant) asks for PCD's compressed data, which PLY has no form of.
    fn of(path: &Path, compressed: bool) -> Result<CloudFormat> {
        match (path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref(), compressed) {
            (Some("pcd"), false) => Ok(CloudFormat::PcdBinary),
            (Some("pcd"), true) => Ok(CloudFormat::PcdBinaryCompressed),
            (Some("ply"), false) => Ok(CloudFormat::PlyBinary),
            (Some("ply"), true) => {
                bail!(
                    "{}: the compressed variant is PCD's binary_compressed data; give a .pcd file name",
                    path.display()
                )
            }
            _ => bail!("{}: give a .pcd or .ply file name to write", path.display()),
        }
    }
}

pub(super) fn write_cloud(cloud: &PointCloud, format: CloudFormat, path: &Path) -> Result<()> {
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let out = BufWriter::new(file);
    match format {
        CloudFormat::PcdBinary => pcd::write_binary(cloud, out),
        CloudFormat::PcdBinaryCompressed => pcd::write_binary_compressed(cloud, out),
        CloudFormat::PlyBinary => ply::write_binary_le(cloud, out),
    }
    .with_context(|| format!("cannot write the point cloud to {}", path.display()))
}

pub(super) fn write_truth(truth: &impl serde::Serialize, path: &Path) -> Result<()> {
    let write = || -> std::io::Result<()> {
        let mut out = BufWriter::new(File::create(path)?);
        serde_json::to_writer_pretty(&mut out, truth)?;
        writeln!(out)?;
        out.flush()
    };
    write().with_context(|| format!("cannot write the ground truth to {}", path.display()))
}

/// Everything needed to score a planner's output on the frame and to run
/// the planner on it.
fn truth_json(name: Option<&str>, spec: &SceneSpec, camera: &CameraModel, sim: &Simulation) -> Value {
    let t = &sim.truth;
    let pose: Vec<f64> = sim.pose.xyz_mm.iter().chain(&sim.pose.angles_deg).copied().collect();
    json!({
        "scene": name,
        "joint": t.joint.name(),
        "parameters": scene_json(spec, camera),
        "pose": pose,
        "euler": spec.euler.name(),
        "hand_eye": rows(&spec.hand_eye),
        "base_from_camera": rows(&sim.base_from_camera),
        "truth": {
            "groove_depth_mm": t.groove_depth_mm,
            "start_camera": xyz(&t.start_camera),
            "end_camera": xyz(&t.end_camera),
            "start_base": xyz(&t.start_base),
            "end_base": xyz(&t.end_base),
            "plate_normal_camera": xyz(&t.plate_normal_camera),
            "plate_normal_base": xyz(&t.plate_normal_base),
            "clipped_start": t.clipped_start,
            "clipped_end": t.clipped_end,
            "length_mm": t.length_mm,
        },
        "seams": sim.seams.iter().map(|seam| {
            let t = &seam.truth;
            json!({
                "workpiece": seam.workpiece + 1,
                "root": seam.root,
                "label": seam.label(),
                "joint": t.joint.name(),
                "start_base": xyz(&t.start_base),
                "end_base": xyz(&t.end_base),
                "start_camera": xyz(&t.start_camera),
                "end_camera": xyz(&t.end_camera),
                "in_image_mm": t.length_mm,
                "physical_mm": seam.physical_mm,
                "seen_mm": seam.seen_mm,
                "seen_share": seam.seen_share,
                "seen": seam.is_seen(),
            })
        }).collect::<Vec<_>>(),
        "plan_args": plan_args(spec, &pose),
        "right_answer": {
            "refuse": sim.answer.refuse,
            "whole_seam": sim.answer.whole_seam,
            "pieces_mm": sim.answer.pieces_mm,
        },
    })
}

/// A joint's cross-section by its parameters.
fn geometry_json(joint: &JointGeometry) -> Value {
    match *joint {
        JointGeometry::VButt { thickness_mm, groove_angle_deg, groove_depth_mm, root_gap_mm } => json!({
            "thickness_mm": thickness_mm,
            "groove_angle_deg": groove_angle_deg,
            "groove_depth_mm": groove_depth_mm,
            "root_gap_mm": root_gap_mm,
        }),
        JointGeometry::IButt { thickness_mm, gap_mm } => json!({ "thickness_mm": thickness_mm, "gap_mm": gap_mm }),
        JointGeometry::Lap { lower_thickness_mm, upper_thickness_mm, overlap_mm } => json!({
            "lower_thickness_mm": lower_thickness_mm,
            "upper_thickness_mm": upper_thickness_mm,
            "overlap_mm": overlap_mm,
        }),
        JointGeometry::Tee { flange_thickness_mm, web_thickness_mm, web_height_mm } => json!({
            "flange_thickness_mm": flange_thickness_mm,
            "web_thickness_mm": web_thickness_mm,
            "web_height_mm": web_height_mm,
        }),
        JointGeometry::Corner { kind, flange_thickness_mm, web_thickness_mm, web_height_mm, proud_mm } => json!({
            "corner": kind.name(),
            "flange_thickness_mm": flange_thickness_mm,
            "web_thickness_mm": web_thickness_mm,
            "web_height_mm": web_height_mm,
            "proud_mm": proud_mm,
        }),
    }
}

fn scene_json(spec: &SceneSpec, camera: &CameraModel) -> Value {
    let plate = |p: &PlateExtent| json!({ "width_mm": p.width_mm, "length_mm": p.length_mm, "offset_mm": p.offset_mm });
    let placement = &spec.placement;
    let noise = &spec.noise;
    let others: Vec<Value> = spec
        .others
        .iter()
        .map(|w| {
            json!({
                "joint": w.joint.joint_type().name(),
                "geometry": geometry_json(&w.joint),
                "plate_a": plate(&w.plate_a),
                "plate_b": plate(&w.plate_b),
                "at_mm": w.at_mm,
                "yaw_deg": w.yaw_deg,
            })
        })
        .collect();
    json!({
        "geometry": geometry_json(&spec.joint),
        "plate_a": plate(&spec.plate_a),
        "plate_b": plate(&spec.plate_b),
        "other_workpieces": others,
        "spacer_height_mm": spec.spacer_height_mm,
        "placement": {
            "distance_mm": placement.distance_mm,
            "tilt_deg": placement.tilt_deg,
            "tilt_azimuth_deg": placement.tilt_azimuth_deg,
            "roll_deg": placement.roll_deg,
            "target_offset_mm": placement.target_offset_mm,
        },
        "noise": {
            "depth_noise": noise.depth_noise,
            "depth_noise_scale": noise.depth_noise_scale,
            "dropout_rate": noise.dropout_rate,
            "mixed_pixel_probability": noise.mixed_pixel_probability,
            "mixed_pixel_jump_mm": noise.mixed_pixel_jump_mm,
            "outlier_rate": noise.outlier_rate,
            "outlier_range_mm": noise.outlier_range_mm,
            "max_incidence_deg": noise.max_incidence_deg,
        },
        "seed": spec.seed,
        "faults": spec.faults.iter().map(|f| format!("{f:?}")).collect::<Vec<_>>(),
        "base_from_workpiece": rows(&spec.base_from_workpiece),
        "camera": {
            "width_px": camera.width_px,
            "height_px": camera.height_px,
            "fov_width_mm": camera.fov_width_mm,
            "fov_height_mm": camera.fov_height_mm,
            "fov_distance_mm": camera.fov_distance_mm,
            "baseline_mm": camera.baseline_mm,
        },
    })
}

/// The planner's arguments for this capture.
fn plan_args(spec: &SceneSpec, pose: &[f64]) -> String {
    let mut args = format!("--joint {}", spec.requested_joint().dashed_name());
    if let Some(depth) = spec.requested_groove_depth_mm() {
        args.push_str(&format!(" --groove-depth {}", short(depth)));
    }
    let pose: Vec<String> = pose.iter().map(|v| short(*v)).collect();
    args.push_str(&format!(" --pose={}", pose.join(",")));
    args
}

/// A number to 1e-6 without trailing zeros.
fn short(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn xyz(v: &Vec3) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// A rigid transform as four rows of its homogeneous matrix.
fn rows(iso: &Isometry3<f64>) -> [[f64; 4]; 4] {
    let m = iso.to_homogeneous();
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(out: PathBuf, truth: Option<PathBuf>) -> SimulateArgs {
        SimulateArgs {
            joint: Some(JointType::VButt),
            distance: Some(650.0),
            tilt: None,
            azimuth: None,
            roll: Some(-20.0),
            seed: Some(9),
            camera: CameraArg::Industrial,
            suite_scene: None,
            fault: None,
            no_noise: false,
            variant: None,
            out,
            truth,
            calibration: None,
            eye_to_hand: false,
            captures: None,
            sphere_radii: None,
            wrong_pairing: None,
            parallel_axes: false,
            small_rotations: false,
            rig: false,
        }
    }

    #[test]
    fn writes_the_cloud_and_a_truth_that_runs_the_planner() {
        let dir = tempfile::tempdir().unwrap();
        let (out, truth) = (dir.path().join("frame.pcd"), dir.path().join("truth.json"));
        run(&args(out.clone(), Some(truth.clone()))).unwrap();
        let bytes = std::fs::read(&out).unwrap();
        assert!(bytes.starts_with(b"# .PCD"));
        let header_end = bytes.windows(12).position(|w| w == b"DATA binary\n").unwrap() + 12;
        assert_eq!(bytes.len() - header_end, 1920 * 1200 * 12);
        let json: Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
        assert_eq!(json["joint"], "v_butt");
        assert_eq!(json["parameters"]["placement"]["distance_mm"], 650.0);
        assert_eq!(json["parameters"]["placement"]["roll_deg"], -20.0);
        assert_eq!(json["pose"].as_array().unwrap().len(), 6);
        assert_eq!(json["hand_eye"][3], json!([0.0, 0.0, 0.0, 1.0]));
        let plan = json["plan_args"].as_str().unwrap();
        assert!(plan.starts_with("--joint v-butt --groove-depth 6 --pose="), "{plan}");
        assert!(json["truth"]["length_mm"].as_f64().unwrap() > 200.0);
    }

    #[test]
    fn a_tee_is_written_with_both_roots_and_what_the_camera_sees_of_each() {
        let dir = tempfile::tempdir().unwrap();
        let (out, truth) = (dir.path().join("tee.pcd"), dir.path().join("tee.json"));
        let mut a = args(out, Some(truth.clone()));
        a.joint = Some("t_fillet".parse().unwrap());
        run(&a).unwrap();
        let json: Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
        assert_eq!(json["joint"], "t_fillet");
        assert_eq!(json["parameters"]["geometry"]["web_thickness_mm"], 8.0);
        assert!(json["plan_args"].as_str().unwrap().starts_with("--joint t-fillet --pose="), "{}", json["plan_args"]);
        let seams = json["seams"].as_array().unwrap();
        assert_eq!(seams.len(), 2);
        let seen: Vec<bool> = seams.iter().map(|s| s["seen"].as_bool().unwrap()).collect();
        // The demo camera leans towards +x: it sees the +x root only.
        assert_eq!(seen, [false, true], "{seams:?}");
        assert_eq!(seams[1]["label"], "workpiece 1 t-fillet root +x");
        assert!(seams[1]["seen_share"].as_f64().unwrap() > 0.99);
        // A suite scene of several workpieces is found by its name.
        let name = weldseam::sim::multi_suite(Draw::Documented)[0].0.clone();
        assert_eq!(find_suite_scene(CameraPreset::Industrial, &name).unwrap().0, name);
    }

    #[test]
    fn suite_scenes_are_found_by_index_or_name() {
        let (by_index, spec) = find_suite_scene(CameraPreset::Industrial, "30").unwrap();
        let (by_name, again) = find_suite_scene(CameraPreset::Industrial, &by_index).unwrap();
        assert_eq!((by_index, spec), (by_name, again));
        let err = find_suite_scene(CameraPreset::Industrial, "9999").unwrap_err().to_string();
        assert!(err.contains("below 66"), "{err}");
        let mut a = args(PathBuf::from("x.pcd"), None);
        a.suite_scene = Some("0".into());
        a.joint = Some(JointType::Lap);
        assert!(scene_from_args(&a).unwrap_err().to_string().contains("not lap"));
        // A weld process scene, by name, with its own solids.
        let clamp = process_suite(Draw::Documented).into_iter().find(|s| s.clamp.is_some()).unwrap();
        let (name, spec) = find_suite_scene(CameraPreset::Industrial, &clamp.name).unwrap();
        assert_eq!((name.as_str(), spec.seed), (clamp.name.as_str(), clamp.spec.seed));
        assert!(matches!(family_scene(&clamp.name), Some(FamilyScene::Process(s)) if s.clamp == clamp.clamp));
        // Each family whose solids the scene model does not draw, by name.
        let names = [
            blocks_suite(Draw::Documented)[0].name.clone(),
            web_near_edge_suite(Draw::Documented)[0].name.clone(),
            curved_suite(Draw::Documented)[0].name.clone(),
            groove_width_suite(Draw::Documented)[0].name.clone(),
            root_land_suite(Draw::Documented)[0].0.clone(),
        ];
        for name in names {
            assert_eq!(find_suite_scene(CameraPreset::Industrial, &name).unwrap().0, name);
        }
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("missing").join("frame.pcd");
        let mut a = args(out, None);
        a.distance = Some(400.0);
        let err = format!("{:#}", run(&a).unwrap_err());
        assert!(err.contains("missing/frame.pcd"), "{err}");
        a.tilt = Some(95.0);
        let err = run(&a).unwrap_err().to_string();
        assert!(err.contains("tilt"), "{err}");
    }

    #[test]
    fn a_variant_is_written_as_ply_with_its_units_and_frame_in_the_truth() {
        let dir = tempfile::tempdir().unwrap();
        let (out, truth) = (dir.path().join("frame.ply"), dir.path().join("truth.json"));
        let mut a = args(out.clone(), Some(truth.clone()));
        a.variant = Some(Variant::parse("cropped:25,voxel:1,metres").unwrap());
        run(&a).unwrap();
        let cloud = weldseam::cloud::load(&out).unwrap();
        let json: Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
        assert_eq!(json["variant"]["name"], "cropped:25,voxel:1,metres");
        assert_eq!(
            (json["variant"]["units"].as_str(), json["variant"]["cloud_frame"].as_str()),
            (Some("m"), Some("camera"))
        );
        assert_eq!(json["variant"]["points"].as_u64(), Some(cloud.len() as u64));
        assert!(!cloud.is_organized() && cloud.len() > 1000, "{} points", cloud.len());
        assert!(cloud.points().iter().all(|p| p[2] > 0.3 && p[2] < 1.0), "depths in metres");
        let err = run(&args(dir.path().join("frame.xyz"), None)).unwrap_err().to_string();
        assert!(err.contains(".pcd or .ply"), "{err}");
    }

    #[test]
    fn the_compressed_variant_is_written_as_pcl_writes_compressed_pcd() {
        let dir = tempfile::tempdir().unwrap();
        let (out, truth) = (dir.path().join("frame.pcd"), dir.path().join("truth.json"));
        let mut a = args(out.clone(), Some(truth.clone()));
        a.variant = Some(Variant::parse("compressed,metres").unwrap());
        run(&a).unwrap();
        let bytes = std::fs::read(&out).unwrap();
        assert!(bytes.windows(23).any(|w| w == b"DATA binary_compressed\n"), "a compressed PCD");
        let cloud = weldseam::cloud::load(&out).unwrap();
        let json: Value = serde_json::from_slice(&std::fs::read(&truth).unwrap()).unwrap();
        assert_eq!(json["variant"]["name"], "metres,compressed");
        assert!(cloud.is_organized() && cloud.points().iter().filter(|p| p[2].is_finite()).all(|p| p[2] < 1.0));
        a.out = dir.path().join("frame.ply");
        let err = run(&a).unwrap_err().to_string();
        assert!(err.contains("give a .pcd file name"), "{err}");
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(short(5.0), "5");
        assert_eq!(short(-0.0000001), "0");
        assert_eq!(short(178.2800004), "178.28");
    }
}
