//! The kernels in four lanes of SSE2, the x86_64 baseline: [`Vector`] for
//! `__m128`, and the entry points compiled for SSE2 that instantiate
//! [`super::generic`] with it.

use std::arch::x86_64::*;

use super::scalar::Corner;
use super::vector::Vector;
use super::{
    BLOCK, LabelledGrid, LabelledWindow, LaneMasks, NormalTest, Planes, QuadBox, RowBounds, TileScales, generic, scalar,
};
use crate::cloud::Point;

/// `_MM_SHUFFLE` in reading order: lanes `a`, `b` of the first operand,
/// then `c`, `d` of the second.
pub(super) const fn pick(a: i32, b: i32, c: i32, d: i32) -> i32 {
    a | b << 2 | c << 4 | d << 6
}

/// Regroups four points loaded as `a = x0 y0 z0 x1`, `b = y1 z1 x2 y2`,
/// `c = z2 x3 y3 z3` into x, y and z lanes. The same in-lane shuffles
/// regroup each 128-bit half of an AVX register, so [`super::avx2`] uses
/// them too, through `$shuffle`.
macro_rules! deinterleave {
    ($shuffle:ident, $a:expr, $b:expr, $c:expr) => {{
        use $crate::kernels::sse2::pick;
        let (a, b, c) = ($a, $b, $c);
        let x = $shuffle::<{ pick(0, 3, 0, 2) }>(a, $shuffle::<{ pick(2, 2, 1, 1) }>(b, c));
        let y = $shuffle::<{ pick(0, 2, 0, 2) }>(
            $shuffle::<{ pick(1, 1, 0, 0) }>(a, b),
            $shuffle::<{ pick(3, 3, 2, 2) }>(b, c),
        );
        let z = $shuffle::<{ pick(0, 2, 0, 2) }>(
            $shuffle::<{ pick(2, 2, 1, 1) }>(a, b),
            $shuffle::<{ pick(0, 0, 3, 3) }>(c, c),
        );
        [x, y, z]
    }};
}
pub(super) use deinterleave;

// SAFETY: every method does what the trait says with SSE2, which every
// x86_64 CPU runs.
unsafe impl Vector for __m128 {
    const LANES: usize = 4;
    type Int = __m128i;

