//! Whether two coplanar pieces of a layer are one plate the image cut: a
//! narrow break between them that runs on, straight in the image, across
//! the surface behind them.
//!
//! A specular streak (a line of saturated structured light, depths off by
//! millimetres) or a thin dropout crosses the image in a straight line,
//! whatever depth each surface under it lies at; where it crosses a plate
//! the plane criterion leaves two coplanar pieces with a narrow break
//! between them, as two butt plates with a square gap look. The two tell
//! apart behind the pieces: a gap between plates is bounded by the plates
//! (past the seam's end the table or the plate under it is whole), while
//! a break in the image runs on across the surface behind, seen at its
//! own depth on the same line of the image. So the line of the break is
//! read in the image (the camera-frame points' `x / z`, `y / z`, scaled to
//! millimetres at the pieces' depth) from the two pieces' facing rims,
//! and followed out past the pieces over the layers behind them: where
//! that surface is seen on both sides of the line close to it, it is
//! either seen on the line too (whole: a physical gap) or not (broken).
//!
//! A break read so must be narrow ([`IMAGE_BREAK_MAX_MM`]: a streak is a
//! few pixels wide, a V-groove's mouth and a slot in a table far wider)
//! and run on broken, from where the surface behind is first seen beside
//! the line, for at least [`RUN_ON_MIN_MM`]. Only positive evidence
//! counts: a frame that shows nothing behind the pieces on the line keeps
//! them two plates.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::cloud::Point;
use crate::geometry::fit::Moments;
use crate::geometry::{Vec3, vec3};

use super::PlaneCluster;
use super::placement::spacing_of;

/// The widest break between two coplanar pieces read as one in the image,
/// mm at the pieces' depth: a streak of bad depths or a dropout a few
/// pixels wide. A square butt gap may be as narrow; what tells the two
/// apart is the surface behind, not the width.
pub(super) const IMAGE_BREAK_MAX_MM: f64 = 3.0;

/// How far the break must run on broken across the surface behind the
/// pieces, mm along its line, counted from where that surface is first
/// seen beside the line: a few millimetres, more than the noise of the
/// line's fit carried past the pieces and more than a mixed return at a
/// plate's end leaves empty.
pub(super) const RUN_ON_MIN_MM: f64 = 4.0;

/// How far past the pieces' rims the break is followed over the surface
/// behind, mm along its line: far enough to cross a lap step's shadow and
/// a strip of the plate under it, not so far that the line's direction,
/// read over the pieces' rims, has drifted off the break.
const FOLLOW_MM: f64 = 60.0;

/// How many points of each piece the rims are read from, at most.
const RIM_SAMPLES: usize = 40_000;

/// The fewest rim points on each side of the break to read its line.
const MIN_RIM_POINTS: usize = 8;

/// What shows a break between two pieces is the image's: its width and
/// how far it runs on, broken, over the surface behind them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageBreak {
    pub width_mm: f64,
    pub run_on_mm: f64,
}

/// A point in the image plane scaled to millimetres at `depth` (camera
/// frame: the camera at the origin looking along +z); None behind the
/// camera.
fn in_image(p: &Vec3, depth: f64) -> Option<[f64; 2]> {
    (p.z > 0.0).then(|| [p.x / p.z * depth, p.y / p.z * depth])
}

/// A cluster's points in the image at one depth, sampled, and their
/// spacing there.
struct InImage {
    points: Vec<[f64; 2]>,
    spacing_mm: f64,
}

impl InImage {
    fn of(c: &PlaneCluster, points: &[Point], depth: f64) -> InImage {
        let stride = (c.members.len() / RIM_SAMPLES).max(1);
        let sampled = c
            .members
            .iter()
            .step_by(stride)
            .filter_map(|&i| points.get(i as usize))
            .map(vec3)
            .filter(|p| p.iter().all(|v| v.is_finite()))
            .filter_map(|p| in_image(&p, depth))
            .collect();
        InImage { points: sampled, spacing_mm: spacing_of(c) * (stride as f64).sqrt() }
    }
}

