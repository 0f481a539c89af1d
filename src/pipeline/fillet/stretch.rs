//! The stretch of a root seen, and where its ends lie: stations a few
//! spacings long along the root, the longest run of those holding both
//! kinds of evidence (across short breaks), its ends moved to where the
//! image's border crosses the root when the evidence runs up to the
//! border, and how far the joint is still seen past each end.

use std::collections::HashMap;

use crate::geometry::{Vec3, extent};

use super::super::boundary::JOINT_BREAK_SPACINGS;
use super::super::view_border::{BORDER_REACH_SPACINGS, SpanEnd, ViewBorder};
use super::TeeView;

/// The length of a station along the root, in point spacings.
pub(super) const STATION_SPACINGS: f64 = 4.0;

/// The most stations a root is read at: a root a few metres long at a
/// fine spacing still costs nothing.
pub(super) const MAX_STATIONS: usize = 20_000;

/// The stretch of the root seen: the longest run of stations holding both
/// kinds of evidence, across breaks of at most
/// [`JOINT_BREAK_SPACINGS`], its ends at the last evidence inward.
///
/// `seen_mm`, the joint in view, is measured as the stretch is: each run
/// from where both kinds of evidence begin to where either ends, summed
/// over the runs. Counted in whole stations instead, the run the root
/// spans would count up to a station past each of its ends that the root,
/// ending at its evidence, never covers: a root seen over its whole
/// visible stretch would read a few stations short of it, more the
/// coarser the cloud (a station is four spacings).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SeenRun {
    pub(super) s0: f64,
    pub(super) s1: f64,
    pub(super) coverage: [f64; 2],
    /// The share of `seen_mm` the stretch `s0..s1` spans.
    pub(super) share: f64,
    pub(super) seen_mm: f64,
    /// Whether stretches seen apart from the run, past a longer break,
    /// were left out.
    pub(super) cut: bool,
}

pub(super) fn seen_run(foot: &[f64], flange: &[f64], spacing: f64) -> Option<SeenRun> {
    let (lo, hi) = extent(foot.iter().chain(flange).copied());
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let width = (STATION_SPACINGS * spacing).max((hi - lo) / MAX_STATIONS as f64).max(f64::MIN_POSITIVE);
    let stations = (((hi - lo) / width).floor() as usize + 1).min(MAX_STATIONS);
    let station = |s: f64| (((s - lo) / width).floor() as usize).min(stations - 1);
    // Per station and kind of evidence: the least and greatest `s` held.
    let mut held = vec![[(f64::INFINITY, f64::NEG_INFINITY); 2]; stations];
    for (j, samples) in [foot, flange].into_iter().enumerate() {
        for &s in samples {
            let (lo, hi) = &mut held[station(s)][j];
            (*lo, *hi) = (lo.min(s), hi.max(s));
        }
    }
    let has: Vec<[bool; 2]> = held.iter().map(|h| h.map(|(lo, hi)| lo <= hi)).collect();
    let seen: Vec<bool> = has.iter().map(|h| h[0] && h[1]).collect();
    // Runs of seen stations joined across short breaks.
    let max_break = ((JOINT_BREAK_SPACINGS * spacing) / width).floor() as usize;
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for k in (0..stations).filter(|&k| seen[k]) {
        match runs.last_mut() {
            Some((_, last)) if k - *last - 1 <= max_break => *last = k,
            _ => runs.push((k, k)),
        }
    }
    let &(first, last) = runs.iter().max_by_key(|(a, b)| b - a)?;
    let in_run = |k: usize| (first..=last).contains(&k);
    // A run's stretch: from where both kinds of evidence begin among its
    // stations to where either ends (empty where they do not overlap).
    let stretch_of = |(a, b): (usize, usize)| {
        let ends = |j: usize| {
            held[a..=b].iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), h| (lo.min(h[j].0), hi.max(h[j].1)))
        };
        let (foot_ends, flange_ends) = (ends(0), ends(1));
        (foot_ends.0.max(flange_ends.0), foot_ends.1.min(flange_ends.1))
    };
    let (s0, s1) = stretch_of((first, last));
    if s1 <= s0 {
        return None;
    }
    let count = (last - first + 1) as f64;
    let share_of = |j: usize| (first..=last).filter(|&k| in_run(k) && has[k][j]).count() as f64 / count;
    let seen_mm: f64 = runs
        .iter()
        .map(|&run| {
            let (a, b) = stretch_of(run);
            (b - a).max(0.0)
        })
        .sum();
    Some(SeenRun {
        s0,
        s1,
        coverage: [share_of(0), share_of(1)],
        share: ((s1 - s0) / seen_mm).min(1.0),
        seen_mm,
        cut: runs.len() > 1,
    })
}

