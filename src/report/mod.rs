//! Pictures and figures of one plan, from its [`PlanTrace`], for a person
//! to see at a glance what the planner found and why it planned or refused
//! (issue 12): what `weldseam plan --debug DIR` writes and the daemon's
//! `[debug]` section keeps.
//!
//! - [`camera_view`]: the frame as the camera saw it (an organized frame
//!   pixel by pixel, any other cloud looked at along the plates' normal),
//!   depth-shaded, the plates in two colours, the edge points, the RANSAC
//!   lines, the fitted weld edges, the seam and its waypoints, and a title
//!   with the joint and the result or the refusal's reason;
//! - [`sections`]: profiles across the seam at four stations, the points
//!   of a thin slab plotted as offset across the seam against height along
//!   the normal, in millimetres at one scale on both axes, with the weld
//!   edges, the planned point and, in a V-groove, its deepest point seen;
//! - [`profile`]: the joint's figures along the seam (gap, high-low,
//!   groove cross-section, lap step) against the distance along it, with
//!   their standard errors and the stretches the weld process cut, drawn
//!   from the plan's report when it carries them;
//! - `trace.json`: the figures of every stage
//!   ([`crate::convert::to_proto::plan_trace`]).
//!
//! Rendering is pure: a trace in, RGB pictures and bytes out
//! ([`debug_set`]); writing them is the caller's (`src/cli/plan.rs`,
//! [`crate::debug_dir`]).

pub mod camera_view;
pub mod canvas;
pub mod profile;
pub mod sections;

use embedded_graphics::mono_font::MonoFont;
use embedded_graphics::mono_font::iso_8859_1::{FONT_6X13, FONT_9X15};
use embedded_graphics::pixelcolor::Rgb888;
use weldseam_proto::plan::PlanResult;

use crate::convert::to_proto;
use crate::joint::JointType;
use crate::pipeline::PlanTrace;

pub use canvas::Canvas;

/// The colours of the pictures, chosen to stay apart for the common forms
/// of colour blindness (blue against orange) and against the grey depth.
pub mod colour {
    use embedded_graphics::pixelcolor::Rgb888;

    pub const BACKGROUND: Rgb888 = Rgb888::new(24, 24, 28);
    pub const TEXT: Rgb888 = Rgb888::new(240, 240, 240);
    pub const DIM_TEXT: Rgb888 = Rgb888::new(170, 170, 175);
    pub const TITLE_PLANNED: Rgb888 = Rgb888::new(20, 60, 30);
    pub const TITLE_REFUSED: Rgb888 = Rgb888::new(130, 20, 20);
    /// Plate 1 and plate 2 (for a lap, the upper plate first).
    pub const PLATES: [Rgb888; 2] = [Rgb888::new(60, 130, 230), Rgb888::new(240, 150, 40)];
    /// Each plate's edge points, darker than the plate.
    pub const EDGE_POINTS: [Rgb888; 2] = [Rgb888::new(10, 30, 110), Rgb888::new(120, 50, 0)];
    /// The plane clusters not chosen as plates, by label in turn: muted,
    /// apart from each other and from the plates' blue and orange.
    pub const OTHER_PLANES: [Rgb888; 5] = [
        Rgb888::new(120, 175, 150),
        Rgb888::new(165, 145, 200),
        Rgb888::new(175, 175, 110),
        Rgb888::new(200, 135, 150),
        Rgb888::new(115, 165, 195),
    ];
    /// Points the plane criterion passed that no plane cluster kept.
    pub const PLANE_POINT: Rgb888 = Rgb888::new(165, 165, 150);
    /// Every other valid point.
    pub const OTHER_POINT: Rgb888 = Rgb888::new(150, 150, 160);
    pub const RANSAC_LINE: Rgb888 = Rgb888::new(235, 235, 235);
    pub const PICKED_LINE: Rgb888 = Rgb888::new(255, 230, 0);
    pub const WELD_EDGE: Rgb888 = Rgb888::new(0, 220, 110);
    pub const SEAM: Rgb888 = Rgb888::new(235, 25, 35);
    pub const WAYPOINT: Rgb888 = Rgb888::new(255, 255, 255);
    pub const ROOT_SEEN: Rgb888 = Rgb888::new(190, 60, 230);
    pub const AXES: Rgb888 = Rgb888::new(120, 120, 128);
    pub const GRID: Rgb888 = Rgb888::new(48, 48, 54);
}

