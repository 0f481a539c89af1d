//! Every protocol version number the documents mention agrees with the
//! code: the binary protocol's newest and oldest served versions
//! ([`PROTOCOL_VERSION`], [`OLDEST_SERVED_VERSION`]) and the text link's
//! version ([`TEXT_PROTOCOL_VERSION`]), read from the crate, never
//! written here. Documents: README.md, proto/PROTOCOL.md, proto/ROBOTS.md
//! and docs/*.md.
//!
//! Each "version N" (or "versions N to M", with or without backticks) is
//! read by its context: a "Changes from version N" names a section of
//! PROTOCOL.md's history, which must exist; one beside "text link" is the
//! text link's; inside PROTOCOL.md's "Changes" (the history) any version
//! up to the newest may be named; everywhere else a version is a claim
//! about today's daemon and must be one it serves (PROTOCOL.md may also
//! name the older versions it refuses).

use std::path::{Path, PathBuf};

use weldseam_proto::text::TEXT_PROTOCOL_VERSION;
use weldseam_proto::{OLDEST_SERVED_VERSION, PROTOCOL_VERSION};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the workspace root").to_path_buf()
}

/// The documents, each with its whitespace runs collapsed to one space.
fn documents() -> Vec<(String, String)> {
    let mut paths = vec![root().join("README.md"), root().join("proto/PROTOCOL.md"), root().join("proto/ROBOTS.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    paths.extend(docs);
    paths
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let name = p.strip_prefix(root()).unwrap().display().to_string();
            (name, text.split_whitespace().collect::<Vec<_>>().join(" "))
        })
        .collect()
}

/// A mention of one or more version numbers: where it is, the text
/// before it, and the numbers ("versions 1 to 6" gives 1 and 6).
struct Mention {
    at: usize,
    before: String,
    after: String,
    numbers: Vec<u32>,
}

fn number_at(text: &str) -> Option<(u32, usize)> {
    let skipped = text.len() - text.trim_start_matches([' ', '`']).len();
    let digits: String = text[skipped..].chars().take_while(|c| c.is_ascii_digit()).collect();
    Some((digits.parse().ok()?, skipped + digits.len()))
}

fn mentions(text: &str) -> Vec<Mention> {
    let lower = text.to_lowercase();
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(i) = lower[from..].find("version") {
        let at = from + i;
        from = at + "version".len();
        let mut rest = &lower[from..];
        rest = rest.strip_prefix('s').unwrap_or(rest);
        let Some((first, used)) = number_at(rest) else { continue };
        let mut numbers = vec![first];
        let tail = rest[used..].trim_start_matches('`');
        for joiner in [" to ", " and ", " or "] {
            if let Some(more) = tail.strip_prefix(joiner)
                && let Some((n, _)) = number_at(more)
            {
                numbers.push(n);
            }
        }
        let start = lower[..at].char_indices().rev().nth(39).map_or(0, |(k, _)| k);
        let end = lower[from..].char_indices().nth(40).map_or(lower.len(), |(k, _)| from + k);
        found.push(Mention { at, before: lower[start..at].to_string(), after: lower[from..end].to_string(), numbers });
    }
    found
}

#[test]
fn every_version_the_documents_name_is_the_codes() {
    let (newest, oldest, text) = (u32::from(PROTOCOL_VERSION), u32::from(OLDEST_SERVED_VERSION), TEXT_PROTOCOL_VERSION);
    let documents = documents();
    let protocol = &documents.iter().find(|(n, _)| n == "proto/PROTOCOL.md").unwrap().1;
    let history_starts = protocol.find("## Changes ").expect("PROTOCOL.md has its history under \"## Changes\"");
    let mut wrong = Vec::new();
    let mut text_link_claims = 0;
    for (name, doc) in &documents {
        for m in mentions(doc) {
            let is_protocol_md = name == "proto/PROTOCOL.md";
            let mut bad = |why: String| wrong.push(format!("{name}: \"…{}version{}…\": {why}", m.before, m.after));
            if m.before.ends_with("changes from ") {
                let n = m.numbers[0];
                if n >= newest || !protocol.contains(&format!("### Changes from version {n} ")) {
                    bad(format!("PROTOCOL.md has no section \"Changes from version {n}\""));
                }
            } else if m.before.contains("text link") || m.before.contains("text protocol") {
                text_link_claims += 1;
                if m.numbers != [text] {
                    bad(format!("the text link's version is {text}"));
                }
            } else if is_protocol_md && m.at > history_starts {
                if m.numbers.iter().any(|&n| n == 0 || n > newest) {
                    bad(format!("the newest version is {newest}"));
                }
            } else if is_protocol_md {
                // Today's protocol: versions served, or the older ones it refuses.
                if m.numbers.iter().any(|&n| n == 0 || n > newest) {
                    bad(format!("this daemon speaks versions {oldest} to {newest}"));
                }
            } else if m.numbers.iter().any(|&n| n < oldest || n > newest) {
                bad(format!("this daemon speaks versions {oldest} to {newest}"));
            }
        }
    }
    // The text link's version, as ROBOTS.md's HELLO row states it
    // ("ok `0,N,0` (N: the text link's version)").
    let robots = &documents.iter().find(|(n, _)| n == "proto/ROBOTS.md").unwrap().1;
    for (k, _) in robots.match_indices(": the text link's version") {
        text_link_claims += 1;
        let digits: String = robots[..k]
            .chars()
            .rev()
            .take_while(|c| c.is_ascii_digit())
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        if digits.parse::<u32>().ok() != Some(text) {
            wrong.push(format!("proto/ROBOTS.md: the text link's version is {text}, not {digits:?}"));
        }
    }
    assert!(text_link_claims > 0, "ROBOTS.md states the text link's version");
    let readme = &documents.iter().find(|(n, _)| n == "README.md").unwrap().1;
    if !readme.contains(&format!("protocol version {newest}")) {
        wrong.push(format!("README.md does not say \"protocol version {newest}\""));
    }
    assert!(wrong.is_empty(), "versions that disagree with the code:\n{}", wrong.join("\n"));
}

#[test]
fn protocol_md_states_the_versions_where_an_integrator_reads_them() {
    let doc = include_str!("../PROTOCOL.md");
    let (newest, oldest) = (PROTOCOL_VERSION, OLDEST_SERVED_VERSION);
    assert!(doc.starts_with(&format!("# The weldseam wire protocol, version {newest}\n")));
    let served = format!("This daemon speaks version {newest} and serves peers of version {oldest} and later");
    assert!(doc.contains(&served), "PROTOCOL.md does not say {served:?}");
    // The header table's version cell, and the Hello's and HelloAck's
    // protocol_version rows, name the newest version.
    let row = |start: &str| doc.lines().filter(|l| l.starts_with(start)).map(str::to_string).collect::<Vec<_>>();
    let cells = [row("| 4 | 2 | version |"), row("| protocol_version | `u16` |")].concat();
    assert_eq!(cells.len(), 3, "the header's version row and two protocol_version rows");
    for cell in cells {
        assert!(cell.contains(&format!("`{newest}`")), "{cell}");
        for n in 1..newest {
            assert!(n >= oldest || !cell.contains(&format!("`{n}`")), "a version no longer served: {cell}");
        }
    }
}
