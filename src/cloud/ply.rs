//! PLY files (Stanford polygon format): ascii, binary little and big
//! endian. Only the vertex element is read; faces and any other elements
//! are stepped over, so a mesh loads as the cloud of its vertices.

use std::io::{self, Write};
use std::path::Path;

use super::reader::{
    Endian, Lines, MAX_POINTS, Scalar, data_error, decode_packed_xyz_f32_le, header_error, parse_coordinate, quoted,
};
use super::{INVALID_POINT, LoadError, Point, PointCloud};

/// Parses a PLY file's bytes; `path` is only used in error messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<PointCloud, LoadError> {
    let mut lines = Lines::new(bytes);
    let header = read_header(&mut lines, path)?;
    let points = match header.format {
        Format::Binary(endian) => decode_binary(lines.rest(), &header, endian, path)?,
        Format::Ascii => {
            let mut tokens = Tokens::new(lines.rest(), lines.line_number() + 1);
            decode_ascii(&mut tokens, &header, path)?
        }
    };
    Ok(PointCloud::unorganized(points))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary(Endian),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PropertyKind {
    Scalar(Scalar),
    List { length: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: PropertyKind,
    line: usize,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    line: usize,
    properties: Vec<Property>,
}

impl Element {
    /// Bytes per item when every property is a scalar; `None` when lists
    /// make items variable-sized.
    fn fixed_stride(&self) -> Option<usize> {
        self.properties.iter().try_fold(0usize, |sum, p| match p.kind {
            PropertyKind::Scalar(s) => sum.checked_add(s.size()),
            PropertyKind::List { .. } => None,
        })
    }
}

/// A validated header. Elements after the vertex element never need
/// reading, so they are not kept.
#[derive(Debug)]
struct Header {
    format: Format,
    before_vertex: Vec<Element>,
    vertex: Element,
    /// Property indices of x, y and z within the vertex element.
    xyz: [usize; 3],
}

impl Header {
    /// True for vertices stored as exactly `float x, float y, float z`.
    fn is_packed_xyz_f32(&self) -> bool {
        self.xyz == [0, 1, 2]
            && self.vertex.properties.len() == 3
            && self.vertex.properties.iter().all(|p| p.kind == PropertyKind::Scalar(Scalar::F32))
    }

    fn axis_of(&self, property: usize) -> Option<usize> {
        self.xyz.iter().position(|&p| p == property)
    }
}

fn read_header(lines: &mut Lines<'_>, path: &Path) -> Result<Header, LoadError> {
    match lines.next_line() {
        Some((_, magic)) if magic.trim_ascii() == b"ply" => {}
        Some(_) => {
            return Err(header_error(path, 1, "not a PLY file: expected the \"ply\" magic line"));
        }
        None => {
            return Err(header_error(path, 1, "file is empty: expected the \"ply\" magic line"));
        }
    }
    let mut format: Option<(Format, usize)> = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some((line, bytes)) = lines.next_line() else {
            return Err(header_error(path, lines.line_number() + 1, "file ends before \"end_header\""));
        };
        let text =
            std::str::from_utf8(bytes).map_err(|_| header_error(path, line, "not text: expected a PLY header line"))?;
        let mut words = text.split_ascii_whitespace();
        let Some(key) = words.next() else {
            continue;
        };
        let values: Vec<&str> = words.collect();
        let at_line = |message: String| header_error(path, line, message);
        match key {
            "comment" | "obj_info" => {}
            "format" => {
                if let Some((_, first)) = format {
                    return Err(at_line(format!("format appears again (first on line {first})")));
                }
                format = Some((parse_format(&values).map_err(at_line)?, line));
            }
            "element" => elements.push(parse_element(&values, line).map_err(at_line)?),
            "property" => {
                let element = elements.last_mut().ok_or_else(|| at_line("property before any element".into()))?;
                let property = parse_property(&values, line).map_err(at_line)?;
                element.properties.push(property);
            }
            "end_header" => {
                let format =
                    format.map(|(f, _)| f).ok_or_else(|| at_line("no \"format\" line before end_header".into()))?;
                return validate(format, elements, line, path);
            }
            other => {
                return Err(at_line(format!(
                    "unknown header keyword {} (expected format, comment, obj_info, element, \
                     property or end_header)",
                    quoted(other)
                )));
            }
        }
    }
}

