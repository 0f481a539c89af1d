//! The weld equation per joint type (section 4.3), from the two fitted
//! weld edges `f_E1` and `f_E2`.
//!
//! - V-butt: the midline shifted by the groove depth along the plate
//!   normal, `f_V = (f_E1 + f_E2) / 2 + d n_V` (Eq. 32). The edges are
//!   where the plates' points stop, and a shallow bevel's first
//!   millimetres lie within the on-plane tolerance of its plate, so each
//!   edge is read somewhat inside the groove, one side more than the
//!   other; where both bevels are seen, the midline is moved to where
//!   their faces meet the plates' top ([`moved_towards`]).
//! - I-butt: the midline, `f_I = (f_E1 + f_E2) / 2` (Eq. 36).
//! - Lap, as the paper has it: the lower plate's edge, `f_D = f_E1`
//!   (Eq. 38). But the lower plate's visible edge is not the weld root:
//!   the upper plate hides, or the projector shadows, a strip beside it.
//!   The root is where the upper plate's side face meets the lower plate's
//!   top surface, which for a cut plate lies straight below the upper
//!   plate's top edge: the upper edge shifted by the plate step along the
//!   normal.

use crate::geometry::Vec3;
use crate::geometry::fit::Plane;

use super::groove::LineAlong;
use super::refit::SeamCurve;

/// The plate normal of Eq. 33 and 34: from two points of `f_E1` and one of
/// `f_E2`, `n_1 = AB × BC / |AB × BC|`, turned to point away from the
/// camera (`n_1 · z_cam >= 0`).
pub fn paper_normal(e1: &SeamCurve, e2: &SeamCurve) -> Option<Vec3> {
    let a = e1.at(e1.s_min);
    let b = e1.at(e1.s_max);
    let c = e2.at(e2.s_min);
    let n1 = (b - a).cross(&(c - b)).try_normalize(1e-12)?;
    Some(if n1.z >= 0.0 { n1 } else { -n1 })
}

/// Eq. 32: the V-butt weld at groove depth `d` below the midline.
pub fn v_butt(e1: &SeamCurve, e2: &SeamCurve, groove_depth_mm: f64, n_v: &Vec3) -> Option<SeamCurve> {
    Some(e1.midline(e2)?.shifted(&(n_v * groove_depth_mm)))
}

/// Eq. 36: the I-butt weld, the midline of the two edges.
pub fn i_butt(e1: &SeamCurve, e2: &SeamCurve) -> Option<SeamCurve> {
    e1.midline(e2)
}

/// `weld` moved across the seam, towards the second weld edge `e2` from
/// the first `e1`, by `offset` at each point along it: where a V-groove's
/// bevels say its edges' midline lies
/// ([`super::groove::GrooveProfile::bevel_midline_offset`]). The curves
/// share their axes; a line in `s` adds to the first two coefficients of
/// `h_a` (Eq. 20).
pub fn moved_towards(weld: &SeamCurve, e1: &SeamCurve, e2: &SeamCurve, offset: &LineAlong) -> SeamCurve {
    let middle = offset.middle_s;
    let sign = (e2.at(middle) - e1.at(middle)).dot(&weld.axes.a).signum();
    let mut moved = weld.clone();
    if moved.coef_a.len() < 2 {
        moved.coef_a.resize(2, 0.0);
    }
    moved.coef_a[0] += sign * offset.at(0.0);
    moved.coef_a[1] += sign * offset.per_mm;
    moved
}

/// Eq. 38 as the paper applies it: of the two edges, the lower plate's is
/// the one further from the camera (larger z) at the same feature value.
pub fn lap_paper(e1: &SeamCurve, e2: &SeamCurve) -> SeamCurve {
    let s = (e1.s_min.max(e2.s_min) + e1.s_max.min(e2.s_max)) / 2.0;
    if e1.at(s).z >= e2.at(s).z { e1.clone() } else { e2.clone() }
}