/// How far beyond each end of the stretch `(s0, s1)` the joint is still
/// seen, mm: over the stations on from each end (across breaks no longer
/// than [`JOINT_BREAK_SPACINGS`]) holding both a point of the web's top
/// (`top`, along the root) and a flange point beside the root (`flange`),
/// to the outermost place both reach.
pub(super) fn joint_beyond_run(top: &[f64], flange: &[f64], (s0, s1): (f64, f64), spacing: f64) -> [f64; 2] {
    let width = STATION_SPACINGS * spacing;
    let station = |s: f64| (s / width).floor() as i64;
    let extents = |samples: &[f64]| {
        let mut at: HashMap<i64, (f64, f64)> = HashMap::new();
        for &s in samples {
            at.entry(station(s)).and_modify(|(lo, hi)| (*lo, *hi) = (lo.min(s), hi.max(s))).or_insert((s, s));
        }
        at
    };
    let (top_at, flange_at) = (extents(top), extents(flange));
    let both = |k: i64| top_at.get(&k).zip(flange_at.get(&k));
    let max_break = (JOINT_BREAK_SPACINGS * spacing / width).floor() as i64;
    // The outermost station seen from `from` on in direction `step`.
    let outermost = |from: i64, step: i64| {
        let (mut k, mut last, mut missed) = (from, None, 0);
        while missed <= max_break {
            if both(k).is_some() {
                (last, missed) = (Some(k), 0);
            } else {
                missed += 1;
            }
            k += step;
        }
        last.and_then(both)
    };
    let before = outermost(station(s0), -1).map_or(0.0, |(t, f)| (s0 - t.0.max(f.0)).max(0.0));
    let after = outermost(station(s1), 1).map_or(0.0, |(t, f)| (t.1.min(f.1) - s1).max(0.0));
    [before, after]
}

/// The share of the stations from `s0` to `s1` holding a sample.
pub(super) fn covered_share(samples: &[f64], s0: f64, s1: f64, spacing: f64) -> f64 {
    let width = (STATION_SPACINGS * spacing).max((s1 - s0) / MAX_STATIONS as f64).max(f64::MIN_POSITIVE);
    let count = (((s1 - s0) / width).ceil() as usize).max(1);
    let mut seen = vec![false; count];
    for s in samples.iter().filter(|s| (s0..=s1).contains(*s)) {
        seen[(((s - s0) / width) as usize).min(count - 1)] = true;
    }
    seen.iter().filter(|&&b| b).count() as f64 / count as f64
}

/// The run's ends moved to where the root crosses the image's border,
/// each where the face's foot and the flange beside the root (`evidence`,
/// along the root `origin + t · r`) both reach that border within its last
/// station ([`ViewBorder::end_at_border`]): a border crossing the root
/// obliquely cuts the evidence, which lies a spacing or more off the root,
/// before or after it cuts the root. An end moves at most a station, in
/// either direction; one that the evidence does not carry to the border
/// stays where the evidence puts it.
pub(super) fn ends_at_border(
    border: &ViewBorder,
    origin: &Vec3,
    r: &Vec3,
    run: SeenRun,
    evidence: [&[Vec3]; 2],
    spacing: f64,
) -> SeenRun {
    let station = STATION_SPACINGS * spacing;
    let reach = BORDER_REACH_SPACINGS * spacing;
    let along = |p: &Vec3| (p - origin).dot(r);
    let near = |at: f64| {
        evidence.map(|set| set.iter().copied().filter(|p| (along(p) - at).abs() <= station).collect::<Vec<Vec3>>())
    };
    let moved = |end: SpanEnd, at: f64| {
        let sets = near(at);
        let sets: [&[Vec3]; 2] = [&sets[0], &sets[1]];
        border.end_at_border(origin, r, end, at, &sets, reach, station).unwrap_or(at)
    };
    let (s0, s1) = (moved(SpanEnd::Start, run.s0), moved(SpanEnd::End, run.s1));
    if s1 <= s0 {
        return run;
    }
    SeenRun { s0, s1, share: ((s1 - s0) / run.seen_mm).min(1.0), ..run }
}

