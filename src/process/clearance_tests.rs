//! Tests of the torch clearance: the indexed search against a scan of
//! every point, and the torch on a tee, beside a wall and under a clamp.

use super::*;
use crate::config::procedure::Procedure;

fn torch() -> Torch {
    Procedure::example().torch
}

/// Points every `step` mm over a rectangle spanned by `u` and `v` from
/// `origin`.
fn patch(origin: Vec3, u: Vec3, v: Vec3, (nu, nv): (usize, usize), step: f64) -> Vec<Vec3> {
    let mut out = Vec::new();
    for i in 0..=nu {
        for j in 0..=nv {
            out.push(origin + u * (i as f64 * step) + v * (j as f64 * step));
        }
    }
    out
}

/// A tee: a flange in z = 0 over x from 0 to 100, a web in x = 0 rising
/// 60 mm, the seam along y; the torch between them.
fn tee() -> Vec<Vec3> {
    let mut points = patch(Vec3::new(0.5, -60.0, 0.0), Vec3::x(), Vec3::y(), (100, 120), 1.0);
    points.extend(patch(Vec3::new(0.0, -60.0, 0.5), Vec3::z(), Vec3::y(), (60, 120), 1.0));
    points
}

fn tee_station(y: f64) -> Station {
    Station { point: Vec3::new(0.0, y, 0.0), along: Vec3::y(), bisector: Vec3::new(1.0, 0.0, 1.0).normalize() }
}

/// The straightforward reference: every point tested against the solid,
/// grown by `edge_per_mm` times the point's range.
fn contact_by_scan(torch: &Torch, points: &[Vec3], point: &Vec3, axis: &Vec3, edge_per_mm: f64) -> Option<f64> {
    let axis = axis.normalize();
    let inside: Vec<f64> = points
        .iter()
        .filter_map(|q| {
            let d = q - point;
            let s = d.dot(&axis);
            let r = radius_at(torch, s)? + edge_per_mm * q.norm();
            ((d - axis * s).norm_squared() < r * r).then_some(s)
        })
        .collect();
    (inside.len() >= MIN_CONTACT_POINTS).then(|| inside.into_iter().min_by(f64::total_cmp)).flatten()
}

/// A camera's lone outlier in the air over the seam is no contact; a few
/// points together are.
#[test]
fn a_lone_outlier_in_the_torch_is_no_contact_and_a_surface_is() {
    let t = torch();
    let station = tee_station(0.0);
    let axis = station.axis(0.0, 10.0);
    let up = |s: f64| station.point + axis.normalize() * s;
    let lone = Obstacles::new([up(30.0)]);
    assert_eq!(contact(&t, &lone, &station.point, &axis), None);
    let few: Vec<Vec3> = (0..MIN_CONTACT_POINTS).map(|k| up(30.0 + k as f64)).collect();
    let hit = contact(&t, &Obstacles::new(few), &station.point, &axis).expect("a surface's few points touch");
    assert!(matches!(hit, Contact::Seen(_)), "{hit:?}");
    let hit = hit.point();
    assert!((hit - up(30.0)).norm() < 1e-4, "the nearest of them: {hit:?}");
}

#[test]
fn the_indexed_search_finds_the_contact_a_scan_of_every_point_finds() {
    let t = torch();
    let mut points = tee();
    // A few loose blocks at places a torch may or may not reach.
    for (x, z) in [(30.0, 45.0), (3.0, 40.0), (40.0, 8.0)] {
        points.extend(patch(Vec3::new(x, -5.0, z), Vec3::x(), Vec3::y(), (4, 10), 1.0));
    }
    let obstacles = Obstacles::new(points.iter().copied());
    let station = tee_station(0.0);
    let mut touched = 0;
    for work in [-40.0, -25.0, -10.0, 0.0, 10.0, 25.0, 40.0] {
        for travel in [0.0, 10.0, 20.0] {
            let axis = station.axis(work, travel);
            let fast = contact(&t, &obstacles, &station.point, &axis)
                .map(|q| (q.point() - station.point).dot(&axis.normalize()));
            let scan = contact_by_scan(&t, &points, &station.point, &axis, 0.0);
            assert_eq!(
                fast.map(|s| (s * 1e6).round()),
                scan.map(|s| (s * 1e6).round()),
                "work {work}, travel {travel}"
            );
            touched += usize::from(scan.is_some());
        }
    }
    assert!(touched > 3 && touched < 21, "{touched} of 21 poses touch: the test must see both");
}

