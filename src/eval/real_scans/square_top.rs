//! A tee root whose flange in view is a narrow sliver: the top of a box
//! section beside a member standing on it, seen only between the standing
//! face and the section's rounded outer edge.
//!
//! A plane fitted freely to a sliver 10 to 25 mm wide with returns
//! scattered a few millimetres about it tilts across its width by degrees
//! with the box, and the root (where it meets the standing face) moves
//! with the tilt. Manufactured hollow sections are square, so the top is
//! fitted square to the standing face: its normal is the one, among those
//! perpendicular to the standing face's normal, that best fits the
//! sliver's points (the one degree of freedom left, the top's tilt along
//! the root, is read over the sliver's whole length), and its offset is
//! the median of the sliver's points along that normal.
//!
//! The assumption is checked on the cloud, not taken: the section's side
//! face below the top (a third large face) must meet the fitted top within
//! [`MAX_OFF_SQUARE_DEG`] of square, and the residual the constraint adds
//! to the sliver's free fit must stay below the noise the sensor shows on
//! the standing face. The measure also says its own uncertainty: the
//! sliver's depths are not independent from point to point (a
//! stereo camera's matching window spans several millimetres), so the
//! offset's and the tilt's one-sigma are read from the scatter of the
//! medians of [`BLOCK_MM`] pieces along the root, and the root's one-sigma
//! is their effect at the visible stretch's ends.

use nalgebra::Matrix2;
use serde::{Deserialize, Serialize};

use crate::geometry::Vec3;
use crate::geometry::fit::{Moments, Plane};

use super::FaceBox;
use super::reference::{MIN_BOX_POINTS, MeasureError, MeasuredPlane, fit_box};

/// A sliver's point counts when it lies farther than this from the
/// standing face's and the side face's planes, mm: axis-aligned boxes
/// along an askew root take in a few points of the large faces beside the
/// sliver, which lie within about four times the sensor's noise on those
/// faces (0.6 to 0.9 mm RMS on the tube-on-beam scans) of their plane.
pub const SLIVER_OFF_FACE_MM: f64 = 4.0;
/// How far from square the side face may meet the fitted top, degrees:
/// hollow sections are made square within about 1 degree at each corner
/// (EN 10219-2), and the side face is two such corners from the standing
/// face (the member's seat on the top and the section's own corner).
pub const MAX_OFF_SQUARE_DEG: f64 = 2.0;
/// The length of the pieces of root whose sliver medians give the
/// uncertainty, mm: longer than the depth camera's matching window at the
/// scans' distance, so the pieces' errors are close to independent.
pub const BLOCK_MM: f64 = 10.0;
/// The least sliver points in a piece for its median to count.
pub const MIN_BLOCK_POINTS: usize = 10;
/// The least pieces for the uncertainty to be read.
pub const MIN_BLOCKS: usize = 4;

/// What the square-top fit measured beside the planes: the checks of its
/// assumption and its uncertainty.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SquareTopFigures {
    /// How far the side face is from square to the fitted top, degrees.
    pub side_off_square_deg: f64,
    /// The angle between the sliver's free least-squares plane and the
    /// fitted top, degrees: what the plain fit would have tilted by.
    pub free_tilt_deg: f64,
    /// The sliver's RMS about its free plane, mm.
    pub free_rms_mm: f64,
    /// The RMS the constraint adds, `sqrt(rms² - free_rms²)`, mm: the part
    /// of the sliver the square top does not explain.
    pub added_rms_mm: f64,
    /// The root's one-sigma at the visible stretch's ends, from the
    /// scatter of the sliver's piece medians, mm.
    pub sigma_mm: f64,
    /// How far the root moves when the top is fitted square to the side
    /// face instead of the standing face, at the visible stretch's ends, mm.
    pub square_to_side_mm: f64,
}

/// The three planes of a square-top root and the sliver's statistics.
pub struct SquareTop {
    /// Standing face, top, side face.
    pub planes: [Plane; 3],
    pub fits: [MeasuredPlane; 3],
    /// The sliver's points (mm) that fixed the top.
    pub sliver: Vec<Vec3>,
    pub side_off_square_deg: f64,
    pub free_tilt_deg: f64,
    pub free_rms_mm: f64,
    pub added_rms_mm: f64,
}

fn angle_deg(a: &Vec3, b: &Vec3) -> f64 {
    a.dot(b).abs().clamp(0.0, 1.0).acos().to_degrees()
}

