//! The camera view of a plan: the frame depth-shaded, the plates in two
//! colours, the edge points, the RANSAC lines (the picked ones brighter),
//! the fitted weld edges, the seam and its waypoints, the stations of the
//! cross-sections, a title with the result or the refusal's reason, and a
//! legend.
//!
//! An organized frame whose pixels the camera model reproduces is drawn
//! pixel by pixel and the 3D overlays projected through the model, so the
//! picture is the camera's own image; any other cloud (unorganized, or a
//! grid the model does not fit) is looked at along the plates' normal,
//! orthographically, nearest point on top.

use embedded_graphics::mono_font::MonoFont;
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::RgbColor;

use crate::camera::CameraModel;
use crate::cloud::PointCloud;
use crate::geometry::{Vec3, vec3};
use crate::pipeline::PlanTrace;
use crate::pipeline::refit::SeamCurve;

use super::{
    Canvas, PointClass, SMALL_FONT, TITLE_FONT, colour, legend_band, plate_names, sections, stack, title_band,
};

/// The largest view, pixels: a 1920 x 1200 frame at half scale, which
/// keeps a 1 mm gap at 700 mm about a pixel wide and the file small.
const MAX_VIEW_WIDTH: f64 = 960.0;
const MAX_VIEW_HEIGHT: f64 = 720.0;

/// The narrowest picture: room for the title and the legend beside a view
/// of a narrow strip.
const MIN_PICTURE_WIDTH: u32 = 720;

/// How far, in pixels, the camera model may put a frame's points from
/// their own pixels (the median over a sample) for the frame to be drawn
/// on its grid: a calibrated model reproduces its grid to a fraction of a
/// pixel; a grid from another camera misses by many.
const MAX_GRID_MISMATCH_PX: f64 = 1.5;

/// How many points the depth range and the view's extent are read from.
const SAMPLE_POINTS: usize = 20_000;

/// The nearest and farthest depths shaded, as fractions of the sorted
/// sample: a stray point does not stretch the shading.
const SHADE_QUANTILES: (f64, f64) = (0.02, 0.98);

/// The share of the points the orthographic view leaves out at each side.
const EXTENT_QUANTILE: f64 = 0.005;

/// Depth shading: the farthest points at this fraction of full colour, in
/// this many steps (bands read as depth contours and compress well).
const FARTHEST_SHADE: f64 = 0.5;
const SHADE_STEPS: f64 = 12.0;

/// How many segments a fitted curve is drawn with.
const CURVE_SEGMENTS: usize = 64;

/// How a 3D point in the camera frame lands in the view.
#[derive(Debug, Clone, PartialEq)]
pub enum View {
    /// The camera's image, scaled.
    Pixels { camera: CameraModel, scale: f64, size: (u32, u32) },
    /// Looking along `normal`: view x along `u`, y along `v`, from
    /// `origin` (the view's top-left corner) at `mm_per_px`.
    Along { origin: Vec3, u: Vec3, v: Vec3, normal: Vec3, mm_per_px: f64, size: (u32, u32) },
}

impl View {
    /// Where `p` lands in the view, pixels.
    pub fn project(&self, p: &Vec3) -> Option<(f64, f64)> {
        match self {
            View::Pixels { camera, scale, .. } => {
                camera.project(p).map(|(x, y)| ((x + 0.5) * scale, (y + 0.5) * scale))
            }
            View::Along { origin, u, v, mm_per_px, .. } => {
                let d = p - origin;
                Some((d.dot(u) / mm_per_px, d.dot(v) / mm_per_px))
            }
        }
    }

    /// The view's size, pixels.
    pub fn size(&self) -> (u32, u32) {
        match self {
            View::Pixels { size, .. } | View::Along { size, .. } => *size,
        }
    }

    /// How far `p` lies from the camera, for the shading.
    fn depth(&self, p: &Vec3) -> f64 {
        match self {
            View::Pixels { .. } => p.z,
            View::Along { normal, .. } => p.dot(normal),
        }
    }
}