#[test]
fn a_torch_on_the_tees_bisector_clears_and_one_leaning_into_the_web_does_not() {
    let t = torch();
    let obstacles = Obstacles::new(tee());
    let station = tee_station(0.0);
    assert_eq!(contact(&t, &obstacles, &station.point, &station.axis(0.0, 10.0)), None);
    // Leaning 35 degrees towards the web (10 degrees off it): the nozzle
    // meets the web.
    let towards_web = [35.0, -35.0]
        .into_iter()
        .find(|w| station.axis(*w, 0.0).x < station.axis(0.0, 0.0).x)
        .expect("one sign leans towards the web");
    let hit = contact(&t, &obstacles, &station.point, &station.axis(towards_web, 0.0)).expect("the web is touched");
    let hit = hit.point();
    assert!(hit.x.abs() < 1e-9, "the contact is on the web: {hit:?}");
}

#[test]
fn a_wall_beside_the_seam_moves_the_work_angle_away_from_it() {
    let t = torch();
    // Flat plates in z = 0, and a wall 9 mm beside the seam, 40 mm high:
    // the nozzle (8 mm radius and 2 mm margin) touches it upright.
    let mut points = patch(Vec3::new(-50.0, -30.0, 0.0), Vec3::x(), Vec3::y(), (58, 60), 1.0);
    points.extend(patch(Vec3::new(9.0, -30.0, 0.0), Vec3::z(), Vec3::y(), (40, 60), 1.0));
    let obstacles = Obstacles::new(points);
    let station = Station { point: Vec3::zeros(), along: Vec3::y(), bisector: Vec3::z() };
    assert!(contact(&t, &obstacles, &station.point, &station.axis(0.0, 10.0)).is_some());
    match clear_station(&t, &obstacles, &station, &[Aim::at_point(0.0)], 10.0) {
        Clearance::Clear { lean_deg, travel_angle_deg, moved } => {
            assert!(moved);
            assert!(lean_deg.abs() <= t.work_deviation_deg);
            let axis = station.axis(lean_deg, travel_angle_deg);
            assert!(axis.x < 0.0, "leans away from the wall: {axis:?}");
            assert_eq!(contact(&t, &obstacles, &station.point, &axis), None);
        }
        blocked => panic!("a 15 degree lean clears a wall 9 mm off: {blocked:?}"),
    }
}

#[test]
fn a_clamp_over_the_seam_blocks_its_stretch_and_only_that() {
    let t = torch();
    let mut points = tee();
    // A clamp's jaw over the root from y = -10 to 10, 12 mm above it.
    points.extend(patch(Vec3::new(2.0, -10.0, 12.0), Vec3::x(), Vec3::y(), (20, 20), 1.0));
    let obstacles = Obstacles::new(points);
    let clearances: Vec<Clearance> = (-50..=50)
        .step_by(5)
        .map(|y| clear_station(&t, &obstacles, &tee_station(y as f64), &[Aim::at_point(0.0)], 10.0))
        .collect();
    let stretches = blocked_stretches(&clearances);
    assert_eq!(stretches.len(), 1, "{clearances:?}");
    let [first, last] = stretches[0];
    // Stations 5 mm apart from y = -50: the jaw spans -10 to 10, and the
    // torch's solid reaches past it along the seam by its width.
    let y = |k: usize| -50.0 + 5.0 * k as f64;
    assert!(y(first) >= -35.0 && y(first) <= -10.0, "from {}", y(first));
    assert!(y(last) <= 35.0 && y(last) >= 10.0, "to {}", y(last));
    assert!(matches!(clearances[0], Clearance::Clear { .. }));
    let Clearance::Blocked { pass: 0, contact } = clearances[10] else { panic!("the middle is blocked") };
    let contact = contact.point();
    assert!(contact.z >= 12.0, "the contact is on the jaw: {contact:?}");
}

