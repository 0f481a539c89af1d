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

use rayon::prelude::*;

use crate::cloud::{Point, PointCloud, is_valid_point};
use crate::geometry::{MAD_PER_SIGMA, Vec3, extent, vec3};
use crate::joint::JointType;

use super::context::CameraGrid;
use super::gather::gather_filter_map;
use super::refit::SeamCurve;

/// A face between these angles from the plate normal is a bevel: V-groove
/// bevels are 15 to 45 degrees (groove angles of 30 to 90), and a square
/// gap's wall, seen through noise, a few degrees at most.
const MIN_BEVEL_DEG: f64 = 10.0;
const MAX_BEVEL_DEG: f64 = 60.0;

/// The flattest face whose top line places a groove's edge, degrees from
/// the plate normal ([`GrooveProfile::bevel_midline_offset`]): a groove
/// judged a V may still have bevels past [`MAX_BEVEL_DEG`] (a 124° groove
/// is 62° a side); one within 15° of the plates' own plane is hardly a
/// face beside their noise.
const MAX_SLOPED_FACE_DEG: f64 = 75.0;

/// How far inside the probe's cut at the edges given, in sigmas of a
/// face's fit across the seam, its points must lie to place its top
/// ([`Face::top`]): nearer the cut, noise has taken out the points it
/// moved outward and left those it moved in.
const TOP_CUT_SIGMAS: f64 = 2.5;

/// The fewest points a face is fitted from, and the least share of the
/// seam's stations it must be seen at: a face is seen along the seam, not
/// in one spot, as spatter or a tack is.
const MIN_FACE_POINTS: usize = 30;
const MIN_STATION_SHARE: f64 = 0.3;

/// The stations the seam is cut into to count where something is seen.
const STATIONS: usize = 32;

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

/// The widest root gap a V-groove has, mm: a face whose foot lies further
/// than half of it from the midline did not show its lower end.
const MAX_ROOT_GAP_MM: f64 = 4.0;

/// The inlier band of a face fit, in robust sigmas of its residuals, and
/// its floor in point spacings.
const TRIM_SIGMA: f64 = 2.5;
const MIN_BAND_SPACINGS: f64 = 0.5;

/// A face whose direction across the seam lies within this many degrees of
/// the camera's rays is no face: a face along the rays is edge-on and
/// invisible, and what lines up with them there is the veil of mixed
/// pixels a depth jump leaves (depths between the near and the far
/// surface along one pixel's ray).
const RAY_ALIGNED_DEG: f64 = 8.0;

/// A point on a surface has other points around it; one of a veil of
/// mixed pixels has only its own row's neighbours at unrelated depths. The
/// points between the edges with fewer than this many others within
/// [`SURFACE_RADIUS_SPACINGS`] are dropped before any fit.
const MIN_SURFACE_NEIGHBOURS: usize = 4;
const SURFACE_RADIUS_SPACINGS: f64 = 2.0;

/// A root face is taken as seen below a bevel when at least this many
/// depth bins (point spacings) of it are, under at least this many of the
/// bevel, and a hinge fits the bins' medians with at most this share of
/// one line's squared residual.
const MIN_ROOT_BINS: usize = 3;
const MIN_BEVEL_BINS: usize = 3;
const HINGE_GAIN: f64 = 0.5;
/// A bevel runs down into its root face: the bevel's line meets the
/// root face's `|t|` where the bins turn from one to the other, within
/// this many depth bins. A few bins of nearly one `|t|` far out from the
/// bevel's foot (stray returns under it) are no root face: the bevel's
/// line meets them far above where the bins turn, and a depth read there
/// would be that much too shallow.
const HINGE_MEET_BINS: f64 = 2.0;
/// The most depth bins in a row a face may leave empty (fewer than three
/// points) and still run on below them. Under a specular streak at 1 mm
/// voxels (fault-streaks-v-butt-00), returns 13 to 16 mm down, under a
/// run of empty bins below a groove 9.6 mm deep, were taken for its root
/// face, and the root read at 5.25 mm.
const MAX_EMPTY_BINS: usize = 1;

/// How far below a face's foot the opposite plate's shadow may begin and
/// still be what ends the face, mm: the foot is read to a few tenths.
const OCCLUSION_MARGIN_MM: f64 = 0.5;

/// The share of the stations along the seam whose bevel foot is taken as
/// the face's: the groove's bottom is hidden or unlit at some stations
/// (the camera's rays lean differently along the seam), seen at others.
const FOOT_QUANTILE: f64 = 0.1;

/// How far the weld edges' distance may stray from the opening the bevels
/// and the depth give a V-groove: this many millimetres and this share of
/// the widest opening (the angles are fitted, not known), before the edges
/// are taken for something else's.
const OPENING_SLACK_MM: f64 = 1.0;
const OPENING_SLACK_SHARE: f64 = 0.15;

/// A face whose foot comes within this many point spacings of the probe's
/// bottom may go on below it: its foot is not taken for the root.
const BOTTOM_MARGIN_SPACINGS: f64 = 2.0;

/// A face fit whose residual RMS exceeds this many point spacings is not a
/// plane face.
const MAX_FACE_RMS_SPACINGS: f64 = 1.0;

/// How far above the plates the probe looks for a plate standing between
/// the edges: a tee's web is taller, and its lower part tells.
const STANDING_PROBE_MM: f64 = 150.0;
/// How near the camera, along its axis, a corner of the probed box may come
/// before the box is not projected (the whole frame is read instead).
const MIN_PROJECTED_DEPTH_MM: f64 = 10.0;
/// How many pixels the projected box is widened by each way: a point's
/// pixel is its projection rounded, and the box's margins are a millimetre.
const PIXEL_MARGIN: f64 = 2.0;

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

/// One side's face between the edges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// -1 for the side of the first weld edge, +1 for the second's.
    pub side: i8,
    /// The points the fit kept.
    pub points: usize,
    /// The face's angle from the plate normal, degrees (`α`).
    pub angle_deg: f64,
    /// The fit's RMS residual, mm.
    pub rms_mm: f64,
    /// How deep the face goes below the plates' top, mm: where it meets
    /// the root face below it, or its foot.
    pub depth_mm: f64,
    /// How far from the midline its foot lies, mm.
    pub foot_mm: f64,
    /// The share of the seam's stations it was seen at.
    pub station_share: f64,
    /// Whether the face runs along the camera's rays (a veil, not a face).
    pub along_rays: bool,
    /// Whether the camera's rays past the opposite plate's edge meet the
    /// face at its foot: then the plate hides the face's lower part, and
    /// the foot is where the view ends, not the root.
    pub foot_hidden: bool,
    /// Whether the face runs down to the deepest points the probe reads
    /// (the surface the plates seem to rest on, which in a frame of several
    /// parts may be another part's plate): its foot is the probe's, not
    /// the root.
    pub foot_at_probe_bottom: bool,
    /// Where the face meets the plates' top (`h = 0`), as a line of `|t|`
    /// along the seam.
    pub top: LineAlong,
}

