//! A reference root measured from a cloud: planes fitted to the points in
//! hand-picked boxes, the line where they meet, and the stretch of that
//! line where the camera sees both faces.
//!
//! The visible stretch is where the camera shows the joint on both sides:
//! a point belongs to a face near the root when it lies within
//! [`FACE_BAND_RMS`] of the face's fitted RMS of its plane (at least
//! [`MIN_FACE_BAND_MM`]), off the other surface by as much (so a point in
//! the root's corner, on both planes at once, counts for neither), and
//! within [`NEAR_ROOT_MM`] of where the face meets the other. The line is
//! cut into [`BIN_MM`] pieces; a piece where each face has at least
//! [`MIN_FACE_POINTS_PER_BIN`] such points is seen, and the visible
//! stretch is the longest run of seen pieces, a gap of at most
//! [`MAX_GAP_BINS`] pieces bridged (one missing piece is a dropout, not
//! the joint's end).

use serde::{Deserialize, Serialize};

use crate::cloud::{PointCloud, is_valid_point};
use crate::geometry::Vec3;
use crate::geometry::fit::{Moments, Plane};

use super::square_top::{SquareTopFigures, fit_square_top, sigma_at_ends, square_plane};
use super::{FaceBox, RootKind, RootReference};

/// A face point lies within this many times its plane's fit RMS of the
/// plane.
pub const FACE_BAND_RMS: f64 = 3.0;
/// The least band, mm: a face fitted better than the scan's quantisation
/// still has points a millimetre off.
pub const MIN_FACE_BAND_MM: f64 = 1.0;
/// How far from the root a face is looked at, mm: "both faces seen within a
/// few millimetres of the root", as a fillet's legs or a groove's foot are.
pub const NEAR_ROOT_MM: f64 = 8.0;
/// The length of a piece of root judged seen or not, mm: a few point
/// spacings of the coarsest scan (about 2.6 mm).
pub const BIN_MM: f64 = 5.0;
/// The least points of each face in a piece for it to be seen.
pub const MIN_FACE_POINTS_PER_BIN: usize = 2;
/// The longest run of unseen pieces inside the visible stretch.
pub const MAX_GAP_BINS: usize = 1;
/// The least points in a box for its plane to be fitted.
pub const MIN_BOX_POINTS: usize = 30;
/// Two faces meeting at less than this angle, degrees, have no well-defined
/// line of intersection.
pub const MIN_FACE_ANGLE_DEG: f64 = 10.0;
/// Two reasonable choices of boxes must put the root within this of each
/// other over its visible stretch, mm, for the reference to be kept: half
/// the tee's 1 mm bar. A plan is judged against both roots (a waypoint's
/// distance is the larger of its two), so which choice is the truth does
/// not decide the verdict: a seam right by one and not by the other is not
/// right.
pub const MAX_BOX_CHOICE_MM: f64 = 0.5;

/// A plane fitted to a box's points, mm in the cloud's frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasuredPlane {
    /// Unit normal, facing away from the camera (`z > 0`).
    pub normal: [f64; 3],
    /// `normal · p = offset_mm` on the plane.
    pub offset_mm: f64,
    /// RMS distance of the box's points from the plane.
    pub rms_mm: f64,
    pub points: usize,
}

/// A reference root: the planes, the line and its visible stretch, mm in
/// the cloud's frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasuredRoot {
    /// One per box, in the boxes' order.
    pub planes: Vec<MeasuredPlane>,
    /// A point of the root line: where the faces' points' centroid projects
    /// onto it.
    pub point_mm: [f64; 3],
    /// The line's unit direction, its largest component positive.
    pub direction: [f64; 3],
    /// The visible stretch, from and to, mm along `direction` from
    /// `point_mm`.
    pub visible_mm: [f64; 2],
    /// The share of the visible stretch's pieces where both faces are seen.
    pub seen_share: f64,
    /// How far the root measured from the alternative boxes lies from this
    /// one at the visible stretch's ends, mm (a root with alternative boxes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub box_choice_mm: Option<f64>,
    /// The root measured from the alternative boxes (a root with them):
    /// a plan is judged against it as well.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alternative: Option<RootLine>,
    /// The square-top fit's checks and uncertainty (a square-top root).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub square_top: Option<SquareTopFigures>,
    /// The root's check stretches, in their order: each one's points'
    /// median signed distance from the flange's plane (positive away from
    /// the camera), mm, and how many points.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub checks: Vec<CheckedStretch>,
}

