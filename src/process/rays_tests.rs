//! Tests of the index by rays: every query against a scan of every point.

use proptest::prelude::*;

use super::*;

/// The straightforward reference: the points strictly within `radius`.
fn within_by_scan(points: &[[f32; 3]], centre: &Vec3, radius: f64) -> Vec<[f32; 3]> {
    let mut out: Vec<[f32; 3]> = points
        .iter()
        .filter(|p| (Vec3::new(p[0].into(), p[1].into(), p[2].into()) - centre).norm_squared() < radius * radius)
        .copied()
        .collect();
    out.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    out
}

fn within_by_index(index: &RayIndex, centre: &Vec3, radius: f64) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    index.near(centre, radius, |p| {
        if (Vec3::new(p[0].into(), p[1].into(), p[2].into()) - centre).norm_squared() < radius * radius {
            out.push(*p);
        }
    });
    out.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    out
}

/// A camera's view of two plates and a block over them, 250 to 330 mm
/// off, with a few points at and behind the camera's plane.
fn scene() -> Vec<[f32; 3]> {
    let mut points = Vec::new();
    for i in 0..300 {
        for j in 0..200 {
            let (x, y) = (-60.0 + i as f32 * 0.4, -40.0 + j as f32 * 0.4);
            // Two plates 5 mm apart in depth, and a block 40 mm nearer.
            let z = if x < 0.0 { 330.0 } else { 325.0 } - if (20.0..35.0).contains(&x) { 40.0 } else { 0.0 };
            points.push([x, y, z + 0.01 * (i % 7) as f32]);
        }
    }
    points.extend([[5.0, 5.0, 0.5], [-3.0, 2.0, -40.0], [0.0, 0.0, 1.0]]);
    points
}

#[test]
fn a_ball_finds_what_a_scan_of_every_point_finds() {
    let points = scene();
    let index = RayIndex::new(&points);
    assert_eq!(index.binned().len() + index.aside.len(), points.len());
    let mut nonempty = 0;
    for (x, y, z, r) in [
        (0.0, 0.0, 320.0, 10.0),
        (27.0, -3.0, 285.0, 6.0),
        (27.0, -3.0, 250.0, 6.0),
        (-50.0, 30.0, 331.0, 1.5),
        (10.0, 0.0, 200.0, 30.0),
        (0.0, 0.0, 20.0, 25.0),
        (5.0, 5.0, 0.0, 2.0),
        (60.0, 0.0, 325.0, 4.0),
    ] {
        let centre = Vec3::new(x, y, z);
        let scan = within_by_scan(&points, &centre, r);
        nonempty += usize::from(!scan.is_empty());
        assert_eq!(within_by_index(&index, &centre, r), scan, "ball at {centre:?}, {r} mm");
    }
    assert!(nonempty >= 4, "the test must ask balls that hold points: {nonempty}");
}

#[test]
fn the_nearest_other_point_is_the_scans() {
    let mut points = scene();
    // Three copies of one point, and four of another.
    points.extend([[1.2, 1.2, 325.0]; 2]);
    points.extend([[-8.0, 4.0, 330.0]; 4]);
    let index = RayIndex::new(&points);
    for p in points.iter().step_by(997).chain(&[[1.2, 1.2, 325.0], [-8.0, 4.0, 330.0], [5.0, 5.0, 0.5]]) {
        let on = points.iter().filter(|q| *q == p).count();
        let best = points
            .iter()
            .map(|q| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2))
            .filter(|&d| d > 0.0)
            .fold(f32::INFINITY, f32::min);
        let expected = best.is_finite().then(|| f64::from(best).sqrt());
        assert_eq!(index.nearest_apart(p), (expected, on), "{p:?}");
    }
}

#[test]
fn clouds_without_area_or_points_are_indexed() {
    let one_ray: Vec<[f32; 3]> = (1..50).map(|k| [0.0, 0.0, 100.0 + k as f32]).collect();
    let index = RayIndex::new(&one_ray);
    let centre = Vec3::new(0.0, 0.0, 120.0);
    assert_eq!(within_by_index(&index, &centre, 3.5), within_by_scan(&one_ray, &centre, 3.5));
    assert_eq!(index.nearest_apart(&one_ray[10]), (Some(1.0), 1));
    let empty = RayIndex::new(&[]);
    assert_eq!(within_by_index(&empty, &centre, 10.0), Vec::<[f32; 3]>::new());
    assert_eq!(empty.nearest_apart(&[0.0, 0.0, 100.0]), (None, 0));
    let behind = [[1.0, 1.0, -5.0], [1.0, 2.0, -5.0]];
    let index = RayIndex::new(&behind);
    assert_eq!(
        within_by_index(&index, &Vec3::new(1.0, 1.5, -5.0), 1.0),
        within_by_scan(&behind, &Vec3::new(1.0, 1.5, -5.0), 1.0)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random clouds spread over the view and in depth, random balls.
    #[test]
    fn random_balls_agree_with_a_scan(
        points in proptest::collection::vec((-200f32..200.0, -150f32..150.0, -20f32..500.0), 1..600),
        balls in proptest::collection::vec((-200f64..200.0, -150f64..150.0, -20f64..500.0, 0.1f64..80.0), 1..8),
    ) {
        let points: Vec<[f32; 3]> = points.into_iter().map(|(x, y, z)| [x, y, z]).collect();
        let index = RayIndex::new(&points);
        for (x, y, z, r) in balls {
            let centre = Vec3::new(x, y, z);
            prop_assert_eq!(within_by_index(&index, &centre, r), within_by_scan(&points, &centre, r));
        }
    }
}