/// A distance across the seam that changes linearly along it: a bevel's
/// top ([`Face::top`]) or how far the bevels' midline lies from the weld
/// edges' ([`GrooveProfile::bevel_midline_offset`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineAlong {
    /// The middle of the span probed along the seam, mm.
    pub middle_s: f64,
    /// The distance there, mm.
    pub at_middle_mm: f64,
    /// Its change per mm along the seam.
    pub per_mm: f64,
}

impl LineAlong {
    /// The distance at `s` mm along the seam.
    pub fn at(&self, s: f64) -> f64 {
        self.at_middle_mm + self.per_mm * (s - self.middle_s)
    }
}

impl Face {
    /// A bevel face: at a groove's angle, as flat as a plate, seen along
    /// the seam.
    pub fn is_bevel(&self, spacing_mm: f64) -> bool {
        (MIN_BEVEL_DEG..=MAX_BEVEL_DEG).contains(&self.angle_deg) && self.is_plane(spacing_mm)
    }

    /// A square gap's wall: nearly along the normal.
    pub fn is_wall(&self, spacing_mm: f64) -> bool {
        self.angle_deg < MIN_BEVEL_DEG && self.is_plane(spacing_mm)
    }

    fn is_plane(&self, spacing_mm: f64) -> bool {
        self.is_seen() && self.rms_mm <= MAX_FACE_RMS_SPACINGS * spacing_mm
    }

    /// Whether the points are evidence of a surface at all: enough of
    /// them, along the seam, not a veil along the camera's rays.
    fn is_seen(&self) -> bool {
        !self.along_rays && self.points >= MIN_FACE_POINTS && self.station_share >= MIN_STATION_SHARE
    }

    /// Whether the face shows the groove's root: its foot comes within
    /// half the widest root gap of the midline.
    pub fn reaches_root(&self, spacing_mm: f64) -> bool {
        !self.foot_hidden && !self.foot_at_probe_bottom && self.foot_mm <= MAX_ROOT_GAP_MM / 2.0 + spacing_mm
    }
}

/// Something standing between the edges, above the plates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Standing {
    pub points: usize,
    /// How far above the plates its highest point lies, mm.
    pub height_mm: f64,
    /// The share of the seam's stations it was seen at.
    pub station_share: f64,
}

/// What lies between a butt joint's edges.
#[derive(Debug, Clone, PartialEq)]
pub struct GrooveProfile {
    pub point_spacing_mm: f64,
    /// How far apart the weld edges are at the seam's middle, mm: a
    /// V-groove's opening at the top.
    pub opening_mm: f64,
    /// The points between the edges below the plates' top margin.
    pub points_below: usize,
    /// The face fitted on each side that had points to fit.
    pub faces: Vec<Face>,
    /// A plate standing between the edges, when one does.
    pub standing: Option<Standing>,
}

/// What the profile says the joint is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Between {
    /// Bevel faces: a V-groove.
    Groove,
    /// No face, or walls along the normal: a square (I) gap.
    SquareGap,
    /// A plate stands between the edges, all along the seam: a tee joint's
    /// web on its flange, not a butt joint.
    StandingPlate(Standing),
    /// Points between the edges that fit neither.
    Unclear,
}

impl GrooveProfile {
    pub fn bevels(&self) -> impl Iterator<Item = &Face> {
        self.faces.iter().filter(|f| f.is_bevel(self.point_spacing_mm))
    }

    pub fn verdict(&self) -> Between {
        if let Some(s) = self.standing.filter(|s| s.points >= MIN_FACE_POINTS && s.station_share >= MIN_STATION_SHARE) {
            return Between::StandingPlate(s);
        }
        if self.bevels().next().is_some() {
            return Between::Groove;
        }
        // Walls, veils along the rays, or too little to be a face.
        let not_a_face = |f: &Face| !f.is_seen() || f.is_wall(self.point_spacing_mm);
        if self.faces.iter().all(not_a_face) { Between::SquareGap } else { Between::Unclear }
    }

    /// Where a V-groove's edges are, read from its bevels rather than from
    /// where the plates' points stop: each bevel's fitted line, carried up
    /// to the plates' top, meets it at the groove's true edge, however far
    /// the strips walked onto the bevel's first millimetres (a bevel 30°
    /// off the plates' plane stays within a 0.4 mm tolerance of it for
    /// 0.7 mm, more under noise, and the face turned to the camera, seen
    /// more densely, loses more). The offset of their midline from the
    /// weld edges' midline, towards the second edge; None unless both
    /// sides show a sloped face.
    pub fn bevel_midline_offset(&self) -> Option<LineAlong> {
        let sloped = |f: &&Face| {
            (MIN_BEVEL_DEG..=MAX_SLOPED_FACE_DEG).contains(&f.angle_deg) && f.is_plane(self.point_spacing_mm)
        };
        let top = |side: i8| self.faces.iter().filter(sloped).find(|f| f.side == side).map(|f| f.top);
        let (first, second) = (top(-1)?, top(1)?);
        // t runs towards the second edge: its top at +|t|, the first's at -|t|.
        Some(LineAlong {
            middle_s: second.middle_s,
            at_middle_mm: 0.5 * (second.at_middle_mm - first.at_middle_mm),
            per_mm: 0.5 * (second.per_mm - first.per_mm),
        })
    }

    /// The groove's angle: both bevels' angles, or twice the one seen.
    pub fn groove_angle_deg(&self) -> Option<f64> {
        let angles: Vec<f64> = self.bevels().map(|f| f.angle_deg).collect();
        match angles.as_slice() {
            [one] => Some(2.0 * one),
            [a, b] => Some(a + b),
            _ => None,
        }
    }

    /// The groove's depth below the plates' top, from the bevels that show
    /// the root, the deeper where both do (a face is only ever seen
    /// shorter than it is); None when none does.
    pub fn depth_mm(&self) -> Option<f64> {
        let spacing = self.point_spacing_mm;
        self.bevels().filter(|f| f.reaches_root(spacing)).map(|f| f.depth_mm).reduce(f64::max)
    }

