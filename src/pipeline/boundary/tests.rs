//! Boundary sampling on constructed grids and clouds.

use super::*;
use crate::cloud::PointCloud;
use crate::geometry::fit::Plane;
use crate::geometry::vec3;

use super::band::MEMBERS_PER_CHUNK;
use super::scattered::{on_plane_for_scatter, percentile_99};

use crate::camera::CameraModel;
use nalgebra::Vector2;

#[test]
fn a_plate_is_seen_beside_an_edge_along_the_stretch_its_points_reach() {
    // Points on a 1 mm grid beside an edge along x at y = 0 (outward
    // +y), from x = 10 to 40 and 3 to 6 mm out; others farther out,
    // behind the edge, or past its span.
    let mut points: Vec<crate::cloud::Point> = Vec::new();
    for x in 0..60 {
        for y in -5..20 {
            points.push([x as f32 + 0.5, y as f32 + 0.5, 600.0]);
        }
    }
    let members: Vec<u32> = (0..points.len() as u32)
        .filter(|&i| {
            let [x, y, _] = points[i as usize];
            ((10.0..40.0).contains(&x) && (3.0..6.0).contains(&y)) || !(0.0..=12.0).contains(&y)
        })
        .collect();
    let cloud = PointCloud::unorganized(points);
    let edge = CoarseEdge { point: Vec3::new(0.0, 0.0, 600.0), direction: Vec3::x(), outward: Vec3::y() };
    let spanned = SpannedEdge { edge, span: [0.0, 50.0] };
    let seen = stretch_seen_beside(&cloud, &[&members], &[spanned], [8.0, 2.0, 1.0]);
    assert_eq!(seen, vec![30.0]);
    // None within a band too narrow to reach them.
    assert_eq!(stretch_seen_beside(&cloud, &[&members], &[spanned], [2.0, 2.0, 1.0]), vec![0.0]);
}

/// Slope of the test edge: slanted so the rows see every sub-pixel phase.
const SLOPE: f64 = 0.1;

/// A frontal plate at 700 mm whose edge is the line x = `edge_x` + SLOPE y,
/// ending at y = `end_y`; beyond it the table 40 mm further away.
fn frame(edge_x: f64, end_y: f64) -> (PointCloud, Vec<u32>) {
    frontal_frame(
        |x, y| x < edge_x + SLOPE * y && y < end_y,
        // The plate minus an eroded 1 mm band, as the plane criterion leaves it.
        |x, y| x < edge_x + SLOPE * y - 1.0 && y < end_y - 1.0,
    )
}

/// An 80 x 80 pixel frame round the optical axis: a frontal plate at
/// 700 mm where `on_plate(x, y)` (x and y at 700 mm), the table 40 mm
/// behind it elsewhere, and the plate's members where `member(x, y)`.
fn frontal_frame(on_plate: impl Fn(f64, f64) -> bool, member: impl Fn(f64, f64) -> bool) -> (PointCloud, Vec<u32>) {
    let camera = CameraModel::default();
    let (w, h) = (80, 80);
    let mut pts = Vec::new();
    let mut members = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let r = camera.ray(camera.cx() - 40.0 + col as f64, camera.cy() - 40.0 + row as f64);
            let (x, y) = (r[0] * 700.0, r[1] * 700.0);
            let z = if on_plate(x, y) { 700.0 } else { 740.0 };
            if member(x, y) {
                members.push((row * w + col) as u32);
            }
            pts.push([(r[0] * z) as f32, (r[1] * z) as f32, z as f32]);
        }
    }
    (PointCloud::organized(w, h, pts).unwrap(), members)
}