/// The title font and the small font of legends, labels and axes: bitmap
/// fonts compiled into embedded-graphics, Latin-1 (for ° and ²).
const TITLE_FONT: MonoFont = FONT_9X15;
const SMALL_FONT: MonoFont = FONT_6X13;

/// What a point of the traced frame was found to be, for its colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointClass {
    Invalid,
    Other,
    PlanePoint,
    /// A plane cluster not chosen as a plate, by its place in the trace.
    OtherPlane(usize),
    Plate(usize),
    Edge(usize),
}

impl PointClass {
    fn colour(self) -> Option<Rgb888> {
        match self {
            PointClass::Invalid => None,
            PointClass::Other => Some(colour::OTHER_POINT),
            PointClass::PlanePoint => Some(colour::PLANE_POINT),
            PointClass::OtherPlane(k) => Some(colour::OTHER_PLANES[k % colour::OTHER_PLANES.len()]),
            PointClass::Plate(k) => Some(colour::PLATES[k]),
            PointClass::Edge(k) => Some(colour::EDGE_POINTS[k]),
        }
    }
}

/// Each point's class, by index into the trace's cloud: later stages
/// refine earlier ones (an edge point is a plate's, a plate is a plane).
pub fn classify(trace: &PlanTrace) -> Vec<PointClass> {
    let Some(cloud) = &trace.cloud else { return Vec::new() };
    let mut classes: Vec<PointClass> =
        cloud.points().iter().map(|p| if p[0].is_finite() { PointClass::Other } else { PointClass::Invalid }).collect();
    let mut mark = |indices: &mut dyn Iterator<Item = usize>, class: PointClass| {
        for i in indices {
            if let Some(c) = classes.get_mut(i) {
                *c = class;
            }
        }
    };
    mark(&mut trace.plane_points.iter().enumerate().filter(|(_, p)| **p).map(|(i, _)| i), PointClass::PlanePoint);
    for (k, plane) in trace.planes.iter().enumerate() {
        mark(&mut plane.members.iter().map(|&i| i as usize), PointClass::OtherPlane(k));
    }
    for k in 0..2 {
        if let Some(plate) = trace.plate(k) {
            mark(&mut plate.members.iter().map(|&i| i as usize), PointClass::Plate(k));
        }
        mark(&mut trace.edge_points[k].iter().map(|&i| i as usize), PointClass::Edge(k));
    }
    classes
}

/// The first line of each picture's title: the joint asked for, the
/// method and what came of it.
fn headline(trace: &PlanTrace) -> String {
    let joint = match trace.joint {
        Some(JointType::VButt) => "V-butt",
        Some(JointType::IButt) => "I-butt",
        Some(JointType::Lap) => "Lap",
        Some(JointType::TFillet) => "Tee",
        None => "Joint auto, not decided",
    };
    let depth = trace.groove_depth_mm.map(|d| format!(" (groove depth {d} mm)")).unwrap_or_default();
    let method = trace.method.name();
    match (&trace.refusal, &trace.weld) {
        (Some(e), _) => format!("{joint} joint{depth}, {method} method: REFUSED at the {} stage", e.stage),
        (None, Some(weld)) => format!(
            "{joint} joint{depth}, {method} method: seam of {:.1} mm, {} waypoints",
            weld.length_mm(),
            trace.waypoints_camera.len()
        ),
        (None, None) => format!("{joint} joint{depth}, {method} method"),
    }
}