fn parse_format(values: &[&str]) -> Result<Format, String> {
    let (kind, version) = match values {
        [kind, version] => (*kind, *version),
        _ => return Err("format takes a kind and a version, e.g. \"format ascii 1.0\"".into()),
    };
    let format = match kind {
        "ascii" => Format::Ascii,
        "binary_little_endian" => Format::Binary(Endian::Little),
        "binary_big_endian" => Format::Binary(Endian::Big),
        other => {
            return Err(format!(
                "unknown format {} (expected ascii, binary_little_endian or binary_big_endian)",
                quoted(other)
            ));
        }
    };
    if version != "1.0" {
        return Err(format!("unsupported PLY version {} (expected 1.0)", quoted(version)));
    }
    Ok(format)
}

fn parse_element(values: &[&str], line: usize) -> Result<Element, String> {
    let [name, count] = values else {
        return Err("element takes a name and a count, e.g. \"element vertex 100\"".into());
    };
    let count =
        count.parse().map_err(|_| format!("element count {} is not a non-negative whole number", quoted(count)))?;
    Ok(Element { name: name.to_string(), count, line, properties: Vec::new() })
}

fn parse_property(values: &[&str], line: usize) -> Result<Property, String> {
    let (kind, name) = match values {
        ["list", length, item, name] => {
            let length = scalar_named(length)?;
            if length.is_float() {
                return Err(format!("list length type {} must be an integer type", quoted(&format!("{length:?}"))));
            }
            let item = scalar_named(item)?;
            (PropertyKind::List { length, item }, *name)
        }
        [scalar, name] => (PropertyKind::Scalar(scalar_named(scalar)?), *name),
        _ => {
            return Err("property takes a type and a name, or \"list\", two types and a name".into());
        }
    };
    Ok(Property { name: name.to_string(), kind, line })
}

fn scalar_named(name: &str) -> Result<Scalar, String> {
    Ok(match name {
        "char" | "int8" => Scalar::I8,
        "uchar" | "uint8" => Scalar::U8,
        "short" | "int16" => Scalar::I16,
        "ushort" | "uint16" => Scalar::U16,
        "int" | "int32" => Scalar::I32,
        "uint" | "uint32" => Scalar::U32,
        "float" | "float32" => Scalar::F32,
        "double" | "float64" => Scalar::F64,
        other => {
            return Err(format!(
                "unknown property type {} (expected char, uchar, short, ushort, int, uint, \
                 float, double or a sized alias such as float32)",
                quoted(other)
            ));
        }
    })
}

fn validate(format: Format, elements: Vec<Element>, end_line: usize, path: &Path) -> Result<Header, LoadError> {
    let mut before_vertex = Vec::new();
    let mut vertex = None;
    for element in elements {
        if element.name == "vertex" {
            vertex = Some(element);
            break;
        }
        before_vertex.push(element);
    }
    let vertex = vertex.ok_or_else(|| header_error(path, end_line, "no \"element vertex\" in the header"))?;
    if vertex.count > MAX_POINTS {
        return Err(header_error(
            path,
            vertex.line,
            format!("{} vertices is more than the {MAX_POINTS} points a cloud may have", vertex.count),
        ));
    }
    let locate = |axis: &str| {
        let index = vertex.properties.iter().position(|p| p.name == axis).ok_or_else(|| {
            header_error(path, vertex.line, format!("vertex element has no {axis:?} property: x, y and z are required"))
        })?;
        match vertex.properties.get(index) {
            Some(Property { kind: PropertyKind::Scalar(s), .. }) if s.is_float() => Ok(index),
            property => Err(header_error(
                path,
                property.map_or(vertex.line, |p| p.line),
                format!("vertex property {axis:?} must be float or double"),
            )),
        }
    };
    let xyz = [locate("x")?, locate("y")?, locate("z")?];
    Ok(Header { format, before_vertex, vertex, xyz })
}

