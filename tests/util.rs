//! Helpers shared by the integration-test suites.

use std::path::PathBuf;

use tempfile::TempDir;

/// Writes `bytes` to a file named `name` in a fresh temporary directory.
/// The file lives as long as the returned directory guard.
pub fn write_temp(name: &str, bytes: &[u8]) -> (TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("create a temporary directory");
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect("write the temporary file");
    (dir, path)
}
