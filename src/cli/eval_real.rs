//! `weldseam eval --real-scans DIR`: plans every present scan of a folder
//! of real scans (manifest.toml, references.toml, files/) typed (its
//! family's joint) and `auto`, at the config's settings, identity pose,
//! in metres, and judges each plan against the scan's reference
//! (`weldseam::eval::real_scans`): right, refused (and by which rule),
//! short of the bar, or confident wrong, with each plan's distance from
//! the reference root and its coverage of the visible root.
//!
//! `--check-references` recomputes every reference root from its boxes
//! and checks it equals the committed figures; `--bless-references`
//! writes the recomputed figures into references.toml (keeping its
//! comments and the sentences on how the boxes were chosen). Missing scan
//! files are named and skipped.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, bail};
use weldseam::config::Config;
use weldseam::convert::to_proto::plan_result;
use weldseam::eval::real_scans::reference::{cloud_points, differs, fit_box, rounded};
use weldseam::eval::real_scans::{
    Expect, MeasuredRoot, RealScans, ScanReference, ScanScore, Verdict, bar_for, measure_root, score,
};
use weldseam::geometry::Vec3;
use weldseam::geometry::pose::RobotPose;
use weldseam::joint::RequestedJoint;
use weldseam::pipeline::input::Units;
use weldseam::pipeline::{Plan, PlanError, PlanRequest, Planner};

use crate::cli::eval::EvalArgs;
use crate::cli::table::Table;

/// The identity flange pose every real scan is planned under: the scans
/// come with no robot pose.
const IDENTITY_POSE: RobotPose = RobotPose { xyz_mm: [0.0; 3], angles_deg: [0.0; 3] };

pub fn run(args: &EvalArgs, dir: &Path) -> anyhow::Result<()> {
    let scans = RealScans::load(dir)?;
    if args.check_references || args.bless_references {
        return check_references(&scans, args.bless_references);
    }
    let config = Config::load_or_default(args.config.as_deref())?;
    let planner = Planner::new(config);
    let mut plans = match &args.plans {
        Some(path) => Some(std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        )),
        None => None,
    };
    let mut table = Table::new(
        "Real scans, default settings, identity pose, metres",
        &[
            "scan",
            "family",
            "request",
            "expected",
            "outcome",
            "seams",
            "median mm",
            "max mm",
            "visible root mm",
            "covered within bar %",
            "rule",
        ],
    );
    let mut counts = std::collections::BTreeMap::<(String, &str), [usize; 5]>::new();
    let mut missing = Vec::new();
    let mut wrong = 0;
    for scan in &scans.manifest {
        let Some(reference) = scans.reference(&scan.id) else {
            missing.push(format!("{} (no reference)", scan.id));
            continue;
        };
        let path = scans.file(&scan.id);
        if !path.exists() {
            missing.push(format!("{} (no file)", scan.id));
            continue;
        }
        let cloud = weldseam::cloud::load(&path).with_context(|| format!("cannot read {}", path.display()))?;
        for (ask, joint) in [("typed", RequestedJoint::Type(reference.joint)), ("auto", RequestedJoint::Auto)] {
            let request = PlanRequest { units: Units::Metres, ..PlanRequest::new(joint, None, IDENTITY_POSE) };
            let outcome = planner.plan(&cloud, &request);
            let judged = judge(&planner, reference, &outcome);
            eprintln!("{} {ask}: {}", scan.id, judged.as_ref().map_or("not scored".into(), |s| s.verdict.label()));
            if let Some(file) = plans.as_mut() {
                writeln!(file, "{}", plan_line(&scan.id, &joint, &planner, &outcome, judged.as_ref()))
                    .context("cannot write the plans file")?;
            }
            let rule = outcome.as_ref().err().map_or("-", |e| e.rule.id);
            let planned = outcome.as_ref().map_or(0, |plan| plan.seams.len());
            table.push(row(&scan.id, &scan.family, &joint, reference, judged.as_ref(), planned, rule));
            let tally = counts.entry((ask.to_string(), expected_word(reference))).or_default();
            tally[0] += 1;
            match judged.as_ref().map(|s| &s.verdict) {
                Some(Verdict::Right) => tally[1] += 1,
                Some(Verdict::Refused { .. }) => tally[2] += 1,
                Some(Verdict::ShortOfBar) => tally[3] += 1,
                Some(Verdict::ConfidentWrong { .. }) => {
                    tally[4] += 1;
                    wrong += 1;
                }
                None => {}
            }
        }
    }
    if let Some(mut file) = plans {
        file.flush().context("cannot write the plans file")?;
    }
    let mut summary = Table::new(
        "Outcomes",
        &["request", "expected", "plans", "right", "refused", "short of the bar", "confident wrong"],
    );
    for ((ask, expected), c) in &counts {
        let mut r = vec![ask.clone(), expected.to_string()];
        r.extend(c.map(|n| n.to_string()));
        summary.push(r);
    }
    let render = |t: &Table| if args.markdown { t.to_markdown() } else { t.to_text() };
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", render(&table))?;
    writeln!(out, "{}", render(&summary))?;
    if !missing.is_empty() {
        writeln!(out, "skipped: {}", missing.join(", "))?;
    }
    out.flush()?;
    if wrong > 0 {
        bail!("{wrong} plan(s) of real scans are confident wrong");
    }
    Ok(())
}

