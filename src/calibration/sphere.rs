//! Calibration spheres in a point cloud: every sphere of a given radius
//! fitted in one capture's cloud, whatever else the cloud holds (the table,
//! the posts, fixtures, stray returns).
//!
//! A ball seen from a camera is a cap facing it, and every point of the
//! cap lies one radius from the centre along its surface normal. So each
//! point (a bounded random sample of [`VOTE_POINTS`]) gets a normal from
//! the plane of its neighbours ([`NORMAL_NEIGHBOURHOOD`] of the radius
//! around it, in the whole cloud), turned towards the camera, and votes
//! for a centre one given radius behind it. A ball's votes pile up at its
//! centre; a plane's spread over a plane, a post's over a half-cylinder,
//! stray returns' anywhere, so the densest piles are the candidates (at
//! most [`MAX_CANDIDATES_PER_RADIUS`] per radius, each at least
//! [`MIN_VOTES`] votes). Each candidate is refined by Levenberg-Marquardt
//! on the geometric distance `|p - c| - r` under a Huber loss, first with
//! the radius free (a real ball measures its own radius), then with the
//! given radius (the centre of a cap seen from one side is pinned far
//! better with the radius known), and kept only when its points cover a
//! cap the way a ball seen from the camera does: a cap of at least
//! [`MIN_CAP_HALF_ANGLE_DEG`] (or, for a ball partly hidden whose fit holds
//! its radius and surface more firmly, [`MIN_PARTIAL_CAP_HALF_ANGLE_DEG`]),
//! round ([`MIN_CAP_ROUNDNESS`]: a strip of a
//! cylinder is not), facing the camera ([`MAX_CAP_OFF_AXIS_DEG`]), its
//! points' normals along the radius ([`MIN_NORMAL_AGREEMENT`]), the
//! points close to the surface ([`MAX_RMS_OVER_BAND`]). A plane patch or a
//! post fails the cap; a cluster of stray returns fails the normals.
//!
//! Which given sphere each fit is, is the business of
//! [`super::naming`]: by radius when the radii differ, by the layout's
//! distances when they do not.

use nalgebra::{DMatrix, Matrix2, Matrix3, SymmetricEigen};
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::refine::{self, Blocks};
use crate::geometry::{Vec3, vec3};

/// The most spheres one capture may hold.
pub const MAX_SPHERES: usize = 6;

/// The most spheres kept from one cloud (the best supported): the given
/// spheres and a few look-alikes for the naming to sort out.
pub const MAX_FOUND: usize = MAX_SPHERES + 2;

/// The smallest and largest sphere radius accepted, mm.
pub const RADIUS_RANGE_MM: [f64; 2] = [2.0, 500.0];

/// Radii at least this far apart name their spheres by size.
pub const MIN_RADIUS_GAP_MM: f64 = 3.0;

/// The points that vote (a seeded random sample of the cloud); the
/// refinement and the normals use every point.
pub const VOTE_POINTS: usize = 40_000;

/// A voting point's normal comes from its neighbours within this
/// fraction of the smallest radius (at least 1 mm): wide enough to
/// average the sensor's noise, narrow enough to stay on a ball's cap.
pub const NORMAL_NEIGHBOURHOOD: f64 = 0.2;

/// The fewest neighbours a normal is estimated from.
pub const MIN_NORMAL_NEIGHBOURS: usize = 8;

/// The votes are counted in cells of this fraction of the radius (at
/// least 0.5 mm), each pile over the 27 cells around one.
pub const VOTE_CELL_FRACTION: f64 = 0.05;

/// The fewest votes a candidate centre needs.
pub const MIN_VOTES: usize = 12;

/// Candidate centres tried per given radius, the most voted first.
pub const MAX_CANDIDATES_PER_RADIUS: usize = 16;

/// The cap's half-angle, from the spread of its points' directions from
/// the centre, must be at least this, degrees: a ball's visible cap is
/// 60 to 85 degrees; a patch of plane or post inside the shell is far
/// smaller.
pub const MIN_CAP_HALF_ANGLE_DEG: f64 = 25.0;

