//! The groove probe: what lies between a butt joint's two weld edges, and
//! how deep a V-groove is (issue 12, items 3 to 6).
//!
//! The paper takes the joint type and the groove depth `d` of Eq. 32,
//! `f_V = (f_E1 + f_E2) / 2 + d n_V`, on trust: a wrong `d` moves every
//! waypoint by the difference, and an I-butt planned as a V-butt sinks the
//! torch into a gap that has no groove. The cloud says which it is. In the
//! seam's axes (`s` along it, `t` across from the midline of the two
//! fitted edges, `h` along the plate normal below the edges' mean height),
//! the points between the edges are:
//!
//! - on a V-groove's two bevel faces: `|t| = w - h tan α` for
//!   `0 <= h <= d`, where `w` is half the groove's opening at the top and
//!   `α` each face's angle from the normal (half the groove angle); below
//!   `d` the root faces stand vertical, `|t| = g / 2` for a root gap `g`;
//! - on a square gap's walls: `|t| = w` at every depth (`α = 0`), or none
//!   at all where the gap is narrower than the point spacing;
//! - on a plate standing between the edges (a tee joint's web on its
//!   flange): far above the plates, `h << 0`, all along the seam.
//!
//! So each side's points are fitted as `|t| = c - h tan α` (least squares
//! after a robust start from the median `|t|` per depth bin, outliers
//! trimmed): a face at `α` between 10 and 60 degrees is a bevel, one at
//! nearly zero a wall.
//!
//! The depth: where a root gap leaves a root face standing along the
//! normal below the bevel and the camera sees it, the median `|t|` of each
//! depth bin runs down the bevel's line and then stays at `g / 2`; the
//! hinge that fits the bins best splits the two, and the depth is where
//! the bevel's line meets `|t| = g / 2`. Where no root face is seen (a
//! camera looking straight down, a zero root gap), the bevel's foot is the
//! `|t|` of the kept point nearest the midline at each station along the
//! seam, median over the stations, read on the fitted line: points thin
//! out towards the bottom of a groove (less light reaches it), so only
//! the foot, not the spread of depths, says where the face ends. A face
//! whose lower part the near plate hides from the camera ends higher, and
//! its foot then lies far from the midline: only a face whose foot comes
//! within half the widest root gap of the midline, and where no ray past
//! the other plate's edge from the camera or the projector meets it, is
//! taken to show the root.
//!
//! A groove may end in a flat root land instead of a sharp root: the
//! bevels run down to a narrow floor parallel to the plates, which the
//! background stage finds as a surface seen only between the plates. The
//! probe stops above it, so each bevel reaches the probe's bottom; that
//! bottom is then the groove's own, and a bevel whose foot lies on it,
//! near enough the midline for the land to be narrow beside the groove's
//! opening, shows the root at the land's depth.
//!
//! Where the weld goes. The paper's rule (Eq. 32) places a V-groove's
//! weld from its top edges, their midline sunk by the depth; it holds
//! where the edges are straight lines a machine cut. A groove cut by hand
//! or by a torch has top edges that scatter millimetres (coboweld/barpoints:
//! 4 to 5 mm) or step back along part of the seam, while its flanks run
//! clean to a root that did not move. The robust rule reads the root from
//! the flanks: each face is also fitted station by station along the seam
//! (its own slope where its points there span depth enough), and the root
//! lies midway between the two faces' feet at the groove's depth (where a
//! sharp V's flanks meet, the middle of a root land or of a root gap); a
//! line through those midpoints is the root ([`RootLine`], [`root`]), and
//! their scatter about it, a step between two runs of them and the share
//! of the seam where both flanks show it are the root's own evidence. The
//! planner welds on it, and judges that evidence by the gates a top edge's
//! samples would face, when the top edges fail those gates
//! (`groove.weld_on_bevel_midline`).
//!
//! The stage's files, each one concern: [`points`] reads the points
//! between the edges (the pixels under the probed box, those on a
//! surface), [`fit`] fits each side's face and finds its depth,
//! [`profile`] is what was found and what it says the joint is, [`root`]
//! the root the flanks place, and [`error`] why a joint is refused; this
//! file holds the entry points, [`probe`] and [`judge`].

mod error;
mod fit;
mod points;
mod profile;
mod root;
#[cfg(test)]
mod tests;

use rayon::prelude::*;

use crate::cloud::{Point, PointCloud, is_valid_point};
use crate::geometry::{Vec3, vec3};
use crate::joint::JointType;
use crate::rules;

use super::context::CameraGrid;
use super::gather::gather_filter_map;
use super::refit::SeamCurve;

pub use error::GrooveError;
pub use profile::{Between, Face, GrooveProfile, LineAlong, Standing, StationLine};
pub use root::RootLine;

use fit::{Views, fit_face};
use points::{Across, STATIONS, SURFACE_RADIUS_SPACINGS, on_surfaces, rows_under, station_share};

/// Points nearer the plates' top than this, in point spacings, are the
/// plates' own rims and noise, not a face.
const TOP_MARGIN_SPACINGS: f64 = 1.0;
/// ... and never nearer than this, mm.
const MIN_TOP_MARGIN_MM: f64 = 0.3;

