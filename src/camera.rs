//! The area-array structured-light camera: its pinhole model and the
//! paper's "plane point cloud density" (section 3.1 and 3.2).
//!
//! The paper describes the camera by its resolution and one field of view
//! (Table 1: 1920 x 1200 px, 700 x 440 mm at 1000 mm). From those follow the
//! focal lengths in pixels, so the same numbers give both the paper's
//! density formula (Eq. 4) and an exact pinhole model that the simulator and
//! the tilt-aware criteria use.
//!
//! A camera may instead be described as its calibration reports it: focal
//! lengths and principal point in pixels, and Brown-Conrady lens
//! distortion. Both forms map to the one pinhole model here
//! ([`CameraModel::fx`] and friends), plus the distortion applied in
//! [`CameraModel::project`] and undone in [`CameraModel::ray`].
//! [`estimate_intrinsics`] recovers the pinhole from an organized frame.

use rayon::prelude::*;

use crate::cloud::PointCloud;
use crate::geometry::Vec3;

/// Focal lengths and principal point, pixels, as a calibration reports
/// them (the config's `fx`, `fy`, `cx`, `cy`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

/// Brown-Conrady lens distortion on normalised image coordinates: radial
/// `k1, k2, k3`, tangential `p1, p2` (the OpenCV order and convention).
/// All zero is a pinhole.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Distortion {
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
    pub k3: f64,
}

/// The most fixed-point steps [`CameraModel::ray`] takes to
/// undo the distortion: measurement lenses converge to well under a
/// thousandth of a pixel in a handful, and the bound keeps a wild
/// calibration from looping.
const UNDISTORT_ITERATIONS: usize = 20;

/// The change, in normalised coordinates, below which the undistortion has
/// converged: about a millionth of a pixel at any focal length a camera has.
const UNDISTORT_CONVERGED: f64 = 1e-12;

impl Distortion {
    /// True for a pinhole (every coefficient zero).
    pub fn is_none(&self) -> bool {
        *self == Distortion::default()
    }

    /// Distorts normalised coordinates `(x, y) = (X/Z, Y/Z)`.
    pub fn apply(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        let xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
        let yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
        (xd, yd)
    }

    /// Undoes [`Distortion::apply`] by fixed-point iteration (bounded by
    /// [`UNDISTORT_ITERATIONS`]), the usual inverse for small distortion.
    pub fn remove(&self, xd: f64, yd: f64) -> (f64, f64) {
        let (mut x, mut y) = (xd, yd);
        for _ in 0..UNDISTORT_ITERATIONS {
            let (fx, fy) = self.apply(x, y);
            let (nx, ny) = (x - (fx - xd), y - (fy - yd));
            let step = (nx - x).abs().max((ny - y).abs());
            (x, y) = (nx, ny);
            if step.is_nan() || step <= UNDISTORT_CONVERGED {
                break;
            }
        }
        (x, y)
    }

    /// An upper bound of how much the distortion can stretch a small step
    /// near normalised radius `r`, along either image axis: the row sums
    /// of its Jacobian, bounded term by term with absolute values.
    fn stretch(&self, r: f64) -> f64 {
        let r2 = r * r;
        // |radial| + |x d(radial)/dx| + |x d(radial)/dy| for each power.
        let radial = 5.0 * self.k1.abs() * r2 + 9.0 * self.k2.abs() * r2 * r2 + 13.0 * self.k3.abs() * r2 * r2 * r2;
        1.0 + radial + 8.0 * (self.p1.abs() + self.p2.abs()) * r
    }
}