/// A root line alone, mm in the cloud's frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RootLine {
    pub point_mm: [f64; 3],
    /// Unit direction, its largest component positive.
    pub direction: [f64; 3],
}

impl RootLine {
    /// Where `p` lies along the line (mm from `point_mm`) and how far from
    /// it, mm.
    fn along_and_off(&self, p: &Vec3) -> (f64, f64) {
        let direction = Vec3::from(self.direction);
        let d = p - Vec3::from(self.point_mm);
        let t = d.dot(&direction);
        (t, (d - direction * t).norm())
    }

    /// How far `other`'s point lies from this line, mm, and how far the two
    /// directions turn apart (the length of their difference).
    fn moved_from(&self, other: &RootLine) -> (f64, f64) {
        let (_, off) = self.along_and_off(&Vec3::from(other.point_mm));
        (off, (Vec3::from(self.direction) - Vec3::from(other.direction)).norm())
    }
}

/// A stretch of the flange measured against the flange's plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckedStretch {
    pub median_mm: f64,
    pub points: usize,
}

impl MeasuredRoot {
    /// A bare line, no planes or stretch yet.
    fn line(point: Vec3, direction: Vec3) -> MeasuredRoot {
        MeasuredRoot {
            planes: Vec::new(),
            point_mm: point.into(),
            direction: direction.into(),
            visible_mm: [0.0; 2],
            seen_share: 0.0,
            box_choice_mm: None,
            alternative: None,
            square_top: None,
            checks: Vec::new(),
        }
    }

    pub fn point(&self) -> Vec3 {
        Vec3::from(self.point_mm)
    }

    pub fn direction(&self) -> Vec3 {
        Vec3::from(self.direction)
    }

    /// The visible stretch's length, mm.
    pub fn visible_length_mm(&self) -> f64 {
        self.visible_mm[1] - self.visible_mm[0]
    }

    /// Where `p` lies along the root (mm from `point_mm`) and how far from
    /// the line, mm.
    pub fn along_and_off(&self, p: &Vec3) -> (f64, f64) {
        self.root_line().along_and_off(p)
    }

    /// The root's line alone.
    fn root_line(&self) -> RootLine {
        RootLine { point_mm: self.point_mm, direction: self.direction }
    }

    /// Where `p` lies along the root (mm from `point_mm`) and how far from
    /// the root, mm: from the line, or from the farther of the line and
    /// the alternative boxes' line where the root has one.
    pub fn along_and_off_either(&self, p: &Vec3) -> (f64, f64) {
        let (t, off) = self.along_and_off(p);
        (t, self.alternative.map_or(off, |a| off.max(a.along_and_off(p).1)))
    }

    /// The visible stretch's ends, mm.
    pub fn visible_ends(&self) -> [Vec3; 2] {
        self.visible_mm.map(|t| self.point() + self.direction() * t)
    }
}

/// Why a root cannot be measured from its boxes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeasureError {
    #[error("box {name:?} holds {points} points, fewer than {MIN_BOX_POINTS}")]
    TooFewPoints { name: String, points: usize },
    #[error("the points of box {name:?} do not span a plane")]
    NoPlane { name: String },
    #[error("the planes of boxes {a:?} and {b:?} meet at {angle_deg:.1}°, below {MIN_FACE_ANGLE_DEG}°")]
    Parallel { a: String, b: String, angle_deg: f64 },
    #[error("no stretch of the root has both faces seen within {NEAR_ROOT_MM} mm of it")]
    NotSeen,
    #[error("the top is not square to the faces beside it: {why}")]
    NotSquare { why: String },
    #[error(
        "the root from the alternative boxes lies {moved_mm:.2} mm from the root from the boxes, beyond {MAX_BOX_CHOICE_MM} mm"
    )]
    Unsteady { moved_mm: f64 },
}