/// The break between `a` and `b` (seen at `depth`) when it is a break in
/// the image: at most [`IMAGE_BREAK_MAX_MM`] wide between their facing
/// rims, and running on broken over `behind` for [`RUN_ON_MIN_MM`].
fn image_break(a: &InImage, b: &InImage, behind: &[&PlaneCluster], points: &[Point], depth: f64) -> Option<ImageBreak> {
    if depth <= 0.0 || behind.is_empty() {
        return None;
    }
    let spacing = a.spacing_mm.max(b.spacing_mm);
    let reach = IMAGE_BREAK_MAX_MM + 2.0 * spacing;
    let (a_near, b_near) = (near(&a.points, &b.points, reach), near(&b.points, &a.points, reach));
    let rim_a = rim_of(&a_near, &b_near, reach)?;
    let rim_b = rim_of(&b_near, &a_near, reach)?;
    let line = BreakLine::through(&rim_a, &rim_b, spacing)?;
    if line.width_mm > IMAGE_BREAK_MAX_MM {
        return None;
    }
    let run_on_mm = line.run_on_behind(behind, points, depth);
    (run_on_mm >= RUN_ON_MIN_MM).then_some(ImageBreak { width_mm: line.width_mm, run_on_mm })
}

/// A piece of a layer set apart as part of a larger cluster of it, which
/// a break in the image cut: their places in the layer (largest first)
/// and what was read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutPiece {
    pub piece: usize,
    pub of: usize,
    pub found: ImageBreak,
}

/// The clusters of `layer` (largest first) that are pieces of a larger
/// cluster of it cut off by a break in the image running on over
/// `behind`, each named once, against the largest cluster it is cut from.
pub fn cut_pieces(layer: &[PlaneCluster], behind: &[&PlaneCluster], points: &[Point]) -> Vec<CutPiece> {
    if layer.len() < 2 || behind.is_empty() {
        return Vec::new();
    }
    let depth = layer[0].centroid.z;
    let seen: Vec<InImage> = layer.iter().map(|c| InImage::of(c, points, depth)).collect();
    (1..layer.len())
        .filter_map(|piece| {
            (0..piece).find_map(|of| {
                image_break(&seen[of], &seen[piece], behind, points, depth).map(|found| CutPiece { piece, of, found })
            })
        })
        .collect()
}

/// The most cells a side of [`near`]'s grid has: a frame whose pieces
/// spread further apart than this many reaches gets coarser cells, which
/// keep every point they must and a few more.
const NEAR_GRID_CELLS: f64 = 1024.0;

/// The points of `of` in or beside a cell of a grid at least `reach` wide
/// that holds a point of `other`: every point within `reach` of `other`,
/// and none far from it, so the nearest-point search runs over the rims
/// only (two plates side by side hold hundreds of thousands of points
/// each). The grid is a dense bitmap over both sets' bounds.
fn near(of: &[[f64; 2]], other: &[[f64; 2]], reach: f64) -> Vec<[f64; 2]> {
    let all = || of.iter().chain(other);
    let (x0, x1) = crate::geometry::extent(all().map(|p| p[0]));
    let (y0, y1) = crate::geometry::extent(all().map(|p| p[1]));
    if !(x0 <= x1 && y0 <= y1) {
        return Vec::new();
    }
    let cell_mm = reach.max((x1 - x0) / NEAR_GRID_CELLS).max((y1 - y0) / NEAR_GRID_CELLS);
    let (nx, ny) = (((x1 - x0) / cell_mm) as usize + 1, ((y1 - y0) / cell_mm) as usize + 1);
    let cell = |p: &[f64; 2]| (((p[0] - x0) / cell_mm) as usize, ((p[1] - y0) / cell_mm) as usize);
    let mut held = vec![false; nx * ny];
    for q in other {
        let (x, y) = cell(q);
        held[y * nx + x] = true;
    }
    let beside_held = |(x, y): (usize, usize)| {
        (y.saturating_sub(1)..=(y + 1).min(ny - 1))
            .any(|row| (x.saturating_sub(1)..=(x + 1).min(nx - 1)).any(|col| held[row * nx + col]))
    };
    of.iter().filter(|p| beside_held(cell(p))).copied().collect()
}

/// The points of `of` within `reach` of `other`, each with its nearest
/// point of `other` and how far that is: the rim of one piece facing the
/// other. None when too few face it.
fn rim_of(of: &[[f64; 2]], other: &[[f64; 2]], reach: f64) -> Option<Vec<Facing>> {
    if of.len() < MIN_RIM_POINTS || other.is_empty() {
        return None;
    }
    let tree = ImmutableKdTree::new_from_slice(other).ok()?;
    let reach_sq = reach * reach;
    let rim: Vec<Facing> = of
        .iter()
        .filter_map(|p| {
            let nearest = tree.query(p).nearest_one::<SquaredEuclidean<f64>>().execute();
            let q = other.get(nearest.item as usize)?;
            (nearest.distance <= reach_sq).then(|| Facing {
                midpoint: [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])],
                distance: nearest.distance.sqrt(),
            })
        })
        .collect();
    (rim.len() >= MIN_RIM_POINTS).then_some(rim)
}