/// A torch behind a surface the camera saw meets the space there, though
/// no cloud point is inside it; against the points alone it meets
/// nothing.
#[test]
fn a_torch_behind_a_seen_surface_meets_the_hidden_space() {
    let t = torch();
    // A table 300 mm in front of a camera at the origin, seen every 0.5 mm.
    let table: Vec<Vec3> = (-200..=200)
        .flat_map(|i| (-200..=200).map(move |j| Vec3::new(i as f64 * 0.5, j as f64 * 0.5, 300.0)))
        .collect();
    let seen = Obstacles::seen_from_camera(table.iter().copied(), &t);
    assert!(seen.takes_hidden_space());
    let over = Station { point: Vec3::new(0.0, 0.0, 300.0), along: Vec3::y(), bisector: -Vec3::z() };
    assert_eq!(contact(&t, &seen, &over.point, &over.axis(0.0, 10.0)), None, "over the table is open");
    // The same torch turned to stand under the table.
    let under = Station { bisector: Vec3::z(), ..over };
    let axis = under.axis(0.0, 10.0);
    let hit = contact(&t, &seen, &under.point, &axis);
    assert!(matches!(hit, Some(Contact::Hidden(p)) if p.z > 300.0), "{hit:?}");
    assert_eq!(contact(&t, &Obstacles::new(table.iter().copied()), &under.point, &axis), None);
    assert_eq!(contact(&t, &seen.seen_only(), &under.point, &axis), None);
}

/// Flat plates in z = 0 and a wall `x` mm beside the seam, `height` mm
/// high.
fn plates_and_wall(x: f64, height: usize) -> Obstacles<'static> {
    let mut points = patch(Vec3::new(-50.0, -30.0, 0.0), Vec3::x(), Vec3::y(), (65, 60), 1.0);
    points.extend(patch(Vec3::new(x, -30.0, 0.0), Vec3::z(), Vec3::y(), (height, 60), 1.0));
    Obstacles::new(points)
}

#[test]
fn every_pass_is_cleared_and_all_lean_as_one() {
    let t = torch();
    let station = Station { point: Vec3::zeros(), along: Vec3::y(), bisector: Vec3::z() };
    let root = Aim::at_point(0.0);
    // A cap bead 5 mm across towards a wall 16 mm off and 8 mm up: the
    // root's torch, upright, passes under the wall's top (60 mm) before
    // its body widens to the wall; the cap's meets the wall at 50 mm.
    let obstacles = plates_and_wall(16.0, 60);
    let cap = Aim { across_mm: 5.0, up_mm: 8.0, work_angle_deg: 0.0 };
    assert!(matches!(clear_station(&t, &obstacles, &station, &[root], 0.0), Clearance::Clear { moved: false, .. }));
    let Clearance::Clear { lean_deg, travel_angle_deg, moved: true } =
        clear_station(&t, &obstacles, &station, &[root, cap], 0.0)
    else {
        panic!("a lean away from the wall clears both passes");
    };
    for aim in [root, cap] {
        let axis = station.axis(aim.work_angle_deg + lean_deg, travel_angle_deg);
        assert_eq!(contact(&t, &obstacles, &aim.point(&station), &axis), None, "{aim:?} at {lean_deg}°");
        assert!(axis.x < 0.0, "leans away from the wall: {axis:?}");
    }
}

#[test]
fn a_pass_no_lean_clears_blocks_the_station_and_is_named() {
    let t = torch();
    let station = Station { point: Vec3::zeros(), along: Vec3::y(), bisector: Vec3::z() };
    // A low wall 12.5 mm off: the root's nozzle (10 mm with its margin)
    // passes it; a bead aimed 7 mm towards it meets it at every lean.
    let obstacles = plates_and_wall(12.5, 30);
    let bead = Aim { across_mm: 7.0, up_mm: 8.0, work_angle_deg: 0.0 };
    let root = Aim::at_point(0.0);
    assert!(matches!(clear_station(&t, &obstacles, &station, &[root], 0.0), Clearance::Clear { moved: false, .. }));
    match clear_station(&t, &obstacles, &station, &[root, bead], 0.0) {
        Clearance::Blocked { pass: 1, contact: Contact::Seen(p) } => {
            assert!((p.x - 12.5).abs() < 1e-4, "the contact is on the wall: {p:?}")
        }
        other => panic!("the bead blocks the station: {other:?}"),
    }
}