#[test]
fn samples_lie_on_the_true_edge_within_a_quarter_pixel() {
    let edge_x = 3.1;
    let (cloud, members) = frame(edge_x, 1e9);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(edge_x - 1.2, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
    let samples = sample_boundary(&cloud, &members, &plane, &edge, &params).samples;
    assert_eq!(samples.len(), 80);
    let pixel = 700.0 / CameraModel::default().fx();
    // Signed distance of each sample from the true edge line, across it.
    let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x;
    let mean = samples.iter().map(|s| offset(&s.position)).sum::<f64>() / samples.len() as f64;
    let worst = samples.iter().map(|s| offset(&s.position).abs()).fold(0.0, f64::max);
    assert!(mean.abs() < 0.1 * pixel, "mean offset {mean} mm");
    assert!(worst < 0.6 * pixel, "worst offset {worst} mm");
}

/// A frontal plate at 700 mm as [`frame`] draws it (no end), its pixels
/// `shift` columns off the image's centre; past its edge, the surface the
/// ray through (x, y) at 700 mm meets is `beyond(x, y)` mm from the
/// camera; and on each row the plate's last pixel and the first pixel
/// beyond mixed as `mixed(row)` says: each `Some(t)` a blend `t` of the
/// way from its own depth to the other's, along its ray, as a depth
/// camera returns one.
fn frame_with(
    edge_x: f64,
    shift: f64,
    beyond: impl Fn(f64, f64) -> f64,
    mixed: impl Fn(usize) -> [Option<f64>; 2],
) -> (PointCloud, Vec<u32>) {
    let camera = CameraModel::default();
    let (w, h) = (80, 80);
    let mut pts = vec![[0.0f32; 3]; w * h];
    let mut members = Vec::new();
    for row in 0..h {
        let ray = |col: usize| camera.ray(camera.cx() - 40.0 + shift + col as f64, camera.cy() - 40.0 + row as f64);
        let depth = |col: usize| {
            let r = ray(col);
            let (x, y) = (r[0] * 700.0, r[1] * 700.0);
            if x < edge_x + SLOPE * y { 700.0 } else { beyond(x, y) }
        };
        let last = (0..w).take_while(|&col| depth(col) == 700.0).last().unwrap();
        let [plate_side, beyond_side] = mixed(row);
        for col in 0..w {
            let mut z = depth(col);
            if col == last
                && let Some(t) = plate_side
            {
                z += t * (depth(last + 1) - z);
            }
            if col == last + 1
                && let Some(t) = beyond_side
            {
                z += t * (depth(last) - z);
            }
            let r = ray(col);
            if depth(col) == 700.0 && (r[0] * 700.0) < edge_x + SLOPE * (r[1] * 700.0) - 1.0 {
                members.push((row * w + col) as u32);
            }
            pts[row * w + col] = [(r[0] * z) as f32, (r[1] * z) as f32, z as f32];
        }
    }
    (PointCloud::organized(w, h, pts).unwrap(), members)
}

/// The samples' mean and worst offset from the edge x = `edge_x` + SLOPE y
/// of [`frame_with`]'s plate, in pixels.
fn offsets_in_pixels(cloud: &PointCloud, members: &[u32], edge_x: f64) -> (f64, f64) {
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(edge_x - 1.2, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
    let samples = sample_boundary(cloud, members, &plane, &edge, &params).samples;
    assert_eq!(samples.len(), 80);
    let pixel = 700.0 / CameraModel::default().fx();
    let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x / pixel;
    let mean = samples.iter().map(|s| offset(&s.position)).sum::<f64>() / samples.len() as f64;
    (mean, samples.iter().map(|s| offset(&s.position).abs()).fold(0.0, f64::max))
}

#[test]
fn mixed_pixels_at_the_edge_neither_widen_nor_narrow_a_gap_seen_through() {
    // The table 40 mm beyond; the rows take turns: no mixed pixel, the
    // plate's last one mixed, the first one beyond mixed, both, each
    // blended a quarter to three quarters of the way.
    let blend = |row: usize| 0.25 + 0.5 * ((row * 7) % 11) as f64 / 10.0;
    let mixed = |row: usize| match row % 4 {
        0 => [None, None],
        1 => [Some(blend(row)), None],
        2 => [None, Some(blend(row))],
        _ => [Some(blend(row)), Some(blend(row + 1))],
    };
    let (cloud, members) = frame_with(3.1, 0.0, |_, _| 740.0, mixed);
    let (mean, worst) = offsets_in_pixels(&cloud, &members, 3.1);
    // Stopping at the first mixed pixel reads the plate's end a pixel
    // short on half the rows: half a pixel on average.
    assert!(mean.abs() < 0.1, "mean offset {mean} pixels");
    assert!(worst < 1.1, "worst offset {worst} pixels");
}

#[test]
fn a_face_beyond_the_edge_is_no_mixture_and_the_plate_ends_before_it() {
    // A bevel going down from the edge at 60 degrees to the plate (1.7 mm
    // deeper per mm out), to the table 40 mm beyond: its pixels lie on a
    // surface. The walk takes those within the on-plane tolerance (0.4 mm,
    // 0.24 mm out) for the plate, and ends half a pixel past the last.
    let bevel = |x: f64, y: f64| (700.0 + 1.7 * (x - 3.1 - SLOPE * y)).min(740.0);
    let (cloud, members) = frame_with(3.1, 0.0, bevel, |_| [None, None]);
    let (mean, worst) = offsets_in_pixels(&cloud, &members, 3.1 + 0.4 / 1.7);
    assert!(mean.abs() < 0.1, "mean offset {mean} pixels");
    assert!(worst < 0.6, "worst offset {worst} pixels");
}

#[test]
fn a_face_the_camera_sees_below_the_edge_is_no_mixture() {
    // A 6 mm plate 35 mm left of the optical axis on a lower plate: the
    // rays run inward as they go down (about 0.05 mm per mm), so the
    // plate's edge face is seen across one or two pixels, each between
    // the two plates as a mixed pixel would be, but on the face: the
    // plate ends half a pixel past its last pixel on top.
    let edge_x = -35.0;
    let face_or_floor = |x: f64, y: f64| (700.0 * (edge_x + SLOPE * y) / x).min(706.0);
    let shift = edge_x * CameraModel::default().fx() / 700.0;
    let (cloud, members) = frame_with(edge_x, shift, face_or_floor, |_| [None, None]);
    let (mean, worst) = offsets_in_pixels(&cloud, &members, edge_x);
    assert!(mean.abs() < 0.1, "mean offset {mean} pixels");
    assert!(worst < 0.6, "worst offset {worst} pixels");
}

#[test]
fn walks_out_through_a_plate_end_the_scan_lines_cross_obliquely_are_no_edge_samples() {
    // A square-cornered plate whose edge runs 22 degrees off the image's
    // columns, so its end, square to the edge, crosses the scan lines
    // (rows) obliquely: the last rows before the corner walk out through
    // the end, short of the edge by up to the band's width.
    let (slope, corner) = (0.4, Vec3::new(3.1, 2.0, 700.0));
    let direction = Vec3::new(slope, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -slope, 0.0).normalize();
    let at = |x: f64, y: f64| {
        let at = Vec3::new(x, y, 700.0) - corner;
        (at.dot(&outward), at.dot(&direction))
    };
    let (cloud, members) =
        frontal_frame(|x, y| at(x, y).0 < 0.0 && at(x, y).1 < 0.0, |x, y| at(x, y).0 < -1.0 && at(x, y).1 < -1.0);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let edge = CoarseEdge { point: corner - outward * 1.2 - direction * 5.0, direction, outward };
    let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
    let boundary = sample_boundary(&cloud, &members, &plane, &edge, &params);
    let pixel = 700.0 / CameraModel::default().fx();
    // Within a pixel: the walk through the end nearest the corner ends
    // within a pixel of the edge, and its sample runs along the edge.
    let offset = |s: &BoundarySample| (s.position - corner).dot(&outward) / pixel;
    let worst = boundary.samples.iter().map(|s| offset(s).abs()).fold(0.0, f64::max);
    assert!(worst < 1.0, "worst offset {worst} pixels");
    assert!(!boundary.across_other_edge.is_empty());
    // The walks through the end still show how far the plate reaches: to
    // the corner, half a scan line at most.
    let (_, reach) = boundary.extent(|s| (s.position - corner).dot(&direction)).unwrap();
    assert!(reach.abs() < pixel, "reaches {reach} mm past the corner");
}

#[test]
fn the_band_alone_gives_the_plates_samples_and_extremes() {
    let (cloud, members) = frame(3.1, 2.0);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(2.0, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
    let near = band_members(&cloud, &members, &edge, params.band_mm);
    assert!(!near.is_empty() && near.len() < members.len() / 2, "{} of {}", near.len(), members.len());
    assert!(near.windows(2).all(|w| w[0] < w[1]), "the band keeps the members' order");
    let all = sample_boundary(&cloud, &members, &plane, &edge, &params);
    let band = sample_boundary(&cloud, &near, &plane, &edge, &params);
    assert_eq!(all.samples.len(), band.samples.len());
    assert!(all.samples.iter().zip(&band.samples).all(|(a, b)| a.position == b.position));
    assert_eq!(all.line_spacing_mm, band.line_spacing_mm);
    assert_eq!(
        members_along(&cloud, &members, &edge, params.band_mm),
        members_along(&cloud, &near, &edge, params.band_mm)
    );
}

#[test]
fn samples_reach_the_plate_corner() {
    let end_y = 2.0;
    let (cloud, members) = frame(3.1, end_y);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(2.0, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
    let boundary = sample_boundary(&cloud, &members, &plane, &edge, &params);
    let last = boundary.samples.iter().map(|s| s.position.y).fold(f64::MIN, f64::max);
    let pixel = 700.0 / CameraModel::default().fy();
    assert!(last > end_y - 1.01 * pixel && last < end_y, "last sample at y = {last}, plate ends at {end_y}");
    // Half a scan line beyond the last sample is the unbiased end.
    let (_, end) = boundary.extent(|s| s.position.y).unwrap();
    assert!((end - end_y).abs() < 0.55 * pixel, "extent ends at {end}, plate at {end_y}");
}

/// A plate of points about `spacing` apart (a jittered square grid,
/// as voxel centroids lie) whose edge is x = `edge_x` + SLOPE y, and a
/// coplanar plate beyond a `gap` wide gap.
fn scattered(spacing: f64, edge_x: f64, gap: f64) -> PointCloud {
    scattered_where(spacing, |x, y| {
        let edge = edge_x + SLOPE * y;
        x < edge || x > edge + gap
    })
}

/// Jittered grid points about `spacing` apart where `keep(x, y)`.
fn scattered_where(spacing: f64, keep: impl Fn(f64, f64) -> bool) -> PointCloud {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut jitter = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.5 * spacing
    };
    let mut points = Vec::new();
    let n = (60.0 / spacing) as i64;
    for row in -n..=n {
        for col in -n..=n {
            let (x, y) = (col as f64 * spacing + jitter(), row as f64 * spacing + jitter());
            if keep(x, y) {
                points.push([x as f32, y as f32, 700.0]);
            }
        }
    }
    PointCloud::unorganized(points)
}

#[test]
fn scattered_samples_lie_on_the_true_edge_within_a_fifth_of_the_spacing() {
    let (spacing, edge_x) = (1.0, 3.3);
    let cloud = scattered(spacing, edge_x, 2.0);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
    let boundary = sample_scattered(&cloud, &plane, &edge, &params, spacing, None);
    assert!(boundary.samples.len() > 50, "{} samples", boundary.samples.len());
    let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x;
    // Away from the plate's ends, where the last strips hold only part
    // of a row and sample the plate's end rather than its side.
    let offsets: Vec<f64> =
        boundary.samples.iter().filter(|s| s.position.y.abs() < 57.0).map(|s| offset(&s.position)).collect();
    let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
    assert!(mean.abs() < 0.2 * spacing, "mean offset {mean} mm");
    let worst = offsets.iter().map(|o| o.abs()).fold(0.0, f64::max);
    assert!(worst < spacing, "a sample {worst} mm off the edge");
}

/// [`scattered`] with depth noise of `sigma` mm (normal, from a fixed
/// seed) on every point, as a consumer depth camera's voxel clouds have.
fn noisy_scattered(spacing: f64, edge_x: f64, gap: f64, sigma: f64) -> PointCloud {
    let mut random = crate::sim::noise::RowRandom::new(0x5ca7, 0);
    let points = scattered(spacing, edge_x, gap)
        .points()
        .iter()
        .map(|p| [p[0], p[1], (f64::from(p[2]) + sigma * random.gaussian()) as f32])
        .collect();
    PointCloud::unorganized(points)
}

#[test]
fn a_noisy_plate_s_edge_is_read_further_out_once_its_noise_is_measured() {
    // Noise of 0.8 mm against the 0.4 mm tolerance keeps 38 % of the
    // plate's points, and its outermost kept point lies rows in.
    let (spacing, edge_x, sigma) = (1.0, 3.3, 0.8);
    let cloud = noisy_scattered(spacing, edge_x, 4.0, sigma);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
    let scatter = plane_scatter(&cloud, &plane, &edge, &params, spacing).unwrap();
    assert!((scatter - sigma).abs() < 0.1 * sigma, "measured {scatter} mm, made {sigma} mm");
    let mean_offset = |scatter: Option<f64>| {
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, spacing, scatter);
        let offsets: Vec<f64> = boundary
            .samples
            .iter()
            .filter(|s| s.position.y.abs() < 50.0)
            .map(|s| (s.position.x - edge_x - SLOPE * s.position.y) * outward.x)
            .collect();
        assert!(offsets.len() > 30, "{} samples", offsets.len());
        offsets.iter().sum::<f64>() / offsets.len() as f64
    };
    let thinned = mean_offset(None);
    assert!(thinned < -0.6 * spacing, "unmeasured, the edge is read {thinned} mm out");
    // The correction takes back what thinning adds to the last gap
    // (1.11 to 0.77 mm here); the rest is the strips' walk stopping
    // at holes the thinned interior makes common, which it leaves.
    let measured = mean_offset(Some(scatter));
    assert!(measured > thinned + 0.25 * spacing && measured < 0.1 * spacing, "measured, read {measured} mm out");
    // Noise within the tolerance thins nothing: the samples stay put.
    assert_eq!(on_plane_for_scatter(0.4, Some(0.1)), 0.4);
    let quiet = scattered(spacing, edge_x, 4.0);
    let at = |scatter| sample_scattered(&quiet, &plane, &edge, &params, spacing, scatter).samples;
    let (known, unknown) = (at(Some(0.1)), at(None));
    assert!(known.iter().zip(&unknown).all(|(a, b)| a.position == b.position) && known.len() == unknown.len());
}

#[test]
fn scattered_samples_never_cross_to_the_plate_beyond_the_gap() {
    let cloud = scattered(1.0, 3.3, 1.5);
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(1.3, 0.0, 700.0), direction, outward };
    let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
    let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, None);
    let beyond = boundary.samples.iter().filter(|s| (s.position.x - 3.3 - SLOPE * s.position.y) > 1.0).count();
    assert_eq!(beyond, 0);
    assert!(!sample_scattered(&cloud, &plane, &edge, &params, f64::NAN, None).samples.iter().any(|_| true));
}

