//! `weldseam eval --suite web-near-edge`: tees whose web stands near the
//! flange's edge (`weldseam::sim::web_near_edge`), planned under
//! `t_fillet` (the default request) or `auto` (`--joint-request auto`)
//! with the config's settings, each root judged as the tee suite judges
//! it (`weldseam::eval::web_near_edge`): right, refused, not planned and
//! not named, or confident wrong.
//!
//! The table lists every root of every scene; the outcome table sums them
//! per group (tuning, held out: `-holdout` scenes and every fresh draw),
//! request and side of the web (the flange's narrow side or its wide
//! one). A confident wrong root fails the command. `--plans FILE` writes
//! each scene's roots as a JSON line.

use std::io::Write;

use anyhow::{Context, bail};
use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::web_near_edge::{RootOutcome, RootVerdict, plan_roots};
use weldseam::joint::RequestedJoint;
use weldseam::pipeline::Planner;
use weldseam::sim::draw::{Draw, is_unseen};
use weldseam::sim::{WebNearEdge, web_near_edge_suite};

use crate::cli::eval::EvalArgs;
use crate::cli::eval_family;
use crate::cli::table::Table;

pub fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let joint = eval_family::fillet_or_auto(args, "web-near-edge", "tees")?;
    let config = Config::load_or_default(args.config.as_deref())?;
    let camera: CameraModel = config.camera;
    let planner = Planner::new(config);
    let draw = args.fresh.map_or(Draw::Documented, Draw::Fresh);
    let scenes = eval_family::chosen(web_near_edge_suite(draw), |s: &WebNearEdge| s.name.as_str(), args)?;

    let mut plans = eval_family::plans_file(args.plans.as_deref())?;
    let mut table = Table::new(
        format!("{} tees with the web near the flange's edge, each root planned as {joint}", scenes.len()),
        &["scene", "root", "seen %", "outcome", "across mm", "ends mm", "rule"],
    );
    let mut counts = eval_family::Counts::<4>::new();
    let count = scenes.len();
    for (k, scene) in scenes.iter().enumerate() {
        let roots = plan_roots(scene, &planner, &camera, joint);
        let verdicts: Vec<&str> = roots.iter().map(|r| r.verdict.label()).collect();
        eprintln!("scene {} of {count}: {} {joint}: {}", k + 1, scene.name, verdicts.join(", "));
        if let Some(file) = plans.as_mut() {
            writeln!(file, "{}", plan_line(&scene.name, joint, &roots)).context("cannot write the plans file")?;
        }
        for (r, root) in roots.iter().enumerate() {
            let figure = |v: Option<f64>, digits: usize| v.map_or("-".into(), |v| format!("{v:.digits$}"));
            table.push(vec![
                if r == 0 { scene.name.clone() } else { String::new() },
                root_name(r, root),
                format!("{:.0}", 100.0 * root.seen_share),
                root.verdict.label().into(),
                figure(root.error.map(|e| e.across_mm), 3),
                figure(root.error.map(|e| e.start_mm.max(e.end_mm)), 2),
                root.rule.into(),
            ]);
            let side = if root.narrow { "narrow" } else { "wide" };
            let group = (is_unseen(&scene.name), format!("{joint}, {side} side's root"));
            counts.entry(group).or_default()[root.verdict as usize] += 1;
        }
    }
    let summary = eval_family::outcome_table_of(&counts, "roots", RootVerdict::ALL.map(RootVerdict::label));
    eval_family::finish(args, plans, [&table, &summary])?;
    let wrong: usize = counts.values().map(|c| c[RootVerdict::ConfidentWrong as usize]).sum();
    if wrong > 0 {
        bail!("{wrong} root(s) of tees with the web near the flange's edge are confident wrong");
    }
    Ok(())
}

/// `-x, narrow (seen)`: the root's side of the web, of the flange, and
/// whether the camera sees it along half its length.
fn root_name(index: usize, root: &RootOutcome) -> String {
    let axis = if index == 0 { "-x" } else { "+x" };
    let side = if root.narrow { "narrow" } else { "wide" };
    let seen = if root.seen { "seen" } else { "hidden" };
    format!("{axis}, {side} ({seen})")
}

/// One scene's roots under one request as a JSON line (`--plans`), for
/// comparing two builds: each root's verdict, its seam's errors in full
/// precision, and the rule named.
fn plan_line(scene: &str, joint: RequestedJoint, roots: &[RootOutcome]) -> serde_json::Value {
    let roots: Vec<serde_json::Value> = roots
        .iter()
        .map(|r| {
            let error = r
                .error
                .map(|e| serde_json::json!({ "across_mm": e.across_mm, "start_mm": e.start_mm, "end_mm": e.end_mm }));
            serde_json::json!({
                "narrow": r.narrow,
                "seen_share": r.seen_share,
                "verdict": r.verdict.label(),
                "error": error,
                "rule": r.rule,
            })
        })
        .collect();
    serde_json::json!({ "scene": scene, "request": joint.name(), "roots": roots })
}
