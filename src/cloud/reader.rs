//! Building blocks shared by the PCD and PLY readers: header line
//! splitting, scalar decoding, the packed-xyz fast path and the error
//! constructors that keep messages uniform across formats.

use std::path::Path;

use super::{LoadError, Point};

/// Clouds above this size are refused: no camera frame comes close, so a
/// larger count means a corrupt header, and honouring it would exhaust
/// memory before the data section could prove it wrong.
pub(super) const MAX_POINTS: usize = 200_000_000;

pub(super) fn header_error(path: &Path, line: usize, message: impl Into<String>) -> LoadError {
    LoadError::Header { path: path.to_path_buf(), line, message: message.into() }
}

pub(super) fn data_error(path: &Path, location: impl Into<String>, message: impl Into<String>) -> LoadError {
    LoadError::Data { path: path.to_path_buf(), location: location.into(), message: message.into() }
}

/// Quotes text taken from the file for an error message. Garbage input can
/// make a "line" megabytes long and full of control bytes, so the text is
/// cut short and escaped to keep the message one readable line.
pub(super) fn quoted(text: &str) -> String {
    const SHOWN_CHARS: usize = 40;
    match text.char_indices().nth(SHOWN_CHARS) {
        Some((cut, _)) => format!("{:?}...", text.get(..cut).unwrap_or(text)),
        None => format!("{text:?}"),
    }
}

/// Parses one coordinate token. Rust's float syntax already covers the
/// spellings writers use for missing returns: `nan`, `NaN`, `-nan`, `inf`.
pub(super) fn parse_coordinate(token: &str) -> Option<f32> {
    token.parse().ok()
}

/// Splits the front of a file into lines, remembering line numbers and the
/// byte offset where the data section will start.
pub(super) struct Lines<'a> {
    bytes: &'a [u8],
    offset: usize,
    number: usize,
}

impl<'a> Lines<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Self {
        Lines { bytes, offset: 0, number: 0 }
    }

    /// The next line, 1-based number first, without its `\n` or `\r\n`.
    pub(super) fn next_line(&mut self) -> Option<(usize, &'a [u8])> {
        let rest = self.rest();
        if rest.is_empty() {
            return None;
        }
        let (line, consumed) = match rest.iter().position(|&b| b == b'\n') {
            Some(end) => (rest.get(..end).unwrap_or(rest), end + 1),
            None => (rest, rest.len()),
        };
        self.offset += consumed;
        self.number += 1;
        Some((self.number, line.strip_suffix(b"\r").unwrap_or(line)))
    }

    /// Number of the last line returned (0 before the first).
    pub(super) fn line_number(&self) -> usize {
        self.number
    }

    /// Everything after the last line returned.
    pub(super) fn rest(&self) -> &'a [u8] {
        self.bytes.get(self.offset..).unwrap_or_default()
    }
}

/// Byte order of binary data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Endian {
    Little,
    Big,
}

/// A numeric type a file can store a value as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    pub(super) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value stored at `offset`, or `None` when the bytes run out.
    /// Widening to f64 is exact for every type a coordinate or a list
    /// length realistically uses.
    pub(super) fn read(self, bytes: &[u8], offset: usize, endian: Endian) -> Option<f64> {
        macro_rules! decode {
            ($ty:ty) => {
                take(bytes, offset).map(|raw| match endian {
                    Endian::Little => <$ty>::from_le_bytes(raw) as f64,
                    Endian::Big => <$ty>::from_be_bytes(raw) as f64,
                })
            };
        }
        match self {
            Scalar::I8 => decode!(i8),
            Scalar::U8 => decode!(u8),
            Scalar::I16 => decode!(i16),
            Scalar::U16 => decode!(u16),
            Scalar::I32 => decode!(i32),
            Scalar::U32 => decode!(u32),
            Scalar::I64 => decode!(i64),
            Scalar::U64 => decode!(u64),
            Scalar::F32 => decode!(f32),
            Scalar::F64 => decode!(f64),
        }
    }

    /// A coordinate stored at `offset`; NaN (an invalid point) if the bytes
    /// run out, which callers rule out by checking lengths first.
    pub(super) fn read_coordinate(self, bytes: &[u8], offset: usize, endian: Endian) -> f32 {
        self.read(bytes, offset, endian).map_or(f32::NAN, |value| value as f32)
    }
}

fn take<const N: usize>(bytes: &[u8], offset: usize) -> Option<[u8; N]> {
    bytes.get(offset..offset.checked_add(N)?)?.try_into().ok()
}

