//! Tests of the hidden space: a block on a table seen from above, the
//! grid against a scan of every point, and the cloud's faults that must
//! cast no shadow.

use std::sync::Arc;

use super::*;

/// The renders' rays, one every [`STEP`] in `(x / z, y / z)`.
const STEP: f64 = 0.002;

fn shadows_of(points: &[Vec3], spacing: f64) -> Option<Shadows> {
    let stored: Vec<[f32; 3]> = points.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
    Shadows::new(&stored, spacing)
}

/// An axis-aligned box, camera frame, mm.
struct Block {
    min: Vec3,
    max: Vec3,
}

/// What a camera at the origin sees of a table at `z = table_z` and a
/// block on it, one ray every `step` in `(x / z, y / z)` over
/// `[-half, half]`.
fn render(table_z: f64, block: &Block, half: f64, step: f64) -> Vec<Vec3> {
    let n = (half / step).round() as i64;
    let mut out = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            let ray = Vec3::new(i as f64 * step, j as f64 * step, 1.0);
            // The slab method: the ray's span inside the box.
            let (mut enter, mut leave) = (0.0f64, f64::INFINITY);
            for k in 0..3 {
                let (a, b) = (block.min[k] / ray[k], block.max[k] / ray[k]);
                enter = enter.max(a.min(b));
                leave = leave.min(a.max(b));
            }
            let t = if enter <= leave && enter > 0.0 { enter } else { table_z };
            out.push(ray * t);
        }
    }
    out
}

fn scene() -> (Vec<Vec3>, Block) {
    // A block 80 mm high on a table 300 mm from the camera, off to one
    // side.
    let block = Block { min: Vec3::new(20.0, -20.0, 220.0), max: Vec3::new(60.0, 20.0, 300.0) };
    (render(300.0, &block, 0.35, STEP), block)
}

#[test]
fn the_inside_of_a_block_and_the_space_behind_it_are_hidden_and_the_air_is_not() {
    let (points, _) = scene();
    let shadows = shadows_of(&points, STEP).expect("a frame's worth of points");
    // Inside the block, under its top.
    assert!(shadows.hides(&Vec3::new(40.0, 0.0, 260.0)));
    // Past the block's far face (x = 60), in its shadow on the table: the
    // ray through the top's far edge reaches the table at x = 81.8.
    assert!(shadows.hides(&Vec3::new(70.0, 0.0, 295.0)));
    // Under the table.
    assert!(shadows.hides(&Vec3::new(-50.0, 0.0, 320.0)));
    // Air: above the block's top, beside it over the table, and between
    // the camera and the block's near face (x = 20).
    for air in [Vec3::new(40.0, 0.0, 200.0), Vec3::new(-40.0, 0.0, 280.0), Vec3::new(15.0, 0.0, 280.0)] {
        assert!(!shadows.hides(&air), "{air:?} is in the open");
    }
    // Beyond the frame's view, nothing is known to be hidden.
    assert!(!shadows.hides(&Vec3::new(500.0, 0.0, 300.0)));
    assert!(!shadows.hides(&Vec3::new(0.0, 0.0, -10.0)));
}

#[test]
fn a_lone_return_in_the_air_casts_no_shadow() {
    let (mut points, _) = scene();
    let outlier = Vec3::new(-60.0, 10.0, 150.0);
    points.push(outlier);
    let shadows = shadows_of(&points, STEP).expect("points");
    // On the outlier's own ray, halfway from it to the table.
    assert!(!shadows.hides(&(outlier * 1.5)));
    // A patch of surface there is a surface: behind it is hidden.
    for di in -3..=3 {
        for dj in -3..=3 {
            points.push(outlier + Vec3::new(di as f64 * 0.3, dj as f64 * 0.3, 0.0));
        }
    }
    let shadows = shadows_of(&points, STEP).expect("points");
    assert!(shadows.hides(&(outlier * 1.5)));
}

