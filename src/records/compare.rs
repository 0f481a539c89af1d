//! Whether a plan made again is the plan recorded: the same bit for bit
//! (every figure and waypoint, the stage times aside, which are the
//! machine's and not the plan's), or which figures changed.

use serde_json::Value;

use super::Outcome;

/// The most changed figures listed; the rest are counted.
pub const MAX_CHANGES_LISTED: usize = 40;

/// What differs between two outcomes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Changes {
    /// Each changed figure: its path in the plan's JSON, then the
    /// recorded and the new value.
    pub listed: Vec<String>,
    /// How many more changed than are listed.
    pub more: usize,
}

impl Changes {
    pub fn is_empty(&self) -> bool {
        self.listed.is_empty() && self.more == 0
    }

    fn push(&mut self, change: String) {
        if self.listed.len() < MAX_CHANGES_LISTED {
            self.listed.push(change);
        } else {
            self.more += 1;
        }
    }
}

/// The outcome as compared: the stage times left out, each seam's
/// figures along it and process put in (the plan's JSON form leaves them
/// out of the seam).
fn comparable(outcome: &Outcome) -> Value {
    match outcome {
        Outcome::Planned(result) => {
            let mut value = serde_json::to_value(result).unwrap_or(Value::Null);
            if let Some(map) = value.as_object_mut() {
                map.remove("timing_ms");
            }
            let seams = value.get_mut("seams").and_then(Value::as_array_mut);
            for (json, seam) in seams.into_iter().flatten().zip(&result.seams) {
                if let Some(map) = json.as_object_mut() {
                    map.insert("along_seam".into(), serde_json::to_value(&seam.along_seam).unwrap_or(Value::Null));
                    map.insert("process".into(), serde_json::to_value(&seam.process).unwrap_or(Value::Null));
                }
            }
            serde_json::json!({ "planned": value })
        }
        Outcome::Refused { code, rule, reason } => {
            serde_json::json!({ "refused": { "code": code, "rule": rule, "reason": reason } })
        }
    }
}

/// What changed from `recorded` to `now`; empty when they are the same.
/// Numbers are compared by their bits (through their shortest exact
/// decimal form), so a change in the last bit of a waypoint is a change.
pub fn compare(recorded: &Outcome, now: &Outcome) -> Changes {
    let mut changes = Changes::default();
    walk("", &comparable(recorded), &comparable(now), &mut changes);
    changes
}

fn walk(path: &str, a: &Value, b: &Value, changes: &mut Changes) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            for (key, va) in x {
                let at = format!("{path}.{key}");
                match y.get(key) {
                    Some(vb) => walk(&at, va, vb, changes),
                    None => changes.push(format!("{at}: {va} -> absent")),
                }
            }
            for (key, vb) in y.iter().filter(|(k, _)| !x.contains_key(*k)) {
                changes.push(format!("{path}.{key}: absent -> {vb}"));
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (k, (va, vb)) in x.iter().zip(y).enumerate() {
                walk(&format!("{path}[{k}]"), va, vb, changes);
            }
        }
        _ if a != b => changes.push(format!("{}: {a} -> {b}", if path.is_empty() { "." } else { path })),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(rule: &str) -> Outcome {
        Outcome::Refused { code: "plan_failed".into(), rule: Some(rule.into()), reason: "r".into() }
    }

    #[test]
    fn the_same_outcome_has_no_change_and_a_different_one_names_the_figure() {
        assert!(compare(&refused("a.b"), &refused("a.b")).is_empty());
        let changes = compare(&refused("a.b"), &refused("a.c"));
        assert_eq!(changes.listed, vec![".refused.rule: \"a.b\" -> \"a.c\"".to_string()]);
    }
}
