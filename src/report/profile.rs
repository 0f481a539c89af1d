//! Profiles along the seam: each figure the planner measured at the
//! waypoints (a butt's gap and high-low, a V-groove's cross-section, a
//! lap's step) plotted against the distance along the seam, one panel per
//! figure, each value with its standard error as a bar of ±1 sigma. A
//! waypoint where the figure was not measured breaks the line and is
//! ticked under the plot; the stretches the weld process cut are shaded
//! across every panel and labelled with their rule, so what the figures
//! did to the weld is read off one picture.
//!
//! Drawn from the plan as the protocol carries it (each seam's
//! `along_seam` and `process`, [`crate::convert::to_proto::add_along_seam`]),
//! one block of panels per seam.

use embedded_graphics::pixelcolor::Rgb888;
use weldseam_proto::along_seam::{JointFigures, Measured};
use weldseam_proto::plan::{PlanResult, Seam};

use crate::pipeline::PlanTrace;

use super::{Canvas, SMALL_FONT, colour, legend_band, stack, title_band};

/// A panel's size and its plot area's margins, pixels.
const PANEL: (u32, u32) = (960, 200);
const MARGIN_LEFT: f64 = 64.0;
const MARGIN_RIGHT: f64 = 16.0;
const MARGIN_TOP: f64 = 24.0;
const MARGIN_BOTTOM: f64 = 34.0;

/// The seams drawn at most: a frame of several workpieces draws its first
/// ones, in the order they are welded.
const MAX_SEAMS_DRAWN: usize = 4;

/// About this many labelled ticks on each axis.
const TICKS: f64 = 5.0;

/// The figure's value line and its ±1 sigma bars.
const VALUE: Rgb888 = Rgb888::new(0, 200, 230);
const SIGMA: Rgb888 = Rgb888::new(60, 110, 130);
/// A stretch the process cut, behind the plot.
const CUT: Rgb888 = Rgb888::new(80, 28, 32);
const CUT_TEXT: Rgb888 = Rgb888::new(240, 120, 120);
/// The tick under a waypoint the figure was not measured at.
const UNMEASURED: Rgb888 = Rgb888::new(235, 25, 35);

/// One figure the profile can show: its title, its unit, the least span
/// of its axis (so a figure that hardly changes is not shown as noise
/// blown up), and how to read it off a waypoint's figures.
struct Figure {
    title: &'static str,
    unit: &'static str,
    min_span: f64,
    read: fn(&JointFigures) -> Option<Measured>,
}

const FIGURES: [Figure; 4] = [
    Figure { title: "gap", unit: "mm", min_span: 0.5, read: |f| f.gap_mm },
    Figure { title: "high-low", unit: "mm", min_span: 0.5, read: |f| f.high_low_mm },
    Figure { title: "groove cross-section", unit: "mm²", min_span: 5.0, read: |f| f.groove_area_mm2 },
    Figure { title: "lap step", unit: "mm", min_span: 0.5, read: |f| f.lap_step_mm },
];

/// The profiles of `report`'s seams, or None when no seam carries a
/// figure along it.
pub fn render(trace: &PlanTrace, report: &PlanResult) -> Option<Canvas> {
    let blocks: Vec<Canvas> = report.seams.iter().take(MAX_SEAMS_DRAWN).enumerate().filter_map(seam_block).collect();
    if blocks.is_empty() {
        return None;
    }
    let width = PANEL.0;
    let title = title_band(trace, width);
    let legend = legend_band(
        &[
            (VALUE, "measured at a waypoint"),
            (SIGMA, "±1 sigma"),
            (UNMEASURED, "not measured there"),
            (CUT, "cut from the weld (rule)"),
        ],
        width,
    );
    let mut bands = vec![&title];
    bands.extend(blocks.iter());
    bands.push(&legend);
    Some(stack(&bands))
}

/// The distance of each waypoint from the first along the seam, mm.
fn distances(seam: &Seam) -> Vec<f64> {
    let mut along = 0.0;
    let mut out = Vec::with_capacity(seam.waypoints.len());
    for (k, w) in seam.waypoints.iter().enumerate() {
        if k > 0 {
            let p = seam.waypoints[k - 1].xyz;
            along += (0..3).map(|i| (w.xyz[i] - p[i]).powi(2)).sum::<f64>().sqrt();
        }
        out.push(along);
    }
    out
}

/// One seam's panels, a figure each, under a line naming the seam.
fn seam_block((k, seam): (usize, &Seam)) -> Option<Canvas> {
    let figures = seam.along_seam.as_deref()?;
    if figures.len() != seam.waypoints.len() {
        return None;
    }
    let s = distances(seam);
    let panels: Vec<Canvas> = FIGURES
        .iter()
        .filter(|f| figures.iter().any(|x| (f.read)(x).is_some()))
        .map(|f| panel(f, seam, figures, &s))
        .collect();
    if panels.is_empty() {
        return None;
    }
    let joint = serde_json::to_value(seam.joint).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default();
    let procedure = seam.process.as_ref().map_or("no weld procedure configured".to_string(), |p| {
        format!("procedure {}, {} stretch(es) cut", p.procedure, p.cut.len())
    });
    let heading = format!("seam {} ({joint}, {:.1} mm): {procedure}", k + 1, seam.length_mm);
    let line_height = SMALL_FONT.character_size.height + 8;
    let mut head = Canvas::new(PANEL.0, line_height, colour::BACKGROUND);
    head.text(&heading, 6, 4, &SMALL_FONT, colour::TEXT);
    let mut bands = vec![&head];
    bands.extend(panels.iter());
    Some(stack(&bands))
}

