//! Tests of the index by blocks of pixels: every query against the index
//! by rays it stands in for and a scan of every point.

use proptest::prelude::*;

use super::super::rays::{RayIndex, ray_bounds};
use super::*;

/// The points strictly within `radius` of `centre`, sorted.
fn within(visit: impl FnOnce(&mut dyn FnMut(&[f32; 3])), centre: &Vec3, radius: f64) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    visit(&mut |p: &[f32; 3]| {
        if (Vec3::new(p[0].into(), p[1].into(), p[2].into()) - centre).norm_squared() < radius * radius {
            out.push(*p);
        }
    });
    out.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    out
}

/// A camera's organized view of two plates and a block over them, 250 to
/// 330 mm off, `width` pixels a row, with empty pixels here and there.
fn frame(width: usize, height: usize) -> Vec<[f32; 3]> {
    let mut points = Vec::new();
    for j in 0..height {
        for i in 0..width {
            let (u, v) = ((i as f64 - width as f64 / 2.0) * 0.0015, (j as f64 - height as f64 / 2.0) * 0.0015);
            let x_at_plate = u * 330.0;
            let z = if x_at_plate < 0.0 { 330.0 } else { 325.0 }
                - if (20.0..35.0).contains(&x_at_plate) { 40.0 } else { 0.0 }
                + 0.01 * ((i * 7 + j * 3) % 11) as f64;
            let empty = (i * 31 + j * 17) % 23 == 0;
            points.push(if empty { [f32::NAN; 3] } else { [(u * z) as f32, (v * z) as f32, z as f32] });
        }
    }
    points
}

#[test]
fn a_ball_finds_what_the_index_by_rays_and_a_scan_find() {
    let points = frame(203, 131);
    let blocks = BlockIndex::new(&points, 203);
    let rays = RayIndex::new(&points);
    let finite: Vec<[f32; 3]> = points.iter().filter(|p| p.iter().all(|c| c.is_finite())).copied().collect();
    let mut nonempty = 0;
    for (x, y, z, r) in [
        (0.0, 0.0, 320.0, 10.0),
        (27.0, -3.0, 285.0, 6.0),
        (27.0, -3.0, 250.0, 6.0),
        (-30.0, 20.0, 331.0, 1.5),
        (10.0, 0.0, 200.0, 30.0),
        (0.0, 0.0, 20.0, 25.0),
        (60.0, 0.0, 325.0, 4.0),
        (-49.0, -31.0, 330.0, 3.0),
    ] {
        let centre = Vec3::new(x, y, z);
        let by_blocks = within(|v| blocks.near(&centre, r, v), &centre, r);
        let by_rays = within(|v| rays.near(&centre, r, v), &centre, r);
        let by_scan = within(|v| finite.iter().for_each(v), &centre, r);
        nonempty += usize::from(!by_scan.is_empty());
        assert_eq!(by_blocks, by_rays, "ball at {centre:?}, {r} mm");
        assert_eq!(by_blocks, by_scan, "ball at {centre:?}, {r} mm");
    }
    assert!(nonempty >= 4, "the test must ask balls that hold points: {nonempty}");
}

/// A ball reads the patches whose boxes it meets, not the slab of
/// surface its window of rays and its ranges hold: in front of the
/// plates it reads nothing, and on them little beyond itself.
#[test]
fn a_ball_reads_little_beyond_itself() {
    let points = frame(203, 131);
    let blocks = BlockIndex::new(&points, 203);
    let read = |centre: &Vec3, r: f64| {
        let mut count = 0;
        blocks.near(centre, r, |_| count += 1);
        count
    };
    assert_eq!(read(&Vec3::new(0.0, 0.0, 300.0), 10.0), 0, "a ball in the air reads no point");
    // A ball reaching a millimetre into a plate, and one through it.
    for (depth, factor) in [(321.0, 4), (330.0, 2)] {
        let centre = Vec3::new(-20.0, 0.0, depth);
        let inside = within(|v| blocks.near(&centre, 10.0, v), &centre, 10.0).len();
        assert!(inside > 100, "the ball holds part of a plate: {inside}");
        let read = read(&centre, 10.0);
        assert!(read < factor * inside, "{read} points read for {inside} inside");
    }
}

#[test]
fn the_frame_bounds_and_the_nearest_other_point_are_the_index_by_rays() {
    let mut points = frame(150, 97);
    // A repeated point, a point at the camera's plane, one behind it and
    // one with an infinite coordinate.
    points[500] = points[501];
    points[900] = [0.5, 0.5, 0.5];
    points[901] = [-3.0, 2.0, -40.0];
    points[902] = [f32::INFINITY, 2.0, 300.0];
    let blocks = BlockIndex::new(&points, 150);
    let rays = RayIndex::new(&points);
    assert_eq!(blocks.ray_bounds(), ray_bounds(&points));
    for p in points.iter().step_by(37).chain([&points[501], &points[900]]) {
        if p.iter().all(|c| c.is_finite()) {
            assert_eq!(blocks.nearest_apart(p), rays.nearest_apart(p), "{p:?}");
        }
    }
    let empty = BlockIndex::new(&[], 10);
    assert_eq!(empty.nearest_apart(&[0.0, 0.0, 100.0]), (None, 0));
    assert_eq!(empty.ray_bounds().2, 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random organized frames (random depths on a random grid of rays,
    /// empty pixels among them), random balls.
    #[test]
    fn random_balls_agree_with_the_index_by_rays(
        width in 1usize..60,
        depths in proptest::collection::vec(prop_oneof![8 => 50f32..600.0, 1 => Just(f32::NAN), 1 => -20f32..1.5], 1..1500),
        step in 0.0005f64..0.02,
        balls in proptest::collection::vec((-200f64..200.0, -150f64..150.0, -20f64..600.0, 0.1f64..80.0), 1..8),
    ) {
        let height = depths.len().div_ceil(width);
        let points: Vec<[f32; 3]> = depths
            .iter()
            .enumerate()
            .map(|(k, &z)| {
                let (u, v) = ((k % width) as f64 - width as f64 / 2.0, (k / width) as f64 - height as f64 / 2.0);
                let z = f64::from(z);
                [(u * step * z.abs().max(1.0)) as f32, (v * step * z.abs().max(1.0)) as f32, z as f32]
            })
            .collect();
        let blocks = BlockIndex::new(&points, width);
        let rays = RayIndex::new(&points);
        prop_assert_eq!(blocks.ray_bounds(), ray_bounds(&points));
        for (x, y, z, r) in balls {
            let centre = Vec3::new(x, y, z);
            prop_assert_eq!(within(|v| blocks.near(&centre, r, v), &centre, r), within(|v| rays.near(&centre, r, v), &centre, r));
        }
        for p in points.iter().step_by(17).filter(|p| p.iter().all(|c| c.is_finite())) {
            prop_assert_eq!(blocks.nearest_apart(p), rays.nearest_apart(p));
        }
    }
}
