//! The welding trajectory (section 5.1): waypoints sampled along the weld
//! at a fixed step, carried into the robot base frame by Eq. 42,
//! `Base_p = Base_T_End · End_T_Camera · Camera_p`, each with a torch
//! orientation.
//!
//! The torch frame: tool z along the plate normal into the workpiece, tool
//! x along the travel direction, tool y completing a right-handed frame;
//! then tilted by the work angle about tool x and the travel angle about
//! tool y.
//!
//! A tee's fillet weld has two faces, not one plate: its torch axis
//! ([`fillet_torch_axis`]) lies in the plane across the root, leaning
//! from the flange towards the web by `trajectory.fillet_work_angle_deg`
//! (45°: the bisector of a square tee's corner), and takes the place of
//! the plate normal as tool z; the work and travel angles then tilt it as
//! for every joint.
//!
//! Which end the waypoints start from is a rule a robot programmer can
//! rely on, stated in the robot base frame (the camera's view of the seam
//! changes with the pose; the base frame does not): the end nearest the
//! request's `start_near` point when it gives one; else, when the seam
//! runs more along base x than along base y, the end with the smaller
//! base x, otherwise the end with the smaller base y.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Unit};

use crate::geometry::{Vec3, extent};

use super::refit::SeamCurve;

/// One waypoint in the robot base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waypoint {
    pub position: Vec3,
    /// `Base_R_Tool`.
    pub orientation: Rotation3<f64>,
}

/// Settings of the trajectory: the config's, with a request's overrides.
pub use crate::config::TrajectoryParams;

/// Feature values along `curve` from `s0` to `s1` at arc-length spacing of
/// at most `step`, both ends included (the spacing is evened out so the
/// last waypoint lands on the seam's end).
pub fn sample_features(curve: &SeamCurve, s0: f64, s1: f64, step: f64) -> Vec<f64> {
    // Dense polyline for arc length; straight seams need few points but
    // higher degrees deserve a fine one.
    const DENSE: usize = 512;
    let ss: Vec<f64> = (0..=DENSE).map(|k| s0 + (s1 - s0) * k as f64 / DENSE as f64).collect();
    let mut arc = vec![0.0; ss.len()];
    for k in 1..ss.len() {
        arc[k] = arc[k - 1] + (curve.at(ss[k]) - curve.at(ss[k - 1])).norm();
    }
    let total = arc[DENSE];
    let segments = ((total / step).ceil() as usize).max(1);
    let mut out = Vec::with_capacity(segments + 1);
    let mut k = 0;
    for j in 0..=segments {
        let target = total * j as f64 / segments as f64;
        while k + 1 < DENSE && arc[k + 1] < target {
            k += 1;
        }
        let span = arc[k + 1] - arc[k];
        let f = if span > 0.0 { ((target - arc[k]) / span).clamp(0.0, 1.0) } else { 0.0 };
        out.push(ss[k] + (ss[k + 1] - ss[k]) * f);
    }
    out
}

/// Orders the seam's ends `s0`, `s1` into (start, end): the start is the
/// end nearest `start_near` (base frame) when given; else the end with the
/// smaller base-frame x when the seam runs at least as much along x as
/// along y, otherwise the one with the smaller base-frame y.
pub fn travel_order(
    curve: &SeamCurve,
    s0: f64,
    s1: f64,
    base_from_camera: &Isometry3<f64>,
    start_near: Option<Vec3>,
) -> (f64, f64) {
    let a = (base_from_camera * Point3::from(curve.at(s0))).coords;
    let b = (base_from_camera * Point3::from(curve.at(s1))).coords;
    let forward = match start_near {
        Some(p) => (a - p).norm() <= (b - p).norm(),
        None => {
            let d = b - a;
            if d.x.abs() >= d.y.abs() { d.x >= 0.0 } else { d.y >= 0.0 }
        }
    };
    if forward { (s0, s1) } else { (s1, s0) }
}