/// A camera's cloud: the torch is grown by how far a surface may reach
/// past its points, and the indexed search still finds what a scan of
/// every point finds.
#[test]
fn a_cameras_surfaces_may_reach_past_their_points_and_the_search_agrees_with_a_scan() {
    let t = torch();
    // A tee seen every 0.4 mm (a camera's spacing
    // at the working distance), 300 mm in front of the camera (only the
    // points are asked here, not what they hide).
    let mut points = patch(Vec3::new(0.4, -30.0, 0.0), Vec3::x(), Vec3::y(), (200, 150), 0.4);
    points.extend(patch(Vec3::new(0.0, -30.0, 0.4), Vec3::z(), Vec3::y(), (150, 150), 0.4));
    let shift = Vec3::new(0.0, 0.0, 300.0);
    // As the index holds them: in single precision.
    let points: Vec<Vec3> = points.iter().map(|p| (p + shift).map(|c| c as f32 as f64)).collect();
    let obstacles = Obstacles::seen_from_camera(points.iter().copied(), &t).seen_only();
    assert_eq!(obstacles.spacing_per_mm, 0.0, "nothing reaches past the points of a bare cloud");
    let obstacles = Obstacles::seen_from_camera(points.iter().copied(), &t);
    let edge_per_mm = EDGE_SPACINGS * obstacles.spacing_per_mm;
    // 0.4 mm apart about 300 mm off.
    assert!((obstacles.spacing_per_mm * 300.0 - 0.4).abs() < 0.1, "{}", obstacles.spacing_per_mm);
    let station = Station { point: shift, ..tee_station(0.0) };
    let mut touched = 0;
    for work in [-40.0, -25.0, -10.0, 0.0, 10.0, 25.0, 40.0] {
        for travel in [0.0, 10.0, 20.0] {
            let axis = station.axis(work, travel);
            let fast = seen_contact(&t, &obstacles, &station.point, &axis).map(|q| (q - station.point).dot(&axis));
            let scan = contact_by_scan(&t, &points, &station.point, &axis, edge_per_mm);
            assert_eq!(fast.map(|s| (s * 1e6).round()), scan.map(|s| (s * 1e6).round()), "{work}, {travel}");
            touched += usize::from(scan.is_some());
        }
    }
    assert!(touched > 3 && touched < 21, "{touched} of 21 poses touch: the test must see both");
    // A ledge facing the camera beside the nozzle, 25 mm up from the aim
    // point, its edge 10.5 mm from an upright torch's axis, seen every
    // 0.4 mm: outside the nozzle and its margin (10 mm), within a
    // surface's reach past its points (0.8 mm).
    let wall: Vec<Vec3> = patch(Vec3::new(10.5, -20.0, 275.0), Vec3::x(), Vec3::y(), (25, 100), 0.4)
        .into_iter()
        .map(|p| p.map(|c| c as f32 as f64))
        .collect();
    let upright = Station { point: shift, along: Vec3::y(), bisector: -Vec3::z() };
    let axis = upright.axis(0.0, 0.0);
    let bare = Obstacles::new(wall.iter().copied());
    assert_eq!(contact(&t, &bare, &upright.point, &axis), None);
    let seen = Obstacles::seen_from_camera(wall.iter().copied(), &t);
    assert!(matches!(contact(&t, &seen, &upright.point, &axis), Some(Contact::Seen(p)) if (p.x - 10.5).abs() < 1e-3));
}

/// A 60 degree V-groove in 20 mm plates with no root gap, seen from a
/// camera 600 mm above its top (camera frame: the plates' tops in
/// z = 600, the root along y at x = 0, z = 620).
fn thick_v_groove() -> Vec<Vec3> {
    let half = 30f64.to_radians();
    let mut points = Vec::new();
    for j in -40..=40 {
        let y = j as f64;
        for k in 0..=46 {
            // Down each flank every 0.5 mm of its slope.
            let down = 20.0 - k as f64 * 0.5 * half.cos();
            let x = down.max(0.0) * half.tan();
            points.push(Vec3::new(x, y, 620.0 - down.max(0.0)));
            points.push(Vec3::new(-x, y, 620.0 - down.max(0.0)));
        }
        for i in 0..=100 {
            let x = 20.0 * half.tan() + 0.5 * i as f64;
            points.push(Vec3::new(x, y, 600.0));
            points.push(Vec3::new(-x, y, 600.0));
        }
    }
    points
}

