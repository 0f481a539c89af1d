//! The fillet stage on small constructed clouds: a web standing on a
//! flange, its faces, tops and flanges laid out point by point, each root
//! read as [`super::find_roots`] reads it.

use super::face::root_from_face;
use super::frame::{side_seen, web_frame};
use super::stretch::seen_run;
use super::*;
use crate::pipeline::view_border::ViewBorder;

/// Where the web stands across the camera's x: 200 mm to the camera's
/// −x, so the camera (at the origin, looking down +z) sees its +x face.
pub(super) const WEB_X: f64 = -200.0;

/// A web face standing on a flange: the flange z = 700, the face x =
/// WEB_X + 5, points on the face from 1 to 39 mm above the flange,
/// along y from −50 to 49.
fn face_points(noise: f64) -> Vec<Vec3> {
    let mut pts = Vec::new();
    for i in 0..100 {
        for j in 0..20 {
            let jitter = noise * (((i * 7 + j * 13) % 11) as f64 / 5.0 - 1.0);
            pts.push(Vec3::new(WEB_X + 5.0 + jitter, -50.0 + i as f64, 700.0 - 1.0 - 2.0 * j as f64));
        }
    }
    pts
}

#[test]
fn a_face_is_fitted_through_its_outliers_and_its_residual_reported() {
    let mut pts = face_points(0.05);
    // A few stray returns a centimetre off the face.
    pts.extend((0..20).map(|k| Vec3::new(WEB_X + 15.0, k as f64, 690.0)));
    let fit = fit_face(&pts, 3.0).unwrap();
    assert!(fit.dropped >= 20, "{} dropped", fit.dropped);
    assert!(fit.rms_mm < 0.06, "{}", fit.rms_mm);
    assert!((fit.plane.normal.x.abs() - 1.0).abs() < 1e-4, "{:?}", fit.plane.normal);
    assert!((fit.plane.signed_distance(&Vec3::new(WEB_X + 5.0, 0.0, 690.0))).abs() < 0.01);
}

/// A face whose band also holds what stands beside it: a sixth of the
/// band's points past the face's one end, 1.5 to 40 mm off its plane on
/// one side (a tube's rounded corner curving away, parts beyond it),
/// spread evenly in the logarithm of their distance. Their distances
/// inflate an RMS, so a trim by a few RMS peels them a few at a time and
/// the plane stays turned towards what is left; the median residual is
/// moved by them only as much as their share, and the plane is the face's.
#[test]
fn a_face_is_fitted_past_the_clutter_beside_its_end_not_turned_towards_it() {
    for seed in 0..3 {
        let mut random = crate::sim::noise::RowRandom::new(seed, 0);
        let mut pts = Vec::new();
        for i in 0..200 {
            for j in 0..39 {
                let x = WEB_X + 5.0 + 0.5 * random.gaussian();
                pts.push(Vec3::new(x, -50.0 + 0.5 * i as f64, 700.0 - 1.0 - j as f64));
            }
        }
        let face = pts.len();
        for _ in 0..face * 3 / 20 {
            let off = (1.5f64.ln() + (40.0f64 / 1.5).ln() * random.uniform()).exp();
            let (y, z) = (50.0 + 6.0 * random.uniform(), 699.0 - 38.0 * random.uniform());
            pts.push(Vec3::new(WEB_X + 5.0 + off, y, z));
        }
        let fit = fit_face(&pts, 3.0).unwrap();
        let turn_deg = fit.plane.normal.x.abs().clamp(0.0, 1.0).acos().to_degrees();
        // The face's own noise turns a plane fitted to it by a few
        // hundredths of a degree.
        assert!(turn_deg < 0.12, "seed {seed}: the plane turned {turn_deg:.3} degrees towards the clutter");
        // At the face's end beside the clutter, where a root would be read.
        let off = fit.plane.signed_distance(&Vec3::new(WEB_X + 5.0, 49.0, 680.0)).abs();
        assert!(off < 0.12, "seed {seed}: {off:.3} mm off the face at its end");
    }
}

