//! Noise-free rendering: one ray per pixel centre against the scene in the
//! camera frame, keeping only returns the projector can light and both the
//! camera and the projector see at a usable angle.
//!
//! Rays are scaled to unit z (as [`CameraModel::ray`] gives them), so a
//! ray's hit parameter is the point's depth. Each solid's projection is
//! bounded once in pixel space, so a pixel tests only the few solids that
//! can cover it.

use rayon::prelude::*;

use super::scene::{ConvexSolid, Scene};
use crate::camera::CameraModel;
use crate::cloud::{INVALID_POINT, Point, PointCloud};
use crate::geometry::Vec3;

/// Solids closer to the camera plane than this are treated as possibly
/// crossing it, so their projection is not bounded.
const MIN_BOUNDED_DEPTH_MM: f64 = 1e-3;

/// Pixel-space bounds `[u_min, u_max, v_min, v_max]` of a solid.
type PixelRect = [f64; 4];

/// A solid as the projector sees it: the bounds of its vertices' view
/// directions `[x/z min, x/z max, y/z min, y/z max]` from the projector,
/// and its nearest depth. A shadow ray from a point is one direction, so
/// these reject almost every solid with four comparisons.
#[derive(Debug, Clone, Copy)]
struct ProjectorFootprint {
    slopes: [f64; 4],
    min_depth: f64,
}

/// A visible, lit return at a pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelHit {
    pub depth: f64,
    /// Index of the solid hit in the scene's list.
    pub solid: usize,
}

/// The first surface along a ray, before the sensor's visibility checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceHit {
    pub depth: f64,
    pub solid: usize,
    pub normal: Vec3,
}

/// The scene as the camera sees it.
pub struct CameraView {
    camera: CameraModel,
    solids: Vec<ConvexSolid>,
    pixel_rects: Vec<Option<PixelRect>>,
    projector_footprints: Vec<Option<ProjectorFootprint>>,
    projector: Vec3,
    min_cos_incidence: f64,
}

impl CameraView {
    /// `scene` must be in the camera frame. Returns steeper than
    /// `max_incidence_deg` to the camera or the projector are dropped.
    pub fn new(scene: Scene, camera: &CameraModel, max_incidence_deg: f64) -> Self {
        let pixel_rects = scene.solids.iter().map(|s| pixel_rect(s, camera)).collect();
        let projector = Vec3::new(camera.baseline_mm, 0.0, 0.0);
        let projector_footprints = scene.solids.iter().map(|s| projector_footprint(s, &projector)).collect();
        CameraView {
            camera: *camera,
            solids: scene.solids,
            pixel_rects,
            projector_footprints,
            projector,
            min_cos_incidence: max_incidence_deg.to_radians().cos(),
        }
    }

    pub fn solids(&self) -> &[ConvexSolid] {
        &self.solids
    }

    /// Solids whose projection may cover pixel row `v`.
    fn solids_in_row(&self, v: f64) -> Vec<usize> {
        (0..self.solids.len())
            .filter(|&i| match self.pixel_rects[i] {
                Some([_, _, v0, v1]) => (v0..=v1).contains(&v),
                None => true,
            })
            .collect()
    }

    fn covers(&self, solid: usize, u: f64) -> bool {
        match self.pixel_rects[solid] {
            Some([u0, u1, _, _]) => (u0..=u1).contains(&u),
            None => true,
        }
    }

    /// The nearest surface along the ray through pixel `(u, v)`.
    pub fn first_surface(&self, u: f64, v: f64) -> Option<SurfaceHit> {
        self.first_surface_among(u, v, &self.solids_in_row(v))
    }

    fn first_surface_among(&self, u: f64, v: f64, candidates: &[usize]) -> Option<SurfaceHit> {
        let dir = Vec3::from(self.camera.ray(u, v));
        let origin = Vec3::zeros();
        let mut best: Option<SurfaceHit> = None;
        for &i in candidates {
            if !self.covers(i, u) {
                continue;
            }
            let limit = best.map_or(f64::INFINITY, |b| b.depth);
            let Some(span) = self.solids[i].clip(&origin, &dir, 0.0, limit) else {
                continue;
            };
            if let Some(normal) = span.normal {
                best = Some(SurfaceHit { depth: span.enter, solid: i, normal });
            }
        }
        best
    }

