//! The image's border as the cloud itself shows it, for reading where a
//! seam leaves the view in a cloud that has lost its pixel grid.
//!
//! A pinhole camera's image is bounded by four planes through its optical
//! centre, the origin of the camera frame: `x / z` and `y / z` each between
//! a least and a greatest value (`u = fx·x/z + cx` and `v = fy·y/z + cy`
//! run from the first pixel to the last). Depth noise and mixed returns
//! move a point along its ray, which keeps both ratios, so the cloud's own
//! extremes of the two ratios give the four planes, whatever was done to
//! the cloud after the camera (its grid dropped, voxel-downsampled, in
//! metres or the base frame, both brought back to the camera's frame and
//! millimetres by the input stage). A voxel's centroid lies inside the
//! border by up to half a voxel, but among the hundreds of voxels along
//! each side of the image some lie on it.
//!
//! What it is for: evidence read a few spacings off a seam (a web face's
//! foot, the flange beside a fillet root) ends where an image border
//! crosses that evidence, which is before or after the border crosses the
//! seam itself when the border runs obliquely across it (a spacing off
//! the seam, times the slant). Where every kind of evidence near an end
//! reaches the border, the seam is seen up to the border and ends where
//! it crosses it ([`ViewBorder::end_at_border`]). A butt or lap plate's
//! weld edge, read in strips two spacings wide that a border crossing it
//! obliquely cuts part way, runs on to the border where the plate's rim
//! beside it does ([`ViewBorder::edge_extent_at_border`]). A lap's root,
//! a plate thickness below the edges read, is clipped to the view the
//! same way where the frame has no grid to project it onto
//! ([`ViewBorder::outside_mm`], from `Context::clip_to_view`).
//!
//! A cloud that is not one camera's view (cropped, or merged from several)
//! has extremes that are no border: its evidence then does not lie on the
//! plane of an extreme near the seam's end except by chance, and the move
//! is bounded by the caller.

use rayon::prelude::*;

use crate::cloud::{Point, PointCloud, is_valid_point};
use crate::geometry::Vec3;

use super::refit::SeamCurve;

/// The four planes bounding the view, each as its unit normal out of the
/// view: a point `p` lies inside when `normal · p ≤ 0` for all four.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewBorder {
    outward: [Vec3; 4],
}

/// Which end of a span is moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpanEnd {
    /// The end at the span's least parameter.
    Start,
    /// The end at its greatest.
    End,
}

impl SpanEnd {
    /// +1 where the parameter grows out of the span at this end.
    fn outward(self) -> f64 {
        match self {
            SpanEnd::Start => -1.0,
            SpanEnd::End => 1.0,
        }
    }
}

/// The fewest valid points a border is read from.
const MIN_POINTS: usize = 100;

/// The least and greatest `x / z` and `y / z` of the points added, and
/// how many were.
#[derive(Debug, Clone, Copy)]
struct Extremes {
    count: usize,
    tangents: [f64; 4],
}

impl Default for Extremes {
    fn default() -> Self {
        Extremes { count: 0, tangents: [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY] }
    }
}

impl Extremes {
    fn add(mut self, p: &Point) -> Self {
        let (tx, ty) = (f64::from(p[0]) / f64::from(p[2]), f64::from(p[1]) / f64::from(p[2]));
        let t = &mut self.tangents;
        *t = [t[0].min(tx), t[1].max(tx), t[2].min(ty), t[3].max(ty)];
        self.count += 1;
        self
    }

    fn merge(self, other: Extremes) -> Self {
        let (a, b) = (self.tangents, other.tangents);
        Extremes {
            count: self.count + other.count,
            tangents: [a[0].min(b[0]), a[1].max(b[1]), a[2].min(b[2]), a[3].max(b[3])],
        }
    }
}

/// A point that bounds the view: a real return in front of the camera.
fn in_front(p: &Point) -> bool {
    is_valid_point(p) && p[2] > 0.0
}

