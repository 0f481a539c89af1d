//! `weldseam demo`: the whole cell in one process over loopback. The
//! daemon listens on two ephemeral ports; the mock camera connects and
//! serves a simulated frame of each joint type when triggered (and a tee
//! joint, seen from the side whose web face its projector lights); the
//! mock controller asks for each plan as a robot would, then for a frame
//! of three workpieces (V-butt, I-butt and lap side by side, each joint
//! left to the daemon). It prints the base-frame waypoints, the error
//! against the simulator's truth (for the tee, against the root the camera
//! sees, by the fillet's bar) and the latency of each request.

use std::io::Write;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use tokio::sync::oneshot;
use weldseam::config::Config;
use weldseam::eval::{TrueSeam, path_error};
use weldseam::geometry::Vec3;
use weldseam::joint::JointType;
use weldseam::mock::camera::{CameraOptions, MockCamera};
use weldseam::mock::controller::{ControllerClient, request_for_simulation};
use weldseam::server::local::LocalDaemon;
use weldseam::sim::scenarios::several_workpieces;
use weldseam::sim::{CameraPlacement, SceneSpec, Simulation, demo_scene, simulate};
use weldseam_proto::message::{FrameSelect, PlanReply, joint_code};

#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Print only the first and last waypoints of each seam.
    #[arg(long)]
    pub brief: bool,
    /// Keep the daemon and its operator page up this many seconds after
    /// the last plan, to look at the page (at most an hour).
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=3600))]
    pub hold: Option<u64>,
    /// Record every plan into this directory (`weldseam records DIR`,
    /// `weldseam replay`).
    #[arg(long)]
    pub records: Option<std::path::PathBuf>,
}

/// How long the demo waits for any one step before calling it failed.
const STEP_TIMEOUT: Duration = Duration::from_secs(120);

pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(cell(args))
}

async fn cell(args: &DemoArgs) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    let mut config = Config::default();
    if let Some(dir) = &args.records {
        config.records.dir = dir.to_str().context("the records directory is not UTF-8")?.to_string();
    }
    let scenes: Vec<(JointType, SceneSpec, Simulation)> = JointType::ALL
        .into_iter()
        .map(demo_scene)
        .chain(std::iter::once(demo_tee()))
        .map(|spec| {
            let sim = simulate(&spec, &config.camera);
            (spec.joint.joint_type(), spec, sim)
        })
        .collect();
    let several = simulate(&several_workpieces(3), &config.camera);

    let daemon = LocalDaemon::start_with_metrics(config).await.context("cannot start the daemon")?;
    let (camera_addr, controller_addr) = (daemon.camera_addr.to_string(), daemon.controller_addr.to_string());
    writeln!(out, "daemon listening: camera link {camera_addr}, controller link {controller_addr}")?;
    if let Some(page) = daemon.metrics_addr {
        writeln!(out, "operator page: http://{page}/ (the metrics at http://{page}/metrics)")?;
    }
    if let Some(hold) = args.hold {
        writeln!(out, "the page stays up {hold} s after the last plan (--hold)")?;
    }

    // The camera answers trigger n with frame n: the scenes in order, then
    // the frame of several parts.
    let frames =
        scenes.iter().map(|(_, _, sim)| &sim.cloud).chain([&several.cloud]).map(|c| Arc::new(c.clone())).collect();
    let (stop_camera, camera_stopped) = oneshot::channel::<()>();
    let options = CameraOptions { name: "demo-camera".into(), ..CameraOptions::default() };
    let camera = tokio::spawn(MockCamera::new(camera_addr, frames, options).run(camera_stopped));

    let mut controller = ControllerClient::connect(&controller_addr, "demo-controller").await?;
    controller.wait_for_camera(STEP_TIMEOUT).await.context("the mock camera did not connect to the daemon")?;
    writeln!(out, "mock camera connected; mock controller requesting one plan per joint type\n")?;

    let mut failures = Vec::new();
    for (k, (joint, spec, sim)) in scenes.iter().enumerate() {
        let p = sim.pose;
        let request = request_for_simulation(k as u64 + 1, *joint, sim, FrameSelect::Trigger);
        writeln!(
            out,
            "== {joint}: pose {:.3}, {:.3}, {:.3} mm; {:.3}, {:.3}, {:.3}°",
            p.xyz_mm[0], p.xyz_mm[1], p.xyz_mm[2], p.angles_deg[0], p.angles_deg[1], p.angles_deg[2]
        )?;
        let sent = Instant::now();
        let reply = match controller.plan(request, STEP_TIMEOUT).await {
            Ok(reply) => reply,
            Err(e) => {
                writeln!(out, "   no plan: {e}")?;
                failures.push(format!("{joint}: {e}"));
                continue;
            }
        };
        let latency_ms = sent.elapsed().as_secs_f64() * 1e3;
        if let Err(e) = report(&mut out, args, (*joint, spec), sim, &reply, latency_ms) {
            failures.push(e.to_string());
        }
    }

    // Several parts in one frame: every seam, each joint found by the daemon.
    let mut request = request_for_simulation(scenes.len() as u64 + 1, JointType::VButt, &several, FrameSelect::Trigger);
    (request.joint, request.groove_depth_mm) = (joint_code::AUTO, None);
    writeln!(out, "== several parts in one frame: V-butt, I-butt and lap side by side, joints left to the daemon")?;
    let sent = Instant::now();
    match controller.plan(request, STEP_TIMEOUT).await {
        Ok(reply) => {
            let latency_ms = sent.elapsed().as_secs_f64() * 1e3;
            if let Err(e) = report_several(&mut out, args, &several, &reply, latency_ms) {
                failures.push(e.to_string());
            }
        }
        Err(e) => {
            writeln!(out, "   no plan: {e}")?;
            failures.push(format!("several parts: {e}"));
        }
    }

    if let Some(hold) = args.hold {
        out.flush()?;
        tokio::time::sleep(Duration::from_secs(hold)).await;
    }
    let _ = stop_camera.send(());
    let _ = tokio::time::timeout(STEP_TIMEOUT, camera).await;
    tokio::time::timeout(STEP_TIMEOUT, daemon.stop()).await.context("the daemon did not stop")??;
    if !failures.is_empty() {
        bail!("demo failed: {}", failures.join("; "));
    }
    Ok(())
}