/// The order of a frame's seams, given each one's ends in the base frame:
/// `(index, forward)` pairs, a seam forward when it runs from its first
/// end to its second. See the module's documentation for the rule.
pub fn seam_order(ends: &[[Vec3; 2]], start_near: Option<Vec3>) -> Vec<(usize, bool)> {
    match start_near {
        Some(p) => {
            let mut left: Vec<usize> = (0..ends.len()).collect();
            let mut at = p;
            let mut order = Vec::with_capacity(ends.len());
            while !left.is_empty() {
                let distance = |k: usize| (ends[k][0] - at).norm().min((ends[k][1] - at).norm());
                let Some(pos) = (0..left.len()).min_by(|a, b| distance(left[*a]).total_cmp(&distance(left[*b]))) else {
                    break;
                };
                let k = left.remove(pos);
                let forward = (ends[k][0] - at).norm() <= (ends[k][1] - at).norm();
                at = if forward { ends[k][1] } else { ends[k][0] };
                order.push((k, forward));
            }
            order
        }
        None => {
            let along_first = |d: Vec3| if d.x.abs() >= d.y.abs() { d.x >= 0.0 } else { d.y >= 0.0 };
            let forward: Vec<bool> = ends.iter().map(|[a, b]| along_first(b - a)).collect();
            let starts: Vec<Vec3> = (0..ends.len()).map(|k| if forward[k] { ends[k][0] } else { ends[k][1] }).collect();
            let spread = |axis: usize| {
                let (lo, hi) = extent(starts.iter().map(|s| s[axis]));
                hi - lo
            };
            let axis = if spread(0) >= spread(1) { 0 } else { 1 };
            let mut order: Vec<usize> = (0..ends.len()).collect();
            order.sort_by(|a, b| starts[*a][axis].total_cmp(&starts[*b][axis]));
            order.into_iter().map(|k| (k, forward[k])).collect()
        }
    }
}

/// The torch orientation for travel direction `travel` and plate normal
/// `into` (both in one frame), with work and travel angles in degrees.
pub fn torch_orientation(travel: &Vec3, into: &Vec3, work_deg: f64, travel_deg: f64) -> Rotation3<f64> {
    let z = into.normalize();
    let x = (travel - z * travel.dot(&z)).normalize();
    let y = z.cross(&x);
    let base = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    let work = Rotation3::from_axis_angle(&Unit::new_normalize(Vec3::x()), work_deg.to_radians());
    let push = Rotation3::from_axis_angle(&Unit::new_normalize(Vec3::y()), travel_deg.to_radians());
    base * work * push
}

/// A fillet weld's torch axis, into the joint (the tool z of a tee's
/// waypoints): in the plane across the root, at `angle_from_flange_deg`
/// from the flange towards the web. `into_flange` is the flange's normal
/// into the workpiece, `away_from_web` the direction in the flange's plane
/// across the root away from the web; the torch lies on the open side,
/// between the flange and the web, and points back down at the root.
pub fn fillet_torch_axis(into_flange: &Vec3, away_from_web: &Vec3, angle_from_flange_deg: f64) -> Vec3 {
    let a = angle_from_flange_deg.to_radians();
    // From the root out to the torch: along the flange, then up off it.
    let out = away_from_web * a.cos() - into_flange * a.sin();
    -out.normalize()
}

/// Samples the weld from `s_start` to `s_end` (in travel order) and
/// returns base-frame waypoints (Eq. 42). `normal` is the torch's axis
/// before the work and travel angles, in the camera frame, into the
/// workpiece: the plate normal, or a fillet's [`fillet_torch_axis`].
pub fn waypoints(
    curve: &SeamCurve,
    s_start: f64,
    s_end: f64,
    normal: &Vec3,
    base_from_camera: &Isometry3<f64>,
    params: &TrajectoryParams,
) -> Vec<Waypoint> {
    let normal_base = base_from_camera.rotation * normal;
    sample_features(curve, s_start, s_end, params.step_mm)
        .into_iter()
        .map(|s| {
            let p = curve.at(s);
            let mut travel = curve.tangent(s);
            if (s_end - s_start) < 0.0 {
                travel = -travel;
            }
            let position = (base_from_camera * Point3::from(p)).coords;
            let travel_base = base_from_camera.rotation * travel;
            let orientation =
                torch_orientation(&travel_base, &normal_base, params.work_angle_deg, params.travel_angle_deg);
            Waypoint { position, orientation }
        })
        .collect()
}