/// The camera model: resolution, field of view (or the intrinsics it
/// implies), distortion, and the measurable range. The config's
/// `[camera]` section builds it (`config::file::CameraSection`). Without
/// intrinsics the focal lengths are derived from the resolution and the
/// field of view (see [`CameraModel::fx`]), never stored, so they are
/// always consistent with them; with intrinsics, the field of view is the
/// one they imply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraModel {
    /// Sensor width in pixels (Table 1: 1920).
    pub width_px: u32,
    /// Sensor height in pixels (Table 1: 1200).
    pub height_px: u32,
    /// Field-of-view width `w1` at distance `l1`, mm (Table 1: 700).
    pub fov_width_mm: f64,
    /// Field-of-view height `h1` at distance `l1`, mm (Table 1: 440).
    pub fov_height_mm: f64,
    /// Distance `l1` at which the field of view is given, mm (Table 1: 1000).
    pub fov_distance_mm: f64,
    /// Camera-to-projector baseline along the camera x axis, mm (Table 1: 150).
    pub baseline_mm: f64,
    /// Nominal depth accuracy at `fov_distance_mm`, mm (Table 1: 0.1).
    pub nominal_accuracy_mm: f64,
    /// Nearest depth the camera can measure, mm. Nearer points are noise or
    /// a corrupt frame; the pipeline treats them as invalid, which also
    /// bounds every neighbour window (a point near the optical centre would
    /// otherwise need the whole image searched).
    pub min_depth_mm: f64,
    /// Farthest depth the camera can measure, mm. Farther points are a
    /// corrupt frame's (a shifted byte makes a depth of 1e30 as easily as
    /// one of 600) and are treated as invalid.
    pub max_depth_mm: f64,
    /// Widest angle off the optical axis, along either image axis, at
    /// which the camera can see a point, degrees. It holds for any cloud
    /// in the camera frame, whatever camera took it, so it is set wider
    /// than any structured-light camera's field of view: it only bounds
    /// coordinates, which with the depth range bounds every point's
    /// neighbour window.
    pub max_off_axis_deg: f64,
    /// How far outside the sensor, in pixels, a point of an organized
    /// frame of this camera's size may project (lens distortion and
    /// calibration move points a little off the pinhole's rays). Frames
    /// of any other size (crops, other cameras) are not held to it.
    pub fov_margin_px: f64,
    /// The calibration's focal lengths and principal point, when the
    /// config gives them; `None` derives them from the field of view.
    pub intrinsics: Option<Intrinsics>,
    /// Lens distortion; all zero (the default) is a pinhole.
    pub distortion: Distortion,
}

impl Default for CameraModel {
    /// The paper's camera, Table 1.
    fn default() -> Self {
        CameraModel {
            width_px: 1920,
            height_px: 1200,
            fov_width_mm: 700.0,
            fov_height_mm: 440.0,
            fov_distance_mm: 1000.0,
            baseline_mm: 150.0,
            nominal_accuracy_mm: 0.1,
            min_depth_mm: 100.0,
            max_depth_mm: 3000.0,
            max_off_axis_deg: 80.0,
            fov_margin_px: 200.0,
            intrinsics: None,
            distortion: Distortion::default(),
        }
    }
}

/// The cap of [`CameraModel::neighbour_window`]'s half-sizes: wider than
/// any sensor, and far from where pixel arithmetic could overflow.
const MAX_WINDOW_PX: usize = 1 << 30;

impl CameraModel {
    /// Focal length along x, in pixels: the calibration's, else `W px`
    /// spread over `w1` mm at `l1`.
    pub fn fx(&self) -> f64 {
        match self.intrinsics {
            Some(i) => i.fx,
            None => self.width_px as f64 * self.fov_distance_mm / self.fov_width_mm,
        }
    }

    /// Focal length along y, in pixels.
    pub fn fy(&self) -> f64 {
        match self.intrinsics {
            Some(i) => i.fy,
            None => self.height_px as f64 * self.fov_distance_mm / self.fov_height_mm,
        }
    }

    /// Principal point x, pixels: the calibration's, else the sensor centre.
    pub fn cx(&self) -> f64 {
        match self.intrinsics {
            Some(i) => i.cx,
            None => (self.width_px as f64 - 1.0) / 2.0,
        }
    }

    /// Principal point y, pixels.
    pub fn cy(&self) -> f64 {
        match self.intrinsics {
            Some(i) => i.cy,
            None => (self.height_px as f64 - 1.0) / 2.0,
        }
    }

    /// The pinhole this model amounts to, whichever form configured it.
    pub fn pinhole(&self) -> Intrinsics {
        Intrinsics { fx: self.fx(), fy: self.fy(), cx: self.cx(), cy: self.cy() }
    }