    /// The return at pixel `(u, v)`, if the sensor gets one.
    pub fn trace_pixel(&self, u: f64, v: f64) -> Option<PixelHit> {
        self.trace_among(u, v, &self.solids_in_row(v))
    }

    fn trace_among(&self, u: f64, v: f64, candidates: &[usize]) -> Option<PixelHit> {
        let hit = self.first_surface_among(u, v, candidates)?;
        let dir = Vec3::from(self.camera.ray(u, v));
        let point = dir * hit.depth;
        let to_projector = self.projector - point;
        let seen = -hit.normal.dot(&dir) / dir.norm();
        let lit = hit.normal.dot(&to_projector) / to_projector.norm();
        let usable = seen >= self.min_cos_incidence && lit >= self.min_cos_incidence;
        (usable && !self.shadowed(&point, &to_projector, hit.solid))
            .then_some(PixelHit { depth: hit.depth, solid: hit.solid })
    }

    /// True when another solid blocks the projector's light to `point`.
    /// The lit solid itself cannot: it is convex and its face at `point`
    /// faces the projector.
    fn shadowed(&self, point: &Vec3, to_projector: &Vec3, lit_solid: usize) -> bool {
        let slope = [-to_projector.x / point.z, point.y / point.z];
        let may_block = |footprint: &Option<ProjectorFootprint>| match footprint {
            Some(f) => {
                f.min_depth < point.z
                    && (f.slopes[0]..=f.slopes[1]).contains(&slope[0])
                    && (f.slopes[2]..=f.slopes[3]).contains(&slope[1])
            }
            None => true,
        };
        (0..self.solids.len()).any(|i| {
            i != lit_solid && may_block(&self.projector_footprints[i]) && self.solids[i].blocks(point, to_projector)
        })
    }

    /// The noise-free depth of every pixel, row-major, NaN without a return.
    pub fn trace_depths(&self) -> Vec<f64> {
        let width = self.camera.width_px as usize;
        let height = self.camera.height_px as usize;
        let mut depths = vec![f64::NAN; width * height];
        depths.par_chunks_mut(width.max(1)).enumerate().for_each(|(row, out)| {
            let v = row as f64;
            let candidates = self.solids_in_row(v);
            for (col, depth) in out.iter_mut().enumerate() {
                if let Some(hit) = self.trace_among(col as f64, v, &candidates) {
                    *depth = hit.depth;
                }
            }
        });
        depths
    }
}

/// The projection's bounding rectangle, one pixel wider for rounding; none
/// when the solid reaches the camera plane (its projection is unbounded).
fn pixel_rect(solid: &ConvexSolid, camera: &CameraModel) -> Option<PixelRect> {
    let mut rect = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
    for v in solid.vertices() {
        if v.z < MIN_BOUNDED_DEPTH_MM {
            return None;
        }
        let (pu, pv) = camera.project(v)?;
        rect = [rect[0].min(pu), rect[1].max(pu), rect[2].min(pv), rect[3].max(pv)];
    }
    Some([rect[0] - 1.0, rect[1] + 1.0, rect[2] - 1.0, rect[3] + 1.0])
}

/// None when the solid reaches the projector's plane, where directions
/// are unbounded.
fn projector_footprint(solid: &ConvexSolid, projector: &Vec3) -> Option<ProjectorFootprint> {
    let mut slopes = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
    let mut min_depth = f64::INFINITY;
    for v in solid.vertices() {
        let d = v - projector;
        if d.z < MIN_BOUNDED_DEPTH_MM {
            return None;
        }
        let (sx, sy) = (d.x / d.z, d.y / d.z);
        slopes = [slopes[0].min(sx), slopes[1].max(sx), slopes[2].min(sy), slopes[3].max(sy)];
        min_depth = min_depth.min(d.z);
    }
    // Widen by a hair so rounding never rejects a grazing blocker.
    let pad = 1e-9 * (1.0 + slopes.iter().fold(0.0f64, |m, s| m.max(s.abs())));
    Some(ProjectorFootprint { slopes: [slopes[0] - pad, slopes[1] + pad, slopes[2] - pad, slopes[3] + pad], min_depth })
}

