//! Boundary sampling: where exactly a plate ends beside the weld.
//!
//! Edge points from the edge criterion lie up to R inside the true edge,
//! because the plane criterion has already trimmed the outermost points.
//! On a pixel grid the true boundary can be read directly: walk each scan
//! line outward across the coarse weld edge while the pixels stay on the
//! plate's plane; the plate ends between the last such pixel and the next,
//! so the boundary sample is half a pixel step beyond the last one. The
//! walk also runs past the ends of the coarse edge, so the samples reach
//! the plate's corners and give the seam's true extent.
//!
//! Without a grid ([`sample_scattered`]) the same rule is read from the
//! points themselves: cut the band beside the coarse edge into strips two
//! point spacings wide along the edge; walk each strip's on-plane points
//! outward until they stop (an empty stretch wider than the plate's
//! interior ever shows, or the band's end); the plate ends on average one
//! gap beyond the last point, where the k points of the strip's last row
//! split the spacing into k + 1 gaps (one point: half a spacing, as on the
//! grid). Where a plate's points scatter about its plane by more than the
//! on-plane tolerance (a consumer camera's depth noise in a 1 mm voxel
//! cloud), the tolerance keeps only some of them and the outermost one
//! kept lies further in; that shortfall is measured on the plate's
//! interior and added (`Thinning`). A strip whose points never stop sees
//! no edge, as a scan line whose walk leaves the band still on the plane
//! does. The strips cover every on-plane point of the band, so they too
//! reach the plate's corners, but only to a strip's width, and where the
//! cloud's border cuts the band a strip sees part of the plate and misses
//! or mistakes its end;
//! [`rim_refined_extent`] reads the ends again from the plate's last rows
//! along the fitted edge.

use crate::cloud::{PointCloud, is_valid_point};
use crate::geometry::fit::Plane;

use super::context::CameraGrid;
use super::gather::gather_filter_map;
use super::refit::SeamCurve;
use crate::geometry::{MAD_PER_SIGMA, Vec3, extent, vec3};

/// One sample of a plate's boundary: a point on the plate's plane and its
/// coordinate along the coarse edge.
#[derive(Debug, Clone, Copy)]
pub struct BoundarySample {
    pub position: Vec3,
    pub along: f64,
}

/// The coarse edge to refine and the plate it belongs to.
#[derive(Debug, Clone, Copy)]
pub struct CoarseEdge {
    pub point: Vec3,
    /// Unit direction along the edge.
    pub direction: Vec3,
    /// Unit vector in the plate's plane, across the edge, pointing out of
    /// the plate (towards the weld).
    pub outward: Vec3,
}

/// Settings of the walk.
#[derive(Debug, Clone, Copy)]
pub struct BoundaryParams {
    /// Half-width of the band around the coarse edge searched, mm.
    pub band_mm: f64,
    /// A pixel is on the plate when within this distance of its plane.
    pub on_plane_mm: f64,
}

struct Walker<'a> {
    cloud: &'a PointCloud,
    plane: &'a Plane,
    edge: &'a CoarseEdge,
    params: &'a BoundaryParams,
    /// Walk along columns (true) or rows, and in which sense.
    along_cols: bool,
    sense: isize,
}

impl Walker<'_> {
    fn index(&self, scanline: usize, k: isize) -> Option<usize> {
        let (w, h) = (self.cloud.width() as isize, self.cloud.height() as isize);
        let (col, row) = if self.along_cols { (k, scanline as isize) } else { (scanline as isize, k) };
        (col >= 0 && row >= 0 && col < w && row < h).then(|| (row * w + col) as usize)
    }

    fn outward_of(&self, p: &Vec3) -> f64 {
        (p - self.edge.point).dot(&self.edge.outward)
    }

    fn on_plate(&self, i: usize) -> Option<Vec3> {
        let p = self.cloud.points()[i];
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(&p);
        (self.plane.signed_distance(&v).abs() <= self.params.on_plane_mm
            && self.outward_of(&v).abs() <= self.params.band_mm)
            .then_some(v)
    }

    /// Walks outward from position `k` on `scanline` and returns the
    /// boundary sample, or `None` when the walk leaves the image or the
    /// band before the plate ends (no boundary there).
    fn walk(&self, scanline: usize, mut k: isize, mean_step: f64) -> Option<(isize, BoundarySample)> {
        let mut last = self.on_plate(self.index(scanline, k)?)?;
        let mut previous: Option<Vec3> = self.index(scanline, k - self.sense).and_then(|i| self.on_plate(i));
        loop {
            let next_k = k + self.sense;
            let next = self.index(scanline, next_k)?;
            match self.on_plate(next) {
                Some(v) => {
                    previous = Some(last);
                    last = v;
                    k = next_k;
                }
                None => {
                    let p = self.cloud.points()[next];
                    // Still on the plane but outside the band: no edge here.
                    if p[0].is_finite() && self.plane.signed_distance(&vec3(&p)).abs() <= self.params.on_plane_mm {
                        return None;
                    }
                    break;
                }
            }
        }
        let step =
            previous.map(|p| self.outward_of(&last) - self.outward_of(&p)).filter(|s| *s > 0.0).unwrap_or(mean_step);
        let position = self.plane.project(&last) + self.edge.outward * (step / 2.0);
        Some((k, BoundarySample { position, along: (position - self.edge.point).dot(&self.edge.direction) }))
    }
}

/// The boundary samples of one edge.
#[derive(Debug, Clone, Default)]
pub struct Boundary {
    pub samples: Vec<BoundarySample>,
    /// Distance along the edge between neighbouring scan lines, mm. The
    /// plate ends on average half of it beyond the outermost samples.
    pub line_spacing_mm: f64,
    /// Where the samples' extent is read from: all of them, or the longest
    /// unbroken stretch.
    pub extent_rule: ExtentRule,
}

/// Which samples prove how far an edge runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ExtentRule {
    /// Every sample: on a pixel grid each comes from a walk along a scan
    /// line that stayed on the plate, and one the fit later trims (a walk
    /// cut short by a mixed pixel) still proves the plate is there.
    #[default]
    AllSamples,
    /// The longest stretch without [`EXTENT_BREAK_LINES`] strips missing:
    /// without a grid, a lone sample far beyond the rest (a chance hole in
    /// a sparse strip at the cloud's border) proves nothing about the edge.
    LongestStretch,
}

impl Boundary {
    /// The range of `along` the samples cover by [`ExtentRule`], widened
    /// by half a scan line at each end.
    pub fn extent(&self, along: impl Fn(&BoundarySample) -> f64) -> Option<(f64, f64)> {
        let mut at: Vec<f64> = self.samples.iter().map(along).collect();
        at.sort_unstable_by(f64::total_cmp);
        let break_mm = match self.extent_rule {
            ExtentRule::AllSamples => f64::INFINITY,
            ExtentRule::LongestStretch => EXTENT_BREAK_LINES * self.line_spacing_mm,
        };
        let mut best: Option<(usize, f64, f64)> = None;
        for run in at.chunk_by(|a, b| b - a <= break_mm) {
            let (lo, hi) = (run[0], run[run.len() - 1]);
            if best.is_none_or(|(n, _, _)| run.len() > n) {
                best = Some((run.len(), lo, hi));
            }
        }
        best.map(|(_, lo, hi)| (lo - self.line_spacing_mm / 2.0, hi + self.line_spacing_mm / 2.0))
    }
}

/// How many strips without a sample break a weld edge into two stretches
/// ([`ExtentRule::LongestStretch`]). A plate seen at all leaves a sample in
/// nearly every strip; a few missing in a row are a glare spot or a tack
/// weld, more than this a different piece of evidence.
const EXTENT_BREAK_LINES: f64 = 8.0;

/// The fraction of the stretch `[s0, s1]` along the seam that lies within
/// one scan line (or strip) of a boundary sample, with `along` the
/// samples' seam coordinate: 1 where the edge was seen all along, near 0
/// where it was only glimpsed. A seam between edges seen along a small
/// part of it is a guess, whatever its fit says.
pub fn coverage(boundary: &Boundary, along: impl Fn(&BoundarySample) -> f64, s0: f64, s1: f64) -> f64 {
    let step = boundary.line_spacing_mm;
    if !(step > 0.0 && s1 > s0) {
        return 0.0;
    }
    let mut at: Vec<f64> = boundary.samples.iter().map(along).filter(|a| a.is_finite()).collect();
    at.sort_unstable_by(f64::total_cmp);
    // The union of the windows [a - step, a + step], clipped to the stretch.
    let mut covered = 0.0;
    let mut reached = s0;
    for a in at {
        let (lo, hi) = ((a - step).max(reached), (a + step).min(s1));
        if hi > lo {
            covered += hi - lo;
            reached = hi;
        }
    }
    covered / (s1 - s0)
}

/// The members within `band_mm` of `edge` on either side, in their order:
/// all [`sample_boundary`] and [`members_along`] read of a plate. A plate
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
const MEMBERS_PER_CHUNK: usize = 1 << 14;

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

/// How far past a weld edge's end, along the seam, the image border may lie
/// for the end to be taken for the border's: a seam leaving the image at a
/// grazing angle runs this far inside the rim the plane criterion trims
/// along the border.
const MAX_BORDER_REACH_MM: f64 = 40.0;
/// The share of the pixels between an edge's end and the image border,
/// just inside the plate, that must lie on the plate's plane for the plate
/// to be taken to run on to the border.
const MIN_ON_PLATE_TO_BORDER: f64 = 0.8;
/// How far inside the fitted edge those pixels are read, in point spacings
/// (the first inside the image), and how far off the plate's plane a point
/// may lie and still be on it.
const BORDER_INSET_SPACINGS: [f64; 2] = [3.0, 1.0];
const ON_PLATE_MM: f64 = 1.0;

