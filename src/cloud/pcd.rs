//! PCD files (Point Cloud Library format, v0.5 to v0.7): ascii, binary and
//! binary_compressed data, organized and unorganized, with any extra fields
//! beside x, y, z.
//!
//! `binary_compressed` is laid out as PCL's writer lays it out: after the
//! DATA line, the compressed and the uncompressed size (u32, little
//! endian), then one LZF stream whose uncompressed bytes hold the fields
//! one after another (every point's first field, then every point's
//! second...), padding fields named `_` left out.

use std::io::{self, Write};
use std::path::Path;

use super::reader::{
    Endian, Lines, MAX_POINTS, Scalar, data_error, decode_packed_xyz_f32_le, header_error, parse_coordinate, quoted,
};
use super::{INVALID_POINT, LoadError, Point, PointCloud};

const VERSIONS: [&str; 6] = ["0.5", ".5", "0.6", ".6", "0.7", ".7"];

const KEYWORDS: &str = "VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS or DATA";

/// Parses a PCD file's bytes; `path` is only used in error messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<PointCloud, LoadError> {
    let mut lines = Lines::new(bytes);
    let header = read_header(&mut lines, path)?;
    let points = match header.data {
        DataKind::Binary => decode_binary(lines.rest(), &header, path)?,
        DataKind::BinaryCompressed => decode_compressed(lines.rest(), &header, path)?,
        DataKind::Ascii => decode_ascii(&mut lines, &header, path)?,
    };
    if header.height > 1 {
        PointCloud::organized(header.width, header.height, points)
            .ok_or_else(|| data_error(path, "end of data", "point count does not match WIDTH x HEIGHT"))
    } else {
        Ok(PointCloud::unorganized(points))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DataKind {
    Ascii,
    Binary,
    BinaryCompressed,
}

/// Where one coordinate sits in a point record: by byte for binary data,
/// by value (token) for ascii data.
#[derive(Clone, Copy, Debug)]
struct Coordinate {
    byte_offset: usize,
    value_index: usize,
    scalar: Scalar,
}

/// A validated header: everything the data section is decoded against.
#[derive(Debug)]
struct Header {
    xyz: [Coordinate; 3],
    /// Where x, y and z sit in a compressed file's field-by-field record:
    /// the bytes of the fields before each, padding fields left out.
    planes: [Coordinate; 3],
    point_bytes: usize,
    /// The bytes one point takes in compressed data: `point_bytes` less
    /// the padding fields, which PCL leaves out there.
    compressed_point_bytes: usize,
    values_per_point: usize,
    width: usize,
    height: usize,
    points: usize,
    data: DataKind,
}

impl Header {
    /// True for the camera layout `x y z` as three contiguous f32, which
    /// the fast decoder handles.
    fn is_packed_xyz_f32(&self) -> bool {
        self.point_bytes == 12
            && self.xyz.iter().zip([0, 4, 8]).all(|(c, offset)| c.scalar == Scalar::F32 && c.byte_offset == offset)
    }
}

/// A header value with the line it came from, so validation errors that
/// only show up once the whole header is read can point back at it.
#[derive(Debug)]
struct At<T> {
    line: usize,
    value: T,
}

/// The header as written, each keyword checked on its own line.
#[derive(Debug, Default)]
struct RawHeader {
    fields: Option<At<Vec<String>>>,
    sizes: Option<At<Vec<usize>>>,
    types: Option<At<Vec<char>>>,
    counts: Option<At<Vec<usize>>>,
    width: Option<At<usize>>,
    height: Option<At<usize>>,
    points: Option<At<usize>>,
}

fn read_header(lines: &mut Lines<'_>, path: &Path) -> Result<Header, LoadError> {
    let mut raw = RawHeader::default();
    loop {
        let Some((line, bytes)) = lines.next_line() else {
            let message = if lines.line_number() == 0 {
                "file is empty: expected a PCD header"
            } else {
                "file ends before the DATA line that closes the header"
            };
            return Err(header_error(path, lines.line_number() + 1, message));
        };
        let text = std::str::from_utf8(bytes)
            .map_err(|_| header_error(path, line, "not text: expected a PCD header line"))?
            .trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let mut words = text.split_ascii_whitespace();
        let key = words.next().unwrap_or_default();
        let values: Vec<&str> = words.collect();
        if key == "DATA" {
            let data = data_kind(&values).map_err(|m| header_error(path, line, m))?;
            return raw.validate(data, line, path);
        }
        raw.record(key, &values, line).map_err(|m| header_error(path, line, m))?;
    }
}

fn data_kind(values: &[&str]) -> Result<DataKind, String> {
    match values {
        ["ascii"] => Ok(DataKind::Ascii),
        ["binary"] => Ok(DataKind::Binary),
        ["binary_compressed"] => Ok(DataKind::BinaryCompressed),
        [other] => Err(format!("unknown DATA kind {} (expected ascii, binary or binary_compressed)", quoted(other))),
        _ => Err("DATA takes exactly one value: ascii, binary or binary_compressed".into()),
    }
}

impl RawHeader {
    fn record(&mut self, key: &str, values: &[&str], line: usize) -> Result<(), String> {
        match key {
            "VERSION" => check_version(values),
            "VIEWPOINT" => check_viewpoint(values),
            "FIELDS" => set(&mut self.fields, key, line, field_names(values)?),
            "SIZE" => set(&mut self.sizes, key, line, numbers(key, values)?),
            "TYPE" => set(&mut self.types, key, line, type_codes(values)?),
            "COUNT" => set(&mut self.counts, key, line, numbers(key, values)?),
            "WIDTH" => set(&mut self.width, key, line, single_number(key, values)?),
            "HEIGHT" => set(&mut self.height, key, line, single_number(key, values)?),
            "POINTS" => set(&mut self.points, key, line, single_number(key, values)?),
            other => Err(format!("unknown header keyword {} (expected {KEYWORDS})", quoted(other))),
        }
    }

    fn validate(self, data: DataKind, data_line: usize, path: &Path) -> Result<Header, LoadError> {
        let missing = |key: &str| header_error(path, data_line, format!("no {key} line before DATA"));
        let names = self.fields.as_ref().ok_or_else(|| missing("FIELDS"))?;
        let sizes = self.sizes.as_ref().ok_or_else(|| missing("SIZE"))?;
        let types = self.types.as_ref().ok_or_else(|| missing("TYPE"))?;
        let field_count = names.value.len();
        let default_counts = At { line: data_line, value: vec![1; field_count] };
        let counts = self.counts.as_ref().unwrap_or(&default_counts);
        for (key, len, line) in [
            ("SIZE", sizes.value.len(), sizes.line),
            ("TYPE", types.value.len(), types.line),
            ("COUNT", counts.value.len(), counts.line),
        ] {
            if len != field_count {
                return Err(header_error(
                    path,
                    line,
                    format!("{key} lists {len} values but FIELDS lists {field_count}"),
                ));
            }
        }
        let scalars = field_scalars(&names.value, sizes, &types.value, path)?;
        let (width, height, points) = self.dimensions(data_line, path)?;
        let layout = Layout::new(&names.value, &scalars, &counts.value)
            .ok_or_else(|| header_error(path, sizes.line, "point record size overflows"))?;
        let xyz_lines = XyzLines { fields: names.line, types: types.line, counts: counts.line };
        let xyz = locate_xyz(&names.value, &layout.starts, &layout, xyz_lines, path)?;
        let planes = locate_xyz(&names.value, &layout.planes, &layout, xyz_lines, path)?;
        Ok(Header {
            xyz,
            planes,
            point_bytes: layout.point_bytes,
            compressed_point_bytes: layout.compressed_point_bytes,
            values_per_point: layout.values_per_point,
            width,
            height,
            points,
            data,
        })
    }

    /// WIDTH, HEIGHT and the point total, checked against POINTS and the
    /// size limit.
    fn dimensions(&self, data_line: usize, path: &Path) -> Result<(usize, usize, usize), LoadError> {
        let (width, width_line) = match (&self.width, &self.points) {
            (Some(width), _) => (width.value, width.line),
            // v0.5 files may carry only POINTS: a plain list of points.
            (None, Some(points)) => (points.value, points.line),
            (None, None) => {
                return Err(header_error(path, data_line, "no WIDTH line before DATA"));
            }
        };
        let height = self.height.as_ref().map_or(1, |h| h.value);
        if let Some(h) = &self.height
            && h.value == 0
        {
            return Err(header_error(path, h.line, "HEIGHT must be at least 1"));
        }
        let total = width.checked_mul(height).filter(|&total| total <= MAX_POINTS).ok_or_else(|| {
            header_error(
                path,
                width_line,
                format!("WIDTH {width} x HEIGHT {height} is more than the {MAX_POINTS} points a cloud may have"),
            )
        })?;
        if let Some(points) = &self.points
            && points.value != total
        {
            return Err(header_error(
                path,
                points.line,
                format!("POINTS is {} but WIDTH x HEIGHT is {width} x {height} = {total}", points.value),
            ));
        }
        Ok((width, height, total))
    }
}

fn set<T>(slot: &mut Option<At<T>>, key: &str, line: usize, value: T) -> Result<(), String> {
    if let Some(first) = slot {
        return Err(format!("{key} appears again (first on line {})", first.line));
    }
    *slot = Some(At { line, value });
    Ok(())
}

fn check_version(values: &[&str]) -> Result<(), String> {
    match values {
        [version] if VERSIONS.contains(version) => Ok(()),
        _ => Err(format!("unsupported VERSION {} (expected 0.5, 0.6 or 0.7)", quoted(&values.join(" ")))),
    }
}

/// The viewpoint is a sensor pose PCL records but the planner does not
/// use (clouds arrive in the camera frame); it is only checked for shape.
fn check_viewpoint(values: &[&str]) -> Result<(), String> {
    let numeric = values.iter().all(|v| v.parse::<f64>().is_ok());
    if values.len() == 7 && numeric { Ok(()) } else { Err("VIEWPOINT needs 7 numbers: tx ty tz qw qx qy qz".into()) }
}

fn field_names(values: &[&str]) -> Result<Vec<String>, String> {
    if values.is_empty() {
        return Err("FIELDS lists no fields".into());
    }
    Ok(values.iter().map(|v| v.to_string()).collect())
}

fn numbers(key: &str, values: &[&str]) -> Result<Vec<usize>, String> {
    values
        .iter()
        .map(|v| v.parse().map_err(|_| format!("{key} value {} is not a non-negative whole number", quoted(v))))
        .collect()
}

fn single_number(key: &str, values: &[&str]) -> Result<usize, String> {
    match numbers(key, values)?.as_slice() {
        [value] => Ok(*value),
        _ => Err(format!("{key} takes exactly one value")),
    }
}

fn type_codes(values: &[&str]) -> Result<Vec<char>, String> {
    values
        .iter()
        .map(|v| match *v {
            "I" => Ok('I'),
            "U" => Ok('U'),
            "F" => Ok('F'),
            other => Err(format!("unknown TYPE {} (expected I, U or F)", quoted(other))),
        })
        .collect()
}

fn field_scalars(
    names: &[String],
    sizes: &At<Vec<usize>>,
    types: &[char],
    path: &Path,
) -> Result<Vec<Scalar>, LoadError> {
    names
        .iter()
        .zip(&sizes.value)
        .zip(types)
        .map(|((name, &size), &code)| {
            scalar_for(code, size).ok_or_else(|| {
                header_error(
                    path,
                    sizes.line,
                    format!(
                        "field {} is TYPE {code} with SIZE {size}; F fields take 4 or 8 bytes, \
                         I and U fields 1, 2, 4 or 8",
                        quoted(name)
                    ),
                )
            })
        })
        .collect()
}

fn scalar_for(code: char, size: usize) -> Option<Scalar> {
    Some(match (code, size) {
        ('I', 1) => Scalar::I8,
        ('I', 2) => Scalar::I16,
        ('I', 4) => Scalar::I32,
        ('I', 8) => Scalar::I64,
        ('U', 1) => Scalar::U8,
        ('U', 2) => Scalar::U16,
        ('U', 4) => Scalar::U32,
        ('U', 8) => Scalar::U64,
        ('F', 4) => Scalar::F32,
        ('F', 8) => Scalar::F64,
        _ => return None,
    })
}

/// The name PCL gives padding fields; its compressed data leaves them out.
const PADDING_FIELD: &str = "_";

/// Where each field starts in a point record, with overflow-checked totals.
struct Layout {
    starts: Vec<Coordinate>,
    /// Each field's start in the compressed layout's per-point bytes
    /// (padding fields take none there).
    planes: Vec<Coordinate>,
    counts: Vec<usize>,
    point_bytes: usize,
    compressed_point_bytes: usize,
    values_per_point: usize,
}

impl Layout {
    fn new(names: &[String], scalars: &[Scalar], counts: &[usize]) -> Option<Self> {
        let mut layout = Layout {
            starts: Vec::with_capacity(names.len()),
            planes: Vec::with_capacity(names.len()),
            counts: counts.to_vec(),
            point_bytes: 0,
            compressed_point_bytes: 0,
            values_per_point: 0,
        };
        for ((name, &scalar), &count) in names.iter().zip(scalars).zip(counts) {
            layout.starts.push(Coordinate {
                byte_offset: layout.point_bytes,
                value_index: layout.values_per_point,
                scalar,
            });
            layout.planes.push(Coordinate {
                byte_offset: layout.compressed_point_bytes,
                value_index: layout.values_per_point,
                scalar,
            });
            let bytes = scalar.size().checked_mul(count)?;
            layout.point_bytes = layout.point_bytes.checked_add(bytes)?;
            if name != PADDING_FIELD {
                layout.compressed_point_bytes = layout.compressed_point_bytes.checked_add(bytes)?;
            }
            layout.values_per_point = layout.values_per_point.checked_add(count)?;
        }
        Some(layout)
    }
}

/// The header lines an error about x, y or z points at.
#[derive(Clone, Copy)]
struct XyzLines {
    fields: usize,
    types: usize,
    counts: usize,
}

/// x, y and z among `starts` (one per field), checked to be single floats.
fn locate_xyz(
    names: &[String],
    starts: &[Coordinate],
    layout: &Layout,
    lines: XyzLines,
    path: &Path,
) -> Result<[Coordinate; 3], LoadError> {
    let locate = |axis: &str| {
        let index = names.iter().position(|n| n == axis).ok_or_else(|| {
            header_error(path, lines.fields, format!("no {axis:?} field: FIELDS must include x, y and z"))
        })?;
        let requirement = format!("field {axis:?} must be TYPE F with SIZE 4 or 8 and COUNT 1");
        let start = starts.get(index).copied().filter(|c| c.scalar.is_float());
        let start = start.ok_or_else(|| header_error(path, lines.types, requirement.clone()))?;
        match layout.counts.get(index).copied().unwrap_or(0) {
            1 => Ok(start),
            count => Err(header_error(path, lines.counts, format!("{requirement}, not COUNT {count}"))),
        }
    };
    Ok([locate("x")?, locate("y")?, locate("z")?])
}

fn decode_binary(body: &[u8], header: &Header, path: &Path) -> Result<Vec<Point>, LoadError> {
    // Cannot overflow: the point total is capped and the record size is a
    // checked sum, but a corrupt header must still not panic.
    let expected = header
        .points
        .checked_mul(header.point_bytes)
        .ok_or_else(|| data_error(path, "point 0 (byte 0)", "data size overflows"))?;
    let Some(data) = body.get(..expected) else {
        let found = body.len();
        let point = found.checked_div(header.point_bytes).unwrap_or(0);
        return Err(data_error(
            path,
            format!("point {point} (byte {found})"),
            format!("file ends early: expected {expected} bytes of binary data after the header, found {found}"),
        ));
    };
    if header.is_packed_xyz_f32() {
        return Ok(decode_packed_xyz_f32_le(data));
    }
    // A record holds at least x, y and z, so it is never empty; max(1)
    // only keeps chunks_exact from panicking should that ever change.
    Ok(data
        .chunks_exact(header.point_bytes.max(1))
        .map(|record| header.xyz.map(|c| c.scalar.read_coordinate(record, c.byte_offset, Endian::Little)))
        .collect())
}

/// LZF output is at most this many times its input (a three-byte back
/// reference copies at most 264 bytes), so a declared size beyond it is
/// refused before anything is allocated for it.
const LZF_MAX_EXPANSION: usize = 88;

/// The compressed and the uncompressed size before the LZF stream.
const COMPRESSED_SIZES_BYTES: usize = 8;

/// Decodes `DATA binary_compressed`: two sizes, then one LZF stream of
/// the fields laid out one after another.
fn decode_compressed(body: &[u8], header: &Header, path: &Path) -> Result<Vec<Point>, LoadError> {
    let Some((sizes, rest)) = body.split_first_chunk::<COMPRESSED_SIZES_BYTES>() else {
        return Err(data_error(
            path,
            "compressed sizes (byte 0)",
            format!(
                "file ends early: expected the {COMPRESSED_SIZES_BYTES} bytes of compressed and uncompressed \
                 size after the header, found {}",
                body.len()
            ),
        ));
    };
    let [c0, c1, c2, c3, u0, u1, u2, u3] = *sizes;
    let compressed = u32::from_le_bytes([c0, c1, c2, c3]) as usize;
    let uncompressed = u32::from_le_bytes([u0, u1, u2, u3]) as usize;
    let location = "compressed data (byte 8)";
    // Cannot overflow: the point total is capped and the record size is a
    // checked sum, but a corrupt header must still not panic.
    let expected = header.points.checked_mul(header.compressed_point_bytes);
    if expected != Some(uncompressed) {
        return Err(data_error(
            path,
            "compressed sizes (byte 4)",
            format!(
                "uncompressed size {uncompressed} is not POINTS {} x {} bytes per point",
                header.points, header.compressed_point_bytes
            ),
        ));
    }
    let Some(stream) = rest.get(..compressed) else {
        return Err(data_error(
            path,
            location,
            format!("file ends early: expected {compressed} bytes of compressed data, found {}", rest.len()),
        ));
    };
    if uncompressed > compressed.saturating_mul(LZF_MAX_EXPANSION) {
        return Err(data_error(
            path,
            location,
            format!(
                "{compressed} bytes of LZF data cannot hold the {uncompressed} bytes declared \
                 (LZF expands at most {LZF_MAX_EXPANSION} times)"
            ),
        ));
    }
    if uncompressed == 0 {
        return Ok(Vec::new());
    }
    let mut data = vec![0; uncompressed];
    match lzf_rust::decompress(stream, &mut data) {
        Ok(written) if written == uncompressed => {}
        Ok(written) => {
            return Err(data_error(
                path,
                location,
                format!("LZF data decompresses to {written} bytes, not the {uncompressed} declared"),
            ));
        }
        Err(err) => return Err(data_error(path, location, format!("corrupt LZF data: {err}"))),
    }
    // Each coordinate's values follow one another from its field's start,
    // which lies `points` records' worth of earlier fields into the data.
    let columns = header.planes.map(|c| (c.byte_offset * header.points, c.scalar));
    Ok((0..header.points)
        .map(|i| {
            columns.map(|(start, scalar)| scalar.read_coordinate(&data, start + i * scalar.size(), Endian::Little))
        })
        .collect())
}

fn decode_ascii(lines: &mut Lines<'_>, header: &Header, path: &Path) -> Result<Vec<Point>, LoadError> {
    // The header's count is untrusted; every point takes at least six bytes
    // ("1 2 3\n"), so the remaining size bounds the allocation.
    let mut points = Vec::with_capacity(header.points.min(lines.rest().len() / 6));
    while points.len() < header.points {
        let index = points.len();
        let Some((line, bytes)) = lines.next_line() else {
            return Err(data_error(
                path,
                format!("point {index} (line {})", lines.line_number() + 1),
                format!("file ends early: expected {} points, found {index}", header.points),
            ));
        };
        let location = || format!("point {index} (line {line})");
        let text =
            std::str::from_utf8(bytes).map_err(|_| data_error(path, location(), "not text: expected ascii values"))?;
        if text.trim().is_empty() {
            continue;
        }
        let point = parse_ascii_point(text, header).map_err(|m| data_error(path, location(), m))?;
        points.push(point);
    }
    Ok(points)
}

fn parse_ascii_point(text: &str, header: &Header) -> Result<Point, String> {
    let mut point = INVALID_POINT;
    let mut found = 0;
    for (index, token) in text.split_ascii_whitespace().enumerate() {
        found += 1;
        for (axis, (coordinate, value)) in ["x", "y", "z"].into_iter().zip(header.xyz.iter().zip(point.iter_mut())) {
            if coordinate.value_index == index {
                *value = parse_coordinate(token)
                    .ok_or_else(|| format!("cannot read {} as a number for field {axis:?}", quoted(token)))?;
            }
        }
    }
    if found != header.values_per_point {
        return Err(format!("expected {} values on the line, found {found}", header.values_per_point));
    }
    Ok(point)
}

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

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> &'static Path {
        Path::new("scan.pcd")
    }

    /// A 10-line x y z header: WIDTH is on line 6, POINTS on 9, DATA on 10.
    fn xyz_header(width: usize, height: usize, data: &str) -> String {
        format!(
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {width}\n\
             HEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {data}\n",
            width * height
        )
    }

    fn le_f32(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// Point equality that treats NaN as equal to NaN.
    fn same_points(a: &[Point], b: &[Point]) -> bool {
        a.len() == b.len()
            && a.iter().zip(b).all(|(p, q)| p.iter().zip(q).all(|(u, v)| u == v || (u.is_nan() && v.is_nan())))
    }

    fn parse_str(text: &str) -> Result<PointCloud, LoadError> {
        parse(text.as_bytes(), path())
    }

    #[test]
    fn ascii_with_comments_before_and_inside_the_header() {
        let text = "# .PCD v0.7 - Point Cloud Data file format\n# from a test\nVERSION .7\n\
                    FIELDS x y z\n# sizes follow\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\n\
                    DATA ascii\n1 2 3\r\n4.5 -5 6e1\n\n7 8 9\n";
        let cloud = parse_str(text).unwrap();
        assert!(!cloud.is_organized());
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0], [4.5, -5.0, 60.0], [7.0, 8.0, 9.0]]);
    }

    #[test]
    fn ascii_nan_tokens_are_invalid_points() {
        let text = xyz_header(2, 2, "ascii") + "nan nan nan\n1 2 3\nNaN NaN NaN\n0 0 0\n";
        let cloud = parse_str(&text).unwrap();
        assert!(cloud.is_organized());
        assert_eq!(cloud.len(), 4);
        assert_eq!(cloud.valid_count(), 1);
        assert_eq!(cloud.at(1, 0), Some(&[1.0, 2.0, 3.0]));
    }

    #[test]
    fn binary_organized_keeps_the_grid_and_its_holes() {
        let values = [
            1.0,
            2.0,
            3.0,
            f32::NAN,
            f32::NAN,
            f32::NAN,
            0.0,
            0.0,
            0.0, //
            4.0,
            5.0,
            6.0,
            7.0,
            8.0,
            9.0,
            10.0,
            11.0,
            12.0,
        ];
        let mut bytes = xyz_header(3, 2, "binary").into_bytes();
        bytes.extend(le_f32(&values));
        let cloud = parse(&bytes, path()).unwrap();
        assert!(cloud.is_organized());
        assert_eq!((cloud.width(), cloud.height(), cloud.len()), (3, 2, 6));
        assert_eq!(cloud.valid_count(), 4);
        assert_eq!(cloud.at(1, 0), None);
        assert_eq!(cloud.at(2, 0), None, "0,0,0 is a missing return");
        assert_eq!(cloud.at(2, 1), Some(&[10.0, 11.0, 12.0]));
    }

    #[test]
    fn binary_unorganized_drops_invalid_points() {
        let mut bytes = xyz_header(3, 1, "binary").into_bytes();
        bytes.extend(le_f32(&[1.0, 2.0, 3.0, 0.0, 0.0, 0.0, f32::NAN, 1.0, 1.0]));
        let cloud = parse(&bytes, path()).unwrap();
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0]]);
    }

    const MIXED_HEADER: &str = "VERSION 0.7\nFIELDS intensity x y z normal rgb\n\
        SIZE 1 8 8 8 4 4\nTYPE U F F F F U\nCOUNT 1 1 1 1 3 1\nWIDTH 2\nHEIGHT 1\n\
        VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n";

    #[test]
    fn binary_extra_fields_and_doubles_are_skipped_and_narrowed() {
        let mut bytes = format!("{MIXED_HEADER}DATA binary\n").into_bytes();
        for (i, xyz) in [[1.25f64, -2.5, 1e3], [0.1, 0.2, 0.3]].iter().enumerate() {
            bytes.push(200 + i as u8);
            for c in xyz {
                bytes.extend(c.to_le_bytes());
            }
            bytes.extend(le_f32(&[9.0, 9.0, 9.0]));
            bytes.extend(0xdead_beef_u32.to_le_bytes());
        }
        let cloud = parse(&bytes, path()).unwrap();
        assert_eq!(cloud.points(), &[[1.25, -2.5, 1e3], [0.1f64 as f32, 0.2f64 as f32, 0.3f64 as f32]]);
    }

    #[test]
    fn ascii_extra_fields_with_counts_are_skipped() {
        let text = format!("{MIXED_HEADER}DATA ascii\n7 1 2 3 0 0 1 4278190080\n8 4 5 6 0 1 0 0\n");
        let cloud = parse_str(&text).unwrap();
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    #[test]
    fn padded_f32_layout_matches_the_packed_one() {
        let values = [1.0, 2.0, 3.0, -4.0, 5.5, 6.0];
        let mut packed = xyz_header(2, 1, "binary").into_bytes();
        packed.extend(le_f32(&values));
        let mut padded =
            "FIELDS x y z _\nSIZE 4 4 4 4\nTYPE F F F U\nWIDTH 2\nHEIGHT 1\nDATA binary\n".as_bytes().to_vec();
        for xyz in values.chunks(3) {
            padded.extend(le_f32(xyz));
            padded.extend([0xff; 4]);
        }
        assert_eq!(parse(&packed, path()).unwrap(), parse(&padded, path()).unwrap());
    }

    #[test]
    fn version_05_files_with_only_points_are_unorganized() {
        let text = "VERSION .5\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n";
        let cloud = parse_str(text).unwrap();
        assert_eq!(cloud.len(), 2);
        assert!(!cloud.is_organized());
    }

    #[test]
    fn trailing_bytes_after_the_data_are_ignored() {
        let mut bytes = xyz_header(1, 1, "binary").into_bytes();
        bytes.extend(le_f32(&[1.0, 2.0, 3.0]));
        bytes.extend(b"\n\n");
        assert_eq!(parse(&bytes, path()).unwrap().len(), 1);
    }

    fn sample_grid() -> PointCloud {
        let points = (0..12)
            .map(|i| match i {
                4 => INVALID_POINT,
                i => [i as f32 * 0.1, -(i as f32) / 3.0, 500.0 + i as f32],
            })
            .collect();
        PointCloud::organized(4, 3, points).unwrap()
    }

    #[test]
    fn binary_and_ascii_writers_round_trip() {
        let unorganized = PointCloud::unorganized(vec![[1.5, -2.0, 1e-7], [3.0, 4.0, 5.0]]);
        for cloud in [sample_grid(), unorganized] {
            let mut binary = Vec::new();
            write_binary(&cloud, &mut binary).unwrap();
            let mut ascii = Vec::new();
            write_ascii(&cloud, &mut ascii).unwrap();
            let mut compressed = Vec::new();
            write_binary_compressed(&cloud, &mut compressed).unwrap();
            for bytes in [binary, ascii, compressed] {
                let back = parse(&bytes, path()).unwrap();
                assert_eq!((back.width(), back.height()), (cloud.width(), cloud.height()));
                assert_eq!(back.is_organized(), cloud.is_organized());
                assert!(same_points(back.points(), cloud.points()));
            }
        }
    }

    /// The data section PCL's writer puts after `DATA binary_compressed`:
    /// the two sizes, then the LZF stream of `planar` (fields one after
    /// another), then the zeros PCL pads the file to a page with.
    fn pcl_compressed_body(planar: &[u8]) -> Vec<u8> {
        let mut stream = vec![0; lzf_rust::max_compressed_size(planar.len())];
        let written = lzf_rust::compress(planar, &mut stream).unwrap();
        stream.truncate(written);
        let mut body = Vec::new();
        body.extend((written as u32).to_le_bytes());
        body.extend((planar.len() as u32).to_le_bytes());
        body.extend(stream);
        body.extend([0; 37]);
        body
    }

    /// Fields of 1, 8, 4 and 4 bytes, a padding field PCL leaves out of
    /// compressed data and an unused rgb field, in PCL's layout.
    #[test]
    fn compressed_files_laid_out_as_pcl_writes_them() {
        let header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS intensity x y _ z rgb\n\
                      SIZE 1 8 4 4 4 4\nTYPE U F F U F U\nCOUNT 1 1 1 1 1 1\nWIDTH 3\nHEIGHT 1\n\
                      VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary_compressed\n";
        let xs = [1.5f64, -250.25, 0.0];
        let ys = [2.0f32, 7.5, f32::NAN];
        let zs = [500.0f32, 612.5, f32::NAN];
        let mut planar = vec![10u8, 20, 30];
        planar.extend(xs.iter().flat_map(|v| v.to_le_bytes()));
        planar.extend(ys.iter().flat_map(|v| v.to_le_bytes()));
        planar.extend(zs.iter().flat_map(|v| v.to_le_bytes()));
        planar.extend([0xff00_00ffu32, 0x00ff_00ff, 0x0000_ffff].iter().flat_map(|v| v.to_le_bytes()));
        let mut bytes = header.as_bytes().to_vec();
        bytes.extend(pcl_compressed_body(&planar));
        let cloud = parse(&bytes, path()).unwrap();
        assert_eq!(cloud.points(), &[[1.5, 2.0, 500.0], [-250.25, 7.5, 612.5]]);
    }

    #[test]
    fn compressed_organized_frames_keep_the_grid() {
        let header = xyz_header(2, 2, "binary_compressed");
        let planar = le_f32(&[1.0, f32::NAN, 3.0, 4.0, -1.0, f32::NAN, -3.0, -4.0, 400.0, f32::NAN, 402.0, 403.0]);
        let mut bytes = header.into_bytes();
        bytes.extend(pcl_compressed_body(&planar));
        let cloud = parse(&bytes, path()).unwrap();
        assert!(cloud.is_organized());
        assert_eq!(cloud.valid_count(), 3);
        assert_eq!(cloud.at(0, 1), Some(&[3.0, -3.0, 402.0]));
        assert_eq!(cloud.at(1, 0), None);
    }

    #[test]
    fn broken_compressed_data_is_an_error_naming_the_problem() {
        let header = xyz_header(2, 1, "binary_compressed");
        let planar = le_f32(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let good = pcl_compressed_body(&planar);
        let with_body = |body: &[u8]| {
            let mut bytes = header.clone().into_bytes();
            bytes.extend(body);
            parse(&bytes, path()).map_err(|e| e.to_string())
        };
        assert!(with_body(&good).is_ok());
        let sized = |compressed: u32, uncompressed: u32| {
            let mut body = good.clone();
            body[..4].copy_from_slice(&compressed.to_le_bytes());
            body[4..8].copy_from_slice(&uncompressed.to_le_bytes());
            body
        };
        let stream_len = u32::from_le_bytes(good[..4].try_into().unwrap());
        let mut corrupt = good.clone();
        corrupt[8] = 0xe0; // a back reference before any output
        let cases: Vec<(&str, Vec<u8>, &str)> = vec![
            ("no sizes", good[..5].to_vec(), "expected the 8 bytes of compressed and uncompressed size"),
            ("size not points x record", sized(stream_len, 25), "uncompressed size 25 is not POINTS 2 x 12"),
            ("huge size", sized(stream_len, u32::MAX), "is not POINTS 2 x 12"),
            ("stream cut", sized(10_000, 24), "expected 10000 bytes of compressed data"),
            ("expansion", sized(0, 24), "cannot hold the 24 bytes declared (LZF expands at most 88 times)"),
            ("corrupt stream", corrupt, "corrupt LZF data"),
            ("short stream", sized(stream_len - 1, 24), "data at compressed data (byte 8)"),
        ];
        for (name, body, expected) in cases {
            let message = with_body(&body).expect_err(name);
            assert!(message.contains(expected), "{name}: {message}");
            assert!(message.contains("scan.pcd"), "{name}: {message}");
        }
    }

    #[test]
    fn xyz_with_count_above_one_is_refused_as_the_message_says() {
        for counts in ["3 1 1", "1 2 1", "1 1 4"] {
            let text =
                format!("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT {counts}\nWIDTH 1\nDATA ascii\n1 2 3 4 5\n");
            let err = parse_str(&text).unwrap_err();
            assert!(matches!(err, LoadError::Header { line: 4, .. }), "{counts}: {err}");
            assert!(err.to_string().contains("COUNT 1, not COUNT"), "{counts}: {err}");
        }
    }

    #[test]
    fn absurd_sizes_are_refused_before_allocating() {
        for (width, height) in [("100000", "100000"), ("18446744073709551615", "2")] {
            let text = format!("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH {width}\nHEIGHT {height}\nDATA binary\n");
            let err = parse_str(&text).unwrap_err();
            assert!(matches!(err, LoadError::Header { line: 4, .. }), "{err}");
            assert!(err.to_string().contains("points a cloud may have"), "{err}");
        }
        let huge_count = "FIELDS x y z n\nSIZE 4 4 4 8\nTYPE F F F F\nCOUNT 1 1 1 4611686018427387904\n\
                          WIDTH 1\nDATA binary\n";
        let err = parse_str(huge_count).unwrap_err();
        assert!(err.to_string().contains("overflows"), "{err}");
    }

    #[test]
    fn malformed_files_name_the_file_and_the_place() {
        use crate::cloud::reader::test_support::{Expected, Expected::*, assert_located_errors};
        let header = xyz_header(2, 1, "binary");
        let ascii = xyz_header(2, 1, "ascii");
        let mut truncated = header.clone().into_bytes();
        truncated.extend(le_f32(&[1.0, 2.0, 3.0, 4.0, 5.0]));
        let garbage: Vec<u8> = (0u32..4096)
            .scan(0x2545_f491_u32, |state, _| {
                *state = state.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                Some((*state >> 16) as u8)
            })
            .collect();
        let cases: Vec<(&str, Vec<u8>, Expected)> = vec![
            ("truncated binary", truncated, DataAt("point 1 (byte 20)")),
            ("missing FIELDS", header.replace("FIELDS x y z\n", "").into(), HeaderLine(9)),
            ("no x field", header.replace("x y z", "a y z").into(), HeaderLine(2)),
            ("POINTS mismatch", header.replace("POINTS 2", "POINTS 3").into(), HeaderLine(9)),
            ("non-numeric WIDTH", header.replace("WIDTH 2", "WIDTH two").into(), HeaderLine(6)),
            ("unknown DATA", header.replace("DATA binary", "DATA zip").into(), HeaderLine(10)),
            ("unknown TYPE", header.replace("TYPE F F F", "TYPE F F Q").into(), HeaderLine(4)),
            ("x not float", header.replace("TYPE F F F", "TYPE U F F").into(), HeaderLine(4)),
            ("SIZE count", header.replace("SIZE 4 4 4", "SIZE 4 4").into(), HeaderLine(3)),
            ("repeated key", header.replace("HEIGHT 1", "WIDTH 2").into(), HeaderLine(7)),
            ("unknown keyword", format!("# c\nCOLOR red\n{header}").into(), HeaderLine(2)),
            ("no DATA line", "VERSION 0.7\nFIELDS x y z\n".into(), HeaderLine(3)),
            ("bad ascii token", format!("{ascii}1 2 3\n4 x 6\n").into(), DataAt("point 1 (line 12)")),
            ("too few values", format!("{ascii}1 2 3\n4 5\n").into(), DataAt("point 1 (line 12)")),
            ("too many values", format!("{ascii}1 2 3 4\n").into(), DataAt("point 0 (line 11)")),
            ("ascii ends early", format!("{ascii}1 2 3\n").into(), DataAt("point 1 (line 12)")),
            ("empty file", Vec::new(), HeaderLine(1)),
            ("random garbage", garbage, HeaderLine(1)),
        ];
        assert_located_errors("scan.pcd", cases, |bytes| parse(bytes, path()));
    }

    #[test]
    fn truncation_message_reports_sizes() {
        let mut bytes = xyz_header(2, 1, "binary").into_bytes();
        bytes.extend([0; 13]);
        let message = parse(&bytes, path()).unwrap_err().to_string();
        assert!(
            message.ends_with(
                "data at point 1 (byte 13): file ends early: expected 24 bytes of binary \
                 data after the header, found 13"
            ),
            "{message}"
        );
    }

    #[test]
    fn every_prefix_of_a_binary_file_fails_cleanly() {
        let mut binary = Vec::new();
        write_binary(&sample_grid(), &mut binary).unwrap();
        let mut compressed = Vec::new();
        write_binary_compressed(&sample_grid(), &mut compressed).unwrap();
        for bytes in [binary, compressed] {
            assert!(parse(&bytes, path()).is_ok());
            for cut in 0..bytes.len() {
                assert!(parse(&bytes[..cut], path()).is_err(), "prefix of {cut} bytes");
            }
        }
    }

    #[test]
    fn damaged_bytes_never_panic() {
        let grid = sample_grid();
        let mut binary = Vec::new();
        write_binary(&grid, &mut binary).unwrap();
        let mut ascii = Vec::new();
        write_ascii(&grid, &mut ascii).unwrap();
        let mixed = format!("{MIXED_HEADER}DATA ascii\n7 1 2 3 0 0 1 4\n8 4 5 6 0 1 0 0\n");
        let mut compressed = Vec::new();
        write_binary_compressed(&grid, &mut compressed).unwrap();
        for file in [binary, ascii, mixed.into_bytes(), compressed] {
            assert!(parse(&file, path()).is_ok());
            for at in 0..file.len() {
                for byte in [0, b'\n', b' ', b'9', b'x', 0xff] {
                    let mut damaged = file.clone();
                    damaged[at] = byte;
                    let _ = parse(&damaged, path());
                }
            }
        }
    }
}