fn thick_v_station() -> Station {
    Station { point: Vec3::new(0.0, 0.0, 620.0), along: Vec3::y(), bisector: -Vec3::z() }
}

/// The example's thick V entry extends its contact tip past the nozzle:
/// that torch reaches the root of a 20 mm, 60 degree groove, which the
/// procedure's own torch (its nozzle 12 mm from the work) and a tip
/// extended only 1/8 in do not.
#[test]
fn an_extended_tip_reaches_a_thick_v_grooves_root_and_the_example_nozzle_does_not() {
    let p = Procedure::example();
    let thick = p.torch_for(p.entry(crate::joint::JointType::VButt, 20.0).expect("a thick V entry"));
    assert!(thick.extended_tip().is_some(), "{thick:?}");
    let obstacles = Obstacles::new(thick_v_groove());
    let station = thick_v_station();
    let root = [Aim::at_point(0.0)];
    let at = |torch: &Torch| clear_station(torch, &obstacles, &station, &root, 10.0);
    assert_eq!(at(&thick), Clearance::Clear { lean_deg: 0.0, travel_angle_deg: 10.0, moved: false });
    assert!(matches!(at(&p.torch), Clearance::Blocked { .. }), "{:?}", at(&p.torch));
    let eighth_inch = Torch { nozzle_to_work_mm: thick.contact_tip_to_work_mm + 3.2, ..thick };
    assert!(matches!(at(&eighth_inch), Clearance::Blocked { .. }), "{:?}", at(&eighth_inch));
}

/// The tip past the nozzle is a solid of its own diameter: a surface
/// within its radius and margin touches it, one just beyond does not
/// (the nozzle begins farther up).
#[test]
fn an_extended_tip_is_part_of_the_torchs_solid() {
    let p = Procedure::example();
    let thick = p.torch_for(p.entry(crate::joint::JointType::VButt, 20.0).expect("a thick V entry"));
    let (_, tip_diameter) = thick.extended_tip().expect("extended");
    let s = (thick.contact_tip_to_work_mm + thick.nozzle_to_work_mm) / 2.0;
    let beside = |r: f64| -> Vec<Vec3> { (0..5).map(|k| Vec3::new(r, k as f64 * 0.2, s)).collect() };
    let reach = tip_diameter / 2.0 + thick.margin_mm;
    let axis = Vec3::z();
    let touching = Obstacles::new(beside(reach - 0.3));
    assert!(matches!(contact(&thick, &touching, &Vec3::zeros(), &axis), Some(Contact::Seen(_))));
    assert_eq!(contact(&thick, &Obstacles::new(beside(reach + 0.3)), &Vec3::zeros(), &axis), None);
    // The body still ends where the nozzle's length and the body's put it
    // past the nozzle's end, not the tip's.
    let top = thick.solid_end_mm() - 1.0;
    let at_top: Vec<Vec3> = (0..5).map(|k| Vec3::new(thick.nozzle_diameter_mm / 2.0, k as f64 * 0.2, top)).collect();
    assert!(matches!(contact(&thick, &Obstacles::new(at_top), &Vec3::zeros(), &axis), Some(Contact::Seen(_))));
    // The same nozzle with its tip flush has nothing there.
    let flush = Torch { contact_tip_to_work_mm: thick.nozzle_to_work_mm, ..thick };
    assert_eq!(contact(&flush, &touching, &Vec3::zeros(), &axis), None);
}

/// The space behind the seen surfaces, indexed for one torch, answers for
/// another as it would had it been indexed for that one.
#[test]
fn the_hidden_space_answers_every_torch_as_if_indexed_for_it() {
    let p = Procedure::example();
    let thick = p.torch_for(p.entry(crate::joint::JointType::VButt, 20.0).expect("a thick V entry"));
    let points = thick_v_groove();
    let for_procedure = Obstacles::seen_from_camera(points.iter().copied(), &p.torch);
    let for_thick = Obstacles::seen_from_camera(points.iter().copied(), &thick);
    let station = thick_v_station();
    let mut touched = 0;
    for up_mm in [0.0, 4.0, 8.0] {
        for work in [-30.0, -15.0, 0.0, 15.0, 30.0] {
            let aim = Aim { across_mm: 0.0, up_mm, work_angle_deg: work };
            let axis = station.axis(work, 10.0);
            let a = contact(&thick, &for_procedure, &aim.point(&station), &axis);
            assert_eq!(a, contact(&thick, &for_thick, &aim.point(&station), &axis), "up {up_mm}, work {work}");
            touched += usize::from(a.is_some());
        }
    }
    assert!(touched > 0 && touched < 15, "{touched} of 15 poses touch: the test must see both");
}

