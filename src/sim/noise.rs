//! The sensor's imperfections, applied to a noise-free depth frame: depth
//! noise growing with distance, mixed pixels at depth edges, random
//! dropouts and sparse outliers.
//!
//! Each row draws from its own generator seeded by `(seed, row)`, so a
//! frame is the same bit for bit whatever the number of threads.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use rayon::prelude::*;

use super::InvalidScene;
use crate::camera::CameraModel;

/// The largest [`NoiseSpec::depth_noise_scale`]: ten times the camera's
/// sigma is already no structured-light camera's.
pub const MAX_DEPTH_NOISE_SCALE: f64 = 10.0;

/// How the simulated sensor degrades a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseSpec {
    /// Gaussian noise along each ray with the camera's depth sigma.
    pub depth_noise: bool,
    /// The depth sigma as a multiple of the camera's (1 for the camera as
    /// specified; the hard suite raises it).
    pub depth_noise_scale: f64,
    /// Fraction of valid pixels that lose their return.
    pub dropout_rate: f64,
    /// Chance that a pixel at a depth edge mixes with its neighbour.
    pub mixed_pixel_probability: f64,
    /// Depth step to a 4-neighbour above which a pixel is at an edge.
    pub mixed_pixel_jump_mm: f64,
    /// Fraction of valid pixels displaced along their ray.
    pub outlier_rate: f64,
    /// Outliers move uniformly within this distance either way.
    pub outlier_range_mm: f64,
    /// Returns whose surface is steeper than this to the camera ray or the
    /// projector ray are lost. A property of the sensor, not random, so
    /// [`NoiseSpec::none`] keeps it.
    pub max_incidence_deg: f64,
}

impl Default for NoiseSpec {
    /// A realistic industrial structured-light camera.
    fn default() -> Self {
        NoiseSpec {
            depth_noise: true,
            depth_noise_scale: 1.0,
            dropout_rate: 0.003,
            mixed_pixel_probability: 0.5,
            mixed_pixel_jump_mm: 2.0,
            outlier_rate: 1e-4,
            outlier_range_mm: 50.0,
            max_incidence_deg: 80.0,
        }
    }
}

impl NoiseSpec {
    /// No random effects: every return lies exactly on a surface.
    pub fn none() -> Self {
        NoiseSpec {
            depth_noise: false,
            dropout_rate: 0.0,
            mixed_pixel_probability: 0.0,
            outlier_rate: 0.0,
            ..NoiseSpec::default()
        }
    }

    pub fn validate(&self) -> Result<(), InvalidScene> {
        let rates = [
            ("dropout rate", self.dropout_rate),
            ("mixed pixel probability", self.mixed_pixel_probability),
            ("outlier rate", self.outlier_rate),
        ];
        for (name, rate) in rates {
            if !(0.0..=1.0).contains(&rate) {
                return Err(InvalidScene(format!("the {name} must be between 0 and 1")));
            }
        }
        if !(self.depth_noise_scale > 0.0 && self.depth_noise_scale <= MAX_DEPTH_NOISE_SCALE) {
            return Err(InvalidScene(format!(
                "the depth noise scale must be above 0 and at most {MAX_DEPTH_NOISE_SCALE}"
            )));
        }
        if !(self.mixed_pixel_jump_mm >= 0.0 && self.outlier_range_mm >= 0.0) {
            return Err(InvalidScene("the mixed pixel jump and the outlier range must not be negative".into()));
        }
        if !(self.max_incidence_deg > 0.0 && self.max_incidence_deg <= 90.0) {
            return Err(InvalidScene("the maximum incidence must be between 0 and 90 degrees".into()));
        }
        Ok(())
    }
}

/// Applies `spec` to the noise-free depths (row-major, NaN = no return).
pub fn degrade(exact: &[f64], camera: &CameraModel, spec: &NoiseSpec, seed: u64) -> Vec<f64> {
    let width = (camera.width_px as usize).max(1);
    let mut out = exact.to_vec();
    out.par_chunks_mut(width).enumerate().for_each(|(row, out_row)| {
        let mut random = RowRandom::new(seed, row);
        for (col, depth) in out_row.iter_mut().enumerate() {
            *depth = degrade_pixel(exact, width, col, row, camera, spec, &mut random);
        }
    });
    out
}

/// One row's random numbers: its own stream of the seeded generator (also
/// the crate's unit tests' seeded draws).
pub(crate) struct RowRandom {
    rng: ChaCha8Rng,
    /// Box-Muller yields normals in pairs; the second waits here.
    spare_normal: Option<f64>,
}

impl RowRandom {
    pub(crate) fn new(seed: u64, row: usize) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(row as u64);
        RowRandom { rng, spare_normal: None }
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal.
    pub(crate) fn gaussian(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        let radius = (-2.0 * (1.0 - self.uniform()).ln()).sqrt();
        let (sin, cos) = (std::f64::consts::TAU * self.uniform()).sin_cos();
        self.spare_normal = Some(radius * sin);
        radius * cos
    }
}