#[test]
fn the_root_is_where_the_face_meets_the_flange_and_runs_where_both_are_seen() {
    // A 40 mm web 10 mm thick centred on x = WEB_X: its top at z = 660
    // 4 mm either side of it (a trimmed rim of 1 mm), its +x face 5 mm
    // out, seen from y = −50 to 49; the flange seen at z = 700 from the
    // face outward, but only for y < 20 beside the face; the −x side
    // shows no face, and the flange from the edge of the web's shadow
    // on (where the camera's ray over the top's edge lands).
    let shadow_edge = (WEB_X - 4.0) * 700.0 / 660.0;
    let mut pts = face_points(0.0);
    for i in 0..100 {
        for j in 0..=8 {
            pts.push(Vec3::new(WEB_X - 4.0 + j as f64, -50.0 + i as f64, 660.0));
        }
        for j in 0..30 {
            let y = -50.0 + i as f64;
            if y < 20.0 {
                pts.push(Vec3::new(WEB_X + 5.0 + 0.5 * j as f64, y, 700.0));
            }
            pts.push(Vec3::new(shadow_edge - j as f64, y, 700.0));
        }
    }
    let roots = roots_of(&pts);
    let seen: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
    assert_eq!(seen.len(), 1, "{roots:?}");
    let root = seen[0];
    // The root is x = WEB_X + 5, z = 700, from y = −50 to the flange's
    // end at 19, on the side facing the camera.
    assert_eq!(root.side, Side::Near);
    for s in [root.line.s_min, root.line.s_max] {
        let p = root.line.at(s);
        assert!((p.x - WEB_X - 5.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
    }
    let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 19.0).abs() < 1e-6, "{ends:?}");
    assert!((root.web_angle_deg - 90.0).abs() < 1e-6, "{}", root.web_angle_deg);
    assert!((root.web_height_mm - 40.0).abs() < 1e-6);
    assert!(root.coverage.iter().all(|c| *c > 0.99), "{:?}", root.coverage);
    assert!(root.away_from_web().x > 0.99);
    // The other side: no face seen, so no root, and the reason says so.
    let hidden = roots.iter().find_map(|r| r.as_ref().err()).unwrap();
    assert_eq!(hidden.side, Side::Far);
    assert!(hidden.reason.contains("far side") && hidden.reason.contains("hidden by the web"), "{}", hidden.reason);
    assert_eq!(hidden.rule.id, "tee.flange_edge_at_shadow", "{}", hidden.reason);
    assert!(root.ends_set_by.is_empty(), "{:?}", root.ends_set_by);
}

#[test]
fn a_flange_in_one_piece_round_the_webs_end_is_seen_on_both_sides() {
    // The web of the test above, its +x face seen; the flange one plane
    // on both sides, joined beyond the web's end (y from 50 to 60), far
    // wider on the -x side, so the piece's centroid lies there. The +x
    // root is still read: the flange's points lie on that side too.
    let mut pts = face_points(0.0);
    for i in 0..100 {
        let y = -50.0 + i as f64;
        for j in 0..=8 {
            pts.push(Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0));
        }
        for j in 0..30 {
            pts.push(Vec3::new(WEB_X + 5.0 + 0.5 * j as f64, y, 700.0));
        }
        for j in 0..120 {
            pts.push(Vec3::new(WEB_X - 30.0 - j as f64, y, 700.0));
        }
    }
    for i in 0..10 {
        for j in 0..170 {
            pts.push(Vec3::new(WEB_X + 20.0 - j as f64, 50.0 + i as f64, 700.0));
        }
    }
    let flange = |p: &Vec3| p.z == 700.0;
    let on_flange: Vec<&Vec3> = pts.iter().filter(|p| flange(p)).collect();
    let mean_x = on_flange.iter().map(|p| p.x).sum::<f64>() / on_flange.len() as f64;
    assert!(mean_x < WEB_X - 4.0, "the piece's centroid lies on the -x side: {mean_x}");
    let roots = roots_with_flange_pieces(&pts, &[&flange]);
    let seen: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
    assert_eq!(seen.len(), 1, "{roots:?}");
    let root = seen[0];
    assert_eq!(root.side, Side::Near);
    assert!((root.line.at(root.line.s_min).x - WEB_X - 5.0).abs() < 1e-6);
    let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
    // The -x side shows no face, and its flange stops short of the web:
    // not planned, and not for want of a flange on that side.
    let hidden = roots.iter().find_map(|r| r.as_ref().err()).unwrap();
    assert_eq!(hidden.side, Side::Far);
    assert!(hidden.flange_seen, "{}", hidden.reason);
}

/// The roots read with the web's top out of view from the face of
/// [`face_points`] (x = WEB_X + 5, 1 to 39 mm over the flange), its points
/// where `keep`, and the flange seen on both sides of it along y from −50
/// to 49.
fn one_face_roots(keep: impl Fn(&Vec3) -> bool) -> [Result<Root, RootNotSeen>; 2] {
    let mut pts = face_points(0.0);
    pts.retain(|p| p.z == 700.0 || keep(p));
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 10.0 - j as f64, y, 700.0)));
    }
    let cloud = cloud_of(&pts);
    let flange = PlaneCluster::of_points(&pts, |p| p.z == 700.0);
    let face = plus_x_face_standing_on(&flange);
    find_roots(&test_view(&cloud, Web::Face(&face), &[&flange]))
}