    /// The same camera with another sensor size and pinhole (an organized
    /// frame's estimate), the field of view being the one they imply at
    /// the same `fov_distance_mm`; depth range, accuracy and distortion
    /// kept.
    pub fn with_pinhole(&self, width_px: u32, height_px: u32, pinhole: Intrinsics) -> CameraModel {
        CameraModel {
            width_px,
            height_px,
            fov_width_mm: width_px as f64 * self.fov_distance_mm / pinhole.fx,
            fov_height_mm: height_px as f64 * self.fov_distance_mm / pinhole.fy,
            intrinsics: Some(pinhole),
            ..*self
        }
    }

    /// Resolution `F` in pixels.
    pub fn resolution(&self) -> f64 {
        self.width_px as f64 * self.height_px as f64
    }

    /// Plane point cloud density at distance `L`, points per mm², for a
    /// plane square to the optical axis (Eq. 4): `D = F l1² / (w1 h1 L²)`.
    pub fn density(&self, distance_mm: f64) -> f64 {
        self.resolution() * self.fov_distance_mm * self.fov_distance_mm
            / (self.fov_width_mm * self.fov_height_mm * distance_mm * distance_mm)
    }

    /// Theoretical neighbour count within radius `R` (Eq. 6): `N = π R² D`.
    pub fn theoretical_neighbours(&self, radius_mm: f64, distance_mm: f64) -> f64 {
        std::f64::consts::PI * radius_mm * radius_mm * self.density(distance_mm)
    }

    /// The neighbour count corrected for a radius measurement error `e`
    /// (Eq. 12): `N' = π (R + e)² D`. Eq. 13's bounds are `e = ∓ accuracy`.
    pub fn corrected_neighbours(&self, radius_mm: f64, error_mm: f64, distance_mm: f64) -> f64 {
        let r = radius_mm + error_mm;
        std::f64::consts::PI * r * r * self.density(distance_mm)
    }

    /// `N'min` of Eq. 13, the paper's plane point threshold (Eq. 14).
    pub fn min_plane_neighbours(&self, radius_mm: f64, distance_mm: f64) -> f64 {
        self.corrected_neighbours(radius_mm, -self.nominal_accuracy_mm, distance_mm)
    }

    /// Density of points on a plane through `p` with unit normal `n`, as a
    /// pinhole sensor samples it. The pixel footprint on the plane grows
    /// with `z³ / |n·p|`, so `D = fx fy |n·p| / z³`; for a frontal plane
    /// (`n = z`) this is exactly Eq. 4, and a plate tilted by θ shows
    /// about `cos θ` of it, the foreshortening Eq. 4 leaves out.
    pub fn plane_density_at(&self, p: &Vec3, n: &Vec3) -> f64 {
        // Summed in this order on purpose: plans are compared digit for
        // digit, and a dot product may add the terms in another.
        let n_dot_p = (n.x * p.x + n.y * p.y + n.z * p.z).abs();
        self.fx() * self.fy() * n_dot_p / (p.z * p.z * p.z)
    }

