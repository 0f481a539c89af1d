//! The plates path's own checks: the seam's axes, a weld edge's extent
//! without a grid, a lap's step and the edges' overlap.

use super::*;

#[test]
fn edge_samples_without_a_direction_in_the_plates_give_no_seam() {
    let normal = Vec3::z();
    let none = seam_axes(&[Vec::new(), Vec::new()], &normal).unwrap_err();
    assert_eq!((none.rule.id, none.stage), ("seam.samples_not_along_a_line", Stage::Refit), "{none}");
    // Samples stacked along the normal: a face seen edge-on, no edge.
    let stacked: Vec<Vec3> = (0..10).map(|k| Vec3::new(0.0, 0.0, 700.0 + k as f64)).collect();
    let along_normal = seam_axes(&[stacked.clone(), stacked], &normal).unwrap_err();
    assert_eq!(along_normal.rule.id, "seam.samples_not_along_a_line", "{along_normal}");
    // Two edges along x: the seam runs along x.
    let edge = |y: f64| (0..10).map(|k| Vec3::new(k as f64, y, 700.0)).collect::<Vec<_>>();
    let axes = seam_axes(&[edge(-1.0), edge(1.0)], &normal).expect("a seam along x");
    assert!(axes.e.dot(&Vec3::x()).abs() > 1.0 - 1e-9);
}

#[test]
fn a_weld_edge_without_a_grid_runs_along_its_longest_unbroken_stretch() {
    use super::super::super::boundary::{BoundarySample, ExtentRule};
    // Samples a millimetre apart from 0 to 19 mm, then 20 strips with
    // none, then three more: a chance hole, not the edge.
    let at = (0..20).chain(40..43).map(|k| k as f64);
    let samples = at.map(|x| BoundarySample { position: Vec3::new(x, 0.0, 700.0), along: x }).collect();
    let strips = Boundary {
        samples,
        across_other_edge: Vec::new(),
        line_spacing_mm: 1.0,
        extent_rule: ExtentRule::LongestStretch,
    };
    // `seam.longest_seen_stretch` cuts the three off.
    assert_eq!(strips.extent(|s| s.position.x), Some((-0.5, 19.5)));
    // Every sample counts on a pixel grid, and samples eight strips
    // apart still lie on one stretch.
    let grid = Boundary { extent_rule: ExtentRule::AllSamples, ..strips.clone() };
    assert_eq!(grid.extent(|s| s.position.x), Some((-0.5, 42.5)));
    let at = (0..20).chain(27..30).map(|k| k as f64);
    let samples = at.map(|x| BoundarySample { position: Vec3::new(x, 0.0, 700.0), along: x }).collect();
    let bridged = Boundary { samples, ..strips };
    assert_eq!(bridged.extent(|s| s.position.x), Some((-0.5, 29.5)));
}

#[test]
fn a_lap_without_a_step_or_edges_that_do_not_overlap_are_refused_by_rule() {
    let points: Vec<Vec3> = (0..10).map(|k| Vec3::new(k as f64, 0.0, 700.0)).collect();
    let axes = SeamAxes::paper(&points);
    let edge = refit::fit(&points, &axes, 1).expect("a line").curve;
    let normal = Vec3::z();
    let flat = lap_root(&edge, None, &normal).unwrap_err();
    assert_eq!((flat.rule.id, flat.stage), ("lap.no_step_along_normal", Stage::WeldEquation), "{flat}");
    let root = lap_root(&edge, Some(3.0), &normal).expect("a step");
    assert!((root.at(2.0) - edge.at(2.0) - normal * 3.0).norm() < 1e-9);
    let apart = check_overlap(10.0, 4.0).unwrap_err();
    assert_eq!((apart.rule.id, apart.stage), ("seam.edges_do_not_overlap", Stage::WeldEquation), "{apart}");
    assert_eq!(check_overlap(10.0, 10.0).unwrap_err().rule.id, "seam.edges_do_not_overlap");
    assert_eq!(check_overlap(4.0, 10.0), Ok(()));
}
