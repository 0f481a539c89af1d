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
/// `b` are pieces of. A lap's upper plate ends on its lower plate, so the
/// lower one is seen on one side of it only; two butt plates have nothing
/// lying along the gap between them. A bar ([`BAR_ELONGATION`]) lies
/// across when the two lie on opposite sides of its long axis. A top no
/// longer than that (a bar the view cuts short, as a crop round the seam
/// cuts a clamp to a square pad, or a block) has no long axis to tell
/// across from along: it lies across when the line through the two
/// pieces' centroids passes through its footprint between them
/// ([`passes_through`]). Pieces of a lap's lower plate lie beyond the
/// upper plate's edge, the line through them beside the plate.
pub(super) fn lies_across(top: &PlaneCluster, a: &PlaneCluster, b: &PlaneCluster, normal: &Vec3) -> bool {
    if top.elongation >= BAR_ELONGATION {
        return side_of(top, a, normal) * side_of(top, b, normal) < 0.0;
    }
    passes_through(top, a.centroid, b.centroid, normal)
}

/// Whether the segment from `a` to `b`, seen along `normal`, passes
/// through `top`'s footprint: the rectangle of its area and elongation
/// along its long axis, round its centroid. The point of the segment
/// nearest the centroid across the segment must lie between `a` and `b`,
/// and closer to the centroid than the rectangle reaches in that
/// direction.
pub(super) fn passes_through(top: &PlaneCluster, a: Vec3, b: Vec3, normal: &Vec3) -> bool {
    let in_plane = |v: Vec3| v - normal * normal.dot(&v);
    let run = in_plane(b - a);
    let length = run.norm();
    if length == 0.0 {
        return false;
    }
    let along = run / length;
    let to_top = in_plane(top.centroid - a);
    let at = to_top.dot(&along);
    if !(0.0..=length).contains(&at) {
        return false;
    }
    let off = to_top - along * at;
    let miss_mm = off.norm();
    if miss_mm == 0.0 {
        return true;
    }
    // The rectangle's half reach along the miss's direction: its
    // support function, from its sides along and across the long axis.
    let towards = off / miss_mm;
    let elongation = top.elongation.max(1.0);
    let (long_mm, short_mm) = ((top.area_mm2 * elongation).sqrt(), (top.area_mm2 / elongation).sqrt());
    let across_axis = normal.cross(&top.long_axis);
    let reach_mm = 0.5 * (towards.dot(&top.long_axis).abs() * long_mm + towards.dot(&across_axis).abs() * short_mm);
    miss_mm < reach_mm
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

/// How far outside a plane's trimmed edge the face falling from that edge
/// may be seen, in point spacings on top of the plane criterion's rim:
/// depth noise and a face seen at a grazing angle spread its points a
/// little across.
const FALL_REACH_SPACINGS: f64 = 4.0;

/// The points of a face falling from a top to the plane under it are kept
/// this many point spacings (and at least the coplanar tolerance) clear of
/// either plane, so that neither plane's own points and noise count.
const FALL_MARGIN_SPACINGS: f64 = 2.0;

/// The fewest points that show a face falling from a top (as many as make
/// a web's side face in the fillet stage).
pub(super) const FALL_MIN_POINTS: usize = crate::pipeline::fillet::MIN_FACE_POINTS;

/// A face falls from a top to the plane under it when the points round
/// one side of the top's outline fill each of this many bands of height
/// between the two planes: a face seen over the whole drop. A lap's or a
/// plate's edge over a lower layer stands no higher than the plate is
/// thick, a clamp or a part held over a plate leaves a gap under it, and
/// a veil of mixed returns hanging along the camera's rays from an edge
/// slants away from the outline after a band or two.
pub(super) const FALL_HEIGHT_BANDS: usize = 8;

/// How many of a top's points [`face_falls_from`] reads its outline from,
/// at most.
const OUTLINE_SAMPLES: usize = 4_000;

/// Whether a face falls from `top`'s edges to the plane `height_mm` under
/// it (along `normal`, away from the camera): among `points`, outside
/// `top`'s plane and the lower one, round the outline of `top` (the sides
/// of the rectangle round it that covers the least area, widened and
/// narrowed by `rim_mm` and a few spacings), at least [`FALL_MIN_POINTS`]
/// round one side lie between the two planes, and they fill each of
/// [`FALL_HEIGHT_BANDS`] bands of height between them. A block standing on a plate shows its side
/// faces so, however wide its top; a top seen over a plane with nothing
/// between them (a plate held over another, a far layer seen past an
/// edge) does not, nor does a plate over a table whose edge leaves a veil
/// of mixed returns along the camera's rays under it (the veil's lower
/// part lies inside the plate's outline).
pub(super) fn face_falls_from(
    top: &PlaneCluster,
    height_mm: f64,
    normal: &Vec3,
    rim_mm: f64,
    tolerance_mm: f64,
    points: &[Point],
) -> bool {
    let spacing = spacing_of(top);
    let stride = (top.members.len() / OUTLINE_SAMPLES).max(1);
    let outline: Vec<Vec3> = every_member_point(&top.members, stride, points).collect();
    let Some(along_axis) = crate::geometry::outline_axis(&outline, normal) else {
        return false;
    };
    let across_axis = normal.cross(&along_axis);
    let place = |p: &Vec3| {
        let d = p - top.centroid;
        (along_axis.dot(&d), across_axis.dot(&d), -normal.dot(&d))
    };
    let reach = rim_mm + FALL_REACH_SPACINGS * spacing;
    let margin = tolerance_mm.max(FALL_MARGIN_SPACINGS * spacing);
    let placed: Vec<(f64, f64, f64)> = outline.iter().map(place).collect();
    let (along_lo, along_hi) = extent(placed.iter().map(|o| o.0));
    let (across_lo, across_hi) = extent(placed.iter().map(|o| o.1));
    let near_edge = |v: f64, lo: f64, hi: f64| (lo - reach..=hi + reach).contains(&v);
    let inside = |v: f64, lo: f64, hi: f64| (lo + reach..=hi - reach).contains(&v);
    // Heights over the lower plane: the top's plane lies `height_mm` up.
    // Each side of the outline (along's low and high, across's low and
    // high) counts its points and the bands of height they fill.
    let band_of = |h: f64| ((h - margin) / (height_mm - 2.0 * margin) * FALL_HEIGHT_BANDS as f64) as usize;
    let mut sides = [(0usize, [false; FALL_HEIGHT_BANDS]); 4];
    for p in points.iter().map(vec3).filter(|p| p.iter().all(|v| v.is_finite())) {
        let (along, across, up) = place(&p);
        let h = height_mm + up;
        let round_outline = near_edge(along, along_lo, along_hi)
            && near_edge(across, across_lo, across_hi)
            && !(inside(along, along_lo, along_hi) && inside(across, across_lo, across_hi));
        if !(margin..height_mm - margin).contains(&h) || !round_outline {
            continue;
        }
        let off_edges = [along - along_lo, along_hi - along, across - across_lo, across_hi - across];
        let side = (0..4).min_by(|&a, &b| off_edges[a].abs().total_cmp(&off_edges[b].abs())).unwrap_or(0);
        sides[side].0 += 1;
        sides[side].1[band_of(h).min(FALL_HEIGHT_BANDS - 1)] = true;
    }
    sides.iter().any(|(count, bands)| *count >= FALL_MIN_POINTS && bands.iter().all(|&b| b))
}
