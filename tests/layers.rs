//! The library's top-level modules form layers, not circles: no module
//! reaches, through the others, back to itself, so each can be read (and
//! one day built) on top of the ones it names. The configuration holds
//! plain data the pipeline reads; the kernels depend on nothing in the
//! pipeline.
//!
//! The graph is read from the source: a module names another where its
//! code writes `crate::other` (in a `use` or a path, `use crate::{a, b}`
//! included) or climbs there with `super::`. Comments and string literals
//! are not code. Code under `#[cfg(test)]` is left out of the circle
//! check, as a crate's dev-dependencies are: a module's own tests may
//! build their input with a module above it (a simulated frame).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// `text` with comments and the contents of string and character
/// literals blanked, so that what remains is code. Lines are kept.
fn code_only(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
        } else if c == 'r' && matches!(next, Some('"') | Some('#')) && !is_ident(chars.get(i.wrapping_sub(1))) {
            // A raw string: r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            out.push_str("\"\"");
            j += 1;
            while j < chars.len() {
                if chars[j] == '"' && (0..hashes).all(|h| chars.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                out.push(blank(chars[j]));
                j += 1;
            }
            i = j;
        } else if c == '"' {
            out.push_str("\"\"");
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                if i < chars.len() {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
            i += 1;
        } else if c == '\'' && (next == Some('\\') || chars.get(i + 2) == Some(&'\'')) {
            // A character literal ('x', '\n', '\''); a lifetime has no
            // closing quote.
            let mut j = i + 1;
            if chars.get(j) == Some(&'\\') {
                j += 2;
            }
            while j < chars.len() && chars[j] != '\'' {
                j += 1;
            }
            out.push_str("' '");
            i = j + 1;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn is_ident(c: Option<&char>) -> bool {
    c.is_some_and(|c| c.is_alphanumeric() || *c == '_' || *c == '$')
}

/// The end (exclusive) of the item that starts at `from` in `code`: its
/// `;` or its block's closing brace, whichever comes first at depth 0.
fn item_end(code: &[u8], from: usize) -> usize {
    let mut depth = 0usize;
    let mut k = from;
    while k < code.len() {
        match code[k] {
            b'{' => depth += 1,
            // The attribute was on a field or an arm: it ends where its
            // enclosing block does.
            b'}' if depth == 0 => return k,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            b';' if depth == 0 => return k + 1,
            _ => {}
        }
        k += 1;
    }
    code.len()
}

/// What a file holds outside `#[cfg(test)]`: its code with every item
/// under that attribute blanked, and the names of the child modules it
/// declares in files of their own (`mod x;`), test-only ones apart.
struct Parsed {
    code: String,
    children: Vec<String>,
    test_children: Vec<String>,
}

fn parse(text: &str) -> (String, Parsed) {
    let all = code_only(text);
    let mut bytes = all.clone().into_bytes();
    let marker = "#[cfg(test)]";
    let mut test_children = Vec::new();
    let mut from = 0;
    while let Some(at) = all[from..].find(marker).map(|k| k + from) {
        let start = at + marker.len();
        let end = item_end(all.as_bytes(), start);
        if let Some(name) = declared_module(&all[start..end]) {
            test_children.push(name);
        }
        for b in &mut bytes[at..end] {
            if *b != b'\n' {
                *b = b' ';
            }
        }
        from = end;
    }
    let code = String::from_utf8(bytes).expect("blanking keeps UTF-8: only ASCII is replaced");
    let children = code.split(';').filter_map(declared_module).collect();
    (all, Parsed { code, children, test_children })
}

/// `x` where `item` ends in `[pub[(...)]] mod x;`, declaring a module in
/// a file of its own.
fn declared_module(item: &str) -> Option<String> {
    let item = item.trim_end();
    let item = item.strip_suffix(';').unwrap_or(item);
    let mut words = item.split_whitespace().rev();
    match (words.next(), words.next()) {
        (Some(name), Some("mod")) if name.chars().all(|c| c.is_alphanumeric() || c == '_') => Some(name.to_string()),
        _ => None,
    }
}

/// The file of child module `name` declared in `file`.
fn child_file(file: &Path, name: &str) -> PathBuf {
    let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
    let dir =
        if matches!(stem, "mod" | "lib") { file.parent().unwrap().to_path_buf() } else { file.with_extension("") };
    let flat = dir.join(format!("{name}.rs"));
    if flat.exists() { flat } else { dir.join(name).join("mod.rs") }
}

/// The top-level modules `code` names, from a file `depth` modules below
/// the crate root.
fn named_modules(code: &str, depth: usize) -> BTreeSet<String> {
    let mut named = BTreeSet::new();
    let bytes = code.as_bytes();
    let ident_at =
        |k: usize| -> String { code[k..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect() };
    for (at, _) in code.match_indices("crate::") {
        if at > 0 && is_ident(Some(&(bytes[at - 1] as char))) {
            continue;
        }
        let rest = code[at + "crate::".len()..].trim_start();
        if let Some(group) = rest.strip_prefix('{') {
            // `use crate::{a, b::c, d::{e, f}}`: the first name of each
            // entry at the group's own depth.
            let mut depth = 0;
            let mut entry_start = true;
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => entry_start = true,
                    c if entry_start && (c.is_alphanumeric() || c == '_') => {
                        named.insert(group[k..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect());
                        entry_start = false;
                    }
                    c if c.is_whitespace() => {}
                    _ => entry_start = false,
                }
            }
        } else {
            named.insert(ident_at(code.len() - rest.len()));
        }
    }
    // `super::` climbing out of the module to the crate root.
    for (at, _) in code.match_indices("super::") {
        if at > 0 && (is_ident(Some(&(bytes[at - 1] as char))) || code[..at].ends_with("super::")) {
            continue;
        }
        let mut k = at;
        let mut climbs = 0;
        while code[k..].starts_with("super::") {
            climbs += 1;
            k += "super::".len();
        }
        if climbs >= depth {
            named.insert(ident_at(k));
        }
    }
    named.retain(|n| !n.is_empty() && n != "self" && n != "super");
    named
}

/// Each top-level module of the library, the modules its code outside
/// `#[cfg(test)]` names, and for each one a file that names it.
fn module_graph() -> BTreeMap<String, BTreeMap<String, String>> {
    let root = src().join("lib.rs");
    let (_, lib) = parse(&std::fs::read_to_string(&root).unwrap());
    let mut graph = BTreeMap::new();
    for top in &lib.children {
        let mut edges: BTreeMap<String, String> = BTreeMap::new();
        let mut pending = vec![(child_file(&root, top), 1usize)];
        while let Some((file, depth)) = pending.pop() {
            let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            let (_, parsed) = parse(&text);
            for name in named_modules(&parsed.code, depth) {
                if &name != top && lib.children.contains(&name) {
                    edges.entry(name).or_insert_with(|| relative(&file));
                }
            }
            for child in &parsed.children {
                pending.push((child_file(&file, child), depth + 1));
            }
        }
        graph.insert(top.clone(), edges);
    }
    graph
}

fn relative(file: &Path) -> String {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    file.strip_prefix(manifest).unwrap_or(file).display().to_string()
}

/// A circle through `start` in `graph`, if there is one, as the modules
/// in order back to `start`.
fn circle_through(graph: &BTreeMap<String, BTreeMap<String, String>>, start: &str) -> Option<Vec<String>> {
    // Depth-first from `start`, keeping the path; the first edge back to
    // `start` closes a circle.
    fn walk(
        graph: &BTreeMap<String, BTreeMap<String, String>>,
        start: &str,
        path: &mut Vec<String>,
        seen: &mut BTreeSet<String>,
    ) -> bool {
        let here = path.last().unwrap().clone();
        for next in graph.get(&here).into_iter().flat_map(|e| e.keys()) {
            if next == start {
                return true;
            }
            if seen.insert(next.clone()) {
                path.push(next.clone());
                if walk(graph, start, path, seen) {
                    return true;
                }
                path.pop();
            }
        }
        false
    }
    let mut path = vec![start.to_string()];
    let mut seen = BTreeSet::from([start.to_string()]);
    walk(graph, start, &mut path, &mut seen).then_some(path)
}

#[test]
fn the_top_level_modules_name_each_other_without_a_circle() {
    let graph = module_graph();
    assert!(graph.len() > 10 && graph.contains_key("pipeline"), "the module tree was not read: {graph:?}");
    assert!(graph["pipeline"].contains_key("config"), "the graph misses the pipeline's use of the config");
    let mut circles = Vec::new();
    let mut reported = BTreeSet::new();
    for module in graph.keys() {
        if reported.contains(module) {
            continue;
        }
        if let Some(circle) = circle_through(&graph, module) {
            let steps: Vec<String> = circle
                .iter()
                .zip(circle.iter().cycle().skip(1))
                .map(|(from, to)| format!("{from} -> {to} ({})", graph[from][to]))
                .collect();
            reported.extend(circle);
            circles.push(steps.join(", "));
        }
    }
    assert!(circles.is_empty(), "import circles among the top-level modules:\n{}", circles.join("\n"));
}

#[test]
fn the_kernels_name_nothing_of_the_pipeline_not_even_in_their_tests() {
    let mut offenders = Vec::new();
    let mut files = vec![src().join("kernels")];
    while let Some(path) = files.pop() {
        if path.is_dir() {
            files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
        } else if path.extension().is_some_and(|e| e == "rs") {
            let (all_code, _) = parse(&std::fs::read_to_string(&path).unwrap());
            let depth = path.strip_prefix(src()).unwrap().components().count() - 1;
            let depth = if path.ends_with("mod.rs") { depth } else { depth + 1 };
            if named_modules(&all_code, depth).contains("pipeline") {
                offenders.push(relative(&path));
            }
        }
    }
    assert!(offenders.is_empty(), "kernel files naming the pipeline: {offenders:?}");
}

#[test]
fn the_reader_sees_code_not_comments_strings_or_tests() {
    let text = "use crate::{a, b::{c, d}, e::f};\n\
                // use crate::comment;\n\
                let s = \"crate::string\";\n\
                let t = r#\"crate::raw\"#;\n\
                let c = '{';\n\
                fn g<'a>(x: &'a str) { crate::h::i(x) }\n\
                #[cfg(test)]\n\
                mod tests { use crate::tested; fn k() { let _ = \"}\"; } }\n\
                #[cfg(test)]\n\
                mod helpers;\n\
                pub(crate) mod child;\n\
                use super::super::climbed;\n";
    let (_, parsed) = parse(text);
    let named: Vec<String> = named_modules(&parsed.code, 2).into_iter().collect();
    assert_eq!(named, ["a", "b", "climbed", "e", "h"]);
    assert_eq!(named_modules(&parsed.code, 3).len(), 4, "two climbs from three deep stay inside the crate's module");
    assert_eq!((parsed.children, parsed.test_children), (vec!["child".to_string()], vec!["helpers".to_string()]));
}
