//! Writing PCD files: an x y z float cloud as ascii, binary or
//! binary_compressed data, organized or not.

use super::*;

/// The header of an x y z float PCD of `cloud`'s shape, with `data` as
/// its DATA kind.
fn write_header<W: Write>(cloud: &PointCloud, data: &str, out: &mut W) -> io::Result<()> {
    write!(
        out,
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n\
         COUNT 1 1 1\nWIDTH {}\nHEIGHT {}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {data}\n",
        cloud.width(),
        cloud.height(),
        cloud.len()
    )
}

/// Writes `cloud` as an ascii PCD (fields x y z), keeping its organization;
/// invalid points are written as `NaN`.
pub fn write_ascii<W: Write>(cloud: &PointCloud, mut out: W) -> io::Result<()> {
    write_header(cloud, "ascii", &mut out)?;
    for [x, y, z] in cloud.points() {
        // Display prints the shortest text that reads back to the same f32.
        writeln!(out, "{x} {y} {z}")?;
    }
    out.flush()
}

/// Writes `cloud` as a binary PCD (fields x y z, f32 little endian),
/// keeping its organization; invalid points are written as NaN.
pub fn write_binary<W: Write>(cloud: &PointCloud, mut out: W) -> io::Result<()> {
    write_header(cloud, "binary", &mut out)?;
    let mut buf = Vec::with_capacity(cloud.len() * 12);
    for p in cloud.points() {
        for c in p {
            buf.extend_from_slice(&c.to_le_bytes());
        }
    }
    out.write_all(&buf)?;
    out.flush()
}

/// Writes `cloud` as PCL writes `DATA binary_compressed` (fields x y z,
/// f32 little endian), keeping its organization; invalid points are
/// written as NaN.
pub fn write_binary_compressed<W: Write>(cloud: &PointCloud, mut out: W) -> io::Result<()> {
    write_header(cloud, "binary_compressed", &mut out)?;
    // All x, then all y, then all z: similar values side by side compress
    // better, which is why PCL lays the fields out so.
    let mut planar = Vec::with_capacity(cloud.len() * 12);
    for axis in 0..3 {
        for p in cloud.points() {
            planar.extend_from_slice(&p[axis].to_le_bytes());
        }
    }
    let mut compressed = vec![0; lzf_rust::max_compressed_size(planar.len())];
    let written = if planar.is_empty() {
        0
    } else {
        lzf_rust::compress(&planar, &mut compressed)
            .map_err(|err| io::Error::other(format!("LZF compression failed: {err}")))?
    };
    let size = |n: usize| {
        u32::try_from(n).map_err(|_| {
            io::Error::new(io::ErrorKind::InvalidInput, "cloud too large for binary_compressed (over 4 GiB of data)")
        })
    };
    out.write_all(&size(written)?.to_le_bytes())?;
    out.write_all(&size(planar.len())?.to_le_bytes())?;
    out.write_all(compressed.get(..written).unwrap_or_default())?;
    out.flush()
}