/// The second part of the title: the refusal's rule and reason, or the
/// figures a welding engineer checks first and each warning's rule and
/// message.
fn detail(trace: &PlanTrace) -> String {
    if let Some(e) = &trace.refusal {
        return format!("{}: {}", e.rule.id, e.reason);
    }
    let mut parts = Vec::new();
    if let Some(fits) = &trace.weld_edges {
        parts.push(format!(
            "edge fits {:.3} / {:.3} mm rms over {} / {} samples",
            fits[0].rms_mm, fits[1].rms_mm, fits[0].points_used, fits[1].points_used
        ));
    }
    if let Some(q) = &trace.quality {
        if let Some(g) = q.gap_mm {
            // A V-groove's edges are its top corners, not the root gap.
            let name = if trace.joint == Some(JointType::VButt) { "groove top" } else { "gap" };
            parts.push(format!("{name} {:.2} to {:.2} mm", g.min, g.max));
        }
        if let Some(h) = q.misalignment_mm {
            parts.push(format!("high-low {h:.2} mm"));
        }
        if let Some(step) = q.lap_step_mm {
            parts.push(format!("lap step {step:.2} mm"));
        }
        parts.push(format!("position ±{:.2} mm (1 sigma)", q.uncertainty_across_mm));
    }
    parts.extend(trace.warnings.iter().map(|w| format!("warning {}: {}", w.rule.id, w.message)));
    parts.join("; ")
}

/// What the plates are called in the legends: a lap's are one over the
/// other.
fn plate_names(joint: Option<JointType>) -> [&'static str; 2] {
    match joint {
        Some(JointType::Lap) => ["upper plate", "lower plate"],
        _ => ["plate 1", "plate 2"],
    }
}

/// A title band across `width` pixels: the headline, then `detail`
/// wrapped, on green for a plan and red for a refusal.
fn title_band(trace: &PlanTrace, width: u32) -> Canvas {
    const PAD: u32 = 6;
    let line_height = TITLE_FONT.character_size.height + 3;
    let chars = ((width - 2 * PAD) / (TITLE_FONT.character_size.width + TITLE_FONT.character_spacing)) as usize;
    let mut lines = canvas::wrap(&headline(trace), chars);
    let detail_lines = canvas::wrap(&detail(trace), chars);
    let first_detail = lines.len();
    lines.extend(detail_lines);
    let band = if trace.refusal.is_some() { colour::TITLE_REFUSED } else { colour::TITLE_PLANNED };
    let mut canvas = Canvas::new(width, 2 * PAD + line_height * lines.len() as u32, band);
    for (k, line) in lines.iter().enumerate() {
        let ink = if k < first_detail || trace.refusal.is_some() { colour::TEXT } else { colour::DIM_TEXT };
        canvas.text(line, PAD.into(), (PAD + line_height * k as u32).into(), &TITLE_FONT, ink);
    }
    canvas
}

/// A legend band across `width` pixels: a swatch and a name per entry,
/// wrapped onto as many rows as it takes.
fn legend_band(entries: &[(Rgb888, &str)], width: u32) -> Canvas {
    const PAD: i64 = 6;
    const SWATCH: u32 = 11;
    let row_height = SMALL_FONT.character_size.height as i64 + 6;
    let place = |canvas: Option<&mut Canvas>| {
        let (mut x, mut y) = (PAD, PAD);
        let mut canvas = canvas;
        for (ink, name) in entries {
            let entry_width = i64::from(SWATCH) + 5 + i64::from(canvas::text_width(name, &SMALL_FONT)) + 16;
            if x > PAD && x + entry_width > i64::from(width) - PAD {
                (x, y) = (PAD, y + row_height);
            }
            if let Some(c) = canvas.as_deref_mut() {
                c.fill_rect(x, y + 1, SWATCH, SWATCH, *ink);
                c.text(name, x + i64::from(SWATCH) + 5, y, &SMALL_FONT, colour::TEXT);
            }
            x += entry_width;
        }
        y + row_height
    };
    let height = place(None) + PAD / 2;
    let mut canvas = Canvas::new(width, height as u32, colour::BACKGROUND);
    place(Some(&mut canvas));
    canvas
}

