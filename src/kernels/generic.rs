//! The kernels written once over [`Vector`]: the distance predicate in
//! lanes, the block count of eight grid pixels and the labelled count of
//! a span of points. [`super::sse2`] and [`super::avx2`] instantiate them
//! inside functions compiled for their instruction set; [`super::scalar`]
//! holds the plain forms they must agree with.

use super::vector::Vector;
use super::{BLOCK, LabelledGrid, Planes};
use crate::cloud::Point;

/// [`super::within`] in lanes: all ones where `q` lies within `radius_sq`
/// of `p`, by the same subtractions, multiplies, additions and ordered
/// compare in the same order, so the same decision bit for bit.
///
/// # Safety
/// The CPU must run `V`'s instruction set.
#[inline(always)]
pub(super) unsafe fn within<V: Vector>([px, py, pz]: [V; 3], [qx, qy, qz]: [V; 3], radius_sq: V) -> V::Int {
    // SAFETY: the caller's CPU runs `V`.
    unsafe {
        let (dx, dy, dz) = (px.sub(qx), py.sub(qy), pz.sub(qz));
        dx.mul(dx).add(dy.mul(dy)).add(dz.mul(dz)).le(radius_sq)
    }
}

/// [`super::count_block`], `V::LANES` pixels of the block at a time.
///
/// # Safety
/// The CPU must run `V`'s instruction set, and `V::LANES` must divide
/// [`BLOCK`].
#[inline(always)]
pub(super) unsafe fn count_block<V: Vector>(
    planes: Planes,
    first: usize,
    ranges: impl Iterator<Item = (usize, usize)> + Clone,
    radius_sq: f32,
) -> [u32; BLOCK] {
    let mut out = [0u32; BLOCK];
    // SAFETY: the caller's CPU runs `V`; every load reads `V::LANES`
    // floats from slices checked to hold them.
    unsafe {
        let r2 = V::splat(radius_sq);
        for lane in (0..BLOCK).step_by(V::LANES) {
            let at = |v: &[f32]| V::load(v[first + lane..first + lane + V::LANES].as_ptr());
            let p = [at(planes.xs), at(planes.ys), at(planes.zs)];
            let mut counts = V::splat_u32(0);
            for (start, end) in ranges.clone() {
                // Slicing checks the bounds once per span; the loads stay
                // inside those slices.
                let (lo, reach) = (start + lane, end + lane + V::LANES - 1);
                let (xs, ys, zs) = (&planes.xs[lo..reach], &planes.ys[lo..reach], &planes.zs[lo..reach]);
                for k in 0..end - start {
                    // k + LANES <= reach - lo, the length of each slice.
                    let q = [V::load(xs.as_ptr().add(k)), V::load(ys.as_ptr().add(k)), V::load(zs.as_ptr().add(k))];
                    // A true lane is all ones, -1: subtracting counts it.
                    counts = V::sub_u32(counts, within(p, q, r2));
                }
            }
            let out = &mut out[lane..lane + V::LANES];
            V::store_u32(counts, out.as_mut_ptr());
        }
    }
    out
}

/// [`super::scalar::count_span`] `V::LANES` points at a time, for at least
/// that many points. A length that is no multiple of `V::LANES` ends with
/// the last `V::LANES` points, the lanes counted before masked off.
///
/// # Safety
/// The CPU must run `V`'s instruction set.
#[inline(always)]
pub(super) unsafe fn count_span<V: Vector>(
    p: &Point,
    points: &[Point],
    labels: &[u32],
    label: u32,
    radius_sq: f32,
) -> u32 {
    let lanes = V::LANES;
    let n = points.len().min(labels.len());
    debug_assert!(n >= lanes);
    // SAFETY: the caller's CPU runs `V`; every load reads `V::LANES`
    // values from slices checked to hold them.
    unsafe {
        let centre = [V::splat(p[0]), V::splat(p[1]), V::splat(p[2])];
        let (r2, wanted) = (V::splat(radius_sq), V::splat_u32(label));
        let count_at = |at: usize| -> V::Int {
            let q = V::load_points(points[at..at + lanes].as_ptr());
            let same = V::eq_u32(V::load_u32(labels[at..at + lanes].as_ptr()), wanted);
            V::and_u32(within(centre, q, r2), same)
        };
        // A counted lane is all ones, -1: subtracting counts it.
        let mut counts = V::splat_u32(0);
        for at in (0..n + 1 - lanes).step_by(lanes) {
            counts = V::sub_u32(counts, count_at(at));
        }
        let done = n / lanes * lanes;
        if done < n {
            // Lanes 0..done + LANES - n of the last LANES points were
            // counted above.
            let fresh = V::lanes_above((done + lanes - 1 - n) as i32);
            counts = V::sub_u32(counts, V::and_u32(fresh, count_at(n - lanes)));
        }
        V::sum_u32(counts)
    }
}

/// [`super::labelled_count_at_most`] with `count_span` counting one row of
/// the window. The rows go from the point's outwards: the middle ones hold
/// the most neighbours, so a count that passes the threshold is told
/// sooner.
#[inline(always)]
pub(super) fn labelled_count_at_most(
    grid: &LabelledGrid,
    i: usize,
    (wx, wy): (usize, usize),
    label: u32,
    radius_sq: f32,
    threshold: f64,
    count_span: impl Fn(&Point, &[Point], &[u32], u32, f32) -> u32,
) -> bool {
    let (w, h) = (grid.width, grid.height);
    let p = grid.points[i];
    let (col, row) = (i % w, i / w);
    let (c0, c1) = (col.saturating_sub(wx), (col + wx).min(w - 1));
    let (below, above) = (row - row.saturating_sub(wy), (row + wy).min(h - 1) - row);
    let span = |row: usize| {
        let span = row * w + c0..row * w + c1 + 1;
        (&grid.points[span.clone()], &grid.labels[span])
    };
    let (points, labels) = span(row);
    let mut count = count_span(&p, points, labels, label, radius_sq);
    // The rows at the same distance above and below together: two
    // independent counts per check.
    for d in 1..=below.max(above) {
        if count as f64 > threshold {
            return false;
        }
        if d <= below {
            let (points, labels) = span(row - d);
            count += count_span(&p, points, labels, label, radius_sq);
        }
        if d <= above {
            let (points, labels) = span(row + d);
            count += count_span(&p, points, labels, label, radius_sq);
        }
    }
    count as f64 <= threshold
}