/// A ball partly hidden (cut by the view's edge, or behind another ball)
/// shows less of its cap: it is still accepted down to this half-angle,
/// degrees, when the fit says more firmly than usual that it is a ball of
/// the given radius: the radius it measures with the radius free within
/// [`PARTIAL_CAP_FIT_FRACTION`] of the inlier band, and its points' RMS
/// distance from the surface within that fraction too. On the simulated
/// tooling-ball rig such balls' caps measure 25.0 and 29.6 degrees with the
/// radius within 0.02 mm and an RMS of 0.03 mm or less, while a patch of
/// table or post does not measure the ball's radius at all (kilometres, or
/// 20 to 33 mm for a 19.05 mm ball); 20 degrees leaves a little room below
/// the smallest seen, and the firmer fit makes up for the smaller cap's
/// weaker hold on the radius.
pub const MIN_PARTIAL_CAP_HALF_ANGLE_DEG: f64 = 20.0;

/// See [`MIN_PARTIAL_CAP_HALF_ANGLE_DEG`]: a quarter of the band (0.1 mm
/// for a 19.05 mm ball), half of what any cap is allowed
/// ([`MAX_RMS_OVER_BAND`]).
pub const PARTIAL_CAP_FIT_FRACTION: f64 = 0.25;

/// The cap's axis (the mean direction of its points from the centre)
/// must point within this of the camera, degrees.
pub const MAX_CAP_OFF_AXIS_DEG: f64 = 70.0;

/// The cap's directions, across its axis, must spread at least this
/// fraction as much one way as the other: a cap is round, a strip of a
/// cylinder of about the ball's radius is not.
pub const MIN_CAP_ROUNDNESS: f64 = 0.1;

/// The fraction of the cap's voting points whose normal lies within
/// [`NORMAL_AGREEMENT_DEG`] of the direction from the centre.
pub const MIN_NORMAL_AGREEMENT: f64 = 0.6;

/// See [`MIN_NORMAL_AGREEMENT`].
pub const NORMAL_AGREEMENT_DEG: f64 = 20.0;

/// The most points the refinement uses (a uniform subsample): the
/// centre of twenty thousand points with the sensor's noise is already
/// pinned to microns, and the cost stays bounded whatever the cloud.
pub const REFINE_MAX_POINTS: usize = 20_000;

/// The most points the fits that only place the narrow shell use (the
/// first fit on the wide shell and the narrowing passes): they need the
/// centre within a fraction of the band, which a few thousand points give
/// to a few microns, and they run for every candidate, most of them a
/// patch of table or post that the measured radius then turns away. The
/// fits that measure the radius and the centre use up to
/// [`REFINE_MAX_POINTS`].
pub const PLACING_MAX_POINTS: usize = 4_000;

/// The first fit of a candidate uses the points within this fraction of
/// the radius of its surface (at least three bands).
pub const WIDE_SHELL_FRACTION: f64 = 0.15;

/// Fits with the radius given on the narrow shell (three bands) before
/// the radius is measured.
pub const NARROWING_PASSES: usize = 2;

/// The fewest points on a sphere's surface for it to count as seen.
pub const MIN_SPHERE_POINTS: usize = 150;

/// A fit whose surface points lie further than this fraction of the
/// inlier band from it, RMS, is not a sphere of that radius.
pub const MAX_RMS_OVER_BAND: f64 = 0.5;

/// The half-width of the shell that counts as a sphere's surface, mm: 2 % of the radius, at least 0.3 mm (the sensor's noise
/// and a few pixels' mixing at the rim stay inside).
pub fn inlier_band(radius_mm: f64) -> f64 {
    (0.02 * radius_mm).max(0.3)
}

/// One sphere fitted in a capture.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedSphere {
    /// The centre in the camera frame, mm.
    pub centre: Vec3,
    /// The radius the fit measured with the radius free, mm.
    pub measured_radius_mm: f64,
    /// Which of the given radii it is (the first index of that radius).
    pub radius_index: usize,
    /// The points on its surface.
    pub points: usize,
    /// RMS of their distances to the surface, mm.
    pub rms_mm: f64,
    /// The half-angle of the cap its points cover, degrees.
    pub cap_half_angle_deg: f64,
}

/// Why spheres could not be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SphereError {
    #[error("{count} sphere radii given; at most {MAX_SPHERES} spheres are supported")]
    TooManySpheres { count: usize },
    #[error("no sphere radius given")]
    NoRadius,
    #[error("sphere radius {radius} mm is outside {} to {} mm", RADIUS_RANGE_MM[0], RADIUS_RANGE_MM[1])]
    Radius { radius: f64 },
}

