//! The simulated workpiece as convex polyhedra: the two plates of a joint,
//! the spacer blocks they rest on and the table underneath.
//!
//! Workpiece frame W: the seam runs along +y at x = 0, z points up, the
//! bottom of the reference plate is at z = 0 and the table's top at
//! `-spacer_height`. Every solid is an intersection of half-spaces, so a
//! ray hit is a slab clip (Cyrus-Beck) and "is this point on a surface" is
//! one maximum over plane distances.

use nalgebra::Isometry3;

use super::{CornerKind, JointGeometry, PlateExtent, SceneSpec};
use crate::geometry::Vec3;

/// The points `p` with `normal · p <= offset`; `normal` is the outward unit
/// normal of the face on the boundary plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfSpace {
    pub normal: Vec3,
    pub offset: f64,
}

/// What a solid is, so tests and scene checks can tell plates from the
/// background they must not be confused with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceKind {
    Plate,
    Spacer,
    Table,
    /// Something lying on the workpiece that is not part of it (a clamp).
    Clutter,
    /// Weld metal: tacks and spatter.
    Weld,
}

/// A bounded convex polyhedron: its half-spaces and its corner points
/// (kept for image-space and box culling).
#[derive(Debug, Clone)]
pub struct ConvexSolid {
    pub kind: SurfaceKind,
    planes: Vec<HalfSpace>,
    vertices: Vec<Vec3>,
}

/// The part of a line `origin + t dir` inside a solid, `enter <= exit`.
/// `normal` is the outward normal of the face crossed at `enter`, absent
/// when the line starts inside (at `enter == t_min`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    pub enter: f64,
    pub exit: f64,
    pub normal: Option<Vec3>,
}

/// A shadow or view ray counts as blocked only through this fraction of
/// its length inside a solid (touching surfaces do not block).
pub const MIN_BLOCKED_FRACTION: f64 = 1e-7;

/// Edges shorter than this are dropped from profiles: a V groove as deep
/// as the plate has no root face, and the zero-length edge has no normal.
const MIN_EDGE_MM: f64 = 1e-9;

impl ConvexSolid {
    /// A convex polygon in the xz plane (any orientation) swept along y
    /// over `y_range`. Returns `None` for a degenerate profile or range.
    pub fn extruded(kind: SurfaceKind, profile_xz: &[[f64; 2]], y_range: [f64; 2]) -> Option<Self> {
        let [y0, y1] = y_range;
        if profile_xz.len() < 3 || y1 - y0 <= MIN_EDGE_MM {
            return None;
        }
        let n = profile_xz.len() as f64;
        let centre = profile_xz.iter().fold([0.0, 0.0], |c, p| [c[0] + p[0] / n, c[1] + p[1] / n]);
        let mut planes = vec![
            HalfSpace { normal: Vec3::new(0.0, -1.0, 0.0), offset: -y0 },
            HalfSpace { normal: Vec3::new(0.0, 1.0, 0.0), offset: y1 },
        ];
        for (i, p) in profile_xz.iter().enumerate() {
            let q = profile_xz[(i + 1) % profile_xz.len()];
            let edge = [q[0] - p[0], q[1] - p[1]];
            let len = edge[0].hypot(edge[1]);
            if len <= MIN_EDGE_MM {
                continue;
            }
            // Either perpendicular; the centre of a convex polygon is
            // inside, so the outward one points away from it.
            let mut normal = Vec3::new(edge[1] / len, 0.0, -edge[0] / len);
            let along_normal = normal.x * (centre[0] - p[0]) + normal.z * (centre[1] - p[1]);
            if along_normal > 0.0 {
                normal = -normal;
            }
            let offset = normal.x * p[0] + normal.z * p[1];
            planes.push(HalfSpace { normal, offset });
        }
        if planes.len() < 5 {
            return None;
        }
        let vertices = profile_xz.iter().flat_map(|p| [Vec3::new(p[0], y0, p[1]), Vec3::new(p[0], y1, p[1])]).collect();
        Some(ConvexSolid { kind, planes, vertices })
    }

