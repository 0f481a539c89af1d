//! Profiles across the seam: at four stations along the weld, the points
//! of a thin slab square to it, plotted as offset across the seam against
//! height along the plate normal (towards the camera is up), millimetres
//! at one scale on both axes so a groove's faces keep their angle. Each
//! panel marks the weld edges and the samples they were fitted to, the
//! planned point and, between a butt joint's edges, the deepest point the
//! camera saw (a V-groove's root, when its bottom is in view).

use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;
use crate::pipeline::PlanTrace;
use crate::pipeline::trace::TracedWeld;

use super::{Canvas, PointClass, SMALL_FONT, colour, legend_band, plate_names, stack, title_band};

/// The stations, as fractions of the planned stretch: the middle of each
/// quarter, so the ends (where a seam most often goes wrong) are near the
/// first and last.
const STATIONS: [(char, f64); 4] = [('A', 0.125), ('B', 0.375), ('C', 0.625), ('D', 0.875)];

/// A panel's size and its plot area's margins, pixels.
const PANEL: (u32, u32) = (480, 330);
const MARGIN_LEFT: f64 = 46.0;
const MARGIN_RIGHT: f64 = 12.0;
const MARGIN_TOP: f64 = 40.0;
const MARGIN_BOTTOM: f64 = 34.0;

/// The slab's half-thickness along the seam: a point spacing, so about
/// two rows of points cross it, but never thinner than this, mm.
const MIN_SLAB_HALF_MM: f64 = 0.25;

/// The half-width across the seam shown: twice the edges' offset plus
/// this much plate either side, within these bounds, mm.
const PLATE_SHOWN_MM: f64 = 8.0;
const HALF_WIDTH_MM: (f64, f64) = (10.0, 40.0);

/// The points' heights shown, as quantiles of the slab's (a stray point
/// or the table seen through a gap does not flatten the profile).
const HEIGHT_QUANTILES: (f64, f64) = (0.01, 0.99);

/// The share of the lowest points between a butt joint's edges whose
/// highest one is marked as the deepest seen: one noisy point is not.
const DEEPEST_QUANTILE: f64 = 0.05;

/// The stations along `weld`: a letter and the feature coordinate.
pub fn stations(weld: &TracedWeld) -> Vec<(char, f64)> {
    let (s0, s1) = weld.span;
    STATIONS.iter().map(|&(name, f)| (name, s0 + (s1 - s0) * f)).collect()
}

/// The sections of `trace`, when it has a weld and its edges.
pub fn render(trace: &PlanTrace, classes: &[PointClass]) -> Option<Canvas> {
    let weld = trace.weld.as_ref()?;
    trace.weld_edges.as_ref()?;
    let panels: Vec<Canvas> = stations(weld).into_iter().map(|(name, s)| panel(trace, classes, name, s)).collect();
    let width = 2 * PANEL.0;
    let mut grid = Canvas::new(width, 2 * PANEL.1, colour::BACKGROUND);
    for (k, p) in panels.iter().enumerate() {
        grid.paste(p, (k % 2) as i64 * i64::from(PANEL.0), (k / 2) as i64 * i64::from(PANEL.1));
    }
    let title = title_band(trace, width);
    let plates = plate_names(trace.joint);
    let mut entries = vec![
        (colour::PLATES[0], plates[0]),
        (colour::PLATES[1], plates[1]),
        (colour::OTHER_POINT, "other points"),
        (colour::WELD_EDGE, "weld edge and its fit samples"),
        (colour::SEAM, "planned point"),
    ];
    if trace.joint != Some(JointType::Lap) {
        entries.push((colour::ROOT_SEEN, "deepest point seen between the edges"));
    }
    let legend = legend_band(&entries, width);
    Some(stack(&[&title, &grid, &legend]))
}

/// Coordinates square to the weld at a station: along it, across it
/// (the first plate's edge on the left) and up towards the camera.
struct Station {
    origin: Vec3,
    along: Vec3,
    across: Vec3,
    up: Vec3,
}

impl Station {
    /// (along, across, up) of `p`, mm.
    fn coords(&self, p: &Vec3) -> (f64, f64, f64) {
        let d = p - self.origin;
        (d.dot(&self.along), d.dot(&self.across), d.dot(&self.up))
    }
}

/// The plot's mapping from (across, up) in mm to panel pixels.
struct Plot {
    x0: f64,
    y1: f64,
    px_per_mm: f64,
}

impl Plot {
    fn at(&self, (x, y): (f64, f64)) -> (f64, f64) {
        (MARGIN_LEFT + (x - self.x0) * self.px_per_mm, MARGIN_TOP + (self.y1 - y) * self.px_per_mm)
    }

    fn width_mm(&self) -> f64 {
        (f64::from(PANEL.0) - MARGIN_LEFT - MARGIN_RIGHT) / self.px_per_mm
    }

    fn height_mm(&self) -> f64 {
        (f64::from(PANEL.1) - MARGIN_TOP - MARGIN_BOTTOM) / self.px_per_mm
    }
}

