//! The groove probe on constructed clouds: a V-groove, a square gap, a
//! veil along the rays, a plate standing between the edges.

use super::fit::root_hinge;
use super::points::{MIN_SURFACE_NEIGHBOURS, SURFACE_RADIUS_SPACINGS};
use super::profile::MIN_FACE_POINTS;
use super::*;
use crate::pipeline::refit::SeamAxes;

fn edge(a: f64) -> SeamCurve {
    SeamCurve {
        axes: SeamAxes { origin: Vec3::new(0.0, 0.0, 700.0), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() },
        coef_a: vec![a, 0.0],
        coef_b: vec![0.0, 0.0],
        s_min: -50.0,
        s_max: 50.0,
    }
}

/// Points every `step` mm over a profile `z(x)` across the seam (x) and
/// along it (y), rows shifted against each other as a camera's pixels
/// fall, at 700 mm from the camera.
fn cloud_of(profile: impl Fn(f64) -> Option<f64>, half_width: f64, step: f64) -> PointCloud {
    let mut points = Vec::new();
    let n = (half_width / step) as i64;
    let rows = (50.0 / step) as i64;
    for j in -rows..=rows {
        for i in -n..=n {
            let x = i as f64 * step + step * (j as f64 * 0.618).fract();
            if let Some(depth) = profile(x) {
                points.push([x as f32, (j as f64 * step) as f32, (700.0 + depth) as f32]);
            }
        }
    }
    PointCloud::unorganized(points)
}