/// The band beside the test edge, and the edge 2 mm inside the plate.
fn test_edge(edge_x: f64) -> (Plane, CoarseEdge, BoundaryParams) {
    let plane = Plane { normal: Vec3::z(), offset: 700.0 };
    let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
    let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
    let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
    (plane, edge, BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 })
}

#[test]
fn scattered_plate_running_on_past_the_edge_has_no_boundary_there() {
    // A lap's lower plate: it ends at the upper plate's edge for y < 0
    // and runs on beyond the upper plate's end, y > 0.
    let edge_x = 3.3;
    let cloud = scattered_where(1.0, |x, y| y > 0.0 || x < edge_x + SLOPE * y || x > edge_x + SLOPE * y + 20.0);
    let (plane, edge, params) = test_edge(edge_x);
    let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, None);
    assert!(boundary.samples.len() > 20, "{} samples", boundary.samples.len());
    let (_, end) = boundary.extent(|s| s.position.y).unwrap();
    assert!(end < 2.5, "the edge is seen up to y = {end} mm, where the plate runs on");
}

#[test]
fn scattered_gap_narrower_than_the_spacing_is_no_edge() {
    // Two coplanar plates 0.3 spacings apart: the cloud cannot show the
    // gap, and no strip may claim to.
    let cloud = scattered(1.0, 3.3, 0.3);
    let (plane, edge, params) = test_edge(3.3);
    // A point that happens to fall into the gap is lost, as a camera
    // loses it, and leaves a chance hole here and there; the edge is
    // seen along a small part of the plate only, which is what the
    // planner's coverage gate refuses.
    let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, None);
    let seen = coverage(&boundary, |s| s.along, -55.0, 55.0);
    assert!(seen < 0.5, "the edge is claimed along {:.0} % of the plate across a 0.3 mm gap", 100.0 * seen);
    // The same plates 2 mm apart: the edge is seen nearly everywhere.
    let cloud = scattered(1.0, 3.3, 2.0);
    let seen = coverage(&sample_scattered(&cloud, &plane, &edge, &params, 1.0, None), |s| s.along, -55.0, 55.0);
    assert!(seen > 0.9, "the edge of a 2 mm gap is seen along {:.0} % of the plate", 100.0 * seen);
}