/// A weld edge's extent carried to the image border where the plate runs
/// on to it. The plane criterion trims a plate's rim along the border as
/// along any edge, so the boundary samples stop a rim's depth inside it;
/// where the seam leaves the image at a grazing angle, that depth becomes
/// millimetres along the seam. The end is moved to where the fitted edge
/// leaves the image only when the pixels just inside the plate between the
/// two are seen on the plate's plane: where the plate
/// ends before the border, or the view beyond its end is empty, the end
/// stays.
pub(super) fn reach_image_border(
    cloud: &PointCloud,
    grid: &CameraGrid,
    edge: &SeamCurve,
    plate: &Plane,
    inward: &Vec3,
    spacing_mm: f64,
    (lo, hi): (f64, f64),
) -> (f64, f64) {
    if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
        return (lo, hi);
    }
    let step = 0.5 * spacing_mm;
    let reach = |end: f64, outward: f64| -> f64 {
        let steps = (MAX_BORDER_REACH_MM / step) as usize;
        let Some(exit) = (1..=steps).map(|k| end + outward * k as f64 * step).find(|&s| !grid.in_view(&edge.at(s)))
        else {
            return end;
        };
        // The border lies between the last step in view and `exit`.
        let border = exit - outward * 0.5 * step;
        let insets = BORDER_INSET_SPACINGS.map(|k| k * spacing_mm);
        let (mut seen, mut on_plate) = (0usize, 0usize);
        let mut s = end;
        while (border - s) * outward > 0.0 {
            // Where the plate lies between the edge and the border, the
            // deeper reading may fall outside the image.
            let at = edge.at(s);
            if let Some(i) = insets.iter().find_map(|d| grid.pixel_of(&(at + inward * *d))) {
                seen += 1;
                let q = cloud.points()[i];
                on_plate += usize::from(is_valid_point(&q) && plate.signed_distance(&vec3(&q)).abs() <= ON_PLATE_MM);
            }
            s += outward * step;
        }
        // Where nothing inside the plate is in view, the edge runs along
        // the border itself.
        if on_plate as f64 >= MIN_ON_PLATE_TO_BORDER * seen as f64 { border } else { end }
    };
    (reach(lo, -1.0), reach(hi, 1.0))
}

/// How far inside each weld edge, in point spacings, the plates' surfaces
/// are read beyond the seam's ends: past the rim the plane criterion trims,
/// and at three depths so a streak running along the edge does not hide
/// the plate from all of them.
const SURFACE_INSET_SPACINGS: [f64; 3] = [2.0, 4.0, 6.0];
/// The farthest beyond a seam's end the plates' surfaces are followed, mm.
const MAX_SURFACE_FOLLOW_MM: f64 = 400.0;

/// How far beyond each end of the span `(s0, s1)` both plates' surfaces
/// are seen beside their weld edges, on the camera's grid: the joint goes
/// on there, though its edges were not found (a streak or spatter hiding
/// one edge while the plate is still seen). Each plate is read just inside
/// its fitted edge, on its plane; a break along the weld no longer than
/// [`JOINT_BREAK_SPACINGS`] is crossed, as the coverage report crosses it.
/// Zero where a plate ends with the seam, or the view does.
pub(super) fn surfaces_beyond(
    cloud: &PointCloud,
    grid: &CameraGrid,
    edges: [&SeamCurve; 2],
    planes: [&Plane; 2],
    inwards: [Vec3; 2],
    spacing_mm: f64,
    (s0, s1): (f64, f64),
) -> [f64; 2] {
    if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
        return [0.0; 2];
    }
    let step = 0.5 * spacing_mm;
    let max_break = JOINT_BREAK_SPACINGS * spacing_mm;
    // Plate k's surface just inside its edge at `s`: None out of view.
    let seen = |k: usize, s: f64| -> Option<bool> {
        let inside = inside_edge(cloud, grid, edges[k], planes[k], inwards[k], spacing_mm, s);
        if inside.on_plate { Some(true) } else { (inside.in_view > 0).then_some(false) }
    };
    let follow = |end: f64, outward: f64| -> f64 {
        let mut last_both = 0.0;
        let steps = (MAX_SURFACE_FOLLOW_MM / step) as usize;
        for n in 1..=steps {
            let beyond = n as f64 * step;
            let s = end + outward * beyond;
            match (seen(0, s), seen(1, s)) {
                (Some(true), Some(true)) => last_both = beyond,
                (None, _) | (_, None) => break,
                _ if beyond - last_both > max_break => break,
                _ => {}
            }
        }
        last_both
    };
    [follow(s0, -1.0), follow(s1, 1.0)]
}

/// Whether the cloud, on the camera's grid, shows `plate` not to be beside
/// its fitted edge `edge` anywhere from `from` to `to` along the weld: just
/// inside the edge (`inward`, on the plate's plane, past the rim the plane
/// criterion trims, at [`SURFACE_INSET_SPACINGS`]), no pixel in view sees a
/// point on the plane, at any station half a spacing apart, though the
/// pixels are in view. Along the rest of the edge those pixels see the
/// plate: where they do not, what was taken for its edge is not its edge
/// (the foot of the face of a plate above it, running on past its end).
pub(super) fn plate_unseen_beside(
    cloud: &PointCloud,
    grid: &CameraGrid,
    edge: &SeamCurve,
    plate: &Plane,
    inward: Vec3,
    spacing_mm: f64,
    (from, to): (f64, f64),
) -> bool {
    if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
        return false;
    }
    let step = 0.5 * spacing_mm;
    let stations = ((to - from).abs() / step).floor() as usize;
    let direction = (to - from).signum();
    let mut in_view = 0;
    for n in 1..=stations {
        let inside = inside_edge(cloud, grid, edge, plate, inward, spacing_mm, from + direction * n as f64 * step);
        if inside.on_plate {
            return false;
        }
        in_view += inside.in_view;
    }
    in_view >= MIN_STATIONS_UNSEEN * SURFACE_INSET_SPACINGS.len()
}

/// The fewest stations whose pixels must all be in view before a plate is
/// taken as not beside its edge there: a stretch of a spacing or two is the
/// rim the plane criterion trims.
const MIN_STATIONS_UNSEEN: usize = 4;

/// What the pixels just inside a plate's edge see at one station.
struct InsideEdge {
    /// How many of them are in view.
    in_view: usize,
    /// Whether any sees a point on the plate's plane.
    on_plate: bool,
}

/// The pixels just inside `edge` at `s` along it (`inward`, on `plate`'s
/// plane, past the rim the plane criterion trims, at
/// [`SURFACE_INSET_SPACINGS`]), read on the camera's grid.
fn inside_edge(
    cloud: &PointCloud,
    grid: &CameraGrid,
    edge: &SeamCurve,
    plate: &Plane,
    inward: Vec3,
    spacing_mm: f64,
    s: f64,
) -> InsideEdge {
    let at = edge.at(s);
    let mut inside = InsideEdge { in_view: 0, on_plate: false };
    for d in SURFACE_INSET_SPACINGS.map(|n| n * spacing_mm) {
        if let Some(i) = grid.pixel_of(&(at + inward * d)) {
            inside.in_view += 1;
            let q = cloud.points()[i];
            inside.on_plate |= is_valid_point(&q) && plate.signed_distance(&vec3(&q)).abs() <= ON_PLATE_MM;
        }
    }
    inside
}

/// The longest break along the weld, in point spacings, across which a
/// piece of a plate in its plane is taken for the same plate seen through a
/// narrow gap in the cloud: a streak or a stripe of dropouts a few pixels
/// wide, crossing the weld obliquely.
pub const JOINT_BREAK_SPACINGS: f64 = 12.0;

/// Where a plate is seen along the weld, from where its own cluster is
/// (`own`) and where other pieces in its plane are (`pieces`): the pieces
/// that reach within `max_break` of it, and of each other so joined, are
/// the same plate seen through a narrow gap in the cloud (a streak, a
/// stripe of dropouts); a piece beyond a longer break is the plate on the
/// far side of something hiding the joint (a clamp), another stretch of
/// the joint, not this one.
pub fn joined_extent(own: (f64, f64), pieces: &[(f64, f64)], max_break: f64) -> (f64, f64) {
    let mut pieces: Vec<(f64, f64)> = pieces.to_vec();
    pieces.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut lo, mut hi) = own;
    // Each pass joins what touches the extent so far; a piece joined on
    // one side may bring another within reach, so repeat until none does.
    loop {
        let before = (lo, hi);
        for &(a, b) in &pieces {
            if a <= hi + max_break && b >= lo - max_break {
                (lo, hi) = (lo.min(a), hi.max(b));
            }
        }
        if (lo, hi) == before {
            return (lo, hi);
        }
    }
}

/// How deep, in neighbour radii, the plane criterion trims a plate's rim:
/// a point `d` radii inside a straight edge keeps the part of its disc
/// within the plate, and passes while that part is at least `min_ratio` of
/// a whole disc (Eq. 6's count against the full-plane count). The cap
/// beyond the edge holds `(acos d - d sqrt(1 - d²)) / pi` of the disc;
/// solved for the cap that leaves `min_ratio`.
pub fn rim_trim_radii(min_ratio: f64) -> f64 {
    let cap = |d: f64| (d.acos() - d * (1.0 - d * d).sqrt()) / std::f64::consts::PI;
    let lost = (1.0 - min_ratio).clamp(0.0, 0.5);
    // The cap shrinks from half the disc at d = 0 to nothing at d = 1.
    let (mut near, mut far) = (0.0_f64, 1.0_f64);
    for _ in 0..60 {
        let mid = 0.5 * (near + far);
        if cap(mid) > lost {
            near = mid;
        } else {
            far = mid;
        }
    }
    0.5 * (near + far)
}