fn decode_binary(body: &[u8], header: &Header, endian: Endian, path: &Path) -> Result<Vec<Point>, LoadError> {
    let mut offset = 0;
    for element in &header.before_vertex {
        offset = skip_binary_element(body, offset, element, endian, path)?;
    }
    match header.vertex.fixed_stride() {
        Some(stride) => decode_fixed_vertices(body, offset, stride, header, endian, path),
        None => decode_walked_vertices(body, offset, header, endian, path),
    }
}

fn skip_binary_element(
    body: &[u8],
    start: usize,
    element: &Element,
    endian: Endian,
    path: &Path,
) -> Result<usize, LoadError> {
    let location = |item: usize, byte: usize| format!("{} {item} (byte {byte})", element.name);
    if let Some(stride) = element.fixed_stride() {
        let end = stride.checked_mul(element.count).and_then(|bytes| bytes.checked_add(start));
        return match end {
            Some(end) if end <= body.len() => Ok(end),
            _ => {
                let available = body.len().saturating_sub(start);
                let item = available.checked_div(stride).unwrap_or(0);
                Err(data_error(
                    path,
                    location(item, body.len()),
                    format!(
                        "file ends early: {} {} items of {stride} bytes do not fit in the \
                         {available} bytes left",
                        element.count, element.name
                    ),
                ))
            }
        };
    }
    // Every item of a list element holds at least one length byte, so this
    // loop stops at the end of the data whatever count the header claims.
    let mut offset = start;
    for item in 0..element.count {
        offset = walk_binary_item(body, offset, &element.properties, endian, |_, _, _| {})
            .map_err(|m| data_error(path, location(item, offset), m))?;
    }
    Ok(offset)
}

/// Steps over one binary item, calling `visit(property, type, offset)` for
/// each scalar property; returns the offset just past the item.
fn walk_binary_item(
    body: &[u8],
    mut offset: usize,
    properties: &[Property],
    endian: Endian,
    mut visit: impl FnMut(usize, Scalar, usize),
) -> Result<usize, String> {
    for (index, property) in properties.iter().enumerate() {
        let ends_early = || format!("file ends early inside property {:?}", property.name);
        let size = match property.kind {
            PropertyKind::Scalar(scalar) => {
                visit(index, scalar, offset);
                scalar.size()
            }
            PropertyKind::List { length, item } => {
                let raw = length.read(body, offset, endian).ok_or_else(ends_early)?;
                let items =
                    list_length(raw).ok_or_else(|| format!("list {:?} has an invalid length {raw}", property.name))?;
                items
                    .checked_mul(item.size())
                    .and_then(|bytes| bytes.checked_add(length.size()))
                    .ok_or_else(ends_early)?
            }
        };
        offset = offset.checked_add(size).filter(|&end| end <= body.len()).ok_or_else(ends_early)?;
    }
    Ok(offset)
}

fn list_length(raw: f64) -> Option<usize> {
    (raw >= 0.0 && raw.fract() == 0.0 && raw <= f64::from(u32::MAX)).then_some(raw as usize)
}

fn decode_fixed_vertices(
    body: &[u8],
    start: usize,
    stride: usize,
    header: &Header,
    endian: Endian,
    path: &Path,
) -> Result<Vec<Point>, LoadError> {
    let available = body.len().saturating_sub(start);
    let needed = stride.checked_mul(header.vertex.count);
    let data = needed.and_then(|n| body.get(start..)?.get(..n));
    let Some(data) = data else {
        let vertex = available.checked_div(stride).unwrap_or(0);
        return Err(data_error(
            path,
            format!("vertex {vertex} (byte {})", body.len()),
            format!(
                "file ends early: expected {} vertices of {stride} bytes from byte {start} \
                 after the header, found {available} bytes",
                header.vertex.count
            ),
        ));
    };
    if endian == Endian::Little && header.is_packed_xyz_f32() {
        return Ok(decode_packed_xyz_f32_le(data));
    }
    let mut offsets = [(0, Scalar::F32); 3];
    let mut offset = 0;
    for (index, property) in header.vertex.properties.iter().enumerate() {
        if let PropertyKind::Scalar(scalar) = property.kind {
            if let Some(slot) = header.axis_of(index).and_then(|a| offsets.get_mut(a)) {
                *slot = (offset, scalar);
            }
            offset += scalar.size();
        }
    }
    // x, y and z are scalar properties, so the stride is at least 12;
    // max(1) only keeps chunks_exact from panicking should that change.
    Ok(data
        .chunks_exact(stride.max(1))
        .map(|item| offsets.map(|(at, scalar)| scalar.read_coordinate(item, at, endian)))
        .collect())
}

