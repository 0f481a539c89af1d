//! Reading and writing PCD files: every data kind, header forms and
//! the errors of broken files.

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
    let mut padded = "FIELDS x y z _\nSIZE 4 4 4 4\nTYPE F F F U\nWIDTH 2\nHEIGHT 1\nDATA binary\n".as_bytes().to_vec();
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
        let text = format!("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT {counts}\nWIDTH 1\nDATA ascii\n1 2 3 4 5\n");
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
