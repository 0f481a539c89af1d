//! `weldseam plan`: plans the weld of one point-cloud file and prints the
//! base-frame trajectory, as a summary or as one JSON object on stdout.

use std::path::PathBuf;

use std::io::Write;

use anyhow::{Context, anyhow, bail};
use weldseam::convert::to_proto::{add_along_seam, plan_result, refusal};
use weldseam::geometry::Vec3;
use weldseam::geometry::pose::{RobotPose, hand_eye_from_rows};
use weldseam::joint::RequestedJoint;
use weldseam::pipeline::{PlanRequest, Planner, Stage};

use super::args;

#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// Point cloud: .pcd or .ply (camera frame and millimetres unless
    /// --cloud-frame and --units say otherwise).
    #[arg(long)]
    pub cloud: PathBuf,
    #[command(flatten)]
    pub input: args::CloudInputArgs,
    /// Joint type: v-butt, i-butt, lap or t-fillet (a tee joint's fillet
    /// roots; underscores work too); auto to have the planner decide it
    /// from the cloud and say why; or the types a fixture holds joined by
    /// a plus sign, such as v-butt+lap: decided as with auto, a workpiece
    /// of another type named as not planned.
    #[arg(long)]
    pub joint: RequestedJoint,
    /// Robot pose at capture: x,y,z,rx,ry,rz (mm, degrees).
    #[arg(long, allow_hyphen_values = true, value_parser = args::pose)]
    pub pose: RobotPose,
    #[command(flatten)]
    pub request: args::RequestArgs,
    #[command(flatten)]
    pub roi: args::RoiArgs,
    #[command(flatten)]
    pub config: args::ConfigArgs,
    /// Print one JSON object on stdout instead of a summary: the plan, or
    /// on a refusal `{"error": {"stage", "code", "rule", "gate", "message"}}`
    /// (the code a controller would get, the id of the rule that refused:
    /// `weldseam rules ID` explains it; the exit status is non-zero). Each
    /// warning and each unplanned joint's refusal carries its `rule` too.
    #[arg(long)]
    pub json: bool,
    /// Also write the plan's pictures and figures into this directory
    /// (created when needed): camera.png (the plates, edges, seam and
    /// waypoints, or the refusal), sections.png (profiles across the seam),
    /// profile.png (the joint's figures along the seam) and trace.json
    /// (every stage's figures, the plan as --json prints it).
    #[arg(long, value_name = "DIR")]
    pub debug: Option<PathBuf>,
    /// Start at the seam end nearest this base-frame point: x,y,z (mm).
    /// With several workpieces in view, the seam nearest it comes first,
    /// then each next the nearest to where the last one ends.
    #[arg(long, allow_hyphen_values = true, value_parser = args::point)]
    pub start_near: Option<[f64; 3]>,
    /// Return one seam only: the one nearest --start-near (the first of
    /// the default order without it).
    #[arg(long)]
    pub one_seam: bool,
}

