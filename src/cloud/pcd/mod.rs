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

#[cfg(test)]
mod tests;
mod write;

pub use write::{write_ascii, write_binary, write_binary_compressed};

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
