//! `weldseam eval`: plans the seeded suite of simulated scenes with the
//! robust method and the paper's exact method side by side and prints the
//! accuracy table (docs/ACCURACY.md holds its latest output). With
//! `--suite consumer` the scenes are a consumer depth camera's, handed over
//! as its users do (cropped, downsampled, in metres) and planned with the
//! same config; `--suite faults` and `--suite hard` are issue 12's test
//! bed. Below the accuracy tables, every scene's outcome is counted as
//! within the bar, refused or a confident wrong seam, per joint (and per
//! fault), and the confident wrong seams and the refusals are listed.
//! `--suite tee` and `--suite multi` are issue 15's frames of more seams
//! than one (a tee's two roots, several workpieces): below the scenes,
//! the seams the frames show against what the planner returned (found,
//! missed, extra) and, for tees, the refusals that name the tee. Then
//! how often each rule of the planner refused and warned, by its id, and
//! last, on frames of one seam, the joint types and groove depths found
//! and the joint's figures along the seam (gap, high-low, groove area,
//! lap step at every waypoint) against the scene's true joint
//! (`weldseam::eval::along_seam`).

use std::io::Write;

use anyhow::Context;
use std::path::PathBuf;

use weldseam::config::{Config, Method};
use weldseam::convert::to_proto::plan_result;
use weldseam::eval::{
    DepthAsk, EvalRequest, JointAsk, SceneOutcome, Verdict, count_rules, count_verdicts, names_a_corner, names_a_tee,
    run_suite_asking, summarise,
};
use weldseam::geometry::pose::EulerConvention;
use weldseam::joint::{JointSet, JointType, RequestedJoint};
use weldseam::pipeline::Stage;
use weldseam::sim::consumer::{consumer_camera, consumer_far_suite, consumer_variant};
use weldseam::sim::draw::is_unseen;
use weldseam::sim::variants::Variant;
use weldseam::sim::{
    Draw, FaultKind, consumer_suite, corner_suite, eval_suite, fault_suite, hard_suite, multi_suite, root_land_suite,
    tee_suite,
};

use crate::cli::args::{GrooveDepthArg, JointRequestArg, SuiteArg};
use crate::cli::table::Table;

