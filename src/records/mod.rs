//! Plan records: for every plan the daemon answers, the frame as
//! received, the request, the configuration (its hash, and its file when
//! the daemon was started from one) and the plan or the refusal, so that a
//! plan can be listed, exported and planned again (`weldseam records`,
//! `weldseam replay`).
//!
//! The store is one directory of files `<sequence>-r<request id>.wsrec`
//! (the file's stem is the record's id), bounded by `records.max_bytes`
//! and `records.max_age_days`: after each write the oldest records go
//! until both hold. Only files named so are ever counted or deleted. A
//! failed write (a full disk) is logged and counted by the daemon; it
//! never fails a plan. This module does file I/O and the format
//! ([`format`](mod@format)); the daemon's writer is `src/server/recorder.rs`.

pub mod compare;
pub mod format;
pub mod replay;

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, SystemTime};

pub use format::{FORMAT_VERSION, FormatError, Outcome, Record};

/// The extension of a record file.
pub const EXTENSION: &str = "wsrec";

/// Why the store could not do something.
#[derive(Debug, thiserror::Error)]
pub enum RecordsError {
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: {source}", path.display())]
    Format {
        path: PathBuf,
        #[source]
        source: FormatError,
    },
    #[error("no record {id} in {}", dir.display())]
    NotFound { id: String, dir: PathBuf },
}

fn io(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> RecordsError {
    let path = path.to_path_buf();
    move |source| RecordsError::Io { action, path, source }
}

/// One record file of the store.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// The file's stem: `<sequence>-r<request id>`.
    pub id: String,
    pub sequence: u64,
    pub path: PathBuf,
    pub bytes: u64,
    pub modified: SystemTime,
}

/// The store's limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    pub max_bytes: u64,
    pub max_age: Duration,
}

/// What the store holds now.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Held {
    pub count: u64,
    pub bytes: u64,
    pub max_bytes: u64,
}

/// A directory of plan records.
#[derive(Debug)]
pub struct Store {
    dir: PathBuf,
    limits: Limits,
    /// The records held, oldest first, and the next sequence number.
    state: Mutex<(Vec<Entry>, u64)>,
}

/// The records in `dir`, oldest first (by sequence number).
pub fn list(dir: &Path) -> Result<Vec<Entry>, RecordsError> {
    let mut entries = Vec::new();
    for item in std::fs::read_dir(dir).map_err(io("read the directory", dir))? {
        let item = item.map_err(io("read the directory", dir))?;
        let path = item.path();
        let Some(id) = record_id(&path) else { continue };
        let Some(sequence) = id.split('-').next().and_then(|s| s.parse().ok()) else { continue };
        let Ok(meta) = item.metadata() else { continue };
        entries.push(Entry {
            id,
            sequence,
            bytes: meta.len(),
            modified: meta.modified().unwrap_or(SystemTime::UNIX_EPOCH),
            path,
        });
    }
    entries.sort_by_key(|e| e.sequence);
    Ok(entries)
}

/// A record file's id: the stem of `<digits>-r<digits>.wsrec`.
fn record_id(path: &Path) -> Option<String> {
    if path.extension()? != EXTENSION {
        return None;
    }
    let stem = path.file_stem()?.to_str()?;
    let (sequence, request) = stem.split_once("-r")?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (digits(sequence) && digits(request)).then(|| stem.to_string())
}

/// Reads the record at `path`.
pub fn read(path: &Path) -> Result<Record, RecordsError> {
    let bytes = std::fs::read(path).map_err(io("read", path))?;
    Record::decode(&bytes).map_err(|source| RecordsError::Format { path: path.to_path_buf(), source })
}

/// The path of record `id` in `dir`.
pub fn find(dir: &Path, id: &str) -> Result<PathBuf, RecordsError> {
    list(dir)?
        .into_iter()
        .find(|e| e.id == id)
        .map(|e| e.path)
        .ok_or_else(|| RecordsError::NotFound { id: id.to_string(), dir: dir.to_path_buf() })
}