#[test]
fn a_web_seen_by_one_face_only_gives_that_face_s_root_and_names_the_other() {
    // The face of the tests above, x = WEB_X + 5, seen from 1 to 39 mm
    // over the flange; no web's top; the flange seen on both sides.
    let roots = one_face_roots(|_| true);
    let seen: Vec<&Root> = roots.iter().filter_map(|r| r.as_ref().ok()).collect();
    assert_eq!(seen.len(), 1, "{roots:?}");
    let root = seen[0];
    assert_eq!((root.side, root.evidence), (Side::Near, RootEvidence::Face));
    for s in [root.line.s_min, root.line.s_max] {
        let p = root.line.at(s);
        assert!((p.x - WEB_X - 5.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
    }
    let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
    assert!(root.away_from_web().x > 0.99);
    assert!((root.web_height_mm - 39.0).abs() < 1e-9);
    // The other face is not looked for: with the top out of view
    // nothing places it, and the web hides it.
    let other = roots.iter().find_map(|r| r.as_ref().err()).unwrap();
    assert_eq!(other.side, Side::Far);
    assert!(other.flange_seen);
    assert_eq!(other.rule.id, "tee.root_hidden_by_web");
    assert!(other.reason.contains("top is out of view"), "{}", other.reason);
}

/// A tee whose +x face (x = WEB_X + 5) returns points only from
/// `lowest(y)` up to 39 mm over the flange, along y from −50 to 49;
/// its top (z = 660) and the flange up to the root (z = 700) seen on
/// both sides along the same stretch, every point `keep` keeps.
fn tee_with_face_seen_above(lowest: impl Fn(f64) -> f64, keep: impl Fn(&Vec3) -> bool) -> Vec<Vec3> {
    let mut pts = Vec::new();
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
        pts.extend(
            (0..20)
                .map(|j| 1.0 + 2.0 * j as f64)
                .filter(|&h| h >= lowest(y))
                .map(|h| Vec3::new(WEB_X + 5.0, y, 700.0 - h)),
        );
    }
    pts.retain(keep);
    pts
}

/// The tee of `pts` to read roots in: the web's top the points at
/// z = 660, the flange's pieces those at z = 700 either side of WEB_X.
fn tee_parts(pts: &[Vec3]) -> (PointCloud, PlaneCluster, [PlaneCluster; 2]) {
    let sides = [
        PlaneCluster::of_points(pts, |p| p.z == 700.0 && p.x > WEB_X),
        PlaneCluster::of_points(pts, |p| p.z == 700.0 && p.x < WEB_X),
    ];
    (cloud_of(pts), PlaneCluster::of_points(pts, |p| p.z == 660.0), sides)
}

/// The +x face (x = WEB_X + 5) of the tests' tee, seen standing 39 mm
/// tall on `flange`, as the face search gives it when the web's top is
/// out of view.
fn plus_x_face_standing_on(flange: &PlaneCluster) -> StandingFace {
    StandingFace {
        plane: Plane { normal: Vec3::x(), offset: WEB_X + 5.0 },
        centroid: Vec3::new(WEB_X + 5.0, 0.0, 680.0),
        flange: flange.plane,
        points: 2000,
        seen_height_mm: 39.0,
    }
}

/// The root read from the +x side face of the tee of `pts` ([`tee_parts`]).
fn plus_x_face_reading(pts: &[Vec3]) -> Result<Root, NotRead> {
    let (cloud, top, [plus, minus]) = tee_parts(pts);
    let pieces = [&plus, &minus];
    let view = test_view(&cloud, Web::Top(&top), &pieces);
    let frame = web_frame(&view, false).expect("the web's frame");
    let sign = frame.u.x.signum();
    root_from_face(&view, &frame, sign, side_seen(&frame, sign))
}

/// The root of `roots` on the web's +x face ([`assert_on_plus_x_face`]).
fn plus_x_face_root(roots: &[Result<Root, RootNotSeen>]) -> Root {
    let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera").clone();
    assert_on_plus_x_face(&root);
    root
}

/// Asserts `root` is read from the web's +x face and lies on the
/// face's line x = WEB_X + 5, z = 700.
fn assert_on_plus_x_face(root: &Root) {
    assert_eq!(root.evidence, RootEvidence::Face);
    for s in [root.line.s_min, root.line.s_max] {
        let p = root.line.at(s);
        assert!((p.x - WEB_X - 5.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
    }
}

/// The ids of the rules that moved or cut `root`'s ends.
pub(super) fn ids(root: &Root) -> Vec<&'static str> {
    root.ends_set_by.iter().map(|r| r.id).collect()
}

pub(super) fn ends_y(root: &Root) -> [f64; 2] {
    [root.line.s_min, root.line.s_max].map(|s| root.line.at(s).y)
}

#[test]
fn a_face_seen_higher_up_along_the_web_gives_its_root_all_along() {
    // The face's lowest return rises from 1 mm over the flange (y < 0)
    // to 25 mm (y = 49), as where the face turns past the grazing angle
    // the sensor returns: the root runs the web's length, not only
    // where the face is seen within its foot's band of its lowest point.
    let pts = tee_with_face_seen_above(|y| if y < 0.0 { 1.0 } else { 1.0 + 0.5 * y }, |_| true);
    let (cloud, top, [plus, minus]) = tee_parts(&pts);
    let root = plus_x_face_root(&find_roots(&test_view(&cloud, Web::Top(&top), &[&plus, &minus])));
    let ends = ends_y(&root);
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
    assert_eq!(root.joint_beyond_ends_mm, Some([0.0, 0.0]));
}

#[test]
fn the_web_and_the_flange_seen_past_the_face_s_end_are_reported_beyond_the_root() {
    // The face returns nothing for y > 20 while the web's top and the
    // flange up to the root go on to y = 49: the face's root is read
    // where the face is seen, and the 29 mm of joint beyond it reported
    // (for the flange's edge to be read instead, and the quality gate
    // to refuse a root stopping short).
    let pts = tee_with_face_seen_above(|y| if y <= 20.0 { 1.0 } else { f64::INFINITY }, |_| true);
    let root = plus_x_face_reading(&pts).expect("the +x face's root");
    assert_on_plus_x_face(&root);
    let ends = ends_y(&root);
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 20.0).abs() < 1e-6, "{ends:?}");
    let [before, after] = root.joint_beyond_ends_mm.expect("measured under a web's top");
    assert_eq!(before, 0.0);
    assert!((after - 29.0).abs() < 1e-6, "{after}");
}