    /// The opening at the top a V-groove `depth_mm` deep has with the
    /// bevels seen, least and most: `g + d (tan α1 + tan α2)` over root
    /// gaps `g` up to the widest, and for a side whose bevel is not seen,
    /// any bevel angle. None when no bevel is seen.
    pub fn expected_opening_mm(&self, depth_mm: f64) -> Option<(f64, f64)> {
        let run = |deg: f64| depth_mm * deg.to_radians().tan();
        let angles: Vec<f64> = self.bevels().map(|f| f.angle_deg).collect();
        match angles.as_slice() {
            [a, b] => Some((run(*a) + run(*b), MAX_ROOT_GAP_MM + run(*a) + run(*b))),
            [a] => Some((run(*a) + run(MIN_BEVEL_DEG), MAX_ROOT_GAP_MM + run(*a) + run(MAX_BEVEL_DEG))),
            _ => None,
        }
    }

    /// Checks that the weld edges are as far apart as the top of the
    /// V-groove the bevels and `depth_mm` make. Edges much further apart
    /// belong to something beside the groove (another part abutting a
    /// plate, with the true groove between the edges); much nearer, to
    /// something inside it; and a depth given for a groove whose root the
    /// camera cannot see is checked here too.
    pub fn check_opening(&self, depth_mm: f64) -> Result<(), GrooveError> {
        let Some((least, most)) = self.expected_opening_mm(depth_mm) else {
            return Ok(());
        };
        let slack = OPENING_SLACK_MM + OPENING_SLACK_SHARE * most + 2.0 * self.point_spacing_mm;
        if (least - slack..=most + slack).contains(&self.opening_mm) {
            return Ok(());
        }
        Err(GrooveError::OpeningMismatch {
            opening_mm: self.opening_mm,
            depth_mm,
            least_mm: least,
            most_mm: most,
            profile: self.describe(),
        })
    }

    /// The verdict and its figures in a sentence, for the seam's evidence.
    pub fn verdict_sentence(&self) -> String {
        match self.verdict() {
            Between::Groove => {
                let angle = self.groove_angle_deg().map_or(String::new(), |a| format!(" of {a:.0}°"));
                let depth = self.depth_mm().map_or("root not seen".into(), |d| format!("{d:.1} mm deep"));
                let sides = self.bevels().count();
                format!("a V-groove{angle}, {depth}, bevel faces seen on {sides} side(s)")
            }
            Between::SquareGap => format!("a square gap, no bevel face ({} points below the top)", self.points_below),
            Between::StandingPlate(_) => "a plate standing between the edges".into(),
            Between::Unclear => format!("neither bevels nor a square gap ({})", self.describe()),
        }
    }

    /// The profile in a sentence, for logs and refusals.
    pub fn describe(&self) -> String {
        let mut parts = vec![format!("{} points between the edges below their top", self.points_below)];
        for f in &self.faces {
            parts.push(format!(
                "side {}: {} points at {:.1}° from the normal{}, rms {:.2} mm, {:.1} mm deep{}, seen at {:.0}% of the seam",
                if f.side < 0 { 1 } else { 2 },
                f.points,
                f.angle_deg,
                if f.along_rays { " along the camera's rays" } else { "" },
                f.rms_mm,
                f.depth_mm,
                if f.foot_hidden {
                    " (below it hidden by the other plate)"
                } else if f.foot_at_probe_bottom {
                    " (down to the surface behind the plates, where the probe stops)"
                } else {
                    ""
                },
                100.0 * f.station_share
            ));
        }
        if let Some(s) = &self.standing {
            parts.push(format!(
                "{} points up to {:.1} mm above the plates, at {:.0}% of the seam",
                s.points,
                s.height_mm,
                100.0 * s.station_share
            ));
        }
        parts.join("; ")
    }
}

/// Why the joint between the edges is not the one requested, or cannot be
/// told.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GrooveError {
    #[error(
        "a plate stands between the two plates' edges, up to {height_mm:.0} mm above them along {share:.0} % of the \
         seam: this looks like a tee joint (a web standing on a flange), which is not planned; {profile}"
    )]
    LooksLikeTee { height_mm: f64, share: f64, profile: String },
    #[error(
        "no groove faces between the weld edges ({profile}): this looks like an I-butt joint, not the V-butt requested"
    )]
    LooksLikeIButt { profile: String },
    #[error(
        "groove faces between the weld edges ({profile}): this looks like a V-butt joint, not the I-butt requested"
    )]
    LooksLikeVButt { profile: String },
    #[error(
        "the points between the weld edges are neither a V-groove's faces nor a square gap ({profile}): the joint \
         type cannot be told; name it in the request"
    )]
    Unclear { profile: String },
    #[error(
        "the weld edges are {opening_mm:.1} mm apart, but a V-groove {depth_mm:.1} mm deep with the bevels seen \
         opens {least_mm:.1} to {most_mm:.1} mm at its top ({profile}): the edges found are not this groove's \
         (another part beside the joint, or something in the groove), or the groove depth is wrong"
    )]
    OpeningMismatch { opening_mm: f64, depth_mm: f64, least_mm: f64, most_mm: f64, profile: String },
}

impl GrooveError {
    /// Whether the type was left to the planner and could not be told
    /// (every other error names what the joint looks like).
    pub fn is_unknown(&self) -> bool {
        matches!(self, GrooveError::Unclear { .. })
    }
}

/// The butt joint the profile shows, checked against the one requested
/// (None: `auto`). A V-butt joint needs bevel faces between its edges and
/// an I-butt joint must show none; a plate standing between them is
/// neither; points that fit nothing are refused only when the planner must
/// decide, or when a V-groove was requested and its faces are not seen.
pub fn judge(requested: Option<JointType>, profile: &GrooveProfile) -> Result<JointType, GrooveError> {
    let described = || profile.describe();
    match (profile.verdict(), requested) {
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
    }
}

/// A point between the edges in the seam's axes.
#[derive(Debug, Clone, Copy, Default)]
struct Across {
    /// Along the seam, mm.
    s: f64,
    station: usize,
    /// Signed distance from the midline, positive towards the second edge.
    t: f64,
    /// Depth below the edges' mean height, along the normal.
    h: f64,
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
            fit_face(&points, side, spacing, (top_margin, bottom), &view, half_opening, middle)
        })
        .collect();
    GrooveProfile { point_spacing_mm: spacing, opening_mm: 2.0 * half_opening, points_below, faces, standing }
}