#[test]
fn a_point_beside_a_surfaces_edge_is_not_behind_it() {
    let (points, block) = scene();
    let shadows = shadows_of(&points, STEP).expect("points");
    // Half a cell past the block top's far edge, seen from the camera:
    // the ray passes over the block to the table, so a point on it under
    // the top's height is in the open, though the cell it falls in
    // borders the top's.
    let slope = block.max.x / block.min.z + shadows.cell() / 2.0;
    let past = Vec3::new(slope * 260.0, 0.0, 260.0);
    assert!(!shadows.hides(&past), "{past:?}");
    // Well inside the edge, the same depth is behind the top.
    let inside = Vec3::new((slope - 4.0 * shadows.cell()) * 260.0, 0.0, 260.0);
    assert!(shadows.hides(&inside), "{inside:?}");
}

/// The straightforward reference: for a query, the nine cells round its
/// ray, each read off every point, and the rule applied.
fn hides_by_scan(shadows: &Shadows, points: &[Vec3], p: &Vec3) -> bool {
    if p.z <= MIN_DEPTH_MM {
        return false;
    }
    let cell_of = |q: &Vec3| {
        (
            ((q.x / q.z - shadows.origin[0]) / shadows.cell).floor() as i64,
            ((q.y / q.z - shadows.origin[1]) / shadows.cell).floor() as i64,
        )
    };
    let (ci, cj) = cell_of(p);
    if ci < 1 || cj < 1 || ci >= shadows.width as i64 - 1 || cj >= shadows.height as i64 - 1 {
        return false;
    }
    let mut nearest = [f32::INFINITY; 9];
    for q in points.iter().filter(|q| q.z > MIN_DEPTH_MM) {
        let (i, j) = cell_of(q);
        if (i - ci).abs() <= 1 && (j - cj).abs() <= 1 {
            let k = ((j - cj + 1) * 3 + (i - ci + 1)) as usize;
            nearest[k] = nearest[k].min(q.norm() as f32);
        }
    }
    let seen: Vec<f32> = nearest.into_iter().filter(|r| r.is_finite()).collect();
    let farthest = seen.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    seen.len() >= MIN_SEEN_CELLS && (p.norm() as f32) > farthest + BEHIND_TOLERANCE_MM as f32
}

#[test]
fn the_grid_hides_what_a_scan_of_every_point_hides() {
    let block = Block { min: Vec3::new(20.0, -20.0, 220.0), max: Vec3::new(60.0, 20.0, 300.0) };
    let points = render(300.0, &block, 0.3, 2.0 * STEP);
    let shadows = shadows_of(&points, 2.0 * STEP).expect("points");
    let (mut hidden, mut checked) = (0, 0);
    for x in (-100..=110).step_by(7) {
        for z in (150..=330).step_by(9) {
            for y in [-25.0, -3.0, 19.5] {
                let p = Vec3::new(x as f64, y, z as f64);
                assert_eq!(shadows.hides(&p), hides_by_scan(&shadows, &points, &p), "{p:?}");
                hidden += usize::from(shadows.hides(&p));
                checked += 1;
            }
        }
    }
    assert!(hidden > checked / 10 && hidden < checked * 9 / 10, "{hidden} of {checked}: the test must see both");
}

#[test]
fn a_wide_frame_at_a_fine_spacing_gets_coarser_cells_within_the_bound() {
    // Points spread over a wide view at a spacing fine enough to need far
    // more cells than the bound.
    let points: Vec<Vec3> =
        (0..200).map(|k| Vec3::new(-250.0 + 2.5 * k as f64, 250.0 - 2.5 * k as f64, 300.0)).collect();
    let shadows = shadows_of(&points, 1e-6).expect("points");
    assert!(shadows.width * shadows.height <= MAX_CELLS, "{} x {}", shadows.width, shadows.height);
    assert!(shadows_of(&points, 0.0).is_none(), "no spacing, no grid");
    assert!(shadows_of(&[Vec3::new(0.0, 0.0, -5.0)], STEP).is_none(), "nothing in front of the camera");
}

/// The hidden space laid tile by tile over an organized frame answers as
/// the grid over the whole frame does, point for point; and a ball round
/// each point asked that it clears holds no point the grid hides (its
/// centre, and points on its rim and halfway there, each way along each
/// axis and diagonal). How many points are hidden, and how many balls
/// cleared.
fn lazy_agrees_with_the_grid(points: &[Vec3], width: usize, spacing: f64, queries: &[Vec3]) -> usize {
    lazy_agrees_and_clears(points, width, spacing, queries).0
}

