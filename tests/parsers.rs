//! Loading clouds from disk through `cloud::load`: dispatch by extension,
//! both formats, and errors that name the file.

use std::path::Path;

use weldseam::cloud::{INVALID_POINT, LoadError, Point, PointCloud, load, pcd, ply};

use crate::util::write_temp;

fn grid(width: usize, height: usize) -> PointCloud {
    let points = (0..width * height)
        .map(|i| {
            if i % 7 == 3 {
                INVALID_POINT
            } else {
                let (col, row) = ((i % width) as f32, (i / width) as f32);
                [col * 0.25 - 100.0, row * 0.25 - 80.0, 400.0 + (col + row) * 0.01]
            }
        })
        .collect();
    PointCloud::organized(width, height, points).expect("grid size matches")
}

/// Point equality that treats NaN as equal to NaN.
fn same_points(a: &[Point], b: &[Point]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| p.iter().zip(q).all(|(u, v)| u == v || (u.is_nan() && v.is_nan())))
}

fn encoded(write: impl FnOnce(&mut Vec<u8>) -> std::io::Result<()>) -> Vec<u8> {
    let mut bytes = Vec::new();
    write(&mut bytes).expect("writing to memory cannot fail");
    bytes
}

#[test]
fn binary_and_ascii_pcd_files_load_as_organized_clouds() {
    let cloud = grid(16, 9);
    let binary = encoded(|out| pcd::write_binary(&cloud, out));
    let ascii = encoded(|out| pcd::write_ascii(&cloud, out));
    let compressed = encoded(|out| pcd::write_binary_compressed(&cloud, out));
    for (name, bytes) in [("frame.pcd", binary), ("frame_ascii.PCD", ascii), ("frame_lzf.pcd", compressed)] {
        let (_dir, path) = write_temp(name, &bytes);
        let loaded = load(&path).expect(name);
        assert!(loaded.is_organized(), "{name}");
        assert_eq!((loaded.width(), loaded.height()), (16, 9), "{name}");
        assert!(same_points(loaded.points(), cloud.points()), "{name}");
    }
}

#[test]
fn ply_files_load_as_unorganized_clouds_of_valid_points() {
    let cloud = grid(8, 5);
    let binary = encoded(|out| ply::write_binary_le(&cloud, out));
    let ascii = encoded(|out| ply::write_ascii(&cloud, out));
    let valid = PointCloud::unorganized(cloud.points().to_vec());
    for (name, bytes) in [("part.ply", binary), ("part_ascii.ply", ascii)] {
        let (_dir, path) = write_temp(name, &bytes);
        let loaded = load(&path).expect(name);
        assert!(!loaded.is_organized(), "{name}");
        assert_eq!(loaded, valid, "{name}");
    }
}

#[test]
fn unknown_extensions_are_refused_by_name() {
    let (_dir, path) = write_temp("scan.xyz", b"1 2 3\n");
    let err = load(&path).expect_err("xyz is not a supported format");
    assert!(matches!(err, LoadError::UnknownFormat { .. }), "{err}");
    assert!(err.to_string().contains("scan.xyz"), "{err}");
}

#[test]
fn missing_files_are_io_errors() {
    let (dir, _) = write_temp("other.pcd", b"");
    let err = load(&dir.path().join("absent.pcd")).expect_err("file does not exist");
    assert!(matches!(err, LoadError::Io { .. }), "{err}");
    assert!(err.to_string().contains("absent.pcd"), "{err}");
}

#[test]
fn truncated_files_report_the_full_path_and_offset() {
    let bytes = encoded(|out| pcd::write_binary(&grid(4, 2), out));
    let (_dir, path) = write_temp("cut.pcd", &bytes[..bytes.len() - 5]);
    let message = load(&path).expect_err("data is cut").to_string();
    assert!(message.contains(&path.display().to_string()), "{message}");
    assert!(message.contains("data at point 7 (byte 91)"), "{message}");
}

