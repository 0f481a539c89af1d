//! The flange's plane where a face stands on it, rather than over the
//! whole flange.
//!
//! The flange's plane ([`super::frame::flange_plane`]) is fitted to all
//! its pieces, which is right for the plates the paper welds, flat to a
//! fraction of the camera's noise. A real flange is not that flat: a
//! beam's top, a block's face or a plate bent by its own cutting lies a
//! millimetre or more off one plane over its length, and a consumer depth
//! camera bends a flat surface by as much over its field of view. The root
//! lies where the face meets the flange *at the face*, and a plane fitted
//! over the whole flange, its centroid some hundred millimetres away,
//! places it off by the flange's tilt there times that distance (0.5° over
//! 170 mm is 1.5 mm, the public tube-on-beam scan `pc0002`'s second root).
//!
//! So the flange at the root is read from the flange's own points in a
//! band beside the face's foot, as wide as the band the root's stretch is
//! read from ([`super::face`]) but starting past the face's own scatter
//! across its plane (a depth camera blends face and flange into the
//! inside corner there), along the face's length. Across that band the
//! flange is seen over a few spacings only,
//! too narrow to tell its tilt across the root from its noise; along the
//! root it is seen over the face's whole length. The model is therefore
//! the flange's height over the whole flange's plane as a straight line
//! along the root, `h(t) = a + b·t`: its offset and its tilt along the root
//! are read where the face stands, its tilt across the root is the whole
//! flange's. Fitted by least squares and refitted without the points
//! further than `trim_sigma` standard deviations of the median residual
//! (a tack, spatter, the foot's mixed returns), as the face is.

use crate::geometry::Vec3;
use crate::geometry::fit::Plane;

use super::face::trimmed_fit;

/// The flange's height over a reference plane along the root: `a + b·t`
/// at `t` mm along it, from `points` samples (`rms_mm` about the line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct HeightLine {
    pub a: f64,
    pub b: f64,
    pub rms_mm: f64,
    pub points: usize,
    mean_t: f64,
    var_t: f64,
}

impl HeightLine {
    /// The least-squares line through `samples` (`(t, h)`), trimmed of
    /// the samples further than `trim_sigma` standard deviations (the
    /// median residual's) and never tighter than `floor_mm`; `None` with
    /// fewer than `min_points` samples or all of them at one `t`.
    pub(super) fn fit(samples: &[(f64, f64)], trim_sigma: f64, floor_mm: f64, min_points: usize) -> Option<HeightLine> {
        if samples.len() < min_points {
            return None;
        }
        trimmed_fit(
            samples,
            (trim_sigma, floor_mm),
            min_points,
            |kept| least_squares(&kept),
            |line, &(t, h)| (h - line.at(t)).abs(),
        )
    }

    /// The height at `t`.
    pub(super) fn at(&self, t: f64) -> f64 {
        self.a + self.b * t
    }

    /// The line's prediction error at `t`, one sigma.
    pub(super) fn sigma_at(&self, t: f64) -> f64 {
        let n = self.points.max(1) as f64;
        self.rms_mm * (1.0 / n + (t - self.mean_t).powi(2) / (n * self.var_t)).sqrt()
    }

    /// The plane on which the height over `reference` (`h(p) = d − n·p`,
    /// `n` into the workpiece) is this line along `r` from `origin`
    /// (`t = (p − origin)·r`), `r` lying in the reference plane.
    pub(super) fn plane(&self, reference: &Plane, origin: &Vec3, r: &Vec3) -> Plane {
        // d − n·p = a + b (p − o)·r  ⇔  (n + b r)·p = d − a + b o·r
        let normal = reference.normal + r * self.b;
        let length = normal.norm();
        Plane { normal: normal / length, offset: (reference.offset - self.a + self.b * origin.dot(r)) / length }
    }
}

/// The least-squares line through `samples`, `None` with fewer than two
/// or all at one `t`.
fn least_squares(samples: &[(f64, f64)]) -> Option<HeightLine> {
    let n = samples.len();
    if n < 2 {
        return None;
    }
    let mean_t = samples.iter().map(|s| s.0).sum::<f64>() / n as f64;
    let mean_h = samples.iter().map(|s| s.1).sum::<f64>() / n as f64;
    let stt: f64 = samples.iter().map(|&(t, _)| (t - mean_t).powi(2)).sum();
    let sth: f64 = samples.iter().map(|&(t, h)| (t - mean_t) * (h - mean_h)).sum();
    if stt <= 0.0 {
        return None;
    }
    let b = sth / stt;
    let a = mean_h - b * mean_t;
    let rms_mm = (samples.iter().map(|&(t, h)| (h - a - b * t).powi(2)).sum::<f64>() / n as f64).sqrt();
    Some(HeightLine { a, b, rms_mm, points: n, mean_t, var_t: stt / n as f64 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tilted_line_is_read_through_its_noise_and_its_outliers() {
        // 0.5° along the root, 1 mm high at t = 0, a tack 4 mm tall over
        // a tenth of it.
        let slope = 0.5f64.to_radians().tan();
        let samples: Vec<(f64, f64)> = (0..600)
            .map(|i| {
                let t = -75.0 + 0.25 * f64::from(i);
                let noise = 0.3 * ((f64::from(i) * 2.399).sin());
                let tack = if (20.0..35.0).contains(&t) { 4.0 } else { 0.0 };
                (t, 1.0 + slope * t + noise + tack)
            })
            .collect();
        let line = HeightLine::fit(&samples, 2.5, 0.05, 30).unwrap();
        assert!((line.a - 1.0).abs() < 0.05, "offset {}", line.a);
        assert!((line.b - slope).abs() < 0.001, "slope {} against {slope}", line.b);
        assert!(line.points < 560, "the tack is trimmed: {} kept", line.points);
        // Without the trim the tack pulls the line up.
        let plain = least_squares(&samples).unwrap();
        assert!((plain.a - 1.0).abs() > 0.2, "the untrimmed line {}", plain.a);
    }

    #[test]
    fn the_plane_holds_the_line_and_keeps_the_reference_tilt_across() {
        let reference = Plane { normal: Vec3::new(0.0, 0.0, 1.0), offset: 500.0 };
        let (origin, r) = (Vec3::new(10.0, 20.0, 498.0), Vec3::new(1.0, 0.0, 0.0));
        let line = HeightLine { a: 1.5, b: 0.01, rms_mm: 0.0, points: 100, mean_t: 0.0, var_t: 1.0 };
        let plane = line.plane(&reference, &origin, &r);
        for (t, across) in [(-80.0, 0.0), (0.0, 30.0), (60.0, -12.0)] {
            // The point at height a + b t over the reference, at t along r.
            let height = line.at(t);
            let p = Vec3::new(10.0 + t, 20.0 + across, 500.0 - height);
            assert!(plane.signed_distance(&p).abs() < 1e-9, "{t} {across}: {}", plane.signed_distance(&p));
        }
        assert!(plane.normal.y.abs() < 1e-12, "no tilt across the root: {:?}", plane.normal);
    }

    #[test]
    fn too_few_samples_or_one_station_read_no_line() {
        assert_eq!(HeightLine::fit(&[(0.0, 1.0), (1.0, 1.0)], 2.5, 0.05, 30), None);
        let one_station: Vec<(f64, f64)> = (0..50).map(|i| (3.0, f64::from(i))).collect();
        assert_eq!(HeightLine::fit(&one_station, 2.5, 0.05, 30), None);
    }
}
