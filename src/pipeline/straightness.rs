//! Whether a seam's root is straight: the planner welds plane joints, whose
//! root is the line where two flat faces meet, and plans it as one.
//!
//! A fit over the whole stretch does not tell a bent root from a straight
//! one by its residual: a face of a round tube fitted with a plane over
//! 60 mm leaves a residual of a point spacing or so, the camera's noise on a
//! coarse cloud, while the tube's foot bends millimetres away from the line
//! the plane meets the flange along. What tells them apart is where along
//! the root the deviation lies: noise scatters each sample about the line
//! independently, so the mean of the samples within a few spacings along the
//! root (a station) scatters by the noise over the root of their count,
//! while a bent root moves every station's mean together, in a curve.
//!
//! So the root samples (a web face's foot, the flange beside the root, a
//! plate's boundary samples) are read as their offset from the fitted root
//! in one direction across it, averaged per station, and a parabola
//! `v = a + b·x + c·x²` (`x` along the stretch, from −1 to 1) is fitted to
//! the station means by least squares: their trend along the root, which
//! noise does not follow. Where the trend leaves the fitted root furthest
//! is how far the root bends from the straight seam planned (a face fitted
//! over its whole height meets the flange along a line its foot need not
//! follow: a tube's foot curves off it, a twisted face's foot crosses it).
//! The noise explains a deviation up to [`NOISE_SIGMAS`] times the trend's
//! standard error there (from the station means' own scatter about the
//! parabola, which holds the camera's low-frequency wobble too), and the
//! cloud's resolution one under [`RESOLUTION_SPACINGS`] point spacings. A
//! bend beyond both is a curved root, which
//! [`crate::rules::quality::EDGE_FIT_RESIDUAL`] refuses by name.

use nalgebra::{Matrix3, Vector3};

/// How many standard errors of the trend the camera's noise explains: a
/// straight root's station means give a trend beyond three of them once in
/// several hundred.
pub const NOISE_SIGMAS: f64 = 3.0;

/// The bend the cloud's resolution explains, in point spacings: a root is
/// read from samples a spacing apart, and an edge or a face's foot is
/// placed to about a spacing, so a deviation under one is not a bend that
/// can be told from the sampling (nor one that moves the seam further
/// than the sampling already does).
pub const RESOLUTION_SPACINGS: f64 = 1.0;

/// A station's length along the root, in point spacings, at most: long
/// enough to hold several samples of a sparse cloud's foot, short against
/// a stretch worth planning (a short stretch has shorter stations).
pub const STATION_SPACINGS: f64 = 4.0;

/// The fewest samples that make a station's mean, where the samples are
/// points (a face's foot, the flange beside the root): fewer are a glimpse.
/// Evidence read one sample to a station already (a flange's innermost
/// point per station) passes [`Samples::PerStation`].
pub const MIN_STATION_SAMPLES: usize = 3;

/// The fewest stations that show a curve: a parabola through three is
/// exact, its scatter unmeasured.
pub const MIN_STATIONS: usize = 6;

/// The shortest root whose straightness can be told at `spacing_mm`:
/// [`MIN_STATIONS`] stations of one point spacing each, the shortest a
/// station is.
pub fn shortest_checkable_mm(spacing_mm: f64) -> f64 {
    MIN_STATIONS as f64 * spacing_mm
}

/// What the samples given to [`bend_of`] are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Samples {
    /// Points, averaged per station (at least [`MIN_STATION_SAMPLES`]).
    Points,
    /// One figure per station already.
    PerStation,
}

/// How far a root bends from straight over the stretch read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RootBend {
    /// The largest distance of the samples' trend (the parabola through
    /// the station means) from the fitted root over the stretch, mm.
    pub deviation_mm: f64,
    /// The stretch the stations span, mm.
    pub over_mm: f64,
    /// The largest deviation the noise and the resolution explain, mm.
    pub explained_mm: f64,
    /// Which of the root's evidence bends (`"the web's face"`, ...).
    pub evidence: &'static str,
}

impl RootBend {
    /// Whether the bend is beyond what the noise and the resolution explain.
    pub fn is_curved(&self) -> bool {
        self.deviation_mm > self.explained_mm
    }

    /// The larger of two bends by their share of what is explained, either
    /// when only one was measured.
    pub fn worse(a: Option<RootBend>, b: Option<RootBend>) -> Option<RootBend> {
        match (a, b) {
            (Some(a), Some(b)) => {
                Some(if b.deviation_mm / b.explained_mm > a.deviation_mm / a.explained_mm { b } else { a })
            }
            (a, b) => a.or(b),
        }
    }
}

