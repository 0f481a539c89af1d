//! The faults' validation, rendering and right answers on small scenes.

use super::*;
use crate::geometry::vec3;
use crate::sim::{CameraPlacement, NoiseSpec, demo_scene, simulate};

fn small_camera() -> CameraModel {
    CameraModel { width_px: 480, height_px: 300, ..CameraModel::default() }
}

/// A noise-free demo scene of `joint` seen from 600 mm at 15 degrees.
fn clean(joint: JointType) -> SceneSpec {
    let mut spec = demo_scene(joint);
    spec.noise = NoiseSpec::none();
    spec.placement = CameraPlacement { tilt_azimuth_deg: 40.0, ..CameraPlacement::straight(600.0, 15.0) };
    spec
}

/// The pixels a fault changes: `(clean point, faulted point)` in the
/// workpiece frame, either absent where that frame has no return.
fn changes(spec: &SceneSpec, fault: Fault) -> Vec<(Option<Vec3>, Option<Vec3>)> {
    let camera = small_camera();
    let mut faulted = spec.clone();
    faulted.faults.push(fault);
    assert_eq!(faulted.validate(), Ok(()));
    let workpiece_from_camera = spec.workpiece_from_camera();
    let to_workpiece = |p: &crate::cloud::Point| {
        p[0].is_finite().then(|| workpiece_from_camera.transform_point(&vec3(p).into()).coords)
    };
    let (a, b) = (simulate(spec, &camera), simulate(&faulted, &camera));
    a.cloud
        .points()
        .iter()
        .zip(b.cloud.points())
        .filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits))
        .map(|(p, q)| (to_workpiece(p), to_workpiece(q)))
        .collect()
}

#[test]
fn a_dropout_band_removes_the_returns_over_the_seam_and_nothing_else() {
    for joint in JointType::ALL {
        let spec = clean(joint);
        let half = spec.joint.seam_edge_half_width() + 2.0;
        let changed = changes(&spec, Fault::SeamDropout { along_mm: [100.0, 140.0], margin_mm: 2.0 });
        assert!(changed.len() > 20, "{joint}: {} pixels", changed.len());
        for (before, after) in changed {
            let p = before.expect("a band only removes returns");
            assert!(after.is_none(), "{joint}: a return kept");
            assert!((100.0..=140.0).contains(&p.y) && p.x.abs() <= half + 1e-6, "{joint}: {p:?}");
        }
    }
}

#[test]
fn glaring_edges_remove_returns_near_each_edge_along_its_own_runs_only() {
    for joint in JointType::ALL {
        let spec = clean(joint);
        let glare = Fault::EdgeGlare { seed: 11, band_mm: 1.5, run_mm: [5.0, 20.0], share: 0.3 };
        let runs = glare.glare_runs(&spec);
        let [y0, y1] = spec.seam_range();
        for edge in &runs {
            assert!(!edge.is_empty(), "{joint}: every edge glares somewhere");
            let covered: f64 = edge.iter().map(|[a, b]| b - a).sum();
            assert!((0.1..=0.6).contains(&(covered / (y1 - y0))), "{joint}: covers {covered:.0} mm of {:.0}", y1 - y0);
        }
        assert_ne!(runs[0], runs[1], "{joint}: each edge glares on its own");
        let edges = spec.joint.seam_edges_xz();
        let changed = changes(&spec, glare);
        assert!(changed.len() > 20, "{joint}: {} pixels", changed.len());
        for (before, after) in changed {
            let p = before.expect("glare only removes returns");
            assert!(after.is_none(), "{joint}: a return kept");
            let near = edges.iter().zip(&runs).any(|([x, z], runs)| {
                (p.x - x).hypot(p.z - z) <= 1.5 + 1e-6 && runs.iter().any(|[a, b]| (*a..=*b).contains(&p.y))
            });
            assert!(near, "{joint}: {p:?} is near no glaring run of an edge");
        }
    }
}