/// Samples the boundary of the plate whose member pixels are `members`
/// beside `edge`: all of them, or only those [`band_members`] keeps, which
/// give the same samples. Organized clouds only.
pub fn sample_boundary(
    cloud: &PointCloud,
    members: &[u32],
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
) -> Boundary {
    let points = cloud.points();
    let w = cloud.width();
    let near: Vec<usize> = members
        .iter()
        .map(|&i| i as usize)
        .filter(|&i| (vec3(&points[i]) - edge.point).dot(&edge.outward).abs() <= params.band_mm)
        .collect();
    if near.is_empty() {
        return Boundary::default();
    }
    // Walk along the image axis that crosses the edge most directly.
    let mean_axis_step = |dc: usize, dr: usize| -> f64 {
        let mut sum = 0.0;
        let mut n = 0usize;
        for &i in near.iter().step_by((near.len() / 500).max(1)) {
            let (col, row) = (i % w + dc, i / w + dr);
            if col < w && row < cloud.height() {
                let q = points[row * w + col];
                if q[0].is_finite() {
                    sum += (vec3(&q) - vec3(&points[i])).dot(&edge.outward);
                    n += 1;
                }
            }
        }
        if n == 0 { 0.0 } else { sum / n as f64 }
    };
    let (col_step, row_step) = (mean_axis_step(1, 0), mean_axis_step(0, 1));
    let along_cols = col_step.abs() >= row_step.abs();
    let axis_step = if along_cols { col_step } else { row_step };
    if axis_step == 0.0 {
        return Boundary::default();
    }
    let walker = Walker { cloud, plane, edge, params, along_cols, sense: if axis_step > 0.0 { 1 } else { -1 } };
    let mean_step = axis_step.abs();

    // The outermost member on each scan line starts that line's walk.
    let split = |i: usize| {
        if along_cols { (i / w, (i % w) as isize) } else { (i % w, (i / w) as isize) }
    };
    let mut start: std::collections::BTreeMap<usize, isize> = std::collections::BTreeMap::new();
    for &i in &near {
        let (line, k) = split(i);
        let entry = start.entry(line).or_insert(k);
        if (k - *entry) * walker.sense > 0 {
            *entry = k;
        }
    }
    let mut found: Vec<(usize, isize, BoundarySample)> = Vec::new();
    for (&line, &k) in &start {
        if let Some((end, s)) = walker.walk(line, k, mean_step) {
            found.push((line, end, s));
        }
    }
    extend_past_ends(&walker, &mut found, mean_step);
    found.sort_by_key(|(line, _, _)| *line);
    let line_spacing_mm = median_line_spacing(&found);
    Boundary {
        samples: found.into_iter().map(|(_, _, s)| s).collect(),
        line_spacing_mm,
        extent_rule: ExtentRule::AllSamples,
    }
}

/// Samples the boundary of a plate beside `edge` in a cloud without a
/// pixel grid whose points lie about `spacing_mm` apart. Every valid point
/// on the plate's plane within the band counts, not only the plate's
/// members: the plane criterion has trimmed the outermost ones.
///
/// A strip has a boundary only where its on-plane points, walked outward
/// from the inner side of the band, stop: at the first empty stretch wider
/// than any the plate's interior shows ([`hole_threshold`]), or at the
/// band's outer side. A strip whose points run on through the band has
/// none: the plate goes on there (a lap's lower plate beyond the upper
/// plate's end), or a coplanar plate lies across a gap too narrow for this
/// cloud to show. Either way no edge is seen there, and none is invented.
pub fn sample_scattered(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    scatter_mm: Option<f64>,
) -> Boundary {
    use rayon::prelude::*;

    if !(spacing_mm.is_finite() && spacing_mm > 0.0) {
        return Boundary::default();
    }
    // Two spacings: a strip one spacing wide misses the boundary row's
    // point about as often as it holds it, and its outermost point is then
    // a row in; at two the row is nearly always there.
    let strip_mm = STRIP_SPACINGS * spacing_mm;
    let points = cloud.points();
    let mut in_band: Vec<BandPoint> = gather_filter_map(points, |i, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        let d = v - edge.point;
        let out = d.dot(&edge.outward);
        let on_plane = plane.signed_distance(&v).abs() <= params.on_plane_mm;
        (on_plane && out.abs() <= params.band_mm).then(|| BandPoint {
            strip: strip_of(d.dot(&edge.direction), strip_mm),
            out,
            index: i as u32,
        })
    });
    // Strip by strip, each walked outward; the index settles a tie, so the
    // order does not depend on the sort.
    in_band
        .par_sort_unstable_by(|a, b| a.strip.cmp(&b.strip).then(a.out.total_cmp(&b.out)).then(a.index.cmp(&b.index)));
    let strips = || in_band.chunk_by(|a, b| a.strip == b.strip);
    let point = |b: &BandPoint| vec3(&points[b.index as usize]);
    let hole_mm = hole_threshold(strips(), params.band_mm, spacing_mm);
    let thinning = Thinning::measure(cloud, plane, edge, params, strip_mm, scatter_mm, strips());
    let samples = strips()
        .filter_map(|strip| {
            let last = strip_boundary(strip, hole_mm, params.band_mm)?;
            let (last_out, last_point) = (strip[last].out, point(&strip[last]));
            // The k points of the strip's last row (within half a spacing
            // of the outermost) split the spacing beyond the row into k + 1
            // gaps on average: the plate ends one gap beyond the outermost.
            let row = strip[..=last].iter().filter(|b| b.out >= last_out - spacing_mm / 2.0).count();
            let beyond = spacing_mm / (row + 1) as f64 + thinning.shortfall_mm(strip[last].strip);
            let position = plane.project(&last_point) + edge.outward * beyond;
            // The walk may end on a point past the plate's end along the
            // edge, where only the foot of a steep face grazes the plane
            // (a lap's upper plate running on beyond the lower plate): it
            // lies on the edge's line, so it places the edge across
            // rightly, but not where the plate is. The strip's points
            // inside the coarse edge are the plate's, and bound the
            // sample along the edge.
            let along = |p: &Vec3| (p - edge.point).dot(&edge.direction);
            let (lo, hi) = extent(strip[..=last].iter().filter(|b| b.out <= 0.0).map(|b| along(&point(b))));
            let shift = along(&position).clamp(lo, hi) - along(&position);
            let position = position + edge.direction * shift;
            Some(BoundarySample { position, along: along(&position) })
        })
        .collect();
    Boundary { samples, line_spacing_mm: strip_mm, extent_rule: ExtentRule::LongestStretch }
}

/// How far off its plane, in sigmas of its own scatter about it, a point
/// of a plate without a pixel grid still counts as on it
/// ([`on_plane_for_scatter`]): 2.5 keeps 98.8 % of a plate's points under
/// normal noise.
const ON_PLANE_SIGMAS: f64 = 2.5;

/// The fewest points of a band's inner third [`plane_scatter`] measures
/// a sigma from.
const MIN_SCATTER_POINTS: usize = 30;

/// How far off a plate's plane, in point spacings (or on-plane
/// tolerances, where larger), [`plane_scatter`] first reads its points:
/// wider than any camera's depth noise at its own spacing, narrower than
/// the step to another surface.
const SCATTER_WINDOW_SPACINGS: f64 = 3.0;

/// How far the points of a plate scatter about its plane, one sigma (mm),
/// measured in a cloud without a pixel grid whose points lie about
/// `spacing_mm` apart, on the points of the inner third of the band beside
/// `edge` (a robust sigma: the median absolute distance over that of
/// normal noise), from the points within [`SCATTER_WINDOW_SPACINGS`] of
/// the plane and again within four of the sigmas found. The inner third
/// lies well inside the plate whatever the coarse edge's error, so the
/// lower plate of a lap, a groove's bevel or a web standing beside it do
/// not enter. `None` below [`MIN_SCATTER_POINTS`] points.
pub fn plane_scatter(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
) -> Option<f64> {
    let window_mm = SCATTER_WINDOW_SPACINGS * spacing_mm.max(params.on_plane_mm);
    let inner = -params.band_mm..=-params.band_mm / 3.0;
    let distances: Vec<f64> = gather_filter_map(cloud.points(), |_, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        let d = plane.signed_distance(&v);
        (d.abs() <= window_mm && inner.contains(&(v - edge.point).dot(&edge.outward))).then_some(d.abs())
    });
    let sigma_within = |window: f64| {
        let mut within: Vec<f64> = distances.iter().copied().filter(|d| *d <= window).collect();
        if within.len() < MIN_SCATTER_POINTS {
            return None;
        }
        let mid = within.len() / 2;
        Some(*within.select_nth_unstable_by(mid, f64::total_cmp).1 / MAD_PER_SIGMA)
    };
    let first = sigma_within(window_mm)?;
    // A window much wider than the noise takes in more than the plate's
    // points; one much narrower cuts its tails and reads too small a sigma.
    sigma_within((4.0 * first).min(window_mm)).or(Some(first))
}

/// The on-plane tolerance for a plate whose points scatter `sigma_mm`
/// about its plane: the configured one, or [`ON_PLANE_SIGMAS`] sigmas
/// where the noise is larger. A tolerance a camera's noise exceeds keeps a
/// fraction of the plate's points, the strips' outermost kept point then
/// lies rows inside the plate's end, and the edge is read inside the plate
/// (by about 0.5 sigma² mm at a consumer camera's 1 mm voxels: 0.9 mm at
/// 1.3 mm of depth noise).
fn on_plane_for_scatter(configured_mm: f64, sigma_mm: Option<f64>) -> f64 {
    sigma_mm.map_or(configured_mm, |s| configured_mm.max(ON_PLANE_SIGMAS * s))
}

/// How far further inside a plate's end its strips' outermost on-plane
/// point lies because the on-plane tolerance keeps only a fraction of its
/// points ([`sample_scattered`]), strip by strip.
///
/// The plate ends, on average, as far beyond its outermost point as a
/// position taken at random inside the plate lies beyond the nearest
/// point on its inner side: for gaps g between consecutive points across
/// a strip, Σg² / 2Σg (half a pitch for rows at a fixed pitch, one mean
/// gap for points strewn at random). The difference between that mean for
/// the on-plane points and for all of the plate's points (within
/// [`ON_PLANE_SIGMAS`] of its measured noise) is what the tolerance's
/// thinning adds to the gap at the end; the row rule of
/// [`sample_scattered`] accounts for the rest. Both are read from the
/// band's inner third, where nothing but the plate lies near its plane
/// (not a groove's bevel, which the wider tolerance would take for the
/// plate beyond its edge), and pooled over [`THINNING_POOL_STRIPS`] strips
/// either side, since the noise changes with depth along the edge.
struct Thinning {
    /// Per strip with points in the inner third, ascending: the strip and
    /// the running sums, from the first strip through this one, of Σg and
    /// Σg² over the on-plane points' gaps and over all the plate's points'.
    running: Vec<(i32, [f64; 4])>,
}

/// How many strips either side of a strip [`Thinning`] pools its gaps
/// over: ten spacings along the edge, over which the noise hardly changes.
const THINNING_POOL_STRIPS: i32 = 5;