    /// An axis-aligned box.
    pub fn cuboid(kind: SurfaceKind, min: Vec3, max: Vec3) -> Option<Self> {
        let profile = [[min.x, min.z], [max.x, min.z], [max.x, max.z], [min.x, max.z]];
        if max.x - min.x <= MIN_EDGE_MM || max.z - min.z <= MIN_EDGE_MM {
            return None;
        }
        Self::extruded(kind, &profile, [min.y, max.y])
    }

    /// The same solid expressed in another frame: `to_frame` maps this
    /// solid's coordinates into the new ones.
    pub fn transformed(&self, to_frame: &Isometry3<f64>) -> Self {
        let planes = self
            .planes
            .iter()
            .map(|h| {
                let normal = to_frame.rotation * h.normal;
                HalfSpace { normal, offset: h.offset + normal.dot(&to_frame.translation.vector) }
            })
            .collect();
        let vertices = self.vertices.iter().map(|v| to_frame.transform_point(&(*v).into()).coords).collect();
        ConvexSolid { kind: self.kind, planes, vertices }
    }

    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    pub fn planes(&self) -> &[HalfSpace] {
        &self.planes
    }

    /// Clips the line `origin + t dir`, `t` in `[t_min, t_max]`, to the
    /// solid (Cyrus-Beck).
    #[inline]
    pub fn clip(&self, origin: &Vec3, dir: &Vec3, t_min: f64, t_max: f64) -> Option<Span> {
        let mut enter = t_min;
        let mut exit = t_max;
        let mut normal = None;
        for h in &self.planes {
            let denom = h.normal.dot(dir);
            let room = h.offset - h.normal.dot(origin);
            if denom == 0.0 {
                if room < 0.0 {
                    return None;
                }
                continue;
            }
            let t = room / denom;
            if denom < 0.0 {
                if t > enter {
                    enter = t;
                    normal = Some(h.normal);
                }
            } else if t < exit {
                exit = t;
            }
            if enter > exit {
                return None;
            }
        }
        Some(Span { enter, exit, normal })
    }

    /// Whether the solid blocks the segment from `from` to `from + delta`
    /// (a view or shadow ray): only a stretch inside it longer than
    /// [`MIN_BLOCKED_FRACTION`] of the segment does, so surfaces the
    /// segment merely touches at its end do not.
    pub fn blocks(&self, from: &Vec3, delta: &Vec3) -> bool {
        self.clip(from, delta, 0.0, 1.0).is_some_and(|s| s.exit - s.enter > MIN_BLOCKED_FRACTION)
    }

    /// How far `p` lies outside the worst of the half-spaces: negative
    /// inside, zero exactly on the surface, and a lower bound of the
    /// distance to the solid outside.
    pub fn excess(&self, p: &Vec3) -> f64 {
        self.planes.iter().map(|h| h.normal.dot(p) - h.offset).fold(f64::NEG_INFINITY, f64::max)
    }
}

/// All solids of a scene in one frame.
#[derive(Debug, Clone)]
pub struct Scene {
    pub solids: Vec<ConvexSolid>,
}

impl Scene {
    /// The scene in another frame (see [`ConvexSolid::transformed`]).
    pub fn transformed(&self, to_frame: &Isometry3<f64>) -> Scene {
        Scene { solids: self.solids.iter().map(|s| s.transformed(to_frame)).collect() }
    }

    /// Distance-like measure of `p` from the nearest surface: zero for a
    /// point exactly on some solid's boundary.
    pub fn surface_gap(&self, p: &Vec3) -> f64 {
        self.solids.iter().map(|s| s.excess(p).abs()).fold(f64::INFINITY, f64::min)
    }
}