/// The point `offset_mm` back from `w` along its torch axis (tool z points
/// into the workpiece, so back is out of it), with the same orientation:
/// where a robot approaches the seam's first waypoint from and retracts
/// to after its last.
pub fn backed_off(w: &Waypoint, offset_mm: f64) -> Waypoint {
    Waypoint { position: w.position - w.orientation * Vec3::z() * offset_mm, orientation: w.orientation }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::refit::SeamAxes;
    use nalgebra::{Translation3, UnitQuaternion};

    fn line() -> SeamCurve {
        SeamCurve {
            axes: SeamAxes { origin: Vec3::new(0.0, 0.0, 700.0), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() },
            coef_a: vec![2.0, 0.0],
            coef_b: vec![0.0, 0.0],
            s_min: -50.0,
            s_max: 50.0,
        }
    }

    #[test]
    fn sampling_covers_both_ends_at_most_one_step_apart() {
        let s = sample_features(&line(), -50.0, 51.0, 5.0);
        assert_eq!(s.len(), 22);
        assert!((s[0] + 50.0).abs() < 1e-12 && (s[21] - 51.0).abs() < 1e-9);
        assert!(s.windows(2).all(|w| (w[1] - w[0] - 101.0 / 21.0).abs() < 1e-6));
    }

    #[test]
    fn torch_z_points_into_the_plate_and_x_along_travel() {
        let r = torch_orientation(&Vec3::new(1.0, 0.0, 0.1), &Vec3::z(), 0.0, 0.0);
        assert!((r * Vec3::z() - Vec3::z()).norm() < 1e-12);
        assert!((r * Vec3::x() - Vec3::x()).norm() < 1e-12);
        let tilted = torch_orientation(&Vec3::x(), &Vec3::z(), 30.0, 0.0);
        assert!(((tilted * Vec3::z()).dot(&Vec3::z()) - 30f64.to_radians().cos()).abs() < 1e-12);
    }

    #[test]
    fn a_fillet_torch_bisects_a_square_tee_and_leans_as_configured() {
        // The flange is z = const (into it +z), the web stands at the
        // root's -x side, so away from the web is +x.
        let axis = fillet_torch_axis(&Vec3::z(), &Vec3::x(), 45.0);
        let half = std::f64::consts::FRAC_1_SQRT_2;
        assert!((axis - Vec3::new(-half, 0.0, half)).norm() < 1e-12, "{axis:?}");
        // 30° from the flange: flatter, further out over the flange.
        let flat = fillet_torch_axis(&Vec3::z(), &Vec3::x(), 30.0);
        assert!((flat.z - 0.5).abs() < 1e-12 && flat.x < -0.86, "{flat:?}");
        // As tool z, a work angle tilts it further about the travel axis.
        let r = torch_orientation(&Vec3::y(), &axis, 10.0, 0.0);
        assert!(((r * Vec3::z()).dot(&axis) - 10f64.to_radians().cos()).abs() < 1e-12);
    }

    #[test]
    fn seams_follow_from_the_start_point_each_to_the_nearest_next() {
        // Three seams along base y, at x = 0, 100 and 300 mm.
        let seam = |x: f64, flip: bool| {
            let (a, b) = (Vec3::new(x, 0.0, 0.0), Vec3::new(x, 50.0, 0.0));
            if flip { [b, a] } else { [a, b] }
        };
        let ends = [seam(300.0, false), seam(0.0, true), seam(100.0, false)];
        // From near the third seam's far end: it first, backwards, then the
        // one at x = 0 from y = 0, then x = 300 from its end nearer (0, 50).
        let order = seam_order(&ends, Some(Vec3::new(110.0, 60.0, 0.0)));
        assert_eq!(order, vec![(2, false), (1, false), (0, false)]);
        // Without a point: each seam from its smaller base y, by base x.
        assert_eq!(seam_order(&ends, None), vec![(1, false), (2, true), (0, true)]);
        assert_eq!(seam_order(&[], None), vec![]);
    }

    #[test]
    fn waypoints_are_transformed_into_the_base_frame() {
        let base_from_camera = Isometry3::from_parts(
            Translation3::new(100.0, -200.0, 300.0),
            UnitQuaternion::from_axis_angle(&Vec3::x_axis(), std::f64::consts::PI),
        );
        let params = TrajectoryParams { step_mm: 10.0, ..TrajectoryParams::default() };
        // The seam runs along camera y, which this pose turns into base -y:
        // the default starts at the smaller base y, camera y = +50.
        let (s0, s1) = travel_order(&line(), -50.0, 50.0, &base_from_camera, None);
        assert_eq!((s0, s1), (50.0, -50.0), "from the smaller base-frame y");
        let near_other_end = Some(Vec3::new(102.0, 250.0, -400.0));
        assert_eq!(travel_order(&line(), -50.0, 50.0, &base_from_camera, near_other_end), (-50.0, 50.0));
        let (s0, s1) = (-50.0, 50.0);
        let w = waypoints(&line(), s0, s1, &Vec3::z(), &base_from_camera, &params);
        assert_eq!(w.len(), 11);
        // Camera (2, -50, 700) → rotate 180° about x → (2, 50, -700) → translate.
        assert!((w[0].position - Vec3::new(102.0, -150.0, -400.0)).norm() < 1e-9);
        assert!((w[0].orientation * Vec3::z() - Vec3::new(0.0, 0.0, -1.0)).norm() < 1e-9);
        // The torch points down (base -z) here, so backing off rises.
        let above = backed_off(&w[0], 50.0);
        assert!((above.position - w[0].position - Vec3::new(0.0, 0.0, 50.0)).norm() < 1e-9);
    }
}
