//! Calibration spheres in a point cloud: each sphere's centre fitted in
//! one capture's cloud, and the spheres named alike across captures.
//!
//! A sphere is found by RANSAC: four points near one another give an
//! algebraic sphere (`|p|² = 2 c·p + k`, linear in `c` and `k`), kept when
//! its radius is within [`RADIUS_TOLERANCE`] of a given one, and scored by
//! the points within [`inlier_band`] of its surface. The best is refined by
//! Levenberg-Marquardt on the geometric distance `|p - c| - r` under a
//! Huber loss, first with the radius free (to tell which sphere it is),
//! then with the given radius (the centre of a cap seen from one side is
//! pinned far better with the radius known). A partial view is nothing
//! special: only the points seen count. Several spheres are found one
//! after another, each claiming its points.
//!
//! Identification: spheres whose given radii differ by at least
//! [`MIN_RADIUS_GAP_MM`] are told apart by their measured radius alone.
//! Spheres of equal radius are told apart by the distances between their
//! centres, which no robot or camera motion changes: each capture's
//! centres are matched to a reference capture's (the first that shows
//! every sphere) by the assignment whose pairwise distances agree best,
//! and a capture whose best and second-best assignments agree about as
//! well is left unnamed. Distances tell spheres apart only when a capture
//! sees three or more of them (one distance reads the same either way
//! round), so equal spheres need at least three in the cell, each pair at
//! its own distance.

use nalgebra::{Matrix4, Vector4};
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::refine::{self, Blocks};
use crate::geometry::{Vec3, vec3};

/// The most spheres one capture may hold.
pub const MAX_SPHERES: usize = 6;

/// The smallest and largest sphere radius accepted, mm.
pub const RADIUS_RANGE_MM: [f64; 2] = [2.0, 500.0];

/// A hypothesis whose radius is further than this fraction from every
/// given radius is discarded.
pub const RADIUS_TOLERANCE: f64 = 0.1;

/// Radii at least this far apart name their spheres by size.
pub const MIN_RADIUS_GAP_MM: f64 = 3.0;

/// RANSAC hypotheses tried per sphere.
pub const RANSAC_HYPOTHESES: usize = 1000;

/// The points RANSAC scores hypotheses on (a uniform subsample of the
/// cloud); the refinement uses every point near the sphere found.
pub const RANSAC_SAMPLE_POINTS: usize = 10_000;

/// A fit whose surface points lie further than this fraction of the
/// inlier band from it, RMS, is not a sphere of that radius.
pub const MAX_RMS_OVER_BAND: f64 = 0.5;

/// RANSAC rounds per sphere sought, counting the rejected ones.
pub const MAX_ATTEMPTS_PER_SPHERE: usize = 2;

/// The most points the refinement uses (a uniform subsample): the
/// centre of twenty thousand points with the sensor's noise is already
/// pinned to microns, and the cost stays bounded whatever the cloud.
pub const REFINE_MAX_POINTS: usize = 20_000;

/// The fewest points on a sphere's surface for it to count as seen.
pub const MIN_SPHERE_POINTS: usize = 150;

/// Pairwise-distance mismatch, mm RMS, below which an assignment of
/// equal spheres is accepted, and the margin by which the second best
/// must be worse.
pub const DISTANCE_MATCH_MM: f64 = 2.0;

/// The half-width of the shell that counts as a sphere's surface for
/// RANSAC, mm: 2 % of the radius, at least 0.3 mm (the sensor's noise
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
    /// Which of the given radii it is (its index), when radii tell.
    pub radius_index: usize,
    /// The points on its surface.
    pub points: usize,
    /// RMS of their distances to the surface, mm.
    pub rms_mm: f64,
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