#[test]
fn a_root_runs_to_the_image_border_past_where_the_border_cuts_its_face() {
    // The face seen from 20 mm over the flange up; the image's border
    // slanting so that what stands higher leaves the view sooner: the
    // root (z = 700) is in view for y < 45, the face's lowest returns
    // (z = 680) for y < 35, the web's top for y < 25. The root runs on
    // along the flange up to it, to within a step of where it leaves
    // the view.
    let in_view = |p: &Vec3| p.y < 45.0 + 0.5 * (p.z - 700.0);
    let pts = tee_with_face_seen_above(|_| 20.0, in_view);
    let (cloud, top, [plus, minus]) = tee_parts(&pts);
    let pieces = [&plus, &minus];
    let view = test_view(&cloud, Web::Top(&top), &pieces);
    let root = plus_x_face_root(&find_roots(&TeeView { in_view: Some(&in_view), ..view }));
    let ends = ends_y(&root);
    assert!((ends[0] + 50.0).abs() < 1e-6, "{ends:?}");
    assert!((44.5..45.0).contains(&ends[1]), "{ends:?}");
    assert_eq!(ids(&root), ["tee.root_runs_past_cut_foot"]);
    // Without the grid nothing says the border cut the face: the root
    // ends where its face's foot is seen.
    let root = plus_x_face_root(&find_roots(&view));
    assert!((ends_y(&root)[1] - 34.0).abs() < 1e-6, "{:?}", ends_y(&root));
    assert!(root.ends_set_by.is_empty(), "{:?}", root.ends_set_by);
}

/// The roots [`find_roots`] reads from `pts`: the web's top the points
/// at z = 660, the flange's pieces those at z = 700 either side of
/// x = WEB_X, a point spacing of 1 mm.
fn roots_of(pts: &[Vec3]) -> [Result<Root, RootNotSeen>; 2] {
    roots_of_web_at(pts, WEB_X)
}

fn roots_of_web_at(pts: &[Vec3], web_x: f64) -> [Result<Root, RootNotSeen>; 2] {
    roots_with_flange_pieces(pts, &[&|p: &Vec3| p.z == 700.0 && p.x > web_x, &|p: &Vec3| p.z == 700.0 && p.x < web_x])
}

/// The roots [`find_roots`] reads from `pts` with the web's top the
/// points at z = 660 and a flange piece of the points each of `pieces`
/// picks.
fn roots_with_flange_pieces(pts: &[Vec3], pieces: &[&dyn Fn(&Vec3) -> bool]) -> [Result<Root, RootNotSeen>; 2] {
    let cloud = cloud_of(pts);
    let top = PlaneCluster::of_points(pts, |p| p.z == 660.0);
    let clusters: Vec<PlaneCluster> = pieces.iter().map(|pick| PlaneCluster::of_points(pts, pick)).collect();
    let pieces: Vec<&PlaneCluster> = clusters.iter().collect();
    find_roots(&test_view(&cloud, Web::Top(&top), &pieces))
}

pub(super) fn cloud_of(pts: &[Vec3]) -> PointCloud {
    PointCloud::unorganized(pts.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect())
}

