//! Naming the spheres fitted in each capture: which given sphere each one
//! is, so that its centre can be paired with the same sphere's centre in
//! the other captures.
//!
//! Spheres whose radii differ by at least
//! [`MIN_RADIUS_GAP_MM`](super::sphere::MIN_RADIUS_GAP_MM) are named by
//! their radius. Spheres of one radius (a rig of tooling balls) are named
//! by the distances between their centres, which no robot or camera motion
//! changes: the rig's layout, given as the distances between the spheres
//! or found from the captures (the layout that the most captures agree
//! with, each pair's distance then averaged over them). Each capture's
//! spheres are matched to the layout by the assignment under which every
//! distance agrees within [`DISTANCE_MATCH_MM`] and that names the most
//! spheres; fits that match no sphere of the layout (a look-alike on the
//! table) are left aside. A capture whose spheres can be assigned in two
//! ways as good (two balls of one radius seen, whose one distance reads
//! the same either way round) is left unnamed and reported, never
//! guessed. A layout that reads nearly the same under some exchange of
//! equal spheres ([`MIN_LAYOUT_ASYMMETRY_MM`]) cannot name them at all and
//! is refused.

use super::sphere::{FittedSphere, MAX_SPHERES, radii_distinct, radius_classes};
use crate::geometry::Vec3;

/// Every distance of an assignment must agree with the layout within
/// this, mm: the centres' own error is a few hundredths of a millimetre,
/// a post bent or a ball reseated moves them by more.
pub const DISTANCE_MATCH_MM: f64 = 2.0;

/// A layout of equal spheres must move some distance by at least this
/// under every exchange of them, mm, or they cannot be told apart:
/// comfortably over twice [`DISTANCE_MATCH_MM`].
pub const MIN_LAYOUT_ASYMMETRY_MM: f64 = 5.0;

/// The most captures tried as the reference when the layout is found
/// from the captures.
pub const MAX_LAYOUT_CANDIDATES: usize = 50;

/// A sphere of one radius of unknown count must be named in at least
/// this many captures to count as one of the rig's.
pub const MIN_SPHERE_CAPTURES: usize = 3;

/// Each capture's spheres, named.
#[derive(Debug, Clone, PartialEq)]
pub struct Naming {
    /// `centres[capture][sphere]`: the centre of given sphere `sphere` in
    /// that capture, `None` where it was not seen or not named.
    pub centres: Vec<Vec<Option<Vec3>>>,
    /// The captures none of whose spheres could be named, with why.
    pub unnamed: Vec<(usize, String)>,
    /// The layout the spheres were named by, as the capture file gives
    /// it (pairs (0,1), (0,2), ..., (1,2), ...), when distances named them.
    pub distances: Option<Vec<f64>>,
}

/// Why the spheres cannot be named at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NamingError {
    #[error("sphere_distances_mm has {got} distances; {spheres} spheres have {expected}")]
    DistanceCount { got: usize, expected: usize, spheres: usize },
    #[error(
        "sphere_distances_mm has {got} distances; n spheres have n(n-1)/2 of them (1, 3, 6, 10 or 15 for 2 to \
         {MAX_SPHERES})"
    )]
    DistanceCountOfOneRadius { got: usize },
    #[error("sphere_distances_mm: {value} is not a distance in mm")]
    Distance { value: f64 },
    #[error(
        "no capture shows all {spheres} spheres of one radius, so their layout cannot be found: give \
         sphere_distances_mm in the capture file"
    )]
    NoLayout { spheres: usize },
    #[error(
        "the rig's layout is too symmetric to tell its spheres of one radius apart: exchanging spheres {a} and {b} \
         changes no distance by more than {asymmetry_mm:.1} mm (at least {MIN_LAYOUT_ASYMMETRY_MM} mm is needed); \
         move a sphere so that the distances between them all differ"
    )]
    Symmetric { a: usize, b: usize, asymmetry_mm: f64 },
}