/// The far end along y of the strips' extent of the plate beside the
/// test edge, and of the same refined along the rim of the true edge
/// (the line a fit of the samples gives).
fn strip_and_rim_ends(cloud: &PointCloud, edge_x: f64) -> (f64, f64) {
    let (plane, coarse, params) = test_edge(edge_x);
    let strips = sample_scattered(cloud, &plane, &coarse, &params, 1.0, None).extent(|s| s.position.y).unwrap();
    let fitted = CoarseEdge { point: Vec3::new(edge_x, 0.0, 700.0), ..coarse };
    let rim = rim_refined_extent(cloud, &plane, &fitted, &params, 1.0, 0.0, |p: &Vec3| p.y, strips);
    (strips.1, rim.1)
}

/// The plate of [`test_edge`] cut by a straight cloud border (the image
/// border or a crop) that crosses its edge at y = 20 mm, obliquely:
/// a point `d` inside the edge is kept up to y = 20 - `lean` d / 0.8.
fn plate_cut_by_a_border(edge_x: f64, lean: f64) -> PointCloud {
    scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < 20.0 - SLOPE * 20.0 * lean + lean * (x - edge_x))
}

#[test]
fn the_rim_reaches_a_border_that_cuts_the_band_inside_the_plate() {
    // Beyond y = 10 the border has cut the band's inner side away and
    // left the plate's rim up to where it crosses the edge, y = 20:
    // the strips there start outside the coarse edge and are dropped.
    // The rim's rows, 0.5 to 1.5 mm inside the edge, meet the border
    // at y = 18.75 to 16.25: the rule reads the end to that, no better.
    // `seam.end_read_from_plate_rim` fires: the end moves out to the rim's.
    let (strips, rim) = strip_and_rim_ends(&plate_cut_by_a_border(3.3, 2.0), 3.3);
    assert!((16.25..=19.25).contains(&rim), "the rim reaches y = {rim} mm, the plate is seen up to 20");
    assert!(20.0 - strips > 20.0 - rim + 1.0, "the strips reach y = {strips} mm, the rim {rim}");
}