    #[inline(always)]
    unsafe fn splat(v: f32) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_set1_ps(v) }
    }
    #[inline(always)]
    unsafe fn load(at: *const f32) -> Self {
        // SAFETY: the caller gives four readable floats.
        unsafe { _mm_loadu_ps(at) }
    }
    #[inline(always)]
    unsafe fn load_points(at: *const Point) -> [Self; 3] {
        let at = at.cast::<f32>();
        // SAFETY: the caller gives four readable points, twelve floats.
        let (a, b, c) = unsafe { (_mm_loadu_ps(at), _mm_loadu_ps(at.add(4)), _mm_loadu_ps(at.add(8))) };
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { deinterleave!(_mm_shuffle_ps, a, b, c) }
    }
    #[inline(always)]
    unsafe fn add(self, other: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_add_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn sub(self, other: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_sub_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn mul(self, other: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_mul_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn le(self, other: Self) -> __m128i {
        // An ordered compare: NaN is false.
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_castps_si128(_mm_cmple_ps(self, other)) }
    }
    #[inline(always)]
    unsafe fn div(self, other: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_div_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn min(self, other: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_min_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn max(self, other: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_max_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn abs(self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_and_ps(self, _mm_castsi128_ps(_mm_set1_epi32(i32::MAX))) }
    }
    #[inline(always)]
    unsafe fn negate_where(self, mask: __m128i) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_xor_ps(self, _mm_and_ps(_mm_castsi128_ps(mask), _mm_set1_ps(-0.0))) }
    }
    #[inline(always)]
    unsafe fn least(self) -> f32 {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe {
            let v = _mm_min_ps(self, _mm_movehl_ps(self, self));
            _mm_cvtss_f32(_mm_min_ps(v, _mm_shuffle_ps::<{ pick(1, 1, 1, 1) }>(v, v)))
        }
    }
    #[inline(always)]
    unsafe fn greatest(self) -> f32 {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe {
            let v = _mm_max_ps(self, _mm_movehl_ps(self, self));
            _mm_cvtss_f32(_mm_max_ps(v, _mm_shuffle_ps::<{ pick(1, 1, 1, 1) }>(v, v)))
        }
    }
    #[inline(always)]
    unsafe fn select(mask: __m128i, a: Self, b: Self) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe {
            let mask = _mm_castsi128_ps(mask);
            _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b))
        }
    }
    #[inline(always)]
    unsafe fn lt(self, other: Self) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_castps_si128(_mm_cmplt_ps(self, other)) }
    }
    #[inline(always)]
    unsafe fn gt(self, other: Self) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_castps_si128(_mm_cmpgt_ps(self, other)) }
    }
    #[inline(always)]
    unsafe fn ge(self, other: Self) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_castps_si128(_mm_cmpge_ps(self, other)) }
    }
    #[inline(always)]
    unsafe fn to_bits(self) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_castps_si128(self) }
    }
    #[inline(always)]
    unsafe fn from_i32(a: __m128i) -> Self {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_cvtepi32_ps(a) }
    }
    #[inline(always)]
    unsafe fn splat_u32(v: u32) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_set1_epi32(v as i32) }
    }
    #[inline(always)]
    unsafe fn load_u32(at: *const u32) -> __m128i {
        // SAFETY: the caller gives four readable u32.
        unsafe { _mm_loadu_si128(at.cast()) }
    }
    #[inline(always)]
    unsafe fn eq_u32(a: __m128i, b: __m128i) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_cmpeq_epi32(a, b) }
    }
    #[inline(always)]
    unsafe fn and_u32(a: __m128i, b: __m128i) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_and_si128(a, b) }
    }
    #[inline(always)]
    unsafe fn sub_u32(a: __m128i, b: __m128i) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_sub_epi32(a, b) }
    }
    #[inline(always)]
    unsafe fn add_u32(a: __m128i, b: __m128i) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_add_epi32(a, b) }
    }
    #[inline(always)]
    unsafe fn lanes_above(k: i32) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_cmpgt_epi32(_mm_setr_epi32(0, 1, 2, 3), _mm_set1_epi32(k)) }
    }
    #[inline(always)]
    unsafe fn sum_u32(a: __m128i) -> u32 {
        let mut lanes = [0u32; 4];
        // SAFETY: `lanes` holds four u32.
        unsafe { Self::store_u32(a, lanes.as_mut_ptr()) };
        lanes.iter().fold(0u32, |s, &v| s.wrapping_add(v))
    }
    #[inline(always)]
    unsafe fn store_u32(a: __m128i, at: *mut u32) {
        // SAFETY: the caller gives four writable u32.
        unsafe { _mm_storeu_si128(at.cast(), a) }
    }
    #[inline(always)]
    unsafe fn pack_u16(high: __m128i, low: __m128i) -> __m128i {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_or_si128(_mm_slli_epi32::<16>(high), _mm_and_si128(low, _mm_set1_epi32(0xffff))) }
    }
    #[inline(always)]
    unsafe fn store_pairs(low: __m128i, high: __m128i, at: *mut u64) {
        // SAFETY: the caller gives four writable u64, two 128-bit stores.
        unsafe {
            _mm_storeu_si128(at.cast(), _mm_unpacklo_epi32(low, high));
            _mm_storeu_si128(at.add(2).cast(), _mm_unpackhi_epi32(low, high));
        }
    }
    #[inline(always)]
    unsafe fn mask_bits(a: __m128i) -> u32 {
        // SAFETY: every x86_64 CPU runs SSE2.
        unsafe { _mm_movemask_ps(_mm_castsi128_ps(a)) as u32 }
    }
}

/// [`super::count_block`] in two halves of four lanes.
#[target_feature(enable = "sse2")]
pub(super) fn count_block(
    planes: Planes,
    first: usize,
    ranges: impl Iterator<Item = (usize, usize)> + Clone,
    radius_sq: f32,
) -> [u32; BLOCK] {
    // SAFETY: this function runs only where SSE2 does; 4 divides 8.
    unsafe { generic::count_block::<__m128>(planes, first, ranges, radius_sq) }
}