/// The extremes of a row's or a column's first and last point in front
/// of the camera (one point if only one is; none if none is).
fn line_ends<'p>(mut line: impl DoubleEndedIterator<Item = &'p Point>) -> Extremes {
    let first = line.find(|p| in_front(p));
    let last = line.rfind(|p| in_front(p));
    first.into_iter().chain(last).fold(Extremes::default(), Extremes::add)
}

impl ViewBorder {
    /// The border of the view the cloud's valid points in front of the
    /// camera span; `None` for fewer than 100 of them (`MIN_POINTS`).
    ///
    /// On a pixel grid only the first and last valid pixel of every row
    /// and column are read: along a row `x / z` grows with the column (a
    /// pixel's point lies on its ray), so they hold the extremes, and a
    /// frame's border is read without a pass over its millions of points.
    pub fn of_cloud(cloud: &PointCloud) -> Option<ViewBorder> {
        let points = cloud.points();
        let extremes = if cloud.is_organized() && cloud.width() > 0 {
            let (width, height) = (cloud.width(), cloud.height());
            let rows =
                points.par_chunks(width).map(|row| line_ends(row.iter())).reduce(Extremes::default, Extremes::merge);
            let columns = (0..width)
                .into_par_iter()
                .map(|col| line_ends((0..height).map(|row| &points[row * width + col])))
                .reduce(Extremes::default, Extremes::merge);
            rows.merge(columns)
        } else {
            points
                .par_iter()
                .filter(|p| in_front(p))
                .fold(Extremes::default, |e, p| e.add(p))
                .reduce(Extremes::default, Extremes::merge)
        };
        (extremes.count >= MIN_POINTS).then(|| ViewBorder::from_tangents(extremes.tangents))
    }

    /// The border whose planes are `x / z` from `tangents[0]` to
    /// `tangents[1]` and `y / z` from `tangents[2]` to `tangents[3]`.
    pub fn from_tangents([x_lo, x_hi, y_lo, y_hi]: [f64; 4]) -> ViewBorder {
        // x ≤ x_hi·z  ⇔  (1, 0, −x_hi)·p ≤ 0, and so on for the others.
        let outward = [
            Vec3::new(-1.0, 0.0, x_lo),
            Vec3::new(1.0, 0.0, -x_hi),
            Vec3::new(0.0, -1.0, y_lo),
            Vec3::new(0.0, 1.0, -y_hi),
        ]
        .map(|n| n.normalize());
        ViewBorder { outward }
    }

    /// How far `p` lies outside the view, mm (negative inside): its
    /// signed distance from the border plane it lies furthest out of.
    pub fn outside_mm(&self, p: &Vec3) -> f64 {
        self.outward.iter().map(|n| n.dot(p)).fold(f64::NEG_INFINITY, f64::max)
    }

    /// Whether a plate's edge, given by its outermost points, runs along
    /// the border: at least half of them within `reach_mm` of it. A
    /// plate's cluster ends up to a neighbour radius inside its last
    /// returns (the rim the plane criterion trims), and those lie on the
    /// border where the border cuts the plate, so the caller's reach is
    /// that rim and a spacing or two. An edge that only touches the
    /// border (at a corner of the image, or of a crop) does not run along
    /// it; no points say nothing.
    pub fn runs_along(&self, edge: &[Vec3], reach_mm: f64) -> bool {
        let on_border = edge.iter().filter(|p| self.outside_mm(p) >= -reach_mm).count();
        !edge.is_empty() && 2 * on_border >= edge.len()
    }

    /// Where the line `origin + t · direction` (unit `direction`) leaves
    /// the view going out of its span at `end` from `at` (the span's end
    /// parameter there), when every evidence set holds a point within
    /// `reach_mm` of the plane it leaves by: the seam is then seen up to
    /// the border, whatever cut the evidence a little before or after it.
    ///
    /// `None` when the line does not leave the view through a plane the
    /// evidence reaches, leaves it at a grazing angle (under
    /// [`MIN_CROSSING_SIN`]), or when the crossing lies more than
    /// `max_move_mm` from `at`: the end is then not the border's.
    #[allow(clippy::too_many_arguments)]
    pub fn end_at_border(
        &self,
        origin: &Vec3,
        direction: &Vec3,
        end: SpanEnd,
        at: f64,
        evidence: &[&[Vec3]],
        reach_mm: f64,
        max_move_mm: f64,
    ) -> Option<f64> {
        let exit = self.exit(origin, direction, end)?;
        let reached = |set: &&[Vec3]| exit.reached_by(set, reach_mm);
        ((exit.t - at).abs() <= max_move_mm && !evidence.is_empty() && evidence.iter().all(reached)).then_some(exit.t)
    }

