//! The `[camera]` section's checks, which build the camera model from
//! the file.

use crate::camera::{CameraModel, Distortion, Intrinsics};

use super::{ConfigError, MAX_CAMERA_MM, MAX_SENSOR_PX, MIN_LENGTH_MM, check, file, in_range};

// Every number has a floor and a ceiling: a value outside them is a typo
// or a unit mix-up, and an unbounded one (a billion RANSAC iterations, a
// tolerance of 1e-30 mm) would hang or silently break the planner rather
// than fail at start.

/// How far the configured intrinsics and field of view may disagree, as a
/// fraction of the focal length, when both are given: the two forms are
/// the same numbers written twice, so anything beyond rounding in the
/// datasheet (a few parts in ten thousand) is a typo or two cameras' values.
const INTRINSICS_AGREEMENT: f64 = 1e-3;

/// The largest lens distortion coefficient, in magnitude: measurement
/// cameras' are below 1, fisheyes' a few; beyond 10 the model is not
/// Brown-Conrady's any more.
const MAX_DISTORTION: f64 = 10.0;

impl file::CameraSection {
    /// Checks the `[camera]` section and builds the camera model: the field
    /// of view or the intrinsics (all four), or both when they agree.
    pub fn validate(&self) -> Result<CameraModel, ConfigError> {
        let c = self;
        // A sensor of 32768 pixels a side is beyond any camera; the tile
        // keys of the full-plane counts hold 16-bit tile indices.
        for (key, px) in [("camera.width_px", c.width_px), ("camera.height_px", c.height_px)] {
            check(key, (1..=MAX_SENSOR_PX).contains(&px), || format!("must lie in [1, {MAX_SENSOR_PX}], got {px}"))?;
        }
        in_range("camera.fov_distance_mm", c.fov_distance_mm, MIN_LENGTH_MM, MAX_CAMERA_MM)?;
        let (w, h) = (f64::from(c.width_px), f64::from(c.height_px));
        // Focal lengths from a tenth of the sensor (a 157° view) to a
        // thousand times it; the principal point within a sensor's width
        // of the sensor.
        let given = [("camera.fx", c.fx), ("camera.fy", c.fy), ("camera.cx", c.cx), ("camera.cy", c.cy)];
        let intrinsics = match (c.fx, c.fy, c.cx, c.cy) {
            (Some(fx), Some(fy), Some(cx), Some(cy)) => {
                in_range("camera.fx", fx, 0.1 * w, 1000.0 * w)?;
                in_range("camera.fy", fy, 0.1 * h, 1000.0 * h)?;
                in_range("camera.cx", cx, -w, 2.0 * w)?;
                in_range("camera.cy", cy, -h, 2.0 * h)?;
                Some(Intrinsics { fx, fy, cx, cy })
            }
            (None, None, None, None) => None,
            _ => {
                let (set, unset): (Vec<&(&'static str, Option<f64>)>, Vec<_>) =
                    given.iter().partition(|(_, v)| v.is_some());
                let names = |keys: &[&(&'static str, Option<f64>)]| {
                    keys.iter().map(|(k, _)| k.trim_start_matches("camera.")).collect::<Vec<_>>().join(", ")
                };
                return Err(ConfigError::Invalid {
                    key: unset[0].0,
                    message: format!(
                        "the intrinsics need all of fx, fy, cx and cy; {} given but not {}",
                        names(&set),
                        names(&unset)
                    ),
                });
            }
        };
        // Each side of the field of view: as given (and then held to agree
        // with the intrinsics, if any), else implied by the intrinsics,
        // else the paper's.
        let paper = CameraModel::default();
        let sides = [
            ("camera.fov_width_mm", c.fov_width_mm, w, intrinsics.map(|i| i.fx), paper.fov_width_mm),
            ("camera.fov_height_mm", c.fov_height_mm, h, intrinsics.map(|i| i.fy), paper.fov_height_mm),
        ];
        let mut fov = [0.0; 2];
        for (side, (key, given, px, focal, default)) in fov.iter_mut().zip(sides) {
            *side = match (given, focal) {
                (Some(mm), focal) => {
                    in_range(key, mm, MIN_LENGTH_MM, MAX_CAMERA_MM)?;
                    if let Some(f) = focal {
                        let implied = px * c.fov_distance_mm / mm;
                        let focal_key = if key.ends_with("width_mm") { "camera.fx" } else { "camera.fy" };
                        check(focal_key, ((implied - f) / f).abs() <= INTRINSICS_AGREEMENT, || {
                            format!(
                                "{f} px disagrees with {key} ({mm} mm), which implies {implied:.3} px; \
                                 must agree within {}%: give the intrinsics or the field of view, not both",
                                INTRINSICS_AGREEMENT * 100.0
                            )
                        })?;
                    }
                    mm
                }
                (None, Some(f)) => px * c.fov_distance_mm / f,
                (None, None) => default,
            };
        }
        let [fov_width_mm, fov_height_mm] = fov;
        in_range("camera.baseline_mm", c.baseline_mm, 0.0, 10_000.0)?;
        in_range("camera.nominal_accuracy_mm", c.nominal_accuracy_mm, 1e-6, 100.0)?;
        in_range("camera.min_depth_mm", c.min_depth_mm, 1.0, c.fov_distance_mm)?;
        in_range("camera.max_depth_mm", c.max_depth_mm, c.fov_distance_mm, MAX_CAMERA_MM)?;
        // Up to 89°: the off-axis limit bounds every coordinate by a
        // multiple of the depth, which a limit of 90° would not.
        in_range("camera.max_off_axis_deg", c.max_off_axis_deg, 1.0, 89.0)?;
        in_range("camera.fov_margin_px", c.fov_margin_px, 0.0, f64::from(MAX_SENSOR_PX))?;
        for (key, k) in
            [("camera.k1", c.k1), ("camera.k2", c.k2), ("camera.p1", c.p1), ("camera.p2", c.p2), ("camera.k3", c.k3)]
        {
            in_range(key, k, -MAX_DISTORTION, MAX_DISTORTION)?;
        }
        Ok(CameraModel {
            width_px: c.width_px,
            height_px: c.height_px,
            fov_width_mm,
            fov_height_mm,
            fov_distance_mm: c.fov_distance_mm,
            baseline_mm: c.baseline_mm,
            nominal_accuracy_mm: c.nominal_accuracy_mm,
            min_depth_mm: c.min_depth_mm,
            max_depth_mm: c.max_depth_mm,
            max_off_axis_deg: c.max_off_axis_deg,
            fov_margin_px: c.fov_margin_px,
            intrinsics,
            distortion: Distortion { k1: c.k1, k2: c.k2, p1: c.p1, p2: c.p2, k3: c.k3 },
        })
    }
}