/// Checks the given radii.
pub fn check_radii(radii: &[f64]) -> Result<(), SphereError> {
    if radii.is_empty() {
        return Err(SphereError::NoRadius);
    }
    if radii.len() > MAX_SPHERES {
        return Err(SphereError::TooManySpheres { count: radii.len() });
    }
    match radii.iter().find(|r| !(RADIUS_RANGE_MM[0]..=RADIUS_RANGE_MM[1]).contains(*r)) {
        Some(&radius) => Err(SphereError::Radius { radius }),
        None => Ok(()),
    }
}

/// True when every pair of radii differs by at least [`MIN_RADIUS_GAP_MM`]:
/// the spheres are then named by size.
pub fn radii_distinct(radii: &[f64]) -> bool {
    radii.iter().enumerate().all(|(i, a)| radii[..i].iter().all(|b| (a - b).abs() >= MIN_RADIUS_GAP_MM))
}

/// The first index of each given radius's class (radii closer than
/// [`MIN_RADIUS_GAP_MM`] are one class).
pub fn radius_classes(radii: &[f64]) -> Vec<usize> {
    (0..radii.len()).map(|k| (0..=k).find(|&j| (radii[j] - radii[k]).abs() < MIN_RADIUS_GAP_MM).unwrap_or(k)).collect()
}

/// A voting point: where it is and its surface normal, towards the camera.
struct Oriented {
    point: Vec3,
    normal: Vec3,
}

/// Finds the spheres of the given radii among `points` (camera frame,
/// mm; invalid points are skipped): every one that passes the cap's
/// checks, the best supported first, at most [`MAX_FOUND`]. `seed` makes
/// the voting sample repeatable.
pub fn fit_spheres(points: &[[f32; 3]], radii: &[f64], seed: u64) -> Result<Vec<FittedSphere>, SphereError> {
    check_radii(radii)?;
    let valid: Vec<Vec3> = points.iter().filter(|p| p.iter().all(|v| v.is_finite())).map(vec3).collect();
    if valid.len() < MIN_SPHERE_POINTS {
        return Ok(Vec::new());
    }
    let smallest = radii.iter().copied().fold(f64::INFINITY, f64::min);
    let neighbourhood = (NORMAL_NEIGHBOURHOOD * smallest).max(1.0);
    let grid = Grid::new(&valid, neighbourhood);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let voters: Vec<usize> = if valid.len() <= VOTE_POINTS {
        (0..valid.len()).collect()
    } else {
        (0..VOTE_POINTS).map(|_| below(&mut rng, valid.len())).collect()
    };
    let oriented: Vec<Oriented> =
        voters.iter().filter_map(|&i| normal_at(&valid, &grid, &valid[i], neighbourhood)).collect();
    let classes = radius_classes(radii);
    let mut order: Vec<usize> = (0..radii.len()).filter(|&k| classes[k] == k).collect();
    order.sort_by(|a, b| radii[*b].total_cmp(&radii[*a]));
    let mut claimed = vec![false; valid.len()];
    let mut found: Vec<FittedSphere> = Vec::new();
    for k in order {
        let radius = radii[k];
        for candidate in vote_peaks(&oriented, radius) {
            let Some(sphere) = check_candidate(&valid, &grid, &claimed, &oriented, candidate, radius, k) else {
                continue;
            };
            let reach = radius + 3.0 * inlier_band(radius);
            for i in grid.within(&valid, &sphere.centre, reach) {
                claimed[i] = true;
            }
            found.push(sphere);
        }
    }
    found.sort_by_key(|s| std::cmp::Reverse(s.points));
    found.truncate(MAX_FOUND);
    Ok(found)
}

/// Uniform index below `n` (n > 0).
fn below(rng: &mut ChaCha8Rng, n: usize) -> usize {
    (rng.next_u64() % n as u64) as usize
}