#[test]
fn the_rim_stops_where_a_border_cuts_the_edge_away() {
    // Beyond y = 20 the border has cut the edge away and left the
    // plate's inside up to y = 27.5 (the band's inner side): strips
    // that stop at the border take it for the plate's end.
    // The rim's rows meet the border at y = 20.6 to 21.9.
    // `seam.end_read_from_plate_rim` fires: the end moves in to the rim's.
    let (strips, rim) = strip_and_rim_ends(&plate_cut_by_a_border(3.3, -1.0), 3.3);
    assert!((20.6..=22.4).contains(&rim), "the rim reaches y = {rim} mm, the edge is seen up to 20");
    assert!(strips - 20.0 > rim - 20.0 + 1.0, "the strips reach y = {strips} mm, the rim {rim}");
}

#[test]
fn the_rim_reaches_the_plate_corner_and_not_the_foot_of_a_face_beyond() {
    // The plate ends at y = 20; beyond, along the edge line, lie only
    // points on the edge itself at the plate's height, as the foot of
    // a lap's upper plate leaves them beyond the lower plate's end.
    let edge_x = 3.3;
    let cloud = scattered_where(1.0, |x, y| {
        let edge = edge_x + SLOPE * y;
        (x < edge && y < 20.0) || (y >= 20.0 && (x - edge).abs() < 0.2)
    });
    let (_, rim) = strip_and_rim_ends(&cloud, edge_x);
    assert!((rim - 20.0).abs() < 0.5, "the rim reaches y = {rim} mm, the plate ends at 20");
}