impl Store {
    /// Opens (creating it when needed) the store in `dir`.
    pub fn open(dir: &Path, limits: Limits) -> Result<Store, RecordsError> {
        std::fs::create_dir_all(dir).map_err(io("create the directory", dir))?;
        let entries = list(dir)?;
        let next = entries.last().map_or(1, |e| e.sequence + 1);
        let store = Store { dir: dir.to_path_buf(), limits, state: Mutex::new((entries, next)) };
        store.prune(SystemTime::now())?;
        Ok(store)
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, (Vec<Entry>, u64)> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Takes the next record's id for request `request_id`.
    pub fn next_id(&self, request_id: u64) -> (u64, String) {
        let mut state = self.lock();
        let sequence = state.1;
        state.1 += 1;
        (sequence, format!("{sequence:010}-r{request_id}"))
    }

    /// Writes `bytes` as record `id` (from [`Store::next_id`]), then drops
    /// the oldest records beyond the limits. The file is written under a
    /// temporary name and renamed, so a failed write leaves no record.
    pub fn save(&self, sequence: u64, id: &str, bytes: &[u8]) -> Result<(), RecordsError> {
        let path = self.dir.join(format!("{id}.{EXTENSION}"));
        let partial = self.dir.join(format!(".{id}.partial"));
        let written = std::fs::write(&partial, bytes)
            .map_err(io("write", &partial))
            .and_then(|()| std::fs::rename(&partial, &path).map_err(io("rename", &partial)));
        if let Err(e) = written {
            let _ = std::fs::remove_file(&partial);
            return Err(e);
        }
        let entry =
            Entry { id: id.to_string(), sequence, path, bytes: bytes.len() as u64, modified: SystemTime::now() };
        {
            let mut state = self.lock();
            let at = state.0.partition_point(|e| e.sequence < sequence);
            state.0.insert(at, entry);
        }
        self.prune(SystemTime::now())
    }

    /// Drops the oldest records while the store is over its size or holds
    /// records older than its age limit.
    fn prune(&self, now: SystemTime) -> Result<(), RecordsError> {
        let mut state = self.lock();
        let entries = &mut state.0;
        let mut total: u64 = entries.iter().map(|e| e.bytes).sum();
        let mut first_error = None;
        while let Some(oldest) = entries.first() {
            let too_old = now.duration_since(oldest.modified).is_ok_and(|age| age > self.limits.max_age);
            if total <= self.limits.max_bytes && !too_old {
                break;
            }
            let oldest = entries.remove(0);
            total -= oldest.bytes;
            if let Err(e) = std::fs::remove_file(&oldest.path)
                && e.kind() != std::io::ErrorKind::NotFound
            {
                first_error.get_or_insert(RecordsError::Io { action: "remove", path: oldest.path, source: e });
            }
        }
        first_error.map_or(Ok(()), Err)
    }

    /// What the store holds now.
    pub fn held(&self) -> Held {
        let state = self.lock();
        Held {
            count: state.0.len() as u64,
            bytes: state.0.iter().map(|e| e.bytes).sum(),
            max_bytes: self.limits.max_bytes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_oldest_records_go_first_and_other_files_are_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("notes.txt"), b"keep").unwrap();
        let limits = Limits { max_bytes: 250, max_age: Duration::from_secs(3600) };
        let store = Store::open(dir.path(), limits).unwrap();
        for request in 1..=4 {
            let (sequence, id) = store.next_id(request);
            store.save(sequence, &id, &[0u8; 100]).unwrap();
        }
        let ids: Vec<String> = list(dir.path()).unwrap().into_iter().map(|e| e.id).collect();
        assert_eq!(ids, vec!["0000000003-r3", "0000000004-r4"]);
        assert_eq!(store.held(), Held { count: 2, bytes: 200, max_bytes: 250 });
        assert!(dir.path().join("notes.txt").exists());
        // A reopened store goes on numbering after the newest record.
        let again = Store::open(dir.path(), limits).unwrap();
        assert_eq!(again.next_id(9).1, "0000000005-r9");
    }

    #[test]
    fn records_past_their_age_are_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path(), Limits { max_bytes: 1 << 20, max_age: Duration::from_secs(60) }).unwrap();
        let (sequence, id) = store.next_id(1);
        store.save(sequence, &id, b"x").unwrap();
        store.prune(SystemTime::now() + Duration::from_secs(61)).unwrap();
        assert_eq!(store.held().count, 0);
        assert!(list(dir.path()).unwrap().is_empty());
    }

    #[test]
    fn a_write_that_fails_leaves_no_record_and_says_where() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path(), Limits { max_bytes: 1 << 20, max_age: Duration::from_secs(60) }).unwrap();
        std::fs::remove_dir_all(dir.path()).unwrap();
        let (sequence, id) = store.next_id(1);
        let error = store.save(sequence, &id, b"x").unwrap_err().to_string();
        assert!(error.starts_with("cannot write"), "{error}");
        assert_eq!(store.held().count, 0);
    }
}