/// Half the side of the square table: large enough to fill any view of
/// the camera's working range.
const TABLE_HALF_SIDE_MM: f64 = 1500.0;
const TABLE_THICKNESS_MM: f64 = 20.0;
/// Spacer blocks sit this far inside the plate edges, as a fitter places
/// them so they carry the plate without showing.
const SPACER_INSET_MM: f64 = 15.0;
/// Extent of one spacer block along the seam.
const SPACER_LENGTH_MM: f64 = 40.0;
/// Gap between the support of the lap's overhanging upper plate and the
/// lower plate's edge.
const SUPPORT_CLEARANCE_MM: f64 = 5.0;

/// One plate's cross-section and its span along the seam.
#[derive(Debug, Clone, PartialEq)]
pub struct PlateShape {
    pub profile_xz: Vec<[f64; 2]>,
    pub y_range: [f64; 2],
}

impl PlateShape {
    fn x_range(&self) -> [f64; 2] {
        self.profile_xz.iter().fold([f64::INFINITY, f64::NEG_INFINITY], |r, p| [r[0].min(p[0]), r[1].max(p[0])])
    }

    fn bottom_z(&self) -> f64 {
        self.profile_xz.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min)
    }

    /// The cross-section with its corner at `corner_xz` rounded to an arc
    /// of `radius_mm` tangent to both edges that meet there (a rolled
    /// section's edge), drawn as `segments` straight pieces so the plate
    /// stays a convex polygon. Unchanged when no corner lies there, or when
    /// the arc would not fit on the shorter edge.
    pub fn with_rounded_corner(&self, corner_xz: [f64; 2], radius_mm: f64, segments: usize) -> PlateShape {
        let n = self.profile_xz.len();
        let at = |p: [f64; 2]| (p[0] - corner_xz[0]).hypot(p[1] - corner_xz[1]) < MIN_EDGE_MM;
        let Some(k) = self.profile_xz.iter().position(|p| at(*p)) else { return self.clone() };
        let corner = self.profile_xz[k];
        let toward = |q: [f64; 2]| {
            let (dx, dz) = (q[0] - corner[0], q[1] - corner[1]);
            let length = dx.hypot(dz);
            ([dx / length, dz / length], length)
        };
        let (before, before_length) = toward(self.profile_xz[(k + n - 1) % n]);
        let (after, after_length) = toward(self.profile_xz[(k + 1) % n]);
        // The arc's centre lies on the bisector, where it is `radius` from
        // both edges; it touches them `tangent` from the corner.
        let half_angle = 0.5 * (before[0] * after[0] + before[1] * after[1]).clamp(-1.0, 1.0).acos();
        let tangent = radius_mm / half_angle.tan();
        if !(radius_mm > 0.0 && segments > 0 && tangent < before_length.min(after_length)) {
            return self.clone();
        }
        let bisector = [before[0] + after[0], before[1] + after[1]];
        let bisector_length = bisector[0].hypot(bisector[1]);
        let to_centre = radius_mm / half_angle.sin() / bisector_length;
        let centre = [corner[0] + bisector[0] * to_centre, corner[1] + bisector[1] * to_centre];
        let from = [corner[0] + before[0] * tangent, corner[1] + before[1] * tangent];
        let to = [corner[0] + after[0] * tangent, corner[1] + after[1] * tangent];
        let angle = |p: [f64; 2]| (p[1] - centre[1]).atan2(p[0] - centre[0]);
        let (start, mut sweep) = (angle(from), angle(to) - angle(from));
        // The short way round: the arc turns through less than a half turn.
        if sweep > std::f64::consts::PI {
            sweep -= std::f64::consts::TAU;
        } else if sweep < -std::f64::consts::PI {
            sweep += std::f64::consts::TAU;
        }
        let arc = (0..=segments).map(|i| {
            let a = start + sweep * i as f64 / segments as f64;
            [centre[0] + radius_mm * a.cos(), centre[1] + radius_mm * a.sin()]
        });
        let mut profile_xz: Vec<[f64; 2]> = self.profile_xz[..k].to_vec();
        profile_xz.extend(arc);
        profile_xz.extend_from_slice(&self.profile_xz[k + 1..]);
        PlateShape { profile_xz, y_range: self.y_range }
    }
}

