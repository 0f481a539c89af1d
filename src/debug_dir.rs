//! Writing plans' debug sets (pictures and figures, made by
//! [`crate::report`]) to disk: `weldseam plan --debug DIR` writes one set
//! into DIR, and the daemon keeps its last `debug.keep_last` plans' sets,
//! each in a directory of its own under `debug.dir`, the oldest deleted.
//! This module does file I/O and nothing else.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::report::DebugSet;

/// A debug set or its directory could not be written, read or removed.
#[derive(Debug, thiserror::Error)]
#[error("cannot {action} {}: {source}", path.display())]
pub struct DebugDirError {
    pub action: &'static str,
    pub path: PathBuf,
    #[source]
    pub source: std::io::Error,
}

fn io_error(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> DebugDirError {
    let path = path.to_path_buf();
    move |source| DebugDirError { action, path, source }
}

/// Writes `set`'s files into `dir`, creating it when needed; a file of
/// the same name is replaced.
pub fn write_set(dir: &Path, set: &DebugSet) -> Result<(), DebugDirError> {
    std::fs::create_dir_all(dir).map_err(io_error("create the directory", dir))?;
    for (name, bytes) in &set.files {
        let path = dir.join(name);
        std::fs::write(&path, bytes).map_err(io_error("write", &path))?;
    }
    Ok(())
}

/// The prefix of the daemon's set directories: `plan-<sequence>-<label>`.
/// Only directories named so are ever counted or deleted.
const SET_PREFIX: &str = "plan-";

/// The last plans' debug sets in one directory.
#[derive(Debug)]
pub struct DebugStore {
    dir: PathBuf,
    keep_last: usize,
    /// The next set's sequence number: one past the highest in the
    /// directory, so a restarted daemon neither overwrites nor miscounts.
    next: Mutex<u64>,
}

impl DebugStore {
    /// Opens (creating it when needed) the directory of the sets, keeping
    /// `keep_last` of them (at least one).
    pub fn open(dir: &Path, keep_last: usize) -> Result<DebugStore, DebugDirError> {
        std::fs::create_dir_all(dir).map_err(io_error("create the directory", dir))?;
        let next = sets(dir)?.last().map_or(1, |(sequence, _)| sequence + 1);
        Ok(DebugStore { dir: dir.to_path_buf(), keep_last: keep_last.max(1), next: Mutex::new(next) })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes `set` as the newest set, named with `label` (letters, digits,
    /// `-` and `_` kept, anything else dropped), then deletes the oldest
    /// sets beyond `keep_last`. Returns the set's directory.
    pub fn save(&self, label: &str, set: &DebugSet) -> Result<PathBuf, DebugDirError> {
        let sequence = {
            let mut next = self.next.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            let sequence = *next;
            *next += 1;
            sequence
        };
        let label: String = label.chars().filter(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_')).collect();
        let path = self.dir.join(format!("{SET_PREFIX}{sequence:08}-{label}"));
        write_set(&path, set)?;
        self.prune()?;
        Ok(path)
    }

    /// Deletes the oldest sets beyond `keep_last`.
    fn prune(&self) -> Result<(), DebugDirError> {
        let all = sets(&self.dir)?;
        let excess = all.len().saturating_sub(self.keep_last);
        for (_, path) in &all[..excess] {
            std::fs::remove_dir_all(path).map_err(io_error("delete the old debug set", path))?;
        }
        Ok(())
    }
}

/// The set directories in `dir`, oldest first.
fn sets(dir: &Path) -> Result<Vec<(u64, PathBuf)>, DebugDirError> {
    let entries = std::fs::read_dir(dir).map_err(io_error("list", dir))?;
    let mut found = Vec::new();
    for entry in entries {
        let entry = entry.map_err(io_error("list", dir))?;
        let name = entry.file_name();
        let sequence = name
            .to_str()
            .and_then(|n| n.strip_prefix(SET_PREFIX))
            .and_then(|rest| rest.split('-').next())
            .and_then(|digits| digits.parse::<u64>().ok());
        if let Some(sequence) = sequence
            && entry.file_type().is_ok_and(|t| t.is_dir())
        {
            found.push((sequence, entry.path()));
        }
    }
    found.sort();
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(text: &str) -> DebugSet {
        DebugSet { files: vec![("trace.json", text.as_bytes().to_vec())] }
    }

    #[test]
    fn the_store_keeps_the_newest_sets_across_restarts_and_nothing_else_is_touched() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("plan-notes")).unwrap();
        std::fs::write(dir.path().join("plan-00000001-file"), b"not a set").unwrap();
        let store = DebugStore::open(dir.path(), 2).unwrap();
        for k in 0..3 {
            store.save(&format!("r{k}/.."), &set(&k.to_string())).unwrap();
        }
        // A restarted daemon continues the numbering.
        let store = DebugStore::open(dir.path(), 2).unwrap();
        let newest = store.save("r3", &set("3")).unwrap();
        assert_eq!(newest.file_name().unwrap(), "plan-00000004-r3");
        let kept: Vec<String> = sets(dir.path())
            .unwrap()
            .iter()
            .map(|(_, p)| std::fs::read_to_string(p.join("trace.json")).unwrap())
            .collect();
        assert_eq!(kept, ["2", "3"]);
        assert!(dir.path().join("plan-notes").is_dir() && dir.path().join("plan-00000001-file").is_file());
    }

    #[test]
    fn a_directory_that_cannot_be_made_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a-file");
        std::fs::write(&file, b"x").unwrap();
        let e = write_set(&file.join("sub"), &set("{}")).unwrap_err().to_string();
        assert!(e.contains("cannot create the directory") && e.contains("a-file"), "{e}");
    }
}
