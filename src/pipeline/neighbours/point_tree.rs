//! A static KD-tree over a cloud's valid points whose radius queries can
//! stop early.
//!
//! The criteria only need a neighbour count up to their threshold, and a
//! normal only needs enough neighbours to fit a plane, so a query stops as
//! soon as its visitor has what it needs. That bounds the work per point
//! however dense the cloud: 50,000 points in a 0.6 mm cube make every
//! point every other's neighbour, and a query that collects them all costs
//! the whole cloud per point. Pruning is by each node's bounding box, so
//! exact duplicates and tight clumps beyond the radius cost one box test.

use std::ops::ControlFlow;

use crate::cloud::Point;

/// Points per leaf: a leaf's points are tested one by one.
const LEAF_POINTS: usize = 16;

/// Subtrees larger than this are partitioned on their own rayon task.
const PARALLEL_POINTS: usize = 1 << 15;

/// A node's bounding box and the range of tree-ordered points under it.
#[derive(Debug, Clone, Copy)]
struct Node {
    min: [f32; 3],
    max: [f32; 3],
}

/// The tree: points in tree order, and a complete binary tree of boxes in
/// heap order (node `k` has children `2k + 1` and `2k + 2`) over halves of
/// the point range.
pub(crate) struct PointTree {
    points: Vec<Point>,
    /// Tree position → cloud point index.
    index_of: Vec<u32>,
    nodes: Vec<Node>,
    /// Levels below the root; the nodes of the last level are the leaves.
    depth: u32,
}

/// The point range of node `k` at level `level` over `n` points: each
/// level halves its parent's range, the lower half taking the odd point.
fn range_of(n: usize, level: u32, k: usize) -> (usize, usize) {
    let first = (1usize << level) - 1;
    let mut lo = 0;
    let mut hi = n;
    let position = k - first;
    for bit in (0..level).rev() {
        let mid = lo + (hi - lo).div_ceil(2);
        if position >> bit & 1 == 0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (lo, hi)
}

impl PointTree {
    /// Builds the tree over the valid (finite) points of `cloud_points`.
    pub(crate) fn new(cloud_points: &[Point]) -> PointTree {
        let mut items: Vec<(Point, u32)> =
            cloud_points.iter().enumerate().filter(|(_, p)| p[0].is_finite()).map(|(i, p)| (*p, i as u32)).collect();
        let n = items.len();
        let mut depth = 0;
        while n.div_ceil(1 << depth) > LEAF_POINTS {
            depth += 1;
        }
        partition(&mut items, depth);
        let points: Vec<Point> = items.iter().map(|(p, _)| *p).collect();
        let index_of = items.iter().map(|(_, i)| *i).collect();
        let first_leaf = (1usize << depth) - 1;
        let mut nodes = vec![Node { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3] }; 2 * first_leaf + 1];
        for (k, node) in nodes.iter_mut().enumerate().skip(first_leaf) {
            let (lo, hi) = range_of(n, depth, k);
            for p in &points[lo..hi] {
                grow(&mut node.min, &mut node.max, p);
            }
        }
        for k in (0..first_leaf).rev() {
            let (a, b) = (nodes[2 * k + 1], nodes[2 * k + 2]);
            nodes[k] = Node {
                min: std::array::from_fn(|axis| a.min[axis].min(b.min[axis])),
                max: std::array::from_fn(|axis| a.max[axis].max(b.max[axis])),
            };
        }
        PointTree { points, index_of, nodes, depth }
    }

    /// Calls `visit(j, q)` for candidates `q` (cloud index `j`) of every
    /// point within `reach_sq` of `p`, nearer subtrees first, until it
    /// breaks. Candidates are a superset of the points within the reach:
    /// the caller applies its own predicate.
    pub(crate) fn visit_near(&self, p: &Point, reach_sq: f32, mut visit: impl FnMut(usize, &Point) -> ControlFlow<()>) {
        if self.points.is_empty() {
            return;
        }
        let reach_sq = reach_sq as f64;
        let first_leaf = (1usize << self.depth) - 1;
        let n = self.points.len();
        // A depth-first walk needs one pending sibling per level.
        let mut stack = Vec::with_capacity(self.depth as usize + 1);
        stack.push((0usize, 0u32));
        while let Some((k, level)) = stack.pop() {
            if box_distance_sq(&self.nodes[k], p) > reach_sq {
                continue;
            }
            if k >= first_leaf {
                let (lo, hi) = range_of(n, level, k);
                for (q, &j) in self.points[lo..hi].iter().zip(&self.index_of[lo..hi]) {
                    if visit(j as usize, q).is_break() {
                        return;
                    }
                }
                continue;
            }
            let (left, right) = (2 * k + 1, 2 * k + 2);
            // The nearer child is visited first, so it goes on top.
            let (near, far) = if box_distance_sq(&self.nodes[left], p) <= box_distance_sq(&self.nodes[right], p) {
                (left, right)
            } else {
                (right, left)
            };
            stack.push((far, level + 1));
            stack.push((near, level + 1));
        }
    }
}