/// The tee of `web` on `flange_pieces` in `cloud`: a point spacing of
/// 1 mm, a 1 mm rim trimmed, the default tolerances, no image border.
pub(super) fn test_view<'a>(cloud: &'a PointCloud, web: Web<'a>, flange_pieces: &'a [&'a PlaneCluster]) -> TeeView<'a> {
    TeeView {
        cloud,
        web,
        flange_pieces,
        point_spacing_mm: 1.0,
        rim_mm: 1.0,
        on_plane_mm: 0.4,
        trim_sigma: 3.0,
        projector: Vec3::new(150.0, 0.0, 0.0),
        in_view: None,
        border: None,
        max_beyond_mm: 2.0,
        every_side: false,
        web_thickness_max_mm: 30.0,
    }
}

#[test]
fn a_face_edge_on_to_the_camera_gives_its_root_from_the_flange_edge_and_a_shadow_edge_gives_none() {
    // The web of the test above with no face points at all: its +x
    // root at x = WEB_X + 4 is read from the flange's edge there. On
    // the −x side the flange is seen from where the camera's ray over
    // the top's edge (x = WEB_X − 4, z = 660) lands on it: the shadow's
    // edge, which must not be taken for a root.
    let shadow_edge = (WEB_X - 4.0) * 700.0 / 660.0;
    let mut pts = Vec::new();
    for i in 0..100 {
        let y = -50.0 + i as f64;
        for j in 0..=8 {
            pts.push(Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0));
        }
        for j in 0..30 {
            pts.push(Vec3::new(WEB_X + 4.0 + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0));
            pts.push(Vec3::new(shadow_edge - 0.5 * j as f64, y, 700.0));
        }
    }
    let roots = roots_of(&pts);
    let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera").clone();
    let hidden = roots.iter().find_map(|r| r.as_ref().err()).expect("the shadowed root refused");
    assert!(matches!(root.evidence, RootEvidence::FlangeEdge { view_margin_deg, .. } if view_margin_deg > 10.0));
    for s in [root.line.s_min, root.line.s_max] {
        let p = root.line.at(s);
        assert!((p.x - WEB_X - 4.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
    }
    let ends = [root.line.at(root.line.s_min).y, root.line.at(root.line.s_max).y];
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
    assert!((root.web_angle_deg - 90.0).abs() < 1e-6, "{}", root.web_angle_deg);
    assert!(hidden.reason.contains("shadow"), "{}", hidden.reason);
    assert_eq!(hidden.rule.id, "tee.flange_edge_at_shadow");
}

/// The ends (y) of the root [`roots_of`] reads from `pts` on the web's
/// camera side, which must come from the flange's edge and lie on the
/// line x = WEB_X + 4, z = 700 (the edge-on web of the tests below).
fn flange_edge_root_ends(pts: &[Vec3]) -> [f64; 2] {
    let roots = roots_of(pts);
    let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera");
    assert!(matches!(root.evidence, RootEvidence::FlangeEdge { .. }), "{:?}", root.evidence);
    [root.line.s_min, root.line.s_max].map(|s| {
        let p = root.line.at(s);
        assert!((p.x - WEB_X - 4.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
        p.y
    })
}

#[test]
fn the_webs_end_face_is_no_side_face_and_the_root_runs_to_the_webs_end() {
    // The web of the test above, its top from y = −50 to 47 and its
    // +x root at x = WEB_X + 4 seen only on the flange's edge (the side
    // face edge-on). Its end face, across the web at y = 47.5, returns
    // points on both sides of its middle; past it the flange runs on
    // under where the web would stand, so the station holding the
    // web's end holds flange points off the root's line.
    let mut pts = Vec::new();
    for i in 0..110 {
        let y = -50.0 + i as f64;
        if y <= 47.0 {
            pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
        } else {
            pts.extend((0..14).map(|j| Vec3::new(WEB_X - 10.0 + j as f64, y, 700.0)));
        }
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 4.0 + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0)));
    }
    // The end cut 17° off square, so that the camera sees it.
    for h in 1..40 {
        pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, 47.5 + 0.3 * j as f64, 700.0 - h as f64)));
    }
    // From the flange's first point to the web top's last: not a
    // station (4 mm) short of the web's end.
    let ends = flange_edge_root_ends(&pts);
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 47.0).abs() < 1e-6, "{ends:?}");
    let roots = roots_of(&pts);
    let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera");
    assert_eq!(ids(root), ["tee.flange_edge_ends_with_web_top"]);
    // The end face read as a face is refused as the web's end.
    let end_face = plus_x_face_reading(&pts).expect_err("the web's end");
    assert_eq!(end_face.rule.id, "tee.side_face_is_web_end", "{end_face}");
}

#[test]
fn a_web_top_seen_all_along_the_root_covers_it_whatever_its_stations() {
    // The edge-on web of the test before last, its top seen every
    // 0.5 mm from y = −50, its edge's points a few hundredths of a
    // millimetre in or out, the flange from y = −48: the top's edge
    // covers the root all along, though its outermost point in each
    // station, one to a station at a place of its own, left some of
    // the coverage gate's stations (as wide, from the root's start)
    // empty.
    let mut pts = Vec::new();
    for i in 0..200 {
        let y = -50.0 + 0.5 * i as f64;
        pts.extend((0..8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
        pts.push(Vec3::new(WEB_X + 4.0 - 0.01 * ((i * 37) % 11) as f64, y, 660.0));
        if y >= -48.0 {
            pts.extend((0..30).map(|j| Vec3::new(WEB_X + 4.0 + 0.5 * j as f64, y, 700.0)));
        }
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
    }
    let roots = roots_of(&pts);
    let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera");
    assert!(matches!(root.evidence, RootEvidence::FlangeEdge { .. }), "{:?}", root.evidence);
    assert!(root.coverage.iter().all(|c| *c > 0.99), "{:?}", root.coverage);
}

/// Row `i` (y = −50 + i) of an edge-on web: its top (z = 660) 8 mm
/// wide round WEB_X, the flange (z = 700) from its +x root at
/// x = WEB_X + 4 outward, every other row's points half a step out, and
/// from 26 mm off on its −x side.
fn edge_on_web_row(i: usize) -> impl Iterator<Item = Vec3> {
    let y = -50.0 + i as f64;
    let top = (0..=8).map(move |j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0));
    let plus = (0..30).map(move |j| Vec3::new(WEB_X + 4.0 + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0));
    let minus = (0..30).map(move |j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0));
    top.chain(plus).chain(minus)
}