/// One station's panel.
fn panel(trace: &PlanTrace, classes: &[PointClass], name: char, s: f64) -> Canvas {
    let mut canvas = Canvas::new(PANEL.0, PANEL.1, colour::BACKGROUND);
    let (Some(weld), Some(edges)) = (&trace.weld, &trace.weld_edges) else { return canvas };
    let origin = weld.curve.at(s);
    let along = weld.curve.tangent(s);
    let normal = if weld.normal.z < 0.0 { -weld.normal } else { weld.normal };
    let mut across = normal.cross(&along).normalize();
    if (edges[0].curve.at(s) - origin).dot(&across) > 0.0 {
        across = -across;
    }
    let station = Station { origin, along, across, up: -normal };
    let flat = |p: &Vec3| {
        let (_, x, y) = station.coords(p);
        (x, y)
    };
    let edge_at = edges.each_ref().map(|f| flat(&f.curve.at(s)));
    let half_width =
        (2.0 * edge_at[0].0.abs().max(edge_at[1].0.abs()) + PLATE_SHOWN_MM).clamp(HALF_WIDTH_MM.0, HALF_WIDTH_MM.1);

    let spacing = trace
        .quality
        .map(|q| q.point_spacing_mm)
        .or_else(|| trace.camera.map(|c| c.pixel_footprint_at(&origin)))
        .unwrap_or(MIN_SLAB_HALF_MM);
    let slab = spacing.max(MIN_SLAB_HALF_MM);
    let in_slab = |p: &Vec3| {
        let (a, x, _) = station.coords(p);
        a.abs() <= slab && x.abs() <= half_width
    };
    let points: Vec<((f64, f64), PointClass)> = trace
        .cloud
        .iter()
        .flat_map(|c| c.points().iter().enumerate())
        .filter(|(_, p)| p[0].is_finite())
        .map(|(i, p)| (vec3(p), classes.get(i).copied().unwrap_or(PointClass::Other)))
        .filter(|(p, _)| in_slab(p))
        .map(|(p, class)| (flat(&p), class))
        .collect();
    let samples: Vec<(f64, f64)> = trace.fit_samples.iter().flatten().filter(|p| in_slab(p)).map(flat).collect();
    // Sections are drawn for a seam, whose joint is decided by then.
    let joint = trace.joint.unwrap_or(JointType::IButt);
    let deepest = deepest_between(joint, &points, edge_at);

    // The heights shown: the slab's, without its strays, and every marker.
    let mut markers = vec![(0.0, 0.0), edge_at[0], edge_at[1]];
    markers.extend(deepest);
    let (m_lo, m_hi) = crate::geometry::extent(markers.iter().map(|m| m.1));
    let mut heights: Vec<f64> = points.iter().map(|(p, _)| p.1).collect();
    heights.sort_unstable_by(f64::total_cmp);
    let pick = |q: f64| heights.get(((heights.len() as f64 - 1.0) * q).round() as usize).copied();
    let reach = 0.6 * half_width;
    let lo = pick(HEIGHT_QUANTILES.0).map_or(m_lo, |h| h.max(m_lo - reach)).min(m_lo) - 1.5;
    let hi = pick(HEIGHT_QUANTILES.1).map_or(m_hi, |h| h.min(m_hi + reach)).max(m_hi) + 1.5;
    let plot_w = f64::from(PANEL.0) - MARGIN_LEFT - MARGIN_RIGHT;
    let plot_h = f64::from(PANEL.1) - MARGIN_TOP - MARGIN_BOTTOM;
    let px_per_mm = (plot_w / (2.0 * half_width)).min(plot_h / (hi - lo));
    let mut plot = Plot { x0: 0.0, y1: 0.0, px_per_mm };
    plot.x0 = -plot.width_mm() / 2.0;
    plot.y1 = 0.5 * (lo + hi) + plot.height_mm() / 2.0;

    draw_axes(&mut canvas, &plot, plate_names(trace.joint)[0]);
    for ((x, y), class) in &points {
        if let Some(ink) = class.colour() {
            canvas.disc(plot.at((*x, *y)), 3, ink, None);
        }
    }
    for p in &samples {
        canvas.disc(plot.at(*p), 3, colour::WELD_EDGE, None);
    }
    for (k, e) in edge_at.iter().enumerate() {
        canvas.ring(plot.at(*e), 13, colour::WELD_EDGE, 2);
        // Each edge's name on its own plate's side, clear of the other's.
        let (x, y) = plot.at(*e);
        let text = format!("edge {}", k + 1);
        let width = i64::from(super::canvas::text_width(&text, &SMALL_FONT));
        let left = if e.0 <= edge_at[1 - k].0 { x as i64 - width - 4 } else { x as i64 + 4 };
        canvas.text(&text, left, y as i64 - 22, &SMALL_FONT, colour::WELD_EDGE);
    }
    if let Some(d) = deepest {
        canvas.ring(plot.at(d), 11, colour::ROOT_SEEN, 2);
    }
    let planned = plot.at((0.0, 0.0));
    canvas.ring(planned, 15, colour::SEAM, 2);
    canvas.line((planned.0 - 11.0, planned.1), (planned.0 + 11.0, planned.1), colour::SEAM, 1);
    canvas.line((planned.0, planned.1 - 11.0), (planned.0, planned.1 + 11.0), colour::SEAM, 1);

    let (mut line, depths) = caption(joint, edge_at, deepest);
    line = format!("{name} at {:.0} mm: {line}", s - weld.span.0);
    if points.is_empty() {
        line.push_str("; no point in the slab");
    }
    canvas.text(&line, 6, 4, &SMALL_FONT, colour::TEXT);
    canvas.text(&depths, 6, 19, &SMALL_FONT, colour::DIM_TEXT);
    canvas
}