/// [`super::scalar::count_span`] four points at a time on spans that hold
/// as many.
#[target_feature(enable = "sse2")]
#[inline]
pub(super) fn count_span(p: &Point, points: &[Point], labels: &[u32], label: u32, radius_sq: f32) -> u32 {
    if points.len().min(labels.len()) >= 4 {
        // SAFETY: this function runs only where SSE2 does.
        unsafe { generic::count_span::<__m128>(p, points, labels, label, radius_sq) }
    } else {
        scalar::count_span(p, points, labels, label, radius_sq)
    }
}

/// [`super::labelled_count_at_most`], four points at a time.
#[target_feature(enable = "sse2")]
pub(super) fn labelled_count_at_most(grid: &LabelledGrid, query: &LabelledWindow) -> bool {
    generic::labelled_count_at_most(
        grid,
        query,
        #[inline(always)]
        |p, points, labels, label, radius_sq| count_span(p, points, labels, label, radius_sq),
    )
}

/// [`super::depth_range`] in four lanes, twice a block.
#[target_feature(enable = "sse2")]
#[inline]
pub(super) fn depth_range(z: &[f32; BLOCK]) -> (f32, f32) {
    // SAFETY: this function runs only where SSE2 does; 4 divides 8.
    unsafe { generic::depth_range::<__m128>(z) }
}

/// [`super::normal_test`] in four lanes, twice a block.
#[target_feature(enable = "sse2")]
#[inline]
pub(super) fn normal_test(planes: Planes, width: usize, first: usize, step: usize, test: &NormalTest) -> LaneMasks {
    // SAFETY: this function runs only where SSE2 does; 4 divides 8.
    unsafe { generic::normal_test::<__m128>(planes, width, first, step, test) }
}

/// [`super::tile_keys`] in four lanes, twice a block.
#[target_feature(enable = "sse2")]
#[inline]
pub(super) fn tile_keys(lanes: &[[f32; BLOCK]; 3], scales: &TileScales) -> [u64; BLOCK] {
    // SAFETY: this function runs only where SSE2 does; 4 divides 8.
    unsafe { generic::tile_keys::<__m128>(lanes, scales) }
}

#[target_feature(enable = "sse2")]
fn load4(v: &[u32]) -> __m128i {
    let v = &v[..4];
    // SAFETY: `v` holds four u32.
    unsafe { _mm_loadu_si128(v.as_ptr().cast()) }
}

/// Four u16 widened to u32 lanes.
#[target_feature(enable = "sse2")]
fn load4_u16(v: &[u16]) -> __m128i {
    let v = &v[..4];
    // SAFETY: `v` holds four u16, one 64-bit load.
    let packed = unsafe { _mm_loadl_epi64(v.as_ptr().cast()) };
    _mm_unpacklo_epi16(packed, _mm_setzero_si128())
}

/// All ones in the lanes labelled as one of the plates.
#[target_feature(enable = "sse2")]
fn member_lanes<const N: usize>(labels: __m128i, plate_labels: [u32; N]) -> [__m128i; N] {
    plate_labels.map(|l| _mm_cmpeq_epi32(labels, _mm_set1_epi32(l as i32)))
}