#[test]
fn past_a_plate_end_where_the_table_is_seen_the_strips_keep_the_end() {
    // The plate ends at y = 20 and the table, 40 mm further away, is
    // seen beyond: the plate's own end, which the strips read; the rim
    // is the cloud's border's witness only.
    let edge_x = 3.3;
    let plate = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < 20.0);
    let table = scattered_where(1.0, |_, y| y >= 20.0);
    let mut points = plate.points().to_vec();
    points.extend(table.points().iter().map(|p| [p[0] * 740.0 / 700.0, p[1] * 740.0 / 700.0, 740.0]));
    let cloud = PointCloud::unorganized(points);
    let (plane, coarse, params) = test_edge(edge_x);
    let strips = sample_scattered(&cloud, &plane, &coarse, &params, 1.0, None).extent(|s| s.position.y).unwrap();
    let fitted = CoarseEdge { point: Vec3::new(edge_x, 0.0, 700.0), ..coarse };
    let refined = rim_refined_extent(&cloud, &plane, &fitted, &params, 1.0, 0.0, |p: &Vec3| p.y, strips);
    assert_eq!(refined.1, strips.1);
    // The same plate with nothing beyond: the cloud ends with it.
    let (strips_end, rim_end) = strip_and_rim_ends(&plate, edge_x);
    assert!((rim_end - 20.0).abs() < 0.5 && rim_end != strips_end, "rim {rim_end}, strips {strips_end}");
}

/// A square lattice of points `pitch` apart (voxel centroids of a
/// plate), its rows turned `turn` radians from the test edge and
/// shifted `shift` of a pitch across it, kept where `keep(x, y)`.
fn lattice_where(pitch: f64, turn: f64, shift: f64, keep: impl Fn(f64, f64) -> bool) -> PointCloud {
    let angle = SLOPE.atan() + turn;
    let (along, across) = (Vector2::new(angle.sin(), angle.cos()), Vector2::new(angle.cos(), -angle.sin()));
    let n = (80.0 / pitch) as i64;
    let points = (-n..=n)
        .flat_map(|i| (-n..=n).map(move |j| (i, j)))
        .map(|(i, j)| across * ((i as f64 + shift) * pitch) + along * (j as f64 * pitch))
        .filter(|p| keep(p.x, p.y))
        .map(|p| [p.x as f32, p.y as f32, 700.0])
        .collect();
    PointCloud::unorganized(points)
}