/// The deepest groove probed below the plates, mm, when the surface they
/// rest on is not seen (then the probe stops half a millimetre above it).
const MAX_PROBE_DEPTH_MM: f64 = 60.0;

/// Something standing this far above the plates between the edges, along
/// much of the seam, is a plate, not a tack or spatter: a weld bead or a
/// tack stands 1 to 3 mm proud.
const STANDING_MIN_MM: f64 = 5.0;

/// How far above the plates the probe looks for a plate standing between
/// the edges: a tee's web is taller, and its lower part tells.
const STANDING_PROBE_MM: f64 = 150.0;

/// What the probe needs besides the cloud.
#[derive(Debug, Clone, Copy)]
pub struct ProbeSetting<'a> {
    /// The two weld edges, fitted on shared axes (`a` across, `b` along the
    /// plate normal, away from the camera).
    pub edges: [&'a SeamCurve; 2],
    /// The stretch along the seam's feature axis both edges were seen.
    pub span: (f64, f64),
    pub point_spacing_mm: f64,
    /// How far below the plates' top the surface they rest on lies.
    pub depth_to_support_mm: Option<f64>,
    /// Whether that surface is seen only between the plates: then it is
    /// the groove's own floor (a root land at the bevels' foot, or what
    /// shows through the root gap), where a face running down to it ends
    /// at the root, not a surface behind the plates that cuts the probe
    /// short.
    pub floor_between_plates: bool,
    /// The frame's pixel grid, when it lies on the configured camera's:
    /// then only the pixels the probed box projects onto are read, not the
    /// whole frame.
    pub(super) grid: Option<&'a CameraGrid<'a>>,
    /// Where the structured-light projector sits in the camera frame: a
    /// point it does not light is not measured, so its shadow ends a face
    /// as the camera's own view does. The camera's origin for a sensor
    /// without one.
    pub projector: Vec3,
}

/// The butt joint the profile shows, checked against the one requested
/// (None: `auto`). A V-butt joint needs bevel faces between its edges and
/// an I-butt joint must show none; a plate standing between them is
/// neither; points that fit nothing are refused only when the planner must
/// decide, or when a V-groove was requested and its faces are not seen.
pub fn judge(requested: Option<JointType>, profile: &GrooveProfile) -> Result<JointType, GrooveError> {
    let described = || profile.describe();
    let judged = match (profile.verdict(), requested) {
        (Between::StandingPlate(s), _) => Err(GrooveError::LooksLikeTee {
            height_mm: s.height_mm,
            share: 100.0 * s.station_share,
            profile: described(),
        }),
        (Between::Groove, Some(JointType::IButt)) => Err(GrooveError::LooksLikeVButt { profile: described() }),
        (Between::Groove, _) => Ok(JointType::VButt),
        (Between::SquareGap | Between::Unclear, Some(JointType::VButt)) => {
            Err(GrooveError::LooksLikeIButt { profile: described() })
        }
        (Between::SquareGap, _) => Ok(JointType::IButt),
        (Between::Unclear, Some(joint)) => Ok(joint),
        (Between::Unclear, None) => Err(GrooveError::Unclear { profile: described() }),
    };
    if let (None, Ok(joint)) = (requested, &judged) {
        tracing::debug!(rule = rules::groove::TYPE_FROM_GROOVE.id, %joint, "the butt joint named from its groove");
    }
    judged
}