    /// The border plane the line `origin + t · direction` leaves the view
    /// by going out of its span at `end`: of the planes it heads out
    /// through at a sine of at least [`MIN_CROSSING_SIN`], the one it
    /// crosses first going outward.
    fn exit(&self, origin: &Vec3, direction: &Vec3, end: SpanEnd) -> Option<Exit> {
        let heading = *direction * end.outward();
        self.outward
            .iter()
            .map(|n| Exit { outward: *n, t: -n.dot(origin) / n.dot(direction), sine: n.dot(&heading) })
            .filter(|exit| exit.sine >= MIN_CROSSING_SIN)
            .min_by(|a, b| (end.outward() * a.t).total_cmp(&(end.outward() * b.t)))
    }
}

/// Where a line leaves the view: the border plane's outward unit normal,
/// the line's parameter at the crossing, and the sine of the angle it
/// crosses the plane at.
#[derive(Debug, Clone, Copy)]
struct Exit {
    outward: Vec3,
    t: f64,
    sine: f64,
}

impl Exit {
    /// Whether a point of `evidence` lies within `reach_mm` inside the
    /// plane the line leaves by.
    fn reached_by(&self, evidence: &[Vec3], reach_mm: f64) -> bool {
        evidence.iter().any(|p| self.outward.dot(p) >= -reach_mm)
    }
}

/// The least sine of the angle between a line and a border plane for the
/// crossing to set the line's end: at a grazing angle the evidence's reach
/// spreads far along the line.
pub const MIN_CROSSING_SIN: f64 = 0.17;

/// Evidence reaches the image's border when a point of it lies within
/// this many spacings inside it: a voxel's centroid lies up to half a
/// voxel inside, and the voxels nearest the border a little more.
pub const BORDER_REACH_SPACINGS: f64 = 1.5;

/// An edge's evidence at its end: its rim's points within this many
/// spacings of the end along the seam (two of the strips a boundary is
/// read in); and the farthest an end lies from the border it moves to,
/// across the border.
pub const END_EVIDENCE_SPACINGS: f64 = 4.0;