/// The demo's tee: the simulator's, the camera tilted 20° across the web
/// so that the web's face on its side is lit and seen (the default view
/// looks down along it, steeper than the projector lights it).
fn demo_tee() -> SceneSpec {
    let spec = demo_scene(JointType::TFillet);
    SceneSpec { placement: CameraPlacement { tilt_deg: 20.0, tilt_azimuth_deg: 0.0, ..spec.placement }, ..spec }
}

/// Prints the reply for the frame of several parts: each seam against the
/// true seam it lies nearest, every part's seam found once.
fn report_several(
    out: &mut impl Write,
    args: &DemoArgs,
    sim: &Simulation,
    reply: &PlanReply,
    latency_ms: f64,
) -> anyhow::Result<()> {
    let pipeline_ms = reply.result.timing_ms.get("total").copied().unwrap_or(f64::NAN);
    writeln!(
        out,
        "   frame {} planned: {} seams, {} not planned; pipeline {:.0} ms, request to reply {:.0} ms",
        reply.frame_id,
        reply.result.seams.len(),
        reply.result.unplanned.len(),
        pipeline_ms,
        latency_ms
    )?;
    let mut found = vec![false; sim.seams.len()];
    for (k, seam) in reply.result.seams.iter().enumerate() {
        let path: Vec<Vec3> = seam.waypoints.iter().map(|w| Vec3::from(w.xyz)).collect();
        let nearest = sim
            .seams
            .iter()
            .enumerate()
            .filter_map(|(t, truth)| path_error(&truth.truth, &path).map(|e| (t, e)))
            .min_by(|a, b| a.1.max_mm.total_cmp(&b.1.max_mm));
        let Some((t, e)) = nearest else { bail!("several parts: seam {} matches no true seam", k + 1) };
        let joint = weldseam::convert::from_proto::joint(seam.joint);
        writeln!(
            out,
            "   seam {}: {joint} (workpiece {}), {:.1} mm, {} waypoints from ({:.1}, {:.1}, {:.1}) mm; \
             error max {:.3} mm, ends {:.2} and {:.2} mm -> {}",
            k + 1,
            sim.seams[t].workpiece + 1,
            seam.length_mm,
            seam.waypoints.len(),
            path.first().map_or(f64::NAN, |p| p.x),
            path.first().map_or(f64::NAN, |p| p.y),
            path.first().map_or(f64::NAN, |p| p.z),
            e.max_mm,
            e.start_mm,
            e.end_mm,
            if e.passes() { "within the 1 mm bar" } else { "MISSES the 1 mm bar" }
        )?;
        if !args.brief {
            for w in &seam.waypoints {
                writeln!(
                    out,
                    "        xyz {:>9.3} {:>9.3} {:>9.3}   rpy {:>8.3} {:>8.3} {:>8.3}",
                    w.xyz[0], w.xyz[1], w.xyz[2], w.rpy_deg[0], w.rpy_deg[1], w.rpy_deg[2]
                )?;
            }
        }
        if !e.passes() || joint != sim.seams[t].truth.joint || std::mem::replace(&mut found[t], true) {
            bail!("several parts: seam {} is not its workpiece's seam within the bar", k + 1);
        }
    }
    writeln!(out)?;
    if found.iter().any(|f| !f) {
        bail!("several parts: {} of {} seams found", found.iter().filter(|f| **f).count(), found.len());
    }
    Ok(())
}