impl Thinning {
    /// None where the plate's noise is within the tolerance (every point
    /// of the plate is on its plane), or unknown.
    fn none() -> Self {
        Thinning { running: Vec::new() }
    }

    fn measure<'a>(
        cloud: &PointCloud,
        plane: &Plane,
        edge: &CoarseEdge,
        params: &BoundaryParams,
        strip_mm: f64,
        scatter_mm: Option<f64>,
        on_plane: impl Iterator<Item = &'a [BandPoint]>,
    ) -> Self {
        let all_mm = on_plane_for_scatter(params.on_plane_mm, scatter_mm);
        if all_mm <= params.on_plane_mm {
            return Thinning::none();
        }
        let inner = -params.band_mm..=-params.band_mm / 3.0;
        let mut all: Vec<(i32, f64)> = gather_filter_map(cloud.points(), |_, p| {
            if !p[0].is_finite() {
                return None;
            }
            let v = vec3(p);
            let d = v - edge.point;
            let out = d.dot(&edge.outward);
            let near_plane = plane.signed_distance(&v).abs() <= all_mm;
            (near_plane && inner.contains(&out)).then(|| (strip_of(d.dot(&edge.direction), strip_mm), out))
        });
        all.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut per_strip: std::collections::BTreeMap<i32, [f64; 4]> = std::collections::BTreeMap::new();
        for strip in on_plane {
            let [s1, s2] = gap_sums(strip.iter().map(|b| b.out).filter(|out| inner.contains(out)));
            let entry = per_strip.entry(strip[0].strip).or_default();
            (entry[0], entry[1]) = (s1, s2);
        }
        for strip in all.chunk_by(|a, b| a.0 == b.0) {
            let [s1, s2] = gap_sums(strip.iter().map(|a| a.1));
            let entry = per_strip.entry(strip[0].0).or_default();
            (entry[2], entry[3]) = (s1, s2);
        }
        let mut total = [0.0; 4];
        let running = per_strip
            .into_iter()
            .map(|(strip, sums)| {
                for (t, s) in total.iter_mut().zip(sums) {
                    *t += s;
                }
                (strip, total)
            })
            .collect();
        Thinning { running }
    }

    /// How much further in than the row rule says strip `strip`'s
    /// outermost on-plane point lies, mm; zero where nothing was thinned.
    fn shortfall_mm(&self, strip: i32) -> f64 {
        let upto = |s: i32| {
            let n = self.running.partition_point(|(k, _)| *k <= s);
            n.checked_sub(1).map_or([0.0; 4], |i| self.running[i].1)
        };
        let (hi, lo) =
            (upto(strip.saturating_add(THINNING_POOL_STRIPS)), upto(strip.saturating_sub(THINNING_POOL_STRIPS + 1)));
        let sums: [f64; 4] = std::array::from_fn(|i| hi[i] - lo[i]);
        let empty_space = |s1: f64, s2: f64| (s1 > 0.0).then(|| s2 / (2.0 * s1));
        match (empty_space(sums[0], sums[1]), empty_space(sums[2], sums[3])) {
            (Some(on_plane), Some(all)) => (on_plane - all).max(0.0),
            _ => 0.0,
        }
    }
}

/// Σg and Σg² over the gaps g between consecutive values of `outs`
/// (ascending).
fn gap_sums(outs: impl Iterator<Item = f64>) -> [f64; 2] {
    let mut previous: Option<f64> = None;
    let mut sums = [0.0; 2];
    for out in outs {
        if let Some(before) = previous {
            let gap = out - before;
            sums[0] += gap;
            sums[1] += gap * gap;
        }
        previous = Some(out);
    }
    sums
}

/// Refines the ends of a weld edge's extent `(lo, hi)`, read from strips
/// to a strip's width, where the cloud's border cuts the plate, in a cloud
/// without a pixel grid, in the camera frame. `edge` is a line fitted to
/// the boundary samples, `edge_rms_mm` its fit's RMS; `along` gives the
/// coordinate the extent is in.
///
/// Where the image border or a crop cuts the band beside the weld, a
/// strip sees part of the plate only and either misses the edge (the
/// seam stops short) or takes the border for it (the seam runs on). The
/// rows between half a spacing and a spacing and a half inside the edge
/// ([`RIM_ROWS_SPACINGS`]) run wherever the plate runs beside the weld,
/// and nothing beyond the edge (another plate, the foot of a face grazing
/// the plane) lies in them. Each end walks along the rim's on-plane
/// points from a point well inside the strips' extent for as long as they
/// follow one another within [`RIM_BREAK_SPACINGS`] (or the rim's own
/// steps), and across a stretch the rows miss where the plate is seen on
/// both sides of them ([`RimBands::reach`]); the plate ends half a spacing
/// beyond the last point.
///
/// The rim's end is taken only where the cloud itself ends there: where
/// no point of any depth, carried along its line of sight onto the
/// plate's plane, lies in the rows beyond it ([`RIM_AT_BORDER_SPACINGS`]).
/// Elsewhere the table or a shadow lies beyond a plate's own end, and the
/// strips read that end. A rim that stops more than a spacing short of
/// the rows' last points moves an end in only where the strips run past
/// all of them. Where the edge's fit scatters too much to place the rows
/// ([`MAX_RIM_EDGE_RMS_SPACINGS`]), the extent stays.
#[allow(clippy::too_many_arguments)]
pub fn rim_refined_extent(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    edge_rms_mm: f64,
    along: impl Fn(&Vec3) -> f64 + Sync,
    (lo, hi): (f64, f64),
) -> (f64, f64) {
    // The rows keep half a spacing clear of the fitted edge: an edge whose
    // samples scatter by more than a quarter spacing (two RMS past the
    // clearance) wanders in and out of them, and its rim says nothing.
    let known = edge_rms_mm <= MAX_RIM_EDGE_RMS_SPACINGS * spacing_mm;
    if !(spacing_mm.is_finite() && spacing_mm > 0.0 && known) {
        return (lo, hi);
    }
    let inside = RIM_START_STRIPS * STRIP_SPACINGS * spacing_mm;
    if hi - lo <= 2.0 * inside {
        return (lo, hi);
    }
    let [inner, outer] = RIM_ROWS_SPACINGS.map(|rows| -rows * spacing_mm);
    let beside = RIM_BESIDE_SPACINGS * spacing_mm;
    let offset = |q: &Vec3| (q - edge.point).dot(&edge.outward);
    // Every on-plane point of the rows and of the bands beside them, and
    // every other point whose line of sight crosses the plate's plane in
    // the rows (the plane n·x = offset meets the line of sight t v at
    // t = offset / n·v), by where it lies along the edge.
    let classified: Vec<(f64, RimBand)> = gather_filter_map(cloud.points(), |_, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        if plane.signed_distance(&v).abs() <= params.on_plane_mm {
            let band = RimBand::of(offset(&v), [inner, outer], beside)?;
            return Some((along(&v), band));
        }
        let t = plane.offset / plane.normal.dot(&v);
        let q = v * t;
        let crosses = t.is_finite() && t > 0.0 && (outer..=inner).contains(&offset(&q));
        crosses.then(|| (along(&q), RimBand::SightLine))
    });
    let sorted = |wanted: RimBand| {
        let mut at: Vec<f64> = classified.iter().filter(|c| c.1 == wanted).map(|c| c.0).collect();
        at.sort_unstable_by(f64::total_cmp);
        at
    };
    let [rim, near, deep] = [RimBand::Rows, RimBand::Near, RimBand::Deep].map(sorted);
    // The rows' extent as the cloud shows it, whatever lies in them.
    let in_view = classified.iter().filter(|c| matches!(c.1, RimBand::Rows | RimBand::SightLine)).map(|c| c.0);
    let (view_lo, view_hi) = extent(in_view);
    if rim.is_empty() {
        return (lo, hi);
    }
    // A tilted plate's voxel centroids, or a camera's anisotropic grid,
    // leave wider steps along the rim than the mean spacing says: the
    // rim's own steps set the break, as the plate's do for the strips.
    let typical = percentile_99(rim.windows(2).map(|w| w[1] - w[0])).unwrap_or(0.0);
    let break_mm = (RIM_BREAK_SPACINGS * spacing_mm).max(HOLE_OVER_INTERIOR * typical);
    let half = spacing_mm / 2.0;
    let border_mm = RIM_AT_BORDER_SPACINGS * spacing_mm;
    let bands = RimBands { rim: &rim, near: &near, deep: &deep, break_mm };
    // A rim that runs to within a spacing of the rows' last points has
    // seen the plate go on until the cloud ends. One that stops further
    // short, with points off the plane beyond it in the rows, may have
    // lost the plate's last points to noise rather than seen its end: it
    // moves an end in only where the strips read past everything the rows
    // show by more than a strip (their extent adds half of one), taking
    // the border for the edge.
    let strip_mm = STRIP_SPACINGS * spacing_mm;
    let end = match rim.iter().rposition(|&a| a <= hi - inside) {
        Some(from) => {
            let rim_end = bands.reach(rim[from], Sense::Up);
            let at_border = view_hi - rim_end <= border_mm;
            let (refined, kept) = (rim_end + half, hi);
            let trusted = refined >= kept || view_hi - rim_end <= spacing_mm || kept > view_hi + strip_mm;
            if at_border && trusted { refined } else { kept }
        }
        None => hi,
    };
    let start = match rim.iter().position(|&a| a >= lo + inside) {
        Some(from) => {
            let rim_start = bands.reach(rim[from], Sense::Down);
            let at_border = rim_start - view_lo <= border_mm;
            let (refined, kept) = (rim_start - half, lo);
            let trusted = refined <= kept || rim_start - view_lo <= spacing_mm || kept < view_lo - strip_mm;
            if at_border && trusted { refined } else { kept }
        }
        None => lo,
    };
    (start, end)
}