/// The cloud's valid points in its own units, as f64.
pub fn cloud_points(cloud: &PointCloud) -> Vec<[f64; 3]> {
    cloud.points().iter().filter(|p| is_valid_point(p)).map(|p| p.map(f64::from)).collect()
}

/// Fits a box's plane: its points (in the cloud's units) scaled to mm.
pub fn fit_box(points: &[[f64; 3]], face: &FaceBox, mm_per_unit: f64) -> Result<(Plane, MeasuredPlane), MeasureError> {
    let inside: Vec<Vec3> = points.iter().filter(|p| face.contains(p)).map(|p| Vec3::from(*p) * mm_per_unit).collect();
    if inside.len() < MIN_BOX_POINTS {
        return Err(MeasureError::TooFewPoints { name: face.name.clone(), points: inside.len() });
    }
    let moments: Moments = inside.iter().collect();
    let plane =
        moments.plane().ok_or_else(|| MeasureError::NoPlane { name: face.name.clone() })?.facing_away_from_camera();
    let rms = (inside.iter().map(|p| plane.signed_distance(p).powi(2)).sum::<f64>() / inside.len() as f64).sqrt();
    let measured =
        MeasuredPlane { normal: plane.normal.into(), offset_mm: plane.offset, rms_mm: rms, points: inside.len() };
    Ok((plane, measured))
}

/// The line where two planes meet, through the point of it nearest `near`.
fn meet(a: &Plane, b: &Plane, near: &Vec3) -> Option<(Vec3, Vec3)> {
    let direction = a.normal.cross(&b.normal);
    if direction.norm() < MIN_FACE_ANGLE_DEG.to_radians().sin() {
        return None;
    }
    let direction = direction.normalize();
    let m = nalgebra::Matrix3::from_rows(&[a.normal.transpose(), b.normal.transpose(), direction.transpose()]);
    let point = m.lu().solve(&Vec3::new(a.offset, b.offset, direction.dot(near)))?;
    Some((point, direction))
}

/// The direction with its largest component positive, so a root's
/// direction does not flip between two measurements.
fn canonical(direction: Vec3) -> Vec3 {
    let largest = (0..3).max_by(|&i, &j| direction[i].abs().total_cmp(&direction[j].abs())).unwrap_or(0);
    if direction[largest] < 0.0 { -direction } else { direction }
}

/// Measures a root from its boxes on the cloud's valid points (in the
/// cloud's units).
///
/// A root with alternative boxes is measured from them too, and refused
/// as [`MeasureError::Unsteady`] when the two lines lie more than
/// [`MAX_BOX_CHOICE_MM`] apart at the visible stretch's ends.
pub fn measure_root(points: &[[f64; 3]], root: &RootReference, mm_per_unit: f64) -> Result<MeasuredRoot, MeasureError> {
    let mut measured = measure_boxes(points, root, mm_per_unit)?;
    if !root.alternative.is_empty() {
        let other = RootReference {
            faces: root.alternative.clone(),
            alternative: Vec::new(),
            checks: Vec::new(),
            ..root.clone()
        };
        let other = measure_boxes(points, &other, mm_per_unit)?;
        let moved_mm = measured.visible_ends().iter().map(|p| other.along_and_off(p).1).fold(0.0, f64::max);
        if moved_mm > MAX_BOX_CHOICE_MM {
            return Err(MeasureError::Unsteady { moved_mm });
        }
        measured.box_choice_mm = Some(moved_mm);
        measured.alternative = Some(other.root_line());
    }
    Ok(measured)
}