    /// The largest pixel offset, along each image axis, at which a point
    /// within `radius_mm` of `p` can appear. A ball of radius R at depth z
    /// projects within `f R sqrt(1 + t²) / (z - R)` pixels, where `t` is the
    /// tangent of the ray's angle off the axis, so scanning that window
    /// finds every 3D neighbour: it is exact, not an approximation.
    ///
    /// With lens distortion the pixel grid is the distorted image's, so
    /// the window is widened by a bound of how much the distortion can
    /// stretch a step near `p` ([`Distortion`]'s Jacobian, term by term in
    /// absolute value). That keeps it conservative; the rest of the
    /// pipeline reads pixels as a pinhole within a window of a few pixels,
    /// which holds for the small distortion of measurement cameras (a
    /// fraction of a percent of stretch across such a window).
    pub fn neighbour_window(&self, p: [f32; 3], radius_mm: f64) -> (usize, usize) {
        let z = p[2] as f64;
        if z <= radius_mm * 1.001 {
            // Closer than R to the optical centre: every pixel may hold a
            // neighbour. Never happens inside a camera's working range.
            return (self.width_px as usize, self.height_px as usize);
        }
        let tx = p[0] as f64 / z;
        let ty = p[1] as f64 / z;
        let reach = radius_mm / (z - radius_mm);
        let (wx, wy) = if self.distortion.is_none() {
            (self.fx() * reach * (1.0 + tx * tx).sqrt(), self.fy() * reach * (1.0 + ty * ty).sqrt())
        } else {
            // A step along one axis moves the distorted image along both,
            // so both axes take the wider angle's reach, times the most
            // the distortion stretches anywhere the ball can project.
            let t_max = tx.abs().max(ty.abs());
            let undistorted = reach * (1.0 + t_max * t_max).sqrt();
            let r_max = (tx * tx + ty * ty).sqrt() + std::f64::consts::SQRT_2 * undistorted;
            let reach_any = undistorted * self.distortion.stretch(r_max);
            (self.fx() * reach_any, self.fy() * reach_any)
        };
        // A point absurdly far off the axis (a corrupt frame's, say) would
        // need a window past what converts to an integer; capped, it
        // still covers any image, which every scan clips to.
        let half = |w: f64| {
            if w >= MAX_WINDOW_PX as f64 { MAX_WINDOW_PX } else { crate::geometry::ceil_i64(w).max(0) as usize }
        };
        (half(wx), half(wy))
    }

    /// The region of camera-frame space this camera can measure, for
    /// testing points of a `width x height` cloud (organized or not).
    pub fn measurable_volume(&self, width: usize, height: usize, organized: bool) -> MeasurableVolume {
        let off_axis = self.max_off_axis_deg.to_radians().tan();
        let mut tangents = [-off_axis, off_axis, -off_axis, off_axis];
        let own_grid = organized && (width, height) == (self.width_px as usize, self.height_px as usize);
        if own_grid {
            // The pixel grid is this camera's: every point lies on the ray
            // of a pixel of the sensor, give or take the margin.
            let m = self.fov_margin_px;
            let (u_max, v_max) = (self.width_px as f64 - 1.0 + m, self.height_px as f64 - 1.0 + m);
            let view = [(-m - self.cx()) / self.fx(), (u_max - self.cx()) / self.fx()];
            let view_v = [(-m - self.cy()) / self.fy(), (v_max - self.cy()) / self.fy()];
            tangents = [
                tangents[0].max(view[0]),
                tangents[1].min(view[1]),
                tangents[2].max(view_v[0]),
                tangents[3].min(view_v[1]),
            ];
        }
        MeasurableVolume {
            min_depth: self.min_depth_mm as f32,
            max_depth: self.max_depth_mm as f32,
            tangents: tangents.map(|t| t as f32),
            fov_applies: own_grid,
        }
    }

    /// Projects a camera-frame point to pixel coordinates `(u, v)`,
    /// through the lens distortion when there is one.
    pub fn project(&self, p: &Vec3) -> Option<(f64, f64)> {
        if p.z <= 0.0 {
            return None;
        }
        if self.distortion.is_none() {
            return Some((self.fx() * p.x / p.z + self.cx(), self.fy() * p.y / p.z + self.cy()));
        }
        let (xd, yd) = self.distortion.apply(p.x / p.z, p.y / p.z);
        Some((self.fx() * xd + self.cx(), self.fy() * yd + self.cy()))
    }

    /// The ray through pixel `(u, v)`, scaled so its z component is 1:
    /// the inverse of [`CameraModel::project`], the distortion undone
    /// iteratively.
    pub fn ray(&self, u: f64, v: f64) -> [f64; 3] {
        let (xd, yd) = ((u - self.cx()) / self.fx(), (v - self.cy()) / self.fy());
        if self.distortion.is_none() {
            return [xd, yd, 1.0];
        }
        let (x, y) = self.distortion.remove(xd, yd);
        [x, y, 1.0]
    }