fn y_range(extent: &PlateExtent) -> [f64; 2] {
    [extent.offset_mm, extent.offset_mm + extent.length_mm]
}

impl JointGeometry {
    /// The cross-sections of plate A (x < 0; the upper plate of a lap) and
    /// plate B (x > 0; the lower plate of a lap).
    pub fn plate_shapes(&self, plate_a: &PlateExtent, plate_b: &PlateExtent) -> [PlateShape; 2] {
        let (a, b) = match *self {
            JointGeometry::IButt { thickness_mm: t, gap_mm } => {
                let h = gap_mm / 2.0;
                (rectangle(-plate_a.width_mm, -h, 0.0, t), rectangle(h, plate_b.width_mm, 0.0, t))
            }
            JointGeometry::VButt { thickness_mm: t, groove_depth_mm: d, root_gap_mm: r, .. } => {
                let bevel_x = self.seam_edge_half_width();
                let profile = |width: f64, side: f64| {
                    vec![
                        [side * width, 0.0],
                        [side * r / 2.0, 0.0],
                        [side * r / 2.0, t - d],
                        [side * bevel_x, t],
                        [side * width, t],
                    ]
                };
                (profile(plate_a.width_mm, -1.0), profile(plate_b.width_mm, 1.0))
            }
            JointGeometry::Lap { lower_thickness_mm: t1, upper_thickness_mm: t2, overlap_mm } => {
                (rectangle(-plate_a.width_mm, 0.0, t1, t1 + t2), rectangle(-overlap_mm, plate_b.width_mm, 0.0, t1))
            }
            JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h } => {
                (rectangle(-w / 2.0, w / 2.0, f, f + h), rectangle(-plate_a.width_mm, plate_b.width_mm, 0.0, f))
            }
            JointGeometry::Corner { kind, flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h, proud_mm } => {
                match kind {
                    // The web on the flange's end, outer faces flush.
                    CornerKind::Inside => (rectangle(-w, 0.0, f, f + h), rectangle(-w, plate_b.width_mm, 0.0, f)),
                    // The web beside the flange's end, reaching down from
                    // its top (to the table when the scene's spacers are
                    // as tall as the web's part under the flange).
                    CornerKind::Outside => {
                        (rectangle(-w, 0.0, f + proud_mm - h, f + proud_mm), rectangle(0.0, plate_b.width_mm, 0.0, f))
                    }
                }
            }
        };
        [
            PlateShape { profile_xz: a, y_range: y_range(plate_a) },
            PlateShape { profile_xz: b, y_range: y_range(plate_b) },
        ]
    }

    /// Distance from the seam line to each plate's top seam-side edge:
    /// half the gap, or half the groove's opening for a V; zero for a lap.
    pub fn seam_edge_half_width(&self) -> f64 {
        match *self {
            JointGeometry::IButt { gap_mm, .. } => gap_mm / 2.0,
            JointGeometry::VButt { groove_angle_deg, groove_depth_mm, root_gap_mm, .. } => {
                root_gap_mm / 2.0 + groove_depth_mm * (groove_angle_deg / 2.0).to_radians().tan()
            }
            JointGeometry::Lap { .. } | JointGeometry::Corner { .. } => 0.0,
            JointGeometry::Tee { web_thickness_mm, .. } => web_thickness_mm / 2.0,
        }
    }

    /// The weld roots as `(x, z)` of lines along y: the one seam of a butt
    /// or lap joint (at x = 0, [`JointGeometry::seam_z`] high), or a tee's
    /// two fillet roots, the -x side's first.
    pub fn seam_lines_xz(&self) -> Vec<[f64; 2]> {
        match *self {
            JointGeometry::Tee { flange_thickness_mm, web_thickness_mm, .. } => {
                vec![[-web_thickness_mm / 2.0, flange_thickness_mm], [web_thickness_mm / 2.0, flange_thickness_mm]]
            }
            _ => vec![[0.0, self.seam_z()]],
        }
    }

    /// The seam-side top edges whose visibility defines the observed seam,
    /// as `(x, z)` of lines along y: both plates' top edges for a butt
    /// joint; the upper plate's top edge and the root line for a lap; a
    /// tee's two roots; a corner's weld line twice.
    pub fn seam_edges_xz(&self) -> [[f64; 2]; 2] {
        match *self {
            JointGeometry::Lap { lower_thickness_mm: t1, upper_thickness_mm: t2, .. } => [[0.0, t1 + t2], [0.0, t1]],
            JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, .. } => [[-w / 2.0, f], [w / 2.0, f]],
            JointGeometry::Corner { flange_thickness_mm: f, .. } => [[0.0, f], [0.0, f]],
            _ => {
                let x = self.seam_edge_half_width();
                let t = self.top_z(0.0);
                [[-x, t], [x, t]]
            }
        }
    }

    /// Height of the true seam point (the weld root) above z = 0; a tee's
    /// roots lie on the flange's top.
    pub fn seam_z(&self) -> f64 {
        match *self {
            JointGeometry::Tee { flange_thickness_mm, .. } | JointGeometry::Corner { flange_thickness_mm, .. } => {
                flange_thickness_mm
            }
            JointGeometry::IButt { thickness_mm, .. } => thickness_mm,
            JointGeometry::VButt { thickness_mm, groove_depth_mm, .. } => thickness_mm - groove_depth_mm,
            JointGeometry::Lap { lower_thickness_mm, .. } => lower_thickness_mm,
        }
    }

    /// Height of the top surface at `x` across the seam; for a lap, the
    /// upper plate's top on its side (x < 0) and the lower one's beyond;
    /// for a tee, the web's top over it and the flange's beside it.
    pub fn top_z(&self, x: f64) -> f64 {
        match *self {
            JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h } => {
                if x.abs() <= w / 2.0 { f + h } else { f }
            }
            JointGeometry::Corner { kind, flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h, proud_mm } => {
                let web_top = match kind {
                    CornerKind::Inside => f + h,
                    CornerKind::Outside => f + proud_mm,
                };
                if (-w..=0.0).contains(&x) { web_top } else { f }
            }
            JointGeometry::IButt { thickness_mm, .. } | JointGeometry::VButt { thickness_mm, .. } => thickness_mm,
            JointGeometry::Lap { lower_thickness_mm, upper_thickness_mm, .. } => {
                if x < 0.0 {
                    lower_thickness_mm + upper_thickness_mm
                } else {
                    lower_thickness_mm
                }
            }
        }
    }
}

