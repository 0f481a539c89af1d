//! Loading clouds from disk through `cloud::load`: dispatch by extension,
//! both formats, and errors that name the file.

use std::path::Path;
use std::time::Instant;

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
    for (name, bytes) in [("frame.pcd", binary), ("frame_ascii.PCD", ascii)] {
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

/// Timing probe for a full 1920x1200 camera frame; run it in release with
/// `--ignored --nocapture`. It prints rather than asserts: timings depend
/// on the machine.
#[test]
#[ignore]
fn full_frame_binary_pcd_parse_time() {
    let bytes = encoded(|out| pcd::write_binary(&grid(1920, 1200), out));
    let mut fastest = f64::INFINITY;
    for _ in 0..20 {
        let start = Instant::now();
        let cloud = pcd::parse(&bytes, Path::new("frame.pcd")).expect("valid frame");
        fastest = fastest.min(start.elapsed().as_secs_f64());
        assert_eq!(cloud.len(), 1920 * 1200);
    }
    println!("1920x1200 binary PCD ({} bytes): fastest parse {:.2} ms", bytes.len(), fastest * 1e3);
}