fn expected_word(reference: &ScanReference) -> &'static str {
    match reference.expect {
        Expect::Planned => "a plan",
        Expect::Refused => "a refusal",
    }
}

/// One plan's row of the table.
fn row(
    id: &str,
    family: &str,
    joint: &RequestedJoint,
    reference: &ScanReference,
    judged: Option<&ScanScore>,
    planned: usize,
    rule: &str,
) -> Vec<String> {
    let expected = match (&reference.expect, &reference.refusal) {
        (Expect::Refused, Some(r)) => format!("refused: {}", r.class.describe()),
        _ => {
            let (bar, share) = bar_for(reference.joint);
            format!("{} within {bar} mm over {:.0} %", reference.joint, 100.0 * share)
        }
    };
    let figure = |v: Option<f64>| v.filter(|v| v.is_finite()).map_or("-".into(), |v| format!("{v:.2}"));
    let (seams, median, max, visible, covered) = match judged {
        Some(s) => (
            planned.to_string(),
            figure(s.seams.iter().map(|x| x.median_mm).reduce(f64::max)),
            figure(s.seams.iter().map(|x| x.max_mm).reduce(f64::max)),
            s.roots.iter().map(|r| format!("{:.0}", r.visible_mm)).collect::<Vec<_>>().join(" / "),
            s.roots.iter().map(|r| format!("{:.1}", 100.0 * r.coverage)).collect::<Vec<_>>().join(" / "),
        ),
        None => ("-".into(), "-".into(), "-".into(), "-".into(), "-".into()),
    };
    let outcome = judged.map_or("not scored (references not blessed)".into(), |s| s.verdict.label());
    vec![
        id.into(),
        family.into(),
        joint.name().into_owned(),
        expected,
        outcome,
        seams,
        median,
        max,
        if visible.is_empty() { "-".into() } else { visible },
        if covered.is_empty() { "-".into() } else { covered },
        rule.into(),
    ]
}

/// The plan's seams in the cloud's frame, mm: the waypoints are in the
/// base frame, `Base_T_End · End_T_Camera · p` under the identity pose.
fn seams_in_cloud_frame(planner: &Planner, plan: &Plan) -> Vec<Vec<Vec3>> {
    let base_from_camera = IDENTITY_POSE.to_isometry(planner.config().euler) * planner.config().hand_eye;
    let camera_from_base = base_from_camera.inverse();
    plan.seams
        .iter()
        .map(|s| s.waypoints.iter().map(|w| camera_from_base.transform_point(&w.position.into()).coords).collect())
        .collect()
}

fn judge(planner: &Planner, reference: &ScanReference, outcome: &Result<Plan, PlanError>) -> Option<ScanScore> {
    match outcome {
        Ok(plan) => score(reference, Ok(&seams_in_cloud_frame(planner, plan))),
        Err(e) => score(reference, Err(e.rule.id)),
    }
}

