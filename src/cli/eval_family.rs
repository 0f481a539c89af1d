//! What the eval runs of the seeded scene families (`--suite curved`,
//! `--suite groove-width`, `--suite web-near-edge`, `--suite blocks`)
//! share: the `--plans` file, the outcome table summed per group (tuning,
//! held out) and request, and the printing.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::Context;

use weldseam::joint::{JointType, RequestedJoint};

use crate::cli::args::JointRequestArg;
use crate::cli::eval::EvalArgs;
use crate::cli::table::Table;

/// Per group (held out or not) and request: how many plans got each
/// verdict, indexed as the family's verdict enum is.
pub type Counts<const N: usize> = BTreeMap<(bool, String), [usize; N]>;

/// The `--plans` file, created empty, when one is asked for.
pub fn plans_file(path: Option<&Path>) -> anyhow::Result<Option<BufWriter<File>>> {
    path.map(|path| File::create(path).map(BufWriter::new).with_context(|| format!("cannot create {}", path.display())))
        .transpose()
}

/// The outcome table: one row per group and request, the plans and the
/// count of each verdict, named by `verdicts` in their index order.
pub fn outcome_table<const N: usize>(counts: &Counts<N>, verdicts: [&str; N]) -> Table {
    outcome_table_of(counts, "plans", verdicts)
}

/// [`outcome_table`] of a family that judges something else than whole
/// plans (each root of a tee): `counted` heads the column of their number.
pub fn outcome_table_of<const N: usize>(counts: &Counts<N>, counted: &str, verdicts: [&str; N]) -> Table {
    let mut header = vec!["scenes", "request", counted];
    header.extend(verdicts);
    let mut summary = Table::new("Outcomes", &header);
    for ((held_out, request), c) in counts {
        let group = if *held_out { "held out" } else { "tuning" };
        let mut row = vec![group.to_string(), request.clone(), c.iter().sum::<usize>().to_string()];
        row.extend(c.map(|n| n.to_string()));
        summary.push(row);
    }
    summary
}

/// Prints the per-plan table and the outcome table, as markdown under
/// `--markdown`, and flushes the plans file.
pub fn finish(args: &EvalArgs, plans: Option<BufWriter<File>>, tables: [&Table; 2]) -> anyhow::Result<()> {
    if let Some(mut file) = plans {
        file.flush().context("cannot write the plans file")?;
    }
    let mut out = std::io::stdout().lock();
    for t in tables {
        writeln!(out, "{}", if args.markdown { t.to_markdown() } else { t.to_text() })?;
    }
    out.flush()?;
    Ok(())
}

/// The family's `scenes` the run plans: those whose name holds
/// `--filter`, at most `--limit` of them; an error when none is left.
pub fn chosen<S>(mut scenes: Vec<S>, name: impl Fn(&S) -> &str, args: &EvalArgs) -> anyhow::Result<Vec<S>> {
    if let Some(f) = &args.filter {
        scenes.retain(|s| name(s).contains(f.as_str()));
    }
    scenes.truncate(args.limit.unwrap_or(usize::MAX));
    anyhow::ensure!(!scenes.is_empty(), "no scene matches the filter");
    Ok(scenes)
}

/// The request a family of fillet roots is planned under: `t_fillet` by
/// default (`--joint-request scene` or `t-fillet`), or `auto`; any other
/// request, or a `--joint-set`, is an error naming the `suite`.
pub fn fillet_or_auto(args: &EvalArgs, suite: &str, what: &str) -> anyhow::Result<RequestedJoint> {
    match (args.joint_set, args.joint_request) {
        (None, JointRequestArg::Scene | JointRequestArg::TFillet) => Ok(RequestedJoint::Type(JointType::TFillet)),
        (None, JointRequestArg::Auto) => Ok(RequestedJoint::Auto),
        _ => anyhow::bail!("--suite {suite} plans its {what} as t_fillet or, with --joint-request auto, as auto"),
    }
}