/// The plate's on-plane points in its rim (the rows [`rim_refined_extent`]
/// follows and the band as wide again deeper in: half a spacing to two
/// and a half inside the fitted `edge`, clear of whatever lies beyond
/// it) within `near_mm` along the edge of either end of `(lo, hi)`, as
/// `along` reads a point: where the plate's last rows run at each end of
/// its edge, to tell whether the image's border cut them there.
#[allow(clippy::too_many_arguments)]
pub fn rim_points_at_ends(
    cloud: &PointCloud,
    plane: &Plane,
    edge: &CoarseEdge,
    params: &BoundaryParams,
    spacing_mm: f64,
    along: impl Fn(&Vec3) -> f64 + Sync,
    (lo, hi): (f64, f64),
    near_mm: f64,
) -> Vec<Vec3> {
    let [inner, outer] = RIM_ROWS_SPACINGS.map(|rows| -rows * spacing_mm);
    let rim = (outer - RIM_BESIDE_SPACINGS * spacing_mm)..=inner;
    gather_filter_map(cloud.points(), |_, p| {
        if !p[0].is_finite() {
            return None;
        }
        let v = vec3(p);
        let at = along(&v);
        let at_an_end = (at - lo).abs() <= near_mm || (at - hi).abs() <= near_mm;
        let in_rim = || rim.contains(&(v - edge.point).dot(&edge.outward));
        (at_an_end && plane.signed_distance(&v).abs() <= params.on_plane_mm && in_rim()).then_some(v)
    })
}

/// Where a point read by [`rim_refined_extent`] lies across the edge. (Its
/// default only fills the slots of a gathered vector before they are
/// written.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum RimBand {
    /// On the plate's plane, in the rows the rim follows.
    #[default]
    Rows,
    /// On the plane, between the rows and the fitted edge.
    Near,
    /// On the plane, deeper into the plate than the rows.
    Deep,
    /// Off the plane, its line of sight crossing the plane in the rows.
    SightLine,
}

impl RimBand {
    /// The band of an on-plane point `offset` mm outward of the fitted
    /// edge, with the rows `[inner, outer]` (both negative, inside the
    /// plate) and bands `beside` mm wide on either side of them.
    fn of(offset: f64, [inner, outer]: [f64; 2], beside: f64) -> Option<Self> {
        if (outer..=inner).contains(&offset) {
            Some(Self::Rows)
        } else if (inner..=(inner + beside).min(0.0)).contains(&offset) {
            Some(Self::Near)
        } else if ((outer - beside)..outer).contains(&offset) {
            Some(Self::Deep)
        } else {
            None
        }
    }
}

/// Which way along the edge a rim walk goes.
#[derive(Debug, Clone, Copy)]
enum Sense {
    Up,
    Down,
}

impl Sense {
    /// The nearer of two positions to where a walk this way started.
    fn nearer(self, a: f64, b: f64) -> f64 {
        match self {
            Sense::Up => a.min(b),
            Sense::Down => a.max(b),
        }
    }

    /// Whether `a` lies beyond `b`, going this way.
    fn beyond(self, a: f64, b: f64) -> bool {
        match self {
            Sense::Up => a > b,
            Sense::Down => a < b,
        }
    }
}

/// The along-edge positions (sorted) of the on-plane points of the rim's
/// rows and of the bands beside them, and the widest step that continues
/// a walk.
struct RimBands<'a> {
    rim: &'a [f64],
    near: &'a [f64],
    deep: &'a [f64],
    break_mm: f64,
}

impl RimBands<'_> {
    /// How far the plate runs beside the weld from `from`, a point of the
    /// rows, in `sense`. The rows are one point spacing wide, and the rows
    /// of a lattice (voxel centroids) can run along them a little further
    /// apart than that: where the last lattice row leaves them and the
    /// next has not yet come in, the rows hold no point for a stretch
    /// although the plate goes on. Such a stretch has the plate on both
    /// sides of the rows, nearer the edge and deeper in; where a border
    /// cuts the plate obliquely, or the plate ends, one side stops with
    /// the rows. So the walk follows the rows, then goes on as far as both
    /// bands beside them go on together, and from there along the rows
    /// again.
    fn reach(&self, from: f64, sense: Sense) -> f64 {
        let mut at = from;
        // Each round moves `at` on to a further point, so the rounds are
        // at most the points there are.
        for _ in 0..=self.rim.len() + self.near.len() + self.deep.len() {
            let along_rows = walk(self.rim, at, self.break_mm, sense);
            let [near, deep] = [self.near, self.deep].map(|band| walk(band, along_rows, self.break_mm, sense));
            let bracketed = sense.nearer(near, deep);
            if !sense.beyond(bracketed, along_rows) {
                return along_rows;
            }
            at = bracketed;
        }
        at
    }
}

/// The furthest of the sorted positions `at` reached from `from` in
/// `sense` by steps of at most `break_mm`; `from` when none is.
fn walk(at: &[f64], from: f64, break_mm: f64, sense: Sense) -> f64 {
    let mut reached = from;
    match sense {
        Sense::Up => {
            for &a in &at[at.partition_point(|&a| a <= from)..] {
                if a - reached > break_mm {
                    break;
                }
                reached = a;
            }
        }
        Sense::Down => {
            for &a in at[..at.partition_point(|&a| a < from)].iter().rev() {
                if reached - a > break_mm {
                    break;
                }
                reached = a;
            }
        }
    }
    reached
}

/// How close to the cloud's end along the rim's rows, in point spacings,
/// the rim must run for [`rim_refined_extent`] to take the plate's end
/// from it: where the cloud ends, the rim ends within a step or two of
/// the last point of any depth in its rows.
const RIM_AT_BORDER_SPACINGS: f64 = 3.0;

/// The largest RMS of an edge's fit, in point spacings, for which
/// [`rim_refined_extent`] reads its rim: two RMS within the rows' half a
/// spacing of clearance. A noisy cloud's edge (a consumer camera's at
/// 400 mm and beyond) keeps the strips' ends.
const MAX_RIM_EDGE_RMS_SPACINGS: f64 = 0.25;

/// The rows [`rim_refined_extent`] follows, as offsets inside a fitted
/// edge in point spacings: the plate's last row lies within a spacing of
/// its end, so this band of one spacing holds a point about every spacing
/// along the plate, and is half a spacing clear of the edge, where the
/// foot of a face or the noise of the edge's fit could put points.
const RIM_ROWS_SPACINGS: [f64; 2] = [0.5, 1.5];

/// The width, in point spacings, of the bands on either side of the rim's
/// rows that show the plate going on where the rows hold no point
/// ([`RimBands::reach`]): the one nearer the edge is the half spacing the
/// rows keep clear of it, the deeper one as wide as the rows.
const RIM_BESIDE_SPACINGS: f64 = 1.0;

/// The widest step along the rim, in point spacings, that still continues
/// it: a point every spacing on average, so three is a dropout or two.
const RIM_BREAK_SPACINGS: f64 = 3.0;

/// How far inside the strips' extent, in strips, a rim walk starts: the
/// strips read each end to about one strip.
const RIM_START_STRIPS: f64 = 2.0;

/// The width of [`sample_scattered`]'s strips, in point spacings.
const STRIP_SPACINGS: f64 = 2.0;

/// The narrowest empty stretch across a strip taken for the plate's end,
/// in point spacings: rows lie about one spacing apart, so a stretch half
/// as wide again is already rare inside a plate.
const MIN_HOLE_SPACINGS: f64 = 1.5;

/// How much wider than the plate interior's widest common stretch (its
/// 99th percentile) an empty stretch must be to end the plate.
const HOLE_OVER_INTERIOR: f64 = 1.25;

/// The empty stretch across a strip that ends a plate, mm: measured on the
/// cloud itself, from the gaps between consecutive points in the inner
/// third of the band (well inside the plate, whatever the coarse edge's
/// error), and never under [`MIN_HOLE_SPACINGS`] spacings. Voxel centroids
/// of a tilted plate, or a camera's anisotropic grid, leave wider gaps
/// than the mean spacing says; this keeps them from ending the plate.
fn hole_threshold<'a>(strips: impl Iterator<Item = &'a [BandPoint]> + Clone, band_mm: f64, spacing_mm: f64) -> f64 {
    let inner = -band_mm / 3.0;
    let gaps =
        strips.flat_map(|strip| strip.windows(2).filter(move |w| w[1].out <= inner).map(|w| w[1].out - w[0].out));
    let floor = MIN_HOLE_SPACINGS * spacing_mm;
    percentile_99(gaps).map_or(floor, |q99| floor.max(HOLE_OVER_INTERIOR * q99))
}

/// The 99th percentile of `values`, the value a sort puts at rank
/// ⌊0.99 n⌋ (the last for fewer than a hundred); `None` when there are
/// none. The values are read twice, counted and then scanned keeping the
/// largest hundredth, so a band's thousands of gaps are never held.
fn percentile_99(values: impl Iterator<Item = f64> + Clone) -> Option<f64> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    let n = values.clone().count();
    let rank = (n * 99 / 100).min(n.checked_sub(1)?);
    // The values from the rank up: the rank's is the least of them.
    let kept = n - rank;
    let mut largest = BinaryHeap::with_capacity(kept + 1);
    for v in values {
        largest.push(Reverse(TotalOrder(v)));
        if largest.len() > kept {
            largest.pop();
        }
    }
    largest.peek().map(|Reverse(TotalOrder(v))| *v)
}

/// An `f64` ordered by [`f64::total_cmp`].
#[derive(Debug, Clone, Copy)]
struct TotalOrder(f64);

impl PartialEq for TotalOrder {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other).is_eq()
    }
}

impl Eq for TotalOrder {}

