//! `weldseam camera`: a mock camera for commissioning. Replays PCD or PLY
//! files, or simulated scenes, over the camera link, answering triggers
//! or free-running.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, bail};
use tracing::info;
use weldseam::camera::CameraModel;
use weldseam::joint::JointType;
use weldseam::mock::camera::{CameraOptions, MockCamera};
use weldseam::sim::{demo_scene, simulate};

#[derive(Debug, clap::Args)]
pub struct CameraArgs {
    /// The daemon's camera link, host:port.
    #[arg(long, default_value = "127.0.0.1:7301")]
    pub connect: String,
    /// Point-cloud files to send in turn (.pcd or .ply, camera frame).
    #[arg(long, num_args = 1..)]
    pub file: Vec<PathBuf>,
    /// The files' units; auto guesses them per file (a median distance
    /// below 20 means metres). Frames are sent in millimetres.
    #[arg(long, value_enum, default_value_t = super::args::UnitsArg::Auto)]
    pub units: super::args::UnitsArg,
    /// Simulated scenes to send in turn: v-butt, i-butt, lap.
    #[arg(long, num_args = 1.., value_delimiter = ',')]
    pub simulate: Vec<JointType>,
    /// Push frames at this rate without waiting for triggers.
    #[arg(long)]
    pub free_run_hz: Option<f64>,
    /// Stop after this many frames.
    #[arg(long)]
    pub frames: Option<u64>,
    /// The camera's name in its hello; plan requests choose a camera by it.
    #[arg(long, default_value = "mock-camera")]
    pub name: String,
}

pub fn run(args: &CameraArgs) -> anyhow::Result<()> {
    if args.file.is_empty() == args.simulate.is_empty() {
        bail!("give either --file or --simulate");
    }
    if let Some(hz) = args.free_run_hz
        && !(hz.is_finite() && hz > 0.0 && hz <= 100.0)
    {
        bail!("--free-run-hz must be above 0 and at most 100, got {hz}");
    }
    let mut frames = Vec::new();
    for path in &args.file {
        let mut cloud = weldseam::cloud::load(path)?;
        if weldseam::pipeline::input::is_in_metres(&cloud, args.units.to_library()) {
            cloud = weldseam::pipeline::input::metres_to_millimetres(&cloud);
        }
        info!(file = %path.display(), width = cloud.width(), height = cloud.height(), "loaded");
        frames.push(Arc::new(cloud));
    }
    let camera = CameraModel::default();
    for joint in &args.simulate {
        let sim = simulate(&demo_scene(*joint), &camera);
        let p = sim.pose;
        info!(
            joint = %joint,
            pose = format!(
                "{:.3},{:.3},{:.3},{:.4},{:.4},{:.4}",
                p.xyz_mm[0], p.xyz_mm[1], p.xyz_mm[2], p.angles_deg[0], p.angles_deg[1], p.angles_deg[2]
            ),
            "simulated scene ready; pass this pose to the controller"
        );
        frames.push(Arc::new(sim.cloud));
    }
    let options = CameraOptions {
        name: args.name.clone(),
        free_run_hz: args.free_run_hz,
        max_frames: args.frames,
        ..CameraOptions::default()
    };
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().context("cannot start")?;
    let summary = runtime.block_on(MockCamera::new(args.connect.clone(), frames, options).run(async {
        let _ = tokio::signal::ctrl_c().await;
    }))?;
    info!(
        frames = summary.frames_sent,
        triggers = summary.triggers_answered,
        held = summary.frames_held,
        refused = summary.frames_refused,
        "camera stopped"
    );
    Ok(())
}
