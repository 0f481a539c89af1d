//! Holds a program's Rust transcription to the program file it follows:
//! every statement the transcription runs is tagged `at(<line>,
//! r#"<text>"#)` with its line number in the file and that line's text
//! (trimmed). A tag whose line no longer reads so (the program changed and
//! its transcription did not) fails, and so does a statement line of the
//! program that no tag names.

use std::path::PathBuf;

/// A shipped program, by its path under deploy/robots/.
pub fn program(relative: &str) -> (PathBuf, String) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("deploy/robots").join(relative);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (path, text)
}

/// The `(line, text)` tags in a transcription's source: `at(<line>,
/// r#"<text>"#)`, spaces and line breaks (rustfmt's) allowed between the
/// parts.
pub fn tags(source: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    let mut rest = source;
    while let Some(at) = rest.find("at(") {
        rest = &rest[at + "at(".len()..];
        let after_digits = rest.trim_start();
        let digits: String = after_digits.chars().take_while(char::is_ascii_digit).collect();
        let Ok(line) = digits.parse::<usize>() else { continue };
        let Some(text) = after_digits[digits.len()..].trim_start().strip_prefix(',') else { continue };
        let Some(text) = text.trim_start().strip_prefix("r#\"") else { continue };
        let Some(end) = text.find("\"#") else { break };
        found.push((line, text[..end].to_string()));
        rest = &text[end..];
    }
    found
}

/// Checks `source`'s tags against the program at `relative`: every tag
/// reads as its line does, and every line `is_statement` takes is tagged.
/// Returns how many statement lines there are, or every disagreement.
pub fn check(relative: &str, source: &str, is_statement: fn(&str) -> bool) -> Result<usize, String> {
    let (_, text) = program(relative);
    check_text(relative, &text, source, is_statement)
}

fn check_text(relative: &str, text: &str, source: &str, is_statement: fn(&str) -> bool) -> Result<usize, String> {
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let tags = tags(source);
    let mut problems = Vec::new();
    for (line, tagged) in &tags {
        match lines.get(line.wrapping_sub(1)) {
            Some(actual) if actual == tagged => {}
            Some(actual) => problems.push(format!("{relative}:{line} reads {actual:?}, transcribed as {tagged:?}")),
            None => problems.push(format!("{relative}:{line} is past the end (transcribed as {tagged:?})")),
        }
    }
    let mut statements = 0;
    for (k, line) in lines.iter().enumerate() {
        if is_statement(line) {
            statements += 1;
            if !tags.iter().any(|(n, _)| *n == k + 1) {
                problems.push(format!("{relative}:{} is not transcribed: {line:?}", k + 1));
            }
        }
    }
    match problems.is_empty() {
        true => Ok(statements),
        false => Err(problems.join("\n")),
    }
}

#[test]
fn a_changed_or_untranscribed_line_is_caught() {
    let program = "a = 0\n# a comment\nb = 1\nc = 2\n";
    let statement = |line: &str| !line.is_empty() && !line.starts_with('#');
    let whole = "u.at(1, r#\"a = 0\"#); u.at(3, r#\"b = 1\"#); u.at(4, r#\"c = 2\"#);";
    assert_eq!(check_text("p", program, whole, statement), Ok(3));
    let changed = whole.replace("c = 2", "c = 3");
    assert!(check_text("p", program, &changed, statement).unwrap_err().contains("p:4 reads \"c = 2\""));
    let missing = "u.at(3, r#\"b = 1\"#); u.at(\n    4,\n    r#\"c = 2\"#,\n);";
    assert!(check_text("p", program, missing, statement).unwrap_err().contains("p:1 is not transcribed"));
}
