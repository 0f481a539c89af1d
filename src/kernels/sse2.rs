//! The kernels' four-lane forms in SSE2, the x86_64 baseline.

use std::arch::x86_64::*;

/// [`super::within`] of four lanes: all ones where `q` lies within
/// `radius_sq` of `p`, by the same operations in the same order.
#[target_feature(enable = "sse2")]
#[inline]
pub(crate) fn within([px, py, pz]: [__m128; 3], [qx, qy, qz]: [__m128; 3], radius_sq: __m128) -> __m128 {
    let (dx, dy, dz) = (_mm_sub_ps(px, qx), _mm_sub_ps(py, qy), _mm_sub_ps(pz, qz));
    let d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    // An ordered compare: NaN is false.
    _mm_cmple_ps(d2, radius_sq)
}
