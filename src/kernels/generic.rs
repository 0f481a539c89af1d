//! The kernels written once over [`Vector`]: the distance predicate in
//! lanes, the block count of eight grid pixels, the labelled count of a
//! span of points, and the robust plane criterion's per-block facts (the
//! depth range, the normal test and the full-count memo keys). [`super::sse2`] and [`super::avx2`] instantiate them
//! inside functions compiled for their instruction set; [`super::scalar`]
//! holds the plain forms they must agree with.

use super::scalar::{FLOOR_LIMIT, FLOOR_SHIFT};
use super::vector::Vector;
use super::{BLOCK, LabelledGrid, LabelledWindow, LaneMasks, NormalTest, Planes, QUAD, QuadBox, TileScales};
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
    query: &LabelledWindow,
    count_span: impl Fn(&Point, &[Point], &[u32], u32, f32) -> u32,
) -> bool {
    let &LabelledWindow { centre: i, window: (wx, wy), label, radius_sq, threshold } = query;
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

/// [`super::depth_range`], `V::LANES` lanes at a time: `min` and `max`
/// keep their second operand where a lane is NaN, so an invalid lane
/// never wins and a block of them gives the infinities the lanes start
/// from.
///
/// # Safety
/// The CPU must run `V`'s instruction set, and `V::LANES` must divide
/// [`BLOCK`].
#[inline(always)]
pub(super) unsafe fn depth_range<V: Vector>(z: &[f32; BLOCK]) -> (f32, f32) {
    // SAFETY: the caller's CPU runs `V`; every load reads `V::LANES`
    // floats of slices checked to hold them.
    unsafe {
        let (mut low, mut high) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        for lane in (0..BLOCK).step_by(V::LANES) {
            let v = V::load(z[lane..lane + V::LANES].as_ptr());
            (low, high) = (v.min(low), v.max(high));
        }
        (low.least(), high.greatest())
    }
}

/// The x, y and z lanes of the `V::LANES` pixels from index `at`. A
/// function, not a closure: a closure is compiled without the caller's
/// instruction set, and its loads were calls.
///
/// # Safety
/// The CPU must run `V`'s instruction set.
#[inline(always)]
unsafe fn load_points<V: Vector>(planes: Planes, at: usize) -> [V; 3] {
    let lanes = at..at + V::LANES;
    let (xs, ys, zs) = (&planes.xs[lanes.clone()], &planes.ys[lanes.clone()], &planes.zs[lanes]);
    // SAFETY: the caller's CPU runs `V`; each slice holds `V::LANES` floats.
    unsafe { [V::load(xs.as_ptr()), V::load(ys.as_ptr()), V::load(zs.as_ptr())] }
}

/// `du × dv` in lanes, term for term as the scalar cross product.
///
/// # Safety
/// The CPU must run `V`'s instruction set.
#[inline(always)]
unsafe fn cross<V: Vector>(du: [V; 3], dv: [V; 3]) -> [V; 3] {
    // SAFETY: the caller's CPU runs `V`.
    unsafe {
        [
            du[1].mul(dv[2]).sub(du[2].mul(dv[1])),
            du[2].mul(dv[0]).sub(du[0].mul(dv[2])),
            du[0].mul(dv[1]).sub(du[1].mul(dv[0])),
        ]
    }
}

/// `a · b` in lanes, x, y, z in order without fusing.
///
/// # Safety
/// The CPU must run `V`'s instruction set.
#[inline(always)]
unsafe fn dot<V: Vector>(a: [V; 3], b: [V; 3]) -> V {
    // SAFETY: the caller's CPU runs `V`.
    unsafe { a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2])) }
}