/// [`super::members_corner`]'s accumulation over a multiple of four
/// pixels. The compares of `minps` and `maxps` return their second
/// operand when the first is NaN, which skips NaN as the scalar form
/// does.
#[target_feature(enable = "sse2")]
pub(super) fn members_corner<const N: usize>(labels: &[u32], points: &[Point], plate_labels: [u32; N]) -> Corner {
    let abs = _mm_castsi128_ps(_mm_set1_epi32(i32::MAX));
    let far = _mm_set1_ps(f32::INFINITY);
    let (mut z_min, mut x_max, mut y_max, mut any) = (far, _mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_si128());
    for (labels, quad) in labels.chunks_exact(4).zip(points.chunks_exact(4)) {
        let member =
            member_lanes(load4(labels), plate_labels).into_iter().fold(_mm_setzero_si128(), |a, m| _mm_or_si128(a, m));
        let member_ps = _mm_castsi128_ps(member);
        // SAFETY: `quad` holds four points.
        let [x, y, z] = unsafe { <__m128 as Vector>::load_points(quad.as_ptr()) };
        z_min = _mm_min_ps(_mm_or_ps(_mm_and_ps(member_ps, z), _mm_andnot_ps(member_ps, far)), z_min);
        x_max = _mm_max_ps(_mm_and_ps(member_ps, _mm_and_ps(x, abs)), x_max);
        y_max = _mm_max_ps(_mm_and_ps(member_ps, _mm_and_ps(y, abs)), y_max);
        any = _mm_or_si128(any, member);
    }
    let mut out = [[0f32; 4]; 3];
    // SAFETY: each row of `out` holds four floats.
    unsafe {
        _mm_storeu_ps(out[0].as_mut_ptr(), z_min);
        _mm_storeu_ps(out[1].as_mut_ptr(), x_max);
        _mm_storeu_ps(out[2].as_mut_ptr(), y_max);
    }
    let [z, x, y] = out;
    Corner {
        z_min: z.into_iter().fold(f32::INFINITY, |a, v| if v < a { v } else { a }),
        x_max: x.into_iter().fold(0.0, |a, v| if v > a { v } else { a }),
        y_max: y.into_iter().fold(0.0, |a, v| if v > a { v } else { a }),
        any: _mm_movemask_epi8(any) != 0,
    }
}

/// [`RowBounds::open_members`] for the columns `cols` (a multiple of
/// four, every window inside the row and of `area` pixels) with the
/// full counts `full` of the row: the bound in integer lanes, the
/// threshold `ratio · N` in double lanes as the scalar form computes
/// it.
#[target_feature(enable = "sse2")]
pub(super) fn open_members<const N: usize>(
    bounds: &RowBounds<N>,
    cols: std::ops::Range<usize>,
    area: u32,
    full: &[u16],
    ratio: f64,
    open: &mut Vec<(u32, u8)>,
) {
    let wx = bounds.wx;
    let (ratio, area) = (_mm_set1_pd(ratio), _mm_set1_epi32(area as i32));
    let low_field = _mm_set1_epi32(0xffff);
    for c in cols.step_by(4) {
        let fields = _mm_sub_epi32(load4(&bounds.prefix[c + wx + 1..]), load4(&bounds.prefix[c - wx..]));
        let plates = member_lanes(load4(&bounds.labels[c..]), bounds.plate_labels);
        let (mut member, mut same) = (_mm_setzero_si128(), _mm_setzero_si128());
        for (k, m) in plates.into_iter().enumerate() {
            let field = match (N, k) {
                (1, _) => fields,
                (_, 0) => _mm_and_si128(fields, low_field),
                _ => _mm_srli_epi32::<16>(fields),
            };
            member = _mm_or_si128(member, m);
            same = _mm_or_si128(same, _mm_and_si128(m, field));
        }
        let member_bits = _mm_movemask_ps(_mm_castsi128_ps(member));
        if member_bits == 0 {
            continue;
        }
        // At most the window's non-members are not of the plate.
        let bound = _mm_sub_epi32(_mm_add_epi32(load4_u16(&bounds.counts[c..]), same), area);
        let full = load4_u16(&full[c..]);
        let high = |v: __m128i| _mm_unpackhi_epi64(v, v);
        let above = |b: __m128i, n: __m128i| {
            _mm_movemask_pd(_mm_cmpgt_pd(_mm_cvtepi32_pd(b), _mm_mul_pd(ratio, _mm_cvtepi32_pd(n))))
        };
        let settled = above(bound, full) | above(high(bound), high(full)) << 2;
        let mut left = member_bits & !settled;
        while left != 0 {
            let lane = left.trailing_zeros() as usize;
            left &= left - 1;
            let k = bounds.plate_of(bounds.labels[c + lane]).unwrap_or(0);
            open.push(((c + lane) as u32, k as u8));
        }
    }
}

/// [`super::quad_boxes`] in four lanes.
#[target_feature(enable = "sse2")]
pub(super) fn quad_boxes(rows: &[&[Point]], min_depth: f32, out: &mut [QuadBox]) {
    // SAFETY: this function runs only where SSE2 does; 4 divides 4.
    unsafe { generic::quad_boxes::<__m128>(rows, min_depth, out) }
}