#[test]
fn the_rim_reaches_the_end_of_a_lattice_whose_rows_miss_the_rim_rows() {
    // Voxel centroids lie on a lattice whose pitch can exceed the
    // measured spacing: with the spacing taken as 1 mm and a pitch of
    // 1.15 mm, the rim's rows (0.5 to 1.5 mm inside the edge) hold no
    // lattice row for a stretch wherever two rows straddle them. The
    // plate ends at y = 20 with nothing beyond: wherever its rows lie,
    // the rim reads that end within the lattice's pitch.
    let edge_x = 3.3;
    let mut worst: f64 = 0.0;
    for turn in [0.01, 0.03, -0.02] {
        for k in 0..8 {
            let cloud = lattice_where(1.15, turn, k as f64 / 8.0, |x, y| x < edge_x + SLOPE * y && y < 20.0);
            let (_, rim) = strip_and_rim_ends(&cloud, edge_x);
            worst = worst.max((rim - 20.0).abs());
        }
    }
    assert!(worst < 0.8, "the rim's end is {worst:.2} mm from the plate's");
}

#[test]
fn a_rim_that_loses_its_points_to_noise_short_of_the_border_keeps_the_strips_end() {
    // The cloud ends at y = 20 across the whole band, but the last
    // 2.5 mm of the rows lie off the plane (a noisy camera near its
    // image border): the rows' points stop short of the cloud's end,
    // and the strips, which read every row, see the end itself.
    let edge_x = 3.3;
    let plate = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < 20.0);
    let noisy = |p: &[f32; 3]| {
        let inside = f64::from(p[0]) - edge_x - SLOPE * f64::from(p[1]);
        f64::from(p[1]) > 17.5 && (-2.0..=0.0).contains(&inside)
    };
    let points = plate.points().iter().map(|p| if noisy(p) { [p[0], p[1], 699.0] } else { *p }).collect();
    let (strips, rim) = strip_and_rim_ends(&PointCloud::unorganized(points), edge_x);
    assert_eq!(rim, strips, "the rim's end replaced the strips' at {strips}");
    assert!((strips - 20.0).abs() < 1.1, "the strips end at {strips}, the cloud at 20");
}

#[test]
fn a_strip_holding_the_plate_corner_and_a_face_foot_beyond_ends_at_the_corner() {
    // The foot of a lap's upper plate runs on along the edge line past
    // the lower plate's end, its points on the line itself, outermost
    // in the corner strip: the sample keeps to where the plate is,
    // wherever the plate's end falls in its strip.
    let edge_x = 3.3;
    let (plane, coarse, params) = test_edge(edge_x);
    for end_y in (0..20).map(|k| 18.0 + 0.1 * k as f64) {
        let plate = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < end_y);
        let foot = (0..80).map(|k| end_y + 0.25 * k as f64).map(|y| [(edge_x + SLOPE * y) as f32, y as f32, 700.0]);
        let cloud = PointCloud::unorganized(plate.points().iter().copied().chain(foot).collect());
        let boundary = sample_scattered(&cloud, &plane, &coarse, &params, 1.0, None);
        let beyond = boundary.samples.iter().map(|s| s.position.y).fold(f64::MIN, f64::max);
        assert!(beyond < end_y + 0.1, "a boundary sample at y = {beyond} mm, past the plate's end at {end_y}");
    }
}

#[test]
fn an_edge_fitted_to_noisy_samples_keeps_the_strips_ends() {
    let cloud = plate_cut_by_a_border(3.3, 2.0);
    let (plane, coarse, params) = test_edge(3.3);
    let strips = sample_scattered(&cloud, &plane, &coarse, &params, 1.0, None).extent(|s| s.position.y).unwrap();
    let fitted = CoarseEdge { point: Vec3::new(3.3, 0.0, 700.0), ..coarse };
    let noisy = rim_refined_extent(&cloud, &plane, &fitted, &params, 1.0, 0.3, |p: &Vec3| p.y, strips);
    assert_eq!(noisy, strips);
}

#[test]
fn the_rim_trim_leaves_the_disc_fraction_the_criterion_asks() {
    // Half the disc is lost on the edge itself, none a radius inside.
    assert!(rim_trim_radii(0.5) < 1e-9);
    assert!((rim_trim_radii(1.0) - 1.0).abs() < 1e-9);
    // At the default 0.8 a point passes from about half a radius in.
    let d = rim_trim_radii(0.8);
    let cap = (d.acos() - d * (1.0 - d * d).sqrt()) / std::f64::consts::PI;
    assert!((cap - 0.2).abs() < 1e-9 && (0.45..0.55).contains(&d), "d = {d}, cap {cap}");
}

