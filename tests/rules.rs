//! The rulebook's document and references: docs/RULES.md is the
//! catalogue rendered, and every config key, constant and test a rule
//! names exists, so the document cannot drift from the code.
//!
//! `WELDSEAM_BLESS=1 cargo test --test tests rules_document_is_current`
//! rewrites docs/RULES.md after a change to the catalogue.

use std::path::Path;

use weldseam::rules::{self, Source};

fn repo_file(path: &str) -> String {
    let full = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[test]
fn rules_document_is_current() {
    let rendered = rules::markdown();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/RULES.md");
    if std::env::var_os("WELDSEAM_BLESS").is_some() {
        std::fs::write(&path, &rendered).expect("docs/RULES.md is writable");
        return;
    }
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        on_disk == rendered,
        "docs/RULES.md differs from the catalogue in src/rules/: run \
         `WELDSEAM_BLESS=1 cargo test --test tests rules_document_is_current` and commit the file"
    );
}

/// Looks a dotted key up in the documented configuration, where every key
/// a user may set is written with its default.
fn config_has_key(config: &toml::Table, key: &str) -> bool {
    let mut parts = key.split('.').peekable();
    let mut table = config;
    while let Some(part) = parts.next() {
        match (table.get(part), parts.peek()) {
            (Some(_), None) => return true,
            (Some(toml::Value::Table(inner)), Some(_)) => table = inner,
            _ => return false,
        }
    }
    false
}

#[test]
fn every_parameter_a_rule_names_exists() {
    let config: toml::Table = repo_file("config/weldseam.toml").parse().expect("config/weldseam.toml parses");
    for rule in rules::all() {
        for parameter in rule.parameters {
            match parameter.source {
                Source::Config(key) => assert!(
                    config_has_key(&config, key),
                    "{}: config key `{key}` is not in config/weldseam.toml",
                    rule.id
                ),
                Source::Constant { file, name } => {
                    let text = repo_file(file);
                    assert!(text.contains(&format!("const {name}:")), "{}: no `const {name}` in {file}", rule.id);
                }
            }
        }
    }
}

/// A test named as `path::function`: the file exists and declares the
/// function.
fn test_text(rule: &str, reference: &str) -> String {
    let (file, function) = reference
        .rsplit_once("::")
        .unwrap_or_else(|| panic!("{rule}: test `{reference}` is not written as path::function"));
    let text = repo_file(file);
    assert!(text.contains(&format!("fn {function}(")), "{rule}: no `fn {function}` in {file}");
    text
}

#[test]
fn every_test_a_rule_names_exists_and_a_firing_test_names_the_rule() {
    for rule in rules::all() {
        for reference in rule.fires {
            let text = test_text(rule.id, reference);
            assert!(text.contains(rule.id), "{}: {reference}'s file never names the rule's id", rule.id);
        }
        for reference in rule.holds {
            test_text(rule.id, reference);
        }
    }
}

#[test]
fn every_rule_is_shown_firing() {
    for rule in rules::all() {
        assert!(!rule.fires.is_empty(), "{}: no test shows the rule firing", rule.id);
        assert!(!rule.reason.is_empty(), "{}: no reason given", rule.id);
    }
}
