//! The kernels' eight-lane forms, where the CPU runs AVX2.

use std::arch::x86_64::*;

/// [`super::within`] of eight lanes: all ones where `q` lies within
/// `radius_sq` of `p`, by the same operations in the same order.
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn within([px, py, pz]: [__m256; 3], [qx, qy, qz]: [__m256; 3], radius_sq: __m256) -> __m256 {
    let (dx, dy, dz) = (_mm256_sub_ps(px, qx), _mm256_sub_ps(py, qy), _mm256_sub_ps(pz, qz));
    let d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    // An ordered compare: NaN is false.
    _mm256_cmp_ps::<_CMP_LE_OQ>(d2, radius_sq)
}
