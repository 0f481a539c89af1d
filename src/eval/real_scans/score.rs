//! A plan of a real scan judged against its reference.
//!
//! Each seam planned is matched to the reference root it lies nearest
//! (median distance of its waypoints from the root line); its distance is
//! the median and the max over its waypoints. A root's coverage is the
//! share of its visible stretch that the seams matched to it cover within
//! the bar: between two consecutive waypoints both within the bar, the
//! stretch of root between their feet is covered. A seam more than
//! [`CONFIDENT_WRONG_MM`] from its root anywhere, or any seam where only a
//! refusal is right, is confident wrong; a plan whose every root is
//! covered within the bar over the least share is right; one within
//! [`CONFIDENT_WRONG_MM`] that misses the bar is short of it.

use crate::geometry::Vec3;

use super::{CONFIDENT_WRONG_MM, Expect, ScanReference, bar_for};

/// One planned seam against the root it lies nearest.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamScore {
    /// The index of the root it was matched to.
    pub root: usize,
    pub median_mm: f64,
    pub max_mm: f64,
}

/// One reference root against the seams matched to it.
#[derive(Debug, Clone, PartialEq)]
pub struct RootScore {
    pub visible_mm: f64,
    /// The share of the visible stretch covered within the bar.
    pub coverage: f64,
}

/// What a plan is on a real scan.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Every root within the bar over the least share, or refused for the
    /// expected class of reason.
    Right,
    /// Refused where a plan was expected, or for a reason other than the
    /// expected class's rules.
    Refused { rule: &'static str },
    /// Every seam within [`CONFIDENT_WRONG_MM`] of a root, but a root is
    /// not covered within the bar over the least share.
    ShortOfBar,
    /// A seam off every root, or a seam where only a refusal is right.
    ConfidentWrong { why: String },
}

impl Verdict {
    pub fn label(&self) -> String {
        match self {
            Verdict::Right => "right".into(),
            Verdict::Refused { rule } => format!("refused ({rule})"),
            Verdict::ShortOfBar => "short of the bar".into(),
            Verdict::ConfidentWrong { .. } => "CONFIDENT WRONG".into(),
        }
    }
}

/// A plan of a scan against its reference.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanScore {
    pub verdict: Verdict,
    pub seams: Vec<SeamScore>,
    pub roots: Vec<RootScore>,
}

/// Judges what the planner returned: the seams' waypoints in the cloud's
/// frame, mm, or the id of the rule that refused. A root without its
/// measured figures cannot be scored (the references are not blessed):
/// None.
pub fn score(reference: &ScanReference, planned: Result<&[Vec<Vec3>], &'static str>) -> Option<ScanScore> {
    let roots: Vec<_> = reference.roots.iter().map(|r| r.measured.as_ref()).collect::<Option<Vec<_>>>()?;
    let seams_planned = match planned {
        Err(rule) => {
            let right = reference.expect == Expect::Refused
                && reference.refusal.as_ref().is_some_and(|r| r.rules.iter().any(|id| id == rule));
            let verdict = if right { Verdict::Right } else { Verdict::Refused { rule } };
            let roots = roots.iter().map(|r| RootScore { visible_mm: r.visible_length_mm(), coverage: 0.0 }).collect();
            return Some(ScanScore { verdict, seams: Vec::new(), roots });
        }
        Ok(seams) => seams,
    };
    if reference.expect == Expect::Refused {
        let class = reference.refusal.as_ref().map_or("nothing to plan", |r| r.class.describe());
        return Some(ScanScore {
            verdict: Verdict::ConfidentWrong {
                why: format!("{} seam(s) planned where only a refusal is right ({class})", seams_planned.len()),
            },
            seams: Vec::new(),
            roots: Vec::new(),
        });
    }
    let (bar_mm, min_coverage) = bar_for(reference.joint);
    let mut seams = Vec::new();
    let mut covered: Vec<Vec<[f64; 2]>> = vec![Vec::new(); roots.len()];
    for path in seams_planned.iter().filter(|p| !p.is_empty()) {
        let per_root: Vec<Vec<(f64, f64)>> =
            roots.iter().map(|r| path.iter().map(|p| r.along_and_off_either(p)).collect()).collect();
        let medians: Vec<f64> = per_root.iter().map(|w| median(w.iter().map(|(_, off)| *off).collect())).collect();
        let Some(nearest) = (0..roots.len()).min_by(|&a, &b| medians[a].total_cmp(&medians[b])) else {
            break;
        };
        let waypoints = &per_root[nearest];
        let max_mm = waypoints.iter().map(|(_, off)| *off).fold(0.0, f64::max);
        seams.push(SeamScore { root: nearest, median_mm: medians[nearest], max_mm });
        for pair in waypoints.windows(2) {
            if pair.iter().all(|(_, off)| *off <= bar_mm) {
                let (a, b) = (pair[0].0, pair[1].0);
                covered[nearest].push([a.min(b), a.max(b)]);
            }
        }
    }
    let root_scores: Vec<RootScore> = roots
        .iter()
        .zip(&covered)
        .map(|(r, spans)| {
            let length = union_within(spans, r.visible_mm);
            RootScore { visible_mm: r.visible_length_mm(), coverage: length / r.visible_length_mm().max(f64::EPSILON) }
        })
        .collect();
    let verdict = if let Some((k, worst)) = seams
        .iter()
        .enumerate()
        .filter(|(_, s)| s.max_mm > CONFIDENT_WRONG_MM)
        .max_by(|a, b| a.1.max_mm.total_cmp(&b.1.max_mm))
    {
        Verdict::ConfidentWrong {
            why: format!(
                "seam {} lies up to {:.2} mm from the nearest root ({}), beyond {CONFIDENT_WRONG_MM} mm",
                k + 1,
                worst.max_mm,
                reference.roots[worst.root].name
            ),
        }
    } else if seams.is_empty() {
        Verdict::Refused { rule: "-" }
    } else if root_scores.iter().all(|r| r.coverage >= min_coverage) && seams.iter().all(|s| s.median_mm <= bar_mm) {
        Verdict::Right
    } else {
        Verdict::ShortOfBar
    };
    Some(ScanScore { verdict, seams, roots: root_scores })
}

/// The length of the union of `spans` inside `within`.
fn union_within(spans: &[[f64; 2]], within: [f64; 2]) -> f64 {
    let mut clipped: Vec<[f64; 2]> =
        spans.iter().map(|s| [s[0].max(within[0]), s[1].min(within[1])]).filter(|s| s[1] > s[0]).collect();
    clipped.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut total = 0.0;
    let mut reach = f64::NEG_INFINITY;
    for s in clipped {
        let start = s[0].max(reach);
        if s[1] > start {
            total += s[1] - start;
        }
        reach = reach.max(s[1]);
    }
    total
}

fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { (values[n / 2 - 1] + values[n / 2]) / 2.0 }
}