#[test]
fn pieces_join_a_plate_across_narrow_breaks_only() {
    // A streak's 2 mm break joins; a clamp's 30 mm does not, nor what
    // lies beyond it.
    let pieces = [(52.0, 80.0), (110.0, 150.0), (-40.0, -2.0)];
    assert_eq!(joined_extent((0.0, 50.0), &pieces, 4.0), (-40.0, 80.0));
    assert_eq!(joined_extent((0.0, 50.0), &[], 4.0), (0.0, 50.0));
    // Chains: each piece within reach of the one before.
    assert_eq!(joined_extent((0.0, 10.0), &[(23.0, 30.0), (12.0, 20.0)], 4.0), (0.0, 30.0));
}

#[test]
fn an_edge_standing_in_for_the_root_ends_the_seam_only_inside_the_view() {
    // `seam.end_at_image_border` for a lap: its upper edge over -100..90,
    // its lower edge over -93..95.
    let extents = [(-100.0, 90.0), (-93.0, 95.0)];
    // Both ends inside the view: the stretch both show.
    assert_eq!(seam_span(extents, [[false; 2]; 2]), (-93.0, 90.0));
    // The lower edge leaves the image at -93: the upper edge's end.
    assert_eq!(seam_span(extents, [[false; 2], [true, false]]), (-100.0, 90.0));
    // Leaving the image past the upper edge's end, it extends nothing.
    assert_eq!(seam_span(extents, [[false; 2], [false, true]]), (-93.0, 90.0));
    // With no edge left to end it, the stretch both show.
    assert_eq!(seam_span(extents, [[true, false], [true, false]]), (-93.0, 90.0));
}

#[test]
fn members_along_finds_the_plate_beside_the_edge() {
    let edge_x = 3.3;
    let cloud = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y.abs() < 30.0);
    let members: Vec<u32> = (0..cloud.len() as u32).collect();
    let (_, edge, params) = test_edge(edge_x);
    let [lo, hi] = members_along(&cloud, &members, &edge, params.band_mm).unwrap();
    assert!(lo.y > -30.0 && lo.y < -29.0 && hi.y < 30.0 && hi.y > 29.0, "{lo:?} {hi:?}");
    assert!(members_along(&cloud, &[], &edge, params.band_mm).is_none());
}

#[test]
fn the_plate_s_reach_along_an_edge_is_its_first_extreme_member_however_the_members_are_split() {
    // Members along y = 0..n in a band inside the edge x = 0 (outward
    // +x), three chunks' worth, with the extremes tied across chunks:
    // two members at the least y and two at the greatest, each pair a
    // chunk apart and told apart by x.
    let n = 3 * MEMBERS_PER_CHUNK;
    let mut pts: Vec<[f32; 3]> = (0..n).map(|i| [-0.5, 10.0 + i as f32 * 0.01, 700.0]).collect();
    let (lo, hi) = (5.0f32, 10.0 + n as f32 * 0.01);
    pts[7] = [-0.25, lo, 700.0];
    pts[7 + MEMBERS_PER_CHUNK] = [-0.75, lo, 700.0];
    pts[40] = [-0.25, hi, 700.0];
    pts[n - 3] = [-0.75, hi, 700.0];
    // A member outside the band, further along than all.
    pts[n - 1] = [0.5, 1000.0, 700.0];
    let cloud = PointCloud::unorganized(pts.clone());
    let edge = CoarseEdge { point: Vec3::new(0.0, 0.0, 700.0), direction: Vec3::y(), outward: Vec3::x() };
    let members: Vec<u32> = (0..n as u32).collect();
    let [back, forward] = members_along(&cloud, &members, &edge, 1.0).unwrap();
    assert_eq!((back, forward), (vec3(&pts[7]), vec3(&pts[40])));
    // The band keeps the members within a millimetre either side, in order.
    let band = band_members(&cloud, &members, &edge, 1.0);
    let expected: Vec<u32> = (0..n as u32).filter(|&i| pts[i as usize][0].abs() <= 1.0).collect();
    assert_eq!(band, expected);
}

#[test]
fn the_99th_percentile_is_the_value_a_sort_ranks_there() {
    assert_eq!(percentile_99(std::iter::empty()), None);
    for n in [1usize, 2, 99, 100, 101, 250, 4321] {
        // Repeats and a spread of magnitudes, in no order.
        let values: Vec<f64> =
            (0..n).map(|i| ((i * 7919) % 613) as f64 * if i % 5 == 0 { 10.0 } else { 0.01 }).collect();
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        let rank = (n * 99 / 100).min(n - 1);
        assert_eq!(percentile_99(values.iter().copied()), Some(sorted[rank]), "{n} values");
    }
}