fn rectangle(x0: f64, x1: f64, z0: f64, z1: f64) -> Vec<[f64; 2]> {
    vec![[x0, z0], [x1, z0], [x1, z1], [x0, z1]]
}

/// Builds the scene in the (first) workpiece's frame: every workpiece's
/// plates and spacers, the faults and the table.
pub fn build_scene(spec: &SceneSpec) -> Scene {
    build_scene_reshaped(spec, |_, _| {})
}

/// [`build_scene`] with each workpiece's plate cross-sections (its index,
/// then plates A and B as [`JointGeometry::plate_shapes`] gives them)
/// changed by `reshape` before they are extruded: a family whose plates
/// differ from the joint's in a detail (an edge rounded) keeps the rest of
/// the scene, the spacers under the reshaped plates included.
pub fn build_scene_reshaped(spec: &SceneSpec, reshape: impl Fn(usize, &mut [PlateShape; 2])) -> Scene {
    let table_top = -spec.spacer_height_mm;
    let mut solids: Vec<ConvexSolid> = Vec::new();
    for (k, workpiece) in spec.workpieces().iter().enumerate() {
        let pose = workpiece.pose();
        let mut shapes = workpiece.joint.plate_shapes(&workpiece.plate_a, &workpiece.plate_b);
        reshape(k, &mut shapes);
        let own = workpiece_solids(&workpiece.joint, &shapes, table_top);
        solids.extend(own.iter().map(|s| s.transformed(&pose)));
    }
    solids.extend(super::faults::fault_solids(spec));
    solids.extend(ConvexSolid::cuboid(
        SurfaceKind::Table,
        Vec3::new(-TABLE_HALF_SIDE_MM, -TABLE_HALF_SIDE_MM, table_top - TABLE_THICKNESS_MM),
        Vec3::new(TABLE_HALF_SIDE_MM, TABLE_HALF_SIDE_MM, table_top),
    ));
    Scene { solids }
}

