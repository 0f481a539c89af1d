//! The region of interest: an axis-aligned box, in the camera frame or in
//! the robot base frame, outside which a cloud's points are dropped before
//! any search. It runs on the camera-frame millimetres `input::prepare`
//! makes, so a base-frame box is tested through the capture pose and the
//! hand-eye. An organized frame keeps its grid (the dropped pixels become
//! invalid), so a raw frame keeps its pixel-grid paths; an unorganized
//! cloud simply loses the points.

use nalgebra::{Isometry3, Point3};
use rayon::prelude::*;

use crate::cloud::{INVALID_POINT, Point, PointCloud};
pub use crate::geometry::region::{MAX_ROI_COORDINATE_MM, MAX_ROI_SIZE_MM, Roi, RoiError};

/// A box must keep at least this many valid points: fewer cannot hold two
/// plates with edges long enough for their lines (the RANSAC stage alone
/// wants 40 inliers per edge line, and the plates must be found first).
pub const MIN_ROI_POINTS: usize = 500;

/// A box that leaves too few points to plan.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "the region of interest {roi} keeps {kept} of the cloud's {valid} valid points; \
     at least {MIN_ROI_POINTS} are needed"
)]
pub struct TooFewPoints {
    pub roi: Roi,
    pub kept: usize,
    pub valid: usize,
}

/// `cloud` (camera frame) with every point outside `roi` dropped: made
/// invalid in an organized cloud, removed from an unorganized one.
/// `box_from_camera` takes camera-frame points into the box's frame:
/// None for a camera-frame box, `Base_T_End · End_T_Camera` for a
/// base-frame one (the paper's Eq. 42).
pub fn crop(
    cloud: &PointCloud,
    roi: &Roi,
    box_from_camera: Option<&Isometry3<f64>>,
) -> Result<PointCloud, TooFewPoints> {
    let inside = |p: &Point| {
        let q = Point3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
        // A camera-frame box needs no transform: a raw frame's millions
        // of points are only compared.
        roi.contains(&box_from_camera.map_or(q, |t| t * q))
    };
    // One pass writes the kept points and counts them, chunk by chunk.
    const CHUNK: usize = 1 << 14;
    let mut points = vec![INVALID_POINT; cloud.len()];
    let kept: usize = points
        .par_chunks_mut(CHUNK)
        .zip(cloud.points().par_chunks(CHUNK))
        .map(|(out, chunk)| {
            let mut kept = 0;
            for (o, p) in out.iter_mut().zip(chunk) {
                if p[0].is_finite() && inside(p) {
                    *o = *p;
                    kept += 1;
                }
            }
            kept
        })
        .sum();
    if kept < MIN_ROI_POINTS {
        return Err(TooFewPoints { roi: *roi, kept, valid: cloud.valid_count() });
    }
    let cropped = match cloud.is_organized() {
        true => PointCloud::organized(cloud.width(), cloud.height(), points),
        false => Some(PointCloud::unorganized(points)),
    };
    // Same size as the input, so organized() cannot refuse it.
    Ok(cropped.unwrap_or_else(|| PointCloud::unorganized(Vec::new())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Vec3;
    use crate::geometry::region::CloudFrame;
    use nalgebra::{Translation3, UnitQuaternion};

    /// An 80 x 60 grid of points 1 mm apart at 500 mm, in the camera frame.
    fn plate() -> PointCloud {
        let points = (0..4800).map(|i| [(i % 80) as f32 - 40.0, (i / 80) as f32 - 30.0, 500.0]).collect();
        PointCloud::organized(80, 60, points).unwrap()
    }

    #[test]
    fn an_organized_cloud_keeps_its_grid_and_an_unorganized_one_loses_the_points() {
        let roi = Roi::new([-20.0, -20.0, 400.0], [19.5, 19.5, 600.0], CloudFrame::Camera).unwrap();
        let organized = crop(&plate(), &roi, None).unwrap();
        assert!(organized.is_organized());
        assert_eq!((organized.width(), organized.height(), organized.valid_count()), (80, 60, 1600));
        let bag = PointCloud::unorganized(plate().points().to_vec());
        let unorganized = crop(&bag, &roi, None).unwrap();
        assert!(!unorganized.is_organized());
        assert_eq!((unorganized.len(), unorganized.valid_count()), (1600, 1600));
    }

    #[test]
    fn a_box_in_another_frame_is_tested_through_the_transform() {
        // The other frame is the camera's turned 90° about z and moved.
        let other_from_camera = Isometry3::from_parts(
            Translation3::new(100.0, 0.0, -500.0),
            UnitQuaternion::from_axis_angle(&Vec3::z_axis(), std::f64::consts::FRAC_PI_2),
        );
        // A camera point (x, y, 500) lies at (100 - y, x, 0) there.
        let roi = Roi::new([79.5, -30.5, -1.0], [120.5, 29.5, 1.0], CloudFrame::Base).unwrap();
        let cropped = crop(&plate(), &roi, Some(&other_from_camera)).unwrap();
        assert_eq!(cropped.valid_count(), 41 * 60);
        let in_camera = Roi::new([-30.5, -20.5, 499.0], [29.5, 20.5, 501.0], CloudFrame::Camera).unwrap();
        let kept = |c: &PointCloud| c.points().iter().map(|p| p[0].is_finite()).collect::<Vec<_>>();
        let expected = crop(&plate(), &in_camera, None).unwrap();
        assert!(kept(&cropped) == kept(&expected), "the boxes keep different points");
    }

    #[test]
    fn a_box_keeping_too_few_points_is_refused_naming_it_and_the_count() {
        let roi = Roi::new([-2.0, -2.0, 400.0], [2.0, 2.0, 600.0], CloudFrame::Camera).unwrap();
        let e = crop(&plate(), &roi, None).unwrap_err().to_string();
        assert!(e.contains("x -2..2, y -2..2, z 400..600 mm (camera frame)") && e.contains("keeps 25 of"), "{e}");
        assert!(e.contains(&format!("at least {MIN_ROI_POINTS}")), "{e}");
    }
}
