//! Which plate of a layer a nearer plane stands beside: a lap's lower
//! plate under its upper plate's edge, a tee's flange piece on each side
//! of its web, read as steps across a coarse grid of the plane.

use crate::cloud::Point;
use crate::geometry::{Vec3, plane_axes};

use super::PlaneCluster;
use super::placement::{SIDE_BY_SIDE_AREA_RATIO, every_member_point, spacing_of};

/// Of `pieces` (largest first), the one `top` stands beside: of those at
/// least [`SIDE_BY_SIDE_AREA_RATIO`] of the largest, the ones nearest
/// `top` across the plane, within [`BESIDE_TOLERANCE_CELLS`] of the
/// nearest, and of them the largest (two pieces of one plate a streak
/// splits along the seam stand beside it alike). The largest, 0, where
/// only one piece is that large, or none lies within `reach_mm` of `top`
/// (read to a cell), or no points are given.
pub(super) fn standing_beside(
    top: &PlaneCluster,
    pieces: &[&PlaneCluster],
    normal: &Vec3,
    points: &[Point],
    reach_mm: f64,
) -> usize {
    let Some(largest) = pieces.first() else {
        return 0;
    };
    let plates = pieces.iter().take_while(|c| c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * largest.area_mm2).count();
    if plates < 2 {
        return 0;
    }
    let Some(gaps) = gaps_across(top, &pieces[..plates], normal, points, reach_mm) else {
        return 0;
    };
    let nearest = gaps.iter().flatten().fold(f64::INFINITY, |a, &b| a.min(b));
    let tolerance = BESIDE_TOLERANCE_CELLS * BESIDE_CELL_SPACINGS * spacing_of(top);
    gaps.iter().position(|g| g.is_some_and(|g| g <= nearest + tolerance)).unwrap_or(0)
}

/// The cells of [`gaps_across`], in point spacings of the upper plane: a
/// cell that wide holds about nine of a plate's points, so every fourth
/// marks it about twice (in a frame's pixel order, in three of its four
/// rows), and a cell left empty inside a plate is crossed in one step.
const BESIDE_CELL_SPACINGS: f64 = 3.0;

/// Every how many of a cluster's points [`gaps_across`] marks a cell with.
const BESIDE_MARK_STRIDE: usize = 4;

/// Every how many of the upper plane's points [`gaps_across`] marks a cell
/// with: it is the largest plane of a lap, and its nearest cells to each
/// other plate are all that is read of it, so a cell it leaves empty here
/// and there moves the gap by a cell at most where the edge is read best.
const BESIDE_TOP_MARK_STRIDE: usize = 8;

/// Every how many of the clusters' points [`gaps_across`] takes their
/// extent from.
const BESIDE_BOUNDS_STRIDE: usize = 8;

/// How many cells further from a lap's upper plate (or a web's top) than
/// the nearest plate of the layer under it another plate of that layer may
/// lie and still stand beside it: each plate's nearest point is read to a
/// cell, and the cells count steps along the diagonal as one.
const BESIDE_TOLERANCE_CELLS: f64 = 2.0;

/// The most cells the grid of [`gaps_across`] may hold; a coarser cell is
/// taken beyond it.
const BESIDE_MAX_CELLS: f64 = 4.0e6;

/// How far across the plane each of `others` lies from `top`, mm: steps of
/// a grid of cells [`BESIDE_CELL_SPACINGS`] wide from the cells `top`'s
/// points mark to the nearest cell the other's points mark, each step a
/// cell (also along the diagonal). `None` for one further than `reach_mm`
/// and a cell (a gap is read to a cell); `None` for all where the points
/// give no extent.
fn gaps_across(
    top: &PlaneCluster,
    others: &[&PlaneCluster],
    normal: &Vec3,
    points: &[Point],
    reach_mm: f64,
) -> Option<Vec<Option<f64>>> {
    let [u_axis, v_axis] = plane_axes(normal)?;
    let project = |p: Vec3| (p.dot(&u_axis), p.dot(&v_axis));
    // The extent from every few points, widened by a cell: a point the
    // sample misses lies in the border cells it is clamped into.
    let [u0, v0, u1, v1] = std::iter::once(top)
        .chain(others.iter().copied())
        .flat_map(|c| every_member_point(&c.members, BESIDE_BOUNDS_STRIDE, points))
        .map(project)
        .fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |[u0, v0, u1, v1], (u, v)| {
            [u0.min(u), v0.min(v), u1.max(u), v1.max(v)]
        });
    if !(u1 > u0 && v1 > v0) {
        return None;
    }
    let fine = (BESIDE_CELL_SPACINGS * spacing_of(top)).max(f64::EPSILON);
    let [u0, v0, u1, v1] = [u0 - fine, v0 - fine, u1 + fine, v1 + fine];
    let cell_mm = fine.max(((u1 - u0) * (v1 - v0) / BESIDE_MAX_CELLS).sqrt());
    let (width, height) = (((u1 - u0) / cell_mm) as usize + 1, ((v1 - v0) / cell_mm) as usize + 1);
    let cell_of = |p: Vec3| {
        let (u, v) = project(p);
        let (x, y) = (((u - u0) / cell_mm) as usize, ((v - v0) / cell_mm) as usize);
        y.min(height - 1) * width + x.min(width - 1)
    };
    // Steps from the top's cells, a ring at a time, out to the reach and
    // the cell it is read to.
    let reach = (reach_mm / cell_mm).ceil() as u32 + 1;
    let mut steps = vec![u32::MAX; width * height];
    let mut front: Vec<usize> = Vec::new();
    for c in every_member_point(&top.members, BESIDE_TOP_MARK_STRIDE, points).map(cell_of) {
        if steps[c] != 0 {
            steps[c] = 0;
            front.push(c);
        }
    }
    for step in 1..=reach {
        let mut next = Vec::new();
        for &c in &front {
            let (x, y) = (c % width, c / width);
            for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                    let n = ny * width + nx;
                    if steps[n] == u32::MAX {
                        steps[n] = step;
                        next.push(n);
                    }
                }
            }
        }
        front = next;
    }
    let gaps = others
        .iter()
        .map(|c| {
            let nearest = every_member_point(&c.members, BESIDE_MARK_STRIDE, points)
                .map(|p| steps[cell_of(p)])
                .min()
                .filter(|&s| s != u32::MAX);
            nearest.map(|s| s as f64 * cell_mm).filter(|&gap| gap <= reach_mm + cell_mm)
        })
        .collect();
    Some(gaps)
}