/// The camera view and where its view area lies on the picture.
#[derive(Debug, Clone)]
pub struct CameraView {
    pub canvas: Canvas,
    pub view: Option<View>,
    /// The view area's top-left corner on the canvas.
    pub view_origin: (i64, i64),
}

impl CameraView {
    /// Where the camera-frame point `p` lands on the picture.
    pub fn to_canvas(&self, p: &Vec3) -> Option<(f64, f64)> {
        let (x, y) = self.view.as_ref()?.project(p)?;
        Some((x + self.view_origin.0 as f64, y + self.view_origin.1 as f64))
    }
}

/// Draws the camera view of `trace`, its points coloured by `classes`.
pub fn render(trace: &PlanTrace, classes: &[PointClass]) -> CameraView {
    let view = trace.cloud.as_ref().and_then(|cloud| choose_view(trace, cloud));
    let area = match (&view, &trace.cloud) {
        (Some(view), Some(cloud)) => {
            let mut area = draw_points(cloud, classes, view);
            draw_overlays(&mut area, trace, view);
            area
        }
        _ => {
            let mut area = Canvas::new(MAX_VIEW_WIDTH as u32, 120, colour::BACKGROUND);
            area.text("no valid point of the frame reached the stages", 12, 50, &TITLE_FONT, colour::DIM_TEXT);
            area
        }
    };
    // A narrow view sits in the middle of a picture wide enough to read.
    let width = area.width().max(MIN_PICTURE_WIDTH);
    let inset = i64::from(width - area.width()) / 2;
    let mut band = Canvas::new(width, area.height(), colour::BACKGROUND);
    band.paste(&area, inset, 0);
    let title = title_band(trace, width);
    let legend = legend_band(&legend_entries(trace), width);
    let view_origin = (inset, i64::from(title.height()));
    CameraView { canvas: stack(&[&title, &band, &legend]), view, view_origin }
}

fn legend_entries(trace: &PlanTrace) -> Vec<(Rgb888, &'static str)> {
    let plates = plate_names(trace.joint);
    vec![
        (colour::PLATES[0], plates[0]),
        (colour::PLATES[1], plates[1]),
        (colour::OTHER_PLANES[0], "other planes"),
        (colour::EDGE_POINTS[0], "edge points 1"),
        (colour::EDGE_POINTS[1], "edge points 2"),
        (colour::RANSAC_LINE, "RANSAC line"),
        (colour::PICKED_LINE, "picked line"),
        (colour::WELD_EDGE, "fitted weld edge"),
        (colour::SEAM, "seam"),
        (colour::WAYPOINT, "waypoint"),
        (colour::TEXT, "A-D: sections"),
    ]
}

/// The camera's own grid when the frame is organized and the camera model
/// reproduces it, else the view along the plates' normal.
fn choose_view(trace: &PlanTrace, cloud: &PointCloud) -> Option<View> {
    let valid: Vec<Vec3> = sample_valid(cloud).into_iter().map(|(_, p)| p).collect();
    if valid.is_empty() {
        return None;
    }
    if let Some(camera) = &trace.camera
        && cloud.is_organized()
        && grid_fits(cloud, camera)
    {
        let (w, h) = (cloud.width() as f64, cloud.height() as f64);
        let scale = (MAX_VIEW_WIDTH / w).min(MAX_VIEW_HEIGHT / h).min(1.0);
        let size = ((w * scale).round().max(1.0) as u32, (h * scale).round().max(1.0) as u32);
        return Some(View::Pixels { camera: *camera, scale, size });
    }
    Some(along_normal(trace, &valid))
}

/// Whether `camera` puts a sample of the frame's points on their own pixels.
fn grid_fits(cloud: &PointCloud, camera: &CameraModel) -> bool {
    if (cloud.width(), cloud.height()) != (camera.width_px as usize, camera.height_px as usize) {
        return false;
    }
    let mut misses: Vec<f64> = sample_valid(cloud)
        .into_iter()
        .map(|(i, p)| {
            let (col, row) = ((i % cloud.width()) as f64, (i / cloud.width()) as f64);
            camera.project(&p).map_or(f64::INFINITY, |(u, v)| (u - col).hypot(v - row))
        })
        .collect();
    misses.sort_unstable_by(f64::total_cmp);
    misses.get(misses.len() / 2).is_some_and(|&m| m <= MAX_GRID_MISMATCH_PX)
}