/// A rim point of one piece and its nearest point of the other: the
/// middle between them and how far apart they are.
#[derive(Debug, Clone, Copy)]
struct Facing {
    midpoint: [f64; 2],
    distance: f64,
}

/// The break's line in the image, through its middle and along it, with
/// how wide the break is and how far the pieces face each other along it.
struct BreakLine {
    origin: [f64; 2],
    along: [f64; 2],
    across: [f64; 2],
    /// The pieces' facing edges' reach along the line, from `origin`.
    span: [f64; 2],
    width_mm: f64,
    spacing_mm: f64,
}

impl BreakLine {
    /// The line through the middles of the facing edges' points: the
    /// rims' points whose nearest point across lies within two spacings
    /// of the least such distance (points of one piece facing the other
    /// across the break, and the row behind them, not those along its
    /// side); the break as wide as the tenth percentile of those
    /// distances, the edges' narrowest stretch but for a stray point.
    fn through(rim_a: &[Facing], rim_b: &[Facing], spacing_mm: f64) -> Option<BreakLine> {
        let least = rim_a.iter().chain(rim_b).map(|f| f.distance).fold(f64::INFINITY, f64::min);
        let edges: Vec<&Facing> =
            rim_a.iter().chain(rim_b).filter(|f| f.distance <= least + 2.0 * spacing_mm).collect();
        if edges.len() < 2 * MIN_RIM_POINTS {
            return None;
        }
        // The least-squares line through the middles, in the image plane.
        let moments: Moments = edges.iter().map(|f| Vec3::new(f.midpoint[0], f.midpoint[1], 0.0)).collect();
        let (centre, direction) = moments.line()?;
        let (mean, along) = ([centre.x, centre.y], [direction.x, direction.y]);
        let across = [-along[1], along[0]];
        let (lo, hi) = crate::geometry::extent(
            edges.iter().map(|f| (f.midpoint[0] - mean[0]) * along[0] + (f.midpoint[1] - mean[1]) * along[1]),
        );
        let mut distances: Vec<f64> = edges.iter().map(|f| f.distance).collect();
        distances.sort_by(f64::total_cmp);
        Some(BreakLine {
            origin: mean,
            along,
            across,
            span: [lo, hi],
            width_mm: distances[distances.len() / 10],
            spacing_mm,
        })
    }