/// Finds up to `radii.len()` spheres among `points` (camera frame, mm;
/// invalid points are skipped), largest first. `seed` makes the RANSAC
/// draws repeatable.
pub fn fit_spheres(points: &[[f32; 3]], radii: &[f64], seed: u64) -> Result<Vec<FittedSphere>, SphereError> {
    check_radii(radii)?;
    let valid: Vec<Vec3> = points.iter().filter(|p| p.iter().all(|v| v.is_finite())).map(vec3).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut claimed = vec![false; valid.len()];
    let mut found: Vec<FittedSphere> = Vec::new();
    let (smallest, largest) = radii.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(*r), hi.max(*r)));
    // A rejected hypothesis (another object's points, a sphere hidden
    // behind another) claims its points too, and the search goes on.
    for _ in 0..MAX_ATTEMPTS_PER_SPHERE * radii.len() {
        if found.len() == radii.len() {
            break;
        }
        let free: Vec<usize> = (0..valid.len()).filter(|&i| !claimed[i]).collect();
        let Some(start) = ransac(&valid, &free, radii, smallest, largest, &mut rng) else { break };
        let sphere = refine_sphere(&valid, &free, start, radii, &found);
        let (centre, radius) = match &sphere {
            Some(s) => (s.centre, radii[s.radius_index]),
            None => (start.centre, start.radius),
        };
        let reach = radius + 3.0 * inlier_band(radius);
        for (i, c) in claimed.iter_mut().enumerate() {
            if (valid[i] - centre).norm() < reach {
                *c = true;
            }
        }
        found.extend(sphere);
    }
    Ok(found)
}

/// A sphere hypothesis: centre and radius.
#[derive(Debug, Clone, Copy)]
struct Hypothesis {
    centre: Vec3,
    radius: f64,
}

/// The sphere through four points, if they are not coplanar.
fn sphere_through(p: [&Vec3; 4]) -> Option<Hypothesis> {
    let mut m = Matrix4::zeros();
    let mut y = Vector4::zeros();
    for (row, q) in p.iter().enumerate() {
        m.set_row(row, &nalgebra::RowVector4::new(2.0 * q.x, 2.0 * q.y, 2.0 * q.z, 1.0));
        y[row] = q.norm_squared();
    }
    let s = m.lu().solve(&y)?;
    let centre = Vec3::new(s[0], s[1], s[2]);
    let r2 = s[3] + centre.norm_squared();
    (r2 > 0.0 && r2.is_finite()).then(|| Hypothesis { centre, radius: r2.sqrt() })
}

/// Uniform index below `n` (n > 0).
fn below(rng: &mut ChaCha8Rng, n: usize) -> usize {
    (rng.next_u64() % n as u64) as usize
}

/// The best-supported sphere among `free` points, radius within the
/// given ones' range.
fn ransac(
    points: &[Vec3],
    free: &[usize],
    radii: &[f64],
    smallest: f64,
    largest: f64,
    rng: &mut ChaCha8Rng,
) -> Option<Hypothesis> {
    if free.len() < MIN_SPHERE_POINTS {
        return None;
    }
    let stride = free.len().div_ceil(RANSAC_SAMPLE_POINTS).max(1);
    let sample: Vec<Vec3> = free.iter().step_by(stride).map(|&i| points[i]).collect();
    let grid = Grid::new(&sample, largest);
    let mut best: Option<(usize, Hypothesis)> = None;
    for _ in 0..RANSAC_HYPOTHESES {
        let seed = below(rng, sample.len());
        let near = grid.within(&sample, &sample[seed], 2.0 * largest);
        if near.len() < 4 {
            continue;
        }
        let pick = [0, 1, 2].map(|_| &sample[near[below(rng, near.len())]]);
        let Some(h) = sphere_through([&sample[seed], pick[0], pick[1], pick[2]]) else { continue };
        let fits = radii.iter().any(|r| (h.radius - r).abs() <= RADIUS_TOLERANCE * r);
        if !fits || h.radius < smallest * (1.0 - RADIUS_TOLERANCE) {
            continue;
        }
        let band = inlier_band(h.radius);
        let support = grid
            .within(&sample, &h.centre, h.radius + band)
            .iter()
            .filter(|&&k| ((sample[k] - h.centre).norm() - h.radius).abs() < band)
            .count();
        if best.is_none_or(|(count, _)| support > count) {
            best = Some((support, h));
        }
    }
    best.map(|(_, h)| h)
}

/// The fit's points: those among `free` within `band` of the sphere.
fn shell(points: &[Vec3], free: &[usize], centre: &Vec3, radius: f64, band: f64) -> Vec<Vec3> {
    free.iter().map(|&i| points[i]).filter(|p| ((p - centre).norm() - radius).abs() < band).collect()
}

