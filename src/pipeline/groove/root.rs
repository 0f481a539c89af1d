//! A V-groove's root read from its two flanks, station by station along
//! the seam ([`GrooveProfile::root`]), and how steady it runs.
//!
//! The paper places a V-groove's weld from its edges: the midline of the
//! two plates' top edges, sunk by the groove depth (Eq. 32). That holds
//! where the edges are sharp lines a machine cut. A groove cut by hand or
//! by a torch has ragged top edges that scatter millimetres about any
//! line, and may be cut wider along part of the seam on one side only,
//! while its flanks run clean down to a root that did not move. The
//! root is then read where the flanks say it is: at each station each
//! flank's own line `|t| = c - h tan α` ([`super::Face::stations`]) is
//! carried down to the groove's depth `d`, and the root lies midway
//! between the two feet there: where a sharp V's flanks meet, the middle
//! of a root land, or the middle of a root gap. A line through those
//! midpoints along the seam (least squares, the stations far off it
//! trimmed) is the root; the midpoints' scatter about it, and any step
//! between two runs of them, are the root's own evidence, judged by the
//! same gates as a top edge's samples would be.

use crate::geometry::MAD_PER_SIGMA;

use super::profile::{GrooveProfile, LineAlong, MAX_SLOPED_FACE_DEG, MIN_BEVEL_DEG};

/// The fewest stations (of [`super::points::STATIONS`]) where both flanks
/// are seen that a root line is read from: a quarter of the seam.
const MIN_ROOT_STATIONS: usize = 8;

/// The largest RMS of a flank the root is read from, in point spacings:
/// half again a bevel's ([`super::profile`]'s one spacing). A depth camera
/// whose noise is of the order of its voxels (a RealSense-class cloud at
/// 1 mm voxels: its plates scatter 0.9 to 1.25 mm about their planes at a
/// 1.08 mm spacing, coboweld/barpoints) leaves a flank a little above one
/// spacing; the root line's own residual is judged by the edge fit's gate.
const MAX_FLANK_RMS_SPACINGS: f64 = 1.5;

/// The band of stations kept about the root line, in robust sigmas of
/// their residuals, and its floor in point spacings: a station where one
/// flank is cut short (a dropout, spatter on it) is left out, not
/// averaged in.
const TRIM_SIGMA: f64 = 3.0;
const MIN_BAND_SPACINGS: f64 = 0.5;

/// A V-groove's root, as its two flanks place it along the seam.
#[derive(Debug, Clone, PartialEq)]
pub struct RootLine {
    /// How far the root lies from the weld edges' midline, across the
    /// seam towards the second edge, along it.
    pub offset: LineAlong,
    /// The depth it was read at below the plates' top, mm.
    pub depth_mm: f64,
    /// Each station's root, `(s, offset)` mm, where both flanks are seen.
    pub samples: Vec<(f64, f64)>,
    /// How many of them the line kept, and their RMS off it, mm.
    pub kept: usize,
    pub rms_mm: f64,
    /// The share of the probed stations with a root sample.
    pub station_share: f64,
    /// From the first station with a root sample to the last, along the
    /// seam's feature axis, mm.
    pub span: (f64, f64),
}

impl RootLine {
    /// Each sample's residual off the root line, `(s, residual)`.
    pub fn residuals(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.samples.iter().map(|&(s, t)| (s, t - self.offset.at(s)))
    }
}

impl GrooveProfile {
    /// The root the two flanks place, when both sides show a sloped plane
    /// face and a bevel shows the root (the groove's depth is measured),
    /// read at stations enough along the seam; None otherwise.
    pub fn root(&self) -> Option<RootLine> {
        let spacing = self.point_spacing_mm;
        let depth = self.depth_mm()?;
        let sloped = |side: i8| {
            self.faces.iter().find(|f| {
                f.side == side
                    && (MIN_BEVEL_DEG..=MAX_SLOPED_FACE_DEG).contains(&f.angle_deg)
                    && f.is_seen()
                    && f.station_rms_mm <= MAX_FLANK_RMS_SPACINGS * spacing
            })
        };
        let (first, second) = (sloped(-1)?, sloped(1)?);
        // The first flank lies at t = -|t|, the second at +|t|.
        let samples: Vec<(f64, f64)> = first
            .stations
            .iter()
            .zip(&second.stations)
            .filter_map(|(a, b)| {
                let (a, b) = (a.as_ref()?, b.as_ref()?);
                Some((0.5 * (a.s + b.s), 0.5 * (b.at(depth) - a.at(depth))))
            })
            .collect();
        let stations = first.stations.len();
        if samples.len() < MIN_ROOT_STATIONS {
            return None;
        }
        let middle_s = 0.5 * (self.span.0 + self.span.1);
        let mut line = fit(samples.iter().copied(), middle_s)?;
        let mut kept: Vec<(f64, f64)> = samples.clone();
        for _ in 0..2 {
            let mut residuals: Vec<f64> = samples.iter().map(|&(s, t)| (t - line.at(s)).abs()).collect();
            let middle = residuals.len() / 2;
            let mad = *residuals.select_nth_unstable_by(middle, f64::total_cmp).1;
            let band = (TRIM_SIGMA * mad / MAD_PER_SIGMA).max(MIN_BAND_SPACINGS * spacing);
            kept = samples.iter().copied().filter(|&(s, t)| (t - line.at(s)).abs() <= band).collect();
            line = fit(kept.iter().copied(), middle_s)?;
        }
        if kept.len() < MIN_ROOT_STATIONS {
            return None;
        }
        let rms_mm = (kept.iter().map(|&(s, t)| (t - line.at(s)).powi(2)).sum::<f64>() / kept.len() as f64).sqrt();
        // Each station is the span's 1/stations; the samples sit inside theirs.
        let station_len = (self.span.1 - self.span.0) / stations as f64;
        let index = |s: f64| (((s - self.span.0) / station_len).floor().max(0.0) as usize).min(stations - 1);
        let (lo, hi) = samples.iter().fold((usize::MAX, 0), |(lo, hi), &(s, _)| (lo.min(index(s)), hi.max(index(s))));
        let span = (self.span.0 + lo as f64 * station_len, self.span.0 + (hi + 1) as f64 * station_len);
        Some(RootLine {
            offset: line,
            depth_mm: depth,
            kept: kept.len(),
            rms_mm,
            station_share: samples.len() as f64 / stations as f64,
            span,
            samples,
        })
    }
}

/// The least squares line `t = a + b (s - middle_s)` through `(s, t)`.
fn fit(points: impl Iterator<Item = (f64, f64)> + Clone, middle_s: f64) -> Option<LineAlong> {
    let n = points.clone().count() as f64;
    if n < 2.0 {
        return None;
    }
    let (ms, mt) = points.clone().fold((0.0, 0.0), |(a, b), (s, t)| (a + (s - middle_s) / n, b + t / n));
    let (sss, sst) = points.fold((0.0, 0.0), |(a, b), (s, t)| {
        let x = s - middle_s - ms;
        (a + x * x, b + x * (t - mt))
    });
    if sss <= f64::EPSILON {
        return None;
    }
    let per_mm = sst / sss;
    Some(LineAlong { middle_s, at_middle_mm: mt - per_mm * ms, per_mm })
}
