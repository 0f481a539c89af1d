//! The kernels in eight lanes, where the CPU runs AVX2: [`Vector`] for
//! `__m256`, the entry points compiled for AVX2 that instantiate
//! [`super::generic`] with it, and the one kernel that only this level
//! has, the fused run count.

use std::arch::x86_64::*;

use super::sse2::deinterleave;
use super::vector::Vector;
use super::{BLOCK, LaneMasks, NormalTest, Planes, QuadBox, TileScales, generic};
use crate::cloud::Point;

// SAFETY: every method does what the trait says with AVX2, which the
// entry points below are compiled for and called only where it runs.
unsafe impl Vector for __m256 {
    const LANES: usize = 8;
    type Int = __m256i;

    #[inline(always)]
    unsafe fn splat(v: f32) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_set1_ps(v) }
    }
    #[inline(always)]
    unsafe fn load(at: *const f32) -> Self {
        // SAFETY: the caller gives eight readable floats.
        unsafe { _mm256_loadu_ps(at) }
    }
    #[inline(always)]
    unsafe fn load_points(at: *const Point) -> [Self; 3] {
        let at = at.cast::<f32>();
        // Each 128-bit half holds four points as the SSE2 form loads them,
        // so the same in-lane shuffles regroup them.
        // SAFETY: the caller gives eight readable points, 24 floats.
        let (a, b, c) = unsafe {
            (
                _mm256_loadu2_m128(at.add(12), at),
                _mm256_loadu2_m128(at.add(16), at.add(4)),
                _mm256_loadu2_m128(at.add(20), at.add(8)),
            )
        };
        // SAFETY: inlined only into AVX2 code.
        unsafe { deinterleave!(_mm256_shuffle_ps, a, b, c) }
    }
    #[inline(always)]
    unsafe fn add(self, other: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_add_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn sub(self, other: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_sub_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn mul(self, other: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_mul_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn le(self, other: Self) -> __m256i {
        // An ordered compare: NaN is false.
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(self, other)) }
    }
    #[inline(always)]
    unsafe fn div(self, other: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_div_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn min(self, other: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_min_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn max(self, other: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_max_ps(self, other) }
    }
    #[inline(always)]
    unsafe fn abs(self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_and_ps(self, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX))) }
    }
    #[inline(always)]
    unsafe fn negate_where(self, mask: __m256i) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_xor_ps(self, _mm256_and_ps(_mm256_castsi256_ps(mask), _mm256_set1_ps(-0.0))) }
    }
    #[inline(always)]
    unsafe fn least(self) -> f32 {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm_min_ps(_mm256_castps256_ps128(self), _mm256_extractf128_ps::<1>(self)).least() }
    }
    #[inline(always)]
    unsafe fn greatest(self) -> f32 {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm_max_ps(_mm256_castps256_ps128(self), _mm256_extractf128_ps::<1>(self)).greatest() }
    }
    #[inline(always)]
    unsafe fn lt(self, other: Self) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(self, other)) }
    }
    #[inline(always)]
    unsafe fn gt(self, other: Self) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(self, other)) }
    }
    #[inline(always)]
    unsafe fn ge(self, other: Self) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OQ>(self, other)) }
    }
    #[inline(always)]
    unsafe fn select(mask: __m256i, a: Self, b: Self) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_blendv_ps(b, a, _mm256_castsi256_ps(mask)) }
    }
    #[inline(always)]
    unsafe fn to_bits(self) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_castps_si256(self) }
    }
    #[inline(always)]
    unsafe fn from_i32(a: __m256i) -> Self {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_cvtepi32_ps(a) }
    }
    #[inline(always)]
    unsafe fn splat_u32(v: u32) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_set1_epi32(v as i32) }
    }
    #[inline(always)]
    unsafe fn load_u32(at: *const u32) -> __m256i {
        // SAFETY: the caller gives eight readable u32.
        unsafe { _mm256_loadu_si256(at.cast()) }
    }
    #[inline(always)]
    unsafe fn eq_u32(a: __m256i, b: __m256i) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_cmpeq_epi32(a, b) }
    }
    #[inline(always)]
    unsafe fn and_u32(a: __m256i, b: __m256i) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_and_si256(a, b) }
    }
    #[inline(always)]
    unsafe fn sub_u32(a: __m256i, b: __m256i) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_sub_epi32(a, b) }
    }
    #[inline(always)]
    unsafe fn add_u32(a: __m256i, b: __m256i) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_add_epi32(a, b) }
    }
    #[inline(always)]
    unsafe fn lanes_above(k: i32) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_cmpgt_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(k)) }
    }
    #[inline(always)]
    unsafe fn sum_u32(a: __m256i) -> u32 {
        // SAFETY: inlined only into AVX2 code.
        unsafe {
            let halves = _mm_add_epi32(_mm256_castsi256_si128(a), _mm256_extracti128_si256::<1>(a));
            <__m128 as Vector>::sum_u32(halves)
        }
    }
    #[inline(always)]
    unsafe fn store_u32(a: __m256i, at: *mut u32) {
        // SAFETY: the caller gives eight writable u32.
        unsafe { _mm256_storeu_si256(at.cast(), a) }
    }
    #[inline(always)]
    unsafe fn pack_u16(high: __m256i, low: __m256i) -> __m256i {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_or_si256(_mm256_slli_epi32::<16>(high), _mm256_and_si256(low, _mm256_set1_epi32(0xffff))) }
    }
    #[inline(always)]
    unsafe fn store_pairs(low: __m256i, high: __m256i, at: *mut u64) {
        // Unpacking works within 128-bit halves, leaving lanes 0, 1, 4, 5
        // in one register and 2, 3, 6, 7 in the other; the permutes put
        // them back in order.
        // SAFETY: the caller gives eight writable u64, two 256-bit stores.
        unsafe {
            let (lows, highs) = (_mm256_unpacklo_epi32(low, high), _mm256_unpackhi_epi32(low, high));
            _mm256_storeu_si256(at.cast(), _mm256_permute2x128_si256::<0x20>(lows, highs));
            _mm256_storeu_si256(at.add(4).cast(), _mm256_permute2x128_si256::<0x31>(lows, highs));
        }
    }
    #[inline(always)]
    unsafe fn mask_bits(a: __m256i) -> u32 {
        // SAFETY: inlined only into AVX2 code.
        unsafe { _mm256_movemask_ps(_mm256_castsi256_ps(a)) as u32 }
    }
}