/// Decodes back-to-back little-endian f32 `x y z` records. This is how
/// structured-light cameras deliver full frames, so it gets one branch-free
/// loop the compiler can vectorise; a trailing partial record is ignored.
pub(super) fn decode_packed_xyz_f32_le(data: &[u8]) -> Vec<Point> {
    let (records, _) = data.as_chunks::<12>();
    records
        .iter()
        .map(|&[x0, x1, x2, x3, y0, y1, y2, y3, z0, z1, z2, z3]| {
            [
                f32::from_le_bytes([x0, x1, x2, x3]),
                f32::from_le_bytes([y0, y1, y2, y3]),
                f32::from_le_bytes([z0, z1, z2, z3]),
            ]
        })
        .collect()
}

/// What the malformed-file tests of both parsers expect, and their check.
#[cfg(test)]
pub(super) mod test_support {
    use super::super::{LoadError, PointCloud};

    /// Where a malformed file must be reported broken.
    pub enum Expected {
        HeaderLine(usize),
        DataAt(&'static str),
    }

    /// Parses every case and checks the error names `file` and the place.
    pub fn assert_located_errors(
        file: &str,
        cases: Vec<(&str, Vec<u8>, Expected)>,
        parse: impl Fn(&[u8]) -> Result<PointCloud, LoadError>,
    ) {
        for (name, bytes, expected) in cases {
            let err = parse(&bytes).expect_err(name);
            let message = err.to_string();
            assert!(message.contains(file), "{name}: {message}");
            match (expected, &err) {
                (Expected::HeaderLine(want), LoadError::Header { line, .. }) => {
                    assert_eq!(*line, want, "{name}: {message}");
                    assert!(message.contains(&format!("header line {want}:")), "{name}");
                }
                (Expected::DataAt(want), LoadError::Data { location, .. }) => {
                    assert_eq!(location, want, "{name}: {message}");
                    assert!(message.contains(want), "{name}");
                }
                _ => panic!("{name}: wrong error kind: {message}"),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_terminators_and_track_offsets() {
        let mut lines = Lines::new(b"a\r\nbb\n\nccc");
        assert_eq!(lines.next_line(), Some((1, &b"a"[..])));
        assert_eq!(lines.next_line(), Some((2, &b"bb"[..])));
        assert_eq!(lines.rest(), b"\nccc");
        assert_eq!(lines.next_line(), Some((3, &b""[..])));
        assert_eq!(lines.next_line(), Some((4, &b"ccc"[..])));
        assert_eq!(lines.next_line(), None);
        assert_eq!(lines.line_number(), 4);
    }

    #[test]
    fn scalars_decode_both_byte_orders() {
        let bytes = [0x01, 0x02, 0x03, 0x04];
        assert_eq!(Scalar::U16.read(&bytes, 1, Endian::Big), Some(f64::from(0x0203u16)));
        assert_eq!(Scalar::U16.read(&bytes, 1, Endian::Little), Some(f64::from(0x0302u16)));
        assert_eq!(Scalar::I8.read(&[0xff], 0, Endian::Little), Some(-1.0));
        assert_eq!(Scalar::U32.read(&bytes, 1, Endian::Little), None);
        assert_eq!(Scalar::U8.read(&bytes, usize::MAX, Endian::Little), None);
        assert!(Scalar::F64.read_coordinate(&bytes, 0, Endian::Little).is_nan());
    }

    #[test]
    fn packed_decoding_matches_the_input() {
        let mut bytes = Vec::new();
        for v in [1.0f32, -2.5, 3e3, f32::NAN, 0.0, 7.0] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes.push(9);
        let points = decode_packed_xyz_f32_le(&bytes);
        assert_eq!(points.len(), 2);
        assert_eq!(points[0], [1.0, -2.5, 3e3]);
        assert!(points[1][0].is_nan());
        assert_eq!(points[1][2], 7.0);
    }

    #[test]
    fn coordinates_accept_nan_spellings() {
        for token in ["nan", "NaN", "-nan", "NAN"] {
            assert!(parse_coordinate(token).is_some_and(f32::is_nan), "{token}");
        }
        assert_eq!(parse_coordinate("-1.5e2"), Some(-150.0));
        assert_eq!(parse_coordinate("1,5"), None);
    }

    #[test]
    fn quoting_cuts_long_garbage() {
        let long = "x".repeat(1000);
        assert!(quoted(&long).len() < 50);
        assert_eq!(quoted("a\u{1}"), "\"a\\u{1}\"");
    }
}