/// The reference of [`on_surfaces`]: every point's neighbours counted
/// through the cell index the unorganized clouds' neighbour searches
/// use (a query stops as soon as it has enough).
pub(super) fn on_surfaces_by_cells(points: Vec<Across>, radius: f64) -> Vec<Across> {
    use crate::pipeline::neighbours::cells::CellIndex;
    use std::ops::ControlFlow;
    let coords: Vec<Point> = points.iter().map(|p| [p.s, p.t, p.h].map(|v| v as f32)).collect();
    let index = CellIndex::for_radius(&coords, radius);
    let radius_sq = (radius * radius) as f32;
    let keep: Vec<bool> = coords
        .iter()
        .map(|p| {
            // The point itself is among them.
            let mut found = 0;
            index.visit_within(p, radius_sq, radius_sq * (1.0 + 1e-5), |_| {
                found += 1;
                if found > MIN_SURFACE_NEIGHBOURS { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            });
            found > MIN_SURFACE_NEIGHBOURS
        })
        .collect();
    points.into_iter().zip(keep).filter_map(|(p, k)| k.then_some(p)).collect()
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// The slab reading keeps exactly the points the cell index keeps:
    /// points on a lattice, dense or sparse, whose spacing puts many
    /// neighbours exactly at the radius (and repeats some), and strays
    /// among them, near the seam's middle and far along it.
    #[test]
    fn the_surface_filter_keeps_what_the_cell_index_keeps(
        lattice in proptest::collection::vec((-10i32..10, -5i32..5, 0i32..4), 0..600),
        strays in proptest::collection::vec((-10.0f64..10.0, -5.0f64..5.0, 0.0f64..4.0), 0..100),
        step in proptest::sample::select(vec![0.25f64, 0.5, 1.0]),
        radius_steps in proptest::sample::select(vec![1.0f64, 1.5, 2.0]),
        along in proptest::sample::select(vec![0.0f64, -187.3, 291.9]),
    ) {
        let points: Vec<Across> = lattice
            .iter()
            .map(|&(s, t, h)| (s as f64 * step, t as f64 * step, h as f64 * step))
            .chain(strays.iter().map(|&(s, t, h)| (s * step, t * step, h * step)))
            .map(|(s, t, h)| Across { s: s + along, station: 0, t, h })
            .collect();
        let radius = radius_steps * step;
        let key = |v: Vec<Across>| v.iter().map(|p| (p.s.to_bits(), p.t.to_bits(), p.h.to_bits())).collect::<Vec<_>>();
        proptest::prop_assert_eq!(
            key(on_surfaces(points.clone(), radius)),
            key(on_surfaces_by_cells(points, radius))
        );
    }
}

/// A bevel 64 degrees from the camera's rays, as a V-groove's is under a
/// camera straight above it: its points `pitch` apart along the seam (the
/// camera's pixel step there) and 2.3 spacings apart across it. Every
/// point is on the surface wherever the pixel step lies within a few
/// percent of the cloud's median spacing, either side of it.
#[test]
fn a_bevel_seen_nearly_head_on_stays_on_its_surface_wherever_the_pixel_step_falls() {
    let spacing = 0.19;
    for pitch in [0.95 * spacing, spacing, 1.04 * spacing, 1.1 * spacing] {
        let points: Vec<Across> = (0..60)
            .flat_map(|j| (0..10).map(move |i| (j, i)))
            .map(|(j, i)| {
                let across = 2.3 * spacing * i as f64;
                Across { s: j as f64 * pitch, station: 0, t: across * 0.44, h: across * 0.9 }
            })
            .collect();
        // The patch's own first and last two rows along the seam lack
        // the neighbours beyond them; every other point is kept.
        let inside = |p: &Across| (1.5 * pitch..57.5 * pitch).contains(&p.s);
        let kept = on_surfaces(points.clone(), SURFACE_RADIUS_SPACINGS * spacing);
        let (kept, all) = (kept.iter().filter(|p| inside(p)).count(), points.iter().filter(|p| inside(p)).count());
        assert_eq!(kept, all, "pitch {pitch:.3} mm on a {spacing} mm cloud");
    }
    // A mixed pixel's row: neighbours along the seam a pixel step apart,
    // each at its own depth millimetres off the next, is no surface.
    let veil: Vec<Across> = (0..60)
        .map(|j| Across { s: j as f64 * spacing, station: 0, t: 0.0, h: 1.0 + 1.7 * ((j * 7) % 5) as f64 })
        .collect();
    assert!(on_surfaces(veil, SURFACE_RADIUS_SPACINGS * spacing).is_empty());
}

fn probed(cloud: &PointCloud, half_opening: f64) -> GrooveProfile {
    probed_between(cloud, &edge(-half_opening), &edge(half_opening))
}

fn probed_between(cloud: &PointCloud, e1: &SeamCurve, e2: &SeamCurve) -> GrooveProfile {
    probe(
        cloud,
        &ProbeSetting {
            edges: [e1, e2],
            span: (-45.0, 45.0),
            point_spacing_mm: 0.2,
            depth_to_support_mm: Some(20.0),
            floor_between_plates: false,
            grid: None,
            projector: Vec3::zeros(),
        },
    )
}

/// A 60 degree V-groove 5 mm deep with a 1 mm root gap, whose bevels
/// reach x = ±0.5, and its half opening at the top.
fn v_groove_cloud() -> (PointCloud, f64) {
    let tan = 30f64.to_radians().tan();
    let w = 0.5 + 5.0 * tan;
    let v = |x: f64| {
        if x.abs() >= w {
            Some(0.0)
        } else if x.abs() >= 0.5 {
            Some((w - x.abs()) / tan)
        } else {
            None
        }
    };
    (cloud_of(v, 10.0, 0.2), w)
}

#[test]
fn stray_returns_below_a_groove_do_not_set_its_depth() {
    // The 5 mm groove, and under it, past 3 mm where nothing is seen,
    // a sheet of stray returns 1.5 to 2.5 mm off the midline along the
    // seam, 8 to 10 mm deep (what a specular streak left under a
    // groove at 1 mm voxels): no root face of the bevels above.
    let (cloud, w) = v_groove_cloud();
    let mut points = cloud.points().to_vec();
    for j in -50..=50 {
        for k in 0..=20 {
            let (y, depth) = (j as f64, 8.0 + k as f64 * 0.1);
            let x = 1.5 + 0.05 * (k % 20) as f64;
            points.extend([-x, x].map(|x| [x as f32, y as f32, (700.0 + depth) as f32]));
        }
    }
    let profile = probed(&PointCloud::unorganized(points), w);
    assert_eq!(profile.verdict(), Between::Groove, "{}", profile.describe());
    assert!((profile.depth_mm().unwrap() - 5.0).abs() < 0.2, "{}", profile.describe());
}

#[test]
fn a_bevel_s_root_face_is_where_it_narrows_into_it() {
    // Depth bins a spacing (1 mm) apart: a bevel |t| = 5 - 0.5 h down
    // to 6 mm, then a root face at |t| = 2 below it: the hinge at 6.
    let bevel = |h: f64| (h, 5.0 - 0.5 * h);
    let mut medians: Vec<(f64, f64)> = (0..6).map(|k| bevel(k as f64 + 0.5)).collect();
    medians.extend((6..10).map(|k| (k as f64 + 0.5, 2.0)));
    let hinge = root_hinge(&medians, 1.0).expect("a root face under the bevel");
    assert_eq!(hinge.bins_above, 6);
    assert!((hinge.depth_mm - 6.0).abs() < 1e-9 && (hinge.root_half_gap_mm - 2.0).abs() < 1e-9, "{hinge:?}");
    // Bins of one |t| far out from where the bevel ends (it reaches
    // |t| = 0.25 at 9.5 mm): not its root face, which the bevel's
    // line meets 7 mm above them.
    let mut far_out: Vec<(f64, f64)> = (0..10).map(|k| bevel(k as f64 + 0.5)).collect();
    far_out.extend((10..13).map(|k| (k as f64 + 0.5, 3.5)));
    assert!(root_hinge(&far_out, 1.0).is_none(), "{:?}", root_hinge(&far_out, 1.0));
    // fault-streaks-v-butt-00 at 1 mm voxels (a spacing of 0.947 mm):
    // the bevel seen down to 9.9 mm, then a streak's stray returns 12 to
    // 16 mm down. The bevel's last three bins and the strays scatter about
    // one |t| (2.18) less than a spacing, and the bevel's line meets it
    // within two bins of the split, but the bevel runs on 3.3 bins past
    // that meeting: no root face.
    let strays = [
        (1.4, 4.24),
        (2.4, 4.03),
        (3.3, 3.62),
        (4.3, 3.22),
        (5.2, 2.82),
        (6.2, 2.42),
        (7.1, 2.02),
        (8.1, 1.62),
        (9.0, 1.2),
        (9.9, 1.01),
        (11.8, 3.02),
        (12.8, 1.98),
        (13.7, 3.16),
        (15.6, 3.27),
    ];
    assert!(root_hinge(&strays, 0.947).is_none(), "{:?}", root_hinge(&strays, 0.947));
    // The same frame cropped 25 mm round the seam: the strays lie so that
    // the wall's |t| (2.08) is the bevel's own at the first bin below the
    // split, 7.1 mm down, where the two cannot be told apart. Read from
    // that bin, the bevel seemed to end there, and the depth was read at
    // 7.02 mm (the groove is 9.6 mm deep): the bevel's run past the
    // meeting is read through the bins where line and wall coincide.
    let cropped = [
        (1.42, 4.24),
        (2.37, 4.04),
        (3.32, 3.63),
        (4.26, 3.22),
        (5.21, 2.84),
        (6.16, 2.45),
        (7.11, 2.04),
        (8.05, 1.65),
        (9.0, 1.22),
        (9.95, 1.03),
        (11.84, 3.04),
        (13.74, 2.5),
        (14.68, 2.31),
        (15.63, 2.85),
    ];
    assert!(root_hinge(&cropped, 0.95).is_none(), "{:?}", root_hinge(&cropped, 0.95));
    // A root face's first bin, where the bevel's line crosses its |t|,
    // still starts it: the hinge of a bevel 15° off the normal (|t| =
    // 5 - 0.27 h, meeting |t| = 2 at 11.1 mm), its line within half a
    // spacing of the face's |t| over almost two bins, with the first bin
    // below at 11.5 mm.
    let near_normal = |h: f64| (h, 5.0 - 0.27 * h);
    let mut root: Vec<(f64, f64)> = (0..11).map(|k| near_normal(k as f64 + 0.5)).collect();
    root.extend((11..15).map(|k| (k as f64 + 0.5, 2.0)));
    let hinge = root_hinge(&root, 1.0).expect("a root face under the bevel");
    assert_eq!(hinge.bins_above, 11, "{hinge:?}");
}

#[test]
fn every_point_of_the_probed_box_falls_in_the_rows_read() {
    let camera = crate::camera::CameraModel::default();
    let grid = CameraGrid::for_camera(&camera);
    // A box 300 mm along a seam crossing the view at a slant, 20 mm
    // across, from 150 mm above the plates to 30 mm below, 700 mm off.
    let (e, a) = (Vec3::new(0.8, 0.55, 0.2).normalize(), Vec3::new(-0.55, 0.8, 0.1).normalize());
    let b = e.cross(&a).normalize();
    let origin = Vec3::new(20.0, -10.0, 700.0);
    let at = |s: f64, t: f64, h: f64| origin + e * s + a * t + b * h;
    let corners: Vec<Vec3> = (0..8)
        .map(|k| {
            at(
                if k & 1 == 0 { -150.0 } else { 150.0 },
                if k & 2 == 0 { -10.0 } else { 10.0 },
                if k & 4 == 0 { -150.0 } else { 30.0 },
            )
        })
        .collect();
    let rows = rows_under(&grid, &corners).unwrap();
    let (width, height) = grid.size();
    let read: std::collections::HashSet<usize> =
        rows.iter().flat_map(|&(v, u0, u1)| (u0..=u1).map(move |u| v * width + u)).collect();
    assert!(read.len() < width * height / 4, "{} of {} pixels", read.len(), width * height);
    let mut missed = 0;
    for k in 0..20_000 {
        let f = |m: u64| ((k * m) % 1009) as f64 / 1008.0;
        let p = at(-150.0 + 300.0 * f(7), -10.0 + 20.0 * f(13), -150.0 + 180.0 * f(31));
        if let Some(i) = grid.pixel_of(&p) {
            missed += usize::from(!read.contains(&i));
        }
    }
    assert_eq!(missed, 0);
    // A corner behind the camera: no projection, the whole frame.
    let behind: Vec<Vec3> = corners.iter().map(|c| c - Vec3::new(0.0, 0.0, 800.0)).collect();
    assert!(rows_under(&grid, &behind).is_none());
}

#[test]
fn a_bevel_cut_by_the_probes_bottom_shows_no_root() {
    // The groove of the test below, 5 mm deep, with a surface taken for
    // the plates' support 3.5 mm down (another part's plate, in a frame
    // of several): the probe stops at 3 mm, and the bevels' feet there
    // are not the root.
    let tan = 30f64.to_radians().tan();
    let w = 0.5 + 5.0 * tan;
    let v = |x: f64| if x.abs() >= w { Some(0.0) } else { (x.abs() >= 0.5).then(|| (w - x.abs()) / tan) };
    let cloud = cloud_of(v, 10.0, 0.2);
    let (e1, e2) = (edge(-w), edge(w));
    let setting = ProbeSetting {
        edges: [&e1, &e2],
        span: (-45.0, 45.0),
        point_spacing_mm: 0.2,
        depth_to_support_mm: Some(3.5),
        floor_between_plates: false,
        grid: None,
        projector: Vec3::zeros(),
    };
    let profile = probe(&cloud, &setting);
    assert_eq!(profile.verdict(), Between::Groove, "{}", profile.describe());
    assert!(profile.bevels().all(|f| f.foot_at_probe_bottom), "{}", profile.describe());
    assert_eq!(profile.depth_mm(), None, "{}", profile.describe());
}

#[test]
fn a_groove_ending_in_a_root_land_shows_its_root_at_the_land() {
    // A 90 degree groove 6 mm deep whose bevels end on a flat root land
    // 3 mm wide (|x| <= 1.5): the background stage finds the land as a
    // surface seen only between the plates, 6 mm down. Taken for what the
    // plates rest on, it cuts the probe short and no depth is measured;
    // taken for the groove's own floor, the bevels' feet lie on it and
    // the depth is the land's.
    // A 90 degree groove `depth` deep ending on a land `2 land` wide, and
    // its edges at `±(land + depth)`.
    let landed = |land: f64, depth: f64| {
        let w = land + depth;
        move |x: f64| {
            Some(if x.abs() >= w {
                0.0
            } else if x.abs() >= land {
                w - x.abs()
            } else {
                depth
            })
        }
    };
    let (land, depth) = (1.5, 6.0);
    let w = land + depth;
    let cloud = cloud_of(landed(land, depth), 14.0, 0.2);
    let (e1, e2) = (edge(-w), edge(w));
    let setting = |floor_between_plates| ProbeSetting {
        edges: [&e1, &e2],
        span: (-45.0, 45.0),
        point_spacing_mm: 0.2,
        depth_to_support_mm: Some(depth),
        floor_between_plates,
        grid: None,
        projector: Vec3::zeros(),
    };
    let behind = probe(&cloud, &setting(false));
    assert_eq!(behind.verdict(), Between::Groove, "{}", behind.describe());
    assert_eq!(behind.depth_mm(), None, "{}", behind.describe());
    let floor = probe(&cloud, &setting(true));
    assert_eq!(floor.verdict(), Between::Groove, "{}", floor.describe());
    assert!(floor.bevels().all(|f| f.foot_on_floor && (f.foot_mm - land).abs() < 0.5), "{}", floor.describe());
    assert!((floor.depth_mm().unwrap() - depth).abs() < 1e-9, "{}", floor.describe());
    assert!((floor.groove_angle_deg().unwrap() - 90.0).abs() < 1.0, "{}", floor.describe());
    // The land widens the groove's bottom as a root gap does: the edges'
    // distance fits the depth and the bevels.
    assert_eq!(floor.check_opening(depth), Ok(()));
    // A floor as wide as the groove's opening is a trough's, not a
    // V-groove's land: its bevels' feet do not place the root.
    let (land, depth) = (9.0, 3.0);
    let w = land + depth;
    let cloud = cloud_of(landed(land, depth), 18.0, 0.2);
    let (e1, e2) = (edge(-w), edge(w));
    let trough = probe(&cloud, &ProbeSetting { edges: [&e1, &e2], depth_to_support_mm: Some(depth), ..setting(true) });
    assert_eq!(trough.depth_mm(), None, "{}", trough.describe());
}

#[test]
fn a_v_groove_shows_two_bevels_its_angle_and_depth() {
    let (cloud, w) = v_groove_cloud();
    let profile = probed(&cloud, w);
    assert_eq!(profile.verdict(), Between::Groove, "{}", profile.describe());
    assert!((profile.groove_angle_deg().unwrap() - 60.0).abs() < 1.0, "{}", profile.describe());
    assert!((profile.depth_mm().unwrap() - 5.0).abs() < 0.2, "{}", profile.describe());
    // The bevels alone tell the joint (`butt.type_from_groove`): a
    // V-butt, never an I-butt.
    assert_eq!(judge(None, &profile), Ok(JointType::VButt));
    let err = judge(Some(JointType::IButt), &profile).unwrap_err();
    assert!(matches!(err, GrooveError::LooksLikeVButt { .. }), "{err}");
    assert_eq!(err.rule().id, "groove.bevels_in_i_butt");
    // Its opening, 6.3 mm, fits its depth, and fits neither a groove
    // twice as deep nor the edges of a part standing 40 mm off.
    assert_eq!(profile.check_opening(5.0), Ok(()));
    let too_deep = profile.check_opening(10.0).unwrap_err();
    assert!(matches!(too_deep, GrooveError::OpeningMismatch { .. }), "{too_deep}");
    assert_eq!(too_deep.rule().id, "groove.opening_off_depth");
    let far_apart = GrooveProfile { opening_mm: 40.0, ..profile.clone() };
    let refusal = far_apart.check_opening(5.0).unwrap_err();
    assert_eq!(refusal.rule().id, "groove.opening_off_depth");
    assert!(refusal.to_string().contains("40.0 mm apart"), "{refusal}");
}

#[test]
fn a_v_groove_s_bevels_place_its_edges_where_the_edges_given_are_read_inside_it() {
    // The groove of [`v_groove_cloud`], its edges given 0.3 mm inside
    // it on one side and 0.9 to 1.3 mm along the seam on the other, as
    // the strips read a noisy groove: their midline lies 0.4 mm off
    // the groove's at the middle, 0.29 and 0.51 mm at the ends.
    let (cloud, w) = v_groove_cloud();
    let e1 = edge(-(w - 0.3));
    let e2 = SeamCurve { coef_a: vec![w - 1.1, 0.005], ..edge(0.0) };
    let profile = probed_between(&cloud, &e1, &e2);
    let offset = profile.bevel_midline_offset().unwrap_or_else(|| panic!("{}", profile.describe()));
    let midline = e1.midline(&e2).unwrap();
    // `groove.weld_on_bevel_midline` moves the weld line onto it.
    let moved = crate::pipeline::weld_equation::moved_towards(&midline, &e1, &e2, &offset);
    for s in [-45.0, 0.0, 45.0] {
        let (before, after) = (midline.at(s).x, moved.at(s).x);
        assert!(after.abs() < 0.05, "at s = {s}: the midline {before:.3} mm off, moved to {after:.3} mm");
    }
    // Edges given where the groove is: nothing to move.
    let offset = probed(&cloud, w).bevel_midline_offset().unwrap();
    assert!(offset.at_middle_mm.abs() < 0.02 && offset.per_mm.abs() < 1e-3, "{offset:?}");
    // A square gap has no sloped face to place an edge.
    let gap = |x: f64| if x.abs() >= 1.5 { Some(0.0) } else { None };
    assert_eq!(probed(&cloud_of(gap, 10.0, 0.2), 1.5).bevel_midline_offset(), None);
}

#[test]
fn a_square_gap_shows_no_bevel() {
    let gap = |x: f64| if x.abs() >= 1.5 { Some(0.0) } else { None };
    let profile = probed(&cloud_of(gap, 10.0, 0.2), 1.5);
    assert_eq!(profile.verdict(), Between::SquareGap, "{}", profile.describe());
    assert_eq!(profile.depth_mm(), None);
    // No bevel: an I-butt under `auto` (`butt.type_from_groove`), and
    // no V-butt where one is requested.
    assert_eq!(judge(None, &profile), Ok(JointType::IButt));
    let err = judge(Some(JointType::VButt), &profile).unwrap_err();
    assert_eq!(err.rule().id, "groove.no_bevel_for_v_butt", "{err}");
    assert_eq!(judge(Some(JointType::IButt), &profile), Ok(JointType::IButt));
}

#[test]
fn a_veil_along_the_rays_is_no_face() {
    // A square gap whose walls' top edges leave mixed pixels along the
    // camera's rays: a dense sheet, but along the rays (here the rays
    // run along the normal, so the veil is at 0 degrees and a wall).
    // Tilt the rays instead: the seam 200 mm off the optical axis.
    let mut points = Vec::new();
    for j in -250..=250 {
        let y = j as f64 * 0.2;
        for i in -50..=50 {
            let x = i as f64 * 0.2 + 0.2 * (j as f64 * 0.618).fract();
            if x.abs() >= 1.5 {
                points.push([(x + 200.0) as f32, y as f32, 700.0]);
            }
        }
        // Mixed pixels from the gap's edge down towards the table, on
        // the ray through (201.5, y, 700).
        for k in 1..40 {
            let f = 1.0 + k as f64 * 0.005;
            points.push([(201.5 * f) as f32, (y * f) as f32, (700.0 * f) as f32]);
        }
    }
    let cloud = PointCloud::unorganized(points);
    let axes = SeamAxes { origin: Vec3::new(200.0, 0.0, 700.0), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() };
    let edge = |a: f64| SeamCurve { axes, coef_a: vec![a, 0.0], coef_b: vec![0.0, 0.0], s_min: -45.0, s_max: 45.0 };
    let (e1, e2) = (edge(-1.5), edge(1.5));
    let setting = ProbeSetting {
        edges: [&e1, &e2],
        span: (-45.0, 45.0),
        point_spacing_mm: 0.2,
        depth_to_support_mm: None,
        floor_between_plates: false,
        grid: None,
        projector: Vec3::zeros(),
    };
    let profile = probe(&cloud, &setting);
    assert!(profile.faces.iter().all(|f| f.along_rays || f.points < MIN_FACE_POINTS), "{}", profile.describe());
    assert_eq!(profile.verdict(), Between::SquareGap, "{}", profile.describe());
}

#[test]
fn a_plate_standing_between_the_edges_is_seen() {
    let tee = |x: f64| if x.abs() >= 5.0 { Some(0.0) } else { Some(-60.0) };
    let profile = probed(&cloud_of(tee, 15.0, 0.2), 5.5);
    assert!(matches!(profile.verdict(), Between::StandingPlate(_)), "{}", profile.describe());
    assert!((profile.standing.unwrap().height_mm - 60.0).abs() < 1e-3);
    for requested in [None, Some(JointType::VButt), Some(JointType::IButt)] {
        let err = judge(requested, &profile).unwrap_err();
        assert_eq!(err.rule().id, "butt.plate_standing_in_gap", "{err}");
        assert_eq!(err.rule().gate, Some(crate::rules::Gate::JointMismatch));
    }
}

#[test]
fn a_face_too_flat_for_a_bevel_tells_neither_joint() {
    // Faces 70 degrees from the normal, 1.8 mm deep: seen along the seam
    // and flat as a plate, but too flat for a groove's bevel and far from
    // a square gap's wall.
    let tan = 70f64.to_radians().tan();
    let w = 5.0;
    let shallow = |x: f64| Some(if x.abs() >= w { 0.0 } else { (w - x.abs()) / tan });
    let profile = probed(&cloud_of(shallow, 10.0, 0.2), w);
    assert_eq!(profile.verdict(), Between::Unclear, "{}", profile.describe());
    assert!(profile.faces.iter().all(|f| (f.angle_deg - 70.0).abs() < 2.0), "{}", profile.describe());
    let err = judge(None, &profile).unwrap_err();
    assert_eq!(err.rule().id, "groove.type_unclear", "{err}");
    assert_eq!(err.rule().gate, Some(crate::rules::Gate::JointUnknown));
    // Named in the request, the joint is planned as named; a V-butt
    // still needs its bevels.
    assert_eq!(judge(Some(JointType::IButt), &profile), Ok(JointType::IButt));
    assert_eq!(judge(Some(JointType::VButt), &profile).unwrap_err().rule().id, "groove.no_bevel_for_v_butt");
}

/// The root-land family's documented scenes (`weldseam eval --suite
/// root-land`), under `auto` and `v_butt` without a depth: each planned a
/// V-butt at the land's centre within the bar, the groove's depth measured
/// down to the land. The `-holdout` scenes are left out.
#[test]
fn grooves_ending_in_a_root_land_are_planned_at_the_land_with_their_depth_measured() {
    use crate::camera::CameraModel;
    use crate::config::Config;
    use crate::joint::RequestedJoint;
    use crate::pipeline::{PlanRequest, Planner};
    use crate::sim::{Draw, JointGeometry, root_land_suite, simulate};

    let planner = Planner::new(Config::default());
    for (name, spec) in root_land_suite(Draw::Documented).into_iter().filter(|(n, _)| !n.ends_with("-holdout")) {
        let sim = simulate(&spec, &CameraModel::default());
        let JointGeometry::VButt { groove_depth_mm, .. } = spec.joint else { unreachable!("{name}") };
        for joint in [RequestedJoint::Auto, RequestedJoint::from(JointType::VButt)] {
            let plan = planner
                .plan(&sim.cloud, &PlanRequest::new(joint, None, sim.pose))
                .unwrap_or_else(|e| panic!("{name} ({joint:?}): {} {e}", e.rule.id));
            let seam = &plan.seams[0];
            assert_eq!(seam.joint, JointType::VButt, "{name}");
            let depth = seam.quality.and_then(|q| q.groove_depth_mm).expect("the depth measured");
            assert!((depth - groove_depth_mm).abs() < 0.5, "{name}: depth {depth:.2} against {groove_depth_mm:.2}");
            let error = crate::eval::seam_error(&sim.truth, seam).unwrap();
            assert!(error.passes(), "{name} ({joint:?}): {error:?}");
        }
    }
}