/// The squared distance from `p` to the box, in double precision: every
/// single-precision squared distance of a point inside the box is at
/// least this, less rounding, which the caller's reach leaves room for.
#[inline]
fn box_distance_sq(node: &Node, p: &Point) -> f64 {
    // An empty box (no points) has min > max and an infinite gap.
    (0..3)
        .map(|axis| {
            let v = p[axis] as f64;
            let gap = (node.min[axis] as f64 - v).max(v - node.max[axis] as f64).max(0.0);
            gap * gap
        })
        .sum()
}

/// Widens the box `min..max` to hold `p`.
#[inline]
fn grow(min: &mut [f32; 3], max: &mut [f32; 3], p: &Point) {
    for ((lo, hi), v) in min.iter_mut().zip(max.iter_mut()).zip(p) {
        *lo = lo.min(*v);
        *hi = hi.max(*v);
    }
}

/// Orders `items` so that every node's range holds the points of its
/// half of its parent's, split at the median of the parent's widest axis.
fn partition(items: &mut [(Point, u32)], levels: u32) {
    if levels == 0 || items.len() <= 1 {
        return;
    }
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for (p, _) in items.iter() {
        grow(&mut min, &mut max, p);
    }
    let axis = (0..3).max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b]))).unwrap_or(0);
    let mid = items.len().div_ceil(2);
    // Ties by index keep the order, and so the tree, deterministic.
    items.select_nth_unstable_by(mid.min(items.len() - 1), |a, b| a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1)));
    let (lower, upper) = items.split_at_mut(mid);
    if lower.len() + upper.len() > PARALLEL_POINTS {
        rayon::join(|| partition(lower, levels - 1), || partition(upper, levels - 1));
    } else {
        partition(lower, levels - 1);
        partition(upper, levels - 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scattered(n: usize) -> Vec<Point> {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|i| if i % 11 == 3 { [f32::NAN; 3] } else { [next() * 10.0, next() * 10.0, 500.0 + next() * 3.0] })
            .collect()
    }

    fn brute_force(points: &[Point], p: &Point, r_sq: f32) -> Vec<usize> {
        (0..points.len())
            .filter(|&j| {
                let q = points[j];
                let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r_sq
            })
            .collect()
    }

    #[test]
    fn queries_find_exactly_the_points_a_scan_finds() {
        for n in [0, 1, 2, 15, 16, 17, 100, 3000] {
            let points = scattered(n);
            let tree = PointTree::new(&points);
            for p in points.iter().filter(|p| p[0].is_finite()).take(200) {
                let r_sq = 0.8f32 * 0.8;
                let mut found = Vec::new();
                tree.visit_near(p, r_sq * (1.0 + 1e-5), |j, q| {
                    assert_eq!(*q, points[j]);
                    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                    if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r_sq {
                        found.push(j);
                    }
                    ControlFlow::Continue(())
                });
                found.sort_unstable();
                assert_eq!(found, brute_force(&points, p, r_sq), "{n} points");
            }
        }
    }

    #[test]
    fn a_query_stops_when_told_and_duplicates_beyond_reach_cost_one_box() {
        let mut points = vec![[0.0f32, 0.0, 500.0]; 20_000];
        points.push([5.0, 0.0, 500.0]);
        let tree = PointTree::new(&points);
        let mut visited = 0;
        tree.visit_near(&[0.0, 0.0, 500.0], 1.0, |_, _| {
            visited += 1;
            if visited == 10 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        assert_eq!(visited, 10);
        // From the lone point, the clump 5 mm away is pruned whole.
        let mut candidates = 0;
        tree.visit_near(&[5.0, 0.0, 500.0], 1.0, |_, _| {
            candidates += 1;
            ControlFlow::Continue(())
        });
        assert!(candidates <= LEAF_POINTS, "{candidates} candidates");
    }
}