fn lazy_agrees_and_clears(points: &[Vec3], width: usize, spacing: f64, queries: &[Vec3]) -> (usize, usize) {
    let stored: Vec<[f32; 3]> = points.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
    let grid = Shadows::new(&stored, spacing).expect("points");
    let blocks = Arc::new(BlockIndex::new(&stored, width));
    let lazy = LazyShadows::new(blocks, spacing).expect("points");
    let mut hidden = 0;
    let mut cleared = 0;
    let directions: Vec<Vec3> = (0..27)
        .map(|k| Vec3::new((k % 3) as f64 - 1.0, (k / 3 % 3) as f64 - 1.0, (k / 9) as f64 - 1.0))
        .filter(|d| d.norm() > 0.0)
        .map(|d| d.normalize())
        .collect();
    // Asked a run at a time, in order, the same answers; and the asking
    // stops where it is told to.
    let mut answered = Vec::new();
    lazy.hides_each(queries, |k, hides| {
        answered.push((k, hides));
        true
    });
    let expected: Vec<(usize, bool)> = queries.iter().map(|p| grid.hides(p)).enumerate().collect();
    assert_eq!(answered, expected);
    let stop = queries.len() / 2;
    let mut asked = 0;
    lazy.hides_each(queries, |k, _| {
        asked += 1;
        k < stop
    });
    assert_eq!(asked, (stop + 1).min(queries.len()));
    for p in queries {
        assert_eq!(lazy.hides(p), grid.hides(p), "{p:?}");
        hidden += usize::from(grid.hides(p));
        for radius in [0.5, 3.0, 12.0] {
            if !lazy.clears_ball(p, radius) {
                continue;
            }
            cleared += 1;
            assert!(!grid.hides(p), "{p:?} within {radius} cleared");
            for d in &directions {
                for reach in [0.5, 0.999] {
                    let q = p + d * (radius * reach);
                    assert!(!grid.hides(&q), "{q:?} within {radius} of {p:?} cleared");
                }
            }
        }
    }
    (hidden, cleared)
}

#[test]
fn the_tiles_hide_what_the_whole_grid_hides() {
    let block = Block { min: Vec3::new(20.0, -20.0, 220.0), max: Vec3::new(60.0, 20.0, 300.0) };
    let half = 0.3;
    let points = render(300.0, &block, half, STEP);
    let width = 2 * (half / STEP).round() as usize + 1;
    let mut queries = Vec::new();
    for x in (-100..=110).step_by(3) {
        for z in (150..=330).step_by(4) {
            for y in [-25.0, -3.0, 19.5, 70.0] {
                queries.push(Vec3::new(x as f64, y, z as f64));
            }
        }
    }
    let (hidden, cleared) = lazy_agrees_and_clears(&points, width, STEP, &queries);
    assert!(hidden > queries.len() / 10 && hidden < queries.len() * 9 / 10, "{hidden} of {}", queries.len());
    assert!(cleared > queries.len() / 10, "{cleared} balls of {} points cleared", queries.len());
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]

    /// Random blocks on a table, random spacings of the grid against the
    /// render's, random points asked.
    #[test]
    fn random_scenes_hide_the_same_tile_by_tile(
        (x0, y0, z0) in (-80f64..40.0, -60f64..20.0, 150f64..280.0),
        (dx, dy, dz) in (5f64..60.0, 5f64..60.0, 5f64..80.0),
        spacing_factor in 0.5f64..4.0,
        queries in proptest::collection::vec((-120f64..120.0, -120f64..120.0, 100f64..360.0), 50..200),
    ) {
        let block = Block { min: Vec3::new(x0, y0, z0), max: Vec3::new(x0 + dx, y0 + dy, (z0 + dz).min(299.0)) };
        let (half, step) = (0.25, 2.0 * STEP);
        let points = render(300.0, &block, half, step);
        let width = 2 * (half / step).round() as usize + 1;
        let queries: Vec<Vec3> = queries.into_iter().map(|(x, y, z)| Vec3::new(x, y, z)).collect();
        lazy_agrees_with_the_grid(&points, width, step * spacing_factor, &queries);
    }
}