/// Prints one reply and checks it against the truth.
fn report(
    out: &mut impl Write,
    args: &DemoArgs,
    (joint, spec): (JointType, &SceneSpec),
    sim: &Simulation,
    reply: &PlanReply,
    latency_ms: f64,
) -> anyhow::Result<()> {
    let Some(seam) = reply.result.seams.first() else { bail!("{joint}: the reply has no seam") };
    let pipeline_ms = reply.result.timing_ms.get("total").copied().unwrap_or(f64::NAN);
    writeln!(
        out,
        "   frame {} planned: {:.1} mm of seam, {} waypoints; pipeline {:.0} ms, request to reply {:.0} ms",
        reply.frame_id,
        seam.length_mm,
        seam.waypoints.len(),
        pipeline_ms,
        latency_ms
    )?;
    let last = seam.waypoints.len().saturating_sub(1);
    for (k, w) in seam.waypoints.iter().enumerate() {
        if args.brief && k != 0 && k != last {
            continue;
        }
        writeln!(
            out,
            "   {k:>3}  xyz {:>9.3} {:>9.3} {:>9.3}   rpy {:>8.3} {:>8.3} {:>8.3}",
            w.xyz[0], w.xyz[1], w.xyz[2], w.rpy_deg[0], w.rpy_deg[1], w.rpy_deg[2]
        )?;
    }
    let path: Vec<Vec3> = seam.waypoints.iter().map(|w| Vec3::from(w.xyz)).collect();
    if joint == JointType::TFillet {
        // A tee shows two roots: the seam must lie on the one seen.
        let roots: Vec<TrueSeam> = sim.seams.iter().map(|s| TrueSeam::of(spec, s)).collect();
        let Some((root, e)) = TrueSeam::nearest(&roots, &path) else { bail!("{joint}: the seam lies on no root") };
        let passes = root.seen_enough && e.passes_fillet();
        writeln!(
            out,
            "   error against the {}: {:.3} mm across, ends {:.2} and {:.2} mm -> {}\n",
            root.label,
            e.across_mm,
            e.start_mm,
            e.end_mm,
            if passes { "within the fillet's bar (0.5 mm, ends 1 mm)" } else { "MISSES the fillet's bar" }
        )?;
        if !passes {
            bail!("{joint}: {:.3} mm across, ends {:.2} and {:.2} mm", e.across_mm, e.start_mm, e.end_mm);
        }
        return Ok(());
    }
    let Some(e) = path_error(&sim.truth, &path) else { bail!("{joint}: empty trajectory") };
    writeln!(
        out,
        "   error against the truth: max {:.3} mm, mean {:.3} mm over 12 points; ends {:.2} and {:.2} mm -> {}\n",
        e.max_mm,
        e.mean_mm,
        e.start_mm,
        e.end_mm,
        if e.passes() { "within the 1 mm bar" } else { "MISSES the 1 mm bar" }
    )?;
    if !e.passes() {
        bail!("{joint}: max error {:.3} mm", e.max_mm);
    }
    Ok(())
}