    /// The distance between neighbouring pixels' points on a surface facing
    /// the camera at `p`, mm: the spacing of this camera's raw frames there.
    pub fn pixel_footprint_at(&self, p: &Vec3) -> f64 {
        p.z.abs() / self.fx().min(self.fy())
    }

    /// Depth noise (one sigma, along the ray) at depth `z`: structured
    /// light triangulation error grows with z², anchored at the nominal
    /// accuracy at `fov_distance_mm`.
    pub fn depth_sigma(&self, z_mm: f64) -> f64 {
        let s = z_mm / self.fov_distance_mm;
        self.nominal_accuracy_mm * s * s
    }
}

/// The most points [`estimate_intrinsics`] fits: a regular subsample of
/// this many pins a line down to far below a thousandth of a pixel, and
/// keeps the estimate's cost a millisecond whatever the frame's size.
const ESTIMATE_MAX_SAMPLES: usize = 1 << 16;

/// The fewest valid points an estimate is made from.
const ESTIMATE_MIN_POINTS: usize = 16;

/// An organized frame's pinhole, fitted from its own points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntrinsicsEstimate {
    pub intrinsics: Intrinsics,
    /// RMS of the column and row residuals of the two line fits, pixels:
    /// near zero for a pinhole frame, larger with lens distortion, a
    /// resampled grid or a cloud whose grid is not a camera's.
    pub rms_residual_px: [f64; 2],
    /// Points the fits used.
    pub points: usize,
}

/// Sums of one least-squares line `pixel = f * tangent + c`.
#[derive(Debug, Clone, Copy, Default)]
struct LineSums {
    n: f64,
    t: f64,
    p: f64,
    tt: f64,
    tp: f64,
    pp: f64,
}

impl LineSums {
    fn add(&mut self, tangent: f64, pixel: f64) {
        self.n += 1.0;
        self.t += tangent;
        self.p += pixel;
        self.tt += tangent * tangent;
        self.tp += tangent * pixel;
        self.pp += pixel * pixel;
    }

    fn merge(&mut self, o: &LineSums) {
        self.n += o.n;
        self.t += o.t;
        self.p += o.p;
        self.tt += o.tt;
        self.tp += o.tp;
        self.pp += o.pp;
    }

    /// Slope, intercept and RMS residual, if the tangents vary at all.
    fn fit(&self) -> Option<(f64, f64, f64)> {
        let n = self.n;
        let stt = self.tt - self.t * self.t / n;
        let stp = self.tp - self.t * self.p / n;
        let spp = self.pp - self.p * self.p / n;
        if stt.is_nan() || stt <= 0.0 {
            return None;
        }
        let slope = stp / stt;
        let intercept = (self.p - slope * self.t) / n;
        let rms = ((spp - slope * stp).max(0.0) / n).sqrt();
        (slope.is_finite() && intercept.is_finite()).then_some((slope, intercept, rms))
    }
}

/// Estimates the pinhole of an organized frame. In a pinhole frame the
/// point at pixel `(u, v)` lies on that pixel's ray, so `x/z = (u - cx)/fx`
/// and `y/z = (v - cy)/fy`: a least-squares line of the column against
/// `x/z` over the valid pixels gives `fx` and `cx` (its slope and
/// intercept), one of the row against `y/z` gives `fy` and `cy`, and their
/// residuals say how well a pinhole explains the frame. `None` for an
/// unorganized cloud or one with too few valid points off a single column
/// or row. Rows are summed in parallel and merged in row order, so the
/// estimate does not depend on the number of threads.
pub fn estimate_intrinsics(cloud: &PointCloud) -> Option<IntrinsicsEstimate> {
    if !cloud.is_organized() {
        return None;
    }
    let (width, height) = (cloud.width(), cloud.height());
    let stride = ((width * height) as f64 / ESTIMATE_MAX_SAMPLES as f64).sqrt().ceil().max(1.0) as usize;
    let rows: Vec<[LineSums; 2]> = (0..height)
        .into_par_iter()
        .step_by(stride)
        .map(|row| {
            let mut sums = [LineSums::default(); 2];
            for col in (0..width).step_by(stride) {
                if let Some(p) = cloud.at(col, row)
                    && p[2] > 0.0
                {
                    let z = p[2] as f64;
                    sums[0].add(p[0] as f64 / z, col as f64);
                    sums[1].add(p[1] as f64 / z, row as f64);
                }
            }
            sums
        })
        .collect();
    let mut total = [LineSums::default(); 2];
    for r in &rows {
        total[0].merge(&r[0]);
        total[1].merge(&r[1]);
    }
    if total[0].n < ESTIMATE_MIN_POINTS as f64 {
        return None;
    }
    let (fx, cx, rms_u) = total[0].fit()?;
    let (fy, cy, rms_v) = total[1].fit()?;
    Some(IntrinsicsEstimate {
        intrinsics: Intrinsics { fx, fy, cx, cy },
        rms_residual_px: [rms_u, rms_v],
        points: total[0].n as usize,
    })
}

