//! A frame's pixel grid: where a camera-frame point falls on the image of
//! the camera that made the frame, for reading a plate's pixels beside an
//! edge and where a seam leaves the view.

use crate::camera::CameraModel;
use crate::geometry::Vec3;

/// A frame's pixel grid and the camera that made it: where a point in the
/// camera frame falls on it.
#[derive(Debug)]
pub(in crate::pipeline) struct CameraGrid<'a> {
    camera: &'a CameraModel,
    width: usize,
    height: usize,
}

impl<'a> CameraGrid<'a> {
    /// The grid of `camera`'s own frames.
    pub(in crate::pipeline) fn for_camera(camera: &'a CameraModel) -> Self {
        CameraGrid { camera, width: camera.width_px as usize, height: camera.height_px as usize }
    }

    /// Whether `p` projects inside the image, half a pixel inside the
    /// outermost pixel centres.
    pub(in crate::pipeline) fn in_view(&self, p: &Vec3) -> bool {
        let (u_max, v_max) = (self.width as f64 - 1.5, self.height as f64 - 1.5);
        self.camera.project(p).is_some_and(|(u, v)| (0.5..=u_max).contains(&u) && (0.5..=v_max).contains(&v))
    }

    /// Where `p` projects on the image, pixels.
    pub(in crate::pipeline) fn project(&self, p: &Vec3) -> Option<(f64, f64)> {
        self.camera.project(p)
    }

    /// The image's width and height, pixels.
    pub(in crate::pipeline) fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The index of the pixel `p` projects into, if inside the image.
    pub(in crate::pipeline) fn pixel_of(&self, p: &Vec3) -> Option<usize> {
        let (u, v) = self.camera.project(p)?;
        let (u, v) = (u.round(), v.round());
        let inside = (0.0..self.width as f64).contains(&u) && (0.0..self.height as f64).contains(&v);
        inside.then(|| v as usize * self.width + u as usize)
    }
}