#[test]
fn under_glaring_edges_a_piece_is_a_stretch_where_neither_edge_glares() {
    let mut spec = clean(JointType::IButt);
    let glare = Fault::EdgeGlare { seed: 11, band_mm: 1.5, run_mm: [5.0, 20.0], share: 0.3 };
    let runs: Vec<[f64; 2]> = glare.glare_runs(&spec).into_iter().flatten().collect();
    spec.faults.push(glare);
    let answer = right_answer(&spec, &small_camera());
    assert!(answer.whole_seam && !answer.refuse);
    assert!(!answer.pieces_mm.is_empty());
    for [a, b] in &answer.pieces_mm {
        assert!(b - a >= MIN_PIECE_MM);
        assert!(runs.iter().all(|[c, d]| d <= a || c >= b), "piece {a:.1}..{b:.1} overlaps a glaring run");
    }
}

#[test]
fn a_clamp_covers_the_seam_where_it_lies_and_shadows_beside_it() {
    for joint in JointType::ALL {
        let spec = clean(joint);
        let top = spec.joint.top_z(-1.0).max(spec.joint.top_z(1.0));
        let clamp = Fault::Clamp { centre_mm: 120.0, width_mm: 30.0, height_mm: 20.0, half_reach_mm: 60.0 };
        let changed = changes(&spec, clamp.clone());
        let on_clamp = changed.iter().filter(|(_, q)| q.is_some_and(|q| (q.z - top - 20.0).abs() < 1e-3)).count();
        assert!(on_clamp > 100, "{joint}: {on_clamp} returns on the clamp's top");
        // Hidden behind it or in its shadow: within a few heights of it.
        for (before, after) in &changed {
            let p = before.or(*after).unwrap();
            assert!((p.y - 120.0).abs() <= 15.0 + 3.0 * 20.0 && p.x.abs() <= 60.0 + 3.0 * 20.0, "{joint}: {p:?}");
        }
        let mut faulted = spec.clone();
        faulted.faults.push(clamp);
        let pieces = visible_pieces(&faulted, &small_camera());
        assert_eq!(pieces.len(), 2, "{joint}: {pieces:?}");
        assert!(pieces[0][1] <= 105.0 && pieces[1][0] >= 135.0, "{joint}: {pieces:?}");
        assert!(pieces[0][0] < 1.0 && pieces[1][1] > 239.0, "{joint}: {pieces:?}");
    }
}

#[test]
fn tack_welds_fill_the_seam_at_their_pitch() {
    for joint in JointType::ALL {
        let spec = clean(joint);
        let tacks = Fault::TackWelds { first_mm: 30.0, pitch_mm: 60.0, length_mm: 8.0, crown_mm: 1.5, spread_mm: 2.0 };
        let reach = spec.joint.seam_edge_half_width() + 2.0 + 1.5 + 1.0;
        let changed = changes(&spec, tacks.clone());
        assert!(changed.len() > 20, "{joint}: {} pixels", changed.len());
        for (before, after) in &changed {
            let p = after.or(*before).unwrap();
            let to_tack = ((p.y - 30.0).rem_euclid(60.0)).min(60.0 - (p.y - 30.0).rem_euclid(60.0));
            // The tack itself, or its shadow a few mm beside it.
            assert!(to_tack <= 4.0 + 6.0 && p.x.abs() <= reach + 6.0, "{joint}: {p:?}");
        }
        let mut faulted = spec.clone();
        faulted.faults.push(tacks);
        let pieces = visible_pieces(&faulted, &small_camera());
        // Tacks at 30, 90, 150 and 210 mm of a 240 mm seam.
        assert_eq!(pieces.len(), 5, "{joint}: {pieces:?}");
    }
}

#[test]
fn spatter_lands_beside_the_seam() {
    let spec = clean(JointType::VButt);
    let spread = spec.joint.seam_edge_half_width() + 15.0;
    let changed = changes(&spec, Fault::Spatter { seed: 3, count: 40, radius_mm: 2.0, spread_mm: spread });
    assert!(changed.len() > 40, "{} pixels", changed.len());
    for (before, after) in changed {
        let p = after.or(before).unwrap();
        assert!(p.x.abs() <= spread + 2.0 + 8.0, "{p:?}");
    }
}