/// Stacks bands of one width top to bottom.
fn stack(bands: &[&Canvas]) -> Canvas {
    let width = bands.iter().map(|b| b.width()).max().unwrap_or(1);
    let height = bands.iter().map(|b| b.height()).sum::<u32>().max(1);
    let mut canvas = Canvas::new(width, height, colour::BACKGROUND);
    let mut y = 0;
    for band in bands {
        canvas.paste(band, 0, y);
        y += i64::from(band.height());
    }
    canvas
}

/// The pictures of one plan.
#[derive(Debug, Clone)]
pub struct Pictures {
    pub camera_view: camera_view::CameraView,
    /// Present when a weld was found, refused or not.
    pub sections: Option<Canvas>,
}

/// Draws the pictures of `trace`.
pub fn render(trace: &PlanTrace) -> Pictures {
    let classes = classify(trace);
    Pictures { camera_view: camera_view::render(trace, &classes), sections: sections::render(trace, &classes) }
}

/// The file names of a debug set.
pub const CAMERA_VIEW_FILE: &str = "camera.png";
pub const SECTIONS_FILE: &str = "sections.png";
pub const PROFILE_FILE: &str = "profile.png";
pub const FIGURES_FILE: &str = "trace.json";

/// One plan's pictures and figures as files' bytes, ready to write.
#[derive(Debug, Clone, PartialEq)]
pub struct DebugSet {
    pub files: Vec<(&'static str, Vec<u8>)>,
}

/// Why a debug set could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot encode {file}: {source}")]
    Png {
        file: &'static str,
        #[source]
        source: png::EncodingError,
    },
    #[error("cannot encode {FIGURES_FILE}: {0}")]
    Json(#[from] serde_json::Error),
}

/// The pictures and figures of `trace` as files: the camera view, the
/// sections when there is a weld, the profiles along the seam when
/// `report` carries the figures along its seams, and the figures with
/// `report` (the plan as `plan --json` prints it) when the plan succeeded.
pub fn debug_set(trace: &PlanTrace, report: Option<PlanResult>) -> Result<DebugSet, ReportError> {
    let pictures = render(trace);
    let png = |file: &'static str, canvas: &Canvas| {
        canvas.encode_png().map(|bytes| (file, bytes)).map_err(|source| ReportError::Png { file, source })
    };
    let mut files = vec![png(CAMERA_VIEW_FILE, &pictures.camera_view.canvas)?];
    if let Some(sections) = &pictures.sections {
        files.push(png(SECTIONS_FILE, sections)?);
    }
    if let Some(profile) = report.as_ref().and_then(|r| profile::render(trace, r)) {
        files.push(png(PROFILE_FILE, &profile)?);
    }
    let figures = serde_json::to_vec_pretty(&to_proto::plan_trace(trace, report))?;
    files.push((FIGURES_FILE, figures));
    Ok(DebugSet { files })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Method;
    use crate::pipeline::PlanError;
    use crate::pipeline::quality::{Gate, GateFailure};
    use crate::rules;

    #[test]
    fn the_title_and_the_figures_name_the_rule_of_a_refusal_and_of_a_warning() {
        let mut refused = PlanTrace::new(Some(JointType::Lap), None, Method::Robust);
        refused.refusal = Some(PlanError::by(&rules::input::NO_VALID_POINT, "no point in the camera's volume"));
        assert_eq!(detail(&refused), "frame.no_valid_point: no point in the camera's volume");
        let set = debug_set(&refused, None).unwrap();
        let (_, figures) = set.files.iter().find(|(name, _)| *name == FIGURES_FILE).unwrap();
        let figures: serde_json::Value = serde_json::from_slice(figures).unwrap();
        assert_eq!(figures["error"]["rule"].as_str(), Some("frame.no_valid_point"), "{figures}");

        let mut warned = PlanTrace::new(Some(JointType::Lap), None, Method::Robust);
        let rule = &rules::quality::JOINT_COVERAGE;
        warned.warnings.push(GateFailure {
            rule,
            gate: Gate::JointCoverage,
            value: 0.5,
            limit: 0.8,
            message: "the seam spans 50 % of the joint".into(),
        });
        assert!(
            detail(&warned).ends_with("warning seam.joint_coverage: the seam spans 50 % of the joint"),
            "{}",
            detail(&warned)
        );
    }
}
