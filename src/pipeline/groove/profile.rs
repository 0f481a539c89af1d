//! What the probe found between the edges: each side's face, a plate
//! standing there, and what they say the joint is, how deep and how wide
//! its groove.

use super::error::GrooveError;
use super::points::STATIONS;

/// A face between these angles from the plate normal is a bevel: V-groove
/// bevels are 15 to 45 degrees (groove angles of 30 to 90), and a square
/// gap's wall, seen through noise, a few degrees at most.
pub(super) const MIN_BEVEL_DEG: f64 = 10.0;
const MAX_BEVEL_DEG: f64 = 60.0;

/// The flattest face whose top line places a groove's edge, degrees from
/// the plate normal ([`GrooveProfile::bevel_midline_offset`]): a groove
/// judged a V may still have bevels past [`MAX_BEVEL_DEG`] (a 124° groove
/// is 62° a side); one within 15° of the plates' own plane is hardly a
/// face beside their noise.
pub(super) const MAX_SLOPED_FACE_DEG: f64 = 75.0;

/// The fewest points a face is fitted from, and the least share of the
/// seam's stations it must be seen at: a face is seen along the seam, not
/// in one spot, as spatter or a tack is.
pub(super) const MIN_FACE_POINTS: usize = 30;
const MIN_STATION_SHARE: f64 = 0.3;

/// The widest root gap a V-groove has, mm: a face whose foot lies further
/// than half of it from the midline did not show its lower end.
const MAX_ROOT_GAP_MM: f64 = 4.0;

/// The widest root land a V-groove has, as a share of its opening at the
/// top: the land lies at the bevels' foot, and the bevels make the groove;
/// a floor wider than half the opening is a trough's, whose root the
/// bevels' feet do not place.
const MAX_LAND_SHARE: f64 = 0.5;

/// How far the weld edges' distance may stray from the opening the bevels
/// and the depth give a V-groove: this many millimetres and this share of
/// the widest opening (the angles are fitted, not known), before the edges
/// are taken for something else's.
const OPENING_SLACK_MM: f64 = 1.0;
const OPENING_SLACK_SHARE: f64 = 0.15;

/// A face fit whose residual RMS exceeds this many point spacings is not a
/// plane face.
const MAX_FACE_RMS_SPACINGS: f64 = 1.0;

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
    /// The RMS residual of the fit's points about their own station's
    /// line ([`Face::stations`]), mm: a face whose bevel changes along the
    /// seam (a groove cut wider along part of it, its bevel shallower
    /// there from the same foot) is a plane at each station though no one
    /// plane fits it all.
    pub station_rms_mm: f64,
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
    /// Whether the face runs down to the groove's own floor, a surface
    /// seen only between the plates (a root land): its foot is there.
    pub foot_on_floor: bool,
    /// Where the face meets the plates' top (`h = 0`), as a line of `|t|`
    /// along the seam.
    pub top: LineAlong,
    /// The face's own line at each station along the seam, where it has
    /// points there: where its foot lies station by station
    /// ([`GrooveProfile::root`]).
    pub stations: [Option<StationLine>; STATIONS],
}

/// One station's line of a face across the seam, `|t| = intercept + slope
/// h` (the slope is `-tan α`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationLine {
    /// The mean position along the seam of the station's points, mm.
    pub s: f64,
    pub intercept: f64,
    pub slope: f64,
}

impl StationLine {
    /// `|t|` at depth `h`.
    pub fn at(&self, h: f64) -> f64 {
        self.intercept + self.slope * h
    }
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

    pub(super) fn is_plane(&self, spacing_mm: f64) -> bool {
        self.is_seen() && self.rms_mm <= MAX_FACE_RMS_SPACINGS * spacing_mm
    }

    /// Whether the points are evidence of a surface at all: enough of
    /// them, along the seam, not a veil along the camera's rays.
    pub(super) fn is_seen(&self) -> bool {
        !self.along_rays && self.points >= MIN_FACE_POINTS && self.station_share >= MIN_STATION_SHARE
    }

    /// Whether the face shows the groove's root: its foot comes within
    /// half the widest root gap of the midline, or it runs down to the
    /// groove's floor (a root land) at most half a land of
    /// [`MAX_LAND_SHARE`] of the groove's `opening_mm` from it.
    pub fn reaches_root(&self, spacing_mm: f64, opening_mm: f64) -> bool {
        let reach = if self.foot_on_floor {
            (0.5 * MAX_LAND_SHARE * opening_mm).max(MAX_ROOT_GAP_MM / 2.0)
        } else {
            MAX_ROOT_GAP_MM / 2.0
        };
        !self.foot_hidden && !self.foot_at_probe_bottom && self.foot_mm <= reach + spacing_mm
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
    /// The stretch along the seam's feature axis probed, mm.
    pub span: (f64, f64),
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
        self.bevels().filter(|f| f.reaches_root(spacing, self.opening_mm)).map(|f| f.depth_mm).reduce(f64::max)
    }

    /// The opening at the top a V-groove `depth_mm` deep has with the
    /// bevels seen, least and most: `g + d (tan α1 + tan α2)` over root
    /// gaps `g` up to the widest, and for a side whose bevel is not seen,
    /// any bevel angle. None when no bevel is seen.
    pub fn expected_opening_mm(&self, depth_mm: f64) -> Option<(f64, f64)> {
        let run = |deg: f64| depth_mm * deg.to_radians().tan();
        let angles: Vec<f64> = self.bevels().map(|f| f.angle_deg).collect();
        // A root land seen at the bevels' feet widens the bottom as a root
        // gap does: by the feet's distances from the midline, twice the
        // one seen where one bevel is.
        let feet: Vec<f64> = self.bevels().filter(|f| f.foot_on_floor).map(|f| f.foot_mm.max(0.0)).collect();
        let land = match feet.as_slice() {
            [a, b] => a + b,
            [a] => 2.0 * a,
            _ => 0.0,
        };
        let bottom = MAX_ROOT_GAP_MM.max(land);
        match angles.as_slice() {
            [a, b] => Some((run(*a) + run(*b), bottom + run(*a) + run(*b))),
            [a] => Some((run(*a) + run(MIN_BEVEL_DEG), bottom + run(*a) + run(MAX_BEVEL_DEG))),
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
                } else if f.foot_on_floor {
                    " (down to a root land between the plates)"
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