/// What a camera can measure: a depth range and a pyramid of view
/// directions, as single-precision bounds tested on every point of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasurableVolume {
    min_depth: f32,
    max_depth: f32,
    /// The least and greatest `x / z`, then `y / z`.
    tangents: [f32; 4],
    /// True when the field of view of the camera's own pixel grid narrows
    /// the directions, false when only the off-axis limit does.
    fov_applies: bool,
}

/// Why a point lies outside what the camera can measure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unmeasurable {
    /// Nearer than `camera.min_depth_mm`, or behind the camera.
    Near,
    /// Farther than `camera.max_depth_mm`.
    Far,
    /// Outside the field of view, or farther off the axis than
    /// `camera.max_off_axis_deg`.
    OffView,
}

impl MeasurableVolume {
    /// `None` for a point the camera can measure (or an invalid one, NaN),
    /// else why not. Multiplications rather than divisions, and every
    /// comparison false on NaN, so a point of any magnitude is tested in
    /// a few instructions.
    #[inline]
    pub fn reject(&self, p: &[f32; 3]) -> Option<Unmeasurable> {
        let [x, y, z] = *p;
        if z.is_nan() {
            return None;
        }
        if z < self.min_depth {
            return Some(Unmeasurable::Near);
        }
        if z > self.max_depth {
            return Some(Unmeasurable::Far);
        }
        let [u_lo, u_hi, v_lo, v_hi] = self.tangents;
        let inside = x >= u_lo * z && x <= u_hi * z && y >= v_lo * z && y <= v_hi * z;
        (!inside).then_some(Unmeasurable::OffView)
    }

    /// True when every point the volume accepts lies in front of the
    /// camera and within the cone whose squared tangent is `max_tan_sq`
    /// of its axis, with a margin far beyond single-precision rounding:
    /// a test on every such point against that cone can then be skipped.
    pub fn inside_cone(&self, max_tan_sq: f64) -> bool {
        let [u_lo, u_hi, v_lo, v_hi] = self.tangents.map(f64::from);
        let corner_sq = u_lo.abs().max(u_hi.abs()).powi(2) + v_lo.abs().max(v_hi.abs()).powi(2);
        self.min_depth > 0.0 && corner_sq <= max_tan_sq * (1.0 - 1e-3)
    }