#[test]
fn a_face_seen_along_part_of_the_web_gives_way_to_the_flanges_edge() {
    // The edge-on web of the tests above, its +x face (x = WEB_X + 4)
    // returning points only along part of the web, its flange seen up
    // to the root all along: the root runs the web's length, from the
    // flange's edge. Seen from y = 44 to 49, the face's root is 5 mm
    // long; seen from y = −50 to 20 (71 % of the web's top), the web's
    // top and the flange up to the root go on 29 mm past it.
    for face_seen in [44.0..=49.0, -50.0..=20.0] {
        let mut pts = Vec::new();
        for i in 0..100 {
            let y = -50.0 + i as f64;
            pts.extend(edge_on_web_row(i));
            if face_seen.contains(&y) {
                pts.extend((0..20).map(|j| Vec3::new(WEB_X + 4.0, y, 699.0 - 2.0 * j as f64)));
            }
        }
        let ends = flange_edge_root_ends(&pts);
        assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{face_seen:?}: {ends:?}");
        let roots = roots_of(&pts);
        let root = roots.iter().find_map(|r| r.as_ref().ok()).expect("the root facing the camera");
        assert!(ids(root).contains(&"tee.short_face_gives_way_to_flange_edge"), "{face_seen:?}: {:?}", ids(root));
    }
}

#[test]
fn a_web_axis_off_the_web_is_read_again_along_the_flange_s_edge() {
    // The edge-on web of the tests above, 200 mm long (y from −50 to
    // 149), the image's border cutting its top (z = 660) at y = 20 but
    // the flange (z = 700) only past the web's end. The top's long axis
    // is taken 3° off the web, as from a top the border cuts
    // obliquely: the flange's edge at x = WEB_X + 4, looked for outward
    // of the web's middle line along that axis, crosses that line about
    // 75 mm past the top's middle. Read again along the edge's own
    // line, the root runs the web's length on the edge.
    let in_view = |p: &Vec3| p.y < 20.0 + 4.0 * (p.z - 660.0);
    let mut pts = Vec::new();
    for i in 0..200 {
        pts.extend(edge_on_web_row(i));
    }
    pts.retain(in_view);
    let (cloud, mut top, [plus, minus]) = tee_parts(&pts);
    let skew = 3f64.to_radians();
    top.long_axis = Vec3::new(skew.sin(), skew.cos(), 0.0);
    let pieces = [&plus, &minus];
    let view = TeeView { in_view: Some(&in_view), ..test_view(&cloud, Web::Top(&top), &pieces) };
    let roots = find_roots(&view);
    let root = roots.iter().find_map(|r| r.as_ref().ok()).unwrap_or_else(|| panic!("{roots:?}"));
    assert!(matches!(root.evidence, RootEvidence::FlangeEdge { .. }), "{:?}", root.evidence);
    for s in [root.line.s_min, root.line.s_max] {
        let p = root.line.at(s);
        assert!((p.x - WEB_X - 4.0).abs() < 1e-6 && (p.z - 700.0).abs() < 1e-6, "{p:?}");
    }
    // (Along the edge's fitted line: its ends to a few hundredths.)
    let ends = ends_y(root);
    assert!((ends[0] + 50.0).abs() < 0.05 && (ends[1] - 149.0).abs() < 0.05, "{ends:?}");
    assert!(ids(root).contains(&"tee.flange_edge_read_along_itself"), "{:?}", ids(root));
}

#[test]
fn a_face_that_gives_no_root_leaves_it_to_the_flanges_edge() {
    // The edge-on web of the tests above, its +x face (x = WEB_X + 4)
    // returning points only from y = −50 to −30, where a dropout takes
    // the flange's first 10 mm beside the root: the face's foot and the
    // flange up to it are seen together nowhere, and the root is read
    // from the flange's edge where that is seen, from y = −28 on.
    let mut pts = Vec::new();
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
        let from = if y < -28.0 { WEB_X + 14.0 } else { WEB_X + 4.0 };
        pts.extend((0..30).map(|j| Vec3::new(from + 0.5 * j as f64 + 0.25 * (i % 2) as f64, y, 700.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
        if y <= -30.0 {
            pts.extend((0..20).map(|j| Vec3::new(WEB_X + 4.0, y, 699.0 - 2.0 * j as f64)));
        }
    }
    let ends = flange_edge_root_ends(&pts);
    assert!((ends[0] + 28.0).abs() < 1e-6 && (ends[1] - 49.0).abs() < 1e-6, "{ends:?}");
}

#[test]
fn a_flange_ending_at_the_projectors_shadow_gives_no_root() {
    // A web between the camera (x = 0) and the projector (x = 150),
    // its top from x = 71 to 79 at z = 660, no face points: the camera
    // looks at its −x face, which the projector does not light, so the
    // flange there is seen from where the projector's ray over the
    // top's edge lands; on the +x side, from where the camera's does.
    let lit_from = 150.0 + (71.0 - 150.0) * 700.0 / 660.0;
    let seen_from = 79.0 * 700.0 / 660.0;
    let mut pts = Vec::new();
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..=8).map(|j| Vec3::new(71.0 + j as f64, y, 660.0)));
        for j in 0..30 {
            pts.push(Vec3::new(lit_from - 0.5 * j as f64, y, 700.0));
            pts.push(Vec3::new(seen_from + 0.5 * j as f64, y, 700.0));
        }
    }
    for root in roots_of_web_at(&pts, 75.0) {
        let not_seen = root.expect_err("a shadow's edge is no root");
        assert!(not_seen.reason.contains("shadow"), "{}", not_seen.reason);
        assert_eq!(not_seen.rule.id, "tee.flange_edge_at_shadow", "{}", not_seen.reason);
    }
}

