//! Boundary sampling: where exactly a plate ends beside the weld.
//!
//! Edge points from the edge criterion lie up to R inside the true edge,
//! because the plane criterion has already trimmed the outermost points.
//! On a pixel grid the true boundary can be read directly: walk each scan
//! line outward across the coarse weld edge while the pixels stay on the
//! plate's plane; the plate ends between the last such pixel and the next,
//! so the boundary sample is half a pixel step beyond the last one, or,
//! where the pixels at a depth jump return a blend of both depths (mixed
//! pixels), in the middle of the mixed run ([`grid`]). The walk also runs
//! past the ends of the coarse edge, so the samples reach the plate's
//! corners and give the seam's true extent; a walk that leaves the plate
//! through its end instead (scan lines crossing the end obliquely) shows
//! how far the plate reaches and is no sample of the edge's line.
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
//!
//! The stage's files, by concern: [`grid`] walks the pixel grid's scan
//! lines; [`scattered`] reads the strips of a cloud without a grid and
//! measures how the plane criterion thins a noisy plate; [`rim`] reads
//! the seam's ends again from the plate's last rows; [`band`] gathers a
//! plate's points beside an edge and the stretch a plate is seen along;
//! [`ends`] reads what lies past a seam's ends: the image border, the
//! surfaces beyond, a plate unseen beside, the breaks a seam is joined
//! across.

mod band;
mod ends;
mod grid;
mod rim;
mod scattered;
#[cfg(test)]
mod tests;

use crate::geometry::Vec3;

pub use band::{
    SpannedEdge, band_members, members_along, read_stride, stretch_seen_beside, stretch_seen_beside_reading,
};
pub use ends::{JOINT_BREAK_SPACINGS, joined_extent, rim_trim_radii, seam_span};
pub(super) use ends::{plate_unseen_beside, reach_image_border, surfaces_beyond};
pub use grid::sample_boundary;
pub use rim::{rim_points_at_ends, rim_refined_extent};
pub use scattered::{plane_scatter, sample_scattered};

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

/// The boundary samples of one edge.
#[derive(Debug, Clone, Default)]
pub struct Boundary {
    pub samples: Vec<BoundarySample>,
    /// On a pixel grid, the walks that left the plate across another of
    /// its edges (its end, cut obliquely by the scan lines) rather than
    /// the one sampled: they show how far the plate reaches, and are no
    /// sample of this edge's line ([`grid`]).
    pub across_other_edge: Vec<BoundarySample>,
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
        let mut at: Vec<f64> = self.samples.iter().chain(&self.across_other_edge).map(along).collect();
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
        if let Some((kept, lo, hi)) = best
            && kept < at.len()
        {
            let rule = crate::rules::refit::SEAM_LONGEST_SEEN_STRETCH.id;
            tracing::debug!(
                rule,
                kept,
                samples = at.len(),
                from_mm = lo,
                to_mm = hi,
                "the edge's longest stretch kept"
            );
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
