//! A region of interest: an axis-aligned box, in the camera frame or in
//! the robot base frame, checked once where it is given (the config, the
//! command line, a plan request) and read by the pipeline, which drops a
//! cloud's points outside it before any search (`pipeline::roi::crop`).
//! Plain data at the bottom of the crate, so the configuration can hold a
//! checked box without depending on the pipeline.

use std::fmt;

use nalgebra::Point3;

use super::Vec3;

/// The frame a cloud's coordinates are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CloudFrame {
    /// The camera's optical frame, as cameras deliver frames.
    #[default]
    Camera,
    /// The robot base frame, as tools that merge or register scans write
    /// them: brought into the camera frame with the request's pose and
    /// hand-eye before planning.
    Base,
}

/// The longest side a box may have, mm: ten metres holds any robot cell's
/// workpiece; more is a unit mix-up (metres for millimetres upside down).
pub const MAX_ROI_SIZE_MM: f64 = 10_000.0;

/// The farthest a box's corner may lie from its frame's origin, mm: the
/// ceiling of `robot.max_reach_mm`.
pub const MAX_ROI_COORDINATE_MM: f64 = 100_000.0;

const AXES: [&str; 3] = ["x", "y", "z"];

/// A checked box: finite, each min below its max, within the ceilings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roi {
    min: Vec3,
    max: Vec3,
    frame: CloudFrame,
}

/// Why a box is not one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RoiError {
    #[error("the box's {axis} bounds ({min}, {max}) must be finite numbers")]
    NotFinite { axis: &'static str, min: f64, max: f64 },
    #[error("the box's {axis} min ({min} mm) must be below its max ({max} mm)")]
    Empty { axis: &'static str, min: f64, max: f64 },
    #[error("the box's {axis} side is {size} mm; it must be at most {MAX_ROI_SIZE_MM} mm (are the values in mm?)")]
    TooLarge { axis: &'static str, size: f64 },
    #[error("the box's {axis} bound {value} mm must lie within ±{MAX_ROI_COORDINATE_MM} mm")]
    TooFar { axis: &'static str, value: f64 },
}

impl Roi {
    /// The box from `min` to `max` (mm) in `frame`, checked.
    pub fn new(min: [f64; 3], max: [f64; 3], frame: CloudFrame) -> Result<Roi, RoiError> {
        for (k, axis) in AXES.into_iter().enumerate() {
            let (lo, hi) = (min[k], max[k]);
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(RoiError::NotFinite { axis, min: lo, max: hi });
            }
            if let Some(value) = [lo, hi].into_iter().find(|v| v.abs() > MAX_ROI_COORDINATE_MM) {
                return Err(RoiError::TooFar { axis, value });
            }
            if lo >= hi {
                return Err(RoiError::Empty { axis, min: lo, max: hi });
            }
            if hi - lo > MAX_ROI_SIZE_MM {
                return Err(RoiError::TooLarge { axis, size: hi - lo });
            }
        }
        Ok(Roi { min: Vec3::from(min), max: Vec3::from(max), frame })
    }

    /// The box from `[xmin, ymin, zmin, xmax, ymax, zmax]`, as the command
    /// line and the config write it.
    pub fn from_bounds(bounds: [f64; 6], frame: CloudFrame) -> Result<Roi, RoiError> {
        let [x0, y0, z0, x1, y1, z1] = bounds;
        Roi::new([x0, y0, z0], [x1, y1, z1], frame)
    }

    pub fn min(&self) -> Vec3 {
        self.min
    }

    pub fn max(&self) -> Vec3 {
        self.max
    }

    pub fn frame(&self) -> CloudFrame {
        self.frame
    }

    /// True when `p`, in the box's frame, lies inside it (bounds included).
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        (0..3).all(|k| self.min[k] <= p[k] && p[k] <= self.max[k])
    }
}

impl fmt::Display for Roi {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let frame = match self.frame {
            CloudFrame::Camera => "camera",
            CloudFrame::Base => "base",
        };
        write!(
            f,
            "x {}..{}, y {}..{}, z {}..{} mm ({frame} frame)",
            self.min.x, self.max.x, self.min.y, self.max.y, self.min.z, self.max.z
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_that_are_not_boxes_are_refused_naming_the_axis_and_limit() {
        let frame = CloudFrame::Camera;
        let cases = [
            (Roi::new([0.0, 0.0, 5.0], [1.0, 1.0, 5.0], frame), "z min (5 mm) must be below its max"),
            (Roi::new([0.0, f64::NAN, 0.0], [1.0, 1.0, 1.0], frame), "y bounds"),
            (Roi::new([0.0, 0.0, 0.0], [20_000.0, 1.0, 1.0], frame), "at most 10000 mm"),
            (Roi::new([-2e5, 0.0, 0.0], [-1.99e5, 1.0, 1.0], frame), "within ±100000 mm"),
        ];
        for (result, expected) in cases {
            let e = result.unwrap_err().to_string();
            assert!(e.contains(expected), "{e}");
        }
    }
}
