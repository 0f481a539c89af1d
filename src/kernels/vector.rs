//! What the kernels ask of a vector register: lanes of `f32` coordinates
//! and, beside them, lanes of `u32` labels and counts. The algorithms in
//! [`super::generic`] are written once over this trait; [`super::sse2`]
//! and [`super::avx2`] implement it in four and eight lanes.
//!
//! Every method is an `unsafe fn` marked `#[inline(always)]` in the
//! implementations: it may only be called where the instruction set is
//! known to run, and it is meant to be inlined into a function compiled
//! for that set (`#[target_feature]`), never called on its own.

use crate::cloud::Point;

/// A register of [`Vector::LANES`] `f32` lanes, with the integer register
/// of as many `u32` lanes that its compares and counts live in.
///
/// # Safety
/// An implementation's methods must do what they say on every input,
/// once the CPU runs its instruction set; the kernels rely on it for the
/// bounds of their loads.
pub(crate) unsafe trait Vector: Copy {
    /// Lanes per register.
    const LANES: usize;
    /// A register of `LANES` u32 lanes.
    type Int: Copy;

    /// Every lane `v`.
    unsafe fn splat(v: f32) -> Self;
    /// `LANES` consecutive floats from `at`, unaligned.
    unsafe fn load(at: *const f32) -> Self;
    /// The x, y and z lanes of `LANES` consecutive points from `at`.
    unsafe fn load_points(at: *const Point) -> [Self; 3];
    unsafe fn add(self, other: Self) -> Self;
    unsafe fn sub(self, other: Self) -> Self;
    unsafe fn mul(self, other: Self) -> Self;
    unsafe fn div(self, other: Self) -> Self;
    /// Lane by lane `if self < other { self } else { other }`: `other`
    /// where either lane is NaN, as the x86 instructions have it.
    unsafe fn min(self, other: Self) -> Self;
    /// Lane by lane `if self > other { self } else { other }`.
    unsafe fn max(self, other: Self) -> Self;
    /// Lane by lane `a` where `mask` (a compare's result) is all ones,
    /// `b` where it is all zeros.
    unsafe fn select(mask: Self::Int, a: Self, b: Self) -> Self;
    /// The lanes without their sign bit.
    unsafe fn abs(self) -> Self;
    /// The lanes with their sign bit flipped where `mask` is all ones:
    /// multiplying by -1 without rounding.
    unsafe fn negate_where(self, mask: Self::Int) -> Self;
    /// The least lane, by `min`; the lanes hold no NaN.
    unsafe fn least(self) -> f32;
    /// The greatest lane, by `max`; the lanes hold no NaN.
    unsafe fn greatest(self) -> f32;
    /// All ones where `self <= other`, by an ordered compare: a NaN lane
    /// is never less or equal.
    unsafe fn le(self, other: Self) -> Self::Int;
    /// All ones where `self < other`, ordered.
    unsafe fn lt(self, other: Self) -> Self::Int;
    /// All ones where `self > other`, ordered.
    unsafe fn gt(self, other: Self) -> Self::Int;
    /// All ones where `self >= other`, ordered.
    unsafe fn ge(self, other: Self) -> Self::Int;
    /// The lanes' bits as u32 lanes, unconverted.
    unsafe fn to_bits(self) -> Self::Int;
    /// The i32 lanes of `a` converted to the nearest floats.
    unsafe fn from_i32(a: Self::Int) -> Self;

    /// Every lane `v`.
    unsafe fn splat_u32(v: u32) -> Self::Int;
    /// `LANES` consecutive u32 from `at`, unaligned.
    unsafe fn load_u32(at: *const u32) -> Self::Int;
    /// All ones where the lanes are equal.
    unsafe fn eq_u32(a: Self::Int, b: Self::Int) -> Self::Int;
    unsafe fn and_u32(a: Self::Int, b: Self::Int) -> Self::Int;
    /// Lane by lane `a - b`, wrapping.
    unsafe fn sub_u32(a: Self::Int, b: Self::Int) -> Self::Int;
    /// Lane by lane `a + b`, wrapping.
    unsafe fn add_u32(a: Self::Int, b: Self::Int) -> Self::Int;
    /// All ones in the lanes whose index exceeds `k` (every lane for a
    /// negative `k`).
    unsafe fn lanes_above(k: i32) -> Self::Int;
    /// The lanes' sum, wrapping.
    unsafe fn sum_u32(a: Self::Int) -> u32;
    /// Stores the lanes to `LANES` u32 at `at`, unaligned.
    unsafe fn store_u32(a: Self::Int, at: *mut u32);
    /// Lane by lane `high << 16 | (low & 0xffff)`: two 16-bit fields.
    unsafe fn pack_u16(high: Self::Int, low: Self::Int) -> Self::Int;
    /// Stores `LANES` u64 to `at`, unaligned: lane `l`'s `low` in the low
    /// half of the `l`-th, its `high` in the high half.
    unsafe fn store_pairs(low: Self::Int, high: Self::Int, at: *mut u64);
    /// Bit `l` set where lane `l` of a compare's result is all ones.
    unsafe fn mask_bits(a: Self::Int) -> u32;
}