#[test]
fn the_run_seen_bridges_short_breaks_and_not_long_ones() {
    // Evidence every 0.5 mm from 0 to 40 and 44 to 60 (a 4 mm break,
    // bridged), then 100 to 110 (a 40 mm break, not).
    let s: Vec<f64> = (0..=220)
        .map(|k| k as f64 * 0.5)
        .filter(|s| (0.0..=40.0).contains(s) || (44.0..=60.0).contains(s) || *s >= 100.0)
        .collect();
    let run = seen_run(&s, &s, 0.5).unwrap();
    assert_eq!((run.s0, run.s1), (0.0, 60.0));
    // The joint seen is the run's 60 mm and the 10 mm past the long break.
    assert!((run.seen_mm - 70.0).abs() < 1e-9, "{}", run.seen_mm);
    assert!((run.share - 60.0 / 70.0).abs() < 1e-9, "{}", run.share);
    assert!(run.coverage[0] < 1.0);
    // The 10 mm seen past the long break is left out.
    assert!(run.cut);
    // Nothing seen together: no run.
    assert!(seen_run(&[0.0, 1.0], &[50.0, 51.0], 0.5).is_none());
}

#[test]
fn a_root_seen_over_its_whole_visible_stretch_spans_all_of_it_at_any_spacing() {
    // One unbroken run of evidence, the face's foot from 3.3 to 158.3 mm
    // and the flange from 3.5 to 158.0 mm: the stretch, 3.5 to 158.0 mm,
    // is all the joint in view, however coarse the stations, and its ends
    // do not round to a station's.
    for spacing in [0.5, 1.5, 2.6] {
        let foot: Vec<f64> = (0..=310).map(|k| 3.3 + 0.5 * k as f64).collect();
        let flange: Vec<f64> = foot.iter().map(|s| s + 0.2).filter(|s| *s <= 158.3).collect();
        let run = seen_run(&foot, &flange, spacing).unwrap();
        assert!(!run.cut, "{spacing}");
        assert!((run.s0 - 3.5).abs() < 1e-9 && (run.s1 - 158.0).abs() < 1e-9, "{spacing}: {run:?}");
        assert!((run.share - 1.0).abs() < 1e-12, "{spacing}: {}", run.share);
        assert!((run.seen_mm - 154.5).abs() < 1e-9, "{spacing}: {}", run.seen_mm);
    }
}

#[test]
fn a_web_top_under_the_flange_gives_no_root() {
    // The web's "top" 40 mm beyond the flange, away from the camera: no
    // web stands on that flange, and neither root is read.
    let mut pts = face_points(0.0);
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 740.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
    }
    let cloud = cloud_of(&pts);
    let top = PlaneCluster::of_points(&pts, |p| p.z == 740.0);
    let flange = PlaneCluster::of_points(&pts, |p| p.z == 700.0);
    for root in find_roots(&test_view(&cloud, Web::Top(&top), &[&flange])) {
        let not_seen = root.expect_err("no web stands on the flange");
        assert_eq!(not_seen.rule.id, "tee.web_not_over_flange", "{}", not_seen.reason);
    }
}

#[test]
fn a_flange_seen_on_one_side_only_gives_no_root_on_the_other() {
    // The tee of the tests above, its +x face seen, its flange seen on
    // the +x side only: the −x root is hidden, not invented.
    let mut pts = face_points(0.0);
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
    }
    let roots = roots_with_flange_pieces(&pts, &[&|p: &Vec3| p.z == 700.0]);
    plus_x_face_root(&roots);
    let hidden = roots.iter().find_map(|r| r.as_ref().err()).expect("the −x root not seen");
    assert!(!hidden.flange_seen);
    assert_eq!(hidden.rule.id, "tee.root_hidden_by_web", "{}", hidden.reason);
    assert!(hidden.reason.contains("the flange on this side is not seen"), "{}", hidden.reason);
}

#[test]
fn a_face_whose_flange_is_not_seen_up_to_it_gives_no_root() {
    // The one face of the test of a web seen by one face only, its top
    // out of view, the flange on its side seen only from 20 mm out: the
    // face's foot and the flange up to it are seen together nowhere, and
    // with no top the flange's edge cannot stand in.
    let mut pts = face_points(0.0);
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 25.0 + 0.5 * j as f64, y, 700.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 10.0 - j as f64, y, 700.0)));
    }
    let cloud = cloud_of(&pts);
    let flange = PlaneCluster::of_points(&pts, |p| p.z == 700.0);
    let face = plus_x_face_standing_on(&flange);
    let roots = find_roots(&test_view(&cloud, Web::Face(&face), &[&flange]));
    let near = roots.iter().filter_map(|r| r.as_ref().err()).find(|r| r.side == Side::Near).expect("not seen");
    assert_eq!(near.rule.id, "tee.root_not_seen", "{}", near.reason);
    assert!(near.reason.contains("the flange is not seen up to the web's face"), "{}", near.reason);
}

