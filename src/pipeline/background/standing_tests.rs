//! A member standing on a plate whatever the width of its top (issue 49's
//! blocks): found by the face falling from its top to the plate, not by
//! its top's shape.

use super::*;
use crate::cloud::Point;

/// The layers' selection of the background tests, with room for the
/// blocks' tilt and coarser neighbourhoods.
fn auto() -> Selection {
    Selection { max_tilt_deg: 20.0, neighbour_radius_mm: 2.0, ..super::tests::auto() }
}

fn asking(joint: JointType) -> Selection {
    Selection { joint: Some(joint), ..auto() }
}

/// A block 60 mm across x and 80 mm along y standing `height` mm on a
/// plate at depth 760 (x and y −100..100 round it), seen from the camera
/// at the origin looking down +z: its top, its +x face from `face`'s
/// first to its second height over the plate (none, if None), and the
/// plate. The clusters are the
/// top's and the plate's (one piece round the block); the face is no
/// plane cluster (its normal lies across the camera's).
fn block(height: f64, face: Option<(f64, f64)>) -> (Vec<PlaneCluster>, Vec<Point>) {
    let under_block = |x: f64, y: f64| x.abs() < 30.0 && y.abs() < 40.0;
    let plate: Vec<Vec3> = (-100..100)
        .flat_map(|i| (-100..100).map(move |j| Vec3::new(i as f64 + 0.5, j as f64 + 0.5, 760.0)))
        .filter(|p| !under_block(p.x, p.y))
        .collect();
    let top_z = 760.0 - height;
    let top: Vec<Vec3> =
        (-30..30).flat_map(|i| (-40..40).map(move |j| Vec3::new(i as f64 + 0.5, j as f64 + 0.5, top_z))).collect();
    let face: Vec<Vec3> = face
        .into_iter()
        .flat_map(|(from, to)| {
            (-40..40).flat_map(move |j| {
                (0..=(to - from) as i32).map(move |k| Vec3::new(30.2, j as f64 + 0.5, 760.0 - from - k as f64))
            })
        })
        .collect();
    let all: Vec<Vec3> = [top, plate, face].concat();
    let clusters =
        vec![PlaneCluster::of_points(&all, |p| p.z == top_z), PlaneCluster::of_points(&all, |p| p.z == 760.0)];
    (clusters, all.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect())
}

#[test]
fn a_block_standing_on_a_plate_is_a_tee_by_the_face_falling_from_its_top() {
    // 60 mm tall, its face seen from 1 mm over the plate to 1 mm under
    // its top: a web's top 60 mm wide, too wide for a web by its shape.
    let (planes, points) = block(60.0, Some((1.0, 59.0)));
    assert!(planes[0].width_mm() > 30.0 && planes[0].elongation < 2.0, "{:?}", planes[0].clone_shape());
    for s in [asking(JointType::TFillet), auto()] {
        let chosen = robust_select(planes.clone(), &s, &points).unwrap();
        assert_eq!(chosen.layout, Layout::Tee, "{:?}", s.joint);
        assert!(chosen.web_by_faces);
        assert!(chosen.evidence.contains("60.0 mm over a flange seen on both of its sides"), "{}", chosen.evidence);
    }
    // Under a butt's or a lap's request the block is not read as a tee
    // (a clamp across those joints stands so too): those layouts' own
    // refusals, not `joint.looks_like_tee`.
    for joint in [JointType::IButt, JointType::Lap] {
        let err = robust_select(planes.clone(), &asking(joint), &points).unwrap_err();
        assert_ne!(err.rule().id, "joint.looks_like_tee", "{err}");
    }
}

#[test]
fn a_wide_top_with_no_face_falling_to_the_plate_or_no_higher_than_a_lap_step_is_no_web() {
    // Nothing seen between the top and the plate, or a face seen only
    // near the top (a plate held over another): no web's top.
    for face in [None, Some((40.0, 59.0))] {
        let (planes, points) = block(60.0, face);
        let err = robust_select(planes.clone(), &asking(JointType::TFillet), &points).unwrap_err();
        assert_eq!(err.rule().id, "tee.no_web_top", "{face:?}: {err}");
        assert!(err.to_string().contains("nor a wider one standing"), "{err}");
        let err = robust_select(planes, &auto(), &points).unwrap_err();
        assert_eq!(err.rule().id, "joint.no_layout_fits", "{face:?}: {err}");
    }
    // A block 20 mm tall, its face seen down to the plate: no higher
    // than a lap's upper plate is thick, it is no web by its faces.
    let (planes, points) = block(20.0, Some((1.0, 19.0)));
    let err = robust_select(planes, &asking(JointType::TFillet), &points).unwrap_err();
    assert_eq!(err.rule().id, "tee.no_web_top", "{err}");
}