pub fn run(args: &PlanArgs) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    let config = args.config.load()?;
    let hand_eye = args
        .request
        .hand_eye
        .map(|rows| hand_eye_from_rows(&rows).map_err(|e| anyhow::anyhow!("--hand-eye: {e}")))
        .transpose()?;
    let request = PlanRequest {
        hand_eye,
        step_mm: args.request.step,
        work_angle_deg: args.request.work_angle,
        travel_angle_deg: args.request.travel_angle,
        units: args.input.units.to_library(),
        cloud_frame: args.input.cloud_frame.to_library(),
        roi: args.roi.to_library()?,
        start_near: args.start_near.map(Vec3::from),
        one_seam: args.one_seam,
        ..PlanRequest::new(args.joint, args.request.groove_depth, args.pose)
    };
    let planner = Planner::new(config);
    // A bad flag is the caller's mistake, not the cloud's: say so before
    // reading a possibly large file.
    planner.check_request(&request).map_err(|e| anyhow!("invalid request: {}", e.reason))?;
    let load_start = std::time::Instant::now();
    let cloud = weldseam::cloud::load(&args.cloud)?;
    let load_ms = load_start.elapsed().as_secs_f64() * 1e3;
    tracing::info!(
        file = %args.cloud.display(),
        width = cloud.width(),
        height = cloud.height(),
        valid = cloud.valid_count(),
        load_ms = format!("{load_ms:.1}"),
        "loaded point cloud"
    );
    let (outcome, trace) = match &args.debug {
        Some(_) => {
            let (outcome, trace) = planner.plan_traced(&cloud, &request);
            (outcome, Some(trace))
        }
        // The cloud is not needed after planning: the planner converts it
        // in place rather than hold a copy beside it.
        None => (planner.plan_owned(cloud, &request), None),
    };
    let report = outcome.as_ref().ok().map(|plan| {
        let mut report = plan_result(plan, planner.config().euler);
        add_along_seam(&mut report, plan);
        report.timing_ms.insert("load".into(), load_ms);
        report
    });
    if let (Some(dir), Some(trace)) = (&args.debug, &trace) {
        let mut set = weldseam::report::debug_set(trace, report.clone())?;
        // trace.json holds the plan as `--json` prints it, with each seam's
        // figures along the seam and process beside the protocol's fields.
        if let Some(report) = &report {
            let printed = serde_json::to_value(super::plan_json::plan_json(report))?;
            for (file, bytes) in set.files.iter_mut().filter(|(f, _)| *f == weldseam::report::FIGURES_FILE) {
                let mut figures: serde_json::Value = serde_json::from_slice(bytes)?;
                figures["plan"] = printed.clone();
                *bytes = serde_json::to_vec_pretty(&figures).with_context(|| file.to_string())?;
            }
        }
        weldseam::debug_dir::write_set(dir, &set).context("--debug")?;
        tracing::info!(dir = %dir.display(), files = set.files.len(), "debug pictures and figures written");
    }
    let (plan, report) = match (outcome, report) {
        (Ok(plan), Some(report)) => (plan, report),
        (Ok(_), None) => bail!("no report of the plan of {}", args.cloud.display()),
        (Err(e), _) => {
            if args.json {
                // Scripts read why as well as that: the stage, the code a
                // controller would get and the sentence, on stdout.
                let refusal = serde_json::json!({ "error": refusal(&e) });
                writeln!(out, "{refusal}")?;
            }
            let (cloud, rule) = (args.cloud.display(), e.rule.id);
            return Err(match e.stage {
                Stage::Request => anyhow!("the request does not fit {cloud} (rule {rule}): {}", e.reason),
                _ if e.gate.is_some() => anyhow!(e).context(format!("seam refused in {cloud} (rule {rule})")),
                _ => anyhow!(e).context(format!("no seam found in {cloud} (rule {rule})")),
            });
        }
    };
    if args.json {
        writeln!(out, "{}", serde_json::to_string(&super::plan_json::plan_json(&report))?)?;
        return Ok(());
    }
    if report.seams.is_empty() {
        bail!("no seam found in {}", args.cloud.display());
    }
    let count = report.seams.len();
    for (k, (seam, planned)) in report.seams.iter().zip(&plan.seams).enumerate() {
        let heading = if count > 1 { format!("seam {} of {count}: ", k + 1) } else { String::new() };
        writeln!(
            out,
            "{heading}{} seam, {:.1} mm, {} waypoints every {} mm (base frame, {} angles), planned in {:.0} ms ({} method)",
            planned.joint,
            seam.length_mm,
            seam.waypoints.len(),
            request.step_mm.unwrap_or(planner.config().trajectory.step_mm),
            report.euler_convention,
            plan.timings.total_ms(),
            report.method
        )?;
        write_seam(&mut out, seam, args.joint)?;
    }
    for u in &report.unplanned {
        let joint = u.joint.as_deref().map_or(String::new(), |j| format!(" {j}"));
        let place = u
            .near_camera_mm
            .map_or(String::new(), |p| format!(" near ({:.0}, {:.0}, {:.0}) mm in the camera frame", p[0], p[1], p[2]));
        let rule = u.refusal.rule.as_deref().unwrap_or("?");
        writeln!(out, "not planned:{joint} joint{place} ({}, rule {rule}): {}", u.refusal.code, u.refusal.message)?;
    }
    Ok(())
}