/// One workpiece's plates and the spacers carrying them, in its own frame.
fn workpiece_solids(joint: &JointGeometry, shapes: &[PlateShape; 2], table_top: f64) -> Vec<ConvexSolid> {
    let mut solids: Vec<ConvexSolid> =
        shapes.iter().filter_map(|s| ConvexSolid::extruded(SurfaceKind::Plate, &s.profile_xz, s.y_range)).collect();
    let [a, b] = shapes;
    solids.extend(spacers_under(b, b.x_range(), table_top));
    match *joint {
        JointGeometry::Lap { overlap_mm, .. } => {
            // The upper plate lies on the lower one and overhangs its edge;
            // a raised block carries the overhang as it would on a fixture.
            let [x0, _] = a.x_range();
            let support_end = -overlap_mm - SUPPORT_CLEARANCE_MM + SPACER_INSET_MM;
            solids.extend(spacers_under(a, [x0, support_end], table_top));
        }
        // The web stands on the flange (or, beside an outside corner's
        // flange, on the table).
        JointGeometry::Tee { .. } | JointGeometry::Corner { .. } => {}
        _ => solids.extend(spacers_under(a, a.x_range(), table_top)),
    }
    solids
}

/// Two blocks across the plate near its ends, inset from its edges,
/// filling the space from the table to the plate's bottom.
fn spacers_under(shape: &PlateShape, x_range: [f64; 2], table_top: f64) -> Vec<ConvexSolid> {
    let [x0, x1] = x_range;
    let [y0, y1] = shape.y_range;
    let (bx0, bx1) = (x0 + SPACER_INSET_MM, x1 - SPACER_INSET_MM);
    let top = shape.bottom_z();
    let length = SPACER_LENGTH_MM.min((y1 - y0 - 3.0 * SPACER_INSET_MM) / 2.0);
    if bx1 - bx0 < 1.0 || length < 1.0 || top <= table_top {
        return Vec::new();
    }
    [[y0 + SPACER_INSET_MM, y0 + SPACER_INSET_MM + length], [y1 - SPACER_INSET_MM - length, y1 - SPACER_INSET_MM]]
        .iter()
        .filter_map(|&[ya, yb]| {
            ConvexSolid::cuboid(SurfaceKind::Spacer, Vec3::new(bx0, ya, table_top), Vec3::new(bx1, yb, top))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> ConvexSolid {
        ConvexSolid::cuboid(SurfaceKind::Plate, Vec3::new(-1.0, -2.0, -3.0), Vec3::new(1.0, 2.0, 3.0)).unwrap()
    }

    #[test]
    fn a_ray_through_a_box_enters_and_leaves_at_its_faces() {
        let b = unit_box();
        let span = b.clip(&Vec3::new(0.5, 0.5, 10.0), &Vec3::new(0.0, 0.0, -1.0), 0.0, f64::INFINITY).unwrap();
        assert!((span.enter - 7.0).abs() < 1e-12 && (span.exit - 13.0).abs() < 1e-12);
        assert_eq!(span.normal, Some(Vec3::new(0.0, 0.0, 1.0)));
        // Oblique, entering through the +x face.
        let span = b.clip(&Vec3::new(5.0, 0.0, 0.0), &Vec3::new(-1.0, 0.0, 0.1), 0.0, f64::INFINITY).unwrap();
        assert!((span.enter - 4.0).abs() < 1e-12);
        assert_eq!(span.normal, Some(Vec3::new(1.0, 0.0, 0.0)));
    }

    #[test]
    fn rays_that_miss_or_stop_short_do_not_hit() {
        let b = unit_box();
        let down = Vec3::new(0.0, 0.0, -1.0);
        assert!(b.clip(&Vec3::new(1.5, 0.0, 10.0), &down, 0.0, 100.0).is_none());
        assert!(b.clip(&Vec3::new(0.0, 0.0, 10.0), &down, 0.0, 6.0).is_none());
        // Pointing away: the box is behind the origin.
        assert!(b.clip(&Vec3::new(0.0, 0.0, 10.0), &-down, 0.0, 100.0).is_none());
        // Parallel to a face, outside it.
        assert!(b.clip(&Vec3::new(0.0, 2.5, 10.0), &down, 0.0, 100.0).is_none());
    }

    #[test]
    fn transformed_solids_keep_their_hits() {
        let b = unit_box();
        let iso = Isometry3::new(Vec3::new(10.0, -5.0, 100.0), Vec3::new(0.3, -0.2, 1.1));
        let moved = b.transformed(&iso);
        let origin = Vec3::new(0.2, 0.3, 10.0);
        let dir = Vec3::new(0.05, -0.02, -1.0);
        let here = b.clip(&origin, &dir, 0.0, 1e9).unwrap();
        let there = moved.clip(&iso.transform_point(&origin.into()).coords, &(iso.rotation * dir), 0.0, 1e9).unwrap();
        assert!((here.enter - there.enter).abs() < 1e-9);
        assert!((here.exit - there.exit).abs() < 1e-9);
        let n = iso.rotation * here.normal.unwrap();
        assert!((n - there.normal.unwrap()).norm() < 1e-12);
        for v in moved.vertices() {
            assert!(moved.excess(v).abs() < 1e-9);
        }
    }

    #[test]
    fn a_tees_web_stands_on_its_flange_along_both_roots() {
        let joint = JointGeometry::Tee { flange_thickness_mm: 10.0, web_thickness_mm: 6.0, web_height_mm: 50.0 };
        let web_extent = PlateExtent { width_mm: 80.0, length_mm: 200.0, offset_mm: 10.0 };
        let flange_extent = PlateExtent { width_mm: 100.0, length_mm: 240.0, offset_mm: 0.0 };
        let [web, flange] = joint.plate_shapes(&web_extent, &flange_extent);
        let web = ConvexSolid::extruded(SurfaceKind::Plate, &web.profile_xz, web.y_range).unwrap();
        let flange = ConvexSolid::extruded(SurfaceKind::Plate, &flange.profile_xz, flange.y_range).unwrap();
        assert_eq!(joint.seam_lines_xz(), [[-3.0, 10.0], [3.0, 10.0]]);
        for [x, z] in joint.seam_lines_xz() {
            for y in [10.0, 110.0, 210.0] {
                // On the web's side face and the flange's top at once.
                let root = Vec3::new(x, y, z);
                assert!(web.excess(&root).abs() < 1e-12 && flange.excess(&root).abs() < 1e-12, "{root:?}");
            }
        }
        // The flange spans -80 to 100 mm across, the web's top is 60 mm up.
        assert!(flange.excess(&Vec3::new(-80.0, 5.0, 10.0)).abs() < 1e-12);
        assert!(flange.excess(&Vec3::new(100.0, 5.0, 0.0)).abs() < 1e-12);
        assert!(web.excess(&Vec3::new(0.0, 100.0, 60.0)).abs() < 1e-12);
        assert_eq!((joint.top_z(0.0), joint.top_z(3.5), joint.seam_edge_half_width()), (60.0, 10.0, 3.0));
    }

    #[test]
    fn a_rounded_corner_is_an_arc_tangent_to_both_edges() {
        let flange = PlateShape { profile_xz: rectangle(-20.0, 100.0, 0.0, 10.0), y_range: [0.0, 200.0] };
        let rounded = flange.with_rounded_corner([-20.0, 10.0], 4.0, 8);
        // The corner gives way to 9 points: 4 + 8 in all.
        assert_eq!(rounded.profile_xz.len(), 12);
        for p in &rounded.profile_xz[3..12] {
            assert!(((p[0] + 16.0).hypot(p[1] - 6.0) - 4.0).abs() < 1e-9, "{p:?}");
        }
        // It starts on the top (4 mm in from the edge) and ends on the edge's face (4 mm down).
        assert!((rounded.profile_xz[3][0] + 16.0).abs() < 1e-9 && (rounded.profile_xz[3][1] - 10.0).abs() < 1e-9);
        assert!((rounded.profile_xz[11][0] + 20.0).abs() < 1e-9 && (rounded.profile_xz[11][1] - 6.0).abs() < 1e-9);
        let solid = ConvexSolid::extruded(SurfaceKind::Plate, &rounded.profile_xz, rounded.y_range).unwrap();
        // The sharp corner is cut away; the arc's middle is on the surface.
        assert!(solid.excess(&Vec3::new(-20.0, 50.0, 10.0)) > 1.0);
        let middle = 4.0 * std::f64::consts::FRAC_1_SQRT_2;
        assert!(solid.excess(&Vec3::new(-16.0 - middle, 50.0, 6.0 + middle)).abs() < 0.1);
        // No such corner, or a radius that does not fit: unchanged.
        assert_eq!(flange.with_rounded_corner([-21.0, 10.0], 4.0, 8), flange);
        assert_eq!(flange.with_rounded_corner([-20.0, 10.0], 12.0, 8), flange);
    }

    #[test]
    fn a_tees_spacers_carry_the_flange_only() {
        let spec = crate::sim::demo_scene(crate::joint::JointType::TFillet);
        let scene = build_scene(&spec);
        let spacers: Vec<&ConvexSolid> = scene.solids.iter().filter(|s| s.kind == SurfaceKind::Spacer).collect();
        assert_eq!(spacers.len(), 2);
        for s in spacers {
            // From the table up to the flange's bottom, nowhere into it.
            let top = s.vertices().iter().map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
            assert!(top.abs() < 1e-12, "{top}");
        }
        assert_eq!(scene.solids.iter().filter(|s| s.kind == SurfaceKind::Plate).count(), 2);
    }

    #[test]
    fn a_full_depth_v_groove_drops_its_root_face() {
        let joint =
            JointGeometry::VButt { thickness_mm: 8.0, groove_angle_deg: 60.0, groove_depth_mm: 8.0, root_gap_mm: 0.0 };
        let extent = PlateExtent { width_mm: 100.0, length_mm: 200.0, offset_mm: 0.0 };
        let [a, b] = joint.plate_shapes(&extent, &extent);
        let a = ConvexSolid::extruded(SurfaceKind::Plate, &a.profile_xz, a.y_range).unwrap();
        let b = ConvexSolid::extruded(SurfaceKind::Plate, &b.profile_xz, b.y_range).unwrap();
        // y ends, bottom, bevel, top, outer side: the root face is gone.
        assert_eq!(a.planes().len(), 6);
        let bevel_top = 8.0 * 30f64.to_radians().tan();
        assert!(a.excess(&Vec3::new(-bevel_top, 50.0, 8.0)).abs() < 1e-12);
        assert!(b.excess(&Vec3::new(0.0, 50.0, 0.0)).abs() < 1e-12);
        assert!(b.excess(&Vec3::new(bevel_top / 2.0, 50.0, 4.0)).abs() < 1e-12);
    }
}