/// A step of 1, 2 or 5 times a power of ten giving about [`TICKS`] ticks
/// over `span`.
fn tick_step(span: f64) -> f64 {
    let raw = (span / TICKS).max(f64::MIN_POSITIVE);
    let power = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * power).find(|&step| step >= raw).unwrap_or(10.0 * power)
}

/// The axis range of `values`: their least and greatest with their
/// sigmas, padded, and at least `min_span` wide.
fn value_range(values: &[Measured], min_span: f64) -> (f64, f64) {
    let lo = values.iter().map(|m| m.value - m.sigma).fold(f64::INFINITY, f64::min);
    let hi = values.iter().map(|m| m.value + m.sigma).fold(f64::NEG_INFINITY, f64::max);
    let pad = 0.1 * (hi - lo);
    let (lo, hi) = (lo - pad, hi + pad);
    if hi - lo >= min_span {
        (lo, hi)
    } else {
        let mid = 0.5 * (lo + hi);
        (mid - 0.5 * min_span, mid + 0.5 * min_span)
    }
}

/// One figure against the distance along the seam.
fn panel(figure: &Figure, seam: &Seam, figures: &[JointFigures], s: &[f64]) -> Canvas {
    let mut canvas = Canvas::new(PANEL.0, PANEL.1, colour::BACKGROUND);
    let values: Vec<Option<Measured>> =
        figures.iter().map(figure.read).map(|m| m.filter(|m| m.value.is_finite() && m.sigma.is_finite())).collect();
    let measured: Vec<Measured> = values.iter().flatten().copied().collect();
    let (y0, y1) = value_range(&measured, figure.min_span);
    let s_end = s.last().copied().unwrap_or(0.0).max(1.0);
    let (left, right) = (MARGIN_LEFT, f64::from(PANEL.0) - MARGIN_RIGHT);
    let (top, bottom) = (MARGIN_TOP, f64::from(PANEL.1) - MARGIN_BOTTOM);
    let x = |d: f64| left + (right - left) * d / s_end;
    let y = |v: f64| bottom - (bottom - top) * (v - y0) / (y1 - y0);

    // The cut stretches, behind everything, half a step beyond their ends.
    if let Some(process) = &seam.process {
        for c in &process.cut {
            let (Some(&a), Some(&b)) = (s.get(c.first as usize), s.get(c.last as usize)) else { continue };
            let half = s_end / s.len().max(2) as f64 / 2.0;
            let (xa, xb) = (x((a - half).max(0.0)), x((b + half).min(s_end)));
            canvas.fill_rect(xa as i64, top as i64, (xb - xa).max(2.0) as u32, (bottom - top) as u32, CUT);
            canvas.text(&c.rule, xa as i64 + 2, top as i64 + 2, &SMALL_FONT, CUT_TEXT);
        }
    }
    // Grid and axes, labelled.
    let step = tick_step(y1 - y0);
    let mut v = (y0 / step).ceil() * step;
    while v <= y1 {
        canvas.line((left, y(v)), (right, y(v)), colour::GRID, 1);
        let label = format!("{v:.*}", decimals(step));
        let width = super::canvas::text_width(&label, &SMALL_FONT);
        canvas.text(&label, left as i64 - 4 - i64::from(width), y(v) as i64 - 6, &SMALL_FONT, colour::DIM_TEXT);
        v += step;
    }
    let step = tick_step(s_end);
    let mut d = 0.0;
    while d <= s_end {
        canvas.line((x(d), top), (x(d), bottom), colour::GRID, 1);
        canvas.text(
            &format!("{d:.*}", decimals(step)),
            x(d) as i64 - 8,
            bottom as i64 + 4,
            &SMALL_FONT,
            colour::DIM_TEXT,
        );
        d += step;
    }
    canvas.line((left, bottom), (right, bottom), colour::AXES, 1);
    canvas.line((left, top), (left, bottom), colour::AXES, 1);
    canvas.text("mm along the seam", right as i64 - 110, bottom as i64 + 18, &SMALL_FONT, colour::DIM_TEXT);

    // The sigma bars, then the value line, broken where a waypoint has none.
    for (m, &d) in values.iter().zip(s) {
        match m {
            Some(m) => canvas.line((x(d), y(m.value - m.sigma)), (x(d), y(m.value + m.sigma)), SIGMA, 3),
            None => canvas.line((x(d), bottom - 6.0), (x(d), bottom), UNMEASURED, 2),
        }
    }
    let mut run: Vec<(f64, f64)> = Vec::new();
    for (m, &d) in values.iter().zip(s) {
        match m {
            Some(m) => run.push((x(d), y(m.value))),
            None => draw_run(&mut canvas, &mut run),
        }
    }
    draw_run(&mut canvas, &mut run);

    let median = median_or_nan(measured.iter().map(|m| m.value).collect());
    let sigma = median_or_nan(measured.iter().map(|m| m.sigma).collect());
    let header = format!(
        "{} ({}): median {median:.2}, sigma median {sigma:.2}, measured at {} of {} waypoints",
        figure.title,
        figure.unit,
        measured.len(),
        values.len()
    );
    canvas.text(&header, left as i64, 4, &SMALL_FONT, colour::TEXT);
    canvas
}