/// One plan as a JSON line: the scan, the request, the seams as `plan
/// --json` reports them (no timings) or the refusal and its rule, and the
/// verdict.
fn plan_line(
    id: &str,
    joint: &RequestedJoint,
    planner: &Planner,
    outcome: &Result<Plan, PlanError>,
    judged: Option<&ScanScore>,
) -> serde_json::Value {
    let plan = match outcome {
        Ok(plan) => serde_json::json!({ "seams": plan_result(plan, planner.config().euler).seams }),
        Err(e) => serde_json::json!({ "error": e.to_string(), "rule": e.rule.id }),
    };
    let verdict = judged.map(|s| {
        serde_json::json!({
            "outcome": s.verdict.label(),
            "why": match &s.verdict { Verdict::ConfidentWrong { why } => Some(why.clone()), _ => None },
            "seams": s.seams.iter().map(|x| serde_json::json!({"root": x.root, "median_mm": x.median_mm, "max_mm": x.max_mm})).collect::<Vec<_>>(),
            "roots": s.roots.iter().map(|r| serde_json::json!({"visible_mm": r.visible_mm, "coverage": r.coverage})).collect::<Vec<_>>(),
        })
    });
    serde_json::json!({ "scan": id, "request": joint.name(), "plan": plan, "verdict": verdict })
}

/// Recomputes every reference root from its boxes; with `bless`, writes
/// the figures into references.toml, else checks them against it.
fn check_references(scans: &RealScans, bless: bool) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    let mut measured: Vec<(String, Vec<MeasuredRoot>)> = Vec::new();
    let (mut checked, mut failed, mut skipped) = (0, Vec::new(), Vec::new());
    for reference in scans.references.scans.iter().filter(|r| !r.roots.is_empty()) {
        let path = scans.file(&reference.id);
        if !path.exists() {
            skipped.push(reference.id.clone());
            writeln!(out, "{}: skipped, {} is missing", reference.id, path.display())?;
            continue;
        }
        let cloud = weldseam::cloud::load(&path).with_context(|| format!("cannot read {}", path.display()))?;
        let points = cloud_points(&cloud);
        let mut roots = Vec::new();
        for root in &reference.roots {
            let m = measure_root(&points, root, scans.references.mm_per_unit).with_context(|| {
                // Each box's own fit, to show which box is wrong.
                let fits: Vec<String> = root
                    .faces
                    .iter()
                    .map(|f| match fit_box(&points, f, scans.references.mm_per_unit) {
                        Ok((_, p)) => format!("{:?}: {p:?}", f.name),
                        Err(e) => format!("{:?}: {e}", f.name),
                    })
                    .collect();
                format!("{}, root {:?} (box fits: {})", reference.id, root.name, fits.join("; "))
            })?;
            let m = rounded(&m);
            let rms: Vec<String> = m.planes.iter().map(|p| format!("{:.3}", p.rms_mm)).collect();
            let verdict = match (&root.measured, bless) {
                (_, true) => "written".to_string(),
                (None, false) => {
                    failed.push(format!("{}: {}", reference.id, root.name));
                    "NOT COMMITTED".to_string()
                }
                (Some(committed), false) => match differs(committed, &m) {
                    None => "equal to the committed line".to_string(),
                    Some(why) => {
                        failed.push(format!("{}: {}", reference.id, root.name));
                        format!("DIFFERS: {why}")
                    }
                },
            };
            let mut steady = String::new();
            if let Some(s) = &m.square_top {
                steady.push_str(&format!(
                    ", top square to the standing face: side face {:.2}° off square, free fit tilted {:.2}°, sliver rms {:.3} mm free, {:.3} mm added, root one-sigma {:.2} mm, {:.2} mm if square to the side",
                    s.side_off_square_deg, s.free_tilt_deg, s.free_rms_mm, s.added_rms_mm, s.sigma_mm, s.square_to_side_mm
                ));
            }
            if let Some(moved) = m.box_choice_mm {
                steady.push_str(&format!(", the alternative boxes move it {moved:.2} mm"));
            }
            for (check, c) in root.checks.iter().zip(&m.checks) {
                steady.push_str(&format!(
                    ", {:?} lies {:+.2} mm off the flange's plane (median of {} points)",
                    check.name, c.median_mm, c.points
                ));
            }
            writeln!(
                out,
                "{}, {}: planes rms {} mm, visible {:.1} mm ({:.0} % of it seen){steady}: {verdict}",
                reference.id,
                root.name,
                rms.join(" / "),
                m.visible_length_mm(),
                100.0 * m.seen_share
            )?;
            checked += 1;
            roots.push(m);
        }
        measured.push((reference.id.clone(), roots));
    }
    writeln!(
        out,
        "{checked} root(s) recomputed, {} differ, {} scan(s) skipped as missing",
        failed.len(),
        skipped.len()
    )?;
    if bless {
        let path = scans.dir.join(weldseam::eval::real_scans::REFERENCES_FILE);
        write_measured(&path, &measured)?;
        writeln!(out, "wrote {}", path.display())?;
        return Ok(());
    }
    if !failed.is_empty() {
        bail!("{} reference root(s) differ from references.toml: {}", failed.len(), failed.join(", "));
    }
    Ok(())
}

