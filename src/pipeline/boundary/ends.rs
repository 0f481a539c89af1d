//! What lies past a seam's ends: where a plate reaches the image border,
//! the surfaces beyond an end, a plate unseen beside the seam, and the
//! breaks across which a seam's pieces are one joint.

use crate::cloud::{PointCloud, is_valid_point};
use crate::geometry::fit::Plane;
use crate::geometry::{Vec3, vec3};

use super::super::context::CameraGrid;
use super::super::refit::SeamCurve;

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
pub(in crate::pipeline) fn reach_image_border(
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
/// Zero where a plate ends with the seam, or the view does (where either
/// edge leaves the image).
pub(in crate::pipeline) fn surfaces_beyond(
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
    // Plate k's surface just inside its edge at `s`: None out of view,
    // where the edge has left the image though the pixels inside it,
    // across an oblique border, have not.
    let seen = |k: usize, s: f64| -> Option<bool> {
        if !grid.in_view(&edges[k].at(s)) {
            return None;
        }
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
pub(in crate::pipeline) fn plate_unseen_beside(
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

/// The stretch of a weld both its edges show, from each weld edge's extent
/// `(lo, hi)` along it: where both are seen, save that an end of an edge
/// that only stands in for the joint's own line, and leaves the image
/// there (`leaves_view[k] = [at lo, at hi]`), does not end it. A lap's
/// joint is its upper plate's edge and its root a plate step below; the
/// lower plate's edge the planner reads is where that plate's points stop
/// beside the root, off the root across the seam, so a border crossing the
/// seam obliquely cuts it before or after the root itself. Where it leaves
/// the image, the end is the upper edge's, and the caller clips the root
/// to the view. Where every edge's end there is flagged, none is left to
/// end the seam and both bound it as before.
pub fn seam_span(extents: [(f64, f64); 2], leaves_view: [[bool; 2]; 2]) -> (f64, f64) {
    let end = |at: [f64; 2], leaves: [bool; 2], inner: fn(f64, f64) -> f64| {
        (0..2).filter(|&k| !leaves[k]).map(|k| at[k]).reduce(inner).unwrap_or_else(|| inner(at[0], at[1]))
    };
    let [(a0, a1), (b0, b1)] = extents;
    let [[a0_leaves, a1_leaves], [b0_leaves, b1_leaves]] = leaves_view;
    (end([a0, b0], [a0_leaves, b0_leaves], f64::max), end([a1, b1], [a1_leaves, b1_leaves], f64::min))
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