/// Geometric refinement of a RANSAC sphere: radius free to name it, then
/// the given radius for the centre.
fn refine_sphere(
    points: &[Vec3],
    free: &[usize],
    start: Hypothesis,
    radii: &[f64],
    found: &[FittedSphere],
) -> Option<FittedSphere> {
    let band = inlier_band(start.radius);
    let near = shell(points, free, &start.centre, start.radius, 3.0 * band);
    if near.len() < MIN_SPHERE_POINTS {
        return None;
    }
    let near: Vec<Vec3> = near.iter().step_by(near.len().div_ceil(REFINE_MAX_POINTS)).copied().collect();
    let distances = |p: &[f64], radius: f64| -> Blocks {
        let c = Vec3::new(p[0], p[1], p[2]);
        near.iter().map(|q| [(q - c).norm() - radius]).collect()
    };
    let c0 = [start.centre.x, start.centre.y, start.centre.z, start.radius];
    let free_fit = refine::robust_fit(&c0, &|p| distances(p, p[3])).ok()?;
    let measured = free_fit.params[3];
    // The nearest given radius not yet taken names it, when radii tell.
    let taken = |k: usize| radii_distinct(radii) && found.iter().any(|f| f.radius_index == k);
    let radius_index = (0..radii.len())
        .filter(|&k| !taken(k))
        .min_by(|&a, &b| (radii[a] - measured).abs().total_cmp(&(radii[b] - measured).abs()))?;
    let radius = radii[radius_index];
    // A real sphere measures its own radius to a few hundredths of a
    // millimetre; a patch of something else that RANSAC took for one
    // does not.
    if (measured - radius).abs() > inlier_band(radius) {
        return None;
    }
    let fixed = refine::robust_fit(&free_fit.params[..3], &|p| distances(p, radius)).ok()?;
    let centre = Vec3::new(fixed.params[0], fixed.params[1], fixed.params[2]);
    let on_surface = shell(points, free, &centre, radius, band);
    if on_surface.len() < MIN_SPHERE_POINTS {
        return None;
    }
    let rms = (on_surface.iter().map(|q| ((q - centre).norm() - radius).powi(2)).sum::<f64>()
        / on_surface.len() as f64)
        .sqrt();
    // Points spread across the whole shell rather than on the surface.
    if rms > MAX_RMS_OVER_BAND * band {
        return None;
    }
    Some(FittedSphere { centre, measured_radius_mm: measured, radius_index, points: on_surface.len(), rms_mm: rms })
}

/// A uniform grid of point indices, cells as wide as a sphere's radius.
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

/// Names each capture's spheres: `result[capture][sphere]` is the centre
/// of given sphere `sphere` in that capture, `None` where it was not seen
/// or could not be told apart. Spheres of distinct radii are named by
/// radius; equal ones by the distances between centres.
pub fn identify(captures: &[Vec<FittedSphere>], radii: &[f64]) -> Vec<Vec<Option<Vec3>>> {
    let n = radii.len();
    let by_radius = |spheres: &[FittedSphere]| {
        let mut named = vec![None; n];
        for s in spheres {
            named[s.radius_index] = Some(s.centre);
        }
        named
    };
    if radii_distinct(radii) {
        return captures.iter().map(|c| by_radius(c)).collect();
    }
    let Some(reference) = captures.iter().find(|c| c.len() == n) else {
        // No capture shows them all: only a lone sphere can be named.
        return captures.iter().map(|c| if n == 1 { by_radius(c) } else { vec![None; n] }).collect();
    };
    let reference: Vec<Vec3> = reference.iter().map(|s| s.centre).collect();
    captures.iter().map(|c| match_by_distances(c, &reference, radii)).collect()
}