impl PartialOrd for TotalOrder {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for TotalOrder {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The index of a strip's last point before the plate ends, walking
/// outward from the band's inner side; `None` when the points run on to
/// the band's outer side (no end seen), or when they start outside the
/// coarse edge. The coarse edge runs through the plate's edge points, a
/// little inside the plate, so a run that starts inside it is the plate's;
/// one that starts outside lies past the plate's end: another plate's
/// points, or the foot of a steep face (a lap's upper plate beyond the
/// lower plate's end) whose lowest points graze the plane. Where the image
/// border cuts the band this also drops the strips that see only the
/// plate's outer rim, and the seam stops up to a millimetre or two short
/// of the border: short, never beyond. `strip` is sorted by outward offset.
fn strip_boundary(strip: &[BandPoint], hole_mm: f64, band_mm: f64) -> Option<usize> {
    if strip.first()?.out > 0.0 {
        return None;
    }
    strip.windows(2).position(|w| w[1].out - w[0].out > hole_mm).or_else(|| {
        let last = strip.len() - 1;
        (band_mm - strip[last].out > hole_mm).then_some(last)
    })
}

/// The strip `along_mm` along an edge falls in, for strips `strip_mm`
/// wide. A cloud spans a few thousand strips; clamping could only join
/// strips far past any plate.
fn strip_of(along_mm: f64, strip_mm: f64) -> i32 {
    crate::geometry::floor_i64(along_mm / strip_mm).clamp(i32::MIN.into(), i32::MAX.into()) as i32
}

/// An on-plane point of the band beside an edge in a cloud without a
/// pixel grid ([`sample_scattered`]): the strip along the edge it falls
/// in, its offset outward across the edge, and its index in the cloud,
/// which gives the point itself when a strip's sample needs it (16 bytes,
/// where the strip, the offset and the point took 40).
#[derive(Debug, Clone, Copy, Default)]
struct BandPoint {
    out: f64,
    strip: i32,
    index: u32,
}

/// The median distance along the edge from one scan line's sample to the
/// next line's, per line. `found` is sorted by line.
fn median_line_spacing(found: &[(usize, isize, BoundarySample)]) -> f64 {
    let mut steps: Vec<f64> = found
        .windows(2)
        .filter(|w| w[1].0 > w[0].0)
        .map(|w| (w[1].2.along - w[0].2.along).abs() / (w[1].0 - w[0].0) as f64)
        .collect();
    if steps.is_empty() {
        return 0.0;
    }
    let mid = steps.len() / 2;
    *steps.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Continues sampling on the scan lines beyond the first and last sampled
/// ones, each walk starting a few pixels inside the previous line's
/// boundary pixel, for as long as the plate is there. The plane criterion
/// trims about R off a plate's corners, so without this the seam would
/// stop short of the plate ends. `found` holds (line, boundary pixel,
/// sample).
fn extend_past_ends(walker: &Walker, found: &mut Vec<(usize, isize, BoundarySample)>, mean_step: f64) {
    if found.is_empty() {
        return;
    }
    found.sort_by_key(|(line, _, _)| *line);
    let lines = if walker.along_cols { walker.cloud.height() } else { walker.cloud.width() };
    // Both ends are fixed before extending: extension appends to `found`.
    let ends =
        [(-1isize, found[0].0 as isize, found[0].1), (1, found[found.len() - 1].0 as isize, found[found.len() - 1].1)];
    const MAX_EXTENSION_LINES: usize = 40;
    for (direction, mut line, mut boundary) in ends {
        for _ in 0..MAX_EXTENSION_LINES {
            line += direction;
            if line < 0 || line as usize >= lines {
                break;
            }
            let walked =
                (1..8).find_map(|inset| walker.walk(line as usize, boundary - inset * walker.sense, mean_step));
            match walked {
                Some((end, s)) => {
                    found.push((line as usize, end, s));
                    boundary = end;
                }
                None => break,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::camera::CameraModel;
    use nalgebra::Vector2;

    #[test]
    fn a_plate_is_seen_beside_an_edge_along_the_stretch_its_points_reach() {
        // Points on a 1 mm grid beside an edge along x at y = 0 (outward
        // +y), from x = 10 to 40 and 3 to 6 mm out; others farther out,
        // behind the edge, or past its span.
        let mut points: Vec<crate::cloud::Point> = Vec::new();
        for x in 0..60 {
            for y in -5..20 {
                points.push([x as f32 + 0.5, y as f32 + 0.5, 600.0]);
            }
        }
        let members: Vec<u32> = (0..points.len() as u32)
            .filter(|&i| {
                let [x, y, _] = points[i as usize];
                ((10.0..40.0).contains(&x) && (3.0..6.0).contains(&y)) || !(0.0..=12.0).contains(&y)
            })
            .collect();
        let cloud = PointCloud::unorganized(points);
        let edge = CoarseEdge { point: Vec3::new(0.0, 0.0, 600.0), direction: Vec3::x(), outward: Vec3::y() };
        let spanned = SpannedEdge { edge, span: [0.0, 50.0] };
        let seen = stretch_seen_beside(&cloud, &[&members], &[spanned], [8.0, 2.0, 1.0]);
        assert_eq!(seen, vec![30.0]);
        // None within a band too narrow to reach them.
        assert_eq!(stretch_seen_beside(&cloud, &[&members], &[spanned], [2.0, 2.0, 1.0]), vec![0.0]);
    }

    /// Slope of the test edge: slanted so the rows see every sub-pixel phase.
    const SLOPE: f64 = 0.1;

    /// A frontal plate at 700 mm whose edge is the line x = `edge_x` + SLOPE y,
    /// ending at y = `end_y`; beyond it the table 40 mm further away.
    fn frame(edge_x: f64, end_y: f64) -> (PointCloud, Vec<u32>) {
        let camera = CameraModel::default();
        let (w, h) = (80, 80);
        let mut pts = Vec::new();
        let mut members = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let r = camera.ray(camera.cx() - 40.0 + col as f64, camera.cy() - 40.0 + row as f64);
                let (x, y) = (r[0] * 700.0, r[1] * 700.0);
                let on_plate = x < edge_x + SLOPE * y && y < end_y;
                let z = if on_plate { 700.0 } else { 740.0 };
                // Members are the plate minus an eroded 1 mm band, as the plane criterion leaves it.
                if on_plate && x < edge_x + SLOPE * y - 1.0 && y < end_y - 1.0 {
                    members.push((row * w + col) as u32);
                }
                pts.push([(r[0] * z) as f32, (r[1] * z) as f32, z as f32]);
            }
        }
        (PointCloud::organized(w, h, pts).unwrap(), members)
    }

    #[test]
    fn samples_lie_on_the_true_edge_within_a_quarter_pixel() {
        let edge_x = 3.1;
        let (cloud, members) = frame(edge_x, 1e9);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(edge_x - 1.2, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
        let samples = sample_boundary(&cloud, &members, &plane, &edge, &params).samples;
        assert_eq!(samples.len(), 80);
        let pixel = 700.0 / CameraModel::default().fx();
        // Signed distance of each sample from the true edge line, across it.
        let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x;
        let mean = samples.iter().map(|s| offset(&s.position)).sum::<f64>() / samples.len() as f64;
        let worst = samples.iter().map(|s| offset(&s.position).abs()).fold(0.0, f64::max);
        assert!(mean.abs() < 0.1 * pixel, "mean offset {mean} mm");
        assert!(worst < 0.6 * pixel, "worst offset {worst} mm");
    }

    #[test]
    fn the_band_alone_gives_the_plates_samples_and_extremes() {
        let (cloud, members) = frame(3.1, 2.0);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(2.0, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
        let near = band_members(&cloud, &members, &edge, params.band_mm);
        assert!(!near.is_empty() && near.len() < members.len() / 2, "{} of {}", near.len(), members.len());
        assert!(near.windows(2).all(|w| w[0] < w[1]), "the band keeps the members' order");
        let all = sample_boundary(&cloud, &members, &plane, &edge, &params);
        let band = sample_boundary(&cloud, &near, &plane, &edge, &params);
        assert_eq!(all.samples.len(), band.samples.len());
        assert!(all.samples.iter().zip(&band.samples).all(|(a, b)| a.position == b.position));
        assert_eq!(all.line_spacing_mm, band.line_spacing_mm);
        assert_eq!(
            members_along(&cloud, &members, &edge, params.band_mm),
            members_along(&cloud, &near, &edge, params.band_mm)
        );
    }

    #[test]
    fn samples_reach_the_plate_corner() {
        let end_y = 2.0;
        let (cloud, members) = frame(3.1, end_y);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(2.0, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 3.0, on_plane_mm: 0.4 };
        let boundary = sample_boundary(&cloud, &members, &plane, &edge, &params);
        let last = boundary.samples.iter().map(|s| s.position.y).fold(f64::MIN, f64::max);
        let pixel = 700.0 / CameraModel::default().fy();
        assert!(last > end_y - 1.01 * pixel && last < end_y, "last sample at y = {last}, plate ends at {end_y}");
        // Half a scan line beyond the last sample is the unbiased end.
        let (_, end) = boundary.extent(|s| s.position.y).unwrap();
        assert!((end - end_y).abs() < 0.55 * pixel, "extent ends at {end}, plate at {end_y}");
    }

    /// A plate of points about `spacing` apart (a jittered square grid,
    /// as voxel centroids lie) whose edge is x = `edge_x` + SLOPE y, and a
    /// coplanar plate beyond a `gap` wide gap.
    fn scattered(spacing: f64, edge_x: f64, gap: f64) -> PointCloud {
        scattered_where(spacing, |x, y| {
            let edge = edge_x + SLOPE * y;
            x < edge || x > edge + gap
        })
    }

    /// Jittered grid points about `spacing` apart where `keep(x, y)`.
    fn scattered_where(spacing: f64, keep: impl Fn(f64, f64) -> bool) -> PointCloud {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut jitter = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.5 * spacing
        };
        let mut points = Vec::new();
        let n = (60.0 / spacing) as i64;
        for row in -n..=n {
            for col in -n..=n {
                let (x, y) = (col as f64 * spacing + jitter(), row as f64 * spacing + jitter());
                if keep(x, y) {
                    points.push([x as f32, y as f32, 700.0]);
                }
            }
        }
        PointCloud::unorganized(points)
    }

    #[test]
    fn scattered_samples_lie_on_the_true_edge_within_a_fifth_of_the_spacing() {
        let (spacing, edge_x) = (1.0, 3.3);
        let cloud = scattered(spacing, edge_x, 2.0);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, spacing, None);
        assert!(boundary.samples.len() > 50, "{} samples", boundary.samples.len());
        let offset = |p: &Vec3| (p.x - edge_x - SLOPE * p.y) * outward.x;
        // Away from the plate's ends, where the last strips hold only part
        // of a row and sample the plate's end rather than its side.
        let offsets: Vec<f64> =
            boundary.samples.iter().filter(|s| s.position.y.abs() < 57.0).map(|s| offset(&s.position)).collect();
        let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
        assert!(mean.abs() < 0.2 * spacing, "mean offset {mean} mm");
        let worst = offsets.iter().map(|o| o.abs()).fold(0.0, f64::max);
        assert!(worst < spacing, "a sample {worst} mm off the edge");
    }

    /// [`scattered`] with depth noise of `sigma` mm (normal, from a fixed
    /// seed) on every point, as a consumer depth camera's voxel clouds have.
    fn noisy_scattered(spacing: f64, edge_x: f64, gap: f64, sigma: f64) -> PointCloud {
        let mut random = crate::sim::noise::RowRandom::new(0x5ca7, 0);
        let points = scattered(spacing, edge_x, gap)
            .points()
            .iter()
            .map(|p| [p[0], p[1], (f64::from(p[2]) + sigma * random.gaussian()) as f32])
            .collect();
        PointCloud::unorganized(points)
    }

    #[test]
    fn a_noisy_plate_s_edge_is_read_further_out_once_its_noise_is_measured() {
        // Noise of 0.8 mm against the 0.4 mm tolerance keeps 38 % of the
        // plate's points, and its outermost kept point lies rows in.
        let (spacing, edge_x, sigma) = (1.0, 3.3, 0.8);
        let cloud = noisy_scattered(spacing, edge_x, 4.0, sigma);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
        let scatter = plane_scatter(&cloud, &plane, &edge, &params, spacing).unwrap();
        assert!((scatter - sigma).abs() < 0.1 * sigma, "measured {scatter} mm, made {sigma} mm");
        let mean_offset = |scatter: Option<f64>| {
            let boundary = sample_scattered(&cloud, &plane, &edge, &params, spacing, scatter);
            let offsets: Vec<f64> = boundary
                .samples
                .iter()
                .filter(|s| s.position.y.abs() < 50.0)
                .map(|s| (s.position.x - edge_x - SLOPE * s.position.y) * outward.x)
                .collect();
            assert!(offsets.len() > 30, "{} samples", offsets.len());
            offsets.iter().sum::<f64>() / offsets.len() as f64
        };
        let thinned = mean_offset(None);
        assert!(thinned < -0.6 * spacing, "unmeasured, the edge is read {thinned} mm out");
        // The correction takes back what thinning adds to the last gap
        // (1.11 to 0.77 mm here); the rest is the strips' walk stopping
        // at holes the thinned interior makes common, which it leaves.
        let measured = mean_offset(Some(scatter));
        assert!(measured > thinned + 0.25 * spacing && measured < 0.1 * spacing, "measured, read {measured} mm out");
        // Noise within the tolerance thins nothing: the samples stay put.
        assert_eq!(on_plane_for_scatter(0.4, Some(0.1)), 0.4);
        let quiet = scattered(spacing, edge_x, 4.0);
        let at = |scatter| sample_scattered(&quiet, &plane, &edge, &params, spacing, scatter).samples;
        let (known, unknown) = (at(Some(0.1)), at(None));
        assert!(known.iter().zip(&unknown).all(|(a, b)| a.position == b.position) && known.len() == unknown.len());
    }

    #[test]
    fn scattered_samples_never_cross_to_the_plate_beyond_the_gap() {
        let cloud = scattered(1.0, 3.3, 1.5);
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(1.3, 0.0, 700.0), direction, outward };
        let params = BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 };
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, None);
        let beyond = boundary.samples.iter().filter(|s| (s.position.x - 3.3 - SLOPE * s.position.y) > 1.0).count();
        assert_eq!(beyond, 0);
        assert!(!sample_scattered(&cloud, &plane, &edge, &params, f64::NAN, None).samples.iter().any(|_| true));
    }