fn degrade_pixel(
    exact: &[f64],
    width: usize,
    col: usize,
    row: usize,
    camera: &CameraModel,
    spec: &NoiseSpec,
    random: &mut RowRandom,
) -> f64 {
    let mut z = exact[row * width + col];
    if !z.is_finite() {
        return f64::NAN;
    }
    if let Some(other) = steepest_neighbour(exact, width, col, row, spec.mixed_pixel_jump_mm)
        && random.uniform() < spec.mixed_pixel_probability
    {
        // The pixel's footprint straddles the edge: the sensor reports a
        // blend of both depths along the pixel's own ray.
        z += random.uniform() * (other - z);
    }
    // Noise is specified along the ray; z moves by that over the ray's
    // length per unit depth.
    let [rx, ry, _] = camera.ray(col as f64, row as f64);
    let z_per_mm = 1.0 / (1.0 + rx * rx + ry * ry).sqrt();
    if spec.depth_noise {
        // Scaled before the obliquity, so a scale of 1 gives the camera's
        // frame bit for bit.
        z += random.gaussian() * camera.depth_sigma(z) * spec.depth_noise_scale * z_per_mm;
    }
    // One draw decides between a dropout, an outlier and a normal return.
    let fate = random.uniform();
    if fate < spec.dropout_rate {
        return f64::NAN;
    }
    if fate < spec.dropout_rate + spec.outlier_rate {
        z += (2.0 * random.uniform() - 1.0) * spec.outlier_range_mm * z_per_mm;
    }
    if z > 0.0 { z } else { f64::NAN }
}

/// The valid 4-neighbour depth differing most from this pixel's, if the
/// step exceeds `jump`.
fn steepest_neighbour(exact: &[f64], width: usize, col: usize, row: usize, jump: f64) -> Option<f64> {
    let height = exact.len() / width;
    let z = exact[row * width + col];
    let neighbours = [
        (col > 0).then(|| exact[row * width + col - 1]),
        (col + 1 < width).then(|| exact[row * width + col + 1]),
        (row > 0).then(|| exact[(row - 1) * width + col]),
        (row + 1 < height).then(|| exact[(row + 1) * width + col]),
    ];
    neighbours
        .into_iter()
        .flatten()
        .filter(|n| n.is_finite() && (n - z).abs() > jump)
        .max_by(|a, b| (a - z).abs().total_cmp(&(b - z).abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(width_px: u32, height_px: u32) -> CameraModel {
        CameraModel { width_px, height_px, ..CameraModel::default() }
    }

    #[test]
    fn no_noise_changes_nothing() {
        let cam = camera(8, 4);
        let exact: Vec<f64> = (0..32).map(|i| if i % 5 == 0 { f64::NAN } else { 500.0 + i as f64 * 3.0 }).collect();
        let out = degrade(&exact, &cam, &NoiseSpec::none(), 7);
        for (a, b) in exact.iter().zip(&out) {
            assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()));
        }
    }

    #[test]
    fn depth_noise_has_the_cameras_sigma() {
        let cam = camera(200, 200);
        let exact = vec![1000.0; 200 * 200];
        let spec = NoiseSpec { dropout_rate: 0.0, outlier_rate: 0.0, ..NoiseSpec::default() };
        let out = degrade(&exact, &cam, &spec, 3);
        // Sigma is 0.1 mm along each ray at 1000 mm; in depth it shrinks
        // with the ray's obliquity, so compare each pixel with its own.
        let standardised: Vec<f64> = out
            .iter()
            .enumerate()
            .map(|(i, z)| {
                let [rx, ry, _] = cam.ray((i % 200) as f64, (i / 200) as f64);
                (z - 1000.0) * (1.0 + rx * rx + ry * ry).sqrt() / 0.1
            })
            .collect();
        let n = standardised.len() as f64;
        let mean = standardised.iter().sum::<f64>() / n;
        let sd = (standardised.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((sd - 1.0).abs() < 0.015, "sd {sd}");
    }

    #[test]
    fn dropouts_and_outliers_occur_at_their_rates() {
        let cam = camera(500, 400);
        let exact = vec![800.0; 500 * 400];
        let spec = NoiseSpec { depth_noise: false, dropout_rate: 0.01, outlier_rate: 0.01, ..NoiseSpec::default() };
        let out = degrade(&exact, &cam, &spec, 11);
        let n = out.len() as f64;
        let dropped = out.iter().filter(|z| z.is_nan()).count() as f64 / n;
        let moved = out.iter().filter(|z| (**z - 800.0).abs() > 1e-9).count() as f64 / n;
        assert!((dropped - 0.01).abs() < 0.002, "{dropped}");
        assert!((moved - 0.01).abs() < 0.002, "{moved}");
        assert!(out.iter().filter(|z| z.is_finite()).all(|z| (z - 800.0).abs() <= 50.0));
    }

    #[test]
    fn edge_pixels_mix_with_their_neighbour() {
        let cam = camera(400, 300);
        // A depth step between columns 199 and 200.
        let exact: Vec<f64> = (0..400 * 300).map(|i| if i % 400 < 200 { 700.0 } else { 740.0 }).collect();
        let spec = NoiseSpec { mixed_pixel_probability: 0.5, ..NoiseSpec::none() };
        let out = degrade(&exact, &cam, &spec, 5);
        let mixed = out.iter().zip(&exact).filter(|(o, e)| (*o - *e).abs() > 1e-9).count();
        // Two edge columns of 300 rows, half of them mixed.
        assert!((250..=350).contains(&mixed), "{mixed}");
        for (i, z) in out.iter().enumerate() {
            let col = i % 400;
            if col != 199 && col != 200 {
                assert_eq!(*z, exact[i]);
            } else {
                assert!((700.0..=740.0).contains(z));
            }
        }
    }
}
