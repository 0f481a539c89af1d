//! `weldseam rules`: the planner's rulebook for an integrator or a cell
//! operator who met a rule id in a refusal (on the pendant, in the log, in
//! `plan --json`): every rule in one table, one in full, or docs/RULES.md's
//! text.

use std::fmt::Write as _;
use std::io::Write;

use anyhow::bail;
use weldseam::rules::{self, Rule, Source};

#[derive(Debug, clap::Args)]
pub struct RulesArgs {
    /// A rule's id (`family.decision`): print that rule in full.
    pub id: Option<String>,
    /// Print docs/RULES.md's text (the whole catalogue, as Markdown).
    #[arg(long, conflicts_with = "id")]
    pub markdown: bool,
}

pub fn run(args: &RulesArgs) -> anyhow::Result<()> {
    let text = match (&args.id, args.markdown) {
        (_, true) => rules::markdown(),
        (Some(id), false) => match rules::by_id(id) {
            Some(rule) => in_full(rule),
            None => bail!("no rule has the id {id:?}; `weldseam rules` lists them all"),
        },
        (None, false) => table(),
    };
    std::io::stdout().lock().write_all(text.as_bytes())?;
    Ok(())
}

/// Every rule, one a line: id, stage, effect, summary.
fn table() -> String {
    let all: Vec<&Rule> = rules::all().collect();
    let width = |f: fn(&Rule) -> usize| all.iter().map(|r| f(r)).max().unwrap_or(0);
    let (id_w, stage_w, effect_w) =
        (width(|r| r.id.len()), width(|r| r.stage.name().len()), width(|r| r.effect.name().len()));
    let mut out = String::new();
    let _ = writeln!(out, "{:id_w$}  {:stage_w$}  {:effect_w$}  summary", "id", "stage", "effect");
    for rule in all {
        let _ = writeln!(
            out,
            "{:id_w$}  {:stage_w$}  {:effect_w$}  {}",
            rule.id,
            rule.stage.name(),
            rule.effect.name(),
            rule.summary
        );
    }
    out
}

/// One rule: what it checks and why, its parameters and its tests.
fn in_full(rule: &Rule) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{}\n", rule.id);
    let _ = writeln!(out, "stage:   {}", rule.stage.name());
    let _ = writeln!(out, "effect:  {}", rule.effect.name());
    if let Some(gate) = rule.gate {
        let _ = writeln!(out, "gate:    {gate}");
    }
    let _ = writeln!(out, "checks:  {}", rule.summary);
    if !rule.reason.is_empty() {
        let _ = writeln!(out, "\n{}", rule.reason);
    }
    if !rule.parameters.is_empty() {
        out.push_str("\nparameters:\n");
        for p in rule.parameters {
            let unit = if p.unit.is_empty() { String::new() } else { format!(" ({})", p.unit) };
            let set_by = match p.source {
                Source::Config(key) => format!("config {key}"),
                Source::Constant { file, name } => format!("constant {name} in {file}"),
            };
            let _ = writeln!(out, "  {}{unit}: {}; set by {set_by}", p.name, p.meaning);
        }
    }
    for (what, tests) in [("fires in", rule.fires), ("holds in", rule.holds)] {
        if !tests.is_empty() {
            let _ = writeln!(out, "\n{what}:");
            for test in tests {
                let _ = writeln!(out, "  {test}");
            }
        }
    }
    out
}
