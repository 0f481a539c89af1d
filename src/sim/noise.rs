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

/// How the simulated sensor degrades a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseSpec {
    /// Gaussian noise along each ray with the camera's depth sigma.
    pub depth_noise: bool,
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
        if !(self.mixed_pixel_jump_mm >= 0.0 && self.outlier_range_mm >= 0.0) {
            return Err(InvalidScene(
                "the mixed pixel jump and the outlier range must not be negative".into(),
            ));
        }
        if !(self.max_incidence_deg > 0.0 && self.max_incidence_deg <= 90.0) {
            return Err(InvalidScene(
                "the maximum incidence must be between 0 and 90 degrees".into(),
            ));
        }
        Ok(())
    }
}

/// Applies `spec` to the noise-free depths (row-major, NaN = no return).
pub fn degrade(exact: &[f64], camera: &CameraModel, spec: &NoiseSpec, seed: u64) -> Vec<f64> {
    let width = (camera.width_px as usize).max(1);
    let mut out = exact.to_vec();
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, out_row)| {
            let mut rng = row_rng(seed, row);
            for (col, depth) in out_row.iter_mut().enumerate() {
                *depth = degrade_pixel(exact, width, col, row, camera, spec, &mut rng);
            }
        });
    out
}

fn row_rng(seed: u64, row: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(row as u64);
    rng
}

fn degrade_pixel(
    exact: &[f64],
    width: usize,
    col: usize,
    row: usize,
    camera: &CameraModel,
    spec: &NoiseSpec,
    rng: &mut ChaCha8Rng,
) -> f64 {
    let mut z = exact[row * width + col];
    if !z.is_finite() {
        return f64::NAN;
    }
    if let Some(other) = steepest_neighbour(exact, width, col, row, spec.mixed_pixel_jump_mm)
        && uniform(rng) < spec.mixed_pixel_probability
    {
        // The pixel's footprint straddles the edge: the sensor reports a
        // blend of both depths along the pixel's own ray.
        z += uniform(rng) * (other - z);
    }
    // Noise is specified along the ray; z moves by that over the ray's
    // length per unit depth.
    let [rx, ry, _] = camera.ray(col as f64, row as f64);
    let z_per_mm = 1.0 / (1.0 + rx * rx + ry * ry).sqrt();
    if spec.depth_noise {
        z += gaussian(rng) * camera.depth_sigma(z) * z_per_mm;
    }
    if uniform(rng) < spec.dropout_rate {
        return f64::NAN;
    }
    if uniform(rng) < spec.outlier_rate {
        z += (2.0 * uniform(rng) - 1.0) * spec.outlier_range_mm * z_per_mm;
    }
    if z > 0.0 { z } else { f64::NAN }
}

/// The valid 4-neighbour depth differing most from this pixel's, if the
/// step exceeds `jump`.
fn steepest_neighbour(
    exact: &[f64],
    width: usize,
    col: usize,
    row: usize,
    jump: f64,
) -> Option<f64> {
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

/// Uniform in `[0, 1)` with 53 random bits.
fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Standard normal by Box-Muller.
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let radius = (-2.0 * (1.0 - uniform(rng)).ln()).sqrt();
    radius * (std::f64::consts::TAU * uniform(rng)).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(width_px: u32, height_px: u32) -> CameraModel {
        CameraModel {
            width_px,
            height_px,
            ..CameraModel::default()
        }
    }

    #[test]
    fn no_noise_changes_nothing() {
        let cam = camera(8, 4);
        let exact: Vec<f64> = (0..32)
            .map(|i| {
                if i % 5 == 0 {
                    f64::NAN
                } else {
                    500.0 + i as f64 * 3.0
                }
            })
            .collect();
        let out = degrade(&exact, &cam, &NoiseSpec::none(), 7);
        for (a, b) in exact.iter().zip(&out) {
            assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()));
        }
    }

    #[test]
    fn depth_noise_has_the_cameras_sigma() {
        let cam = camera(200, 200);
        let exact = vec![1000.0; 200 * 200];
        let spec = NoiseSpec {
            dropout_rate: 0.0,
            outlier_rate: 0.0,
            ..NoiseSpec::default()
        };
        let out = degrade(&exact, &cam, &spec, 3);
        let n = out.len() as f64;
        let mean = out.iter().sum::<f64>() / n;
        let sd = (out.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / n).sqrt();
        // Near the axis the ray is almost along z, so sigma_z ≈ 0.1 mm.
        assert!((mean - 1000.0).abs() < 0.002, "mean {mean}");
        assert!((sd - 0.1).abs() < 0.003, "sd {sd}");
    }

    #[test]
    fn dropouts_and_outliers_occur_at_their_rates() {
        let cam = camera(500, 400);
        let exact = vec![800.0; 500 * 400];
        let spec = NoiseSpec {
            depth_noise: false,
            dropout_rate: 0.01,
            outlier_rate: 0.01,
            ..NoiseSpec::default()
        };
        let out = degrade(&exact, &cam, &spec, 11);
        let n = out.len() as f64;
        let dropped = out.iter().filter(|z| z.is_nan()).count() as f64 / n;
        let moved = out.iter().filter(|z| (**z - 800.0).abs() > 1e-9).count() as f64 / n;
        assert!((dropped - 0.01).abs() < 0.002, "{dropped}");
        assert!((moved - 0.01).abs() < 0.002, "{moved}");
        assert!(
            out.iter()
                .filter(|z| z.is_finite())
                .all(|z| (z - 800.0).abs() <= 50.0)
        );
    }

    #[test]
    fn edge_pixels_mix_with_their_neighbour() {
        let cam = camera(400, 300);
        // A depth step between columns 199 and 200.
        let exact: Vec<f64> = (0..400 * 300)
            .map(|i| if i % 400 < 200 { 700.0 } else { 740.0 })
            .collect();
        let spec = NoiseSpec {
            mixed_pixel_probability: 0.5,
            ..NoiseSpec::none()
        };
        let out = degrade(&exact, &cam, &spec, 5);
        let mixed = out
            .iter()
            .zip(&exact)
            .filter(|(o, e)| (*o - *e).abs() > 1e-9)
            .count();
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