/// Arbitrary and damaged files: neither parser panics, and what a parse
/// returns is bounded by the bytes given, so no header can make it
/// allocate for points the file does not hold. A few thousand cases by
/// default; set PROPTEST_CASES for more.
mod damaged_files {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::Config;

    fn config() -> Config {
        let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(3000);
        Config { cases, failure_persistence: None, ..Config::default() }
    }

    /// Valid files of every kind the parsers read, to damage.
    fn originals() -> Vec<(&'static str, Vec<u8>)> {
        let cloud = grid(6, 4);
        let mixed_pcd = "VERSION 0.7\nFIELDS intensity x y z normal\nSIZE 1 8 8 8 4\nTYPE U F F F F\n\
                         COUNT 1 1 1 1 3\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n7 1 2 3 0 0 1\n8 4 5 6 0 1 0\n";
        let mesh_ply = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n\
                        element vertex 3\nproperty double x\nproperty float y\nproperty float z\n\
                        property uchar red\nend_header\n3 0 1 2\n1 2 3 9\n4 5 6 9\n7 8 9 9\n";
        vec![
            ("frame.pcd", encoded(|out| pcd::write_binary(&cloud, out))),
            ("frame.pcd", encoded(|out| pcd::write_ascii(&cloud, out))),
            ("mixed.pcd", mixed_pcd.as_bytes().to_vec()),
            ("compressed.pcd", encoded(|out| pcd::write_binary_compressed(&cloud, out))),
            ("part.ply", encoded(|out| ply::write_binary_le(&cloud, out))),
            ("part.ply", encoded(|out| ply::write_ascii(&cloud, out))),
            ("mesh.ply", mesh_ply.as_bytes().to_vec()),
        ]
    }

    /// Parses `bytes` as `name`'s format and checks the bound.
    fn parse_checked(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
        let path = Path::new(name);
        let parsed = if name.ends_with(".pcd") { pcd::parse(bytes, path) } else { ply::parse(bytes, path) };
        if let Ok(cloud) = parsed {
            if bytes.windows(24).any(|w| w == b"DATA binary_compressed\n") {
                // 12 or more bytes a point, LZF-compressed: LZF expands at
                // most 88 times.
                prop_assert!(
                    cloud.len() * 12 <= bytes.len() * 88,
                    "{} points from {} compressed bytes",
                    cloud.len(),
                    bytes.len()
                );
            } else {
                // Every point takes at least five bytes ("1 2 3" in ascii, 12
                // bytes in binary), so a cloud is never larger than that.
                prop_assert!(
                    cloud.len() * 5 <= bytes.len(),
                    "{} points from {} bytes of {name}",
                    cloud.len(),
                    bytes.len()
                );
            }
        }
        Ok(())
    }

    /// One edit of a file: the offset as a fraction of its length.
    #[derive(Debug, Clone)]
    enum Edit {
        Replace(f64, u8),
        Insert(f64, Vec<u8>),
        Delete(f64, usize),
        Truncate(f64),
        /// A number in the header replaced by one of the extremes a
        /// corrupt header carries.
        Number(f64, &'static str),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        let at = 0.0..1.0f64;
        let extreme = prop::sample::select(vec!["0", "-1", "4294967296", "18446744073709551615", "1e309", "nan"]);
        prop_oneof![
            (at.clone(), any::<u8>()).prop_map(|(a, b)| Edit::Replace(a, b)),
            (at.clone(), prop::collection::vec(any::<u8>(), 1..8)).prop_map(|(a, b)| Edit::Insert(a, b)),
            (at.clone(), 1..16usize).prop_map(|(a, n)| Edit::Delete(a, n)),
            at.clone().prop_map(Edit::Truncate),
            (at, extreme).prop_map(|(a, n)| Edit::Number(a, n)),
        ]
    }

