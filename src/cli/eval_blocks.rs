//! `weldseam eval --suite blocks`: blocks standing on a plate and blocks
//! stacked on them (`weldseam::sim::blocks`), planned under `t_fillet`
//! (the default request) or `auto` (`--joint-request auto`) with the
//! config's settings, each root judged as the tee suite judges a tee's
//! (`weldseam::eval::blocks`): right, refused, not planned and not named,
//! or confident wrong.
//!
//! The table lists every root of every scene; the outcome table sums them
//! per group (tuning, held out: `-holdout` scenes and every fresh draw),
//! request, block (on the plate or stacked) and whether the camera sees
//! the root. A confident wrong root fails the command. `--plans FILE`
//! writes each scene's roots as a JSON line.

use std::io::Write;

use anyhow::{Context, bail};
use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::eval::blocks::{RootOutcome, plan_roots};
use weldseam::eval::web_near_edge::RootVerdict;
use weldseam::joint::RequestedJoint;
use weldseam::pipeline::Planner;
use weldseam::sim::draw::{Draw, is_unseen};
use weldseam::sim::{BlockScene, blocks_suite};

use crate::cli::eval::EvalArgs;
use crate::cli::eval_family;
use crate::cli::table::Table;

pub fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let joint = eval_family::fillet_or_auto(args, "blocks", "blocks' roots")?;
    let config = Config::load_or_default(args.config.as_deref())?;
    let camera: CameraModel = config.camera;
    let planner = Planner::new(config);
    let draw = args.fresh.map_or(Draw::Documented, Draw::Fresh);
    let scenes = eval_family::chosen(blocks_suite(draw), |s: &BlockScene| s.name.as_str(), args)?;

    let mut plans = eval_family::plans_file(args.plans.as_deref())?;
    let mut table = Table::new(
        format!("{} blocks on a plate or stacked, each root planned as {joint}", scenes.len()),
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
                root_name(root),
                format!("{:.0}", 100.0 * root.seen_share),
                root.verdict.label().into(),
                figure(root.error.map(|e| e.across_mm), 3),
                figure(root.error.map(|e| e.start_mm.max(e.end_mm)), 2),
                root.rule.into(),
            ]);
            let block = if root.root.block == 0 { "on the plate" } else { "stacked" };
            let seen = if root.seen { "seen" } else { "hidden" };
            let group = (is_unseen(&scene.name), format!("{joint}, {block}, {seen}"));
            counts.entry(group).or_default()[root.verdict as usize] += 1;
        }
    }
    let summary = eval_family::outcome_table_of(&counts, "roots", RootVerdict::ALL.map(RootVerdict::label));
    eval_family::finish(args, plans, [&table, &summary])?;
    let wrong: usize = counts.values().map(|c| c[RootVerdict::ConfidentWrong as usize]).sum();
    if wrong > 0 {
        bail!("{wrong} root(s) of blocks on a plate are confident wrong");
    }
    Ok(())
}

/// `block 1 -x (seen)`: the block (1 on the plate, 2 stacked on it), the
/// face whose foot the root is, and whether the camera sees it along half
/// its length (or has it in the image at all).
fn root_name(root: &RootOutcome) -> String {
    let seen = match (root.seen, root.in_image) {
        (true, _) => "seen",
        (false, true) => "hidden",
        (false, false) => "out of view",
    };
    format!("block {} {} ({seen})", root.root.block + 1, root.root.face.name())
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
                "block": r.root.block,
                "face": r.root.face.name(),
                "seen_share": r.seen_share,
                "verdict": r.verdict.label(),
                "error": error,
                "rule": r.rule,
            })
        })
        .collect();
    serde_json::json!({ "scene": scene, "request": joint.name(), "roots": roots })
}