/// Probes the points between the two weld edges.
pub fn probe(cloud: &PointCloud, setting: &ProbeSetting) -> GrooveProfile {
    let [e1, e2] = setting.edges;
    let axes = e1.axes;
    let (s0, s1) = setting.span;
    let spacing = setting.point_spacing_mm;
    let top_margin = (TOP_MARGIN_SPACINGS * spacing).max(MIN_TOP_MARGIN_MM);
    let bottom = setting.depth_to_support_mm.map_or(MAX_PROBE_DEPTH_MM, |d| (d - 0.5).min(MAX_PROBE_DEPTH_MM));
    let station_len = (s1 - s0) / STATIONS as f64;
    let floor_mm = setting.depth_to_support_mm.filter(|_| setting.floor_between_plates);

    // The box the probed points lie in, from the two edges at stations
    // along the span: across, the band both edges span (a millimetre
    // wider, for the rounding); along the normal, from the standing
    // probe's height above the edges' mean height to the bottom below it.
    let (band, heights) = {
        let samples = (0..=16).map(|k| s0 + (s1 - s0) * k as f64 / 16.0);
        let widen = |(lo, hi): (f64, f64), v: f64| (lo.min(v), hi.max(v));
        let empty = (f64::INFINITY, f64::NEG_INFINITY);
        let (across, height) = samples.fold((empty, empty), |(across, height), s| {
            let (q1, q2) = (e1.at(s) - axes.origin, e2.at(s) - axes.origin);
            let across = widen(widen(across, q1.dot(&axes.a)), q2.dot(&axes.a));
            (across, widen(height, 0.5 * (q1.dot(&axes.b) + q2.dot(&axes.b))))
        });
        ((across.0 - 1.0, across.1 + 1.0), (height.0 - STANDING_PROBE_MM - 1.0, height.1 + bottom + 1.0))
    };
    // A cheap first test in single precision: along the seam within its
    // span, across it within the band; only the points that pass are read
    // in the seam's axes exactly.
    let f32s = |v: &Vec3| [v.x as f32, v.y as f32, v.z as f32];
    let (origin, along, across) = (f32s(&axes.origin), f32s(&axes.e), f32s(&axes.a));
    let (span32, band32) = ((s0 as f32 - 1.0, s1 as f32 + 1.0), (band.0 as f32, band.1 as f32));
    let near_seam = |p: &[f32; 3]| {
        let d = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
        let s = d[0] * along[0] + d[1] * along[1] + d[2] * along[2];
        let a = d[0] * across[0] + d[1] * across[1] + d[2] * across[2];
        // NaN (an invalid pixel) fails both.
        (span32.0..=span32.1).contains(&s) && (band32.0..=band32.1).contains(&a)
    };
    let read = |p: &Point| -> Option<Across> {
        if !(near_seam(p) && is_valid_point(p)) {
            return None;
        }
        let d = vec3(p) - axes.origin;
        let s = d.dot(&axes.e);
        if !(s0..s1).contains(&s) {
            return None;
        }
        let (q1, q2) = (e1.at(s) - axes.origin, e2.at(s) - axes.origin);
        let (a1, a2) = (q1.dot(&axes.a), q2.dot(&axes.a));
        let half = 0.5 * (a2 - a1).abs();
        let sign = (a2 - a1).signum();
        let t = (d.dot(&axes.a) - 0.5 * (a1 + a2)) * sign;
        // Strictly between the edges: the plates' own boundary points lie
        // on them.
        if t.abs() >= half - 0.5 * spacing {
            return None;
        }
        let h = d.dot(&axes.b) - 0.5 * (q1.dot(&axes.b) + q2.dot(&axes.b));
        let station = (((s - s0) / station_len) as usize).min(STATIONS - 1);
        let standing = (-STANDING_PROBE_MM..-STANDING_MIN_MM).contains(&h);
        (standing || (top_margin..bottom).contains(&h)).then_some(Across { s, station, t, h })
    };
    // On the camera's grid only the pixels under the probed box are read:
    // it projects inside the convex hull of its corners.
    let corners: Vec<Vec3> = (0..8)
        .map(|k| {
            let s = if k & 1 == 0 { s0 - 1.0 } else { s1 + 1.0 };
            let a = if k & 2 == 0 { band.0 } else { band.1 };
            let b = if k & 4 == 0 { heights.0 } else { heights.1 };
            axes.origin + axes.e * s + axes.a * a + axes.b * b
        })
        .collect();
    let points = cloud.points();
    let collected: Vec<Across> = match setting.grid.and_then(|grid| rows_under(grid, &corners)) {
        Some(rows) => {
            let width = cloud.width();
            rows.par_iter()
                .flat_map_iter(|&(v, u0, u1)| points[v * width + u0..=v * width + u1].iter().filter_map(read))
                .collect()
        }
        None => gather_filter_map(points, |_, p| read(p)),
    };
    let mut collected = on_surfaces(collected, SURFACE_RADIUS_SPACINGS * spacing);

    // The camera's rays at the seam's middle, as a slope across the seam
    // (dt/dh): the camera sits at the frame's origin.
    let middle = 0.5 * (s0 + s1);
    let (q1, q2) = (e1.at(middle), e2.at(middle));
    let sign = ((q2 - q1).dot(&axes.a)).signum();
    let slope_from = |eye: Vec3| {
        let ray = 0.5 * (q1 + q2) - eye;
        sign * ray.dot(&axes.a) / ray.dot(&axes.b)
    };
    let view = Views { camera: slope_from(Vec3::zeros()), projector: slope_from(setting.projector) };
    let half_opening = 0.5 * (q2 - q1).dot(&axes.a).abs();

    // The points above the edges, taken out in their order.
    let above: Vec<Across> = collected.extract_if(.., |p| p.h < 0.0).collect();
    let standing = (!above.is_empty()).then(|| Standing {
        points: above.len(),
        height_mm: above.iter().map(|p| -p.h).fold(0.0, f64::max),
        station_share: station_share(&above),
    });
    drop(above);
    let points_below = collected.len();
    let faces = [-1i8, 1]
        .into_iter()
        .filter_map(|side| {
            // The side's points, by reference: a copy of each side cost
            // the groove's points over again.
            let on_side = |p: &&Across| p.t.signum() as i8 == side;
            let mut points: Vec<&Across> = Vec::with_capacity(collected.iter().filter(on_side).count());
            points.extend(collected.iter().filter(on_side));
            fit_face(&points, side, spacing, (top_margin, bottom, floor_mm), &view, half_opening, middle)
        })
        .collect();
    GrooveProfile {
        point_spacing_mm: spacing,
        opening_mm: 2.0 * half_opening,
        points_below,
        faces,
        standing,
        span: (s0, s1),
    }
}
