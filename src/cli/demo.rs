//! `weldseam demo`: the main job on built-in simulated scenes. For each
//! joint type it simulates a camera frame, plans the weld, prints the
//! base-frame waypoints and measures them against the simulator's truth.

use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::seam_error;
use weldseam::joint::JointType;
use weldseam::pipeline::{PlanRequest, Planner};
use weldseam::report::plan_result;
use weldseam::sim::{demo_scene, simulate};

#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Print only the first and last waypoints of each seam.
    #[arg(long)]
    pub brief: bool,
}

pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let config = Config::default();
    let camera: CameraModel = config.camera;
    let planner = Planner::new(config);
    let mut failures = Vec::new();
    for joint in JointType::ALL {
        let spec = demo_scene(joint);
        let sim = simulate(&spec, &camera);
        let p = &spec.placement;
        println!(
            "== {joint}: simulated {}x{} frame, {} valid points, camera at {:.0} mm tilted {:.0}°",
            sim.cloud.width(),
            sim.cloud.height(),
            sim.cloud.valid_count(),
            p.distance_mm,
            p.tilt_deg
        );
        let pose = sim.pose;
        println!(
            "   robot pose at capture: {:.3}, {:.3}, {:.3} mm; {:.3}, {:.3}, {:.3}° ({})",
            pose.xyz_mm[0],
            pose.xyz_mm[1],
            pose.xyz_mm[2],
            pose.angles_deg[0],
            pose.angles_deg[1],
            pose.angles_deg[2],
            planner.config().euler.name()
        );
        let request = PlanRequest::new(joint, spec.joint.groove_depth_mm(), pose);
        let plan = match planner.plan(&sim.cloud, &request) {
            Ok(plan) => plan,
            Err(e) => {
                println!("   no seam: {e}");
                failures.push(format!("{joint}: {e}"));
                continue;
            }
        };
        let report = plan_result(&plan, planner.config().euler);
        let seam = &report.seams[0];
        println!(
            "   planned in {:.0} ms: {:.1} mm of seam, {} waypoints (base frame, mm and degrees)",
            plan.timings.total_ms(),
            seam.length_mm,
            seam.waypoints.len()
        );
        let last = seam.waypoints.len().saturating_sub(1);
        for (k, w) in seam.waypoints.iter().enumerate() {
            if args.brief && k != 0 && k != last {
                continue;
            }
            println!(
                "   {k:>3}  xyz {:>9.3} {:>9.3} {:>9.3}   rpy {:>8.3} {:>8.3} {:>8.3}",
                w.xyz[0], w.xyz[1], w.xyz[2], w.rpy_deg[0], w.rpy_deg[1], w.rpy_deg[2]
            );
        }
        match seam_error(&sim.truth, &plan.seams[0]) {
            Some(e) => {
                println!(
                    "   error against the truth: max {:.3} mm, mean {:.3} mm over 12 points; ends {:.2} and {:.2} mm -> {}",
                    e.max_mm,
                    e.mean_mm,
                    e.start_mm,
                    e.end_mm,
                    if e.passes() { "within the 1 mm bar" } else { "MISSES the 1 mm bar" }
                );
                if !e.passes() {
                    failures.push(format!("{joint}: max error {:.3} mm", e.max_mm));
                }
            }
            None => failures.push(format!("{joint}: empty trajectory")),
        }
    }
    anyhow::ensure!(failures.is_empty(), "demo failed: {}", failures.join("; "));
    Ok(())
}