/// What a panel shows, in words: the edges' offsets from each other and
/// where the planned point lies from them (the planned point is the
/// panel's origin).
fn caption(joint: JointType, edges: [(f64, f64); 2], deepest: Option<(f64, f64)>) -> (String, String) {
    // Rounding shows no "-0.00".
    let mm = |v: f64| format!("{:.2}", if v.abs() < 0.005 { 0.0 } else { v });
    let ([x0, y0], [x1, y1]) = ([edges[0].0, edges[0].1], [edges[1].0, edges[1].1]);
    if joint == JointType::Lap {
        return (
            format!("lower plate {} mm below the upper edge", mm(y0 - y1)),
            format!("planned {} mm below the upper edge, {} mm across from it", mm(y0), mm(x0.abs())),
        );
    }
    let top = 0.5 * (y0 + y1);
    let mut depths = format!("planned {} mm below the edges", mm(top));
    if let Some((_, deep)) = deepest {
        depths.push_str(&format!(", deepest point seen {} mm", mm(top - deep)));
    }
    (format!("edges {} mm apart, {} mm high-low", mm((x1 - x0).abs()), mm((y1 - y0).abs())), depths)
}

/// The deepest point seen between a butt joint's edges (the highest of
/// the lowest few), none for a lap or an empty groove.
fn deepest_between(
    joint: JointType,
    points: &[((f64, f64), PointClass)],
    edges: [(f64, f64); 2],
) -> Option<(f64, f64)> {
    if joint == JointType::Lap {
        return None;
    }
    let (left, right) = (edges[0].0.min(edges[1].0), edges[0].0.max(edges[1].0));
    let mut inside: Vec<(f64, f64)> = points.iter().map(|(p, _)| *p).filter(|p| p.0 > left && p.0 < right).collect();
    inside.sort_unstable_by(|a, b| a.1.total_cmp(&b.1));
    let k = ((inside.len() as f64 * DEEPEST_QUANTILE).floor() as usize).min(inside.len().checked_sub(1)?);
    inside.get(k).copied()
}

/// The step between grid lines: 1, 2 or 5 times a power of ten, giving
/// about eight lines across `range_mm`.
fn grid_step(range_mm: f64) -> f64 {
    let rough = (range_mm / 8.0).max(1e-3);
    let power = 10f64.powf(rough.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * power).find(|&step| step >= rough).unwrap_or(10.0 * power)
}

/// The plot's frame, grid, tick labels and axis names, in millimetres.
fn draw_axes(canvas: &mut Canvas, plot: &Plot, left_plate: &str) {
    let (x1, y0) = (plot.x0 + plot.width_mm(), plot.y1 - plot.height_mm());
    let step = grid_step(plot.width_mm().max(plot.height_mm()));
    let label = |v: f64| if step < 1.0 { format!("{v:.1}") } else { format!("{v:.0}") };
    let ticks = |from: f64, to: f64| {
        let first = (from / step).ceil() as i64;
        let last = (to / step).floor() as i64;
        (first..=last).map(move |k| k as f64 * step)
    };
    for x in ticks(plot.x0, x1) {
        let (a, b) = (plot.at((x, y0)), plot.at((x, plot.y1)));
        canvas.line(a, b, colour::GRID, 1);
        let text = label(x);
        let half = i64::from(super::canvas::text_width(&text, &SMALL_FONT)) / 2;
        canvas.text(&text, a.0 as i64 - half, a.1 as i64 + 3, &SMALL_FONT, colour::DIM_TEXT);
    }
    for y in ticks(y0, plot.y1) {
        let (a, b) = (plot.at((plot.x0, y)), plot.at((x1, y)));
        canvas.line(a, b, colour::GRID, 1);
        let text = label(y);
        let width = i64::from(super::canvas::text_width(&text, &SMALL_FONT));
        canvas.text(&text, a.0 as i64 - width - 4, a.1 as i64 - 6, &SMALL_FONT, colour::DIM_TEXT);
    }
    let (left, top) = plot.at((plot.x0, plot.y1));
    let (right, bottom) = plot.at((x1, y0));
    canvas.frame_rect(left as i64, top as i64, (right - left) as u32 + 1, (bottom - top) as u32 + 1, colour::AXES);
    let axis = format!("across the seam, mm ({left_plate} left); up: height towards the camera, mm");
    canvas.text(&axis, 6, bottom as i64 + 17, &SMALL_FONT, colour::DIM_TEXT);
}
