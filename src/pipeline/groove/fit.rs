//! One side's face between the edges fitted as `|t| = c - h tan α`: its
//! angle, how deep it goes (where it meets a root face, or its foot),
//! whether the camera or the projector sees it down to there, and where it
//! meets the plates' top.

use crate::geometry::MAD_PER_SIGMA;

use super::points::{Across, STATIONS, station_share};
use super::profile::{Face, LineAlong, MIN_FACE_POINTS, StationLine};

/// How far inside the probe's cut at the edges given, in sigmas of a
/// face's fit across the seam, its points must lie to place its top
/// ([`Face::top`]): nearer the cut, noise has taken out the points it
/// moved outward and left those it moved in.
const TOP_CUT_SIGMAS: f64 = 2.5;

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
/// A root face begins where its bevel ends: the depth bins just below the
/// split that still lie nearer the bevel's line than the root face's `|t|`
/// (the corner's, whose medians blend the two) may run on at most this
/// many bins below where the line meets the root face. On the simulated
/// suites' root faces they run on at most 1.13 bins; a streak's stray
/// returns under a groove at 1 mm voxels, taken with the bevel's last
/// bins for a "wall", had the bevel seen 3.3 bins below that meeting
/// (fault-streaks-v-butt-00, whose depth was then read 2.9 mm short).
const MAX_BEVEL_PAST_ROOT_BINS: f64 = 1.5;
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

/// A face whose foot comes within this many point spacings of the probe's
/// bottom may go on below it: its foot is not taken for the root.
const BOTTOM_MARGIN_SPACINGS: f64 = 2.0;

/// A station's own line across the face is fitted from at least this many
/// of the face's kept points there, spread over at least this many point
/// spacings in depth; else the station takes the face's slope and only
/// its own offset. A groove cut by hand changes its bevel along the seam
/// (a wider stretch has a shallower bevel from the same foot), which one
/// slope for the whole face would carry to the wrong foot.
const MIN_STATION_POINTS: usize = 6;
const MIN_STATION_DEPTH_SPACINGS: f64 = 2.0;

/// The slopes `dt/dh` of the camera's and the projector's rays at the
/// seam.
#[derive(Debug, Clone, Copy)]
pub(super) struct Views {
    pub(super) camera: f64,
    pub(super) projector: f64,
}

/// Fits one side's points as `|t| = c - h tan α`; `half_opening` is half
/// the distance between the weld edges.
pub(super) fn fit_face(
    points: &[&Across],
    side: i8,
    spacing: f64,
    (top_margin, bottom, floor_mm): (f64, f64, Option<f64>),
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
    // A face that runs down to the probe's bottom where that bottom is the
    // groove's own floor (a root land) ends on the floor: its foot is
    // where its line meets the floor, the depth the floor's.
    let reaches_bottom = depth_mm >= bottom - BOTTOM_MARGIN_SPACINGS * spacing;
    let floor_mm = floor_mm.filter(|_| reaches_bottom);
    let depth_mm = floor_mm.unwrap_or(depth_mm);
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
    let stations = station_lines(&above, &kept, &line, spacing);
    let station_rms = {
        let off = |p: &&Across| {
            let at = stations[p.station].map_or_else(|| line.at(p.h), |l| l.at(p.h));
            (p.t.abs() - at).powi(2)
        };
        (kept.iter().map(off).sum::<f64>() / kept.len().max(1) as f64).sqrt()
    };
    Some(Face {
        side,
        points: kept.len(),
        angle_deg: angle.to_degrees(),
        // Perpendicular to the face, not along t.
        rms_mm: line.rms * angle.cos(),
        station_rms_mm: station_rms * angle.cos(),
        depth_mm,
        foot_mm: line.at(depth_mm),
        station_share: station_share(kept.iter().copied()),
        along_rays,
        foot_hidden,
        foot_at_probe_bottom: reaches_bottom && floor_mm.is_none(),
        foot_on_floor: floor_mm.is_some(),
        top,
        stations,
    })
}

