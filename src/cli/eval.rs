//! `weldseam eval`: plans the seeded suite of simulated scenes with the
//! robust method and the paper's exact method side by side and prints the
//! accuracy table (docs/ACCURACY.md holds its latest output). With
//! `--suite consumer` the scenes are a consumer depth camera's, handed over
//! as its users do (cropped, downsampled, in metres) and planned with the
//! same config.

use std::io::Write;

use anyhow::Context;
use std::path::PathBuf;

use weldseam::config::{Config, Method};
use weldseam::convert::to_proto::plan_result;
use weldseam::eval::{SceneOutcome, run_suite, summarise};
use weldseam::geometry::pose::EulerConvention;
use weldseam::joint::JointType;
use weldseam::pipeline::Stage;
use weldseam::sim::consumer::{consumer_camera, consumer_variant};
use weldseam::sim::variants::Variant;
use weldseam::sim::{CameraPreset, consumer_suite, eval_suite};

use crate::cli::args::CameraArg;
use crate::cli::table::Table;

#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Configuration file (TOML); built-in defaults otherwise.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Which camera's suite: `industrial` (the default: the 66 scenes of
    /// the paper's camera, rendered with the config's camera) or `consumer`
    /// (20 scans of a RealSense-class camera at 200 to 500 mm, each made
    /// into cropped:40,voxel:1,metres unless --variant says otherwise).
    /// Either way the planner runs with the config as loaded.
    #[arg(long, value_enum, default_value_t)]
    pub suite: CameraArg,
    /// Only scenes whose name contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// At most this many scenes (after the filter).
    #[arg(long)]
    pub limit: Option<usize>,
    /// Plan each scene as this variant of its frame: unorganized,
    /// voxel:MM, metres, base, cropped:MM, or several joined by commas
    /// (e.g. cropped:25,voxel:1,metres). Scored against the same truth.
    #[arg(long, value_name = "VARIANT")]
    pub variant: Option<Variant>,
    /// Skip the paper-exact comparison.
    #[arg(long)]
    pub robust_only: bool,
    /// Print the tables as Markdown (for docs/ACCURACY.md) instead of
    /// aligned text.
    #[arg(long)]
    pub markdown: bool,
    /// Also write every scene's planned seams, one JSON line per scene and
    /// method, with every number in full precision and no timings: two
    /// runs give equal files exactly when every plan is the same, digit for
    /// digit (`diff before.jsonl after.jsonl`).
    #[arg(long, value_name = "FILE")]
    pub plans: Option<PathBuf>,
}

/// The error columns of one method's outcome: max, mean, start, end, result.
fn cells(o: &SceneOutcome) -> Vec<String> {
    match &o.result {
        Ok((e, _)) => vec![
            format!("{:.3}", e.max_mm),
            format!("{:.3}", e.mean_mm),
            format!("{:.2}", e.start_mm),
            format!("{:.2}", e.end_mm),
            if e.passes() { "pass" } else { "FAIL" }.to_string(),
        ],
        Err(err) => {
            let mut row = vec!["-".to_string(); 4];
            row.push(format!("FAIL: {err}"));
            row
        }
    }
}

/// The total and the per-stage times, ms.
fn timings(o: &SceneOutcome) -> Vec<String> {
    match &o.result {
        Ok((_, plan)) => {
            let t = &plan.timings;
            let stages: Vec<String> =
                Stage::IN_ORDER.iter().map(|s| format!("{:.0}", t.get(*s).unwrap_or(0.0))).collect();
            vec![format!("{:.0}", t.total_ms()), stages.join(" / ")]
        }
        Err(_) => vec!["-".into(), "-".into()],
    }
}

/// The scene's name, standoff and tilt.
fn describe(o: &SceneOutcome) -> Vec<String> {
    let p = &o.spec.placement;
    vec![o.name.clone(), format!("{:.0}", p.distance_mm), format!("{:.1}", p.tilt_deg)]
}

/// One scene's plan as a JSON line: the seams as `plan --json` reports
/// them, without the timings that differ from run to run.
fn plan_line(o: &SceneOutcome, euler: EulerConvention) -> serde_json::Value {
    let outcome = match &o.result {
        Ok((_, plan)) => serde_json::json!({ "seams": plan_result(plan, euler).seams }),
        Err(e) => serde_json::json!({ "error": e.to_string() }),
    };
    serde_json::json!({ "scene": o.name, "method": o.method.name(), "plan": outcome })
}