/// Names every capture's spheres; `distances` is the layout when the
/// capture file gives it.
///
/// One radius given (`sphere_radius_mm`) stands for every ball of that
/// radius the rig holds: as many as the distances say, or as the layout
/// found from the captures holds (a lone ball when no capture shows two).
pub fn name_spheres(
    captures: &[Vec<FittedSphere>],
    radii: &[f64],
    distances: Option<&[f64]>,
) -> Result<Naming, NamingError> {
    if radii.len() == 1 {
        let count = match distances {
            Some(d) => (2..=MAX_SPHERES).find(|n| n * (n - 1) / 2 == d.len()).unwrap_or(0),
            None => found_layout(captures, None).map_or(1, |layout| layout.len()),
        };
        if count == 0 {
            return Err(NamingError::DistanceCountOfOneRadius { got: distances.map_or(0, <[f64]>::len) });
        }
        if count > 1 {
            return name_spheres(captures, &vec![radii[0]; count], distances);
        }
    }
    let n = radii.len().min(MAX_SPHERES);
    let classes = radius_classes(&radii[..n]);
    if radii_distinct(&radii[..n]) {
        return Ok(by_radius(captures, n));
    }
    let layout = match distances {
        Some(d) => layout_from_distances(d, n)?,
        None => found_layout(captures, Some(&classes))?,
    };
    check_asymmetry(&layout, &classes)?;
    let mut naming = Naming { centres: Vec::new(), unnamed: Vec::new(), distances: Some(flatten(&layout)) };
    for (i, spheres) in captures.iter().enumerate() {
        match name_capture(spheres, &layout, &classes) {
            Ok(named) => naming.centres.push(named),
            Err(reason) => {
                naming.centres.push(vec![None; n]);
                naming.unnamed.push((i, reason));
            }
        }
    }
    Ok(naming)
}

/// Spheres of distinct radii: each named by its radius, the best
/// supported fit of each.
fn by_radius(captures: &[Vec<FittedSphere>], n: usize) -> Naming {
    let mut naming = Naming { centres: Vec::new(), unnamed: Vec::new(), distances: None };
    for (i, spheres) in captures.iter().enumerate() {
        let mut named: Vec<Option<Vec3>> = vec![None; n];
        let mut best = vec![0usize; n];
        for s in spheres.iter().filter(|s| s.radius_index < n) {
            if s.points > best[s.radius_index] {
                best[s.radius_index] = s.points;
                named[s.radius_index] = Some(s.centre);
            }
        }
        if named.iter().all(Option::is_none) {
            naming.unnamed.push((i, "no sphere found".to_string()));
        }
        naming.centres.push(named);
    }
    naming
}

/// The pair order of the capture file's distances.
fn pairs(n: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..n).flat_map(move |a| (a + 1..n).map(move |b| (a, b)))
}

fn flatten(layout: &[Vec<f64>]) -> Vec<f64> {
    pairs(layout.len()).map(|(a, b)| layout[a][b]).collect()
}

fn layout_from_distances(d: &[f64], n: usize) -> Result<Vec<Vec<f64>>, NamingError> {
    let expected = n * (n - 1) / 2;
    if d.len() != expected {
        return Err(NamingError::DistanceCount { got: d.len(), expected, spheres: n });
    }
    if let Some(&value) = d.iter().find(|v| !(v.is_finite() && **v > 0.0 && **v < 10_000.0)) {
        return Err(NamingError::Distance { value });
    }
    let mut layout = vec![vec![0.0; n]; n];
    for ((a, b), v) in pairs(n).zip(d) {
        layout[a][b] = *v;
        layout[b][a] = *v;
    }
    Ok(layout)
}

/// The layout most captures agree with: each capture that shows exactly
/// the given spheres (for one radius of unknown count, two or more) is a
/// candidate; the one whose naming names the most spheres over all
/// captures wins, spheres it names in fewer than [`MIN_SPHERE_CAPTURES`]
/// captures are dropped (a look-alike in one view), and each distance is
/// averaged over the captures named.
fn found_layout(captures: &[Vec<FittedSphere>], classes: Option<&[usize]>) -> Result<Vec<Vec<f64>>, NamingError> {
    let fits_classes = |spheres: &[FittedSphere]| match classes {
        None => (2..=MAX_SPHERES).contains(&spheres.len()),
        Some(classes) => {
            let n = classes.len();
            let mut labels: Vec<usize> = spheres.iter().map(|s| classes[s.radius_index.min(n - 1)]).collect();
            let mut wanted = classes.to_vec();
            labels.sort_unstable();
            wanted.sort_unstable();
            labels == wanted
        }
    };
    let mut best: Option<(usize, Vec<Vec<f64>>)> = None;
    for reference in captures.iter().filter(|c| fits_classes(c)).take(MAX_LAYOUT_CANDIDATES) {
        let n = reference.len();
        let reference_classes = classes.map_or_else(|| vec![0; n], <[usize]>::to_vec);
        let layout: Vec<Vec<f64>> =
            reference.iter().map(|a| reference.iter().map(|b| (a.centre - b.centre).norm()).collect()).collect();
        let named: Vec<Vec<Option<Vec3>>> =
            captures.iter().filter_map(|c| name_capture(c, &layout, &reference_classes).ok()).collect();
        let keep: Vec<usize> = (0..n)
            .filter(|&k| classes.is_some() || named.iter().filter(|c| c[k].is_some()).count() >= MIN_SPHERE_CAPTURES)
            .collect();
        let score: usize = named.iter().map(|c| keep.iter().filter(|&&k| c[k].is_some()).count()).sum();
        if keep.len() < 2 || best.as_ref().is_some_and(|(s, _)| score <= *s) {
            continue;
        }
        let mut averaged = vec![vec![0.0; keep.len()]; keep.len()];
        for (a, b) in pairs(keep.len()) {
            let (ka, kb) = (keep[a], keep[b]);
            let seen: Vec<f64> =
                named.iter().filter_map(|c| Some((c[ka].as_ref()? - c[kb].as_ref()?).norm())).collect();
            let d = if seen.is_empty() { layout[ka][kb] } else { seen.iter().sum::<f64>() / seen.len() as f64 };
            averaged[a][b] = d;
            averaged[b][a] = d;
        }
        best = Some((score, averaged));
    }
    let spheres = classes.map_or(2, <[usize]>::len);
    best.map(|(_, layout)| layout).ok_or(NamingError::NoLayout { spheres })
}