    /// True when the frame's directions are held to the camera's own
    /// field of view (an organized frame of its size).
    pub fn fov_applies(&self) -> bool {
        self.fov_applies
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn density_matches_the_papers_equation_5() {
        let cam = CameraModel::default();
        // Eq. 5: D = 2.304e9 / (308 L²)
        for l in [500.0, 750.0, 1000.0] {
            let expected = 2.304e9 / (308.0 * l * l);
            assert!((cam.density(l) - expected).abs() < 1e-9 * expected);
        }
    }

    #[test]
    fn neighbour_bounds_follow_equation_13() {
        let cam = CameraModel::default();
        let d = cam.density(500.0);
        let pi = std::f64::consts::PI;
        assert!((cam.min_plane_neighbours(1.0, 500.0) - pi * 0.81 * d).abs() < 1e-9);
        assert!((cam.corrected_neighbours(1.0, 0.1, 500.0) - pi * 1.21 * d).abs() < 1e-9);
        // E2 of Eq. 11 at L = 500, |e| = 0.1: the paper prints 19.74.
        let e2 = cam.corrected_neighbours(1.0, 0.1, 500.0) - cam.theoretical_neighbours(1.0, 500.0);
        assert!((e2 - 19.74).abs() < 0.01, "E2 = {e2}");
    }

    #[test]
    fn tilted_plane_density_is_foreshortened() {
        let cam = CameraModel::default();
        let frontal = cam.plane_density_at(&Vec3::new(0.0, 0.0, 800.0), &Vec3::z());
        let fx_fy = cam.fx() * cam.fy();
        assert!((frontal - fx_fy / (800.0 * 800.0)).abs() < 1e-9);
        let t = 30f64.to_radians();
        let tilted = cam.plane_density_at(&Vec3::new(0.0, 0.0, 800.0), &Vec3::new(t.sin(), 0.0, t.cos()));
        assert!((tilted / frontal - t.cos()).abs() < 1e-12);
    }

    #[test]
    fn projection_inverts_the_ray() {
        let cam = CameraModel::default();
        let r = cam.ray(100.0, 900.0);
        let (u, v) = cam.project(&Vec3::new(r[0] * 700.0, r[1] * 700.0, 700.0)).unwrap();
        assert!((u - 100.0).abs() < 1e-9 && (v - 900.0).abs() < 1e-9);
    }

    #[test]
    fn windows_of_absurd_points_are_capped_not_overflowed() {
        let cam = CameraModel::default();
        assert_eq!(cam.neighbour_window([1e30, -1e30, 150.0], 1.0), (MAX_WINDOW_PX, MAX_WINDOW_PX));
        assert_eq!(cam.neighbour_window([f32::MAX, 0.0, 101.5], 1.0).0, MAX_WINDOW_PX);
        // Such a point in a frame is counted over the whole image, which
        // holds no neighbour of it, without overflowing on the way.
        let mut pts = vec![[0.0f32, 0.0, 500.0]; 9];
        pts[4] = [1e30, 1e30, 150.0];
        let cloud = crate::cloud::PointCloud::organized(3, 3, pts).unwrap();
        let search = crate::pipeline::neighbours::NeighbourSearch::new(&cloud, &cam, 1.0);
        assert_eq!(search.count(4, |_| true), 1, "only itself");
    }

    #[test]
    fn the_measurable_volume_bounds_depth_and_direction() {
        let cam = CameraModel::default();
        let any = cam.measurable_volume(160, 140, true);
        assert!(!any.fov_applies());
        assert_eq!(any.reject(&[0.0, 0.0, 600.0]), None);
        assert_eq!(any.reject(&[f32::NAN, f32::NAN, f32::NAN]), None, "invalid points are not counted twice");
        assert_eq!(any.reject(&[0.0, 0.0, 99.0]), Some(Unmeasurable::Near));
        assert_eq!(any.reject(&[0.0, 0.0, -600.0]), Some(Unmeasurable::Near));
        assert_eq!(any.reject(&[0.0, 0.0, 1e30]), Some(Unmeasurable::Far));
        assert_eq!(any.reject(&[0.0, 0.0, f32::INFINITY]), Some(Unmeasurable::Far));
        assert_eq!(any.reject(&[-1e20, -1e20, 817.0]), Some(Unmeasurable::OffView));
        assert_eq!(any.reject(&[1.0, f32::INFINITY, 600.0]), Some(Unmeasurable::OffView));
        // 60° off the axis is outside this camera's view but inside any
        // camera's limit, so only a frame of the camera's own grid refuses it.
        let wide = [600.0 * 60f32.to_radians().tan(), 0.0, 600.0];
        assert_eq!(any.reject(&wide), None);
        let own = cam.measurable_volume(1920, 1200, true);
        assert!(own.fov_applies());
        assert_eq!(own.reject(&wide), Some(Unmeasurable::OffView));
        assert!(!cam.measurable_volume(1920, 1200, false).fov_applies(), "unorganized clouds have no grid");
        // Every pixel's ray, at any depth in range, is inside the view.
        for (u, v) in [(0.0, 0.0), (1919.0, 1199.0), (0.0, 1199.0), (1919.0, 0.0), (960.0, 600.0)] {
            let r = cam.ray(u, v);
            for z in [100.0, 1000.0, 3000.0] {
                let p = [(r[0] * z) as f32, (r[1] * z) as f32, z as f32];
                assert_eq!(own.reject(&p), None, "pixel ({u}, {v}) at {z} mm");
            }
        }
    }

    #[test]
    fn window_covers_the_ball() {
        let cam = CameraModel::default();
        let (wx, wy) = cam.neighbour_window([0.0, 0.0, 500.0], 1.0);
        // About 13 x 13 pixels at 500 mm, as a ball of 1 mm projects.
        assert!((5..=7).contains(&wx) && (5..=7).contains(&wy), "{wx} {wy}");
    }

    #[test]
    fn the_intrinsics_of_a_pinhole_frame_are_recovered() {
        let cam =
            CameraModel::default().with_pinhole(320, 240, Intrinsics { fx: 400.0, fy: 410.0, cx: 150.5, cy: 131.25 });
        let mut pts = Vec::new();
        for row in 0..240 {
            for col in 0..320 {
                let r = cam.ray(col as f64, row as f64);
                let z = 500.0 + 0.3 * col as f64 - 0.2 * row as f64;
                pts.push(if (row + col) % 7 == 0 { [f32::NAN; 3] } else { r.map(|c| (c * z) as f32) });
            }
        }
        let cloud = PointCloud::organized(320, 240, pts).unwrap();
        let est = estimate_intrinsics(&cloud).unwrap();
        let i = est.intrinsics;
        assert!((i.fx - 400.0).abs() < 1e-3 && (i.fy - 410.0).abs() < 1e-3, "{i:?}");
        assert!((i.cx - 150.5).abs() < 1e-3 && (i.cy - 131.25).abs() < 1e-3, "{i:?}");
        assert!(est.rms_residual_px.iter().all(|r| *r < 1e-3), "{est:?}");
        assert!(estimate_intrinsics(&PointCloud::unorganized(cloud.points().to_vec())).is_none());
    }

    #[test]
    fn distortion_round_trips_and_widens_the_window() {
        let pinhole = CameraModel::default();
        let cam = CameraModel {
            distortion: Distortion { k1: -0.12, k2: 0.08, p1: 0.001, p2: -0.0015, k3: -0.01 },
            ..pinhole
        };
        for (u, v) in [(0.0, 0.0), (1919.0, 1199.0), (100.0, 900.0), (959.5, 599.5)] {
            let r = cam.ray(u, v);
            let (pu, pv) = cam.project(&Vec3::new(r[0] * 700.0, r[1] * 700.0, 700.0)).unwrap();
            assert!((pu - u).abs() < 1e-6 && (pv - v).abs() < 1e-6, "({u}, {v}) -> ({pu}, {pv})");
        }
        // The window holds every pixel a ball of radius R around p reaches
        // (sampled on its surface), and is no narrower than the pinhole's.
        for p in [[0.0f32, 0.0, 500.0], [300.0, -180.0, 600.0], [-380.0, 250.0, 550.0]] {
            let (wx, wy) = cam.neighbour_window(p, 1.0);
            let (px, py) = pinhole.neighbour_window(p, 1.0);
            assert!(wx >= px && wy >= py);
            let c = Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let (u0, v0) = cam.project(&c).unwrap();
            for k in 0..400 {
                let (a, b) = (k as f64 * 0.618_034 * std::f64::consts::TAU, (k as f64 + 0.5) / 400.0);
                let z = 1.0 - 2.0 * b;
                let s = (1.0 - z * z).sqrt();
                let q = c + Vec3::new(s * a.cos(), s * a.sin(), z);
                let (u, v) = cam.project(&q).unwrap();
                assert!((u - u0).abs() <= wx as f64 && (v - v0).abs() <= wy as f64, "{p:?}: ({u}, {v})");
            }
        }
    }
}