/// The lap's plate step at `s` along the upper plate's edge: how far the
/// lower plate's plane lies beyond that edge along `n`, the plate normal
/// pointing away from the camera. `None` where `n` runs along the lower
/// plane.
///
/// Read at the seam, not as the difference of the two planes' offsets:
/// an offset is a plane's distance from the camera's centre, so two planes
/// meeting along the seam at a fraction of a degree differ in offset by
/// that angle times how far the seam lies from the camera's centre across
/// it, in the plates' plane (0.5° at 300 mm: 2.6 mm). Plates parallel to
/// well within that give the same step either way.
pub fn lap_step(upper_edge: &SeamCurve, lower: &Plane, n: &Vec3, s: f64) -> Option<f64> {
    let along = lower.normal.dot(n);
    (along.abs() > MIN_STEP_COSINE).then(|| -lower.signed_distance(&upper_edge.at(s)) / along)
}

/// The least cosine between the plate normal and the lower plate's normal
/// for a lap step to be read along it: plates this far apart (84°) are no
/// lap, and the plate-angle gate refuses them long before.
const MIN_STEP_COSINE: f64 = 0.1;

/// The lap root: the upper plate's edge moved down the plate step.
/// `step_mm` is the distance from the upper plate's edge to the lower
/// plate's top surface ([`lap_step`]) and `n` the plate normal pointing
/// away from the camera.
pub fn lap_root(upper_edge: &SeamCurve, step_mm: f64, n: &Vec3) -> SeamCurve {
    upper_edge.shifted(&(n * step_mm))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::refit::SeamAxes;

    fn edge(y0: f64, z0: f64) -> SeamCurve {
        SeamCurve {
            axes: SeamAxes { origin: Vec3::zeros(), e: Vec3::x(), a: Vec3::y(), b: Vec3::z() },
            coef_a: vec![y0, 0.0],
            coef_b: vec![z0, 0.0],
            s_min: -50.0,
            s_max: 50.0,
        }
    }

    #[test]
    fn v_butt_is_the_midline_shifted_by_the_groove_depth() {
        let w = v_butt(&edge(-3.0, 700.0), &edge(7.0, 700.0), 5.0, &Vec3::z()).unwrap();
        assert!((w.at(10.0) - Vec3::new(10.0, 2.0, 705.0)).norm() < 1e-12);
    }

    #[test]
    fn paper_normal_faces_away_from_the_camera() {
        let n = paper_normal(&edge(-3.0, 700.0), &edge(7.0, 700.0)).unwrap();
        assert!((n - Vec3::z()).norm() < 1e-12);
        let n = paper_normal(&edge(7.0, 700.0), &edge(-3.0, 700.0)).unwrap();
        assert!((n - Vec3::z()).norm() < 1e-12);
    }

    #[test]
    fn lap_paper_takes_the_deeper_edge_and_the_root_sits_below_the_upper_edge() {
        let upper = edge(0.0, 694.0);
        let lower = edge(4.0, 700.0);
        assert_eq!(lap_paper(&upper, &lower), lower);
        let root = lap_root(&upper, 6.0, &Vec3::z());
        assert!((root.at(0.0) - Vec3::new(0.0, 0.0, 700.0)).norm() < 1e-12);
    }

    #[test]
    fn the_lap_step_is_read_at_the_seam_not_from_the_planes_offsets() {
        // The upper edge runs along x at z = 694, 100 mm off the optical
        // axis; the lower plate's plane passes 6 mm beyond it at the seam,
        // turned half a degree about the seam's line, as a plate fitted
        // over a part touching it is.
        let upper = edge(100.0, 694.0);
        let turn = 0.5f64.to_radians();
        let normal = Vec3::new(0.0, -turn.sin(), turn.cos());
        let lower = Plane { normal, offset: normal.dot(&Vec3::new(0.0, 100.0, 700.0)) };
        let step = lap_step(&upper, &lower, &Vec3::z(), 0.0).unwrap();
        assert!((step - 6.0).abs() < 1e-9, "{step}");
        // The offsets' difference is 0.9 mm off: each offset is measured
        // from the camera's centre, not at the seam.
        let upper_plane = Plane { normal: Vec3::z(), offset: 694.0 };
        assert!((lower.offset - upper_plane.offset - step).abs() > 0.8);
        // Along the plate normal, however the lower plate is turned.
        let lifted = Plane { normal, offset: lower.offset + 1.0 };
        let moved = lap_step(&upper, &lifted, &Vec3::z(), 10.0).unwrap();
        assert!((moved - (6.0 + 1.0 / turn.cos())).abs() < 1e-9, "{moved}");
        assert_eq!(lap_step(&upper, &Plane { normal: Vec3::x(), offset: 0.0 }, &Vec3::z(), 0.0), None);
    }
}
