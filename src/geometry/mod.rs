//! Geometry shared by the pipeline, the simulator and the evaluation:
//! rigid transforms and poses, and least-squares plane and line fits.

pub mod fit;
pub mod pose;

pub use nalgebra::{Isometry3, Point3, Rotation3, Unit, Vector3};

/// Shorthand for a camera- or base-frame vector in millimetres.
pub type Vec3 = Vector3<f64>;

/// Converts a stored cloud point to double precision for geometry.
#[inline]
pub fn vec3(p: &[f32; 3]) -> Vec3 {
    Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// Distance from `p` to the segment `a..b`.
pub fn distance_to_segment(p: &Vec3, a: &Vec3, b: &Vec3) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 == 0.0 {
        return (p - a).norm();
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// Distance from `p` to a polyline (the planned trajectory).
pub fn distance_to_polyline(p: &Vec3, polyline: &[Vec3]) -> f64 {
    match polyline {
        [] => f64::INFINITY,
        [only] => (p - only).norm(),
        _ => polyline.windows(2).map(|w| distance_to_segment(p, &w[0], &w[1])).fold(f64::INFINITY, f64::min),
    }
}