/// The 60 degree V-groove of [`thick_v_groove`] as a camera at the origin
/// sees it: an organized frame of `width` x `height` pixels, one ray every
/// 0.0007 in `(x / z, y / z)` (0.42 mm at the plates' tops), single
/// precision.
fn thick_v_frame(width: usize, height: usize) -> Vec<[f32; 3]> {
    let slope = 30f64.to_radians().tan();
    let mut points = Vec::new();
    for j in 0..height {
        for i in 0..width {
            let (u, v) = ((i as f64 - width as f64 / 2.0) * 0.0007, (j as f64 - height as f64 / 2.0) * 0.0007);
            // The plates' tops at z = 600 beyond the groove's edges, the
            // flanks falling to the root at z = 620 within them.
            let z = if 600.0 * u.abs() >= 20.0 * slope { 600.0 } else { 620.0 / (1.0 + u.abs() / slope) };
            points.push([(u * z) as f32, (v * z) as f32, z as f32]);
        }
    }
    points
}

/// Over an organized frame the search reads the blocks of pixels, passing
/// over the boxes of points beside each piece's stretch of axis; it finds
/// the contact a scan of every point finds, torch by torch.
fn organized_search_agrees_with_a_scan(poses: &[(f64, f64, f64, f64)]) -> usize {
    let p = Procedure::example();
    let thick = p.torch_for(p.entry(crate::joint::JointType::VButt, 20.0).expect("a thick V entry"));
    let (width, height) = (161, 121);
    let frame = thick_v_frame(width, height);
    let obstacles = Obstacles::seen_in_organized_frame(&frame, width, &thick);
    let edge_per_mm = EDGE_SPACINGS * obstacles.spacing_per_mm;
    assert!(edge_per_mm > 0.0, "a camera's frame reaches past its points");
    let points: Vec<Vec3> = frame.iter().map(|p| Vec3::new(p[0].into(), p[1].into(), p[2].into())).collect();
    let station = thick_v_station();
    let mut touched = 0;
    for &(across_mm, up_mm, work, travel) in poses {
        let aim = Aim { across_mm, up_mm, work_angle_deg: work };
        let (at, axis) = (aim.point(&station), station.axis(work, travel));
        let fast = seen_contact(&thick, &obstacles, &at, &axis).map(|q| (q - at).dot(&axis.normalize()));
        let scan = contact_by_scan(&thick, &points, &at, &axis, edge_per_mm);
        assert_eq!(fast.map(|s| (s * 1e6).round()), scan.map(|s| (s * 1e6).round()), "{aim:?}, travel {travel}");
        touched += usize::from(scan.is_some());
    }
    touched
}

#[test]
fn the_search_over_a_frames_blocks_finds_what_a_scan_finds_in_a_groove() {
    let mut poses = Vec::new();
    for across_mm in [-4.0, 0.0, 5.0] {
        for up_mm in [0.0, 6.0, 14.0] {
            for work in [-30.0, -10.0, 0.0, 20.0] {
                poses.push((across_mm, up_mm, work, 10.0));
            }
        }
    }
    let touched = organized_search_agrees_with_a_scan(&poses);
    assert!(touched > 0 && touched < poses.len(), "{touched} of {} poses touch: the test must see both", poses.len());
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(16))]

    /// Random torches in and over the groove.
    #[test]
    fn random_torches_in_a_groove_meet_what_a_scan_finds(
        poses in proptest::collection::vec((-8f64..8.0, -2f64..20.0, -40f64..40.0, -5f64..25.0), 1..6),
    ) {
        organized_search_agrees_with_a_scan(&poses);
    }
}