/// Draws a run of the value line (a lone point as a dot) and empties it.
fn draw_run(canvas: &mut Canvas, run: &mut Vec<(f64, f64)>) {
    canvas.polyline(run, VALUE, 2);
    for &p in run.iter() {
        canvas.disc(p, 5, VALUE, None);
    }
    run.clear();
}

/// Decimals that show a tick step's digits.
fn decimals(step: f64) -> usize {
    (-step.log10().floor()).clamp(0.0, 3.0) as usize
}

/// The median of `values`, NaN for none.
fn median_or_nan(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Method;
    use crate::joint::JointType;
    use weldseam_proto::along_seam::{CutStretch, SeamProcess};
    use weldseam_proto::plan::{Joint, PointCounts, Waypoint};

    fn seam(figures: Vec<JointFigures>, cut: Vec<CutStretch>) -> Seam {
        let n = figures.len();
        Seam {
            joint: Joint::IButt,
            joint_evidence: None,
            waypoints: (0..n)
                .map(|k| Waypoint { xyz: [5.0 * k as f64, 0.0, 0.0], rpy_deg: [180.0, 0.0, 0.0] })
                .collect(),
            start_camera: [0.0; 3],
            end_camera: [0.0; 3],
            normal_camera: [0.0, 0.0, 1.0],
            length_mm: 5.0 * (n - 1) as f64,
            edge_fit_rms_mm: [0.1; 2],
            edge_samples: [100; 2],
            edge_samples_dropped: [0; 2],
            coverage: None,
            quality: None,
            warnings: vec![],
            along_seam: Some(figures),
            process: Some(SeamProcess { procedure: "test".into(), waypoints: vec![None; n], cut }),
        }
    }

    fn report(seams: Vec<Seam>) -> PlanResult {
        PlanResult {
            seams,
            unplanned: vec![],
            timing_ms: Default::default(),
            method: "robust".into(),
            euler_convention: "zyx".into(),
            points: PointCounts::default(),
        }
    }

    fn count(canvas: &Canvas, ink: Rgb888) -> usize {
        (0..canvas.height())
            .flat_map(|y| (0..canvas.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| canvas.pixel(x, y) == Some(ink))
            .count()
    }

    #[test]
    fn a_gap_opening_along_the_seam_is_drawn_with_its_cut_and_its_holes() {
        let trace = PlanTrace::new(Some(JointType::IButt), None, Method::Robust);
        let figures: Vec<JointFigures> = (0..40)
            .map(|k| JointFigures {
                gap_mm: (k != 7).then_some(Measured { value: 0.5 + 2.5 * k as f64 / 39.0, sigma: 0.05 }),
                high_low_mm: Some(Measured { value: 0.1, sigma: 0.02 }),
                ..JointFigures::default()
            })
            .collect();
        let cut = CutStretch {
            first: 30,
            last: 39,
            rule: "process.outside_procedure".into(),
            reason: "gap 2.5 mm > 2.0".into(),
            contact_camera_mm: None,
        };
        let canvas = render(&trace, &report(vec![seam(figures, vec![cut])])).expect("a profile");
        assert_eq!(canvas.width(), PANEL.0);
        // Two panels (gap, high-low) under the title, above the legend.
        assert!(canvas.height() > 2 * PANEL.1, "{}", canvas.height());
        assert!(count(&canvas, CUT) > 1000, "the cut stretch is shaded in both panels");
        assert!(count(&canvas, VALUE) > 500);
        assert!(count(&canvas, UNMEASURED) > 10, "the waypoint without a gap is ticked");
    }

    #[test]
    fn no_figures_no_profile() {
        let trace = PlanTrace::new(Some(JointType::TFillet), None, Method::Robust);
        let mut bare = seam(vec![JointFigures::default(); 5], vec![]);
        assert!(render(&trace, &report(vec![bare.clone()])).is_none(), "nothing measured");
        bare.along_seam = None;
        assert!(render(&trace, &report(vec![bare])).is_none(), "nothing carried");
    }

    #[test]
    fn ticks_are_one_two_or_five_times_a_power_of_ten() {
        assert_eq!(tick_step(100.0), 20.0);
        assert_eq!(tick_step(3.0), 1.0);
        assert!((tick_step(0.5) - 0.1).abs() < 1e-12);
        assert_eq!(value_range(&[Measured { value: 1.0, sigma: 0.0 }], 0.5), (0.75, 1.25));
    }
}