/// Writes each root's measured figures into the references file, keeping
/// everything else of it as it is.
fn write_measured(path: &Path, measured: &[(String, Vec<MeasuredRoot>)]) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut doc: toml_edit::DocumentMut = text.parse().with_context(|| format!("{} is not TOML", path.display()))?;
    let scans = doc
        .get_mut("scan")
        .and_then(toml_edit::Item::as_array_of_tables_mut)
        .context("references.toml has no [[scan]]")?;
    for scan in scans.iter_mut() {
        let id = scan.get("id").and_then(toml_edit::Item::as_str).unwrap_or_default().to_string();
        let Some((_, roots)) = measured.iter().find(|(m, _)| *m == id) else { continue };
        let tables = scan.get_mut("root").and_then(toml_edit::Item::as_array_of_tables_mut);
        for (table, m) in tables.into_iter().flat_map(|t| t.iter_mut()).zip(roots) {
            // One inline table right under the root's name and kind (a
            // table of its own would be written after the root's faces).
            let fresh: toml_edit::DocumentMut = format!("measured = {}", inline(m)).parse()?;
            let value = fresh.get("measured").cloned().context("the measured figures do not parse back")?;
            table.insert("measured", value);
        }
    }
    std::fs::write(path, doc.to_string()).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// A root's figures as one inline TOML table, a plane to a line.
fn inline(m: &MeasuredRoot) -> String {
    let list = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ");
    let planes: Vec<String> = m
        .planes
        .iter()
        .map(|p| {
            format!(
                "    {{ normal = [{}], offset_mm = {}, rms_mm = {}, points = {} }},",
                list(&p.normal),
                p.offset_mm,
                p.rms_mm,
                p.points
            )
        })
        .collect();
    // The square-top root's checks and uncertainty, and how far the
    // alternative boxes move the root, where measured.
    let mut extra = String::new();
    if let Some(moved) = m.box_choice_mm {
        extra.push_str(&format!("box_choice_mm = {moved}, "));
    }
    if let Some(a) = &m.alternative {
        extra.push_str(&format!(
            "alternative = {{ point_mm = [{}], direction = [{}] }}, ",
            list(&a.point_mm),
            list(&a.direction)
        ));
    }
    if !m.checks.is_empty() {
        let checks: Vec<String> =
            m.checks.iter().map(|c| format!("{{ median_mm = {}, points = {} }}", c.median_mm, c.points)).collect();
        extra.push_str(&format!("checks = [{}], ", checks.join(", ")));
    }
    if let Some(s) = &m.square_top {
        extra.push_str(&format!(
            "square_top = {{ side_off_square_deg = {}, free_tilt_deg = {}, free_rms_mm = {}, added_rms_mm = {}, sigma_mm = {}, square_to_side_mm = {} }}, ",
            s.side_off_square_deg, s.free_tilt_deg, s.free_rms_mm, s.added_rms_mm, s.sigma_mm, s.square_to_side_mm
        ));
    }
    format!(
        "{{ point_mm = [{}], direction = [{}], visible_mm = [{}], seen_share = {}, {extra}planes = [\n{}\n] }}",
        list(&m.point_mm),
        list(&m.direction),
        list(&m.visible_mm),
        m.seen_share,
        planes.join("\n")
    )
}