/// One seam's figures and waypoints, after its heading line.
fn write_seam(
    out: &mut impl Write,
    seam: &weldseam_proto::plan::Seam,
    requested: RequestedJoint,
) -> anyhow::Result<()> {
    writeln!(
        out,
        "edge fits: rms {:.3} / {:.3} mm over {} / {} samples",
        seam.edge_fit_rms_mm[0], seam.edge_fit_rms_mm[1], seam.edge_samples[0], seam.edge_samples[1]
    )?;
    if let Some(evidence) = &seam.joint_evidence {
        let found = if requested.given().is_none() { "found" } else { "checked" };
        writeln!(out, "joint {found}: {evidence}")?;
    }
    if let Some(c) = &seam.coverage {
        writeln!(
            out,
            "coverage: {:.1} % of the {:.1} mm of joint both plates are seen beside ({:.1} mm beyond it), \
             edges seen along {:.0} % / {:.0} % of the seam",
            100.0 * c.joint,
            c.visible_joint_mm,
            c.beyond_mm,
            100.0 * c.edge[0],
            100.0 * c.edge[1]
        )?;
    }
    if let Some(q) = &seam.quality {
        writeln!(out, "{}", quality_line(q))?;
    }
    for w in &seam.warnings {
        writeln!(out, "warning ({}, rule {}): {}", w.gate, w.rule.as_deref().unwrap_or("?"), w.message)?;
    }
    writeln!(out, "{:>4}  {:>10} {:>10} {:>10}  {:>9} {:>9} {:>9}", "#", "x mm", "y mm", "z mm", "rx°", "ry°", "rz°")?;
    for (k, w) in seam.waypoints.iter().enumerate() {
        writeln!(
            out,
            "{:>4}  {:>10.3} {:>10.3} {:>10.3}  {:>9.3} {:>9.3} {:>9.3}",
            k, w.xyz[0], w.xyz[1], w.xyz[2], w.rpy_deg[0], w.rpy_deg[1], w.rpy_deg[2]
        )?;
    }
    Ok(())
}

/// The quality figures in one line: what a welding engineer checks first.
fn quality_line(q: &weldseam_proto::plan::SeamQuality) -> String {
    let mut parts = vec![format!("point spacing {:.2} mm", q.point_spacing_mm)];
    if let Some(g) = &q.gap_mm {
        parts.push(format!("gap {:.2} / {:.2} / {:.2} mm (min / mean / max)", g.min, g.mean, g.max));
    }
    if let Some(h) = q.misalignment_mm {
        parts.push(format!("misalignment {h:.2} mm"));
    }
    if let Some(step) = q.lap_step_mm {
        parts.push(format!("lap step {step:.2} mm"));
    }
    if let Some(t) = q.depth_to_support_mm {
        parts.push(format!("support {t:.1} mm behind the plates"));
    }
    if let Some(a) = q.groove_angle_deg {
        parts.push(format!("groove angle {a:.1}°"));
    }
    if let Some(d) = q.groove_depth_mm {
        parts.push(format!("groove depth {d:.2} mm (measured)"));
    }
    parts.push(format!("plates at {:.1}°", q.plate_angle_deg));
    parts.push(format!(
        "position known to {:.2} mm across, {:.2} mm along the normal (one sigma)",
        q.uncertainty_across_mm, q.uncertainty_normal_mm
    ));
    format!("quality: {}", parts.join(", "))
}