fn decode_walked_vertices(
    body: &[u8],
    start: usize,
    header: &Header,
    endian: Endian,
    path: &Path,
) -> Result<Vec<Point>, LoadError> {
    // Each vertex takes at least 12 bytes, which bounds the allocation no
    // matter what count the header claims.
    let mut points = Vec::with_capacity(header.vertex.count.min(body.len() / 12));
    let mut offset = start;
    for index in 0..header.vertex.count {
        let mut point = INVALID_POINT;
        let visit = |property, scalar: Scalar, at| {
            if let Some(value) = header.axis_of(property).and_then(|a| point.get_mut(a)) {
                *value = scalar.read_coordinate(body, at, endian);
            }
        };
        offset = walk_binary_item(body, offset, &header.vertex.properties, endian, visit)
            .map_err(|m| data_error(path, format!("vertex {index} (byte {offset})"), m))?;
        points.push(point);
    }
    Ok(points)
}

/// Whitespace-separated tokens of an ascii body, with line numbers for
/// error messages. PLY ascii items are token sequences; writers put one
/// per line, but nothing requires it.
struct Tokens<'a> {
    bytes: &'a [u8],
    offset: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn new(bytes: &'a [u8], first_line: usize) -> Self {
        Tokens { bytes, offset: 0, line: first_line }
    }

    fn next_token(&mut self) -> Option<&'a [u8]> {
        while let Some(&byte) = self.bytes.get(self.offset) {
            if !byte.is_ascii_whitespace() {
                break;
            }
            if byte == b'\n' {
                self.line += 1;
            }
            self.offset += 1;
        }
        let start = self.offset;
        while self.bytes.get(self.offset).is_some_and(|b| !b.is_ascii_whitespace()) {
            self.offset += 1;
        }
        self.bytes.get(start..self.offset).filter(|token| !token.is_empty())
    }
}

fn decode_ascii(tokens: &mut Tokens<'_>, header: &Header, path: &Path) -> Result<Vec<Point>, LoadError> {
    for element in &header.before_vertex {
        // Items without properties consume no tokens; skipping them keeps
        // a huge claimed count from spinning.
        if element.properties.is_empty() {
            continue;
        }
        for item in 0..element.count {
            walk_ascii_item(tokens, &element.properties, |_, _| Ok(()))
                .map_err(|m| data_error(path, format!("{} {item} (line {})", element.name, tokens.line), m))?;
        }
    }
    let mut points = Vec::with_capacity(header.vertex.count.min(tokens.bytes.len() / 6));
    for index in 0..header.vertex.count {
        let mut point = INVALID_POINT;
        let visit = |property: usize, token: &[u8]| {
            let Some(value) = header.axis_of(property).and_then(|a| point.get_mut(a)) else {
                return Ok(());
            };
            let text = String::from_utf8_lossy(token);
            *value = parse_coordinate(&text).ok_or_else(|| {
                let name = header.vertex.properties.get(property).map(|p| p.name.as_str());
                format!("cannot read {} as a number for property {:?}", quoted(&text), name.unwrap_or_default())
            })?;
            Ok(())
        };
        walk_ascii_item(tokens, &header.vertex.properties, visit)
            .map_err(|m| data_error(path, format!("vertex {index} (line {})", tokens.line), m))?;
        points.push(point);
    }
    Ok(points)
}

