//! PCD files (Point Cloud Library format): ascii and binary, organized and
//! unorganized.

use std::io::{self, Write};
use std::path::Path;

use super::{LoadError, PointCloud};

/// Parses a PCD file's bytes; `path` is only used in error messages.
pub fn parse(_bytes: &[u8], path: &Path) -> Result<PointCloud, LoadError> {
    Err(LoadError::UnknownFormat { path: path.to_path_buf() })
}

/// Writes `cloud` as a binary PCD (fields x y z, f32 little endian),
/// keeping its organization; invalid points are written as NaN.
pub fn write_binary<W: Write>(cloud: &PointCloud, mut out: W) -> io::Result<()> {
    write!(
        out,
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n\
         COUNT 1 1 1\nWIDTH {}\nHEIGHT {}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA binary\n",
        cloud.width(),
        cloud.height(),
        cloud.len()
    )?;
    let mut buf = Vec::with_capacity(cloud.len() * 12);
    for p in cloud.points() {
        for c in p {
            buf.extend_from_slice(&c.to_le_bytes());
        }
    }
    out.write_all(&buf)?;
    out.flush()
}