    /// The band beside the test edge, and the edge 2 mm inside the plate.
    fn test_edge(edge_x: f64) -> (Plane, CoarseEdge, BoundaryParams) {
        let plane = Plane { normal: Vec3::z(), offset: 700.0 };
        let direction = Vec3::new(SLOPE, 1.0, 0.0).normalize();
        let outward = Vec3::new(1.0, -SLOPE, 0.0).normalize();
        let edge = CoarseEdge { point: Vec3::new(edge_x - 2.0, 0.0, 700.0), direction, outward };
        (plane, edge, BoundaryParams { band_mm: 6.0, on_plane_mm: 0.4 })
    }

    #[test]
    fn scattered_plate_running_on_past_the_edge_has_no_boundary_there() {
        // A lap's lower plate: it ends at the upper plate's edge for y < 0
        // and runs on beyond the upper plate's end, y > 0.
        let edge_x = 3.3;
        let cloud = scattered_where(1.0, |x, y| y > 0.0 || x < edge_x + SLOPE * y || x > edge_x + SLOPE * y + 20.0);
        let (plane, edge, params) = test_edge(edge_x);
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, None);
        assert!(boundary.samples.len() > 20, "{} samples", boundary.samples.len());
        let (_, end) = boundary.extent(|s| s.position.y).unwrap();
        assert!(end < 2.5, "the edge is seen up to y = {end} mm, where the plate runs on");
    }

    #[test]
    fn scattered_gap_narrower_than_the_spacing_is_no_edge() {
        // Two coplanar plates 0.3 spacings apart: the cloud cannot show the
        // gap, and no strip may claim to.
        let cloud = scattered(1.0, 3.3, 0.3);
        let (plane, edge, params) = test_edge(3.3);
        // A point that happens to fall into the gap is lost, as a camera
        // loses it, and leaves a chance hole here and there; the edge is
        // seen along a small part of the plate only, which is what the
        // planner's coverage gate refuses.
        let boundary = sample_scattered(&cloud, &plane, &edge, &params, 1.0, None);
        let seen = coverage(&boundary, |s| s.along, -55.0, 55.0);
        assert!(seen < 0.5, "the edge is claimed along {:.0} % of the plate across a 0.3 mm gap", 100.0 * seen);
        // The same plates 2 mm apart: the edge is seen nearly everywhere.
        let cloud = scattered(1.0, 3.3, 2.0);
        let seen = coverage(&sample_scattered(&cloud, &plane, &edge, &params, 1.0, None), |s| s.along, -55.0, 55.0);
        assert!(seen > 0.9, "the edge of a 2 mm gap is seen along {:.0} % of the plate", 100.0 * seen);
    }

    /// The far end along y of the strips' extent of the plate beside the
    /// test edge, and of the same refined along the rim of the true edge
    /// (the line a fit of the samples gives).
    fn strip_and_rim_ends(cloud: &PointCloud, edge_x: f64) -> (f64, f64) {
        let (plane, coarse, params) = test_edge(edge_x);
        let strips = sample_scattered(cloud, &plane, &coarse, &params, 1.0, None).extent(|s| s.position.y).unwrap();
        let fitted = CoarseEdge { point: Vec3::new(edge_x, 0.0, 700.0), ..coarse };
        let rim = rim_refined_extent(cloud, &plane, &fitted, &params, 1.0, 0.0, |p: &Vec3| p.y, strips);
        (strips.1, rim.1)
    }