/// Refuses a layout some exchange of equal spheres leaves nearly
/// unchanged.
fn check_asymmetry(layout: &[Vec<f64>], classes: &[usize]) -> Result<(), NamingError> {
    let n = classes.len();
    let mut worst: Option<(f64, usize, usize)> = None;
    let mut permutation: Vec<usize> = Vec::with_capacity(n);
    permutations(n, classes, &mut permutation, &mut |p| {
        if p.iter().enumerate().all(|(k, &v)| k == v) {
            return;
        }
        let change = pairs(n).map(|(a, b)| (layout[a][b] - layout[p[a]][p[b]]).abs()).fold(0.0, f64::max);
        if worst.is_none_or(|(w, _, _)| change < w) {
            let moved: Vec<usize> = (0..n).filter(|&k| p[k] != k).collect();
            worst = Some((change, moved[0], moved.get(1).copied().unwrap_or(moved[0])));
        }
    });
    match worst {
        Some((asymmetry_mm, a, b)) if asymmetry_mm < MIN_LAYOUT_ASYMMETRY_MM => {
            Err(NamingError::Symmetric { a, b, asymmetry_mm })
        }
        _ => Ok(()),
    }
}

/// Calls `visit` with every permutation of `0..n` that keeps each sphere
/// within its radius class.
fn permutations(n: usize, classes: &[usize], current: &mut Vec<usize>, visit: &mut dyn FnMut(&[usize])) {
    if current.len() == n {
        visit(current);
        return;
    }
    let k = current.len();
    for label in 0..n {
        if classes[label] == classes[k] && !current.contains(&label) {
            current.push(label);
            permutations(n, classes, current, visit);
            current.pop();
        }
    }
}

/// One capture's spheres named by the layout, or why they cannot be.
fn name_capture(spheres: &[FittedSphere], layout: &[Vec<f64>], classes: &[usize]) -> Result<Vec<Option<Vec3>>, String> {
    let n = classes.len();
    if spheres.is_empty() {
        return Err("no sphere found".to_string());
    }
    // Every assignment (a sphere to a label, or to none) whose distances
    // all agree with the layout, with the most spheres named.
    let mut best: Vec<(f64, Vec<Option<usize>>)> = Vec::new();
    let mut best_count = 0;
    let mut current: Vec<Option<usize>> = Vec::with_capacity(spheres.len());
    assign(spheres, layout, classes, &mut current, &mut |labels| {
        let count = labels.iter().flatten().count();
        if count == 0 || count < best_count {
            return;
        }
        if count > best_count {
            best_count = count;
            best.clear();
        }
        best.push((mismatch(spheres, layout, labels), labels.to_vec()));
    });
    match best.len() {
        0 => Err(format!(
            "its {} spheres' distances match no part of the layout within {DISTANCE_MATCH_MM} mm",
            spheres.len()
        )),
        1 => {
            let mut named = vec![None; n];
            for (sphere, label) in spheres.iter().zip(&best[0].1) {
                if let Some(label) = label {
                    named[*label] = Some(sphere.centre);
                }
            }
            Ok(named)
        }
        ways => Err(format!(
            "{best_count} of its {} spheres match the layout in {ways} ways (spheres of one radius are named by \
             their distances, which takes three of them in view)",
            spheres.len()
        )),
    }
}

/// RMS difference between an assignment's distances and the layout's.
fn mismatch(spheres: &[FittedSphere], layout: &[Vec<f64>], labels: &[Option<usize>]) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for (a, b) in pairs(spheres.len()) {
        if let (Some(la), Some(lb)) = (labels[a], labels[b]) {
            sum += ((spheres[a].centre - spheres[b].centre).norm() - layout[la][lb]).powi(2);
            count += 1;
        }
    }
    (sum / count.max(1) as f64).sqrt()
}

