//! Holds a transcription to its program file: every statement a
//! transcription runs is tagged `.at(line, r#"text"#)` with its line in the
//! shipped program and that line's text, trimmed. A tag whose line no
//! longer reads so (the program changed, its transcription did not) and a
//! statement line of the program no tag names both fail the check.

use std::path::PathBuf;

/// A shipped robot program under `deploy/robots/`.
pub fn program_path(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("deploy/robots").join(relative)
}

/// The `(line, text)` tags of one program in a transcription's source:
/// every `.at(<line>, r#"<text>"#)` whose receiver name is `receiver`.
pub fn tags(source: &str, receiver: &str) -> Vec<(usize, String)> {
    let marker = format!("{receiver}.at(");
    let mut found = Vec::new();
    let mut rest = source;
    while let Some(at) = rest.find(&marker) {
        rest = &rest[at + marker.len()..];
        let Some(comma) = rest.find(", r#\"") else { continue };
        let Ok(line) = rest[..comma].trim().parse::<usize>() else { continue };
        let text_start = comma + ", r#\"".len();
        let Some(end) = rest[text_start..].find("\"#)") else { continue };
        found.push((line, rest[text_start..text_start + end].to_string()));
        rest = &rest[text_start + end..];
    }
    found
}

/// Checks a transcription's tags against its program: each tag's text is
/// the program's line (trimmed), and each line `is_statement` accepts is
/// tagged at least once. The error lists every disagreement.
pub fn check(relative: &str, source: &str, receiver: &str, is_statement: fn(&str) -> bool) -> Result<usize, String> {
    let text = std::fs::read_to_string(program_path(relative)).map_err(|e| format!("{relative}: {e}"))?;
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let tags = tags(source, receiver);
    let mut problems = Vec::new();
    for (line, tagged) in &tags {
        match lines.get(line.wrapping_sub(1)) {
            Some(actual) if actual == tagged => {}
            Some(actual) => problems.push(format!("{relative}:{line} reads {actual:?}, transcribed as {tagged:?}")),
            None => problems.push(format!("{relative}:{line} does not exist (transcribed as {tagged:?})")),
        }
    }
    for (k, line) in lines.iter().enumerate() {
        if is_statement(line) && !tags.iter().any(|(n, _)| *n == k + 1) {
            problems.push(format!("{relative}:{} is not transcribed: {line:?}", k + 1));
        }
    }
    if problems.is_empty() { Ok(tags.len()) } else { Err(problems.join("\n")) }
}

/// Block closers and section keywords: no behaviour of their own, and any
/// line added or removed around them moves every tag after it.
pub fn is_closer(line: &str) -> bool {
    let word = line.split([' ', ';', '(']).next().unwrap_or("");
    matches!(
        word.to_ascii_uppercase().as_str(),
        "ENDIF" | "ENDWHILE" | "ENDFOR" | "ENDSWITCH" | "ENDSELECT" | "BEGIN" | "VAR" | "CONST" | "ENDDAT"
    )
}
