//! Geometry shared by the pipeline, the simulator and the evaluation:
//! rigid transforms and poses, the pose conventions of robot controllers,
//! least-squares plane and line fits, and the region of interest a cloud
//! is cropped to.

pub mod conventions;
pub mod fit;
pub mod pose;
pub mod region;

pub use nalgebra::{Isometry3, Point3, Rotation3, Unit, Vector3};

/// Shorthand for a camera- or base-frame vector in millimetres.
pub type Vec3 = Vector3<f64>;

/// Converts a stored cloud point to double precision for geometry.
#[inline]
pub fn vec3(p: &[f32; 3]) -> Vec3 {
    Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

// Floor, ceiling and rounding for the small magnitudes of pixel offsets
// and depth steps. Without SSE4.1 the standard ones are library calls, and
// these run on every pixel of a frame.

/// `x.floor()` as an integer, for |x| < 2^52.
#[inline(always)]
pub fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    t - ((t as f64) > x) as i64
}

/// `x.ceil()` as an integer, for |x| < 2^52.
#[inline(always)]
pub fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    t + ((t as f64) < x) as i64
}

/// `x.round()` (half away from zero) as an integer, for |x| < 2^52.
#[inline(always)]
pub fn round_i64(x: f64) -> i64 {
    if x >= 0.0 { floor_i64(x + 0.5) } else { -floor_i64(-x + 0.5) }
}

/// Two unit directions spanning the plane across the unit `normal`: `u`
/// square to the normal and to whichever of x and y lies further from it
/// (so the cross product never nears zero), and `v = normal × u`, so that
/// `u × v` is the normal. `None` for a normal that is not finite.
pub fn plane_axes(normal: &Vec3) -> Option<[Vec3; 2]> {
    let helper = if normal.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
    let u = normal.cross(&helper).try_normalize(1e-12).filter(|u| u.iter().all(|c| c.is_finite()))?;
    Some([u, normal.cross(&u)])
}

/// The median absolute deviation of normally spread values over their
/// standard deviation: a median residual divided by it is a sigma that a
/// minority of outliers cannot widen.
pub const MAD_PER_SIGMA: f64 = 0.674_489_750_196_081_7;

/// The least and greatest of `values`, NaNs skipped (as `f64::min` and
/// `f64::max` skip them); `(∞, −∞)`, a range that holds nothing, when
/// there are none.
pub fn extent(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values.into_iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}

/// The turns [`outline_axis`] tries over a quarter turn: half a degree
/// apart, finer than a plate's edge is read to.
const OUTLINE_TURNS: usize = 180;

/// Of `points`, seen along `normal`, the direction across `normal` of one
/// side of the rectangle round them that covers the least area (None for
/// a normal that spans no plane or fewer than three points). A square or
/// nearly square plane's spread (its long axis) says nothing of where its
/// sides run; its outline does.
pub fn outline_axis(points: &[Vec3], normal: &Vec3) -> Option<Vec3> {
    let [a, b] = plane_axes(normal)?;
    if points.len() < 3 {
        return None;
    }
    let flat: Vec<(f64, f64)> = points.iter().map(|p| (a.dot(p), b.dot(p))).collect();
    let area = |turn: f64| {
        let (c, s) = (turn.cos(), turn.sin());
        let (lo_e, hi_e) = extent(flat.iter().map(|(x, y)| c * x + s * y));
        let (lo_u, hi_u) = extent(flat.iter().map(|(x, y)| c * y - s * x));
        (hi_e - lo_e) * (hi_u - lo_u)
    };
    let turn = (0..OUTLINE_TURNS)
        .map(|k| k as f64 * std::f64::consts::FRAC_PI_2 / OUTLINE_TURNS as f64)
        .min_by(|x, y| area(*x).total_cmp(&area(*y)))?;
    Some(a * turn.cos() + b * turn.sin())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_axes_span_the_plane_across_any_normal() {
        for normal in [Vec3::z(), Vec3::x(), -Vec3::y(), Vec3::new(0.95, 0.1, 0.3).normalize()] {
            let [u, v] = plane_axes(&normal).unwrap();
            assert!((u.norm() - 1.0).abs() < 1e-12 && (v.norm() - 1.0).abs() < 1e-12, "{normal:?}");
            assert!(u.dot(&normal).abs() < 1e-12 && v.dot(&normal).abs() < 1e-12 && u.dot(&v).abs() < 1e-12);
            assert!((u.cross(&v) - normal).norm() < 1e-12, "{normal:?}");
        }
        assert_eq!(plane_axes(&Vec3::new(f64::NAN, 0.0, 1.0)), None);
    }

    #[test]
    fn the_extent_of_values_skips_nans_and_of_none_holds_nothing() {
        assert_eq!(extent([3.0, -1.5, f64::NAN, 7.25, 0.0]), (-1.5, 7.25));
        let (lo, hi) = extent(std::iter::empty());
        assert!(lo > hi, "{lo} {hi}");
        assert_eq!(extent([f64::NAN]), (f64::INFINITY, f64::NEG_INFINITY));
    }

    #[test]
    fn fast_rounding_matches_the_standard_functions() {
        for x in [-3.5, -3.0, -2.9999, -2.5, -0.5, -0.4, -0.0, 0.0, 0.2, 0.5, 1.0, 1.0001, 2.5, 7.9999, 8.0, 1999.75] {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "ceil {x}");
            assert_eq!(round_i64(x), x.round() as i64, "round {x}");
        }
    }
}