/// [`super::normal_test`], `V::LANES` pixels of the block at a time: the
/// operations of the scalar form in the same order (no fused
/// multiply-add), so the same bits.
///
/// # Safety
/// The CPU must run `V`'s instruction set, and `V::LANES` must divide
/// [`BLOCK`].
#[inline(always)]
pub(super) unsafe fn normal_test<V: Vector>(
    planes: Planes,
    width: usize,
    first: usize,
    step: usize,
    test: &NormalTest,
) -> LaneMasks {
    let mut masks = LaneMasks::default();
    // SAFETY: the caller's CPU runs `V`; every load reads `V::LANES`
    // floats from slices checked to hold them.
    unsafe {
        let [nx, ny, nz] = test.reference;
        let reference = [V::splat(nx), V::splat(ny), V::splat(nz)];
        let (cos_sq, zero, tiny) = (V::splat(test.cos_sq), V::splat(0.0), V::splat(super::scalar::MIN_NORM_SQ));
        for lane in (0..BLOCK).step_by(V::LANES) {
            let at = first + lane;
            let centre = load_points::<V>(planes, at);
            let [lx, ly, lz] = load_points::<V>(planes, at - step);
            let [rx, ry, rz] = load_points::<V>(planes, at + step);
            let [ux, uy, uz] = load_points::<V>(planes, at - step * width);
            let [dx, dy, dz] = load_points::<V>(planes, at + step * width);
            let du = [rx.sub(lx), ry.sub(ly), rz.sub(lz)];
            let dv = [dx.sub(ux), dy.sub(uy), dz.sub(uz)];
            let sum = du[0].add(du[1]).add(du[2]).add(dv[0]).add(dv[1]).add(dv[2]).add(centre[0]);
            // Finite: the magnitude is below infinity (NaN compares false).
            let complete = sum.abs().lt(V::splat(f32::INFINITY));
            let n = cross(du, dv);
            // Turned away from the camera: the sign flipped where the
            // normal points towards it. For a NaN the bit differs from the
            // scalar `-1 *`, but every compare below is false either way.
            let along = dot(n, reference).negate_where(dot(n, centre).lt(zero));
            let norm_sq = dot(n, n);
            let facing =
                V::and_u32(V::and_u32(norm_sq.gt(tiny), along.ge(zero)), along.mul(along).ge(cos_sq.mul(norm_sq)));
            masks.complete |= V::mask_bits(complete) << lane;
            masks.facing |= V::mask_bits(facing) << lane;
        }
    }
    masks
}

/// [`super::scalar::floor_i32`] in lanes: the same clamps, shift and
/// compare, so the same integers. `max` gives its second operand for a
/// NaN lane: the low end, as `f32::max` does in the scalar form.
///
/// # Safety
/// The CPU must run `V`'s instruction set.
#[inline(always)]
unsafe fn floor_i32<V: Vector>(x: V) -> V::Int {
    // SAFETY: the caller's CPU runs `V`.
    unsafe {
        let x = x.max(V::splat(-FLOOR_LIMIT)).min(V::splat(FLOOR_LIMIT));
        let rounded = V::sub_u32(x.add(V::splat(FLOOR_SHIFT)).to_bits(), V::splat_u32(FLOOR_SHIFT.to_bits()));
        // A true compare is all ones, -1: adding it subtracts one.
        V::add_u32(rounded, V::from_i32(rounded).gt(x))
    }
}

/// [`super::tile_keys`], `V::LANES` lanes at a time: the operations of
/// [`super::tile_key`] in the same order, so the same keys.
///
/// # Safety
/// The CPU must run `V`'s instruction set, and `V::LANES` must divide
/// [`BLOCK`].
#[inline(always)]
pub(super) unsafe fn tile_keys<V: Vector>(lanes: &[[f32; BLOCK]; 3], scales: &TileScales) -> [u64; BLOCK] {
    let mut keys = [0u64; BLOCK];
    // SAFETY: the caller's CPU runs `V`; every load and store touches
    // `V::LANES` values of slices checked to hold them.
    unsafe {
        let (per_x, per_y) = (V::splat(scales.tiles_per_x), V::splat(scales.tiles_per_y));
        let (per_step, half) = (V::splat(scales.steps_per_mm), V::splat(0.5));
        for lane in (0..BLOCK).step_by(V::LANES) {
            let own = lane..lane + V::LANES;
            let [xs, ys, zs] = lanes;
            let (xs, ys, zs) = (&xs[own.clone()], &ys[own.clone()], &zs[own.clone()]);
            let (x, y, z) = (V::load(xs.as_ptr()), V::load(ys.as_ptr()), V::load(zs.as_ptr()));
            let tile_row = floor_i32(y.div(z).mul(per_y));
            let tile_col = floor_i32(x.div(z).mul(per_x));
            let depth_step = floor_i32(z.mul(per_step).add(half));
            // As `key_of` lays a key out: the tile row and column as the
            // high half's 16-bit fields, the depth step as the low half.
            V::store_pairs(depth_step, V::pack_u16(tile_row, tile_col), keys[own].as_mut_ptr());
        }
    }
    keys
}

