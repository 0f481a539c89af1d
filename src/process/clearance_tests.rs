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

/// The straightforward reference: every point tested against the solid.
fn contact_by_scan(torch: &Torch, points: &[Vec3], point: &Vec3, axis: &Vec3) -> Option<f64> {
    let axis = axis.normalize();
    let inside: Vec<f64> = points
        .iter()
        .filter_map(|q| {
            let d = q - point;
            let s = d.dot(&axis);
            let r = radius_at(torch, s)?;
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
            let fast =
                contact(&t, &obstacles, &station.point, &axis).map(|q| (q - station.point).dot(&axis.normalize()));
            let scan = contact_by_scan(&t, &points, &station.point, &axis);
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
    match clear_station(&t, &obstacles, &station, 0.0, 10.0) {
        Clearance::Clear { work_angle_deg, travel_angle_deg, moved } => {
            assert!(moved);
            assert!(work_angle_deg.abs() <= t.work_deviation_deg);
            let axis = station.axis(work_angle_deg, travel_angle_deg);
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
    let clearances: Vec<Clearance> =
        (-50..=50).step_by(5).map(|y| clear_station(&t, &obstacles, &tee_station(y as f64), 0.0, 10.0)).collect();
    let stretches = blocked_stretches(&clearances);
    assert_eq!(stretches.len(), 1, "{clearances:?}");
    let [first, last] = stretches[0];
    // Stations 5 mm apart from y = -50: the jaw spans -10 to 10, and the
    // torch's solid reaches past it along the seam by its width.
    let y = |k: usize| -50.0 + 5.0 * k as f64;
    assert!(y(first) >= -35.0 && y(first) <= -10.0, "from {}", y(first));
    assert!(y(last) <= 35.0 && y(last) >= 10.0, "to {}", y(last));
    assert!(matches!(clearances[0], Clearance::Clear { .. }));
    let Clearance::Blocked { contact } = clearances[10] else { panic!("the middle is blocked") };
    assert!(contact.z >= 12.0, "the contact is on the jaw: {contact:?}");
}