/// Reads one ascii item, calling `visit(property, token)` for each scalar
/// property; list values are stepped over.
fn walk_ascii_item<'a>(
    tokens: &mut Tokens<'a>,
    properties: &[Property],
    mut visit: impl FnMut(usize, &'a [u8]) -> Result<(), String>,
) -> Result<(), String> {
    for (index, property) in properties.iter().enumerate() {
        let ends_early = || format!("file ends early: expected property {:?}", property.name);
        let token = tokens.next_token().ok_or_else(ends_early)?;
        match property.kind {
            PropertyKind::Scalar(_) => visit(index, token)?,
            PropertyKind::List { .. } => {
                let items: usize = std::str::from_utf8(token).ok().and_then(|t| t.parse().ok()).ok_or_else(|| {
                    format!(
                        "list {:?} length {} is not a count",
                        property.name,
                        quoted(&String::from_utf8_lossy(token))
                    )
                })?;
                for _ in 0..items {
                    tokens.next_token().ok_or_else(ends_early)?;
                }
            }
        }
    }
    Ok(())
}

fn write_header<W: Write>(out: &mut W, format: &str, vertices: usize) -> io::Result<()> {
    write!(
        out,
        "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nend_header\n"
    )
}

/// Writes the points of `cloud` as a binary little-endian PLY with float
/// x y z vertices. Organization is lost (PLY has no pixel grid).
pub fn write_binary_le<W: Write>(cloud: &PointCloud, mut out: W) -> io::Result<()> {
    write_header(&mut out, "binary_little_endian", cloud.len())?;
    let bytes: Vec<u8> = cloud.points().iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    out.write_all(&bytes)?;
    out.flush()
}