/// The plane square to `square_to` (its normal perpendicular to that
/// normal) fitting `points` best, with its offset the points' median along
/// its normal.
pub fn square_plane(points: &[Vec3], square_to: &Vec3) -> Option<Plane> {
    let axis = square_to.normalize();
    let helper = if axis.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
    let b1 = axis.cross(&helper).normalize();
    let b2 = axis.cross(&b1);
    let moments: Moments = points.iter().collect();
    let centroid = moments.centroid()?;
    let mut scatter = Matrix2::zeros();
    for p in points {
        let d = p - centroid;
        let q = nalgebra::Vector2::new(d.dot(&b1), d.dot(&b2));
        scatter += q * q.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(scatter);
    let smallest = if eig.eigenvalues[0] <= eig.eigenvalues[1] { 0 } else { 1 };
    let c = eig.eigenvectors.column(smallest);
    let normal = (b1 * c[0] + b2 * c[1]).normalize();
    let offset = median(points.iter().map(|p| normal.dot(p)).collect())?;
    Some(Plane { normal, offset }.facing_away_from_camera())
}

fn rms(points: &[Vec3], plane: &Plane) -> f64 {
    (points.iter().map(|p| plane.signed_distance(p).powi(2)).sum::<f64>() / points.len().max(1) as f64).sqrt()
}

/// Fits a square-top root's planes: `faces` are the standing face, the
/// sliver and the side face, in that order.
pub fn fit_square_top(points: &[[f64; 3]], faces: &[FaceBox], mm_per_unit: f64) -> Result<SquareTop, MeasureError> {
    let (web, web_fit) = fit_box(points, &faces[0], mm_per_unit)?;
    let (side, side_fit) = fit_box(points, &faces[2], mm_per_unit)?;
    let sliver: Vec<Vec3> = points
        .iter()
        .filter(|p| faces[1].contains(p))
        .map(|p| Vec3::from(*p) * mm_per_unit)
        .filter(|p| {
            web.signed_distance(p).abs() > SLIVER_OFF_FACE_MM && side.signed_distance(p).abs() > SLIVER_OFF_FACE_MM
        })
        .collect();
    let name = || faces[1].name.clone();
    if sliver.len() < MIN_BOX_POINTS {
        return Err(MeasureError::TooFewPoints { name: name(), points: sliver.len() });
    }
    let moments: Moments = sliver.iter().collect();
    let free = moments.plane().ok_or_else(|| MeasureError::NoPlane { name: name() })?.facing_away_from_camera();
    let top = square_plane(&sliver, &web.normal).ok_or_else(|| MeasureError::NoPlane { name: name() })?;
    let (free_rms_mm, top_rms) = (rms(&sliver, &free), rms(&sliver, &top));
    let added_rms_mm = (top_rms.powi(2) - free_rms_mm.powi(2)).max(0.0).sqrt();
    let side_off_square_deg = 90.0 - angle_deg(&top.normal, &side.normal);
    if side_off_square_deg > MAX_OFF_SQUARE_DEG {
        return Err(MeasureError::NotSquare {
            why: format!(
                "the side face {:?} meets the top square to {:?} {side_off_square_deg:.2}° off square, beyond {MAX_OFF_SQUARE_DEG}°",
                faces[2].name, faces[0].name
            ),
        });
    }
    if added_rms_mm > web_fit.rms_mm {
        return Err(MeasureError::NotSquare {
            why: format!(
                "a top square to {:?} leaves {added_rms_mm:.2} mm RMS of the sliver unexplained, more than the {:.2} mm the sensor shows on that face",
                faces[0].name, web_fit.rms_mm
            ),
        });
    }
    let top_fit =
        MeasuredPlane { normal: top.normal.into(), offset_mm: top.offset, rms_mm: top_rms, points: sliver.len() };
    Ok(SquareTop {
        planes: [web, top, side],
        fits: [web_fit, top_fit, side_fit],
        free_tilt_deg: angle_deg(&free.normal, &top.normal),
        sliver,
        side_off_square_deg,
        free_rms_mm,
        added_rms_mm,
    })
}

/// The top's one-sigma height at `ends` (mm along `direction` from
/// `point`), from the sliver's medians over [`BLOCK_MM`] pieces of the root:
/// a line through the medians, its offset's and slope's one-sigma from
/// their scatter about it, the larger of the two ends' figures.
pub fn sigma_at_ends(fit: &SquareTop, point: &Vec3, direction: &Vec3, ends: [f64; 2]) -> Result<f64, MeasureError> {
    let top = fit.planes[1];
    let mut pieces: std::collections::BTreeMap<i64, Vec<(f64, f64)>> = std::collections::BTreeMap::new();
    for p in &fit.sliver {
        let t = (p - point).dot(direction);
        pieces.entry((t / BLOCK_MM).floor() as i64).or_default().push((t, top.signed_distance(p)));
    }
    let medians: Vec<(f64, f64)> = pieces
        .values()
        .filter(|v| v.len() >= MIN_BLOCK_POINTS)
        .filter_map(|v| {
            let t = v.iter().map(|(t, _)| t).sum::<f64>() / v.len() as f64;
            median(v.iter().map(|(_, h)| *h).collect()).map(|h| (t, h))
        })
        .collect();
    if medians.len() < MIN_BLOCKS {
        return Err(MeasureError::TooFewPoints { name: "sliver pieces".into(), points: medians.len() });
    }
    let n = medians.len() as f64;
    let t_mean = medians.iter().map(|(t, _)| t).sum::<f64>() / n;
    let h_mean = medians.iter().map(|(_, h)| h).sum::<f64>() / n;
    let stt = medians.iter().map(|(t, _)| (t - t_mean).powi(2)).sum::<f64>();
    let slope = medians.iter().map(|(t, h)| (t - t_mean) * (h - h_mean)).sum::<f64>() / stt;
    let scatter =
        (medians.iter().map(|(t, h)| (h - h_mean - slope * (t - t_mean)).powi(2)).sum::<f64>() / (n - 2.0)).sqrt();
    let (sigma_offset, sigma_slope) = (scatter / n.sqrt(), scatter / stt.sqrt());
    // A height error h of the top moves the root along the standing face by
    // h / sin(angle between the faces).
    let sine = fit.planes[0].normal.cross(&top.normal).norm().max(f64::EPSILON);
    Ok(ends
        .iter()
        .map(|t| (sigma_offset.powi(2) + ((t - t_mean) * sigma_slope).powi(2)).sqrt() / sine)
        .fold(0.0, f64::max))
}

fn median(mut values: Vec<f64>) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 { values[n / 2] } else { (values[n / 2 - 1] + values[n / 2]) / 2.0 })
}