#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Configuration file (TOML); built-in defaults otherwise.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Which suite: `industrial` (the default: the 66 scenes of the
    /// paper's camera, rendered with the config's camera), `consumer` (20
    /// scans of a RealSense-class camera at 200 to 500 mm, each made into
    /// cropped:40,voxel:1,metres unless --variant says otherwise),
    /// `consumer-far` (24 more of them at 430 to 500 mm), `faults`
    /// (each fault on each joint type, scored as within the bar, refused or
    /// confident wrong) or `hard` (the industrial suite tilted up to 45
    /// degrees, noisier, with up to 5 % dropouts). Every suite runs the
    /// planner with the config as loaded.
    #[arg(long, value_enum, default_value_t)]
    pub suite: SuiteArg,
    /// Plan fresh draw N of the suite instead of the documented one: the
    /// same strata (joint, standoff, tilt, fault), every random choice
    /// redrawn from other seeds, every scene unseen and named `-freshN`
    /// (`sim::draw`). The documented suite is the regression test; fresh
    /// draws measure a rate on scenes nothing was tuned on.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub fresh: Option<u32>,
    /// Only scenes whose name contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// At most this many scenes (after the filter).
    #[arg(long)]
    pub limit: Option<usize>,
    /// Plan each scene as this variant of its frame: unorganized,
    /// voxel:MM, metres, base, cropped:MM, masked:MM (the crop on the
    /// frame's grid), compressed (written as PCD
    /// binary_compressed and read back), or several joined by commas (e.g.
    /// cropped:25,voxel:1,metres). Scored against the same truth.
    #[arg(long, value_name = "VARIANT")]
    pub variant: Option<Variant>,
    /// How each plan names its joint: `scene` (its own type), `auto` (the
    /// planner decides; a seam of another type is a confident wrong one),
    /// `wrong-1` / `wrong-2` (a wrong type on purpose: only a refusal
    /// is right), or `v-butt`, `i-butt`, `lap` (that type for every scene
    /// and every workpiece, the groove depth measured: a scene of another
    /// type is only to be refused). All but `scene` need the robust
    /// method alone.
    #[arg(long, value_enum, default_value_t)]
    pub joint_request: JointRequestArg,
    /// Name these joint types, joined by `+` (e.g. `v-butt+lap`), in
    /// every plan instead: the planner decides among them, a workpiece of
    /// another type is to be refused. The robust method alone.
    #[arg(long, value_name = "TYPES", conflicts_with = "joint_request", value_parser = joint_set)]
    pub joint_set: Option<JointSet>,
    /// What a V-butt request says of the groove depth: `given` (the
    /// scene's) or `measured` (nothing: the planner measures it).
    #[arg(long, value_enum, default_value_t)]
    pub groove_depth: GrooveDepthArg,
    /// Skip the paper-exact comparison.
    #[arg(long)]
    pub robust_only: bool,
    /// Print the tables as Markdown (for docs/ACCURACY.md) instead of
    /// aligned text.
    #[arg(long)]
    pub markdown: bool,
    /// Also write every scene's planned seams (or its refusal's sentence
    /// and rule id), one JSON line per scene and
    /// method, with every number in full precision and no timings: two
    /// runs give equal files exactly when every plan is the same, digit for
    /// digit (`diff before.jsonl after.jsonl`).
    #[arg(long, value_name = "FILE")]
    pub plans: Option<PathBuf>,
    /// Plan the real scans of this folder (manifest.toml, references.toml
    /// and the scans under files/) instead of a simulated suite: each
    /// present scan typed and `auto`, identity pose, metres, judged against
    /// its reference root or expected refusal (src/cli/eval_real.rs).
    #[arg(long, value_name = "DIR")]
    pub real_scans: Option<PathBuf>,
    /// With --real-scans: recompute every reference root from its boxes
    /// and check it equals references.toml's, planning nothing.
    #[arg(long, requires = "real_scans")]
    pub check_references: bool,
    /// With --real-scans: recompute every reference root from its boxes
    /// and write the figures into references.toml.
    #[arg(long, requires = "real_scans", conflicts_with = "check_references")]
    pub bless_references: bool,
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

/// The error columns of a frame of several seams: its seams matched to
/// the true ones (each seam's errors are in the table of every frame's
/// seams; against the frame's first seam alone they would judge a tee's
/// other root, or another workpiece's seam, as a miss).
fn several_cells(o: &SceneOutcome) -> Vec<String> {
    match (&o.result, &o.seams) {
        (Ok(_), Some((_, m))) => {
            let mut row = vec!["-".to_string(); 4];
            row.push(format!("{} of {} seen found, {} extra", m.found.len(), m.seen, m.extra.len()));
            row
        }
        _ => cells(o),
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
        Err(e) => serde_json::json!({ "error": e.to_string(), "rule": e.rule.id }),
    };
    serde_json::json!({ "scene": o.name, "method": o.method.name(), "plan": outcome })
}

/// `--joint-set`: two or more joint types joined by `+`.
fn joint_set(text: &str) -> Result<JointSet, String> {
    match text.parse::<RequestedJoint>() {
        Ok(RequestedJoint::OneOf(set)) => Ok(set),
        Ok(_) => {
            Err(format!("{text:?} names one joint type; --joint-request asks for one, --joint-set for two or more"))
        }
        Err(e) => Err(e.to_string()),
    }
}

