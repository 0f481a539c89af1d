//! `weldseam eval --suite groove-width`: the widened-groove family
//! (`weldseam::sim::groove_width`), root-land V-grooves cut wider along
//! part of their seam, planned under `v_butt` and `auto` with the config's
//! settings.
//!
//! The root runs straight on where the groove widens, so a seam whose
//! waypoints all lie within [`WITHIN_BAR_MM`] of it is right; a refusal
//! is counted as such (a miss, not a wrong answer); a seam farther off
//! than [`CONFIDENT_WRONG_MM`] is a confident wrong one and fails the
//! command, one in between is counted as off the bar. The held-out scenes
//! (`-holdout`, and every fresh draw) are summed in rows of their own.
//! `--plans FILE` writes each outcome as a JSON line.

use std::io::Write;

use anyhow::{Context, bail};
use weldseam::camera::CameraModel;
use weldseam::config::Config;
use weldseam::joint::{JointType, RequestedJoint};
use weldseam::pipeline::Planner;
use weldseam::sim::draw::{Draw, is_unseen};
use weldseam::sim::{WidenedGroove, groove_width_suite};

use crate::cli::eval::EvalArgs;
use crate::cli::eval_family;
use crate::cli::table::Table;

/// A seam whose every waypoint lies within this of the root is within the
/// bar the family's own test holds its plans to.
const WITHIN_BAR_MM: f64 = 1.0;

/// A seam with a waypoint farther than this from the root is a confident
/// wrong one, as on every other suite.
const CONFIDENT_WRONG_MM: f64 = 2.0;

/// How one request on one scene ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum GrooveVerdict {
    /// Planned, every waypoint within [`WITHIN_BAR_MM`] of the root.
    Within,
    /// Refused.
    Refused,
    /// Planned within [`CONFIDENT_WRONG_MM`] of the root, not within the bar.
    OffTheBar,
    /// Planned farther off: a confident wrong seam.
    ConfidentWrong,
}

impl GrooveVerdict {
    fn of(outcome: &Result<f64, &'static str>) -> Self {
        match outcome {
            Err(_) => GrooveVerdict::Refused,
            Ok(worst) if *worst <= WITHIN_BAR_MM => GrooveVerdict::Within,
            Ok(worst) if *worst <= CONFIDENT_WRONG_MM => GrooveVerdict::OffTheBar,
            Ok(_) => GrooveVerdict::ConfidentWrong,
        }
    }

    fn label(self) -> &'static str {
        match self {
            GrooveVerdict::Within => "within the bar",
            GrooveVerdict::Refused => "refused",
            GrooveVerdict::OffTheBar => "off the bar",
            GrooveVerdict::ConfidentWrong => "confident wrong",
        }
    }
}

pub fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let config = Config::load_or_default(args.config.as_deref())?;
    let camera: CameraModel = config.camera;
    let planner = Planner::new(config);
    let draw = args.fresh.map_or(Draw::Documented, Draw::Fresh);
    let scenes = eval_family::chosen(groove_width_suite(draw), |s: &WidenedGroove| s.name.as_str(), args)?;

    let mut plans = eval_family::plans_file(args.plans.as_deref())?;
    let mut table = Table::new(
        format!("{} widened V-grooves, each planned as v_butt and auto", scenes.len()),
        &["scene", "request", "outcome", "worst mm", "rule"],
    );
    // Per group (tuning, held out) and request: counts of each verdict.
    let mut counts = eval_family::Counts::<4>::new();
    let count = scenes.len();
    for (k, scene) in scenes.iter().enumerate() {
        for joint in [RequestedJoint::Type(JointType::VButt), RequestedJoint::Auto] {
            let outcome = scene.plan_with(&planner, &camera, joint);
            let verdict = GrooveVerdict::of(&outcome);
            eprintln!("scene {} of {count}: {} {joint}: {}", k + 1, scene.name, verdict.label());
            if let Some(file) = plans.as_mut() {
                writeln!(file, "{}", plan_line(&scene.name, joint, &outcome)).context("cannot write the plans file")?;
            }
            let (worst, rule) = match &outcome {
                Ok(worst_mm) => (format!("{worst_mm:.2}"), "-"),
                Err(rule) => ("-".into(), *rule),
            };
            table.push(vec![scene.name.clone(), joint.name().into_owned(), verdict.label().into(), worst, rule.into()]);
            counts.entry((is_unseen(&scene.name), joint.name().into_owned())).or_default()[verdict as usize] += 1;
        }
    }
    let summary = eval_family::outcome_table(&counts, ["within the bar", "refused", "off the bar", "confident wrong"]);
    eval_family::finish(args, plans, [&table, &summary])?;
    let wrong: usize = counts.values().map(|c| c[GrooveVerdict::ConfidentWrong as usize]).sum();
    if wrong > 0 {
        bail!(
            "{wrong} plan(s) of widened grooves are confident wrong: a seam more than {CONFIDENT_WRONG_MM} mm off the root"
        );
    }
    Ok(())
}

/// One request's outcome on one scene as a JSON line (`--plans`), for
/// comparing two builds: the worst distance from the root, or the rule
/// that refused.
fn plan_line(scene: &str, joint: RequestedJoint, outcome: &Result<f64, &'static str>) -> serde_json::Value {
    let plan = match outcome {
        Ok(worst_mm) => serde_json::json!({ "worst_mm": worst_mm }),
        Err(rule) => serde_json::json!({ "rule": rule }),
    };
    serde_json::json!({ "scene": scene, "request": joint.name(), "plan": plan })
}
