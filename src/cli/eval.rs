//! `weldseam eval`: plans the seeded suite of simulated scenes with the
//! robust method and the paper's exact method side by side and prints the
//! accuracy table (docs/ACCURACY.md holds its latest output).

use std::io::Write;

use anyhow::Context;
use std::path::PathBuf;

use weldseam::config::{Config, Method};
use weldseam::convert::to_proto::plan_result;
use weldseam::eval::{SceneOutcome, run_suite, summarise};
use weldseam::geometry::pose::EulerConvention;
use weldseam::joint::JointType;
use weldseam::pipeline::Stage;
use weldseam::sim::eval_suite;

#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Configuration file (TOML); built-in defaults otherwise.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Only scenes whose name contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// At most this many scenes (after the filter).
    #[arg(long)]
    pub limit: Option<usize>,
    /// Skip the paper-exact comparison.
    #[arg(long)]
    pub robust_only: bool,
    /// Print Markdown tables (for docs/ACCURACY.md).
    #[arg(long)]
    pub markdown: bool,
    /// Also write every scene's planned seams, one JSON line per scene and
    /// method, with every number in full precision and no timings: two
    /// runs give equal files exactly when every plan is the same, digit for
    /// digit (`diff before.jsonl after.jsonl`).
    #[arg(long, value_name = "FILE")]
    pub plans: Option<PathBuf>,
}

fn cell(o: &SceneOutcome) -> String {
    match &o.result {
        Ok((e, _)) => format!(
            "{:.3} | {:.3} | {:.2} | {:.2} | {}",
            e.max_mm,
            e.mean_mm,
            e.start_mm,
            e.end_mm,
            if e.passes() { "pass" } else { "FAIL" }
        ),
        Err(err) => format!("- | - | - | - | FAIL: {}", err.to_string().replace('|', "/")),
    }
}

fn timings(o: &SceneOutcome) -> String {
    match &o.result {
        Ok((_, plan)) => {
            let t = &plan.timings;
            let stages: Vec<String> =
                Stage::IN_ORDER.iter().map(|s| format!("{:.0}", t.get(*s).unwrap_or(0.0))).collect();
            format!("{:.0} | {}", t.total_ms(), stages.join(" / "))
        }
        Err(_) => "- | -".into(),
    }
}

fn describe(o: &SceneOutcome) -> String {
    let p = &o.spec.placement;
    format!("{} | {:.0} | {:.1}", o.name, p.distance_mm, p.tilt_deg)
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
    let mut scenes = eval_suite();
    if let Some(f) = &args.filter {
        scenes.retain(|(name, _)| name.contains(f.as_str()));
    }
    scenes.truncate(args.limit.unwrap_or(usize::MAX));
    anyhow::ensure!(!scenes.is_empty(), "no scene matches the filter");

    let stage_names: Vec<&str> = Stage::IN_ORDER.iter().map(|s| s.name()).collect();
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "| scene | distance mm | tilt ° | max mm | mean mm | start mm | end mm | result | total ms | {} |{}",
        stage_names.join(" / "),
        if args.robust_only { "" } else { " paper: max mm | mean mm | start mm | end mm | result |" }
    )?;
    writeln!(
        out,
        "|---|---:|---:|---:|---:|---:|---:|---|---:|---|{}",
        if args.robust_only { "" } else { "---:|---:|---:|---:|---|" }
    )?;
    let mut plans = match &args.plans {
        Some(path) => Some(std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        )),
        None => None,
    };
    let mut plans_written = Ok(());
    let results = run_suite(&scenes, &robust.camera, &configs, |_, outcomes| {
        if let Some(file) = plans.as_mut()
            && plans_written.is_ok()
        {
            plans_written = outcomes.iter().try_for_each(|o| writeln!(file, "{}", plan_line(o, robust.euler)));
        }
        let mut line = format!("| {} | {} | {} |", describe(&outcomes[0]), cell(&outcomes[0]), timings(&outcomes[0]));
        if let Some(p) = outcomes.get(1) {
            line.push_str(&format!(" {} |", cell(p)));
        }
        // Progress lines are the table itself, so a long run shows as it goes.
        let _ = writeln!(std::io::stdout().lock(), "{line}");
    });

    plans_written.context("cannot write the plans file")?;
    if let Some(mut file) = plans {
        file.flush().context("cannot write the plans file")?;
    }
    writeln!(out)?;
    writeln!(
        out,
        "| method | joint | scenes | seam found | within 1 mm and ends within 2 mm | worst max mm | mean of max mm | worst end mm | median total ms |"
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|")?;
    for (config, outcomes) in configs.iter().zip(&results) {
        let groups: Vec<(String, Vec<&SceneOutcome>)> = JointType::ALL
            .iter()
            .map(|j| (j.name().to_string(), outcomes.iter().filter(|o| o.spec.joint.joint_type() == *j).collect()))
            .chain(std::iter::once(("all".to_string(), outcomes.iter().collect())))
            .collect();
        for (name, group) in groups {
            let s = summarise(group);
            writeln!(
                out,
                "| {} | {} | {} | {} | {} | {:.3} | {:.3} | {:.2} | {:.0} |",
                config.pipeline.method.name(),
                name,
                s.scenes,
                s.found,
                s.passed,
                s.worst_max_mm,
                s.mean_max_mm,
                s.worst_end_mm,
                s.median_total_ms
            )?;
        }
    }
    let failed = results[0].iter().filter(|o| !o.passes()).count();
    if failed > 0 {
        anyhow::bail!("{failed} of {} scenes miss the bar with the robust method", results[0].len());
    }
    Ok(())
}
