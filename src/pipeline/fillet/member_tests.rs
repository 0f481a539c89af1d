//! The roots of a member standing on a plate with every side a root (a
//! block, [`super::TeeView::every_side`]): read along its top's outline,
//! its ends' roots as well as its sides', and only on a side the camera
//! sees from outside the face.

use super::*;

/// A cube 60 mm a side standing on a plate at depth 760, centred at x =
/// 100 (so the camera, at the origin looking down +z, sees its −x face
/// only, and looks at its ±y faces from between their planes), turned
/// `turn_deg` about the camera's axis: its top at depth 700, its −x face
/// from 1 to 59 mm over the plate, the plate round it; all on a 1 mm
/// grid, returned with the top's and the plate's clusters.
fn cube(turn_deg: f64) -> (PointCloud, PlaneCluster, PlaneCluster) {
    let (c, s) = (turn_deg.to_radians().cos(), turn_deg.to_radians().sin());
    let place = move |x: f64, y: f64, z: f64| Vec3::new(100.0 + c * x - s * y, s * x + c * y, z);
    let mut points = Vec::new();
    for i in -90..90 {
        for j in -90..90 {
            let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
            let on_top = x.abs() < 30.0 && y.abs() < 30.0;
            points.push(place(x, y, if on_top { 700.0 } else { 760.0 }));
        }
    }
    for j in -30..30 {
        for k in 1..60 {
            points.push(place(-30.0, j as f64 + 0.5, 760.0 - k as f64));
        }
    }
    let cloud = PointCloud::unorganized(points.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect());
    let top = PlaneCluster::of_points(&points, |p| p.z == 700.0);
    let plate = PlaneCluster::of_points(&points, |p| p.z == 760.0);
    (cloud, top, plate)
}

#[test]
fn a_block_s_seen_side_gives_its_root_along_its_outline_and_its_other_sides_are_named() {
    for turn_deg in [0.0, 10.0, -12.0] {
        let (cloud, top, plate) = cube(turn_deg);
        let pieces = [&plate];
        let view = TeeView {
            cloud: &cloud,
            web: Web::Top(&top),
            flange_pieces: &pieces,
            point_spacing_mm: 1.0,
            rim_mm: 1.0,
            on_plane_mm: 0.4,
            trim_sigma: 3.0,
            projector: Vec3::zeros(),
            in_view: None,
            border: None,
            max_beyond_mm: 2.0,
            every_side: true,
            web_thickness_max_mm: 30.0,
        };
        let roots: Vec<Result<Root, RootNotSeen>> =
            find_roots(&view).into_iter().chain(find_end_roots(&view)).collect();
        let found: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
        assert_eq!(found.len(), 1, "{turn_deg}°: {roots:?}");
        // On the −x face's foot, x' = −30 in the cube's own axes, along it.
        let (c, s) = (turn_deg.to_radians().cos(), turn_deg.to_radians().sin());
        let own_x = |p: Vec3| c * (p.x - 100.0) + s * p.y;
        for end in [found[0].line.s_min, found[0].line.s_max] {
            let p = found[0].line.at(end);
            assert!((own_x(p) + 30.0).abs() < 0.3 && (p.z - 760.0).abs() < 0.3, "{turn_deg}°: {p:?}");
        }
        assert!(found[0].line.s_max - found[0].line.s_min > 50.0, "{turn_deg}°: {:?}", found[0].line);
        // The other three: named, the two the camera looks at from
        // between their planes, and the far one, as hidden.
        let hidden = roots.iter().filter_map(|r| r.as_ref().err()).filter(|n| n.rule.id == "tee.root_hidden_by_web");
        assert_eq!(hidden.count(), 3, "{turn_deg}°: {roots:?}");
    }
}