impl ViewBorder {
    /// The extent `(lo, hi)` of a plate's weld `edge` (along the seam's
    /// feature axis, as `along` reads a point), each end moved to where
    /// the edge crosses the image's border when the plate's `rim` (its
    /// points beside the edge) runs up to that border near the end: a point
    /// of it within a reach of the plane the edge crosses
    /// ([`Self::end_at_border`]).
    ///
    /// Without a pixel grid an edge's extent is read from strips two
    /// spacings wide, and a border crossing the edge obliquely cuts the
    /// last strip part way: its point stops short of where the edge
    /// leaves the view, by up to a strip and more where the edge's samples
    /// scatter too much for the rim's rows to be read. The rim itself
    /// shows whether the plate runs on to the border; if it does, so does
    /// its edge. An end moves to a border at most [`END_EVIDENCE_SPACINGS`]
    /// spacings from it, either way, measured across the border: a border
    /// crossing the edge at an angle θ thins the plate beside it to
    /// nothing over its width times cot θ, so the rim's rows, up to a
    /// spacing and a half inside the edge, end that far short of where
    /// the edge leaves the view, farther along the edge the more obliquely
    /// the border crosses it. An end the rim does not carry to the border
    /// (the plate's own end, a shadow) stays.
    pub fn edge_extent_at_border(
        &self,
        edge: &SeamCurve,
        (lo, hi): (f64, f64),
        rim: &[Vec3],
        along: impl Fn(&Vec3) -> f64,
        spacing_mm: f64,
    ) -> (f64, f64) {
        let reach = BORDER_REACH_SPACINGS * spacing_mm;
        let near = END_EVIDENCE_SPACINGS * spacing_mm;
        let moved = |end: SpanEnd, at: f64| {
            let evidence: Vec<Vec3> = rim.iter().copied().filter(|p| (along(p) - at).abs() <= near).collect();
            // The edge as a line at this end, `t` mm along it from `at`;
            // the feature coordinate grows by `per_t` a millimetre.
            let direction = edge.tangent(at);
            let per_t = direction.dot(&edge.axes.e);
            // An edge nearly across its feature axis has no ends along it.
            if per_t <= MIN_CROSSING_SIN {
                return at;
            }
            match self.exit(&edge.at(at), &direction, end) {
                Some(exit) if exit.t.abs() * exit.sine <= near && exit.reached_by(&evidence, reach) => {
                    at + exit.t * per_t
                }
                _ => at,
            }
        };
        let (moved_lo, moved_hi) = (moved(SpanEnd::Start, lo), moved(SpanEnd::End, hi));
        if moved_hi > moved_lo { (moved_lo, moved_hi) } else { (lo, hi) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A view 0.35 either side in `x / z` and 0.22 in `y / z` (the default
    /// camera's 700 × 440 mm at a metre).
    fn border() -> ViewBorder {
        ViewBorder::from_tangents([-0.35, 0.35, -0.22, 0.22])
    }

    #[test]
    fn the_border_is_read_from_the_points_rays_whatever_their_depth() {
        // Points on the four edges of the view at several depths, and
        // points inside; NaNs and points behind the camera ignored.
        let mut pts: Vec<[f32; 3]> = Vec::new();
        for k in 0..200 {
            let z = 400.0 + 3.0 * k as f32;
            let s = (k as f32 / 199.0) * 2.0 - 1.0;
            pts.push([0.35 * z, 0.22 * s * z, z]);
            pts.push([-0.35 * z, 0.1 * s * z, z]);
            pts.push([0.3 * s * z, 0.22 * z, z]);
            pts.push([0.2 * s * z, -0.22 * z, z]);
            pts.push([0.0, 0.0, z]);
        }
        pts.push([f32::NAN, 0.0, 500.0]);
        pts.push([900.0, 900.0, -10.0]);
        let cloud = PointCloud::unorganized(pts);
        let read = ViewBorder::of_cloud(&cloud).unwrap();
        let truth = border();
        for (a, b) in read.outward.iter().zip(&truth.outward) {
            assert!((a - b).norm() < 1e-6, "{a:?} against {b:?}");
        }
        assert!(read.outside_mm(&Vec3::new(0.0, 0.0, 700.0)) < -100.0);
        assert!(read.outside_mm(&Vec3::new(0.4 * 700.0, 0.0, 700.0)) > 0.0);
    }

    #[test]
    fn a_pixel_grid_gives_the_border_of_all_its_points_from_its_rows_and_columns_ends() {
        // A 64 × 40 pinhole frame with a ragged border: invalid pixels
        // eating into every side by a varying number, and a hole inside.
        let (width, height, f, c) = (64usize, 40usize, 80.0f32, [31.5f32, 19.5]);
        let mut pts = Vec::with_capacity(width * height);
        for v in 0..height {
            for u in 0..width {
                let z = 600.0 + 0.7 * u as f32 + 1.3 * v as f32;
                let ragged = u < v % 5 || u + (v * 7) % 4 >= width || v < u % 3 || v + u % 6 >= height + 2;
                let hole = (20..30).contains(&u) && (10..20).contains(&v);
                pts.push(if ragged || hole {
                    crate::cloud::INVALID_POINT
                } else {
                    [(u as f32 - c[0]) / f * z, (v as f32 - c[1]) / f * z, z]
                });
            }
        }
        let organized = PointCloud::organized(width, height, pts.clone()).unwrap();
        let unorganized = PointCloud::unorganized(pts);
        let (a, b) = (ViewBorder::of_cloud(&organized).unwrap(), ViewBorder::of_cloud(&unorganized).unwrap());
        for (a, b) in a.outward.iter().zip(&b.outward) {
            assert!((a - b).norm() < 1e-12, "{a:?} against {b:?}");
        }
    }

    #[test]
    fn too_few_points_give_no_border() {
        let cloud = PointCloud::unorganized(vec![[0.0, 0.0, 500.0]; MIN_POINTS - 1]);
        assert!(ViewBorder::of_cloud(&cloud).is_none());
    }

    /// A seam at depth 700 running obliquely towards the view's bottom
    /// border (`y / z = 0.22`, y = 154 mm at that depth).
    fn oblique_seam() -> (Vec3, Vec3) {
        (Vec3::new(-20.0, 100.0, 700.0), Vec3::new(0.6, 0.8, 0.0))
    }

    #[test]
    fn an_end_whose_evidence_reaches_the_border_moves_to_where_the_seam_crosses_it() {
        let (origin, direction) = oblique_seam();
        // The seam crosses y = 154 at t = 67.5.
        let crossing = (0.22 * 700.0 - 100.0) / 0.8;
        // Evidence a few mm beside the seam, ending at the border itself:
        // its last points lie 0.3 mm inside it, at t about 66 and 69.
        let beside = |off: f64, t: f64| origin + direction * t + Vec3::new(0.8, -0.6, 0.0) * off;
        let flange = [beside(2.0, 60.0), beside(3.0, 67.0 + 0.75 * 3.0 - 0.4)];
        let foot = [beside(-2.0, 60.0), beside(-1.5, 68.0 - 0.75 * 1.5 - 0.4)];
        let sets: [&[Vec3]; 2] = [&flange, &foot];
        let moved = border().end_at_border(&origin, &direction, SpanEnd::End, 66.5, &sets, 1.0, 4.0).unwrap();
        assert!((moved - crossing).abs() < 1e-9, "{moved} against {crossing}");
    }

    /// The edge of [`oblique_seam`] as a fitted curve, its feature axis
    /// along the edge.
    fn oblique_edge() -> SeamCurve {
        let (origin, direction) = oblique_seam();
        let axes =
            crate::pipeline::refit::SeamAxes { origin, e: direction, a: Vec3::new(0.8, -0.6, 0.0), b: Vec3::z() };
        SeamCurve { axes, coef_a: vec![0.0, 0.0], coef_b: vec![0.0, 0.0], s_min: -100.0, s_max: 60.0 }
    }

    #[test]
    fn an_edge_read_short_of_an_oblique_border_runs_on_to_it_where_its_plate_does() {
        let edge = oblique_edge();
        let along = |p: &Vec3| edge.axes.feature(p);
        // The edge leaves the view at 67.5 mm; its strips stopped at 64.
        let crossing = (0.22 * 700.0 - 100.0) / 0.8;
        let rim_point = |t: f64, inside: f64| edge.at(t) - edge.axes.a * inside;
        // The plate's rim, a spacing inside the edge, runs to within 0.3
        // mm of the border: the edge is seen up to it.
        let to_border: Vec<Vec3> = (0..12).map(|k| rim_point(60.0 + 0.6 * k as f64, 1.0)).collect();
        let to_border: Vec<Vec3> = to_border.into_iter().filter(|p| border().outside_mm(p) <= -0.3).collect();
        // `seam.end_at_image_border` moves the end out to the crossing.
        let (lo, hi) = border().edge_extent_at_border(&edge, (-50.0, 64.0), &to_border, along, 1.0);
        assert_eq!(lo, -50.0, "the start's rim is nowhere near a border");
        assert!((hi - crossing).abs() < 1e-9, "{hi} against {crossing}");
        // A plate that ends 3 mm before the border (its own end, a
        // shadow) keeps the end its strips read.
        let short: Vec<Vec3> = (0..8).map(|k| rim_point(58.0 + 0.6 * k as f64, 1.0)).collect();
        assert_eq!(border().edge_extent_at_border(&edge, (-50.0, 62.5), &short, along, 1.0), (-50.0, 62.5));
        // Nor does an end move further than the evidence's reach along it.
        assert_eq!(border().edge_extent_at_border(&edge, (-50.0, 60.0), &to_border, along, 1.0), (-50.0, 60.0));
    }

    #[test]
    fn an_edge_the_border_crosses_at_a_shallow_angle_runs_on_to_it_from_where_its_plate_thins_out() {
        // An edge at depth 700 heading into the bottom border (y/z = 0.22,
        // y = 154 mm) at a sine of 0.2, its plate on the border's side: the
        // border cuts the plate beside the edge before the edge itself, and
        // the plate thins to nothing over its width times cot θ (5.0).
        let direction = Vec3::new(0.2f64.mul_add(-0.2, 1.0).sqrt(), 0.2, 0.0);
        let (origin, outward) = (Vec3::new(-20.0, 140.0, 700.0), Vec3::new(0.2, -direction.x, 0.0));
        let axes = crate::pipeline::refit::SeamAxes { origin, e: direction, a: outward, b: Vec3::z() };
        let edge = SeamCurve { axes, coef_a: vec![0.0, 0.0], coef_b: vec![0.0, 0.0], s_min: -100.0, s_max: 60.0 };
        let along = |p: &Vec3| edge.axes.feature(p);
        let crossing = {
            let n = Vec3::new(0.0, 1.0, -0.22).normalize();
            -n.dot(&origin) / n.dot(&direction)
        };
        // The rim's rows, a spacing inside the edge, leave the view 4.9 mm
        // before the edge does (at 70 mm); the strips read the edge to
        // 62 mm, 8 mm short of the crossing (1.6 mm across the border).
        let rim: Vec<Vec3> = (0..40)
            .map(|k| edge.at(45.0 + 0.5 * k as f64) - outward)
            .filter(|p| border().outside_mm(p) <= -0.2)
            .collect();
        assert!(rim.iter().map(along).fold(f64::MIN, f64::max) < crossing - 4.5);
        let (lo, hi) = border().edge_extent_at_border(&edge, (-50.0, 62.0), &rim, along, 1.0);
        assert_eq!(lo, -50.0);
        assert!((hi - crossing).abs() < 1e-9, "{hi} against {crossing}");
    }

    #[test]
    fn an_end_is_not_moved_when_any_evidence_stops_short_of_the_border() {
        let (origin, direction) = oblique_seam();
        let on = |t: f64| origin + direction * t;
        // The flange reaches the border; the face's foot stops 3 mm short
        // of it (hidden, or the plate's end).
        let flange = [on(67.0)];
        let foot = [on(63.0)];
        let sets: [&[Vec3]; 2] = [&flange, &foot];
        assert_eq!(border().end_at_border(&origin, &direction, SpanEnd::End, 63.0, &sets, 1.0, 6.0), None);
        // With both reaching it, the move is bounded.
        let sets: [&[Vec3]; 2] = [&flange, &flange];
        assert_eq!(border().end_at_border(&origin, &direction, SpanEnd::End, 60.0, &sets, 1.0, 4.0), None);
        assert!(border().end_at_border(&origin, &direction, SpanEnd::End, 64.0, &sets, 1.0, 4.0).is_some());
    }

    #[test]
    fn the_start_moves_back_to_the_border_behind_it_and_a_grazing_seam_is_left_alone() {
        let (origin, direction) = oblique_seam();
        // Going backwards the seam leaves by the top border, y/z = −0.22
        // (y = −154 at 700 mm), at t = −317.5.
        let crossing = (-0.22 * 700.0 - 100.0) / 0.8;
        let at_border = [origin + direction * (crossing + 0.5)];
        let sets: [&[Vec3]; 1] = [&at_border];
        let moved = border().end_at_border(&origin, &direction, SpanEnd::Start, crossing + 1.0, &sets, 1.0, 4.0);
        assert!((moved.unwrap() - crossing).abs() < 1e-9);
        // A seam along the border, nearly parallel to it, sets no end by it.
        let along = Vec3::new(1.0, 0.05, 0.0).normalize();
        let start = Vec3::new(0.0, 0.22 * 700.0 - 0.5, 700.0);
        let sets: [&[Vec3]; 1] = [&[start]];
        assert_eq!(border().end_at_border(&start, &along, SpanEnd::End, 0.0, &sets, 1.0, 4.0), None);
    }
}