#[test]
fn streaks_move_depths_along_lines_by_their_offset() {
    let spec = clean(JointType::Lap);
    let streaks = Fault::SpecularStreaks { seed: 5, count: 2, length_mm: 60.0, width_px: 2.0, offset_mm: 10.0 };
    let camera = small_camera();
    let mut faulted = spec.clone();
    faulted.faults.push(streaks);
    let (a, b) = (simulate(&spec, &camera), simulate(&faulted, &camera));
    let moved: Vec<f32> = a
        .cloud
        .points()
        .iter()
        .zip(b.cloud.points())
        .filter(|(p, q)| p[2].to_bits() != q[2].to_bits())
        .map(|(p, q)| (q[2] - p[2]).abs())
        .collect();
    // Two streaks about 60 mm (some 40 px here) long and 2 px wide.
    assert!((60..=400).contains(&moved.len()), "{} pixels", moved.len());
    assert!(moved.iter().all(|d| (4.9..=15.1).contains(d)), "{moved:?}");
}

#[test]
fn a_touching_part_abuts_the_plates_outer_edge() {
    let spec = clean(JointType::IButt);
    let width_b = spec.plate_b.width_mm;
    let changed = changes(&spec, Fault::TouchingPart { plate: PlateSide::B, width_mm: 60.0, step_mm: 2.0 });
    assert!(changed.len() > 500, "{} pixels", changed.len());
    for (before, after) in changed {
        let p = after.or(before).unwrap();
        assert!(p.x >= width_b - 10.0 && p.x <= width_b + 60.0 + 1e-6, "{p:?}");
    }
}

#[test]
fn a_plate_barely_in_view_shows_the_sliver_asked_for() {
    let camera = CameraModel::default();
    for (joint, plate) in [(JointType::VButt, PlateSide::A), (JointType::Lap, PlateSide::B)] {
        let mut spec = demo_scene(joint);
        spec.faults.push(Fault::BarelyInView { plate, in_view_mm: 10.0 });
        frame_barely_in_view(&mut spec, &camera).unwrap();
        assert_eq!(spec.validate(), Ok(()));
        let f = crate::sim::framing(&spec, &camera);
        let index = usize::from(plate == PlateSide::B);
        assert!((f.plate_in_view_mm[index] - 10.0).abs() < 0.5, "{joint}: {f:?}");
        assert!(f.plate_in_view_mm[1 - index] > 40.0 && f.observed_seam_mm > 80.0, "{joint}: {f:?}");
    }
}

#[test]
fn a_wrong_joint_changes_the_request_not_the_frame() {
    let spec = clean(JointType::IButt);
    assert!(changes(&spec, Fault::WrongJoint { requested: JointType::VButt }).is_empty());
    let mut wrong = spec.clone();
    wrong.faults.push(Fault::WrongJoint { requested: JointType::VButt });
    assert_eq!((wrong.requested_joint(), wrong.requested_groove_depth_mm()), (JointType::VButt, Some(3.0)));
    let answer = right_answer(&wrong, &small_camera());
    assert!(answer.refuse && !answer.whole_seam && answer.pieces_mm.is_empty());
    wrong.faults = vec![Fault::WrongJoint { requested: JointType::IButt }];
    assert!(wrong.validate().unwrap_err().to_string().contains("another joint"));
}

#[test]
fn faults_are_validated_with_the_reason() {
    let mut spec = clean(JointType::VButt);
    spec.faults = vec![Fault::Clamp { centre_mm: 100.0, width_mm: 20.0, height_mm: 10.0, half_reach_mm: 2.0 }];
    assert!(spec.validate().unwrap_err().to_string().contains("clamp: the clamp must reach"));
    spec.faults = vec![Fault::SeamDropout { along_mm: [400.0, 450.0], margin_mm: 1.0 }];
    assert!(spec.validate().unwrap_err().to_string().contains("overlapping the seam"));
    spec.faults = vec![Fault::BarelyInView { plate: PlateSide::A, in_view_mm: 60.0 }];
    assert!(spec.validate().unwrap_err().to_string().contains("less than 40 mm"));
    assert_eq!("tack_welds".parse::<FaultKind>(), Ok(FaultKind::TackWelds));
    assert!("rust".parse::<FaultKind>().is_err());
    for kind in FaultKind::ALL {
        let mut spec = clean(JointType::Lap);
        spec.faults.push(Fault::example(kind, &spec));
        frame_barely_in_view(&mut spec, &CameraModel::default()).unwrap();
        assert_eq!(spec.validate(), Ok(()), "{kind}");
        assert_eq!(spec.fault_kind(), Some(kind));
    }
}