/// The face's line `|t| = c - h tan α` at each station along the seam:
/// fitted to the station's own points on the side (`points`), trimmed as
/// the face's line is, where they span depth enough
/// ([`MIN_STATION_POINTS`], [`MIN_STATION_DEPTH_SPACINGS`]) and slope as
/// a face does; else the face's slope through the median offset of the
/// face's `kept` points there; None where the station has too few.
fn station_lines(points: &[&Across], kept: &[&Across], line: &Line, spacing: f64) -> [Option<StationLine>; STATIONS] {
    let by_station = |points: &[&Across]| {
        let mut by: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); STATIONS];
        for p in points {
            by[p.station].push((p.s, p.h, p.t.abs()));
        }
        by
    };
    let (own, face) = (by_station(points), by_station(kept));
    std::array::from_fn(|k| {
        let local = station_line(&own[k], spacing);
        let points = &face[k];
        if local.is_some() || points.len() < MIN_STATION_POINTS {
            return local;
        }
        let s = points.iter().map(|p| p.0).sum::<f64>() / points.len() as f64;
        let mut offsets: Vec<f64> = points.iter().map(|p| p.2 - line.slope * p.1).collect();
        let middle = offsets.len() / 2;
        let intercept = *offsets.select_nth_unstable_by(middle, f64::total_cmp).1;
        Some(StationLine { s, intercept, slope: line.slope })
    })
}

/// One station's own line through its `(s, h, |t|)` points: least squares,
/// then twice the points within [`TRIM_SIGMA`] robust sigmas of it; None
/// unless enough of them span depth enough and it slopes as a face does.
fn station_line(points: &[(f64, f64, f64)], spacing: f64) -> Option<StationLine> {
    let mut kept: Vec<(f64, f64, f64)> = points.to_vec();
    let mut line = fit_line(kept.iter().map(|p| (p.1, p.2)))?;
    for _ in 0..2 {
        let mut residuals: Vec<f64> = points.iter().map(|p| (p.2 - line.at(p.1)).abs()).collect();
        let middle = residuals.len() / 2;
        let mad = *residuals.select_nth_unstable_by(middle, f64::total_cmp).1;
        let band = (TRIM_SIGMA * mad / MAD_PER_SIGMA).max(MIN_BAND_SPACINGS * spacing);
        kept = points.iter().copied().filter(|p| (p.2 - line.at(p.1)).abs() <= band).collect();
        line = fit_line(kept.iter().map(|p| (p.1, p.2)))?;
    }
    let (low, high) = kept.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.1), h.max(p.1)));
    let enough = kept.len() >= MIN_STATION_POINTS && high - low >= MIN_STATION_DEPTH_SPACINGS * spacing;
    let s = kept.iter().map(|p| p.0).sum::<f64>() / kept.len() as f64;
    (enough && line.slope < 0.0).then_some(StationLine { s, intercept: line.intercept, slope: line.slope })
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
pub(super) struct Hinge {
    /// The depth bins above the root face.
    pub(super) bins_above: usize,
    /// The depth the root face starts at (the split between the bins).
    pub(super) depth_mm: f64,
    /// The root face's distance from the midline, mm (half the root gap).
    pub(super) root_half_gap_mm: f64,
}

/// The split of the depth bins' median `|t|` (`(h, |t|)` by increasing
/// `h`) into a sloping line above and a constant below that fits them far
/// better than one line does, when the part below is a wall along the
/// normal at least [`MIN_ROOT_BINS`] bins high that the line above runs
/// down into ([`HINGE_MEET_BINS`]).
pub(super) fn root_hinge(medians: &[(f64, f64)], spacing: f64) -> Option<Hinge> {
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
        let meet = (mean - bevel.intercept) / bevel.slope;
        let meets = bevel.slope < 0.0 && (meet - turn).abs() <= HINGE_MEET_BINS * spacing;
        if !meets {
            continue;
        }
        // And ends there: the bins below that still follow its line. Where
        // the line runs within half a spacing of the wall's |t| (about the
        // meeting) a bin follows both, and neither ends the bevel's run
        // nor extends it.
        let follows_line = |m: &&(f64, f64)| (m.1 - bevel.at(m.0)).abs() < (m.1 - mean).abs();
        let either = |m: &&(f64, f64)| (bevel.at(m.0) - mean).abs() < 0.5 * spacing;
        let bevel_seen_to = lower
            .iter()
            .take_while(|m| either(m) || follows_line(m))
            .filter(|m| !either(m))
            .last()
            .map_or(upper[k - 1].0, |m| m.0);
        if bevel_seen_to - meet > MAX_BEVEL_PAST_ROOT_BINS * spacing {
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