/// Enumerates the assignments of `spheres` to labels of their class (or
/// to none), each label used once, pruning any whose distances disagree
/// with the layout.
fn assign(
    spheres: &[FittedSphere],
    layout: &[Vec<f64>],
    classes: &[usize],
    current: &mut Vec<Option<usize>>,
    visit: &mut dyn FnMut(&[Option<usize>]),
) {
    let k = current.len();
    if k == spheres.len() {
        visit(current);
        return;
    }
    current.push(None);
    assign(spheres, layout, classes, current, visit);
    current.pop();
    let class = classes[spheres[k].radius_index.min(classes.len() - 1)];
    for label in 0..classes.len() {
        if classes[label] != class || current.contains(&Some(label)) {
            continue;
        }
        let agrees = current.iter().enumerate().all(|(j, other)| {
            other.is_none_or(|o| {
                ((spheres[k].centre - spheres[j].centre).norm() - layout[label][o]).abs() <= DISTANCE_MATCH_MM
            })
        });
        if agrees {
            current.push(Some(label));
            assign(spheres, layout, classes, current, visit);
            current.pop();
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A well-fitted ball of the rig's radius at `centre`.
    pub(in crate::calibration) fn sphere(centre: Vec3) -> FittedSphere {
        FittedSphere {
            centre,
            measured_radius_mm: 19.05,
            radius_index: 0,
            points: 500,
            rms_mm: 0.03,
            cap_half_angle_deg: 70.0,
        }
    }

    const CENTRES: [[f64; 3]; 3] = [[-75.0, -40.0, 110.0], [80.0, -25.0, 85.0], [-15.0, 70.0, 135.0]];

    fn moved(c: &[f64; 3]) -> Vec3 {
        nalgebra::Rotation3::new(Vec3::new(0.1, -0.2, 0.3)) * Vec3::from(*c) + Vec3::new(5.0, 3.0, 480.0)
    }

    #[test]
    fn balls_of_one_radius_are_named_by_the_layout_found_from_the_captures() {
        let reference: Vec<FittedSphere> = CENTRES.iter().map(|c| sphere(Vec3::from(*c))).collect();
        // Another order, a look-alike on the table, then two balls only
        // (one distance reads the same either way round).
        let mut other: Vec<FittedSphere> = [2, 0, 1].iter().map(|&k| sphere(moved(&CENTRES[k]))).collect();
        other.push(sphere(Vec3::new(300.0, 0.0, 500.0)));
        let partial = vec![sphere(moved(&CENTRES[2])), sphere(moved(&CENTRES[0]))];
        let naming = name_spheres(&[reference, other, partial, Vec::new()], &[19.05; 3], None).unwrap();
        for (named, centre) in naming.centres[1].iter().zip(&CENTRES) {
            assert!((named.unwrap() - moved(centre)).norm() < 1e-9, "{naming:?}");
        }
        assert_eq!(naming.centres[2], vec![None; 3]);
        assert_eq!(naming.unnamed.iter().map(|u| u.0).collect::<Vec<_>>(), vec![2, 3], "{naming:?}");
        assert!(naming.unnamed[0].1.contains("2 ways"), "{naming:?}");
        let d = naming.distances.unwrap();
        assert!((d[0] - 157.7).abs() < 0.1 && (d[1] - 127.8).abs() < 0.1 && (d[2] - 143.4).abs() < 0.1, "{d:?}");
    }

    #[test]
    fn a_given_layout_names_a_capture_and_a_wrong_one_names_none() {
        let seen: Vec<FittedSphere> = [1, 2, 0].iter().map(|&k| sphere(moved(&CENTRES[k]))).collect();
        let given = [157.69, 127.77, 143.35];
        let naming = name_spheres(std::slice::from_ref(&seen), &[19.05; 3], Some(&given)).unwrap();
        assert!((naming.centres[0][1].unwrap() - moved(&CENTRES[1])).norm() < 1e-9);
        let naming = name_spheres(&[seen], &[19.05; 3], Some(&[150.0, 127.77, 143.35])).unwrap();
        // Two of its distances still match, each either way round.
        assert!(naming.unnamed[0].1.contains("2 of its 3 spheres match the layout in 4 ways"), "{naming:?}");
        assert_eq!(naming.centres[0], vec![None; 3]);
    }

    #[test]
    fn a_symmetric_rig_is_refused() {
        // An isosceles triangle: exchanging its two base balls changes nothing.
        let e = name_spheres(&[], &[19.05; 3], Some(&[150.0, 150.0, 120.0])).unwrap_err();
        assert!(matches!(e, NamingError::Symmetric { .. }), "{e}");
        assert!(e.to_string().contains("too symmetric"), "{e}");
        let e = name_spheres(&[], &[19.05; 3], Some(&[150.0, 120.0])).unwrap_err();
        assert_eq!(e, NamingError::DistanceCount { got: 2, expected: 3, spheres: 3 });
    }
}