/// The image rows the convex hull of `corners` projects onto, each with
/// the columns it covers there (widened by [`PIXEL_MARGIN`]), as `(row,
/// first column, last column)`. None when a corner lies behind or too near
/// the camera, where a projection says nothing.
fn rows_under(grid: &CameraGrid, corners: &[Vec3]) -> Option<Vec<(usize, usize, usize)>> {
    let (width, height) = grid.size();
    let projected: Vec<(f64, f64)> = corners
        .iter()
        .map(|c| if c.z > MIN_PROJECTED_DEPTH_MM { grid.project(c) } else { None })
        .collect::<Option<_>>()?;
    let (v_lo, v_hi) = extent(projected.iter().map(|p| p.1));
    let first = (v_lo - PIXEL_MARGIN).floor().max(0.0) as usize;
    let last = ((v_hi + PIXEL_MARGIN).ceil().min(height as f64 - 1.0)).max(-1.0);
    if last < first as f64 {
        return Some(Vec::new());
    }
    // The hull's part in the strip of rows `v ± margin`: the corners in it
    // and the pairs' segments where they cross its two lines (the hull of
    // points meets a line where the segments between them do).
    let columns = |v: f64| {
        let (y0, y1) = (v - PIXEL_MARGIN, v + PIXEL_MARGIN);
        let mut range = (f64::INFINITY, f64::NEG_INFINITY);
        let mut take = |u: f64| range = (range.0.min(u), range.1.max(u));
        for (k, a) in projected.iter().enumerate() {
            if (y0..=y1).contains(&a.1) {
                take(a.0);
            }
            for b in &projected[k + 1..] {
                for y in [y0, y1] {
                    if (a.1 - y) * (b.1 - y) <= 0.0 && a.1 != b.1 {
                        take(a.0 + (b.0 - a.0) * (y - a.1) / (b.1 - a.1));
                    }
                }
            }
        }
        range
    };
    Some(
        (first..=last as usize)
            .filter_map(|v| {
                let (lo, hi) = columns(v as f64);
                let (lo, hi) =
                    ((lo - PIXEL_MARGIN).floor().max(0.0), (hi + PIXEL_MARGIN).ceil().min(width as f64 - 1.0));
                (lo <= hi).then_some((v, lo as usize, hi as usize))
            })
            .collect(),
    )
}

/// The share of the stations at least one of `points` lies at.
fn station_share<'p>(points: impl IntoIterator<Item = &'p Across>) -> f64 {
    let mut seen = [false; STATIONS];
    for p in points {
        seen[p.station] = true;
    }
    seen.iter().filter(|&&s| s).count() as f64 / STATIONS as f64
}

/// The points with at least [`MIN_SURFACE_NEIGHBOURS`] others within
/// `radius` (in s, t, h).
///
/// Sorted along the seam, a point's neighbours are among the points whose
/// `s` lies within the radius of its own: a slab across the groove one
/// diameter thick. The slab is read outward from the point, nearest in `s`
/// first, and the reading stops once enough neighbours are found. A
/// groove's steep faces crowd a slab's points into a narrow band across
/// the seam, so ordering them across it as well saves little; building a
/// cell index over the same points cost twice this
/// (`tests::on_surfaces_by_cells`, the reference this is checked
/// against).
fn on_surfaces(mut points: Vec<Across>, radius: f64) -> Vec<Across> {
    // Single precision: the coordinates are millimetres from the seam's
    // middle, so a hundredth of a micrometre at worst.
    let mut sorted: Vec<(Point, u32)> =
        points.iter().enumerate().map(|(i, p)| ([p.s, p.t, p.h].map(|v| v as f32), i as u32)).collect();
    sorted.par_sort_unstable_by(|a, b| a.0[0].total_cmp(&b.0[0]));
    let radius_sq = (radius * radius) as f32;
    let keep_sorted: Vec<bool> = (0..sorted.len())
        .into_par_iter()
        .map(|k| {
            let p = &sorted[k].0;
            // A point this far along the seam alone is out of reach, and so
            // is every point past it: the squared distance only grows with
            // the other two terms, as it does in `within`.
            let in_slab = |q: &&Point| (p[0] - q[0]) * (p[0] - q[0]) <= radius_sq;
            // The next point to read below and above the point's place.
            let (mut below, mut above) = (k, k + 1);
            let mut found = 0;
            loop {
                let down = below.checked_sub(1).map(|j| &sorted[j].0).filter(in_slab);
                let up = sorted.get(above).map(|(q, _)| q).filter(in_slab);
                if down.is_none() && up.is_none() {
                    return false;
                }
                found += down.into_iter().chain(up).filter(|q| crate::kernels::within(p, q, radius_sq)).count();
                if found >= MIN_SURFACE_NEIGHBOURS {
                    return true;
                }
                below -= usize::from(down.is_some());
                above += usize::from(up.is_some());
            }
        })
        .collect();
    let mut keep = vec![false; points.len()];
    for ((_, i), k) in sorted.iter().zip(keep_sorted) {
        keep[*i as usize] = k;
    }
    drop(sorted);
    // In place: `retain` reads the points once each, in order.
    let mut kept = keep.into_iter();
    points.retain(|_| kept.next().unwrap_or(false));
    points
}

/// The slopes `dt/dh` of the camera's and the projector's rays at the
/// seam.
#[derive(Debug, Clone, Copy)]
struct Views {
    camera: f64,
    projector: f64,
}