    /// How far the break runs on broken over `behind`, mm: past either end
    /// of the rims, the surface behind read in bins along the line, each
    /// bin where it is seen close to the line on both sides either whole
    /// (seen on the line) or broken; the longest run of broken bins from
    /// the first bin so seen, on either side, stopping at a whole one.
    fn run_on_behind(&self, behind: &[&PlaneCluster], points: &[Point], depth: f64) -> f64 {
        let bin_mm = (2.0 * self.spacing_mm).max(0.5);
        let bins = (FOLLOW_MM / bin_mm).ceil() as usize;
        // Within `gap` of the line a break leaves the surface unseen; it is
        // seen beside the line out to `beside`.
        let gap = (0.5 * self.width_mm - 0.5 * self.spacing_mm).max(0.25 * self.width_mm);
        let beside = 0.5 * self.width_mm + 3.0 * self.spacing_mm;
        // Per side of the rims (before, after), per bin: seen left of the
        // line, right of it, on it.
        let mut seen = vec![[[false; 3]; 2]; bins];
        for c in behind {
            for p in c.members.iter().filter_map(|&i| points.get(i as usize)).map(vec3) {
                let Some(q) = in_image(&p, depth) else { continue };
                let d = [q[0] - self.origin[0], q[1] - self.origin[1]];
                let across = d[0] * self.across[0] + d[1] * self.across[1];
                if across.abs() > beside {
                    continue;
                }
                let along = d[0] * self.along[0] + d[1] * self.along[1];
                let (side, past) = if along < self.span[0] {
                    (0, self.span[0] - along)
                } else if along > self.span[1] {
                    (1, along - self.span[1])
                } else {
                    continue;
                };
                let bin = (past / bin_mm) as usize;
                if bin >= bins {
                    continue;
                }
                let slot = if across.abs() < gap {
                    2
                } else if across < 0.0 {
                    0
                } else {
                    1
                };
                seen[bin][side][slot] = true;
            }
        }
        let run = |side: usize| {
            let mut broken = 0usize;
            for bin in &seen {
                let [left, right, on] = bin[side];
                if !(left && right) {
                    continue;
                }
                if on {
                    break;
                }
                broken += 1;
            }
            broken as f64 * bin_mm
        };
        run(0).max(run(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of points every 0.5 mm over x in `xs`, y in `ys` at depth
    /// `z`, with the pixels a break along x = y crosses (`width` wide)
    /// left out when `width` is positive.
    fn plane(xs: [f64; 2], ys: [f64; 2], z: f64, width: f64) -> Vec<Vec3> {
        let mut out = Vec::new();
        let mut x = xs[0];
        while x <= xs[1] {
            let mut y = ys[0];
            while y <= ys[1] {
                if width <= 0.0 || (x - y).abs() / 2f64.sqrt() >= width / 2.0 {
                    out.push(Vec3::new(x, y, z));
                }
                y += 0.5;
            }
            x += 0.5;
        }
        out
    }

    /// The pieces cut off a layer of two pieces on either side of x = y
    /// at 800 mm (y 0 to 30 mm, the break `upper_break` wide), over a
    /// plane at 810 mm (y -30 to 0) with a break `lower_break` wide in line
    /// with it in the image. Seen from straight above at this distance
    /// the image's axes are x and y, and a line through the optical axis
    /// stays one line at any depth.
    fn cut(upper_break: f64, lower_break: f64, with_lower: bool) -> Vec<CutPiece> {
        let mut all = plane([-40.0, 40.0], [0.0, 30.0], 800.0, upper_break);
        all.extend(plane([-40.0, 40.0], [-30.0, -0.5], 810.0, lower_break * 810.0 / 800.0));
        let points: Vec<Point> = all.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let mut layer = [
            PlaneCluster::of_points(&all, |p| p.z < 805.0 && p.x > p.y),
            PlaneCluster::of_points(&all, |p| p.z < 805.0 && p.x < p.y),
        ];
        layer.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
        let lower = PlaneCluster::of_points(&all, |p| p.z > 805.0);
        let behind: Vec<&PlaneCluster> = if with_lower { vec![&lower] } else { Vec::new() };
        cut_pieces(&layer, &behind, &points)
    }

    #[test]
    fn a_break_running_on_across_the_plane_behind_is_the_image_s() {
        let cuts = cut(1.5, 1.5, true);
        let [found] = cuts.as_slice() else { panic!("one piece cut off: {cuts:?}") };
        assert_eq!((found.piece, found.of), (1, 0));
        assert!(found.found.run_on_mm >= RUN_ON_MIN_MM && found.found.width_mm <= IMAGE_BREAK_MAX_MM, "{found:?}");
    }

    #[test]
    fn a_gap_between_two_plates_over_a_whole_table_is_not() {
        // The table seen whole past the seam's end, or not seen at all.
        assert_eq!(cut(1.5, 0.0, true), []);
        assert_eq!(cut(1.5, 1.5, false), []);
    }

    proptest::proptest! {
        /// The grid's filter keeps every point within the reach of the
        /// other piece: the rims read from the filtered points are the
        /// rims read from all of them, point for point.
        #[test]
        fn the_grid_filter_keeps_every_rim_point(
            a in proptest::collection::vec((-20.0f64..5.0, -20.0f64..20.0), 1..300),
            b in proptest::collection::vec((-5.0f64..20.0, -20.0f64..20.0), 1..300),
            reach in 0.5f64..6.0,
        ) {
            let a: Vec<[f64; 2]> = a.into_iter().map(|(x, y)| [x, y]).collect();
            let b: Vec<[f64; 2]> = b.into_iter().map(|(x, y)| [x, y]).collect();
            let distances = |rim: Option<Vec<Facing>>| -> Vec<u64> {
                rim.unwrap_or_default().iter().map(|f| f.distance.to_bits()).collect()
            };
            // The reference: every point of `a` against every point of `b`.
            let by_hand: Vec<[f64; 2]> = a
                .iter()
                .filter(|p| b.iter().any(|q| (p[0] - q[0]).hypot(p[1] - q[1]) <= reach))
                .copied()
                .collect();
            let filtered = near(&a, &b, reach);
            proptest::prop_assert!(by_hand.iter().all(|p| filtered.contains(p)));
            proptest::prop_assert_eq!(
                distances(rim_of(&filtered, &near(&b, &a, reach), reach)),
                distances(rim_of(&a, &b, reach))
            );
        }
    }

    #[test]
    fn a_wide_break_is_no_image_s_even_where_the_surface_behind_breaks_too() {
        // A 6 mm groove's mouth over a slot of a table in line with it.
        assert_eq!(cut(6.0, 6.0, true), []);
    }
}