/// The bend of root samples given as `(t, v)`: `t` along the root, `v` the
/// sample's offset from the fitted root in one direction across it, both
/// mm. `None` where the samples fill fewer than [`MIN_STATIONS`] stations
/// (the stretch is too short, or too sparse, to show a curve).
pub fn bend_of(
    samples: impl IntoIterator<Item = (f64, f64)>,
    kind: Samples,
    spacing_mm: f64,
    evidence: &'static str,
) -> Option<RootBend> {
    let least = match kind {
        Samples::Points => MIN_STATION_SAMPLES,
        Samples::PerStation => 1,
    };
    let samples: Vec<(f64, f64)> = samples.into_iter().filter(|(t, v)| t.is_finite() && v.is_finite()).collect();
    let (lo, hi) = samples.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(t, _)| (lo.min(t), hi.max(t)));
    // Stations of a few spacings, shorter over a short stretch (twice the
    // fewest stations fit in it) down to one spacing, where a face's foot
    // still holds a handful of points: a curved member's root is often
    // seen over a few centimetres only.
    let width = (STATION_SPACINGS * spacing_mm).min((hi - lo) / (2 * MIN_STATIONS) as f64).max(spacing_mm);
    if width.is_nan() || width <= 0.0 {
        return None;
    }
    let mut stations: std::collections::BTreeMap<i64, (f64, f64, usize)> = std::collections::BTreeMap::new();
    for (t, v) in samples {
        let s = stations.entry((t / width).floor() as i64).or_insert((0.0, 0.0, 0));
        s.0 += t;
        s.1 += v;
        s.2 += 1;
    }
    let means: Vec<(f64, f64)> =
        stations.values().filter(|s| s.2 >= least).map(|&(t, v, n)| (t / n as f64, v / n as f64)).collect();
    if means.len() < MIN_STATIONS {
        return None;
    }
    let (t_lo, t_hi) =
        means.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(t, _)| (lo.min(t), hi.max(t)));
    let (mid, half) = (0.5 * (t_lo + t_hi), 0.5 * (t_hi - t_lo));
    if half.is_nan() || half <= 0.0 {
        return None;
    }
    // On x = (t − mid)/half in [−1, 1]: v = a + b·x + c·x².
    let mut normal = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    for &(t, v) in &means {
        let x = (t - mid) / half;
        let row = Vector3::new(1.0, x, x * x);
        normal += row * row.transpose();
        rhs += row * v;
    }
    let inverse = normal.try_inverse()?;
    let coef = inverse * rhs;
    let dof = (means.len() - 3) as f64;
    let scatter = means
        .iter()
        .map(|&(t, v)| {
            let x = (t - mid) / half;
            (v - (coef[0] + coef[1] * x + coef[2] * x * x)).powi(2)
        })
        .sum::<f64>()
        / dof;
    // The trend's largest distance from the fitted root over the stretch:
    // at an end, or at the parabola's vertex where it lies inside.
    let trend = |x: f64| coef[0] + coef[1] * x + coef[2] * x * x;
    let vertex = (coef[2].abs() > 1e-12).then(|| -coef[1] / (2.0 * coef[2])).filter(|x| x.abs() < 1.0);
    let worst = [-1.0, 1.0]
        .into_iter()
        .chain(vertex)
        .fold(0.0, |w: f64, x| if trend(x).abs() > trend(w).abs() { x } else { w });
    let row = Vector3::new(1.0, worst, worst * worst);
    let trend_error = (scatter * (row.transpose() * inverse * row)[(0, 0)]).max(0.0).sqrt();
    tracing::trace!(evidence, ?means, ?coef, worst, trend_error, "root samples' station means");
    Some(RootBend {
        deviation_mm: trend(worst).abs(),
        over_mm: t_hi - t_lo,
        explained_mm: (NOISE_SIGMAS * trend_error).max(RESOLUTION_SPACINGS * spacing_mm),
        evidence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reproducible scatter in [−1, 1] without a random source.
    fn jitter(k: usize) -> f64 {
        ((k as f64 * 12.9898).sin() * 43_758.547).rem_euclid(1.0) * 2.0 - 1.0
    }

    #[test]
    fn a_straight_root_with_noise_is_not_curved() {
        // 100 mm at 1.5 mm spacing, 5 samples per spacing, 1 mm of noise.
        let samples = (0..330).map(|k| (k as f64 * 0.3, jitter(k)));
        let bend = bend_of(samples, Samples::Points, 1.5, "test").expect("enough stations");
        assert!(!bend.is_curved(), "{bend:?}");
        // From the first station's mean to the last's.
        assert!((90.0..99.0).contains(&bend.over_mm), "{bend:?}");
    }

    #[test]
    fn a_root_on_a_circle_is_curved() {
        // A chord of 60 mm of a 40 mm radius, against the tangent at its
        // middle: 13.5 mm off it at the ends, 11 mm at the last stations'
        // middles.
        let radius: f64 = 40.0;
        let samples = (0..200).map(|k| {
            let t = -30.0 + 60.0 * k as f64 / 199.0;
            (t, radius - (radius * radius - t * t).sqrt() + 0.3 * jitter(k))
        });
        let bend = bend_of(samples, Samples::Points, 1.5, "test").expect("enough stations");
        assert!(bend.is_curved(), "{bend:?}");
        assert!((9.0..14.0).contains(&bend.deviation_mm), "{bend:?}");
    }

    #[test]
    fn a_stretch_of_few_stations_is_not_judged() {
        // Stations are never shorter than a spacing, so a stretch a spacing
        // shorter than the fewest stations holds too few of them, however
        // densely sampled.
        let spacing = 1.5;
        let length = (MIN_STATIONS - 1) as f64 * spacing - 0.01;
        let samples = (0..=100).map(|k| (length * k as f64 / 100.0, 0.0));
        assert!(bend_of(samples, Samples::Points, spacing, "test").is_none());
        // Two spacings longer, it is judged (and straight).
        let longer = length + 2.0 * spacing;
        let samples = (0..=100).map(|k| (longer * k as f64 / 100.0, 0.0));
        assert!(!bend_of(samples, Samples::Points, spacing, "test").expect("judged").is_curved());
    }
}