    /// The plate of [`test_edge`] cut by a straight cloud border (the image
    /// border or a crop) that crosses its edge at y = 20 mm, obliquely:
    /// a point `d` inside the edge is kept up to y = 20 - `lean` d / 0.8.
    fn plate_cut_by_a_border(edge_x: f64, lean: f64) -> PointCloud {
        scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < 20.0 - SLOPE * 20.0 * lean + lean * (x - edge_x))
    }

    #[test]
    fn the_rim_reaches_a_border_that_cuts_the_band_inside_the_plate() {
        // Beyond y = 10 the border has cut the band's inner side away and
        // left the plate's rim up to where it crosses the edge, y = 20:
        // the strips there start outside the coarse edge and are dropped.
        // The rim's rows, 0.5 to 1.5 mm inside the edge, meet the border
        // at y = 18.75 to 16.25: the rule reads the end to that, no better.
        let (strips, rim) = strip_and_rim_ends(&plate_cut_by_a_border(3.3, 2.0), 3.3);
        assert!((16.25..=19.25).contains(&rim), "the rim reaches y = {rim} mm, the plate is seen up to 20");
        assert!(20.0 - strips > 20.0 - rim + 1.0, "the strips reach y = {strips} mm, the rim {rim}");
    }

    #[test]
    fn the_rim_stops_where_a_border_cuts_the_edge_away() {
        // Beyond y = 20 the border has cut the edge away and left the
        // plate's inside up to y = 27.5 (the band's inner side): strips
        // that stop at the border take it for the plate's end.
        // The rim's rows meet the border at y = 20.6 to 21.9.
        let (strips, rim) = strip_and_rim_ends(&plate_cut_by_a_border(3.3, -1.0), 3.3);
        assert!((20.6..=22.4).contains(&rim), "the rim reaches y = {rim} mm, the edge is seen up to 20");
        assert!(strips - 20.0 > rim - 20.0 + 1.0, "the strips reach y = {strips} mm, the rim {rim}");
    }

    #[test]
    fn the_rim_reaches_the_plate_corner_and_not_the_foot_of_a_face_beyond() {
        // The plate ends at y = 20; beyond, along the edge line, lie only
        // points on the edge itself at the plate's height, as the foot of
        // a lap's upper plate leaves them beyond the lower plate's end.
        let edge_x = 3.3;
        let cloud = scattered_where(1.0, |x, y| {
            let edge = edge_x + SLOPE * y;
            (x < edge && y < 20.0) || (y >= 20.0 && (x - edge).abs() < 0.2)
        });
        let (_, rim) = strip_and_rim_ends(&cloud, edge_x);
        assert!((rim - 20.0).abs() < 0.5, "the rim reaches y = {rim} mm, the plate ends at 20");
    }

    #[test]
    fn past_a_plate_end_where_the_table_is_seen_the_strips_keep_the_end() {
        // The plate ends at y = 20 and the table, 40 mm further away, is
        // seen beyond: the plate's own end, which the strips read; the rim
        // is the cloud's border's witness only.
        let edge_x = 3.3;
        let plate = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < 20.0);
        let table = scattered_where(1.0, |_, y| y >= 20.0);
        let mut points = plate.points().to_vec();
        points.extend(table.points().iter().map(|p| [p[0] * 740.0 / 700.0, p[1] * 740.0 / 700.0, 740.0]));
        let cloud = PointCloud::unorganized(points);
        let (plane, coarse, params) = test_edge(edge_x);
        let strips = sample_scattered(&cloud, &plane, &coarse, &params, 1.0, None).extent(|s| s.position.y).unwrap();
        let fitted = CoarseEdge { point: Vec3::new(edge_x, 0.0, 700.0), ..coarse };
        let refined = rim_refined_extent(&cloud, &plane, &fitted, &params, 1.0, 0.0, |p: &Vec3| p.y, strips);
        assert_eq!(refined.1, strips.1);
        // The same plate with nothing beyond: the cloud ends with it.
        let (strips_end, rim_end) = strip_and_rim_ends(&plate, edge_x);
        assert!((rim_end - 20.0).abs() < 0.5 && rim_end != strips_end, "rim {rim_end}, strips {strips_end}");
    }

    /// A square lattice of points `pitch` apart (voxel centroids of a
    /// plate), its rows turned `turn` radians from the test edge and
    /// shifted `shift` of a pitch across it, kept where `keep(x, y)`.
    fn lattice_where(pitch: f64, turn: f64, shift: f64, keep: impl Fn(f64, f64) -> bool) -> PointCloud {
        let angle = SLOPE.atan() + turn;
        let (along, across) = (Vector2::new(angle.sin(), angle.cos()), Vector2::new(angle.cos(), -angle.sin()));
        let n = (80.0 / pitch) as i64;
        let points = (-n..=n)
            .flat_map(|i| (-n..=n).map(move |j| (i, j)))
            .map(|(i, j)| across * ((i as f64 + shift) * pitch) + along * (j as f64 * pitch))
            .filter(|p| keep(p.x, p.y))
            .map(|p| [p.x as f32, p.y as f32, 700.0])
            .collect();
        PointCloud::unorganized(points)
    }

    #[test]
    fn the_rim_reaches_the_end_of_a_lattice_whose_rows_miss_the_rim_rows() {
        // Voxel centroids lie on a lattice whose pitch can exceed the
        // measured spacing: with the spacing taken as 1 mm and a pitch of
        // 1.15 mm, the rim's rows (0.5 to 1.5 mm inside the edge) hold no
        // lattice row for a stretch wherever two rows straddle them. The
        // plate ends at y = 20 with nothing beyond: wherever its rows lie,
        // the rim reads that end within the lattice's pitch.
        let edge_x = 3.3;
        let mut worst: f64 = 0.0;
        for turn in [0.01, 0.03, -0.02] {
            for k in 0..8 {
                let cloud = lattice_where(1.15, turn, k as f64 / 8.0, |x, y| x < edge_x + SLOPE * y && y < 20.0);
                let (_, rim) = strip_and_rim_ends(&cloud, edge_x);
                worst = worst.max((rim - 20.0).abs());
            }
        }
        assert!(worst < 0.8, "the rim's end is {worst:.2} mm from the plate's");
    }

    #[test]
    fn a_rim_that_loses_its_points_to_noise_short_of_the_border_keeps_the_strips_end() {
        // The cloud ends at y = 20 across the whole band, but the last
        // 2.5 mm of the rows lie off the plane (a noisy camera near its
        // image border): the rows' points stop short of the cloud's end,
        // and the strips, which read every row, see the end itself.
        let edge_x = 3.3;
        let plate = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < 20.0);
        let noisy = |p: &[f32; 3]| {
            let inside = f64::from(p[0]) - edge_x - SLOPE * f64::from(p[1]);
            f64::from(p[1]) > 17.5 && (-2.0..=0.0).contains(&inside)
        };
        let points = plate.points().iter().map(|p| if noisy(p) { [p[0], p[1], 699.0] } else { *p }).collect();
        let (strips, rim) = strip_and_rim_ends(&PointCloud::unorganized(points), edge_x);
        assert_eq!(rim, strips, "the rim's end replaced the strips' at {strips}");
        assert!((strips - 20.0).abs() < 1.1, "the strips end at {strips}, the cloud at 20");
    }

    #[test]
    fn a_strip_holding_the_plate_corner_and_a_face_foot_beyond_ends_at_the_corner() {
        // The foot of a lap's upper plate runs on along the edge line past
        // the lower plate's end, its points on the line itself, outermost
        // in the corner strip: the sample keeps to where the plate is,
        // wherever the plate's end falls in its strip.
        let edge_x = 3.3;
        let (plane, coarse, params) = test_edge(edge_x);
        for end_y in (0..20).map(|k| 18.0 + 0.1 * k as f64) {
            let plate = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y < end_y);
            let foot = (0..80).map(|k| end_y + 0.25 * k as f64).map(|y| [(edge_x + SLOPE * y) as f32, y as f32, 700.0]);
            let cloud = PointCloud::unorganized(plate.points().iter().copied().chain(foot).collect());
            let boundary = sample_scattered(&cloud, &plane, &coarse, &params, 1.0, None);
            let beyond = boundary.samples.iter().map(|s| s.position.y).fold(f64::MIN, f64::max);
            assert!(beyond < end_y + 0.1, "a boundary sample at y = {beyond} mm, past the plate's end at {end_y}");
        }
    }

    #[test]
    fn an_edge_fitted_to_noisy_samples_keeps_the_strips_ends() {
        let cloud = plate_cut_by_a_border(3.3, 2.0);
        let (plane, coarse, params) = test_edge(3.3);
        let strips = sample_scattered(&cloud, &plane, &coarse, &params, 1.0, None).extent(|s| s.position.y).unwrap();
        let fitted = CoarseEdge { point: Vec3::new(3.3, 0.0, 700.0), ..coarse };
        let noisy = rim_refined_extent(&cloud, &plane, &fitted, &params, 1.0, 0.3, |p: &Vec3| p.y, strips);
        assert_eq!(noisy, strips);
    }

    #[test]
    fn the_rim_trim_leaves_the_disc_fraction_the_criterion_asks() {
        // Half the disc is lost on the edge itself, none a radius inside.
        assert!(rim_trim_radii(0.5) < 1e-9);
        assert!((rim_trim_radii(1.0) - 1.0).abs() < 1e-9);
        // At the default 0.8 a point passes from about half a radius in.
        let d = rim_trim_radii(0.8);
        let cap = (d.acos() - d * (1.0 - d * d).sqrt()) / std::f64::consts::PI;
        assert!((cap - 0.2).abs() < 1e-9 && (0.45..0.55).contains(&d), "d = {d}, cap {cap}");
    }

    #[test]
    fn pieces_join_a_plate_across_narrow_breaks_only() {
        // A streak's 2 mm break joins; a clamp's 30 mm does not, nor what
        // lies beyond it.
        let pieces = [(52.0, 80.0), (110.0, 150.0), (-40.0, -2.0)];
        assert_eq!(joined_extent((0.0, 50.0), &pieces, 4.0), (-40.0, 80.0));
        assert_eq!(joined_extent((0.0, 50.0), &[], 4.0), (0.0, 50.0));
        // Chains: each piece within reach of the one before.
        assert_eq!(joined_extent((0.0, 10.0), &[(23.0, 30.0), (12.0, 20.0)], 4.0), (0.0, 30.0));
    }

    #[test]
    fn members_along_finds_the_plate_beside_the_edge() {
        let edge_x = 3.3;
        let cloud = scattered_where(1.0, |x, y| x < edge_x + SLOPE * y && y.abs() < 30.0);
        let members: Vec<u32> = (0..cloud.len() as u32).collect();
        let (_, edge, params) = test_edge(edge_x);
        let [lo, hi] = members_along(&cloud, &members, &edge, params.band_mm).unwrap();
        assert!(lo.y > -30.0 && lo.y < -29.0 && hi.y < 30.0 && hi.y > 29.0, "{lo:?} {hi:?}");
        assert!(members_along(&cloud, &[], &edge, params.band_mm).is_none());
    }

    #[test]
    fn the_plate_s_reach_along_an_edge_is_its_first_extreme_member_however_the_members_are_split() {
        // Members along y = 0..n in a band inside the edge x = 0 (outward
        // +x), three chunks' worth, with the extremes tied across chunks:
        // two members at the least y and two at the greatest, each pair a
        // chunk apart and told apart by x.
        let n = 3 * MEMBERS_PER_CHUNK;
        let mut pts: Vec<[f32; 3]> = (0..n).map(|i| [-0.5, 10.0 + i as f32 * 0.01, 700.0]).collect();
        let (lo, hi) = (5.0f32, 10.0 + n as f32 * 0.01);
        pts[7] = [-0.25, lo, 700.0];
        pts[7 + MEMBERS_PER_CHUNK] = [-0.75, lo, 700.0];
        pts[40] = [-0.25, hi, 700.0];
        pts[n - 3] = [-0.75, hi, 700.0];
        // A member outside the band, further along than all.
        pts[n - 1] = [0.5, 1000.0, 700.0];
        let cloud = PointCloud::unorganized(pts.clone());
        let edge = CoarseEdge { point: Vec3::new(0.0, 0.0, 700.0), direction: Vec3::y(), outward: Vec3::x() };
        let members: Vec<u32> = (0..n as u32).collect();
        let [back, forward] = members_along(&cloud, &members, &edge, 1.0).unwrap();
        assert_eq!((back, forward), (vec3(&pts[7]), vec3(&pts[40])));
        // The band keeps the members within a millimetre either side, in order.
        let band = band_members(&cloud, &members, &edge, 1.0);
        let expected: Vec<u32> = (0..n as u32).filter(|&i| pts[i as usize][0].abs() <= 1.0).collect();
        assert_eq!(band, expected);
    }

    #[test]
    fn the_99th_percentile_is_the_value_a_sort_ranks_there() {
        assert_eq!(percentile_99(std::iter::empty()), None);
        for n in [1usize, 2, 99, 100, 101, 250, 4321] {
            // Repeats and a spread of magnitudes, in no order.
            let values: Vec<f64> =
                (0..n).map(|i| ((i * 7919) % 613) as f64 * if i % 5 == 0 { 10.0 } else { 0.01 }).collect();
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            let rank = (n * 99 / 100).min(n - 1);
            assert_eq!(percentile_99(values.iter().copied()), Some(sorted[rank]), "{n} values");
        }
    }
}
