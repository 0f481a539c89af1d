//! A plate's points in the band beside a weld edge, and the stretch along
//! an edge that a plate is seen beside.

use crate::cloud::PointCloud;
use crate::geometry::{Vec3, vec3};

use super::CoarseEdge;

/// The members within `band_mm` of `edge` on either side, in their order:
/// all [`super::sample_boundary`] and [`members_along`] read of a plate. A plate
/// of a raw frame has about a million members and the band a few
/// thousand, so the pass over the members is made once and the two read
/// the band.
pub fn band_members(cloud: &PointCloud, members: &[u32], edge: &CoarseEdge, band_mm: f64) -> Vec<u32> {
    use rayon::prelude::*;
    let points = cloud.points();
    let in_band = |i: u32| (vec3(&points[i as usize]) - edge.point).dot(&edge.outward).abs() <= band_mm;
    // Plain loops over fixed chunks, joined in order: the pass is bound by
    // memory only when the test is compiled into it, which rayon's
    // filter adaptors left to the optimiser's inlining (2 ms more per
    // frame in one build).
    let pieces: Vec<Vec<u32>> = members
        .par_chunks(MEMBERS_PER_CHUNK)
        .map(|chunk| chunk.iter().copied().filter(|&i| in_band(i)).collect())
        .collect();
    pieces.concat()
}

/// Members read per parallel job in the passes over a plate's members.
pub(super) const MEMBERS_PER_CHUNK: usize = 1 << 14;

/// The farthest back and farthest forward of the points added along an
/// edge, each the first added of those at its extreme (so the result does
/// not depend on how the members are split among jobs).
#[derive(Clone, Copy, Default)]
struct AlongReach {
    back: Option<(f64, Vec3)>,
    forward: Option<(f64, Vec3)>,
}

impl AlongReach {
    fn add(&mut self, t: f64, v: Vec3) {
        if self.back.is_none_or(|(b, _)| t < b) {
            self.back = Some((t, v));
        }
        if self.forward.is_none_or(|(f, _)| t > f) {
            self.forward = Some((t, v));
        }
    }

    /// `self` then `later`, as if `later`'s points were added after.
    fn then(self, later: AlongReach) -> AlongReach {
        let mut joined = self;
        for (t, v) in later.back.into_iter().chain(later.forward) {
            joined.add(t, v);
        }
        joined
    }
}

/// The plate's members in the band inside `edge` (between the band's
/// inner side and the coarse edge) that lie farthest back and farthest
/// forward along it: where the plate is seen beside the weld. `None`
/// when no member lies there. `members` may be all the plate's or only
/// those [`band_members`] keeps.
pub fn members_along(cloud: &PointCloud, members: &[u32], edge: &CoarseEdge, band_mm: f64) -> Option<[Vec3; 2]> {
    use rayon::prelude::*;
    let points = cloud.points();
    let reach = members
        .par_chunks(MEMBERS_PER_CHUNK)
        .map(|chunk| {
            let mut reach = AlongReach::default();
            for &i in chunk {
                let v = vec3(&points[i as usize]);
                let d = v - edge.point;
                if (-band_mm..=0.0).contains(&d.dot(&edge.outward)) {
                    reach.add(d.dot(&edge.direction), v);
                }
            }
            reach
        })
        .reduce(AlongReach::default, AlongReach::then);
    Some([reach.back?.1, reach.forward?.1])
}

/// A plate's edge and the stretch along it its edge points span, mm from
/// `edge.point` along `edge.direction`.
#[derive(Debug, Clone, Copy)]
pub struct SpannedEdge {
    pub edge: CoarseEdge,
    pub span: [f64; 2],
}

/// The most bins an edge's stretch is cut into: a span longer than this
/// many bins is read in coarser bins, so a wild line cannot ask for an
/// unbounded count.
const MAX_STRETCH_BINS: usize = 1 << 14;

/// How many points of a plate, spread at its point spacing, a bin beside
/// an edge must expect before the plate's points are read one in several:
/// enough that a bin the plate covers is never left empty by the
/// thinning.
const POINTS_PER_BIN_READ: f64 = 16.0;

/// How long a stretch of each edge the points of `members` are seen
/// beside, mm: each edge's span cut into bins of `bin_mm`, a bin counted
/// where a point lies in it within `band_mm` beyond the edge (on its
/// outward side). A plate seen beside another's edge along its whole
/// length fills every bin; one seen only at a corner, or beyond the
/// image border, few or none. Where a bin holds far more points than it
/// takes to see it covered (`spacing_mm` apart), one point in several is
/// read: a dense frame's plate is millions of points, read here for a
/// yes or no per bin.
pub fn stretch_seen_beside(
    cloud: &PointCloud,
    members: &[&[u32]],
    edges: &[SpannedEdge],
    figures: [f64; 3],
) -> Vec<f64> {
    stretch_seen_beside_reading(cloud, members, edges, figures, read_stride(figures))
}

/// One point in how many [`stretch_seen_beside`] reads of a set spread at
/// `spacing_mm` to see bins of `bin_mm` by `band_mm` covered: a caller
/// that gathers the points itself (from the whole cloud) gathers that
/// share only.
pub fn read_stride([band_mm, bin_mm, spacing_mm]: [f64; 3]) -> usize {
    let per_bin = band_mm * bin_mm / (spacing_mm * spacing_mm).max(f64::MIN_POSITIVE);
    (per_bin / POINTS_PER_BIN_READ).floor().clamp(1.0, u16::MAX as f64) as usize
}

/// [`stretch_seen_beside`], reading one member in `stride`: 1 for
/// members already thinned by [`read_stride`].
pub fn stretch_seen_beside_reading(
    cloud: &PointCloud,
    members: &[&[u32]],
    edges: &[SpannedEdge],
    [band_mm, bin_mm, _]: [f64; 3],
    stride: usize,
) -> Vec<f64> {
    use rayon::prelude::*;
    let points = cloud.points();
    let bins: Vec<(usize, f64)> = edges
        .iter()
        .map(|e| {
            let length = (e.span[1] - e.span[0]).max(0.0);
            let count = ((length / bin_mm).ceil() as usize).clamp(1, MAX_STRETCH_BINS);
            (count, (length / count as f64).max(f64::MIN_POSITIVE))
        })
        .collect();
    let empty = || bins.iter().map(|&(count, _)| vec![false; count]).collect::<Vec<_>>();
    let chunks: Vec<&[u32]> = members.iter().flat_map(|m| m.chunks(MEMBERS_PER_CHUNK)).collect();
    let seen = chunks
        .into_par_iter()
        .map(|chunk| {
            let mut seen = empty();
            for &i in chunk.iter().step_by(stride) {
                let v = vec3(&points[i as usize]);
                for ((e, &(count, width)), seen) in edges.iter().zip(&bins).zip(&mut seen) {
                    let d = v - e.edge.point;
                    let out = d.dot(&e.edge.outward);
                    let along = d.dot(&e.edge.direction) - e.span[0];
                    if out > 0.0 && out <= band_mm && along >= 0.0 && along < count as f64 * width {
                        // The quotient may round up to `count` at the span's end.
                        seen[((along / width) as usize).min(count - 1)] = true;
                    }
                }
            }
            seen
        })
        .reduce(empty, |mut a, b| {
            a.iter_mut().zip(b).for_each(|(a, b)| a.iter_mut().zip(b).for_each(|(a, b)| *a |= b));
            a
        });
    seen.iter().zip(&bins).map(|(s, &(_, width))| s.iter().filter(|&&b| b).count() as f64 * width).collect()
}