pub fn run(args: &EvalArgs) -> anyhow::Result<()> {
    if let Some(dir) = &args.real_scans {
        return crate::cli::eval_real::run(args, dir);
    }
    let mut robust = Config::load_or_default(args.config.as_deref())?;
    robust.pipeline.method = Method::Robust;
    let mut paper = robust.clone();
    paper.pipeline.method = Method::Paper;
    let ask = EvalRequest {
        joint: match (args.joint_set, args.joint_request) {
            (Some(set), _) => JointAsk::Set(set),
            (None, JointRequestArg::Scene) => JointAsk::AsScene,
            (None, JointRequestArg::Auto) => JointAsk::Auto,
            (None, JointRequestArg::Wrong1) => JointAsk::Wrong(1),
            (None, JointRequestArg::Wrong2) => JointAsk::Wrong(2),
            (None, JointRequestArg::VButt) => JointAsk::Type(JointType::VButt),
            (None, JointRequestArg::IButt) => JointAsk::Type(JointType::IButt),
            (None, JointRequestArg::Lap) => JointAsk::Type(JointType::Lap),
            (None, JointRequestArg::TFillet) => JointAsk::Type(JointType::TFillet),
        },
        groove_depth: match args.groove_depth {
            GrooveDepthArg::Given => DepthAsk::Given,
            GrooveDepthArg::Measured => DepthAsk::Measured,
        },
    };
    // The paper's method plans what it is told: no `auto`, no measured
    // depth, no joint check to refuse a wrong type with.
    let robust_only = args.robust_only || ask != EvalRequest::default();
    let configs = if robust_only { vec![robust.clone()] } else { vec![robust.clone(), paper] };
    let draw = args.fresh.map_or(Draw::Documented, Draw::Fresh);
    let (mut scenes, camera, suite_variant) = match args.suite {
        SuiteArg::Industrial => (eval_suite(draw), robust.camera, Variant::raw()),
        SuiteArg::Consumer => (consumer_suite(draw), consumer_camera(), consumer_variant()),
        SuiteArg::ConsumerFar => (consumer_far_suite(draw), consumer_camera(), consumer_variant()),
        SuiteArg::Faults => (fault_suite(draw), robust.camera, Variant::raw()),
        SuiteArg::Hard => (hard_suite(draw), robust.camera, Variant::raw()),
        SuiteArg::Tee => (tee_suite(draw), robust.camera, Variant::raw()),
        SuiteArg::Multi => (multi_suite(draw), robust.camera, Variant::raw()),
        SuiteArg::Corner => (corner_suite(draw), robust.camera, Variant::raw()),
        SuiteArg::RootLand => (root_land_suite(draw), robust.camera, Variant::raw()),
        // Scenes bent after rendering, judged against the bent root.
        SuiteArg::Curved => return crate::cli::eval_curved::run(args),
        // Scenes re-cut after rendering, judged against the straight root.
        SuiteArg::GrooveWidth => return crate::cli::eval_groove_width::run(args),
        // Tees rendered with their own flange edge and cropped, judged root by root.
        SuiteArg::WebNearEdge => return crate::cli::eval_web_near_edge::run(args),
        // Blocks rendered with a stacked block and crops, judged root by root.
        SuiteArg::Blocks => return crate::cli::eval_blocks::run(args),
        // Scenes of the weld process, scored on its figures, passes and torch.
        SuiteArg::Process => return crate::cli::eval_process::run(args),
    };
    let several_seams = matches!(args.suite, SuiteArg::Tee | SuiteArg::Multi | SuiteArg::Corner);
    // Refusals are right answers on these suites; only a confident wrong
    // seam fails them.
    let judged = matches!(args.suite, SuiteArg::Faults | SuiteArg::Hard)
        || several_seams
        || matches!(ask.joint, JointAsk::Wrong(_) | JointAsk::Type(_) | JointAsk::Set(_));
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
    if !robust_only {
        headers.extend(["paper: max mm", "mean mm", "start mm", "end mm", "result"]);
    }
    if judged {
        headers.push("outcome");
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
    let results = run_suite_asking(&scenes, &camera, &variant, &configs, &ask, |k, outcomes| {
        if let Some(file) = plans.as_mut()
            && plans_written.is_ok()
        {
            plans_written = outcomes.iter().try_for_each(|o| writeln!(file, "{}", plan_line(o, robust.euler)));
        }
        let mut row = describe(&outcomes[0]);
        row.extend(if several_seams { several_cells(&outcomes[0]) } else { cells(&outcomes[0]) });
        row.extend(timings(&outcomes[0]));
        if let Some(p) = outcomes.get(1) {
            row.extend(cells(p));
        }
        if judged {
            row.push(outcomes[0].verdict.label().to_string());
        }
        // A long run shows as it goes, on stderr; the tables come at the end.
        eprintln!("scene {} of {count}: {} {} ({})", k + 1, outcomes[0].name, row[7], outcomes[0].verdict.label());
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
    // Its errors are against each frame's first seam only: on frames of
    // several seams the seam tables below say what was found.
    if !several_seams {
        writeln!(out, "{}", render(&summary))?;
    }
    for table in verdict_tables(&configs, &results) {
        writeln!(out, "{}", render(&table))?;
    }
    if several_seams {
        for table in seam_tables(&results[0]) {
            writeln!(out, "{}", render(&table))?;
        }
    } else {
        writeln!(out, "{}", render(&joint_table(&results[0])))?;
        writeln!(out, "{}", render(&along_seam_table(&results[0])))?;
    }
    out.flush()?;
    let robust_outcomes = &results[0];
    if judged {
        let wrong = count_verdicts(robust_outcomes).confident_wrong;
        if wrong > 0 {
            anyhow::bail!(
                "{wrong} of {} scenes got a confident wrong seam from the robust method",
                robust_outcomes.len()
            );
        }
        return Ok(());
    }
    let failed =
        robust_outcomes.iter().filter(|o| !o.passes() || matches!(o.verdict, Verdict::ConfidentWrong { .. })).count();
    if failed > 0 {
        anyhow::bail!("{failed} of {} scenes miss the bar with the robust method", robust_outcomes.len());
    }
    Ok(())
}

/// The robust method's joint types and groove depths against the truth,
/// per joint type of the scenes: what was requested, how many seams named
/// the scene's type, and the measured groove depth's error where the
/// groove's root was seen.
fn joint_table(outcomes: &[SceneOutcome]) -> Table {
    let mut table = Table::new(
        "Joint types and groove depths (robust)",
        &[
            "joint",
            "requested",
            "scenes",
            "seams",
            "type right",
            "type wrong",
            "depth measured",
            "worst depth error mm",
            "mean depth error mm",
        ],
    );
    for joint in JointType::ALL {
        let group: Vec<&SceneOutcome> = outcomes.iter().filter(|o| o.spec.joint.joint_type() == joint).collect();
        if group.is_empty() {
            continue;
        }
        let requested: std::collections::BTreeSet<std::borrow::Cow<str>> =
            group.iter().map(|o| o.requested.name()).collect();
        let seams: Vec<&weldseam::pipeline::Seam> =
            group.iter().filter_map(|o| o.result.as_ref().ok()).filter_map(|(_, plan)| plan.seams.first()).collect();
        let right = seams.iter().filter(|s| s.joint == joint).count();
        let depth_errors: Vec<f64> = group
            .iter()
            .filter_map(|o| {
                let (_, plan) = o.result.as_ref().ok()?;
                let measured = plan.seams.first()?.quality.as_ref()?.groove_depth_mm?;
                Some((measured - o.truth.groove_depth_mm?).abs())
            })
            .collect();
        let worst = depth_errors.iter().copied().fold(f64::NAN, f64::max);
        let mean = depth_errors.iter().sum::<f64>() / depth_errors.len() as f64;
        let figure = |v: f64| if v.is_finite() { format!("{v:.3}") } else { "-".into() };
        table.push(vec![
            joint.name().to_string(),
            requested.into_iter().collect::<Vec<_>>().join(", "),
            group.len().to_string(),
            seams.len().to_string(),
            right.to_string(),
            (seams.len() - right).to_string(),
            depth_errors.len().to_string(),
            figure(worst),
            figure(mean),
        ]);
    }
    table
}

/// The joint's figures along the seam against the truth, per joint type
/// (robust, the first seam of each scene that planned its joint): per
/// figure, the waypoints scored and those left without it, the median and
/// largest error (mm; the groove's area in % of the true area), and the
/// share of errors within two of the figure's own standard errors.
fn along_seam_table(outcomes: &[SceneOutcome]) -> Table {
    use weldseam::eval::along_seam::{FigureErrors, score};
    let mut table = Table::new(
        "Figures along the seam (robust)",
        &["joint", "figure", "scenes", "waypoints", "without", "median error", "max error", "within 2 sigma %"],
    );
    for joint in [JointType::IButt, JointType::VButt, JointType::Lap] {
        let s = score(outcomes, joint);
        let figures: [(&str, &FigureErrors, f64, &str); 4] = [
            ("gap", &s.gap, 1.0, "mm"),
            ("high-low", &s.high_low, 1.0, "mm"),
            ("groove area", &s.groove_area, 100.0, "%"),
            ("lap step", &s.lap_step, 1.0, "mm"),
        ];
        for (name, f, scale, unit) in figures {
            if f.errors.is_empty() && f.missing == 0 {
                continue;
            }
            let figure = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.3} {unit}", v * scale));
            let within = if f.errors.is_empty() {
                "-".into()
            } else {
                format!("{:.0}", 100.0 * f.within_two_sigma as f64 / f.errors.len() as f64)
            };
            table.push(vec![
                joint.name().to_string(),
                name.to_string(),
                s.scenes.to_string(),
                f.errors.len().to_string(),
                f.missing.to_string(),
                figure(f.median()),
                figure(f.max()),
                within,
            ]);
        }
    }
    table
}

/// Issue 15's tables (robust): every seam the frames show against what
/// was returned, scene by scene (the error against the whole seam or the
/// stretch seen it matches best: how far across, and its ends), then the
/// counts, the scenes tuned on and the held-out ones apart: seams seen (at
/// least half their length), found within the bar, missed, extra, of the
/// wrong type, the joints reported seen but not planned, the refusals and
/// those that name a tee, the worst errors of the seams found.
fn seam_tables(outcomes: &[SceneOutcome]) -> Vec<Table> {
    let mut scenes = Table::new(
        "Seams of each frame (robust)",
        &["scene", "seam", "seen %", "seen", "returned", "across mm", "ends mm", "outcome"],
    );
    let mut totals = Table::new(
        "Seams found, missed and extra (robust)",
        &[
            "scenes of",
            "scenes",
            "seams",
            "seams seen",
            "found",
            "missed",
            "extra",
            "type wrong",
            "reported not planned",
            "refused",
            "refusals naming a tee",
            "refusals naming a corner",
            "confident wrong",
            "worst across mm",
            "worst end mm",
        ],
    );
    let figure = |v: f64| if v.is_finite() { format!("{v:.3}") } else { "-".into() };
    for (group, held_out) in [("tuning", false), ("held out", true)] {
        let members: Vec<&SceneOutcome> =
            outcomes.iter().filter(|o| o.seams.is_some() && is_unseen(&o.name) == held_out).collect();
        if members.is_empty() {
            continue;
        }
        let (mut seams, mut seen, mut found, mut missed, mut extra, mut wrong_type, mut unplanned, mut tee_refusals) =
            (0, 0, 0, 0, 0, 0, 0, 0);
        let mut corner_refusals = 0;
        let (mut worst_across, mut worst_end) = (f64::NAN, f64::NAN);
        for o in &members {
            let Some((truths, matches)) = &o.seams else { continue };
            seams += truths.len();
            seen += matches.seen;
            found += matches.found.len();
            missed += matches.missed.len();
            extra += matches.extra.len();
            wrong_type += matches.wrong_type.len();
            if let Ok((_, plan)) = &o.result {
                unplanned += plan.unplanned.len();
            }
            if let Verdict::Refused { reason } = &o.verdict {
                tee_refusals += usize::from(names_a_tee(reason));
                corner_refusals += usize::from(names_a_corner(reason));
            }
            let outcome = match &o.verdict {
                Verdict::Refused { reason } => format!("refused: {reason}"),
                other => other.label().to_string(),
            };
            for (t, truth) in truths.iter().enumerate() {
                let found_by = matches.found.iter().find(|m| m.truth == t);
                let returned = match (found_by, &o.result) {
                    (Some(m), Ok((_, plan))) => format!("found ({})", plan.seams[m.returned].joint),
                    (None, _) if truth.seen_enough => "missed".to_string(),
                    _ => "-".to_string(),
                };
                let error = match (found_by, &o.result) {
                    (Some(m), Ok((_, plan))) => truth
                        .best_error(&plan.seams[m.returned].waypoints.iter().map(|w| w.position).collect::<Vec<_>>()),
                    _ => None,
                };
                if let Some(e) = error {
                    worst_across = worst_across.max(e.across_mm);
                    worst_end = worst_end.max(e.start_mm.max(e.end_mm));
                }
                let first = t == 0;
                scenes.push(vec![
                    if first { o.name.clone() } else { String::new() },
                    truth.label.clone(),
                    format!("{:.0}", 100.0 * truth.seen_share),
                    if truth.seen_enough { "yes" } else { "no" }.into(),
                    returned,
                    error.map_or("-".into(), |e| format!("{:.3}", e.across_mm)),
                    error.map_or("-".into(), |e| format!("{:.2}", e.start_mm.max(e.end_mm))),
                    if first { outcome.clone() } else { String::new() },
                ]);
            }
            for extra in &matches.extra {
                let error = extra.error.map_or("-".into(), |e| format!("{:.3}", e.across_mm));
                let ends = extra.error.map_or("-".into(), |e| format!("{:.2}", e.start_mm.max(e.end_mm)));
                let nearest = extra.nearest.map_or(String::new(), |t| format!(", nearest the {}", truths[t].label));
                scenes.push(vec![
                    String::new(),
                    format!("returned seam {} on no seam{nearest}", extra.returned + 1),
                    "-".into(),
                    "-".into(),
                    "extra".into(),
                    error,
                    ends,
                    String::new(),
                ]);
            }
        }
        let c = count_verdicts(members.iter().copied());
        let counts = [
            c.scenes,
            seams,
            seen,
            found,
            missed,
            extra,
            wrong_type,
            unplanned,
            c.refused,
            tee_refusals,
            corner_refusals,
            c.confident_wrong,
        ];
        let mut row = vec![group.to_string()];
        row.extend(counts.map(|n| n.to_string()));
        row.extend([figure(worst_across), figure(worst_end)]);
        totals.push(row);
    }
    vec![scenes, totals]
}

/// The fault a scene carries, by name (`none` for a clean scene).
fn fault_name(o: &SceneOutcome) -> &'static str {
    o.spec.fault_kind().map_or("none", FaultKind::name)
}

/// The tables of issue 12's outcomes: counts per method and joint (and
/// per fault when any scene has one), then the robust method's confident
/// wrong seams and its refusals, scene by scene.
fn verdict_tables(configs: &[Config], results: &[Vec<SceneOutcome>]) -> Vec<Table> {
    let count_headers = ["scenes", "within the bar", "refused", "confident wrong"];
    let counts = |group: &[&SceneOutcome]| {
        let c = count_verdicts(group.iter().copied());
        [c.scenes, c.within_bar, c.refused, c.confident_wrong].map(|n| n.to_string())
    };
    let headers: Vec<&str> = ["method", "joint"].into_iter().chain(count_headers).collect();
    let mut per_joint = Table::new("Outcomes per method and joint type", &headers);
    let any_fault = results.iter().flatten().any(|o| o.spec.fault_kind().is_some());
    let headers: Vec<&str> = ["method", "fault"].into_iter().chain(count_headers).collect();
    let mut per_fault = Table::new("Outcomes per method and fault", &headers);
    for (config, outcomes) in configs.iter().zip(results) {
        let method = config.pipeline.method.name().to_string();
        let mut groups: Vec<(String, Vec<&SceneOutcome>)> = JointType::ALL
            .iter()
            .map(|j| (j.name().to_string(), outcomes.iter().filter(|o| o.spec.joint.joint_type() == *j).collect()))
            .collect();
        groups.push(("all".to_string(), outcomes.iter().collect()));
        // The scenes nothing was tuned on, summed apart from the rest, when
        // the run has both.
        let (unseen, tuned): (Vec<&SceneOutcome>, Vec<&SceneOutcome>) =
            outcomes.iter().partition(|o| is_unseen(&o.name));
        if !unseen.is_empty() && !tuned.is_empty() {
            groups.push(("all, tuned on".to_string(), tuned));
            groups.push(("all, held out".to_string(), unseen));
        }
        for (name, group) in groups.iter().filter(|(_, g)| !g.is_empty()) {
            per_joint.push([method.clone(), name.clone()].into_iter().chain(counts(group)).collect());
        }
        if any_fault {
            let faults = ["none"].into_iter().chain(FaultKind::ALL.map(FaultKind::name));
            for fault in faults {
                let group: Vec<&SceneOutcome> = outcomes.iter().filter(|o| fault_name(o) == fault).collect();
                if !group.is_empty() {
                    per_fault.push([method.clone(), fault.to_string()].into_iter().chain(counts(&group)).collect());
                }
            }
        }
    }
    let mut wrong = Table::new(
        "Confident wrong seams (robust)",
        &["scene", "fault", "max mm", "mean mm", "start mm", "end mm", "why"],
    );
    let mut refused = Table::new("Refusals (robust)", &["scene", "fault", "rule", "reason"]);
    for o in results.first().into_iter().flatten() {
        match &o.verdict {
            Verdict::WithinBar => {}
            Verdict::Refused { reason } => {
                let rule = o.result.as_ref().err().map_or("-", |e| e.rule.id);
                refused.push(vec![o.name.clone(), fault_name(o).into(), rule.into(), reason.clone()]);
            }
            Verdict::ConfidentWrong { error, why } => {
                let mut row = vec![o.name.clone(), fault_name(o).into()];
                row.extend(match error {
                    Some(e) => [
                        format!("{:.3}", e.max_mm),
                        format!("{:.3}", e.mean_mm),
                        format!("{:.2}", e.start_mm),
                        format!("{:.2}", e.end_mm),
                    ],
                    None => ["-", "-", "-", "-"].map(String::from),
                });
                row.push(why.clone());
                wrong.push(row);
            }
        }
    }
    let mut tables = vec![per_joint];
    if any_fault {
        tables.push(per_fault);
    }
    tables.extend([wrong, refused, rule_table(configs, results)]);
    tables
}

/// How often each rule refused (a plan, or a joint left unplanned beside
/// the seams planned) and warned, per method, over the suite.
fn rule_table(configs: &[Config], results: &[Vec<SceneOutcome>]) -> Table {
    let mut table = Table::new("Refusals and warnings per rule", &["method", "rule", "refusals", "warnings"]);
    for (config, outcomes) in configs.iter().zip(results) {
        for (rule, refusals, warnings) in count_rules(outcomes).rows() {
            let method = config.pipeline.method.name().to_string();
            table.push(vec![method, rule.to_string(), refusals.to_string(), warnings.to_string()]);
        }
    }
    table
}
