//! PLY files: ascii, binary little and big endian.

use std::path::Path;

use super::{LoadError, PointCloud};

/// Parses a PLY file's bytes; `path` is only used in error messages.
pub fn parse(_bytes: &[u8], path: &Path) -> Result<PointCloud, LoadError> {
    Err(LoadError::UnknownFormat { path: path.to_path_buf() })
}