/// Measures a root from one choice of boxes.
fn measure_boxes(points: &[[f64; 3]], root: &RootReference, mm_per_unit: f64) -> Result<MeasuredRoot, MeasureError> {
    let square = match root.kind {
        RootKind::SquareTop => Some(fit_square_top(points, &root.faces, mm_per_unit)?),
        _ => None,
    };
    let fits: Vec<(Plane, MeasuredPlane)> = match &square {
        Some(s) => s.planes.iter().copied().zip(s.fits).collect(),
        None => root.faces.iter().map(|f| fit_box(points, f, mm_per_unit)).collect::<Result<Vec<_>, _>>()?,
    };
    let planes: Vec<Plane> = fits.iter().map(|(p, _)| *p).collect();
    let all: Vec<Vec3> = points
        .iter()
        .filter(|p| root.faces.iter().any(|f| f.contains(p)))
        .map(|p| Vec3::from(*p) * mm_per_unit)
        .collect();
    let centroid = all.iter().sum::<Vec3>() / all.len().max(1) as f64;
    let parallel = |i: usize, j: usize| MeasureError::Parallel {
        a: root.faces[i].name.clone(),
        b: root.faces[j].name.clone(),
        angle_deg: planes[i].normal.cross(&planes[j].normal).norm().asin().to_degrees(),
    };
    // Each root face's foot: the line it meets the other surface along.
    // (the index of the other surface: the other face, or the land).
    let (feet, other): ([(Vec3, Vec3); 2], [usize; 2]) = match root.kind {
        RootKind::Meet | RootKind::SquareTop => {
            let foot = meet(&planes[0], &planes[1], &centroid).ok_or_else(|| parallel(0, 1))?;
            ([foot, foot], [1, 0])
        }
        RootKind::LandCentre => {
            let a = meet(&planes[0], &planes[2], &centroid).ok_or_else(|| parallel(0, 2))?;
            let b = meet(&planes[1], &planes[2], &a.0).ok_or_else(|| parallel(1, 2))?;
            ([a, b], [2, 2])
        }
    };
    let d0 = canonical(feet[0].1);
    let d1 = canonical(feet[1].1);
    let direction = (d0 + d1).normalize();
    let middle = (feet[0].0 + feet[1].0) / 2.0;
    // The point of the line nearest the faces' centroid.
    let point = middle + direction * (centroid - middle).dot(&direction);

    let bands: Vec<f64> = fits.iter().map(|(_, m)| (FACE_BAND_RMS * m.rms_mm).max(MIN_FACE_BAND_MM)).collect();
    // Pieces along the root with points of face 0 and of face 1.
    // Per piece: points of each face, and the least and greatest `along`.
    let mut counts: std::collections::BTreeMap<i64, ([usize; 2], [f64; 2])> = std::collections::BTreeMap::new();
    for raw in points {
        let p = Vec3::from(*raw) * mm_per_unit;
        for face in 0..2 {
            let (foot_point, foot_direction) = feet[face];
            let from_foot = p - foot_point;
            let off_foot = (from_foot - foot_direction * from_foot.dot(&foot_direction)).norm();
            if off_foot > NEAR_ROOT_MM
                || planes[face].signed_distance(&p).abs() > bands[face]
                || planes[other[face]].signed_distance(&p).abs() <= bands[other[face]]
            {
                continue;
            }
            let along = (p - point).dot(&direction);
            let piece = counts.entry((along / BIN_MM).floor() as i64).or_insert(([0; 2], [along, along]));
            piece.0[face] += 1;
            piece.1 = [piece.1[0].min(along), piece.1[1].max(along)];
        }
    }
    let seen: Vec<i64> = counts
        .iter()
        .filter(|(_, (c, _))| c.iter().all(|&n| n >= MIN_FACE_POINTS_PER_BIN))
        .map(|(&bin, _)| bin)
        .collect();
    let (first, last, seen_in_run) = longest_run(&seen).ok_or(MeasureError::NotSeen)?;
    let pieces = (last - first + 1) as f64;
    // From the first seen piece's first face point to the last one's last,
    // so the stretch ends where the faces are seen to end.
    let visible_mm = [counts[&first].1[0], counts[&last].1[1]];
    let square_top = match &square {
        Some(s) => {
            // The root if the top were square to the side face instead.
            let name = root.faces[1].name.clone();
            let other = square_plane(&s.sliver, &planes[2].normal).ok_or(MeasureError::NoPlane { name })?;
            let other = meet(&planes[0], &other, &point).ok_or_else(|| parallel(0, 1))?;
            let other = MeasuredRoot {
                point_mm: other.0.into(),
                direction: other.1.into(),
                ..MeasuredRoot::line(point, direction)
            };
            let ends = visible_mm.map(|t| point + direction * t);
            Some(SquareTopFigures {
                side_off_square_deg: s.side_off_square_deg,
                free_tilt_deg: s.free_tilt_deg,
                free_rms_mm: s.free_rms_mm,
                added_rms_mm: s.added_rms_mm,
                sigma_mm: sigma_at_ends(s, &point, &direction, visible_mm)?,
                square_to_side_mm: ends.iter().map(|p| other.along_and_off(p).1).fold(0.0, f64::max),
            })
        }
        None => None,
    };
    // The flange: the second face, or a groove's land.
    let flange = match root.kind {
        RootKind::LandCentre => planes[2],
        RootKind::Meet | RootKind::SquareTop => planes[1],
    };
    let checks = root
        .checks
        .iter()
        .map(|check| {
            let distances: Vec<f64> = points
                .iter()
                .filter(|p| check.contains(p))
                .map(|p| flange.signed_distance(&(Vec3::from(*p) * mm_per_unit)))
                .collect();
            let points = distances.len();
            if points < MIN_BOX_POINTS {
                return Err(MeasureError::TooFewPoints { name: check.name.clone(), points });
            }
            Ok(CheckedStretch { median_mm: median(distances), points })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(MeasuredRoot {
        planes: fits.into_iter().map(|(_, m)| m).collect(),
        checks,
        visible_mm,
        seen_share: seen_in_run as f64 / pieces,
        square_top,
        ..MeasuredRoot::line(point, direction)
    })
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { (values[n / 2 - 1] + values[n / 2]) / 2.0 }
}

/// The longest run of sorted bin indices with gaps of at most
/// [`MAX_GAP_BINS`]: its first and last bin and how many bins of it are
/// seen.
fn longest_run(seen: &[i64]) -> Option<(i64, i64, usize)> {
    let mut best: Option<(i64, i64, usize)> = None;
    let mut start = 0;
    for k in 0..seen.len() {
        let ends_here = k + 1 == seen.len() || seen[k + 1] - seen[k] > MAX_GAP_BINS as i64 + 1;
        if ends_here {
            let run = (seen[start], seen[k], k + 1 - start);
            if best.is_none_or(|b| run.1 - run.0 > b.1 - b.0) {
                best = Some(run);
            }
            start = k + 1;
        }
    }
    best
}

/// How far two measurements of a root may differ and still be the same
/// reference: the file's figures are written rounded to these.
pub const CHECK_TOLERANCE_MM: f64 = 0.01;
pub const CHECK_TOLERANCE_DIRECTION: f64 = 1e-5;

/// Where a recomputed root differs from the committed one, in words; None
/// when they agree within the tolerances.
pub fn differs(committed: &MeasuredRoot, recomputed: &MeasuredRoot) -> Option<String> {
    let mut problems = Vec::new();
    if committed.planes.len() != recomputed.planes.len() {
        problems.push(format!("{} planes, recomputed {}", committed.planes.len(), recomputed.planes.len()));
    }
    for (k, (a, b)) in committed.planes.iter().zip(&recomputed.planes).enumerate() {
        let turn = (Vec3::from(a.normal) - Vec3::from(b.normal)).norm();
        if turn > CHECK_TOLERANCE_DIRECTION
            || (a.offset_mm - b.offset_mm).abs() > CHECK_TOLERANCE_MM
            || (a.rms_mm - b.rms_mm).abs() > CHECK_TOLERANCE_MM
            || a.points != b.points
        {
            problems.push(format!("plane {}: committed {a:?}, recomputed {b:?}", k + 1));
        }
    }
    // The line: the committed point's distance from the recomputed line,
    // and the turn between directions.
    let moved = |committed: &RootLine, recomputed: &RootLine| {
        let (off, turn) = recomputed.moved_from(committed);
        (off > CHECK_TOLERANCE_MM || turn > CHECK_TOLERANCE_DIRECTION).then_some((off, turn))
    };
    if let Some((off, turn)) = moved(&committed.root_line(), &recomputed.root_line()) {
        problems.push(format!("the line moved {off:.4} mm and turned by {turn:.2e}"));
    }
    let alternative_moved = match (&committed.alternative, &recomputed.alternative) {
        (None, None) => false,
        (Some(a), Some(b)) => moved(a, b).is_some(),
        _ => true,
    };
    if alternative_moved {
        problems.push(format!(
            "the alternative boxes' line: committed {:?}, recomputed {:?}",
            committed.alternative, recomputed.alternative
        ));
    }
    let ends = |m: &MeasuredRoot| m.visible_ends();
    let moved = ends(committed).iter().zip(ends(recomputed)).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    if moved > CHECK_TOLERANCE_MM || (committed.seen_share - recomputed.seen_share).abs() > 1e-3 {
        problems.push(format!(
            "the visible stretch: committed {:?} mm ({:.3} seen), recomputed {:?} mm ({:.3} seen)",
            committed.visible_mm, committed.seen_share, recomputed.visible_mm, recomputed.seen_share
        ));
    }
    let figures = |m: &MeasuredRoot| {
        let mut v: Vec<f64> = m.box_choice_mm.into_iter().collect();
        if let Some(s) = m.square_top {
            v.extend([
                s.side_off_square_deg,
                s.free_tilt_deg,
                s.free_rms_mm,
                s.added_rms_mm,
                s.sigma_mm,
                s.square_to_side_mm,
            ]);
        }
        v
    };
    let (a, b) = (figures(committed), figures(recomputed));
    if committed.checks.len() != recomputed.checks.len()
        || committed
            .checks
            .iter()
            .zip(&recomputed.checks)
            .any(|(x, y)| (x.median_mm - y.median_mm).abs() > CHECK_TOLERANCE_MM || x.points != y.points)
    {
        problems.push(format!("the checks: committed {:?}, recomputed {:?}", committed.checks, recomputed.checks));
    }
    if a.len() != b.len() || a.iter().zip(&b).any(|(x, y)| (x - y).abs() > CHECK_TOLERANCE_MM) {
        problems.push(format!(
            "the box choice and square-top figures: committed {:?} / {:?}, recomputed {:?} / {:?}",
            committed.box_choice_mm, committed.square_top, recomputed.box_choice_mm, recomputed.square_top
        ));
    }
    (!problems.is_empty()).then(|| problems.join("; "))
}

/// The root's figures rounded as the references file keeps them: mm to
/// 1e-3, directions to 1e-7.
pub fn rounded(m: &MeasuredRoot) -> MeasuredRoot {
    let mm = |v: f64| (v * 1e3).round() / 1e3;
    let unit = |v: f64| (v * 1e7).round() / 1e7;
    MeasuredRoot {
        planes: m
            .planes
            .iter()
            .map(|p| MeasuredPlane {
                normal: p.normal.map(unit),
                offset_mm: mm(p.offset_mm),
                rms_mm: mm(p.rms_mm),
                points: p.points,
            })
            .collect(),
        point_mm: m.point_mm.map(mm),
        direction: m.direction.map(unit),
        visible_mm: m.visible_mm.map(mm),
        seen_share: (m.seen_share * 1e3).round() / 1e3,
        box_choice_mm: m.box_choice_mm.map(mm),
        alternative: m.alternative.map(|a| RootLine { point_mm: a.point_mm.map(mm), direction: a.direction.map(unit) }),
        checks: m.checks.iter().map(|c| CheckedStretch { median_mm: mm(c.median_mm), points: c.points }).collect(),
        square_top: m.square_top.map(|s| SquareTopFigures {
            side_off_square_deg: mm(s.side_off_square_deg),
            free_tilt_deg: mm(s.free_tilt_deg),
            free_rms_mm: mm(s.free_rms_mm),
            added_rms_mm: mm(s.added_rms_mm),
            sigma_mm: mm(s.sigma_mm),
            square_to_side_mm: mm(s.square_to_side_mm),
        }),
    }
}