/// The normal of the plane through `p`'s neighbours, turned towards the
/// camera (the origin); `None` with too few neighbours.
fn normal_at(points: &[Vec3], grid: &Grid, p: &Vec3, reach: f64) -> Option<Oriented> {
    let near = grid.within(points, p, reach);
    if near.len() < MIN_NORMAL_NEIGHBOURS {
        return None;
    }
    let n = near.len() as f64;
    let mean = near.iter().fold(Vec3::zeros(), |s, &i| s + points[i]) / n;
    let scatter = near.iter().fold(Matrix3::zeros(), |s, &i| {
        let d = points[i] - mean;
        s + d * d.transpose()
    });
    let eigen = SymmetricEigen::new(scatter);
    let (smallest, _) = eigen.eigenvalues.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    let normal: Vec3 = eigen.eigenvectors.column(smallest).into_owned();
    let normal = if normal.dot(p) > 0.0 { -normal } else { normal };
    normal.iter().all(|v| v.is_finite()).then_some(Oriented { point: *p, normal })
}

/// The centres the votes for `radius` pile up at, the largest pile
/// first; piles closer than a radius to a larger one are its part.
fn vote_peaks(oriented: &[Oriented], radius: f64) -> Vec<Vec3> {
    let cell = (VOTE_CELL_FRACTION * radius).max(0.5);
    let mut cells: std::collections::HashMap<[i64; 3], (usize, Vec3)> = std::collections::HashMap::new();
    for o in oriented {
        let vote = o.point - radius * o.normal;
        let entry = cells.entry(Grid::key(&vote, cell)).or_insert((0, Vec3::zeros()));
        entry.0 += 1;
        entry.1 += vote;
    }
    let pile = |key: &[i64; 3]| {
        let mut count = 0;
        let mut sum = Vec3::zeros();
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some((c, s)) = cells.get(&[key[0] + dx, key[1] + dy, key[2] + dz]) {
                        count += c;
                        sum += s;
                    }
                }
            }
        }
        (count, sum / count.max(1) as f64)
    };
    let mut piles: Vec<(usize, Vec3)> =
        cells.iter().filter(|(_, (c, _))| *c > 0).map(|(key, _)| pile(key)).filter(|(c, _)| *c >= MIN_VOTES).collect();
    piles.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.x.total_cmp(&b.1.x)));
    let mut peaks: Vec<Vec3> = Vec::new();
    for (_, centre) in piles {
        if peaks.len() == MAX_CANDIDATES_PER_RADIUS {
            break;
        }
        if peaks.iter().all(|p| (p - centre).norm() >= radius) {
            peaks.push(centre);
        }
    }
    peaks
}

/// Refines a candidate centre and keeps it when its points form a ball's
/// cap as the camera sees one.
fn check_candidate(
    points: &[Vec3],
    grid: &Grid,
    claimed: &[bool],
    oriented: &[Oriented],
    candidate: Vec3,
    radius: f64,
    radius_index: usize,
) -> Option<FittedSphere> {
    let band = inlier_band(radius);
    // The votes place the centre to a millimetre or two: a first fit on a
    // wide shell brings it within the band.
    let wide = (WIDE_SHELL_FRACTION * radius).max(3.0 * band);
    let free: Vec<usize> =
        grid.within(points, &candidate, radius + wide + 1.0).into_iter().filter(|&i| !claimed[i]).collect();
    let around = shell(points, &free, &candidate, radius, wide);
    if around.len() < MIN_SPHERE_POINTS {
        return None;
    }
    let around: Vec<Vec3> = around.iter().step_by(around.len().div_ceil(PLACING_MAX_POINTS)).copied().collect();
    let coarse = fit_surface(&around, &[candidate.x, candidate.y, candidate.z], Some(radius))?;
    let mut candidate = Vec3::new(coarse[0], coarse[1], coarse[2]);
    // Then on the narrow shell around it, twice: each pass leaves out
    // more of the post and the table.
    for _ in 0..NARROWING_PASSES {
        let near = shell(points, &free, &candidate, radius, 3.0 * band);
        if near.len() < MIN_SPHERE_POINTS {
            return None;
        }
        let near: Vec<Vec3> = near.iter().step_by(near.len().div_ceil(PLACING_MAX_POINTS)).copied().collect();
        let fit = fit_surface(&near, &[candidate.x, candidate.y, candidate.z], Some(radius))?;
        candidate = Vec3::new(fit[0], fit[1], fit[2]);
    }
    let near = shell(points, &free, &candidate, radius, 3.0 * band);
    if near.len() < MIN_SPHERE_POINTS {
        return None;
    }
    let near: Vec<Vec3> = near.iter().step_by(near.len().div_ceil(REFINE_MAX_POINTS)).copied().collect();
    let free_fit = fit_surface(&near, &[candidate.x, candidate.y, candidate.z, radius], None)?;
    let measured = free_fit[3];
    // A real ball measures its own radius to a few hundredths of a
    // millimetre; a patch of something else does not.
    if (measured - radius).abs() > band {
        return None;
    }
    let fixed = fit_surface(&near, &free_fit[..3], Some(radius))?;
    let centre = Vec3::new(fixed[0], fixed[1], fixed[2]);
    let on_surface = shell(points, &free, &centre, radius, band);
    if on_surface.len() < MIN_SPHERE_POINTS {
        return None;
    }
    let rms = (on_surface.iter().map(|q| ((q - centre).norm() - radius).powi(2)).sum::<f64>()
        / on_surface.len() as f64)
        .sqrt();
    if rms > MAX_RMS_OVER_BAND * band {
        return None;
    }
    let firm = (measured - radius).abs() <= PARTIAL_CAP_FIT_FRACTION * band && rms <= PARTIAL_CAP_FIT_FRACTION * band;
    let min_half_angle = if firm { MIN_PARTIAL_CAP_HALF_ANGLE_DEG } else { MIN_CAP_HALF_ANGLE_DEG };
    let cap_half_angle_deg = cap_shape(&on_surface, &centre, min_half_angle)?;
    let agreeing = normal_agreement(oriented, &centre, radius, band)?;
    (agreeing >= MIN_NORMAL_AGREEMENT).then_some(FittedSphere {
        centre,
        measured_radius_mm: measured,
        radius_index,
        points: on_surface.len(),
        rms_mm: rms,
        cap_half_angle_deg,
    })
}