/// The assignment of `spheres` to the reference's names whose pairwise
/// distances agree best, if it is clear.
fn match_by_distances(spheres: &[FittedSphere], reference: &[Vec3], radii: &[f64]) -> Vec<Option<Vec3>> {
    let n = reference.len();
    let mut assignments: Vec<(f64, Vec<usize>)> = Vec::new();
    let mut current = Vec::with_capacity(spheres.len());
    assign(spheres, radii, n, &mut current, &mut assignments, reference);
    assignments.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut named = vec![None; n];
    let Some((best, labels)) = assignments.first() else { return named };
    let clear = match assignments.get(1) {
        Some((second, _)) => *best <= DISTANCE_MATCH_MM && *second > best + DISTANCE_MATCH_MM,
        None => *best <= DISTANCE_MATCH_MM,
    };
    // One distance is the same read either way round: two spheres of one
    // radius are told apart only with a third in view.
    if clear && (spheres.len() >= 3 || n == 1) {
        for (sphere, &label) in spheres.iter().zip(labels) {
            named[label] = Some(sphere.centre);
        }
    }
    named
}

/// Every injective naming of `spheres` compatible with their radii, with
/// its RMS pairwise-distance mismatch against `reference`.
fn assign(
    spheres: &[FittedSphere],
    radii: &[f64],
    n: usize,
    current: &mut Vec<usize>,
    out: &mut Vec<(f64, Vec<usize>)>,
    reference: &[Vec3],
) {
    if current.len() == spheres.len() {
        let mut sum = 0.0;
        let mut pairs = 0usize;
        for a in 0..spheres.len() {
            for b in 0..a {
                let seen = (spheres[a].centre - spheres[b].centre).norm();
                let expected = (reference[current[a]] - reference[current[b]]).norm();
                sum += (seen - expected).powi(2);
                pairs += 1;
            }
        }
        out.push(((sum / pairs.max(1) as f64).sqrt(), current.clone()));
        return;
    }
    let sphere = &spheres[current.len()];
    for label in 0..n {
        let compatible = (radii[label] - radii[sphere.radius_index]).abs() < MIN_RADIUS_GAP_MM;
        if compatible && !current.contains(&label) {
            current.push(label);
            assign(spheres, radii, n, current, out, reference);
            current.pop();
        }
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
    fn spheres_of_different_radii_are_named_by_size() {
        let a = Vec3::new(-60.0, 0.0, 550.0);
        let b = Vec3::new(60.0, 10.0, 580.0);
        let mut points = cap(a, 15.0, 0.4);
        points.extend(cap(b, 25.0, 0.4));
        let found = fit_spheres(&points, &[15.0, 25.0], 2).unwrap();
        let named = identify(&[found], &[15.0, 25.0]);
        assert!((named[0][0].unwrap() - a).norm() < 0.01 && (named[0][1].unwrap() - b).norm() < 0.01, "{named:?}");
    }

    #[test]
    fn equal_spheres_are_named_by_their_distances() {
        let centres = [Vec3::new(-60.0, 0.0, 550.0), Vec3::new(60.0, 10.0, 580.0), Vec3::new(0.0, 70.0, 600.0)];
        let sphere = |c: Vec3, k: usize| FittedSphere {
            centre: c,
            measured_radius_mm: 20.0,
            radius_index: k,
            points: 500,
            rms_mm: 0.03,
        };
        let reference: Vec<FittedSphere> = centres.iter().map(|c| sphere(*c, 0)).collect();
        // The same constellation moved and listed in another order; then
        // one sphere missing, which leaves the other two's one distance
        // reading the same either way round.
        let moved = |c: &Vec3| nalgebra::Rotation3::new(Vec3::new(0.1, -0.2, 0.3)) * c + Vec3::new(5.0, 3.0, -8.0);
        let other: Vec<FittedSphere> = [2, 0, 1].iter().map(|&k| sphere(moved(&centres[k]), 0)).collect();
        let partial = vec![sphere(moved(&centres[2]), 0), sphere(moved(&centres[0]), 0)];
        let named = identify(&[reference, other, partial], &[20.0; 3]);
        for k in 0..3 {
            assert!((named[1][k].unwrap() - moved(&centres[k])).norm() < 1e-9, "{named:?}");
        }
        assert_eq!(named[2], vec![None; 3]);
    }

    #[test]
    fn radii_are_checked() {
        assert_eq!(check_radii(&[]), Err(SphereError::NoRadius));
        assert!(matches!(check_radii(&[1.0]), Err(SphereError::Radius { .. })));
        assert!(matches!(check_radii(&[20.0; 7]), Err(SphereError::TooManySpheres { count: 7 })));
    }
}