/// Fits one side's points as `|t| = c - h tan α`; `half_opening` is half
/// the distance between the weld edges.
fn fit_face(
    points: &[&Across],
    side: i8,
    spacing: f64,
    (top_margin, bottom): (f64, f64),
    view: &Views,
    half_opening: f64,
    middle_s: f64,
) -> Option<Face> {
    if points.len() < 3 {
        return None;
    }
    // A robust start: the median |t| of each depth bin a spacing high,
    // bins with a few points only, fitted by least squares; the table
    // seen through a root gap or a stray return then moves one bin, not
    // the line.
    let bin_of = |h: f64| ((h - top_margin) / spacing).max(0.0) as usize;
    let bins = points.iter().map(|p| bin_of(p.h)).max()? + 1;
    let medians: Vec<(f64, f64)> = {
        let mut by_bin: Vec<Vec<f64>> = vec![Vec::new(); bins];
        for p in points {
            by_bin[bin_of(p.h)].push(p.t.abs());
        }
        let mut medians: Vec<(usize, f64)> = by_bin
            .iter_mut()
            .enumerate()
            .filter(|(_, ts)| ts.len() >= 3)
            .map(|(k, ts)| {
                let middle = ts.len() / 2;
                (k, *ts.select_nth_unstable_by(middle, f64::total_cmp).1)
            })
            .collect();
        // A face is seen down its whole height: bins past a run of empty
        // ones hold something else below it (stray returns under a
        // specular streak), no root face.
        if let Some(break_at) = medians.windows(2).position(|w| w[1].0 - w[0].0 > MAX_EMPTY_BINS + 1) {
            medians.truncate(break_at + 1);
        }
        medians.into_iter().map(|(k, t)| (top_margin + (k as f64 + 0.5) * spacing, t)).collect()
    };
    // Below a bevel with a root gap the root face stands along the
    // normal: fit the bevel above that hinge only, and read the depth
    // where the two meet.
    let hinge = root_hinge(&medians, spacing);
    let above: std::borrow::Cow<[&Across]> = match hinge {
        Some(h) => points.iter().filter(|p| p.h < h.depth_mm).copied().collect(),
        None => points.into(),
    };
    let start = &medians[..hinge.map_or(medians.len(), |h| h.bins_above)];
    let mut line = fit_line(start.iter().copied())?;
    // Then all points within a band of the line, twice.
    let mut kept: Vec<&Across> = above.to_vec();
    let mut residuals: Vec<f64> = Vec::with_capacity(above.len());
    for _ in 0..2 {
        // The residuals' spread by their median, which the outliers do not
        // move (the median over MAD_PER_SIGMA is one sigma of a normal
        // spread).
        residuals.clear();
        residuals.extend(above.iter().map(|p| (p.t.abs() - line.at(p.h)).abs()));
        let middle = residuals.len() / 2;
        let mad = *residuals.select_nth_unstable_by(middle, f64::total_cmp).1;
        let band = (TRIM_SIGMA * mad / MAD_PER_SIGMA).max(MIN_BAND_SPACINGS * spacing);
        kept.clear();
        kept.extend(above.iter().filter(|p| (p.t.abs() - line.at(p.h)).abs() <= band).copied());
        line = fit_line(kept.iter().map(|p| (p.h, p.t.abs())))?;
    }
    let depth_mm = match hinge {
        // The bevel's line meets the root face's |t| = g / 2.
        Some(h) if line.slope < 0.0 => (h.root_half_gap_mm - line.intercept) / line.slope,
        // Else where the bevel ends: at each station the kept point
        // nearest the midline, read on the line by its |t| (the depth
        // noise lies mostly along h, and a veil of mixed pixels below the
        // bevel's foot keeps the foot's |t|); the stations where the
        // groove's bottom is seen best, a low quantile of them.
        _ => {
            let mut nearest = [f64::INFINITY; STATIONS];
            for p in &kept {
                nearest[p.station] = nearest[p.station].min(p.t.abs());
            }
            let mut feet: Vec<f64> = nearest.into_iter().filter(|t| t.is_finite()).collect();
            let rank = (FOOT_QUANTILE * feet.len() as f64) as usize;
            let foot = *feet.select_nth_unstable_by(rank, f64::total_cmp).1;
            (foot - line.intercept) / line.slope
        }
    };
    let slope = -line.slope;
    let angle = slope.atan();
    // The face's dt/dh on this side: |t| = c - h tan α, t = side |t|.
    let face_slope = f64::from(side) * line.slope;
    let along_rays = (face_slope.atan() - view.camera.atan()).abs().to_degrees() < RAY_ALIGNED_DEG;
    // A ray past the opposite edge, t = -side w + k h, meets this face,
    // t = side (c - h tan α), at h_occ; at or above the foot, the opposite
    // plate hides the face below it from the camera, or shades it from the
    // projector.
    let side_f = f64::from(side);
    let hidden_below = |k: f64| {
        let towards = k - side_f * line.slope;
        let h_occ = side_f * (line.intercept + half_opening) / towards;
        towards.abs() > f64::EPSILON && h_occ > 0.0 && h_occ <= depth_mm + OCCLUSION_MARGIN_MM
    };
    let foot_hidden = hidden_below(view.camera) || hidden_below(view.projector);
    let top = top_line(&kept, &line, half_opening - 0.5 * spacing, middle_s);
    Some(Face {
        side,
        points: kept.len(),
        angle_deg: angle.to_degrees(),
        // Perpendicular to the face, not along t.
        rms_mm: line.rms * angle.cos(),
        depth_mm,
        foot_mm: line.at(depth_mm),
        station_share: station_share(kept.iter().copied()),
        along_rays,
        foot_hidden,
        foot_at_probe_bottom: depth_mm >= bottom - BOTTOM_MARGIN_SPACINGS * spacing,
        top,
    })
}

/// Where a face fitted as `line` meets the plates' top: each of its `kept`
/// points carried up the face's slope to `h = 0`, `|t| - (d|t|/dh) h`,
/// then a line along the seam through them. Only from the points whose
/// face lies [`TOP_CUT_SIGMAS`] inside `cut`, the `|t|` past which the
/// probe reads nothing: near it, it keeps only the points noise moved in,
/// and a slope fitted there reads flatter than the face. Too few such
/// points: the face's own intercept, the same all along.
fn top_line(kept: &[&Across], line: &Line, cut: f64, middle_s: f64) -> LineAlong {
    let inside = cut - TOP_CUT_SIGMAS * line.rms;
    let deep: Vec<&Across> = kept.iter().copied().filter(|p| line.at(p.h) <= inside).collect();
    let fitted = (deep.len() >= MIN_FACE_POINTS).then(|| {
        let slope = fit_line(deep.iter().map(|p| (p.h, p.t.abs()))).map_or(line.slope, |l| l.slope);
        fit_line(deep.iter().map(|p| (p.s - middle_s, p.t.abs() - slope * p.h)))
    });
    match fitted.flatten() {
        Some(l) => LineAlong { middle_s, at_middle_mm: l.intercept, per_mm: l.slope },
        None => LineAlong { middle_s, at_middle_mm: line.intercept, per_mm: 0.0 },
    }
}

/// Where a bevel meets the root face below it.
#[derive(Debug, Clone, Copy)]
struct Hinge {
    /// The depth bins above the root face.
    bins_above: usize,
    /// The depth the root face starts at (the split between the bins).
    depth_mm: f64,
    /// The root face's distance from the midline, mm (half the root gap).
    root_half_gap_mm: f64,
}