/// Writes the points of `cloud` as an ascii PLY with float x y z vertices.
pub fn write_ascii<W: Write>(cloud: &PointCloud, mut out: W) -> io::Result<()> {
    write_header(&mut out, "ascii", cloud.len())?;
    for [x, y, z] in cloud.points() {
        // Display prints the shortest text that reads back to the same f32.
        writeln!(out, "{x} {y} {z}")?;
    }
    out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> &'static Path {
        Path::new("part.ply")
    }

    fn parse_bytes(bytes: &[u8]) -> Result<PointCloud, LoadError> {
        parse(bytes, path())
    }

    fn le_f32(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// Two triangles' worth of vertices as binary float x y z.
    const XYZ_LE_HEADER: &str = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n\
        property float x\nproperty float y\nproperty float z\nend_header\n";

    #[test]
    fn ascii_with_comments_extra_properties_and_faces() {
        let text = "ply\r\nformat ascii 1.0\ncomment made by hand\nobj_info scanner 3\n\
                    element vertex 3\nproperty float32 x\nproperty float y\nproperty double z\n\
                    property uchar red\nproperty float nx\n\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n\
                    1 2 3 255 0.5\n4.5 -5 6e1 0 1\nnan NaN nan 3 0\n3 0 1 2\n";
        let cloud = parse_bytes(text.as_bytes()).unwrap();
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0], [4.5, -5.0, 60.0]]);
        assert!(!cloud.is_organized());
    }

    #[test]
    fn binary_little_endian_packed_vertices() {
        let mut bytes = XYZ_LE_HEADER.as_bytes().to_vec();
        bytes.extend(le_f32(&[1.0, 2.0, 3.0, 0.0, 0.0, 0.0]));
        let cloud = parse_bytes(&bytes).unwrap();
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0]], "0,0,0 is a missing return");
    }

    #[test]
    fn binary_big_endian_doubles_with_extra_properties() {
        let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty int id\n\
            property double x\nproperty double y\nproperty double z\nproperty uint8 quality\n\
            end_header\n"
            .to_vec();
        for (id, xyz) in [(7i32, [0.5f64, -1.5, 2e3]), (8, [1.0 / 3.0, 4.0, 5.0])] {
            bytes.extend(id.to_be_bytes());
            for c in xyz {
                bytes.extend(c.to_be_bytes());
            }
            bytes.push(99);
        }
        let cloud = parse_bytes(&bytes).unwrap();
        assert_eq!(cloud.points(), &[[0.5, -1.5, 2e3], [(1.0f64 / 3.0) as f32, 4.0, 5.0]]);
    }

    /// A binary file whose face and camera elements come before the
    /// vertices, so reaching them means walking variable-length lists.
    fn faces_first_file() -> Vec<u8> {
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement face 2\n\
            property list uchar int vertex_indices\nproperty uchar flags\n\
            element camera 1\nproperty float view\nproperty short id\n\
            element vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
            .to_vec();
        bytes.push(3);
        bytes.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
        bytes.push(1);
        bytes.push(4);
        bytes.extend([0i32, 1, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
        bytes.push(0);
        bytes.extend(le_f32(&[1.0]));
        bytes.extend(5i16.to_le_bytes());
        bytes.extend(le_f32(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
        bytes
    }

    #[test]
    fn binary_elements_before_the_vertices_are_skipped() {
        let cloud = parse_bytes(&faces_first_file()).unwrap();
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    #[test]
    fn ascii_elements_before_the_vertices_are_skipped() {
        let text = "ply\nformat ascii 1.0\nelement face 2\nproperty list uchar int idx\n\
                    element empty 1000000000000\nelement vertex 1\nproperty float x\n\
                    property float y\nproperty float z\nend_header\n3 0 1 2\n4 0 1\n2 3\n7 8 9\n";
        let cloud = parse_bytes(text.as_bytes()).unwrap();
        assert_eq!(cloud.points(), &[[7.0, 8.0, 9.0]]);
    }

    #[test]
    fn vertices_with_list_properties_are_walked() {
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\n\
            property float x\nproperty list uint8 float16ish\nproperty float y\n\
            property float z\nend_header\n"
            .to_vec();
        // An unknown type name must be refused rather than guessed at.
        assert!(parse_bytes(&bytes).is_err());
        bytes = String::from_utf8(bytes).unwrap().replace("float16ish", "short samples").into_bytes();
        bytes.extend(le_f32(&[1.0]));
        bytes.push(2);
        bytes.extend([7u8; 4]);
        bytes.extend(le_f32(&[2.0, 3.0, 4.0]));
        bytes.push(0);
        bytes.extend(le_f32(&[5.0, 6.0]));
        let cloud = parse_bytes(&bytes).unwrap();
        assert_eq!(cloud.points(), &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    fn sample_cloud() -> PointCloud {
        PointCloud::unorganized((1..40).map(|i| [i as f32 * 0.1, -(i as f32) / 3.0, 500.0 + i as f32]).collect())
    }

    #[test]
    fn binary_and_ascii_writers_round_trip() {
        let cloud = sample_cloud();
        let mut binary = Vec::new();
        write_binary_le(&cloud, &mut binary).unwrap();
        let mut ascii = Vec::new();
        write_ascii(&cloud, &mut ascii).unwrap();
        assert_eq!(parse_bytes(&binary).unwrap(), cloud);
        assert_eq!(parse_bytes(&ascii).unwrap(), cloud);
    }

    #[test]
    fn huge_vertex_counts_are_refused_before_allocating() {
        let text = XYZ_LE_HEADER.replace("vertex 2", "vertex 200000001");
        let err = parse_bytes(text.as_bytes()).unwrap_err();
        assert!(matches!(err, LoadError::Header { line: 3, .. }), "{err}");
    }

    #[test]
    fn malformed_files_name_the_file_and_the_place() {
        use crate::cloud::reader::test_support::{Expected, Expected::*, assert_located_errors};
        let ascii = XYZ_LE_HEADER.replace("binary_little_endian", "ascii");
        let mut truncated = XYZ_LE_HEADER.as_bytes().to_vec();
        truncated.extend(le_f32(&[1.0, 2.0, 3.0, 4.0]));
        let mut faces = faces_first_file();
        // Faces take 14 + 18 bytes, the camera 6 and the vertices 24.
        let face_data_start = faces.len() - 62;
        faces.truncate(face_data_start + 20);
        let garbage: Vec<u8> = (0u32..4096)
            .scan(0x9e37_79b9_u32, |state, _| {
                *state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                Some((*state >> 24) as u8)
            })
            .collect();
        let cases: Vec<(&str, Vec<u8>, Expected)> = vec![
            ("no vertex element", XYZ_LE_HEADER.replace("element vertex 2", "element point 2").into(), HeaderLine(7)),
            (
                "unknown format",
                XYZ_LE_HEADER.replace("binary_little_endian", "binary_middle_endian").into(),
                HeaderLine(2),
            ),
            ("wrong version", XYZ_LE_HEADER.replace("1.0", "2.0").into(), HeaderLine(2)),
            ("truncated binary", truncated, DataAt("vertex 1 (byte 16)")),
            ("truncated face list", faces, DataAt("face 1 (byte 14)")),
            ("no magic", XYZ_LE_HEADER.replace("ply\n", "PLY\n").into(), HeaderLine(1)),
            ("x is an int", XYZ_LE_HEADER.replace("float x", "int x").into(), HeaderLine(4)),
            ("no z", XYZ_LE_HEADER.replace("float z", "float w").into(), HeaderLine(3)),
            ("property before element", "ply\nformat ascii 1.0\nproperty float x\nend_header\n".into(), HeaderLine(3)),
            ("no end_header", "ply\nformat ascii 1.0\n".into(), HeaderLine(3)),
            ("no format", XYZ_LE_HEADER.replace("format binary_little_endian 1.0\n", "").into(), HeaderLine(6)),
            ("bad count", XYZ_LE_HEADER.replace("vertex 2", "vertex two").into(), HeaderLine(3)),
            ("bad ascii token", format!("{ascii}1 2 3\n4 five 6\n").into(), DataAt("vertex 1 (line 9)")),
            ("ascii ends early", format!("{ascii}1 2 3\n4 5\n").into(), DataAt("vertex 1 (line 10)")),
            ("empty file", Vec::new(), HeaderLine(1)),
            ("random garbage", garbage, HeaderLine(1)),
        ];
        assert_located_errors("part.ply", cases, parse_bytes);
    }

    #[test]
    fn every_prefix_of_a_binary_file_fails_cleanly() {
        let mut packed = Vec::new();
        write_binary_le(&sample_cloud(), &mut packed).unwrap();
        for bytes in [faces_first_file(), packed] {
            assert!(parse_bytes(&bytes).is_ok());
            for cut in 0..bytes.len() {
                assert!(parse_bytes(&bytes[..cut]).is_err(), "prefix of {cut} bytes");
            }
        }
    }

    #[test]
    fn prefixes_cutting_trailing_faces_never_panic() {
        let mut bytes = XYZ_LE_HEADER
            .replace("end_header", "element face 1\nproperty list uchar uint idx\nend_header")
            .into_bytes();
        let vertices_end = bytes.len() + 24;
        bytes.extend(le_f32(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
        bytes.push(3);
        bytes.extend([0u8; 12]);
        for cut in 0..=bytes.len() {
            let result = parse_bytes(&bytes[..cut]);
            assert_eq!(result.is_ok(), cut >= vertices_end, "prefix of {cut} bytes");
        }
    }

    #[test]
    fn damaged_bytes_never_panic() {
        let mut ascii = Vec::new();
        write_ascii(&sample_cloud(), &mut ascii).unwrap();
        let walked = "ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uchar int i\n\
            element vertex 1\nproperty double x\nproperty list short uint8 l\nproperty float y\n\
            property float z\nend_header\n\x01\0\0\0\x05\0\0\0\0\0\0\0\0\0\x02\x01\x02\0\0\0\0\0\0\0\0";
        for file in [faces_first_file(), ascii, walked.as_bytes().to_vec()] {
            assert!(parse_bytes(&file).is_ok());
            for at in 0..file.len() {
                for byte in [0, b'\n', b' ', b'9', b'x', 0xff] {
                    let mut damaged = file.clone();
                    damaged[at] = byte;
                    let _ = parse_bytes(&damaged);
                }
            }
        }
    }
}