    fn apply(bytes: &mut Vec<u8>, edit: &Edit) {
        let at = |f: f64, len: usize| ((f * len as f64) as usize).min(len);
        match edit {
            Edit::Replace(f, b) => {
                if !bytes.is_empty() {
                    let i = at(*f, bytes.len() - 1);
                    bytes[i] = *b;
                }
            }
            Edit::Insert(f, new) => {
                let i = at(*f, bytes.len());
                bytes.splice(i..i, new.iter().copied());
            }
            Edit::Delete(f, n) => {
                let i = at(*f, bytes.len());
                bytes.drain(i..(i + n).min(bytes.len()));
            }
            Edit::Truncate(f) => bytes.truncate(at(*f, bytes.len())),
            Edit::Number(f, text) => {
                // The first run of digits at or after the offset.
                let from = at(*f, bytes.len());
                if let Some(start) = bytes[from..].iter().position(u8::is_ascii_digit).map(|p| p + from) {
                    let end = start + bytes[start..].iter().take_while(|b| b.is_ascii_digit()).count();
                    bytes.splice(start..end, text.bytes());
                }
            }
        }
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..1024), ply_magic in any::<bool>()) {
            // Half the cases start like a file, so the parsers get past the
            // first line.
            let mut file = if ply_magic { b"ply\nformat ascii 1.0\n".to_vec() } else { b"VERSION 0.7\nFIELDS x y z\n".to_vec() };
            file.extend(&bytes);
            // A complete compressed header, so the bytes reach the sizes
            // and the LZF decoder.
            let mut compressed = b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4\nHEIGHT 3\nDATA binary_compressed\n".to_vec();
            compressed.extend(&bytes);
            for name in ["any.pcd", "any.ply"] {
                parse_checked(name, &bytes)?;
                parse_checked(name, &file)?;
            }
            parse_checked("any.pcd", &compressed)?;
        }

        #[test]
        fn damaged_files_never_panic(original in 0..7usize, edits in prop::collection::vec(edit(), 1..6)) {
            let (name, mut bytes) = originals().swap_remove(original);
            for e in &edits {
                apply(&mut bytes, e);
            }
            parse_checked(name, &bytes)?;
        }
    }
}

/// Every PCD writer's output reads back as the cloud written, organized
/// or not, holes and all.
mod pcd_round_trips {
    use super::*;
    use proptest::prelude::*;

    fn coordinate() -> impl Strategy<Value = f32> {
        prop_oneof![Just(f32::NAN), -3000.0f32..3000.0, any::<f32>().prop_filter("finite", |v| v.is_finite())]
    }

    fn point() -> impl Strategy<Value = Point> {
        [coordinate(), coordinate(), coordinate()]
    }

    fn organized() -> impl Strategy<Value = PointCloud> {
        (2..12usize, 2..9usize).prop_flat_map(|(width, height)| {
            prop::collection::vec(point(), width * height)
                .prop_map(move |points| PointCloud::organized(width, height, points).expect("size matches"))
        })
    }

    fn unorganized() -> impl Strategy<Value = PointCloud> {
        prop::collection::vec(point(), 0..200).prop_map(PointCloud::unorganized)
    }

    type Writer = fn(&PointCloud, &mut Vec<u8>) -> std::io::Result<()>;

    fn check(cloud: &PointCloud) -> Result<(), TestCaseError> {
        let writers: [(&str, Writer); 3] = [
            ("binary_compressed", |c, out| pcd::write_binary_compressed(c, out)),
            ("binary", |c, out| pcd::write_binary(c, out)),
            ("ascii", |c, out| pcd::write_ascii(c, out)),
        ];
        for (kind, write) in writers {
            let bytes = encoded(|out| write(cloud, out));
            let back =
                pcd::parse(&bytes, Path::new("round.pcd")).map_err(|e| TestCaseError::fail(format!("{kind}: {e}")))?;
            prop_assert_eq!(
                (back.width(), back.height(), back.is_organized()),
                (cloud.width(), cloud.height(), cloud.is_organized()),
                "{}",
                kind
            );
            prop_assert!(same_points(back.points(), cloud.points()), "{}", kind);
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn organized_clouds_survive_every_writer(cloud in organized()) {
            check(&cloud)?;
        }

        #[test]
        fn unorganized_clouds_survive_every_writer(cloud in unorganized()) {
            check(&cloud)?;
        }
    }
}