pub fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let mut robust = Config::load_or_default(args.config.as_deref())?;
    robust.pipeline.method = Method::Robust;
    let mut paper = robust.clone();
    paper.pipeline.method = Method::Paper;
    let configs = if args.robust_only { vec![robust.clone()] } else { vec![robust.clone(), paper] };
    let (mut scenes, camera, suite_variant) = match CameraPreset::from(args.suite) {
        CameraPreset::Industrial => (eval_suite(), robust.camera, Variant::raw()),
        CameraPreset::Consumer => (consumer_suite(), consumer_camera(), consumer_variant()),
    };
    if let Some(f) = &args.filter {
        scenes.retain(|(name, _)| name.contains(f.as_str()));
    }
    scenes.truncate(args.limit.unwrap_or(usize::MAX));
    anyhow::ensure!(!scenes.is_empty(), "no scene matches the filter");

    let stage_names: Vec<&str> = Stage::IN_ORDER.iter().map(|s| s.name()).collect();
    let stages_header = format!("{} ms", stage_names.join(" / "));
    let mut headers =
        vec!["scene", "distance mm", "tilt °", "max mm", "mean mm", "start mm", "end mm", "result", "total ms"];
    headers.push(&stages_header);
    if !args.robust_only {
        headers.extend(["paper: max mm", "mean mm", "start mm", "end mm", "result"]);
    }
    let variant = args.variant.clone().unwrap_or(suite_variant);
    let mut scenes_table =
        Table::new(format!("{} scenes as {variant} frames, each planned once", scenes.len()), &headers);
    let mut plans = match &args.plans {
        Some(path) => Some(std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        )),
        None => None,
    };
    let mut plans_written = Ok(());
    let count = scenes.len();
    let results = run_suite(&scenes, &camera, &variant, &configs, |k, outcomes| {
        if let Some(file) = plans.as_mut()
            && plans_written.is_ok()
        {
            plans_written = outcomes.iter().try_for_each(|o| writeln!(file, "{}", plan_line(o, robust.euler)));
        }
        let mut row = describe(&outcomes[0]);
        row.extend(cells(&outcomes[0]));
        row.extend(timings(&outcomes[0]));
        if let Some(p) = outcomes.get(1) {
            row.extend(cells(p));
        }
        // A long run shows as it goes, on stderr; the tables come at the end.
        eprintln!("scene {} of {count}: {} {}", k + 1, outcomes[0].name, row[7]);
        scenes_table.push(row);
    });

    plans_written.context("cannot write the plans file")?;
    if let Some(mut file) = plans {
        file.flush().context("cannot write the plans file")?;
    }
    let mut summary = Table::new(
        "Per method and joint type",
        &[
            "method",
            "joint",
            "scenes",
            "seam found",
            "within 1 mm and ends within 2 mm",
            "worst max mm",
            "mean of max mm",
            "worst end mm",
            "median total ms",
        ],
    );
    for (config, outcomes) in configs.iter().zip(&results) {
        let groups: Vec<(String, Vec<&SceneOutcome>)> = JointType::ALL
            .iter()
            .map(|j| (j.name().to_string(), outcomes.iter().filter(|o| o.spec.joint.joint_type() == *j).collect()))
            .chain(std::iter::once(("all".to_string(), outcomes.iter().collect())))
            .collect();
        for (name, group) in groups {
            let s = summarise(group);
            summary.push(vec![
                config.pipeline.method.name().to_string(),
                name,
                s.scenes.to_string(),
                s.found.to_string(),
                s.passed.to_string(),
                format!("{:.3}", s.worst_max_mm),
                format!("{:.3}", s.mean_max_mm),
                format!("{:.2}", s.worst_end_mm),
                format!("{:.0}", s.median_total_ms),
            ]);
        }
    }
    let render = |t: &Table| if args.markdown { t.to_markdown() } else { t.to_text() };
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", render(&scenes_table))?;
    writeln!(out, "{}", render(&summary))?;
    out.flush()?;
    let failed = results[0].iter().filter(|o| !o.passes()).count();
    if failed > 0 {
        anyhow::bail!("{failed} of {} scenes miss the bar with the robust method", results[0].len());
    }
    Ok(())
}