/// The split of the depth bins' median `|t|` (`(h, |t|)` by increasing
/// `h`) into a sloping line above and a constant below that fits them far
/// better than one line does, when the part below is a wall along the
/// normal at least [`MIN_ROOT_BINS`] bins high that the line above runs
/// down into ([`HINGE_MEET_BINS`]).
fn root_hinge(medians: &[(f64, f64)], spacing: f64) -> Option<Hinge> {
    let sse = |l: &Line, part: &[(f64, f64)]| l.rms * l.rms * part.len() as f64;
    let whole = fit_line(medians.iter().copied()).map(|l| sse(&l, medians))?;
    let mut best: Option<(f64, usize, f64)> = None;
    for k in MIN_BEVEL_BINS..=medians.len().saturating_sub(MIN_ROOT_BINS) {
        let (upper, lower) = medians.split_at(k);
        let Some(bevel) = fit_line(upper.iter().copied()) else { continue };
        let mean = lower.iter().map(|m| m.1).sum::<f64>() / lower.len() as f64;
        let wall_sse: f64 = lower.iter().map(|m| (m.1 - mean).powi(2)).sum();
        // The wall stands along the normal: its |t| barely varies.
        if wall_sse / lower.len() as f64 > spacing * spacing {
            continue;
        }
        // And the bevel narrows into it where the bins turn.
        let turn = 0.5 * (upper[k - 1].0 + lower[0].0);
        let meets =
            bevel.slope < 0.0 && ((mean - bevel.intercept) / bevel.slope - turn).abs() <= HINGE_MEET_BINS * spacing;
        if !meets {
            continue;
        }
        let sse = sse(&bevel, upper) + wall_sse;
        if best.is_none_or(|(b, _, _)| sse < b) {
            best = Some((sse, k, mean));
        }
    }
    let (sse, k, root_half_gap_mm) = best?;
    (sse < HINGE_GAIN * whole).then(|| Hinge {
        bins_above: k,
        depth_mm: 0.5 * (medians[k - 1].0 + medians[k].0),
        root_half_gap_mm,
    })
}

/// `y = intercept + slope x`, fitted by least squares, and its RMS
/// residual in y.
#[derive(Debug, Clone, Copy)]
struct Line {
    intercept: f64,
    slope: f64,
    rms: f64,
}

impl Line {
    fn at(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }
}

