//! The points the probe reads: the image rows under the probed box, the
//! stations along the seam they fall at, and those that lie on a surface
//! rather than in a veil of mixed pixels.

use rayon::prelude::*;

use crate::cloud::Point;
use crate::geometry::{Vec3, extent};

use super::super::context::CameraGrid;

/// The stations the seam is cut into to count where something is seen.
pub(super) const STATIONS: usize = 32;

/// A point on a surface has other points around it; one of a veil of
/// mixed pixels has only its own row's neighbours at unrelated depths. The
/// points between the edges with fewer than this many others within
/// [`SURFACE_RADIUS_SPACINGS`] are dropped before any fit.
pub(super) const MIN_SURFACE_NEIGHBOURS: usize = 4;
/// The radius is not two spacings: a bevel seen nearly head-on (60 to 65
/// degrees from its normal, a V-groove under a camera straight above it)
/// has its points stretched across the seam past two spacings, so its
/// four nearest neighbours are the two either side along the seam, the
/// farther pair exactly two of the camera's pixel steps away. The
/// cloud's median spacing and that step differ by a few percent across a
/// frame, and at two spacings the test dropped a bevel's points at one
/// place along the seam and kept them at another (18 of 45 stations of a
/// simulated 52 degree groove at 500 mm showed no bevel). Half a spacing
/// more takes the pair in wherever the step is within a quarter of the
/// median, and still leaves a mixed pixel, millimetres off its row's
/// neighbours, alone.
pub(super) const SURFACE_RADIUS_SPACINGS: f64 = 2.5;

/// How near the camera, along its axis, a corner of the probed box may come
/// before the box is not projected (the whole frame is read instead).
const MIN_PROJECTED_DEPTH_MM: f64 = 10.0;
/// How many pixels the projected box is widened by each way: a point's
/// pixel is its projection rounded, and the box's margins are a millimetre.
const PIXEL_MARGIN: f64 = 2.0;

/// A point between the edges in the seam's axes.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Across {
    /// Along the seam, mm.
    pub(super) s: f64,
    pub(super) station: usize,
    /// Signed distance from the midline, positive towards the second edge.
    pub(super) t: f64,
    /// Depth below the edges' mean height, along the normal.
    pub(super) h: f64,
}

/// The image rows the convex hull of `corners` projects onto, each with
/// the columns it covers there (widened by [`PIXEL_MARGIN`]), as `(row,
/// first column, last column)`. None when a corner lies behind or too near
/// the camera, where a projection says nothing.
pub(super) fn rows_under(grid: &CameraGrid, corners: &[Vec3]) -> Option<Vec<(usize, usize, usize)>> {
    let (width, height) = grid.size();
    let projected: Vec<(f64, f64)> = corners
        .iter()
        .map(|c| if c.z > MIN_PROJECTED_DEPTH_MM { grid.project(c) } else { None })
        .collect::<Option<_>>()?;
    let (v_lo, v_hi) = extent(projected.iter().map(|p| p.1));
    let first = (v_lo - PIXEL_MARGIN).floor().max(0.0) as usize;
    let last = ((v_hi + PIXEL_MARGIN).ceil().min(height as f64 - 1.0)).max(-1.0);
    if last < first as f64 {
        return Some(Vec::new());
    }
    // The hull's part in the strip of rows `v ± margin`: the corners in it
    // and the pairs' segments where they cross its two lines (the hull of
    // points meets a line where the segments between them do).
    let columns = |v: f64| {
        let (y0, y1) = (v - PIXEL_MARGIN, v + PIXEL_MARGIN);
        let mut range = (f64::INFINITY, f64::NEG_INFINITY);
        let mut take = |u: f64| range = (range.0.min(u), range.1.max(u));
        for (k, a) in projected.iter().enumerate() {
            if (y0..=y1).contains(&a.1) {
                take(a.0);
            }
            for b in &projected[k + 1..] {
                for y in [y0, y1] {
                    if (a.1 - y) * (b.1 - y) <= 0.0 && a.1 != b.1 {
                        take(a.0 + (b.0 - a.0) * (y - a.1) / (b.1 - a.1));
                    }
                }
            }
        }
        range
    };
    Some(
        (first..=last as usize)
            .filter_map(|v| {
                let (lo, hi) = columns(v as f64);
                let (lo, hi) =
                    ((lo - PIXEL_MARGIN).floor().max(0.0), (hi + PIXEL_MARGIN).ceil().min(width as f64 - 1.0));
                (lo <= hi).then_some((v, lo as usize, hi as usize))
            })
            .collect(),
    )
}

/// The share of the stations at least one of `points` lies at.
pub(super) fn station_share<'p>(points: impl IntoIterator<Item = &'p Across>) -> f64 {
    let mut seen = [false; STATIONS];
    for p in points {
        seen[p.station] = true;
    }
    seen.iter().filter(|&&s| s).count() as f64 / STATIONS as f64
}

/// The points with at least [`MIN_SURFACE_NEIGHBOURS`] others within
/// `radius` (in s, t, h).
///
/// Sorted along the seam, a point's neighbours are among the points whose
/// `s` lies within the radius of its own: a slab across the groove one
/// diameter thick. The slab is read outward from the point, nearest in `s`
/// first, and the reading stops once enough neighbours are found. A
/// groove's steep faces crowd a slab's points into a narrow band across
/// the seam, so ordering them across it as well saves little; building a
/// cell index over the same points cost twice this
/// (`tests::on_surfaces_by_cells`, the reference this is checked
/// against).
pub(super) fn on_surfaces(mut points: Vec<Across>, radius: f64) -> Vec<Across> {
    // Single precision: the coordinates are millimetres from the seam's
    // middle, so a hundredth of a micrometre at worst.
    let mut sorted: Vec<(Point, u32)> =
        points.iter().enumerate().map(|(i, p)| ([p.s, p.t, p.h].map(|v| v as f32), i as u32)).collect();
    sorted.par_sort_unstable_by(|a, b| a.0[0].total_cmp(&b.0[0]));
    let radius_sq = (radius * radius) as f32;
    let keep_sorted: Vec<bool> = (0..sorted.len())
        .into_par_iter()
        .map(|k| {
            let p = &sorted[k].0;
            // A point this far along the seam alone is out of reach, and so
            // is every point past it: the squared distance only grows with
            // the other two terms, as it does in `within`.
            let in_slab = |q: &&Point| (p[0] - q[0]) * (p[0] - q[0]) <= radius_sq;
            // The next point to read below and above the point's place.
            let (mut below, mut above) = (k, k + 1);
            let mut found = 0;
            loop {
                let down = below.checked_sub(1).map(|j| &sorted[j].0).filter(in_slab);
                let up = sorted.get(above).map(|(q, _)| q).filter(in_slab);
                if down.is_none() && up.is_none() {
                    return false;
                }
                found += down.into_iter().chain(up).filter(|q| crate::kernels::within(p, q, radius_sq)).count();
                if found >= MIN_SURFACE_NEIGHBOURS {
                    return true;
                }
                below -= usize::from(down.is_some());
                above += usize::from(up.is_some());
            }
        })
        .collect();
    let mut keep = vec![false; points.len()];
    for ((_, i), k) in sorted.iter().zip(keep_sorted) {
        keep[*i as usize] = k;
    }
    drop(sorted);
    // In place: `retain` reads the points once each, in order.
    let mut kept = keep.into_iter();
    points.retain(|_| kept.next().unwrap_or(false));
    points
}