/// The sphere through `points` under the Huber loss on their distances
/// from its surface, `|q - c| - r`, from `start`: the centre `c`, and
/// the radius as a fourth parameter when `radius` is `None` (free). The
/// distances' Jacobian is written out (`-(q - c) / |q - c|` for the
/// centre, `-1` for the radius): the fit runs over up to
/// [`REFINE_MAX_POINTS`] points many times per candidate, and central
/// differences would evaluate them eight times a step for the same
/// minimum.
fn fit_surface(points: &[Vec3], start: &[f64], radius: Option<f64>) -> Option<Vec<f64>> {
    let centre = |p: &[f64]| Vec3::new(p[0], p[1], p[2]);
    let radius_of = |p: &[f64]| radius.unwrap_or_else(|| p[3]);
    let residuals = |p: &[f64]| -> Blocks {
        let (c, r) = (centre(p), radius_of(p));
        points.iter().map(|q| [(q - c).norm() - r]).collect()
    };
    let jacobian = |p: &[f64]| -> DMatrix<f64> {
        let c = centre(p);
        let mut jac = DMatrix::zeros(points.len(), p.len());
        for (row, q) in points.iter().enumerate() {
            let towards = (q - c) / (q - c).norm();
            for k in 0..3 {
                jac[(row, k)] = -towards[k];
            }
            if radius.is_none() {
                jac[(row, 3)] = -1.0;
            }
        }
        jac
    };
    refine::robust_fit_with_jacobian(start, &residuals, &jacobian).ok().map(|fit| fit.params)
}

/// The cap's half-angle, degrees, when the points' directions from the
/// centre cover a round cap facing the camera at least `min_half_angle`
/// wide; `None` otherwise. For a cap of half-angle `a` evenly covered the
/// mean of the unit directions is `(1 + cos a) / 2` long.
fn cap_shape(on_surface: &[Vec3], centre: &Vec3, min_half_angle: f64) -> Option<f64> {
    let n = on_surface.len() as f64;
    let directions: Vec<Vec3> = on_surface.iter().map(|p| (p - centre).normalize()).collect();
    let mean = directions.iter().fold(Vec3::zeros(), |s, d| s + d) / n;
    let length = mean.norm();
    let half_angle = (2.0 * length - 1.0).clamp(-1.0, 1.0).acos().to_degrees();
    let axis = mean / length.max(1e-12);
    let off_axis = axis.dot(&(-centre).normalize()).clamp(-1.0, 1.0).acos().to_degrees();
    if half_angle < min_half_angle || off_axis > MAX_CAP_OFF_AXIS_DEG {
        return None;
    }
    // The directions' spread across the axis, in two directions.
    let u = axis.cross(&if axis.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() }).normalize();
    let v = axis.cross(&u);
    let spread = directions.iter().fold(Matrix2::zeros(), |s, d| {
        let q = nalgebra::Vector2::new(d.dot(&u), d.dot(&v));
        s + q * q.transpose()
    });
    let eigen = SymmetricEigen::new(spread).eigenvalues;
    let (lo, hi) = (eigen.min(), eigen.max());
    (hi > 0.0 && lo / hi >= MIN_CAP_ROUNDNESS).then_some(half_angle)
}

