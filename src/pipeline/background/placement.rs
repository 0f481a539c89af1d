//! Where one plane cluster lies against others: across a bar's long axis,
//! beside it, beyond or between a butt pair; and the points a cluster
//! holds. The layout and corner rules are read from these.

use crate::cloud::Point;
use crate::geometry::{Vec3, extent, vec3};

use super::PlaneCluster;

/// How large the second plate of a layer must be, against the first, to
/// count as a plate beside it rather than a piece of fixture or a clamp.
pub(super) const SIDE_BY_SIDE_AREA_RATIO: f64 = 0.25;

/// A plane at least this many times longer than wide is a bar that can lie
/// across another plane, cutting it in two.
pub(super) const BAR_ELONGATION: f64 = 2.0;

/// Whether `top`, nearer the camera, lies across the plane that `a` and
/// `b` are pieces of: `top` is long and narrow, and the two lie on
/// opposite sides of its long axis. A lap's upper plate ends on its lower
/// plate, so the lower one is seen on one side of it only; two butt
/// plates have nothing lying along the gap between them.
pub(super) fn lies_across(top: &PlaneCluster, a: &PlaneCluster, b: &PlaneCluster, normal: &Vec3) -> bool {
    if top.elongation < BAR_ELONGATION {
        return false;
    }
    side_of(top, a, normal) * side_of(top, b, normal) < 0.0
}

/// How much of `under` is seen beside `top` on each side of it, mm²: its
/// points between `top`'s ends along its long axis and beyond its sides
/// across it, each standing for an equal share of `under`'s area. A bar
/// lying across a plate leaves the plate seen on both of its sides, also
/// where the plate is one cluster round the bar's end; a lap's upper plate
/// ends on its lower plate, seen beside one of its sides only. Counting
/// only past the top's own reach across keeps a plate the image border
/// cuts slantwise, whose long axis runs askew of its edges, to one side.
pub(super) fn seen_beside(top: &PlaneCluster, under: &PlaneCluster, normal: &Vec3, points: &[Point]) -> [f64; 2] {
    let across_axis = normal.cross(&top.long_axis);
    let place = |p: Vec3| {
        let d = p - top.centroid;
        (top.long_axis.dot(&d), across_axis.dot(&d))
    };
    let reach: Vec<(f64, f64)> = member_points(&top.members, points).map(place).collect();
    let (along_lo, along_hi) = extent(reach.iter().map(|r| r.0));
    let (across_lo, across_hi) = extent(reach.iter().map(|r| r.1));
    let mut counts = [0usize; 2];
    for (along, across) in member_points(&under.members, points).map(place) {
        if !(along_lo..=along_hi).contains(&along) {
            continue;
        }
        if across < across_lo {
            counts[0] += 1;
        } else if across > across_hi {
            counts[1] += 1;
        }
    }
    let per_point_mm2 = under.area_mm2 / under.members.len().max(1) as f64;
    counts.map(|n| n as f64 * per_point_mm2)
}

/// Which side of `top`'s long axis `c` lies on, and how far: positive on
/// the side `normal × long axis` points to.
pub(super) fn side_of(top: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> f64 {
    normal.cross(&top.long_axis).dot(&(c.centroid - top.centroid))
}

/// A plane cluster's mean point spacing, mm, from its area and count.
pub(super) fn spacing_of(c: &PlaneCluster) -> f64 {
    (c.area_mm2 / c.members.len().max(1) as f64).sqrt()
}

/// The finite points of `members`.
pub(super) fn member_points<'p>(members: &'p [u32], points: &'p [Point]) -> impl Iterator<Item = Vec3> + 'p {
    every_member_point(members, 1, points)
}

/// The finite points of every `every`-th member: a sample read without
/// reading the members skipped.
pub(super) fn every_member_point<'p>(
    members: &'p [u32],
    every: usize,
    points: &'p [Point],
) -> impl Iterator<Item = Vec3> + 'p {
    members
        .iter()
        .step_by(every)
        .filter_map(|&i| points.get(i as usize))
        .map(vec3)
        .filter(|p| p.iter().all(|v| v.is_finite()))
}

/// How far beyond a butt pair, across their seam, a third plate's centroid
/// must lie to be a plate beside them: in units of the distance between
/// the pair's centroids, counted from the nearer of the two. A piece a
/// clamp or a streak cut off one of the pair has that plate's centroid
/// across the seam (it runs on along the seam, not beside it), moved at
/// most by how differently the image border cuts the two pieces; a plate
/// abutting one of the pair lies a plate's width further out.
pub(super) const BEYOND_PAIR_SPACINGS: f64 = 0.5;

/// Where `c`'s centroid lies across the pair `a`, `b`: its place on the
/// line through theirs, in the plane of the layer (0 at `a`'s, 1 at
/// `b`'s); None for a pair whose centroids coincide.
pub(super) fn across_pair(a: &PlaneCluster, b: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> Option<f64> {
    let in_plane = |v: Vec3| v - normal * normal.dot(&v);
    let across = in_plane(b.centroid - a.centroid);
    let spacing = across.norm();
    (spacing > 0.0).then(|| in_plane(c.centroid - a.centroid).dot(&across) / (spacing * spacing))
}

/// Whether `c` lies beside the pair `a`, `b` across their seam, beyond
/// either: its centroid more than [`BEYOND_PAIR_SPACINGS`] of their
/// distance outside the pair.
pub(super) fn lies_beyond_pair(a: &PlaneCluster, b: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> bool {
    across_pair(a, b, c, normal).is_some_and(|t| !(-BEYOND_PAIR_SPACINGS..=1.0 + BEYOND_PAIR_SPACINGS).contains(&t))
}

/// Whether `c` is a strip between the pair `a`, `b`: its centroid between
/// theirs, and it is a bar ([`BAR_ELONGATION`]) narrower than either
/// plate. A V-groove's apex, which the voxels of a noisy cloud flatten
/// into a narrow plane, or the table a gap shows lie so; what the plates
/// rest on reaches out under and beside them.
pub(super) fn lies_between_pair(a: &PlaneCluster, b: &PlaneCluster, c: &PlaneCluster, normal: &Vec3) -> bool {
    across_pair(a, b, c, normal).is_some_and(|t| {
        (0.0..=1.0).contains(&t) && c.elongation >= BAR_ELONGATION && c.width_mm() < a.width_mm().min(b.width_mm())
    })
}