/// [`super::quad_boxes`], `V::LANES` columns (whole quads) of every row at
/// a time; the columns short of a register's width by the scalar form.
///
/// # Safety
/// The CPU must run `V`'s instruction set, [`QUAD`] must divide
/// `V::LANES`, and `V::LANES` must be at most eight.
#[inline(always)]
pub(super) unsafe fn quad_boxes<V: Vector>(rows: &[&[Point]], min_depth: f32, out: &mut [QuadBox]) {
    let columns = rows.first().map_or(0, |row| row.len());
    let whole = columns / V::LANES * V::LANES;
    // SAFETY: the caller's CPU runs `V`; every load reads `V::LANES`
    // points of a slice checked to hold them, every store eight u32 of an
    // array of eight.
    unsafe {
        let (inf, neg, depth) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY), V::splat(min_depth));
        for first in (0..whole).step_by(V::LANES) {
            let (mut low, mut high) = ([inf; 3], [neg; 3]);
            let (mut binned, mut finite) = (V::splat_u32(0), V::splat_u32(0));
            for row in rows {
                let p = V::load_points(row[first..first + V::LANES].as_ptr());
                // Ordered compares: a NaN coordinate is not finite.
                let is_finite = V::and_u32(V::and_u32(p[0].abs().lt(inf), p[1].abs().lt(inf)), p[2].abs().lt(inf));
                let has_ray = V::and_u32(is_finite, p[2].gt(depth));
                for k in 0..3 {
                    low[k] = V::select(has_ray, p[k], inf).min(low[k]);
                    high[k] = V::select(has_ray, p[k], neg).max(high[k]);
                }
                // A true lane is all ones, -1: subtracting counts it.
                binned = V::sub_u32(binned, has_ray);
                finite = V::sub_u32(finite, is_finite);
            }
            let (low, high) = (low.map(|v| lane_bits::<V>(v.to_bits())), high.map(|v| lane_bits::<V>(v.to_bits())));
            let (binned, finite) = (lane_bits::<V>(binned), lane_bits::<V>(finite));
            for (q, quad) in out[first / QUAD..(first + V::LANES) / QUAD].iter_mut().enumerate() {
                let own = q * QUAD..(q + 1) * QUAD;
                let mut b = QuadBox::EMPTY;
                for k in 0..3 {
                    for l in own.clone() {
                        let (a, c) = (f32::from_bits(low[k][l]), f32::from_bits(high[k][l]));
                        b.min[k] = if a < b.min[k] { a } else { b.min[k] };
                        b.max[k] = if c > b.max[k] { c } else { b.max[k] };
                    }
                }
                b.binned = binned[own.clone()].iter().sum();
                b.finite = finite[own].iter().sum();
                *quad = b;
            }
        }
    }
    super::scalar::quad_boxes(rows, whole, min_depth, &mut out[whole / QUAD..]);
}

/// The u32 lanes of `v`, in the first `V::LANES` of eight.
///
/// # Safety
/// The CPU must run `V`'s instruction set, and `V::LANES` must be at most
/// eight.
#[inline(always)]
unsafe fn lane_bits<V: Vector>(v: V::Int) -> [u32; 8] {
    let mut at = [0u32; 8];
    // SAFETY: the caller's CPU runs `V`; the array holds eight u32.
    unsafe { V::store_u32(v, at.as_mut_ptr()) };
    at
}