/// The fraction of the voting points on the sphere's surface whose
/// normal lies along the direction from the centre; `None` when too few
/// voting points lie there to tell.
fn normal_agreement(oriented: &[Oriented], centre: &Vec3, radius: f64, band: f64) -> Option<f64> {
    let limit = NORMAL_AGREEMENT_DEG.to_radians().cos();
    let (mut on, mut agreeing) = (0usize, 0usize);
    for o in oriented {
        let d = o.point - centre;
        let distance = d.norm();
        if (distance - radius).abs() < band {
            on += 1;
            if o.normal.dot(&(d / distance)) >= limit {
                agreeing += 1;
            }
        }
    }
    (on >= MIN_NORMAL_NEIGHBOURS).then(|| agreeing as f64 / on as f64)
}

/// The fit's points: those among `free` within `band` of the sphere.
fn shell(points: &[Vec3], free: &[usize], centre: &Vec3, radius: f64, band: f64) -> Vec<Vec3> {
    free.iter().map(|&i| points[i]).filter(|p| ((p - centre).norm() - radius).abs() < band).collect()
}

/// A uniform grid of point indices.
struct Grid {
    cell: f64,
    cells: std::collections::HashMap<[i64; 3], Vec<usize>>,
}

impl Grid {
    fn new(points: &[Vec3], cell: f64) -> Grid {
        let mut cells: std::collections::HashMap<[i64; 3], Vec<usize>> = std::collections::HashMap::new();
        for (i, p) in points.iter().enumerate() {
            cells.entry(Self::key(p, cell)).or_default().push(i);
        }
        Grid { cell, cells }
    }

    fn key(p: &Vec3, cell: f64) -> [i64; 3] {
        [p.x, p.y, p.z].map(|v| (v / cell).floor() as i64)
    }