fn fit_line(points: impl Iterator<Item = (f64, f64)> + Clone) -> Option<Line> {
    let n = points.clone().count() as f64;
    if n < 2.0 {
        return None;
    }
    let (mx, my) = points.clone().fold((0.0, 0.0), |(x, y), (px, py)| (x + px / n, y + py / n));
    let (sxx, sxy) =
        points.clone().fold((0.0, 0.0), |(xx, xy), (px, py)| (xx + (px - mx) * (px - mx), xy + (px - mx) * (py - my)));
    if sxx <= f64::EPSILON {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let rms = (points.map(|(px, py)| (py - intercept - slope * px).powi(2)).sum::<f64>() / n).sqrt();
    Some(Line { intercept, slope, rms })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::refit::SeamAxes;

    fn edge(a: f64) -> SeamCurve {
        SeamCurve {
            axes: SeamAxes { origin: Vec3::new(0.0, 0.0, 700.0), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() },
            coef_a: vec![a, 0.0],
            coef_b: vec![0.0, 0.0],
            s_min: -50.0,
            s_max: 50.0,
        }
    }

    /// Points every `step` mm over a profile `z(x)` across the seam (x) and
    /// along it (y), rows shifted against each other as a camera's pixels
    /// fall, at 700 mm from the camera.
    fn cloud_of(profile: impl Fn(f64) -> Option<f64>, half_width: f64, step: f64) -> PointCloud {
        let mut points = Vec::new();
        let n = (half_width / step) as i64;
        let rows = (50.0 / step) as i64;
        for j in -rows..=rows {
            for i in -n..=n {
                let x = i as f64 * step + step * (j as f64 * 0.618).fract();
                if let Some(depth) = profile(x) {
                    points.push([x as f32, (j as f64 * step) as f32, (700.0 + depth) as f32]);
                }
            }
        }
        PointCloud::unorganized(points)
    }

    /// The reference of [`on_surfaces`]: every point's neighbours counted
    /// through the cell index the unorganized clouds' neighbour searches
    /// use (a query stops as soon as it has enough).
    pub(super) fn on_surfaces_by_cells(points: Vec<Across>, radius: f64) -> Vec<Across> {
        use crate::pipeline::neighbours::cells::CellIndex;
        use std::ops::ControlFlow;
        let coords: Vec<Point> = points.iter().map(|p| [p.s, p.t, p.h].map(|v| v as f32)).collect();
        let index = CellIndex::for_radius(&coords, radius);
        let radius_sq = (radius * radius) as f32;
        let keep: Vec<bool> = coords
            .iter()
            .map(|p| {
                // The point itself is among them.
                let mut found = 0;
                index.visit_within(p, radius_sq, radius_sq * (1.0 + 1e-5), |_| {
                    found += 1;
                    if found > MIN_SURFACE_NEIGHBOURS { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
                });
                found > MIN_SURFACE_NEIGHBOURS
            })
            .collect();
        points.into_iter().zip(keep).filter_map(|(p, k)| k.then_some(p)).collect()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// The slab reading keeps exactly the points the cell index keeps:
        /// points on a lattice, dense or sparse, whose spacing puts many
        /// neighbours exactly at the radius (and repeats some), and strays
        /// among them, near the seam's middle and far along it.
        #[test]
        fn the_surface_filter_keeps_what_the_cell_index_keeps(
            lattice in proptest::collection::vec((-10i32..10, -5i32..5, 0i32..4), 0..600),
            strays in proptest::collection::vec((-10.0f64..10.0, -5.0f64..5.0, 0.0f64..4.0), 0..100),
            step in proptest::sample::select(vec![0.25f64, 0.5, 1.0]),
            radius_steps in proptest::sample::select(vec![1.0f64, 1.5, 2.0]),
            along in proptest::sample::select(vec![0.0f64, -187.3, 291.9]),
        ) {
            let points: Vec<Across> = lattice
                .iter()
                .map(|&(s, t, h)| (s as f64 * step, t as f64 * step, h as f64 * step))
                .chain(strays.iter().map(|&(s, t, h)| (s * step, t * step, h * step)))
                .map(|(s, t, h)| Across { s: s + along, station: 0, t, h })
                .collect();
            let radius = radius_steps * step;
            let key = |v: Vec<Across>| v.iter().map(|p| (p.s.to_bits(), p.t.to_bits(), p.h.to_bits())).collect::<Vec<_>>();
            proptest::prop_assert_eq!(
                key(on_surfaces(points.clone(), radius)),
                key(on_surfaces_by_cells(points, radius))
            );
        }
    }

    fn probed(cloud: &PointCloud, half_opening: f64) -> GrooveProfile {
        probed_between(cloud, &edge(-half_opening), &edge(half_opening))
    }

    fn probed_between(cloud: &PointCloud, e1: &SeamCurve, e2: &SeamCurve) -> GrooveProfile {
        probe(
            cloud,
            &ProbeSetting {
                edges: [e1, e2],
                span: (-45.0, 45.0),
                point_spacing_mm: 0.2,
                depth_to_support_mm: Some(20.0),
                grid: None,
                projector: Vec3::zeros(),
            },
        )
    }

    /// A 60 degree V-groove 5 mm deep with a 1 mm root gap, whose bevels
    /// reach x = ±0.5, and its half opening at the top.
    fn v_groove_cloud() -> (PointCloud, f64) {
        let tan = 30f64.to_radians().tan();
        let w = 0.5 + 5.0 * tan;
        let v = |x: f64| {
            if x.abs() >= w {
                Some(0.0)
            } else if x.abs() >= 0.5 {
                Some((w - x.abs()) / tan)
            } else {
                None
            }
        };
        (cloud_of(v, 10.0, 0.2), w)
    }

    #[test]
    fn stray_returns_below_a_groove_do_not_set_its_depth() {
        // The 5 mm groove, and under it, past 3 mm where nothing is seen,
        // a sheet of stray returns 1.5 to 2.5 mm off the midline along the
        // seam, 8 to 10 mm deep (what a specular streak left under a
        // groove at 1 mm voxels): no root face of the bevels above.
        let (cloud, w) = v_groove_cloud();
        let mut points = cloud.points().to_vec();
        for j in -50..=50 {
            for k in 0..=20 {
                let (y, depth) = (j as f64, 8.0 + k as f64 * 0.1);
                let x = 1.5 + 0.05 * (k % 20) as f64;
                points.extend([-x, x].map(|x| [x as f32, y as f32, (700.0 + depth) as f32]));
            }
        }
        let profile = probed(&PointCloud::unorganized(points), w);
        assert_eq!(profile.verdict(), Between::Groove, "{}", profile.describe());
        assert!((profile.depth_mm().unwrap() - 5.0).abs() < 0.2, "{}", profile.describe());
    }

    #[test]
    fn a_bevel_s_root_face_is_where_it_narrows_into_it() {
        // Depth bins a spacing (1 mm) apart: a bevel |t| = 5 - 0.5 h down
        // to 6 mm, then a root face at |t| = 2 below it: the hinge at 6.
        let bevel = |h: f64| (h, 5.0 - 0.5 * h);
        let mut medians: Vec<(f64, f64)> = (0..6).map(|k| bevel(k as f64 + 0.5)).collect();
        medians.extend((6..10).map(|k| (k as f64 + 0.5, 2.0)));
        let hinge = root_hinge(&medians, 1.0).expect("a root face under the bevel");
        assert_eq!(hinge.bins_above, 6);
        assert!((hinge.depth_mm - 6.0).abs() < 1e-9 && (hinge.root_half_gap_mm - 2.0).abs() < 1e-9, "{hinge:?}");
        // Bins of one |t| far out from where the bevel ends (it reaches
        // |t| = 0.25 at 9.5 mm): not its root face, which the bevel's
        // line meets 7 mm above them.
        let mut far_out: Vec<(f64, f64)> = (0..10).map(|k| bevel(k as f64 + 0.5)).collect();
        far_out.extend((10..13).map(|k| (k as f64 + 0.5, 3.5)));
        assert!(root_hinge(&far_out, 1.0).is_none(), "{:?}", root_hinge(&far_out, 1.0));
    }

    #[test]
    fn every_point_of_the_probed_box_falls_in_the_rows_read() {
        let camera = crate::camera::CameraModel::default();
        let grid = CameraGrid::for_camera(&camera);
        // A box 300 mm along a seam crossing the view at a slant, 20 mm
        // across, from 150 mm above the plates to 30 mm below, 700 mm off.
        let (e, a) = (Vec3::new(0.8, 0.55, 0.2).normalize(), Vec3::new(-0.55, 0.8, 0.1).normalize());
        let b = e.cross(&a).normalize();
        let origin = Vec3::new(20.0, -10.0, 700.0);
        let at = |s: f64, t: f64, h: f64| origin + e * s + a * t + b * h;
        let corners: Vec<Vec3> = (0..8)
            .map(|k| {
                at(
                    if k & 1 == 0 { -150.0 } else { 150.0 },
                    if k & 2 == 0 { -10.0 } else { 10.0 },
                    if k & 4 == 0 { -150.0 } else { 30.0 },
                )
            })
            .collect();
        let rows = rows_under(&grid, &corners).unwrap();
        let (width, height) = grid.size();
        let read: std::collections::HashSet<usize> =
            rows.iter().flat_map(|&(v, u0, u1)| (u0..=u1).map(move |u| v * width + u)).collect();
        assert!(read.len() < width * height / 4, "{} of {} pixels", read.len(), width * height);
        let mut missed = 0;
        for k in 0..20_000 {
            let f = |m: u64| ((k * m) % 1009) as f64 / 1008.0;
            let p = at(-150.0 + 300.0 * f(7), -10.0 + 20.0 * f(13), -150.0 + 180.0 * f(31));
            if let Some(i) = grid.pixel_of(&p) {
                missed += usize::from(!read.contains(&i));
            }
        }
        assert_eq!(missed, 0);
        // A corner behind the camera: no projection, the whole frame.
        let behind: Vec<Vec3> = corners.iter().map(|c| c - Vec3::new(0.0, 0.0, 800.0)).collect();
        assert!(rows_under(&grid, &behind).is_none());
    }

    #[test]
    fn a_bevel_cut_by_the_probes_bottom_shows_no_root() {
        // The groove of the test below, 5 mm deep, with a surface taken for
        // the plates' support 3.5 mm down (another part's plate, in a frame
        // of several): the probe stops at 3 mm, and the bevels' feet there
        // are not the root.
        let tan = 30f64.to_radians().tan();
        let w = 0.5 + 5.0 * tan;
        let v = |x: f64| if x.abs() >= w { Some(0.0) } else { (x.abs() >= 0.5).then(|| (w - x.abs()) / tan) };
        let cloud = cloud_of(v, 10.0, 0.2);
        let (e1, e2) = (edge(-w), edge(w));
        let setting = ProbeSetting {
            edges: [&e1, &e2],
            span: (-45.0, 45.0),
            point_spacing_mm: 0.2,
            depth_to_support_mm: Some(3.5),
            grid: None,
            projector: Vec3::zeros(),
        };
        let profile = probe(&cloud, &setting);
        assert_eq!(profile.verdict(), Between::Groove, "{}", profile.describe());
        assert!(profile.bevels().all(|f| f.foot_at_probe_bottom), "{}", profile.describe());
        assert_eq!(profile.depth_mm(), None, "{}", profile.describe());
    }

    #[test]
    fn a_v_groove_shows_two_bevels_its_angle_and_depth() {
        let (cloud, w) = v_groove_cloud();
        let profile = probed(&cloud, w);
        assert_eq!(profile.verdict(), Between::Groove, "{}", profile.describe());
        assert!((profile.groove_angle_deg().unwrap() - 60.0).abs() < 1.0, "{}", profile.describe());
        assert!((profile.depth_mm().unwrap() - 5.0).abs() < 0.2, "{}", profile.describe());
        // The bevels alone tell the joint: a V-butt, never an I-butt.
        assert_eq!(judge(None, &profile), Ok(JointType::VButt));
        assert!(matches!(judge(Some(JointType::IButt), &profile), Err(GrooveError::LooksLikeVButt { .. })));
        // Its opening, 6.3 mm, fits its depth, and fits neither a groove
        // twice as deep nor the edges of a part standing 40 mm off.
        assert_eq!(profile.check_opening(5.0), Ok(()));
        assert!(matches!(profile.check_opening(10.0), Err(GrooveError::OpeningMismatch { .. })));
        let far_apart = GrooveProfile { opening_mm: 40.0, ..profile.clone() };
        let refusal = far_apart.check_opening(5.0).unwrap_err();
        assert!(refusal.to_string().contains("40.0 mm apart"), "{refusal}");
    }

    #[test]
    fn a_v_groove_s_bevels_place_its_edges_where_the_edges_given_are_read_inside_it() {
        // The groove of [`v_groove_cloud`], its edges given 0.3 mm inside
        // it on one side and 0.9 to 1.3 mm along the seam on the other, as
        // the strips read a noisy groove: their midline lies 0.4 mm off
        // the groove's at the middle, 0.29 and 0.51 mm at the ends.
        let (cloud, w) = v_groove_cloud();
        let e1 = edge(-(w - 0.3));
        let e2 = SeamCurve { coef_a: vec![w - 1.1, 0.005], ..edge(0.0) };
        let profile = probed_between(&cloud, &e1, &e2);
        let offset = profile.bevel_midline_offset().unwrap_or_else(|| panic!("{}", profile.describe()));
        let midline = e1.midline(&e2).unwrap();
        let moved = crate::pipeline::weld_equation::moved_towards(&midline, &e1, &e2, &offset);
        for s in [-45.0, 0.0, 45.0] {
            let (before, after) = (midline.at(s).x, moved.at(s).x);
            assert!(after.abs() < 0.05, "at s = {s}: the midline {before:.3} mm off, moved to {after:.3} mm");
        }
        // Edges given where the groove is: nothing to move.
        let offset = probed(&cloud, w).bevel_midline_offset().unwrap();
        assert!(offset.at_middle_mm.abs() < 0.02 && offset.per_mm.abs() < 1e-3, "{offset:?}");
        // A square gap has no sloped face to place an edge.
        let gap = |x: f64| if x.abs() >= 1.5 { Some(0.0) } else { None };
        assert_eq!(probed(&cloud_of(gap, 10.0, 0.2), 1.5).bevel_midline_offset(), None);
    }

    #[test]
    fn a_square_gap_shows_no_bevel() {
        let gap = |x: f64| if x.abs() >= 1.5 { Some(0.0) } else { None };
        let profile = probed(&cloud_of(gap, 10.0, 0.2), 1.5);
        assert_eq!(profile.verdict(), Between::SquareGap, "{}", profile.describe());
        assert_eq!(profile.depth_mm(), None);
        assert_eq!(judge(None, &profile), Ok(JointType::IButt));
        let err = judge(Some(JointType::VButt), &profile).unwrap_err();
        assert!(err.to_string().contains("looks like an I-butt joint"), "{err}");
    }

    #[test]
    fn a_veil_along_the_rays_is_no_face() {
        // A square gap whose walls' top edges leave mixed pixels along the
        // camera's rays: a dense sheet, but along the rays (here the rays
        // run along the normal, so the veil is at 0 degrees and a wall).
        // Tilt the rays instead: the seam 200 mm off the optical axis.
        let mut points = Vec::new();
        for j in -250..=250 {
            let y = j as f64 * 0.2;
            for i in -50..=50 {
                let x = i as f64 * 0.2 + 0.2 * (j as f64 * 0.618).fract();
                if x.abs() >= 1.5 {
                    points.push([(x + 200.0) as f32, y as f32, 700.0]);
                }
            }
            // Mixed pixels from the gap's edge down towards the table, on
            // the ray through (201.5, y, 700).
            for k in 1..40 {
                let f = 1.0 + k as f64 * 0.005;
                points.push([(201.5 * f) as f32, (y * f) as f32, (700.0 * f) as f32]);
            }
        }
        let cloud = PointCloud::unorganized(points);
        let axes = SeamAxes { origin: Vec3::new(200.0, 0.0, 700.0), e: Vec3::y(), a: Vec3::x(), b: Vec3::z() };
        let edge = |a: f64| SeamCurve { axes, coef_a: vec![a, 0.0], coef_b: vec![0.0, 0.0], s_min: -45.0, s_max: 45.0 };
        let (e1, e2) = (edge(-1.5), edge(1.5));
        let setting = ProbeSetting {
            edges: [&e1, &e2],
            span: (-45.0, 45.0),
            point_spacing_mm: 0.2,
            depth_to_support_mm: None,
            grid: None,
            projector: Vec3::zeros(),
        };
        let profile = probe(&cloud, &setting);
        assert!(profile.faces.iter().all(|f| f.along_rays || f.points < MIN_FACE_POINTS), "{}", profile.describe());
        assert_eq!(profile.verdict(), Between::SquareGap, "{}", profile.describe());
    }

    #[test]
    fn a_plate_standing_between_the_edges_is_seen() {
        let tee = |x: f64| if x.abs() >= 5.0 { Some(0.0) } else { Some(-60.0) };
        let profile = probed(&cloud_of(tee, 15.0, 0.2), 5.5);
        assert!(matches!(profile.verdict(), Between::StandingPlate(_)), "{}", profile.describe());
        assert!((profile.standing.unwrap().height_mm - 60.0).abs() < 1e-3);
        for requested in [None, Some(JointType::VButt), Some(JointType::IButt)] {
            let err = judge(requested, &profile).unwrap_err();
            assert!(err.to_string().contains("looks like a tee joint"), "{err}");
        }
    }
}