/// [`super::vectorised`]: `loop_body` inlined here, and so compiled for
/// AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn compiled<R>(loop_body: impl FnOnce() -> R) -> R {
    loop_body()
}

/// [`super::count_block`] in one register of eight lanes.
#[target_feature(enable = "avx2")]
pub(super) fn count_block(
    planes: Planes,
    first: usize,
    ranges: impl Iterator<Item = (usize, usize)> + Clone,
    radius_sq: f32,
) -> [u32; BLOCK] {
    // SAFETY: this function runs only where AVX2 does; 8 divides 8.
    unsafe { generic::count_block::<__m256>(planes, first, ranges, radius_sq) }
}

/// [`super::depth_range`] in one register of eight lanes.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn depth_range(z: &[f32; BLOCK]) -> (f32, f32) {
    // SAFETY: this function runs only where AVX2 does; 8 divides 8.
    unsafe { generic::depth_range::<__m256>(z) }
}

/// [`super::normal_test`] in one register of eight lanes.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn normal_test(planes: Planes, width: usize, first: usize, step: usize, test: &NormalTest) -> LaneMasks {
    // SAFETY: this function runs only where AVX2 does; 8 divides 8.
    unsafe { generic::normal_test::<__m256>(planes, width, first, step, test) }
}

/// [`super::tile_keys`] in one register of eight lanes.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn tile_keys(lanes: &[[f32; BLOCK]; 3], scales: &TileScales) -> [u64; BLOCK] {
    // SAFETY: this function runs only where AVX2 does; 8 divides 8.
    unsafe { generic::tile_keys::<__m256>(lanes, scales) }
}

/// [`super::count_runs_fused`]'s eight lanes: [`super::count_block`] over
/// runs, with the squared distance fused.
///
/// # Safety
/// The CPU must run AVX2 and FMA, and every run's pixels, and the seven
/// after each, must lie inside the planes.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn count_runs_fused(
    planes: Planes,
    first: usize,
    runs: &[(isize, usize)],
    radius_sq: f32,
) -> [u32; BLOCK] {
    // SAFETY: each slice holds eight floats.
    let at = |v: &[f32]| unsafe { _mm256_loadu_ps(v[first..first + BLOCK].as_ptr()) };
    let [px, py, pz] = [at(planes.xs), at(planes.ys), at(planes.zs)];
    let r2 = _mm256_set1_ps(radius_sq);
    let mut counts = _mm256_setzero_si256();
    let (xs, ys, zs) = (planes.xs.as_ptr(), planes.ys.as_ptr(), planes.zs.as_ptr());
    for &(offset, len) in runs {
        let start = first.wrapping_add_signed(offset);
        for k in start..start + len {
            // SAFETY: inside the planes, by the caller's promise.
            let (qx, qy, qz) =
                unsafe { (_mm256_loadu_ps(xs.add(k)), _mm256_loadu_ps(ys.add(k)), _mm256_loadu_ps(zs.add(k))) };
            // p - q, as the predicate has it: the load folds into the
            // subtraction.
            let (dx, dy, dz) = (_mm256_sub_ps(px, qx), _mm256_sub_ps(py, qy), _mm256_sub_ps(pz, qz));
            let d2 = _mm256_fmadd_ps(dz, dz, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dx, dx)));
            let near = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(d2, r2));
            // A true lane is all ones, -1: subtracting counts it.
            counts = _mm256_sub_epi32(counts, near);
        }
    }
    let mut out = [0u32; BLOCK];
    // SAFETY: `out` holds eight u32.
    unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), counts) };
    out
}

/// [`super::quad_boxes`] in eight lanes.
#[target_feature(enable = "avx2")]
pub(super) fn quad_boxes(rows: &[&[Point]], min_depth: f32, out: &mut [QuadBox]) {
    // SAFETY: this function runs only where AVX2 does; 4 divides 8.
    unsafe { generic::quad_boxes::<__m256>(rows, min_depth, out) }
}