    /// Indices of the points within `radius` of `centre`.
    fn within(&self, points: &[Vec3], centre: &Vec3, radius: f64) -> Vec<usize> {
        let lo = Self::key(&(centre - Vec3::repeat(radius)), self.cell);
        let hi = Self::key(&(centre + Vec3::repeat(radius)), self.cell);
        let mut out = Vec::new();
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if let Some(list) = self.cells.get(&[x, y, z]) {
                        out.extend(list.iter().copied().filter(|&i| (points[i] - centre).norm() <= radius));
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the camera-facing cap of a sphere, with a little
    /// deterministic noise, and a plane behind it.
    fn cap(centre: Vec3, radius: f64, step: f64) -> Vec<[f32; 3]> {
        let mut out = Vec::new();
        let mut k = 0u32;
        let n = (radius / step) as i64;
        for i in -n..=n {
            for j in -n..=n {
                let (x, y) = (i as f64 * step, j as f64 * step);
                let h = radius * radius - x * x - y * y;
                if h > (0.2 * radius).powi(2) {
                    k += 1;
                    let noise = 0.03 * ((k as f64) * 1.7).sin();
                    let p = centre + Vec3::new(x, y, -h.sqrt() - noise);
                    out.push([p.x as f32, p.y as f32, p.z as f32]);
                }
            }
        }
        out
    }

    /// The written-out Jacobian is the reference's: the fit by central
    /// differences ([`refine::robust_fit`]) reaches the same sphere, with
    /// the radius given and free, from a start a few millimetres off and
    /// with a tenth of the points far from the surface.
    #[test]
    fn the_surface_fit_reaches_the_central_difference_fits_minimum() {
        let centre = Vec3::new(12.0, -8.0, 450.0);
        let mut points: Vec<Vec3> = cap(centre, 19.05, 0.6).iter().map(vec3).collect();
        let stray: Vec<Vec3> = points.iter().step_by(10).map(|p| p + Vec3::new(0.0, 0.0, 4.0)).collect();
        points.extend(stray);
        for (start, radius) in [(vec![14.0, -6.0, 452.0], Some(19.05)), (vec![14.0, -6.0, 452.0, 18.0], None)] {
            let residuals = |p: &[f64]| -> Blocks {
                let c = Vec3::new(p[0], p[1], p[2]);
                let r = radius.unwrap_or_else(|| p[3]);
                points.iter().map(|q| [(q - c).norm() - r]).collect()
            };
            let reference = refine::robust_fit(&start, &residuals).unwrap().params;
            let fast = fit_surface(&points, &start, radius).unwrap();
            for (a, b) in fast.iter().zip(&reference) {
                assert!((a - b).abs() < 1e-6, "{fast:?} against {reference:?}");
            }
            assert!((Vec3::new(fast[0], fast[1], fast[2]) - centre).norm() < 0.01, "{fast:?}");
        }
    }

    #[test]
    fn a_partial_sphere_among_clutter_is_found_to_a_few_microns() {
        let centre = Vec3::new(30.0, -20.0, 600.0);
        let mut points = cap(centre, 25.0, 0.5);
        // A plane behind and scattered outliers.
        for i in 0..4000 {
            let (x, y) = ((i % 80) as f64 * 2.0 - 80.0, (i / 80) as f64 * 2.0 - 50.0);
            points.push([x as f32, y as f32, 700.0]);
        }
        for i in 0..300 {
            let t = i as f64;
            points.push([
                (t * 0.37).sin() as f32 * 60.0,
                (t * 0.11).cos() as f32 * 60.0,
                560.0 + (t * 0.7).sin() as f32 * 80.0,
            ]);
        }
        points.push([f32::NAN, 0.0, 0.0]);
        let found = fit_spheres(&points, &[25.0], 1).unwrap();
        assert_eq!(found.len(), 1);
        assert!((found[0].centre - centre).norm() < 0.01, "{:?}", found[0]);
        assert!((found[0].measured_radius_mm - 25.0).abs() < 0.05, "{:?}", found[0]);
    }

    #[test]
    fn spheres_of_different_radii_are_fitted_each_with_its_radius() {
        let a = Vec3::new(-60.0, 0.0, 550.0);
        let b = Vec3::new(60.0, 10.0, 580.0);
        let mut points = cap(a, 15.0, 0.4);
        points.extend(cap(b, 25.0, 0.4));
        let found = fit_spheres(&points, &[15.0, 25.0], 2).unwrap();
        assert_eq!(found.len(), 2, "{found:?}");
        let small = found.iter().find(|s| s.radius_index == 0).unwrap();
        let large = found.iter().find(|s| s.radius_index == 1).unwrap();
        assert!((small.centre - a).norm() < 0.01 && (large.centre - b).norm() < 0.01, "{found:?}");
    }

    #[test]
    fn a_cylinder_of_the_balls_radius_and_a_plane_are_not_balls() {
        // A pipe of the ball's radius lying across the view, and a table.
        let mut points = Vec::new();
        for i in 0..400 {
            for j in 0..60 {
                let (x, angle) = (i as f64 * 0.5 - 100.0, (j as f64 / 60.0 - 0.5) * 2.6);
                let p = Vec3::new(x, 19.05 * angle.sin(), 560.0 - 19.05 * angle.cos());
                points.push([p.x as f32, p.y as f32, p.z as f32]);
            }
        }
        for i in 0..200 {
            for j in 0..200 {
                points.push([i as f32 - 100.0, j as f32 - 100.0, 600.0]);
            }
        }
        let found = fit_spheres(&points, &[19.05; 3], 3).unwrap();
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn radii_are_checked() {
        assert_eq!(check_radii(&[]), Err(SphereError::NoRadius));
        assert!(matches!(check_radii(&[1.0]), Err(SphereError::Radius { .. })));
        assert!(matches!(check_radii(&[20.0; 7]), Err(SphereError::TooManySpheres { count: 7 })));
    }
}
