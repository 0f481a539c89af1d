//! `weldseam eval --suite curved`: the curved-member family
//! (`weldseam::sim::curved`), tees whose root bends 4 to 16 mm over the
//! seam, planned under `t_fillet` and `auto` with the config's settings.
//!
//! Nothing on these scenes is a plane weld, so the right answer is a
//! refusal; a seam whose waypoints all lie within [`WITHIN_BAR_MM`] of the
//! bent root is a stretch short enough to be straight and is counted
//! apart, not as wrong; a seam farther from the root is a confident wrong
//! one (a curved root planned as a line), and fails the command. The
//! held-out scenes (`-holdout`, and every fresh draw) are summed in rows
//! of their own. `--plans FILE` writes each outcome as a JSON line.

use std::io::Write;

use anyhow::{Context, bail};
use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::Planner;
use weldseam::sim::curved::CurvedOutcome;
use weldseam::sim::draw::{Draw, is_unseen};
use weldseam::sim::{CurvedScene, curved_suite};

use crate::cli::eval::EvalArgs;
use crate::cli::eval_family;
use crate::cli::table::Table;

/// A seam whose every waypoint lies within this of the bent root follows
/// it as closely as the fillet bar asks of a straight root: a stretch
/// short enough to be straight, not a curved root planned as a line.
const WITHIN_BAR_MM: f64 = 1.0;

/// How one request on one scene ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum CurvedVerdict {
    /// Refused: the right answer on a curved root.
    Refused,
    /// Planned, every waypoint within [`WITHIN_BAR_MM`] of the bent root.
    StraightEnough,
    /// Planned farther from the bent root: a confident wrong seam.
    ConfidentWrong,
}

impl CurvedVerdict {
    fn of(outcome: &CurvedOutcome) -> Self {
        match outcome {
            CurvedOutcome::Refused { .. } => CurvedVerdict::Refused,
            CurvedOutcome::Planned { worst_mm, .. } if *worst_mm <= WITHIN_BAR_MM => CurvedVerdict::StraightEnough,
            CurvedOutcome::Planned { .. } => CurvedVerdict::ConfidentWrong,
        }
    }

    fn label(self) -> &'static str {
        match self {
            CurvedVerdict::Refused => "refused (right)",
            CurvedVerdict::StraightEnough => "planned within the bar",
            CurvedVerdict::ConfidentWrong => "confident wrong",
        }
    }
}

pub fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let config = Config::load_or_default(args.config.as_deref())?;
    let camera: CameraModel = config.camera;
    let planner = Planner::new(config);
    let draw = args.fresh.map_or(Draw::Documented, Draw::Fresh);
    let scenes = eval_family::chosen(curved_suite(draw), |s: &CurvedScene| s.name.as_str(), args)?;

    let mut plans = eval_family::plans_file(args.plans.as_deref())?;
    let mut table = Table::new(
        format!("{} curved members, each planned as t_fillet and auto", scenes.len()),
        &["scene", "bend", "request", "outcome", "seams", "worst mm", "rule"],
    );
    // Per group (tuning, held out) and request: counts of each verdict.
    let mut counts = eval_family::Counts::<3>::new();
    let count = scenes.len();
    for (k, scene) in scenes.iter().enumerate() {
        for joint in [RequestedJoint::Type(JointType::TFillet), RequestedJoint::Auto] {
            let outcome = scene.plan_with(&planner, &camera, joint);
            let verdict = CurvedVerdict::of(&outcome);
            eprintln!("scene {} of {count}: {} {joint}: {}", k + 1, scene.name, verdict.label());
            if let Some(file) = plans.as_mut() {
                writeln!(file, "{}", plan_line(&scene.name, joint, &outcome)).context("cannot write the plans file")?;
            }
            let (seams, worst, rule) = match &outcome {
                CurvedOutcome::Planned { seams, worst_mm } => (seams.to_string(), format!("{worst_mm:.2}"), "-"),
                CurvedOutcome::Refused { rule } => ("0".into(), "-".into(), *rule),
            };
            table.push(vec![
                scene.name.clone(),
                format!("{:?}", scene.axis).to_lowercase(),
                joint.name().into_owned(),
                verdict.label().into(),
                seams,
                worst,
                rule.into(),
            ]);
            counts.entry((is_unseen(&scene.name), joint.name().into_owned())).or_default()[verdict as usize] += 1;
        }
    }
    let summary = eval_family::outcome_table(&counts, ["refused (right)", "planned within the bar", "confident wrong"]);
    eval_family::finish(args, plans, [&table, &summary])?;
    let wrong: usize = counts.values().map(|c| c[CurvedVerdict::ConfidentWrong as usize]).sum();
    if wrong > 0 {
        bail!("{wrong} plan(s) of curved members are confident wrong: a curved root planned as a line");
    }
    Ok(())
}

/// One request's outcome on one scene as a JSON line (`--plans`), for
/// comparing two builds: the seams' count and their worst distance from
/// the bent root, or the rule that refused.
fn plan_line(scene: &str, joint: RequestedJoint, outcome: &CurvedOutcome) -> serde_json::Value {
    let plan = match outcome {
        CurvedOutcome::Planned { seams, worst_mm } => serde_json::json!({ "seams": seams, "worst_mm": worst_mm }),
        CurvedOutcome::Refused { rule } => serde_json::json!({ "rule": rule }),
    };
    serde_json::json!({ "scene": scene, "request": joint.name(), "plan": plan })
}
