//! The background stage's rules on constructed clusters and frames.

use super::*;
use crate::cloud::Point;
use crate::pipeline::view_border::ViewBorder;

/// The robust rule over clusters that index no frame: what only
/// their points show is not seen.
fn robust_select(planes: Vec<PlaneCluster>, s: &Selection) -> Result<Selected, BackgroundError> {
    super::robust_select(planes, s, &[])
}

/// A plate as long along y as it is wide across x.
fn cluster(offset: f64, area: f64, centre_x: f64) -> PlaneCluster {
    PlaneCluster {
        label: 0,
        members: vec![0; area as usize].into(),
        plane: Plane { normal: Vec3::z(), offset },
        centroid: Vec3::new(centre_x, 0.0, offset),
        area_mm2: area,
        long_axis: Vec3::y(),
        elongation: 1.0,
    }
}

/// A bar along y, five times longer than wide.
fn bar(offset: f64, area: f64, centre_x: f64) -> PlaneCluster {
    PlaneCluster { elongation: 5.0, ..cluster(offset, area, centre_x) }
}

#[test]
fn a_third_plate_beside_a_butt_pair_is_refused_and_a_piece_along_it_is_not() {
    // Plates of 100 mm side by side at x = 0 and 100, a third abutting
    // the second at x = 190: two joints in one plane.
    let pair = [cluster(700.0, 20_000.0, 0.0), cluster(700.5, 18_000.0, 100.0)];
    let beside = [pair.as_slice(), &[cluster(699.5, 12_000.0, 190.0)]].concat();
    let err = robust_select(beside.clone(), &selection(JointType::IButt)).unwrap_err();
    assert_eq!(err.rule().id, "butt.third_plate_beyond_pair", "{err}");
    assert!(err.to_string().contains("region of interest"), "{err}");
    // On the other side of the pair too, and under auto.
    let before = [pair.as_slice(), &[cluster(699.5, 12_000.0, -95.0)]].concat();
    assert_eq!(robust_select(before, &auto()).unwrap_err().rule().id, "joint.no_layout_fits");
    // A piece of the second plate a clamp cut off lies along the seam,
    // across it where that plate lies: the pair is planned.
    let mut piece = cluster(700.5, 9_000.0, 104.0);
    piece.centroid.y = 150.0;
    let cut = [pair.as_slice(), &[piece]].concat();
    assert_eq!(robust_select(cut, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
    // So is a third plane too small to be a plate (a spatter bead, a
    // tack).
    let bead = [pair.as_slice(), &[cluster(700.0, 300.0, 190.0)]].concat();
    assert_eq!(robust_select(bead, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
}

#[test]
fn a_narrow_strip_between_butt_plates_is_their_floor_and_a_wide_plane_their_support() {
    // Butt plates 100 mm wide at x = 0 and 100; behind them a strip 3 mm
    // wide along the seam (a V's apex in a noisy cloud), or the table.
    let plate = |x: f64| PlaneCluster { elongation: 3.0, ..cluster(700.0, 30_000.0, x) };
    let strip = PlaneCluster { elongation: 100.0, ..cluster(707.6, 900.0, 50.0) };
    let pair = [plate(0.0), plate(100.0)];
    let floor = robust_select([pair.as_slice(), &[strip]].concat(), &selection(JointType::VButt)).unwrap();
    assert!(floor.workpiece.depth_to_support_mm.is_some_and(|d| (d - 7.6).abs() < 1e-9));
    assert!(floor.workpiece.support_between_plates);
    let table = cluster(740.0, 200_000.0, 50.0);
    let rest = robust_select([pair.as_slice(), &[table]].concat(), &selection(JointType::VButt)).unwrap();
    assert_eq!(rest.workpiece.depth_to_support_mm, Some(40.0));
    assert!(!rest.workpiece.support_between_plates);
}

fn selection(joint: JointType) -> Selection {
    Selection { joint: Some(joint), ..auto() }
}

pub(super) fn auto() -> Selection {
    Selection {
        joint: None,
        normal: Vec3::z(),
        coplanar_tolerance_mm: 3.0,
        lap_step_min_mm: 1.0,
        lap_step_max_mm: 30.0,
        web_height_max_mm: 250.0,
        web_thickness_max_mm: 30.0,
        max_tilt_deg: 10.0,
        neighbour_radius_mm: 1.0,
    }
}

/// A web's top along y, 8 mm wide and 200 mm long, `height` over a
/// flange at 760 seen on both of its sides (or only on +x), the table
/// further.
fn tee(height: f64, both_sides: bool) -> Vec<PlaneCluster> {
    let web = PlaneCluster { elongation: 25.0, ..cluster(760.0 - height, 1_600.0, 0.0) };
    let mut planes = vec![web, cluster(760.0, 30_000.0, 80.0), cluster(800.0, 90_000.0, 0.0)];
    if both_sides {
        planes.push(cluster(760.2, 12_000.0, -60.0));
    }
    planes
}

/// A frame of 1 mm returns along y 0..200: a web's top 8 mm wide at
/// x -8..0 and depth `top_z`, the flange at x 0..100 and depth 760,
/// and beyond the web (x -60..-8) returns at depth `beyond_z`, if any.
/// The clusters are the top's and the flange's.
fn corner_frame(top_z: f64, beyond_z: Option<f64>) -> (Vec<PlaneCluster>, Vec<Point>) {
    corner_frame_apart(top_z, beyond_z, 0)
}

/// [`corner_frame`] with the flange starting `gap` mm off the top's
/// edge, at x = gap..100.
fn corner_frame_apart(top_z: f64, beyond_z: Option<f64>, gap: i32) -> (Vec<PlaneCluster>, Vec<Point>) {
    corner_frame_with(top_z, beyond_z, gap, 0..200)
}

/// [`corner_frame_apart`] with the flange along y `flange_y` instead of
/// beside the top's whole length (y 0..200).
fn corner_frame_with(
    top_z: f64,
    beyond_z: Option<f64>,
    gap: i32,
    flange_y: std::ops::Range<i32>,
) -> (Vec<PlaneCluster>, Vec<Point>) {
    let mut points: Vec<Point> = Vec::new();
    let strip = |points: &mut Vec<Point>, x0: i32, x1: i32, ys: std::ops::Range<i32>, z: f64| {
        let first = points.len() as u32;
        for x in x0..x1 {
            for y in ys.clone() {
                points.push([x as f32 + 0.5, y as f32, z as f32]);
            }
        }
        (first..points.len() as u32).collect::<Vec<u32>>()
    };
    let web = strip(&mut points, -8, 0, 0..200, top_z);
    let flange_centre_y = f64::from(flange_y.start + flange_y.end) / 2.0;
    let flange = strip(&mut points, gap, 100, flange_y, 760.0);
    if let Some(z) = beyond_z {
        strip(&mut points, -60, -8, 0..200, z);
    }
    let plane = |members: Vec<u32>, x: f64, y: f64, z: f64, elongation: f64| PlaneCluster {
        area_mm2: members.len() as f64,
        members: members.into(),
        plane: Plane { normal: Vec3::z(), offset: z },
        centroid: Vec3::new(x, y, z),
        label: 0,
        long_axis: Vec3::y(),
        elongation,
    };
    (vec![plane(web, -4.0, 100.0, top_z, 25.0), plane(flange, 50.0, flange_centre_y, 760.0, 2.0)], points)
}

fn corner_kind(top_z: f64, beyond_z: Option<f64>) -> Option<CornerKind> {
    let (planes, points) = corner_frame(top_z, beyond_z);
    find_corner(&planes, &auto(), &points, || None).map(|corner| corner.kind)
}

#[test]
fn a_plates_edge_flush_or_proud_beside_a_flange_with_a_drop_beyond_is_an_outside_corner() {
    assert_eq!(corner_kind(760.0, Some(830.0)), Some(CornerKind::Outside));
    assert_eq!(corner_kind(757.0, Some(830.0)), Some(CornerKind::Outside));
    let (planes, points) = corner_frame(760.0, Some(830.0));
    let corner = find_corner(&planes, &auto(), &points, || None).unwrap();
    assert_eq!(corner.refusal().rule().id, "corner.outside_not_planned");
    assert_eq!(corner.rule(true).id, "corner.outside_not_planned");
    let reason = corner.refusal().to_string();
    assert!(reason.contains("corner joint") && reason.contains("8 mm thick"), "{reason}");
    assert!(reason.contains("outside corner's weld is not planned"), "{reason}");
    // The clusters named are the plate's edge and the flange.
    assert_eq!((corner.standing, corner.flange), (0, 1));
}

#[test]
fn a_sliver_continuing_a_plate_off_its_end_is_no_corner() {
    // A beam's top seen only as a sliver in front of a tube standing near
    // its edge, the rest of the top lying off the sliver's end (y 210 to
    // 400), the floor far below beyond both: the larger plane is not
    // beside the sliver, so the two are not a corner's plates.
    let (planes, points) = corner_frame_with(760.0, Some(830.0), 0, 210..400);
    assert_eq!(find_corner(&planes, &auto(), &points, || None), None);
    // The same plane beside most of the sliver's length is.
    let (planes, points) = corner_frame_with(760.0, Some(830.0), 0, 60..400);
    assert_eq!(find_corner(&planes, &auto(), &points, || None).map(|c| c.kind), Some(CornerKind::Outside));
}

#[test]
fn a_sliver_of_flange_beyond_a_web_near_its_edge_is_no_corner() {
    // A tee's flange ending 8 mm past the web's far face: from the camera
    // the sliver beyond the web lies flush with the wide flange on the
    // web's other side, a web's thickness off it, with the table far
    // below beyond the sliver. An outside corner's edge touches its flange.
    let (planes, points) = corner_frame_apart(760.0, Some(830.0), 8);
    assert_eq!(find_corner(&planes, &auto(), &points, || None), None);
    // Up to two clusters' rims apart (a neighbour radius each, and a
    // couple of spacings) the two touch.
    let (planes, points) = corner_frame_apart(760.0, Some(830.0), 2);
    assert_eq!(find_corner(&planes, &auto(), &points, || None).map(|c| c.kind), Some(CornerKind::Outside));
    // An inside corner's web seen with the table beside its flange is not
    // asked to touch it: the web's side face lies between them.
    let (planes, points) = corner_frame_apart(700.0, Some(860.0), 8);
    assert_eq!(find_corner(&planes, &auto(), &points, || None).map(|c| c.kind), Some(CornerKind::Inside));
}

#[test]
fn a_web_a_web_height_over_a_flange_with_a_drop_beyond_is_an_inside_corner() {
    assert_eq!(corner_kind(700.0, Some(860.0)), Some(CornerKind::Inside));
    let (planes, points) = corner_frame(700.0, Some(860.0));
    let corner = find_corner(&planes, &auto(), &points, || None).unwrap();
    // Under a butt or lap request refused; under `t_fillet` or `auto` its
    // root is a tee's.
    assert_eq!(corner.rule(false).id, "corner.inside_root_needs_fillet_request");
    assert_eq!(corner.refusal().rule().id, "corner.inside_root_needs_fillet_request");
    assert_eq!(corner.rule(true).id, "corner.inside_planned_as_tee_root");
    let reason = corner.refusal().to_string();
    assert!(reason.contains("request t_fillet or auto"), "{reason}");
}

#[test]
fn an_edge_with_its_outer_face_going_down_to_where_the_cloud_ends_is_an_outside_corner() {
    // A crop 25 mm deep took the table; the plate's outer face is seen
    // from under the edge's rim (beyond the flange's level) down to the
    // crop.
    let (planes, mut points) = corner_frame(758.0, None);
    for z in 764..783 {
        for y in 0..200 {
            points.push([-9.0, y as f32, z as f32]);
        }
    }
    let corner = find_corner(&planes, &auto(), &points, || None).expect("refused");
    assert_eq!(corner.kind, CornerKind::Outside);
    assert_eq!(corner.rule(false).id, "corner.outside_not_planned");
    let reason = corner.refusal().to_string();
    assert!(reason.contains("steep face") && reason.contains("24 mm deep"), "{reason}");
}

#[test]
fn a_sliver_cut_by_the_image_border_is_no_corner() {
    // Butt plates, one barely in view: the image's border runs along
    // the sliver's far edge (x = -7.5 at 760 mm).
    let (planes, points) = corner_frame(760.0, None);
    let border = ViewBorder::from_tangents([-7.5 / 760.0, 1.0, -1.0, 1.0]);
    assert_eq!(find_corner(&planes, &auto(), &points, || Some(&border)), None);
}

#[test]
fn an_edge_with_nothing_beyond_inside_the_view_or_in_a_cloud_without_a_grid_is_refused() {
    // An outside corner's plate whose outer face is turned from the
    // camera and whose table a crop took: nothing at a plate's level
    // beyond its edge, and no drop to show. Without the image's border
    // (a cropped or merged cloud) a plate cut as narrow looks the same.
    let (planes, points) = corner_frame(758.0, None);
    let corner = find_corner(&planes, &auto(), &points, || None).expect("refused");
    assert_eq!(corner.kind, CornerKind::Outside);
    assert_eq!(corner.rule(false).id, "corner.outside_not_planned");
    let reason = corner.refusal().to_string();
    assert!(reason.contains("8 mm wide") && reason.contains("2.0 mm over"), "{reason}");
    assert!(reason.contains("widen the crop") && reason.contains("not planned"), "{reason}");
    // In a grid whose border touches the edge only at the image's
    // corner (y = 0), the edge is in view: still refused.
    let corner_of_image = ViewBorder::from_tangents([-1.0, 1.0, 0.0, 1.0]);
    assert!(find_corner(&planes, &auto(), &points, || Some(&corner_of_image)).is_some());
    // Off the flange by a web's thickness (a cropped tee's flange on
    // the far side of its web) or a groove's width, the edge is no
    // corner's.
    let (planes, points) = corner_frame_apart(758.0, None, 8);
    assert_eq!(find_corner(&planes, &auto(), &points, || None), None);
    // The rest of a plate at either level beyond is a plate.
    assert_eq!(corner_kind(758.0, Some(758.0)), None);
    assert_eq!(corner_kind(758.0, Some(760.0)), None);
    // A web's top a web's height over the flange, nothing beyond: a
    // tee whose far side is out of the cloud as much as a corner.
    assert_eq!(corner_kind(700.0, None), None);
}

#[test]
fn returns_at_the_flanges_level_beyond_make_it_no_corner() {
    // A tee's flange beyond its web, a plate under a clamp, the rest of
    // a plate a streak cut.
    assert_eq!(corner_kind(700.0, Some(760.0)), None);
    assert_eq!(corner_kind(760.0, Some(760.0)), None);
}

#[test]
fn a_drop_no_deeper_than_a_lap_step_is_no_corner() {
    assert_eq!(corner_kind(760.0, Some(780.0)), None);
}

#[test]
fn a_web_a_web_height_over_its_flange_seen_on_both_sides_is_a_tee() {
    for joint in [Some(JointType::TFillet), None] {
        let chosen = robust_select(tee(50.0, true), &Selection { joint, ..auto() }).unwrap();
        assert_eq!(chosen.layout, Layout::Tee, "{joint:?}");
        assert_eq!(chosen.workpiece.plates[0].area_mm2, 1_600.0);
        // The larger flange piece, the other its layer mate.
        assert_eq!(chosen.workpiece.plates[1].area_mm2, 30_000.0);
        assert_eq!(chosen.workpiece.layer_mates[1].len(), 1);
        assert_eq!(chosen.workpiece.depth_to_support_mm, Some(40.0));
        assert!(chosen.evidence.contains("50.0 mm over a flange seen on both"), "{}", chosen.evidence);
    }
    // A butt or lap joint requested: named for what it looks like.
    for joint in [JointType::IButt, JointType::VButt, JointType::Lap] {
        let err = robust_select(tee(50.0, true), &selection(joint)).unwrap_err();
        assert!(err.is_joint_mismatch() && err.to_string().contains("looks like a tee joint"), "{err}");
        assert_eq!(err.rule().id, "joint.looks_like_tee", "{err}");
    }
}

/// [`tee`] with its top `width` mm wide instead of 8 (200 mm long).
fn tee_of_width(height: f64, width: f64) -> Vec<PlaneCluster> {
    let mut planes = tee(height, true);
    planes[0].area_mm2 = 200.0 * width;
    planes[0].elongation = 200.0 / width;
    planes
}

#[test]
fn a_bar_lying_on_the_plates_or_too_wide_is_no_web() {
    // A clamp 25 mm over the plates and 30 mm wide (the fault suite's):
    // within a lap's step and no taller than it is wide, so what it was
    // before, butt plates with a clamp over them.
    let clamp = tee_of_width(25.0, 30.0);
    assert!((clamp[0].width_mm() - 30.0).abs() < 1e-9);
    assert_eq!(robust_select(clamp.clone(), &auto()).unwrap().layout, Layout::Butt);
    let err = robust_select(clamp, &selection(JointType::TFillet)).unwrap_err();
    assert_eq!(err.rule().id, "tee.no_web_top", "{err}");
    assert!(err.to_string().contains("at least 1.5 times its width"), "{err}");
    // A flat bar 20 mm wide, 12 mm over the plates: the same.
    let flat = tee_of_width(12.0, 20.0);
    assert_eq!(robust_select(flat.clone(), &auto()).unwrap().layout, Layout::Butt);
    assert_eq!(robust_select(flat, &selection(JointType::TFillet)).unwrap_err().rule().id, "tee.no_web_top");
    // A bar standing on edge, 8 mm wide and 25 mm tall, across butt
    // plates: no tee unless one is asked for.
    assert_eq!(robust_select(tee(25.0, true), &auto()).unwrap().layout, Layout::Butt);
    // A plate 60 mm wide over the table: no web's top.
    let mut wide = tee(50.0, true);
    wide[0].elongation = 3.0;
    wide[0].area_mm2 = 11_000.0;
    assert_ne!(robust_select(wide.clone(), &auto()).map(|s| s.layout).ok(), Some(Layout::Tee));
    assert!(matches!(robust_select(wide, &selection(JointType::TFillet)), Err(BackgroundError::NoWeb { .. })));
}

#[test]
fn a_web_shorter_than_a_lap_step_standing_taller_than_it_is_thick_is_a_tee() {
    // Issue 50's short webs: 8 mm thick, 15 to 25 mm over the flange, no
    // higher than a lap's upper plate may be thick (30 mm) but standing
    // two to three times as tall as their top is wide: under `t_fillet`,
    // on both sides of it or one.
    let tee_asked = selection(JointType::TFillet);
    for height in [15.0, 20.0, 25.0] {
        for both_sides in [true, false] {
            let chosen = robust_select(tee(height, both_sides), &tee_asked).unwrap();
            assert_eq!(chosen.layout, Layout::Tee, "{height} {both_sides}");
            assert_eq!(chosen.workpiece.plates[0].area_mm2, 1_600.0);
            let over = format!("{height:.1} mm over a flange seen on");
            assert!(chosen.evidence.contains(&over), "{}", chosen.evidence);
        }
        // Unnamed, or another joint named, the layers read as before: a
        // bar standing on edge across a joint's plates looks the same.
        assert_ne!(robust_select(tee(height, true), &auto()).map(|s| s.layout).ok(), Some(Layout::Tee));
        assert_eq!(robust_select(tee(height, true), &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
        let err = robust_select(tee(height, true), &selection(JointType::Lap)).unwrap_err();
        assert_eq!(err.rule().id, "lap.upper_plane_lies_across_lower", "{err}");
    }
    // At 1.5 times its width it stands as a web; under it, no.
    assert_eq!(robust_select(tee_of_width(18.1, 12.0), &tee_asked).unwrap().layout, Layout::Tee);
    assert_eq!(robust_select(tee_of_width(17.9, 12.0), &tee_asked).unwrap_err().rule().id, "tee.no_web_top");
}

#[test]
fn a_v_groove_s_root_land_under_its_plates_is_no_web_s_top() {
    // A V-butt cropped round its seam: its plates either side at 360,
    // the groove's root land 3 mm wide 9 mm under them, and the table
    // beyond the plates' end 37 mm under the land: the land is long,
    // narrow and a web's height over a plane, but it lies under the
    // workpiece's top.
    let land = PlaneCluster { elongation: 80.0, ..cluster(369.0, 1_200.0, 0.0) };
    let planes =
        vec![cluster(360.0, 11_000.0, -25.0), cluster(360.1, 11_500.0, 25.0), land, cluster(406.0, 2_000.0, 40.0)];
    let err = robust_select(planes.clone(), &selection(JointType::TFillet)).unwrap_err();
    assert_eq!(err.rule().id, "tee.no_web_top", "{err}");
    assert_eq!(robust_select(planes, &auto()).unwrap().layout, Layout::Butt);
}

#[test]
fn a_web_over_a_flange_seen_on_one_side_is_planned_only_when_named() {
    let chosen = robust_select(tee(60.0, false), &selection(JointType::TFillet)).unwrap();
    assert_eq!(chosen.layout, Layout::Tee);
    assert!(chosen.evidence.contains("one of its sides only"), "{}", chosen.evidence);
    let err = robust_select(tee(60.0, false), &auto()).unwrap_err();
    assert!(err.rule().id == "tee.web_seen_on_one_side" && err.is_unrecognised(), "{err}");
    assert!(err.to_string().contains("tee joint"), "{err}");
}

#[test]
fn a_split_table_is_not_taken_for_a_plate() {
    // Two table pieces, larger than the plates, 40 mm further away.
    let planes = vec![
        cluster(740.0, 90_000.0, -300.0),
        cluster(700.0, 20_000.0, -50.0),
        cluster(740.0, 80_000.0, 300.0),
        cluster(700.5, 25_000.0, 50.0),
    ];
    let w = robust_select(planes, &selection(JointType::IButt)).unwrap().workpiece;
    assert!(w.plates.iter().all(|p| p.plane.offset < 701.0));
}

#[test]
fn table_pieces_under_plates_seen_as_one_are_refused() {
    // The plates merged across an unresolved gap (one plane), the table
    // 34 mm below split in two by the workpiece: no seam lies between
    // the table pieces, whatever their edges look like.
    let planes =
        vec![cluster(905.0, 160_000.0, 0.0), cluster(939.0, 40_000.0, -250.0), cluster(939.3, 30_000.0, 250.0)];
    let err = robust_select(planes, &selection(JointType::IButt)).unwrap_err();
    assert_eq!(err.rule().id, "butt.pair_under_larger_plane", "{err}");
    assert!(err.to_string().contains("34.0 mm nearer the camera"), "{err}");
    // A clamp on the plates is smaller than either plate and is passed over.
    let planes = vec![cluster(880.0, 2_000.0, 0.0), cluster(905.0, 60_000.0, -100.0), cluster(905.2, 50_000.0, 100.0)];
    let w = robust_select(planes, &selection(JointType::IButt)).unwrap().workpiece;
    assert!(w.plates.iter().all(|p| p.plane.offset > 904.0));
}

#[test]
fn plates_filling_the_view_are_both_kept() {
    let planes = vec![cluster(700.0, 70_000.0, -100.0), cluster(700.2, 60_000.0, 100.0)];
    assert!(robust_select(planes, &selection(JointType::VButt)).is_ok());
}

#[test]
fn lap_takes_the_nearest_layers_one_thickness_apart_upper_first() {
    let planes = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
    let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
    assert_eq!(w.plates[0].plane.offset, 700.0);
    assert_eq!(w.plates[1].plane.offset, 706.0);
}

#[test]
fn a_bar_lying_across_a_plate_is_no_lap() {
    // A clamp 15 mm over one plate, which is seen on both of its sides;
    // the other plate lies 7 mm lower, the table further.
    let planes = || {
        vec![
            bar(685.0, 8_000.0, 0.0),
            cluster(700.0, 9_000.0, -40.0),
            cluster(700.0, 8_500.0, 40.0),
            cluster(707.0, 14_000.0, 80.0),
            cluster(760.0, 90_000.0, 0.0),
        ]
    };
    let lap = robust_select(planes(), &selection(JointType::Lap)).unwrap_err();
    assert_eq!(lap.rule().id, "lap.upper_plane_lies_across_lower", "{lap}");
    assert!(lap.to_string().contains("clamp"), "{lap}");
    // As butt plates, the two sides are a pair, and what lies between
    // their edges is the groove probe's to name.
    let butt = robust_select(planes(), &selection(JointType::IButt)).unwrap();
    assert_eq!(butt.workpiece.plates.each_ref().map(|p| p.plane.offset), [700.0, 700.0]);
    assert_eq!(robust_select(planes(), &auto()).unwrap().layout, Layout::Butt);
}

/// A plane cluster at depth `offset` whose centroid is (`x`, `y`).
fn placed(offset: f64, area: f64, x: f64, y: f64) -> PlaneCluster {
    let mut c = cluster(offset, area, x);
    c.centroid.y = y;
    c
}

#[test]
fn a_clamp_cut_short_by_a_crop_round_the_seam_is_no_lap_s_upper_plate() {
    // fault-clamp-lap-02 cropped 35 mm round its seam: the clamp, 37 mm
    // wide along the seam (y), lies across both plates, its pad cut to
    // 70 mm across the seam: 1.9 times longer than wide, no bar. It
    // stands 15.6 mm over the upper plate (x < 0, at 700), which it cuts
    // into pieces on both of its sides along the seam; the lower plate
    // (x > 0) lies 6.8 mm further, the table further still. The clamp
    // and the plate under it were planned as the lap, 129 mm off.
    let mut pad = cluster(684.4, 2_590.0, 0.0);
    (pad.long_axis, pad.elongation) = (Vec3::x(), 70.0 / 37.0);
    let planes = vec![
        pad,
        placed(700.0, 3_000.0, -17.5, -60.0),
        placed(700.0, 2_400.0, -17.5, 60.0),
        placed(706.8, 3_600.0, 17.5, -60.0),
        placed(706.8, 3_200.0, 17.5, 60.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    let err = robust_select(planes, &selection(JointType::Lap)).unwrap_err();
    assert_eq!(err.rule().id, "lap.upper_plane_lies_across_lower", "{err}");
    // A square upper plate (x from -50 to 0, y from -25 to 25) with its
    // lower plate in two pieces beside its edge (a streak between them):
    // the line through the pieces runs beside the plate, not through it.
    let planes = vec![
        placed(700.0, 2_500.0, -25.0, 0.0),
        placed(706.8, 900.0, 17.5, -15.0),
        placed(706.8, 800.0, 17.5, 15.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
    assert_eq!(w.plates.each_ref().map(|p| p.plane.offset), [700.0, 706.8]);
}

/// Points on a 1 mm grid over the rectangle `x`, `y` (mm, ends
/// excluded) at depth `z`, leaving out those `hidden` keeps.
fn grid(x: [i32; 2], y: [i32; 2], z: f64, hidden: impl Fn(f64, f64) -> bool) -> Vec<Vec3> {
    (x[0]..x[1])
        .flat_map(|i| (y[0]..y[1]).map(move |j| Vec3::new(i as f64 + 0.5, j as f64 + 0.5, z)))
        .filter(|p| !hidden(p.x, p.y))
        .collect()
}

/// A plane cluster of each group of points (each at its own depth),
/// indexing the frame of all of them, returned with them.
fn frame_of(groups: &[Vec<Vec3>]) -> (Vec<PlaneCluster>, Vec<Point>) {
    let all: Vec<Vec3> = groups.concat();
    let clusters = groups.iter().map(|g| PlaneCluster::of_points(&all, |p| p.z == g[0].z)).collect();
    (clusters, all.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect())
}

#[test]
fn a_bar_across_a_plate_seen_round_its_end_is_no_lap() {
    // A clamp 30 mm wide, 15 mm over a plate 120 mm wide, from 10 mm
    // inside the plate's one side onto the lower plate past its
    // other: the plate is seen on both of the clamp's sides, one
    // cluster round its end. The lower plate lies 7 mm under it.
    let clamp = |x: f64, y: f64| (-50.0..70.0).contains(&x) && y.abs() < 15.0;
    let (planes, points) = frame_of(&[
        grid([-50, 70], [-15, 15], 685.0, |_, _| false),
        grid([-60, 60], [-100, 100], 700.0, clamp),
        grid([60, 160], [-100, 100], 707.0, clamp),
    ]);
    let err = super::robust_select(planes.clone(), &selection(JointType::Lap), &points).unwrap_err();
    assert_eq!(err.rule().id, "lap.upper_plane_lies_across_lower", "{err}");
    let BackgroundError::LiesAcross { first_mm2, second_mm2, .. } = err else { panic!("{err}") };
    // Beside the clamp, 85 by 110 mm of the plate on either side.
    assert!((first_mm2 - 9_350.0).abs() < 200.0 && (second_mm2 - 9_350.0).abs() < 200.0, "{err}");
    // Without the points, the clusters alone do not show it.
    assert!(robust_select(planes, &selection(JointType::Lap)).is_ok());
}

#[test]
fn a_bar_across_a_small_plate_beside_a_large_one_is_no_lap() {
    // Butt plates at 700: A 200 by 200 mm, B 58 mm wide beside it. A
    // clamp 24 mm wide lies across B, 21 mm over it, and stops short
    // of A: B is seen in two pieces, one on each side of the clamp,
    // each far smaller than A. The layer under the clamp, not its
    // largest piece, is what it lies across.
    let clamp = |p: &Vec3| (-70.0..-3.0).contains(&p.x) && (90.0..114.0).contains(&p.y);
    let all: Vec<Vec3> = [
        grid([-70, -3], [90, 114], 679.0, |_, _| false),
        grid([0, 200], [0, 200], 700.0, |_, _| false),
        grid([-60, -2], [0, 200], 700.0, |x, y| clamp(&Vec3::new(x, y, 0.0))),
    ]
    .concat();
    let planes = vec![
        PlaneCluster::of_points(&all, |p| p.z < 690.0),
        PlaneCluster::of_points(&all, |p| p.z > 690.0 && p.x > 0.0),
        PlaneCluster::of_points(&all, |p| p.z > 690.0 && p.x < 0.0 && p.y < 90.0),
        PlaneCluster::of_points(&all, |p| p.z > 690.0 && p.x < 0.0 && p.y > 114.0),
    ];
    let points: Vec<Point> = all.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
    let err = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap_err();
    assert_eq!(err.rule().id, "lap.upper_plane_lies_across_lower", "{err}");
    let BackgroundError::LiesAcross { first_mm2, second_mm2, .. } = err else { panic!("{err}") };
    // Beside the clamp, B's two pieces: 58 by 90 and 58 by 86 mm.
    assert!((first_mm2 - 5_220.0).abs() < 100.0 && (second_mm2 - 4_988.0).abs() < 100.0, "{err}");
}

#[test]
fn a_lap_whose_lower_plate_runs_on_past_the_upper_plates_end_is_kept() {
    // The upper plate 100 by 300 mm; the lower one, 6 mm under it,
    // reaches 20 mm under it and runs on 50 mm past its end, where
    // it is seen on both sides of the upper plate's long axis.
    let upper = |x: f64, y: f64| (-100.0..0.0).contains(&x) && (-150.0..150.0).contains(&y);
    let (planes, points) =
        frame_of(&[grid([-100, 0], [-150, 150], 700.0, |_, _| false), grid([-20, 100], [-150, 200], 706.0, upper)]);
    let chosen = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap();
    assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.centroid.z), [700.0, 706.0]);
}

#[test]
fn a_lap_whose_lower_plate_is_seen_on_one_side_only_is_kept() {
    // The lower plate split in two along the seam (a streak), both
    // pieces beside the upper plate on the same side of it.
    let mut planes = vec![
        bar(700.0, 20_000.0, 0.0),
        cluster(706.0, 15_000.0, 60.0),
        cluster(706.0, 12_000.0, 60.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    planes[1].centroid.y = -80.0;
    planes[2].centroid.y = 80.0;
    let w = robust_select(planes, &selection(JointType::Lap)).unwrap().workpiece;
    assert_eq!(w.plates[0].plane.offset, 700.0);
    assert_eq!(w.plates[1].area_mm2, 15_000.0);
}

#[test]
fn a_lap_s_lower_plate_is_the_plane_its_upper_plate_stands_beside_not_the_largest_of_its_layer() {
    // The upper plate over x < 0 at 700; the lower plate 6 mm under it
    // from x = -20, seen from x = 0 to 30; a larger part touching it
    // from x = 30 on lies 1.8 mm lower, in the same layer (3 mm).
    let upper = |x: f64, _: f64| x < 0.0;
    let (planes, points) = frame_of(&[
        grid([-100, 0], [-100, 100], 700.0, |_, _| false),
        grid([-20, 30], [-100, 100], 706.0, upper),
        grid([30, 110], [-100, 100], 707.8, |_, _| false),
    ]);
    let chosen = super::robust_select(planes.clone(), &selection(JointType::Lap), &points).unwrap();
    assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.centroid.z), [700.0, 706.0]);
    assert_eq!(chosen.workpiece.layer_mates[1].iter().map(|c| c.centroid.z).collect::<Vec<_>>(), [707.8]);
    assert!(chosen.evidence.contains("6.0 mm over a lower one of 6000 mm²"), "{}", chosen.evidence);
    // Without the points nothing says which stands beside it: the
    // largest, as before.
    let unread = robust_select(planes, &selection(JointType::Lap)).unwrap();
    assert_eq!(unread.workpiece.plates[1].centroid.z, 707.8);
    // Two pieces of the lower plate a streak splits along the seam
    // both stand beside the upper plate: the larger is taken.
    let (planes, points) = frame_of(&[
        grid([-100, 0], [-100, 100], 700.0, |_, _| false),
        grid([-20, 30], [-100, 10], 706.0, upper),
        grid([-20, 30], [12, 100], 706.5, upper),
    ]);
    let split = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap();
    assert_eq!(split.workpiece.plates[1].centroid.z, 706.0);
    // A plate 3.8 mm lower but 16 mm across, with the table between
    // (another workpiece): further than the band a 3.8 mm step hides
    // and the plates' rims, so it is not taken for the lower plate
    // because it is the nearer.
    let (planes, points) = frame_of(&[
        grid([-100, 0], [-100, 100], 700.0, |_, _| false),
        grid([16, 60], [-100, 100], 703.8, |_, _| false),
        grid([80, 200], [-100, 100], 704.0, |_, _| false),
    ]);
    let apart = super::robust_select(planes, &selection(JointType::Lap), &points).unwrap();
    assert_eq!(apart.workpiece.plates[1].centroid.z, 704.0);
}

#[test]
fn a_tee_s_flange_is_the_plane_its_web_stands_beside_not_a_larger_plate_in_its_layer() {
    // A web 8 mm thick along y, its top 80 mm over a flange seen on
    // both of its sides; 30 mm beyond the flange's +x piece, a larger
    // plate of another workpiece lies 2 mm higher, in the flange's
    // layer.
    let (planes, points) = frame_of(&[
        grid([-4, 4], [-100, 100], 680.0, |_, _| false),
        grid([4, 60], [-100, 100], 760.0, |_, _| false),
        grid([-40, -4], [-100, 100], 760.5, |_, _| false),
        grid([90, 200], [-100, 100], 758.0, |_, _| false),
    ]);
    let chosen = super::robust_select(planes.clone(), &selection(JointType::TFillet), &points).unwrap();
    assert_eq!(chosen.layout, Layout::Tee);
    assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.centroid.z), [680.0, 760.0]);
    let e = &chosen.evidence;
    assert!(e.contains("both of its sides") && e.contains("11200") && !e.contains("22000"), "{e}");
    // Without the points, the largest on each side, as before.
    let unread = robust_select(planes, &selection(JointType::TFillet)).unwrap();
    assert_eq!(unread.workpiece.plates[1].centroid.z, 758.0);
}

#[test]
fn the_wrong_joint_requested_is_named_for_what_it_looks_like() {
    // A lap: the upper plate 6 mm over the lower one, the table behind.
    let lap = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
    for joint in [JointType::IButt, JointType::VButt] {
        let err = robust_select(lap.clone(), &selection(joint)).unwrap_err();
        assert!(err.is_joint_mismatch() && err.rule().id == "joint.looks_like_lap", "{err}");
        assert!(err.to_string().contains("6.0 mm apart") && err.to_string().contains("looks like a lap"), "{err}");
    }
    // Butt plates side by side, the table 20 mm behind them (within a
    // lap's step range).
    let butt = vec![cluster(700.0, 30_000.0, -60.0), cluster(700.3, 25_000.0, 60.0), cluster(720.0, 90_000.0, 0.0)];
    let err = robust_select(butt.clone(), &selection(JointType::Lap)).unwrap_err();
    assert!(err.is_joint_mismatch() && err.rule().id == "joint.looks_like_butt", "{err}");
    assert!(err.to_string().contains("looks like a butt joint"), "{err}");
    assert!(robust_select(butt, &selection(JointType::IButt)).is_ok());
    // A clamp beside a lap's upper plate is not a second plate.
    let clamped = vec![
        cluster(700.0, 30_000.0, -60.0),
        cluster(700.5, 2_000.0, 60.0),
        cluster(706.0, 20_000.0, 50.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    assert!(robust_select(clamped, &selection(JointType::Lap)).is_ok());
}

#[test]
fn with_no_type_given_the_layers_decide() {
    let lap = vec![cluster(760.0, 90_000.0, 0.0), cluster(706.0, 20_000.0, 50.0), cluster(700.0, 25_000.0, -50.0)];
    let chosen = robust_select(lap, &auto()).unwrap();
    assert_eq!(chosen.layout, Layout::Lap);
    assert_eq!(chosen.workpiece.plates.each_ref().map(|p| p.plane.offset), [700.0, 706.0]);
    assert!(chosen.evidence.contains("6.0 mm over"), "{}", chosen.evidence);
    let butt = vec![cluster(700.0, 30_000.0, -60.0), cluster(700.3, 25_000.0, 60.0), cluster(720.0, 90_000.0, 0.0)];
    let chosen = robust_select(butt, &auto()).unwrap();
    assert_eq!(chosen.layout, Layout::Butt);
    assert_eq!(chosen.workpiece.depth_to_support_mm, Some(20.0));
    // A plate over a lower plate of its own, nearer than a coplanar
    // pair further on: the nearer top decides
    // (`joint.lap_nearer_than_butt_pair`).
    let over = vec![
        cluster(694.0, 8_000.0, 0.0),
        cluster(700.0, 30_000.0, -60.0),
        cluster(710.0, 25_000.0, 60.0),
        cluster(710.3, 25_000.0, 160.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    assert_eq!(robust_select(over.clone(), &auto()).unwrap().layout, Layout::Lap);
    // A plate lying across a coplanar pair (a clamp or a fixture) is
    // not a lap's upper plate, however large.
    let across = vec![
        cluster(694.0, 20_000.0, 0.0),
        cluster(700.0, 30_000.0, -60.0),
        cluster(700.3, 25_000.0, 60.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    assert_eq!(robust_select(across, &auto()).unwrap().layout, Layout::Butt);
    // A plate with a small piece beside it, 4 mm over a lower plane: a
    // butt pair barely in view, or a lap's upper plate cut by a streak.
    let piece = vec![
        cluster(700.0, 20_000.0, 0.0),
        cluster(700.0, 1_600.0, -70.0),
        cluster(704.0, 40_000.0, -120.0),
        cluster(760.0, 90_000.0, 0.0),
    ];
    let err = robust_select(piece.clone(), &auto()).unwrap_err();
    assert!(err.rule().id == "joint.plate_and_piece_over_lower_plane" && err.is_unrecognised(), "{err}");
    assert_eq!(robust_select(piece, &selection(JointType::IButt)).unwrap().layout, Layout::Butt);
    // Two planes 60 mm apart are neither.
    let apart = vec![cluster(700.0, 1000.0, 0.0), cluster(760.0, 1000.0, 0.0)];
    let err = robust_select(apart, &auto()).unwrap_err();
    assert!(err.is_unrecognised() && !err.is_joint_mismatch(), "{err}");
    assert_eq!(err.rule().id, "joint.no_layout_fits", "{err}");
    assert!(err.to_string().contains("no two coplanar") && err.to_string().contains("no two layers"), "{err}");
}

#[test]
fn failures_say_what_was_found() {
    let one = vec![cluster(700.0, 1000.0, 0.0)];
    let err = robust_select(one, &selection(JointType::IButt)).unwrap_err();
    assert_eq!(err.rule().id, "workpiece.fewer_than_two_planes");
    assert_eq!(err.to_string(), "found 1 workpiece plane(s), need 2");
    let apart = vec![cluster(700.0, 1000.0, 0.0), cluster(760.0, 1000.0, 0.0)];
    let butt = robust_select(apart.clone(), &selection(JointType::IButt)).unwrap_err();
    assert_eq!(butt.rule().id, "butt.no_coplanar_pair", "{butt}");
    assert!(matches!(butt, BackgroundError::NoCoplanarPair { .. }));
    let lap = robust_select(apart, &selection(JointType::Lap)).unwrap_err();
    assert_eq!(lap.rule().id, "lap.no_plate_step", "{lap}");
    assert!(matches!(lap, BackgroundError::NoLapStep { .. }));
}

/// Every refusal's rule carries the refusal class the planner gave it
/// before rules had ids: a joint other than the one requested, one `auto`
/// cannot tell, a corner, or none.
#[test]
fn each_refusal_s_rule_carries_its_refusal_class() {
    use crate::rules::Gate;
    let lap = || Box::new(BackgroundError::NoLapStep { found: 2, offsets_mm: vec![], min_mm: 1.0, max_mm: 30.0 });
    let every = [
        BackgroundError::TooFewPlanes { found: 1 },
        BackgroundError::NoCoplanarPair { found: 2, offsets_mm: vec![] },
        *lap(),
        BackgroundError::PairUnderLargerPlane { area_mm2: 1.0, above_mm: 1.0, smaller_mm2: 1.0 },
        BackgroundError::LooksLikeLap { joint: JointType::IButt, step_mm: 6.0 },
        BackgroundError::LooksLikeButt { first_mm2: 1.0, second_mm2: 1.0, tolerance_mm: 3.0 },
        BackgroundError::LiesAcross { top_mm2: 1.0, above_mm: 1.0, first_mm2: 1.0, second_mm2: 1.0 },
        BackgroundError::ThreeSideBySide { joint: JointType::IButt, first_mm2: 1.0, second_mm2: 1.0, third_mm2: 1.0 },
        BackgroundError::Ambiguous { first_mm2: 1.0, second_mm2: 1.0, step_mm: 4.0 },
        BackgroundError::LooksLikeTee {
            joint: JointType::Lap,
            top_mm2: 1.0,
            width_mm: 1.0,
            height_mm: 50.0,
            first_mm2: 1.0,
            second_mm2: 1.0,
        },
        BackgroundError::NoWeb {
            found: 2,
            offsets_mm: vec![],
            min_mm: 30.0,
            min_height_per_width: 1.5,
            max_mm: 250.0,
            max_width_mm: 30.0,
        },
        BackgroundError::OneSidedWeb { top_mm2: 1.0, width_mm: 1.0, height_mm: 50.0, beside_mm2: 1.0 },
        BackgroundError::LooksLikeCorner { kind: CornerKind::Inside, what: String::new() },
        BackgroundError::LooksLikeCorner { kind: CornerKind::Outside, what: String::new() },
        BackgroundError::Unrecognised { butt: Box::new(BackgroundError::TooFewPlanes { found: 1 }), lap: lap() },
    ];
    let mut ids = std::collections::HashSet::new();
    for err in &every {
        let class = if err.is_joint_mismatch() {
            Some(Gate::JointMismatch)
        } else if err.is_unrecognised() {
            Some(Gate::JointUnknown)
        } else if matches!(err, BackgroundError::LooksLikeCorner { .. }) {
            Some(Gate::CornerJoint)
        } else {
            None
        };
        assert_eq!(err.rule().gate, class, "{}: {err}", err.rule().id);
        assert_eq!(err.rule().stage, crate::rules::Stage::Background, "{}", err.rule().id);
        ids.insert(err.rule().id);
    }
    // One rule per finding.
    assert_eq!(ids.len(), every.len());
}
