//! docs/RULES.md, rendered from the catalogue.

use std::fmt::Write;

use super::{CATALOGUES, Parameter, Rule, Source, Stage};

/// The rulebook as Markdown: a table of every rule by stage, then each
/// rule in full.
pub fn markdown() -> String {
    let mut out = String::new();
    out.push_str(
        "# Rules\n\n\
         Every decision of the planner that can refuse a seam, change a joint's type, or move or cut a \
         seam's end, with the id it carries in refusals and warnings: in `plan --json`, the debug \
         trace, both wire links, the logs, the metrics (`weldseam_refusals_total{rule=...}`) and \
         `weldseam eval`'s tables.\n\n\
         Generated from the catalogue in src/rules/ (`weldseam rules --markdown`); the test \
         `rules_document_is_current` fails when this file differs from it. Ids are stable: a rule \
         that no longer applies is removed and its id never reused.\n\n",
    );
    let rules: Vec<(Stage, &[&Rule])> = Stage::ALL.into_iter().zip(CATALOGUES).collect();
    out.push_str("| id | stage | effect | gate | what it checks |\n| --- | --- | --- | --- | --- |\n");
    for (_, catalogue) in &rules {
        for rule in *catalogue {
            let gate = rule.gate.map_or(String::new(), |g| format!("`{g}`"));
            let _ = writeln!(
                out,
                "| [`{}`](#{}) | {} | {} | {gate} | {} |",
                rule.id,
                anchor(rule.id),
                rule.stage,
                rule.effect.name(),
                rule.summary
            );
        }
    }
    for (stage, catalogue) in &rules {
        if catalogue.is_empty() {
            continue;
        }
        let _ = write!(out, "\n## Stage `{stage}`\n");
        for rule in *catalogue {
            write_rule(&mut out, rule);
        }
    }
    out
}

fn write_rule(out: &mut String, rule: &Rule) {
    let _ = write!(out, "\n### `{}`\n\n{}.\n\n{}\n\n", rule.id, capitalised(rule.summary), rule.reason);
    let gate = rule.gate.map_or(String::new(), |g| format!(", gate `{g}`"));
    let _ = writeln!(out, "Stage `{}`; {}{gate}.", rule.stage, rule.effect.name());
    if !rule.parameters.is_empty() {
        out.push_str("\n| parameter | unit | set by | meaning |\n| --- | --- | --- | --- |\n");
        for Parameter { name, unit, meaning, source } in rule.parameters {
            let set_by = match source {
                Source::Config(key) => format!("config `{key}`"),
                Source::Constant { file, name } => format!("constant `{name}` in {file}"),
            };
            let _ = writeln!(out, "| `{name}` | {unit} | {set_by} | {meaning} |");
        }
    }
    for (what, tests) in [("Fires in", rule.fires), ("Holds in", rule.holds)] {
        if !tests.is_empty() {
            let list: Vec<String> = tests.iter().map(|t| format!("`{t}`")).collect();
            let _ = writeln!(out, "\n{what}: {}.", list.join(", "));
        }
    }
}

/// GitHub's heading anchor for a heading that is the id in backticks.
fn anchor(id: &str) -> String {
    id.chars().filter(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '-').collect()
}

fn capitalised(s: &str) -> String {
    let mut chars = s.chars();
    chars.next().map_or(String::new(), |c| c.to_uppercase().chain(chars).collect())
}