/// Turns per-pixel depths into the organized cloud, each point on its
/// pixel's ray.
pub fn depths_to_cloud(depths: &[f64], camera: &CameraModel) -> PointCloud {
    let width = camera.width_px as usize;
    let height = camera.height_px as usize;
    let mut points: Vec<Point> = vec![INVALID_POINT; width * height];
    points.par_chunks_mut(width.max(1)).zip(depths.par_chunks(width.max(1))).enumerate().for_each(
        |(row, (out, depth_row))| {
            for (col, (p, &z)) in out.iter_mut().zip(depth_row).enumerate() {
                if z.is_finite() && z > 0.0 {
                    let [x, y, _] = camera.ray(col as f64, row as f64);
                    *p = [(x * z) as f32, (y * z) as f32, z as f32];
                }
            }
        },
    );
    PointCloud::organized(width, height, points).expect("the frame holds exactly one point per pixel")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scene::SurfaceKind;

    /// A small camera with the paper's optics, so tests render fast.
    fn small_camera() -> CameraModel {
        CameraModel { width_px: 240, height_px: 150, ..CameraModel::default() }
    }

    /// A 100 mm cube 50 mm thick standing on a table 600 mm in front of the
    /// camera, seen straight on.
    fn block_on_table() -> Scene {
        let cube =
            ConvexSolid::cuboid(SurfaceKind::Plate, Vec3::new(-50.0, -50.0, 550.0), Vec3::new(50.0, 50.0, 600.0))
                .unwrap();
        let table = ConvexSolid::cuboid(
            SurfaceKind::Table,
            Vec3::new(-1000.0, -1000.0, 600.0),
            Vec3::new(1000.0, 1000.0, 620.0),
        )
        .unwrap();
        Scene { solids: vec![cube, table] }
    }

    #[test]
    fn the_block_is_in_front_of_the_table() {
        let cam = small_camera();
        let view = CameraView::new(block_on_table(), &cam, 80.0);
        let centre = view.trace_pixel(cam.cx(), cam.cy()).unwrap();
        assert_eq!(centre.solid, 0);
        assert!((centre.depth - 550.0).abs() < 1e-9);
        let corner = view.trace_pixel(0.0, 0.0).unwrap();
        assert_eq!(corner.solid, 1);
        assert!((corner.depth - 600.0).abs() < 1e-9);
    }

    #[test]
    fn shadows_fall_on_the_side_away_from_the_projector() {
        let cam = small_camera();
        let view = CameraView::new(block_on_table(), &cam, 80.0);
        let depths = view.trace_depths();
        let row = cam.cy().round() as usize;
        let width = cam.width_px as usize;
        // The table at depth 600 around the block, x = ±50 mm, in pixels.
        let edge = |x: f64| cam.project(&Vec3::new(x, 0.0, 600.0)).unwrap().0;
        let (left, right) = (edge(-50.0), edge(50.0));
        let invalid_left = (0..width).filter(|&c| (c as f64) < left && depths[row * width + c].is_nan()).count();
        let invalid_right = (0..width).filter(|&c| (c as f64) > right && depths[row * width + c].is_nan()).count();
        // The projector sits at +x: the block's shadow on the table is on
        // its -x side, 50 mm tall lit from 200 mm to its side at 600 mm:
        // about 50 * 200 / 550 = 18 mm wide, some 7 pixels here.
        assert_eq!(invalid_right, 0);
        assert!((5..=9).contains(&invalid_left), "{invalid_left} shadowed pixels");
    }

    #[test]
    fn grazing_surfaces_give_no_return() {
        let cam = small_camera();
        // A plane tilted 85 degrees from the view.
        let a = 85f64.to_radians();
        let profile = [
            [-1000.0, 600.0],
            [1000.0, 600.0 + 2000.0 * a.tan()],
            [1000.0, 700.0 + 2000.0 * a.tan()],
            [-1000.0, 700.0],
        ];
        let slab = ConvexSolid::extruded(SurfaceKind::Table, &profile, [-1000.0, 1000.0]).unwrap();
        let scene = Scene { solids: vec![slab] };
        assert!(CameraView::new(scene.clone(), &cam, 80.0).trace_pixel(cam.cx(), cam.cy()).is_none());
        assert!(CameraView::new(scene, &cam, 89.0).trace_pixel(cam.cx(), cam.cy()).is_some());
    }
}