/// The run's ends carried on past where the image's border, not the web,
/// ends the face's foot. A face seen only well above the flange (its lower
/// part turned nearly edge-on) has its foot up the face, and where the
/// border crosses the web that foot leaves the view before the root does:
/// the camera is tilted, and what stands higher is seen further in. When
/// the foot's last point lies at the border (within the sampling's reach
/// of it: past the camera's grid a reach on, or by the border the cloud's
/// rays show), the root runs on as far as the flange is seen up to it
/// (across breaks no longer than [`JOINT_BREAK_SPACINGS`]), short of any
/// flange seen under where the web would stand (`under_web`: the web
/// ended there). Where that flange runs to the border too, the end moves
/// on to where the root itself leaves the view, at most a station on; it
/// never lies out of view. An end the border does not cut (the web's end,
/// its shadow, something covering the foot) stays where the evidence puts
/// it.
#[allow(clippy::too_many_arguments)]
pub(super) fn ends_past_cut_foot(
    view: &TeeView,
    origin: &Vec3,
    r: &Vec3,
    run: SeenRun,
    foot: &[Vec3],
    beside: &[Vec3],
    under_web: &[f64],
    spacing: f64,
) -> SeenRun {
    let station = STATION_SPACINGS * spacing;
    let reach = BORDER_REACH_SPACINGS * spacing;
    let max_break = JOINT_BREAK_SPACINGS * spacing;
    let step = 0.25 * spacing;
    let along = |p: &Vec3| (p - origin).dot(r);
    let at_border = |p: &Vec3, outward: f64| match (view.in_view, view.border) {
        (Some(in_view), _) => !in_view(&(p + r * (outward * reach))),
        (None, Some(border)) => border.outside_mm(p) > -reach,
        (None, None) => false,
    };
    let root_in_view = |s: f64| {
        let p = origin + r * s;
        match (view.in_view, view.border) {
            (Some(in_view), _) => in_view(&p),
            (None, Some(border)) => border.outside_mm(&p) <= 0.0,
            (None, None) => true,
        }
    };
    let carried = |end: f64, outward: f64| {
        let ahead_of_end = |s: f64| outward * (s - end);
        let Some(last_foot) = foot.iter().max_by(|a, b| ahead_of_end(along(a)).total_cmp(&ahead_of_end(along(b))))
        else {
            return end;
        };
        if !at_border(last_foot, outward) {
            return end;
        }
        let web_ends = under_web.iter().map(|&s| ahead_of_end(s)).filter(|&d| d > 0.0).fold(f64::INFINITY, f64::min);
        let mut ahead: Vec<(f64, &Vec3)> =
            beside.iter().map(|p| (ahead_of_end(along(p)), p)).filter(|&(d, _)| d > 0.0 && d < web_ends).collect();
        ahead.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut reached: Option<(f64, &Vec3)> = None;
        for (d, p) in ahead {
            if d - reached.map_or(0.0, |(r, _)| r) > max_break {
                break;
            }
            reached = Some((d, p));
        }
        let Some((mut to, last_flange)) = reached else {
            return end;
        };
        if at_border(last_flange, outward) {
            let limit = (to + station).min(web_ends);
            while to + step <= limit && root_in_view(end + outward * (to + step)) {
                to += step;
            }
        }
        while to > 0.0 && !root_in_view(end + outward * to) {
            to = (to - step).max(0.0);
        }
        end + outward * to
    };
    let (s0, s1) = (carried(run.s0, -1.0), carried(run.s1, 1.0));
    if (s0, s1) == (run.s0, run.s1) {
        return run;
    }
    // The face's foot is not seen along what was added.
    let foot_share = run.coverage[0] * (run.s1 - run.s0) / (s1 - s0);
    SeenRun { s0, s1, coverage: [foot_share, run.coverage[1]], share: ((s1 - s0) / run.seen_mm).min(1.0), ..run }
}