#[test]
fn a_face_seen_without_the_web_s_top_no_longer_than_a_web_is_thick_may_be_its_end() {
    // The one face of the test above seen along 9 mm only, as a web's
    // end 9 mm thick stands: with the top out of view nothing tells it
    // from a side face by its direction, and its "root" would run across
    // the web. Seen along 40 mm, more than the thickest web's 30, it is a
    // side face.
    for (half_mm, end) in [(4.0, true), (20.0, false)] {
        let roots = one_face_roots(|p| p.y.abs() <= half_mm);
        let near = roots.iter().find(|r| r.as_ref().map_or_else(|e| e.side, |r| r.side) == Side::Near).unwrap();
        match near {
            Err(why) if end => {
                assert_eq!(why.rule.id, "tee.side_face_is_web_end", "{}", why.reason);
                assert!(why.reason.contains("no longer than the thickest web (30 mm)"), "{}", why.reason);
            }
            Ok(root) if !end => assert!(root.line.s_max - root.line.s_min > 30.0, "{root:?}"),
            other => panic!("{half_mm}: {other:?}"),
        }
    }
}

#[test]
fn mixed_returns_along_the_rays_are_no_side_face() {
    // The tee of the tests above with, on its +x side, no face but a veil
    // of returns along the camera's rays from the flange at the face's
    // foot towards the camera: a plane, but one the camera cannot see as
    // a surface.
    let mut pts = Vec::new();
    for i in 0..100 {
        let y = -50.0 + i as f64;
        pts.extend((0..=8).map(|j| Vec3::new(WEB_X - 4.0 + j as f64, y, 660.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X + 5.5 + 0.5 * j as f64, y, 700.0)));
        pts.extend((0..30).map(|j| Vec3::new(WEB_X - 30.0 - 0.5 * j as f64, y, 700.0)));
        pts.extend((2..=40).map(|j| Vec3::new(WEB_X + 5.0, y, 700.0) * (1.0 - 0.001 * j as f64)));
    }
    let veil = plus_x_face_reading(&pts).expect_err("a veil is no face");
    assert_eq!(veil.rule.id, "tee.side_face_along_camera_rays", "{veil}");
}

#[test]
fn a_flange_edge_running_past_the_web_top_with_no_border_gives_no_root() {
    // The edge-on web of the tests above, its top seen only for y ≤ 19
    // while the flange's edge runs on to y = 49, and nothing (no grid, no
    // rays) tells whether the image cut the top there or the web ends.
    let mut pts = Vec::new();
    for i in 0..100 {
        pts.extend(edge_on_web_row(i).filter(|p| p.z == 700.0 || i < 70));
    }
    let roots = roots_of(&pts);
    let near = roots.iter().filter_map(|r| r.as_ref().err()).find(|r| r.side == Side::Near).expect("not planned");
    assert_eq!(near.rule.id, "tee.flange_edge_past_web_top", "{}", near.reason);
}

#[test]
fn a_face_seen_past_a_long_break_gives_its_longest_run() {
    // The face of the tests above returns nothing from y = 20 to 39, a
    // break longer than a joint's: the root read from the face runs from
    // −50 to 19, the 10 mm past the break left out.
    let pts = tee_with_face_seen_above(|y| if (20.0..40.0).contains(&y) { f64::INFINITY } else { 1.0 }, |_| true);
    let root = plus_x_face_reading(&pts).expect("the +x face's root");
    assert_on_plus_x_face(&root);
    let ends = ends_y(&root);
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 19.0).abs() < 1e-6, "{ends:?}");
    assert_eq!(ids(&root), ["tee.root_longest_seen_run"]);
}

#[test]
fn a_root_whose_evidence_reaches_the_image_border_ends_where_the_border_crosses_it() {
    // The tee of the tests above seen up to an image border at y/z =
    // 39.6/700: the face's foot and the flange beside the root are seen up
    // to y = 39, the root runs on to where the border crosses it.
    let limit = 39.6 / 700.0;
    let pts = tee_with_face_seen_above(|_| 1.0, |p| p.y / p.z < limit);
    let (cloud, top, [plus, minus]) = tee_parts(&pts);
    let pieces = [&plus, &minus];
    let border = ViewBorder::from_tangents([-1.0, 1.0, -1.0, limit]);
    let view = TeeView { border: Some(&border), ..test_view(&cloud, Web::Top(&top), &pieces) };
    let root = plus_x_face_root(&find_roots(&view));
    let ends = ends_y(&root);
    assert!((ends[0] + 50.0).abs() < 1e-6 && (ends[1] - 39.6).abs() < 1e-6, "{ends:?}");
    assert_eq!(ids(&root), ["tee.root_ends_at_image_border"]);
}