/// Up to [`SAMPLE_POINTS`] valid points spread evenly over the frame,
/// with their indices.
fn sample_valid(cloud: &PointCloud) -> Vec<(usize, Vec3)> {
    let stride = (cloud.len() / SAMPLE_POINTS).max(1);
    cloud
        .points()
        .iter()
        .enumerate()
        .step_by(stride)
        .filter(|(_, p)| p[0].is_finite())
        .map(|(i, p)| (i, vec3(p)))
        .collect()
}

/// The value at quantile `q` of `values` (sorted here).
fn quantile(values: &mut [f64], q: f64) -> f64 {
    values.sort_unstable_by(f64::total_cmp);
    values.get(((values.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(0.0)
}

/// The orthographic view along the plates' normal (or the dominant one,
/// or the camera's axis), x along the camera's x, fitted to the points.
fn along_normal(trace: &PlanTrace, valid: &[Vec3]) -> View {
    let normal = trace
        .weld
        .as_ref()
        .map(|w| w.normal)
        .or_else(|| trace.plate(0).map(|p| p.plane.normal))
        .or(trace.dominant_normal)
        .and_then(|n| n.try_normalize(1e-9))
        .unwrap_or_else(Vec3::z);
    let normal = if normal.z < 0.0 { -normal } else { normal };
    let u = (Vec3::x() - normal * normal.x).try_normalize(1e-6).unwrap_or_else(|| normal.cross(&Vec3::y()).normalize());
    let v = normal.cross(&u);
    let extent = |axis: &Vec3| {
        let mut along: Vec<f64> = valid.iter().map(|p| p.dot(axis)).collect();
        let (lo, hi) = (quantile(&mut along, EXTENT_QUANTILE), quantile(&mut along, 1.0 - EXTENT_QUANTILE));
        let margin = 0.03 * (hi - lo) + 1.0;
        (lo - margin, hi + margin)
    };
    let ((mut u0, mut u1), (mut v0, mut v1)) = (extent(&u), extent(&v));
    let (mut u, mut v) = (u, v);
    if v1 - v0 > u1 - u0 {
        // A strip (a crop around the seam) lies across the picture, not
        // down it: turned a quarter about the normal.
        (u, v) = (v, -u);
        ((u0, u1), (v0, v1)) = ((v0, v1), (-u1, -u0));
    }
    let mm_per_px = ((u1 - u0) / MAX_VIEW_WIDTH).max((v1 - v0) / MAX_VIEW_HEIGHT).max(1e-3);
    let size = (((u1 - u0) / mm_per_px).ceil().max(1.0) as u32, ((v1 - v0) / mm_per_px).ceil().max(1.0) as u32);
    // The view's top-left corner, at the nearest point's depth.
    let origin = u * u0 + v * v0;
    View::Along { origin, u, v, normal, mm_per_px, size }
}

/// Shades colours by depth between the frame's near and far quantiles.
struct Shading {
    near: f64,
    far: f64,
}

impl Shading {
    fn of(cloud: &PointCloud, view: &View) -> Shading {
        let mut depths: Vec<f64> = sample_valid(cloud).iter().map(|(_, p)| view.depth(p)).collect();
        let (near, far) = (quantile(&mut depths, SHADE_QUANTILES.0), quantile(&mut depths, SHADE_QUANTILES.1));
        Shading { near, far: far.max(near + 1e-3) }
    }

    fn apply(&self, ink: Rgb888, depth: f64) -> Rgb888 {
        let t = ((depth - self.near) / (self.far - self.near)).clamp(0.0, 1.0);
        let t = (t * SHADE_STEPS).round() / SHADE_STEPS;
        let f = 1.0 - (1.0 - FARTHEST_SHADE) * t;
        let scale = |c: u8| (f64::from(c) * f).round() as u8;
        Rgb888::new(scale(ink.r()), scale(ink.g()), scale(ink.b()))
    }
}

/// The points, each in its class's colour shaded by depth; edge points on
/// top so that downscaling never hides them.
fn draw_points(cloud: &PointCloud, classes: &[PointClass], view: &View) -> Canvas {
    let (w, h) = view.size();
    let mut area = Canvas::new(w, h, colour::BACKGROUND);
    let shading = Shading::of(cloud, view);
    let points = cloud.points();
    let class_of = |i: usize| classes.get(i).copied().unwrap_or(PointClass::Invalid);
    let is_edge = |i: usize| matches!(class_of(i), PointClass::Edge(_));
    match view {
        View::Pixels { scale, .. } => {
            // Each view pixel shows the frame pixel under its centre.
            let width = cloud.width();
            for y in 0..h {
                for x in 0..w {
                    let col = ((f64::from(x) + 0.5) / scale) as usize;
                    let row = ((f64::from(y) + 0.5) / scale) as usize;
                    let i = row * width + col;
                    if let (Some(ink), Some(p)) = (class_of(i).colour(), points.get(i)) {
                        area.set(x.into(), y.into(), shading.apply(ink, view.depth(&vec3(p))));
                    }
                }
            }
            for i in (0..points.len()).filter(|&i| is_edge(i)) {
                let (col, row) = ((i % width) as f64, (i / width) as f64);
                if let Some(ink) = class_of(i).colour() {
                    area.set(((col + 0.5) * scale) as i64, ((row + 0.5) * scale) as i64, ink);
                }
            }
        }
        View::Along { mm_per_px, .. } => {
            // Points a spacing apart leave no holes: each covers a square
            // about its spacing wide, the nearest point on top.
            let valid = points.iter().filter(|p| p[0].is_finite()).count().max(1);
            let spacing = (f64::from(w) * f64::from(h) * mm_per_px * mm_per_px / valid as f64).sqrt();
            let radius = (0.5 * spacing / mm_per_px).round().clamp(0.0, 3.0) as i64;
            let mut nearest = vec![f64::INFINITY; w as usize * h as usize];
            let mut splat = |area: &mut Canvas, i: usize, on_top: bool| {
                let (Some(ink), Some(p)) = (class_of(i).colour(), points.get(i)) else { return };
                let p = vec3(p);
                let Some((x, y)) = view.project(&p) else { return };
                let depth = view.depth(&p);
                let ink = if on_top { ink } else { shading.apply(ink, depth) };
                for dy in -radius..=radius {
                    for dx in -radius..=radius {
                        let (px, py) = (x as i64 + dx, y as i64 + dy);
                        if px < 0 || py < 0 || px >= i64::from(w) || py >= i64::from(h) {
                            continue;
                        }
                        let k = py as usize * w as usize + px as usize;
                        if on_top || depth < nearest[k] {
                            nearest[k] = depth;
                            area.set(px, py, ink);
                        }
                    }
                }
            };
            for i in 0..points.len() {
                splat(&mut area, i, false);
            }
            for i in (0..points.len()).filter(|&i| is_edge(i)) {
                splat(&mut area, i, true);
            }
        }
    }
    area
}

/// `curve` from `s0` to `s1` in view coordinates.
fn projected_curve(view: &View, curve: &SeamCurve, (s0, s1): (f64, f64)) -> Vec<(f64, f64)> {
    (0..=CURVE_SEGMENTS)
        .filter_map(|k| view.project(&curve.at(s0 + (s1 - s0) * k as f64 / CURVE_SEGMENTS as f64)))
        .collect()
}

/// The RANSAC lines, the fitted weld edges, the seam, its waypoints and
/// the sections' stations, in that order (the seam on top), and each
/// plane's depth and area, as the background stage's messages give them.
fn draw_overlays(area: &mut Canvas, trace: &PlanTrace, view: &View) {
    let normal = trace.dominant_normal.unwrap_or_else(|| trace.planes.first().map_or_else(Vec3::z, |p| p.plane.normal));
    for (k, plane) in trace.planes.iter().enumerate() {
        if let Some(at) = label_point(trace, k).and_then(|p| view.project(&p)) {
            let text = format!("{:.1} mm, {:.0} mm²", normal.dot(&plane.centroid), plane.area_mm2);
            label(area, at, (0.0, 0.0), &text, &SMALL_FONT);
        }
    }
    for line in trace.edge_lines.iter().filter(|l| !l.picked) {
        if let (Some(a), Some(b)) = (view.project(&line.ends[0]), view.project(&line.ends[1])) {
            area.line(a, b, colour::RANSAC_LINE, 1);
        }
    }
    for line in trace.edge_lines.iter().filter(|l| l.picked) {
        if let (Some(a), Some(b)) = (view.project(&line.ends[0]), view.project(&line.ends[1])) {
            area.line(a, b, colour::PICKED_LINE, 2);
        }
    }
    for fit in trace.weld_edges.iter().flatten() {
        area.polyline(&projected_curve(view, &fit.curve, (fit.curve.s_min, fit.curve.s_max)), colour::WELD_EDGE, 2);
    }
    let Some(weld) = &trace.weld else { return };
    area.polyline(&projected_curve(view, &weld.curve, weld.span), colour::SEAM, 3);
    for p in trace.waypoints_camera.iter().filter_map(|p| view.project(p)) {
        area.disc(p, 5, colour::WAYPOINT, Some(colour::SEAM));
    }
    if let Some(start) = trace.waypoints_camera.first().and_then(|p| view.project(p)) {
        label(area, start, (10.0, -22.0), "start", &TITLE_FONT);
    }
    for (name, s) in sections::stations(weld) {
        let (Some(at), Some(ahead)) = (view.project(&weld.curve.at(s)), view.project(&weld.curve.at(s + 1.0))) else {
            continue;
        };
        // Beside the seam, square to it on the picture.
        let (dx, dy) = (ahead.0 - at.0, ahead.1 - at.1);
        let norm = dx.hypot(dy).max(1e-9);
        let side = (-dy / norm * 26.0, dx / norm * 26.0);
        area.line(at, (at.0 + side.0, at.1 + side.1), colour::TEXT, 1);
        label(area, at, side, &name.to_string(), &TITLE_FONT);
    }
}

/// Where plane `k`'s label goes: at its centroid when the camera sees the
/// plane there, else (a table's centroid lies behind the plates on it) at
/// the point of the plane farthest from every other plane's centroid.
fn label_point(trace: &PlanTrace, k: usize) -> Option<Vec3> {
    /// A member this near the centroid shows the plane is seen there, mm.
    const SEEN_AT_CENTROID_MM: f64 = 5.0;
    let plane = trace.planes.get(k)?;
    let points = trace.cloud.as_ref()?.points();
    let stride = (plane.members.len() / SAMPLE_POINTS).max(1);
    let sample: Vec<Vec3> =
        plane.members.iter().step_by(stride).filter_map(|&i| points.get(i as usize).map(vec3)).collect();
    let by = |score: &dyn Fn(&Vec3) -> f64| sample.iter().copied().min_by(|a, b| score(a).total_cmp(&score(b)));
    let nearest = by(&|p| (p - plane.centroid).norm())?;
    if (nearest - plane.centroid).norm() <= SEEN_AT_CENTROID_MM {
        return Some(nearest);
    }
    let others: Vec<Vec3> = trace.planes.iter().enumerate().filter(|(j, _)| *j != k).map(|(_, p)| p.centroid).collect();
    by(&|p| -others.iter().map(|c| (p - c).norm()).fold(f64::INFINITY, f64::min))
}

/// `text` on a dark patch centred at `offset` from `at`.
fn label(area: &mut Canvas, at: (f64, f64), offset: (f64, f64), text: &str, font: &MonoFont) {
    let (w, h) = (super::canvas::text_width(text, font) as i64, font.character_size.height as i64);
    // Inside the view, however near its border the point lies.
    let x = ((at.0 + offset.0) as i64 - w / 2).clamp(3, (i64::from(area.width()) - w - 3).max(3));
    let y = ((at.1 + offset.1) as i64 - h / 2).clamp(2, (i64::from(area.height()) - h - 2).max(2));
    area.fill_rect(x - 3, y - 2, (w + 6) as u32, (h + 4) as u32, colour::BACKGROUND);
    area.text(text, x, y, font, colour::TEXT);
}
