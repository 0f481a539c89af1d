//! The speed kernels' layer: which instruction set the fast paths run on,
//! the one distance predicate that their exactness depends on, and every
//! vector loop of the pipeline. The stages call the functions here and
//! hold no intrinsics of their own.
//!
//! The instruction set is chosen once per process ([`isa`]): the best the
//! CPU runs, or a lower one named by the environment variable
//! `WELDSEAM_ISA` (`scalar`, `sse2` or `avx2`), read once. Every kernel
//! asks [`isa`] rather than detecting the CPU itself, so a test can force
//! each level the machine runs and compare the results: every level
//! classifies every point identically (see the exactness invariant in
//! docs/ARCHITECTURE.md).
//!
//! The layout follows the usual split of portable SIMD code:
//! - [`scalar`]: each kernel in plain Rust, the reference of the others
//!   and the path on any CPU;
//! - [`vector`]: what a kernel asks of a register ([`vector::Vector`]);
//! - [`generic`]: each kernel written once over that trait;
//! - `sse2` and `avx2`: the trait in four and eight lanes, and thin entry
//!   points compiled for the instruction set that instantiate the generic
//!   kernels.
//!
//! The predicate "`q` lies within the radius of `p`" is [`within`] in
//! scalar form and [`generic::within`] in lanes: the same subtractions,
//! multiplies, additions and ordered compare in the same order, so the
//! same decision bit for bit, NaN (an invalid pixel) never within.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU8, Ordering};

#[cfg(target_arch = "x86_64")]
mod avx2;
mod generic;
mod scalar;
#[cfg(target_arch = "x86_64")]
mod sse2;
mod vector;

use crate::cloud::Point;

#[cfg(test)]
pub(crate) mod exactness;

/// The environment variable that lowers the instruction set.
pub const ISA_VARIABLE: &str = "WELDSEAM_ISA";

/// An instruction set level of the fast paths, lowest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Isa {
    /// Plain Rust, on any CPU: the reference form of every kernel.
    Scalar,
    /// Four lanes: the x86_64 baseline.
    Sse2,
    /// Eight lanes, where the CPU runs AVX2.
    Avx2,
}

impl Isa {
    /// Every level, lowest first.
    pub(crate) const ALL: [Isa; 3] = [Isa::Scalar, Isa::Sse2, Isa::Avx2];

    /// The level's name, as `WELDSEAM_ISA` spells it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Sse2 => "sse2",
            Isa::Avx2 => "avx2",
        }
    }

    fn parse(name: &str) -> Option<Isa> {
        Isa::ALL.into_iter().find(|isa| isa.name().eq_ignore_ascii_case(name.trim()))
    }

    /// Whether this CPU runs the level.
    pub(crate) fn supported(self) -> bool {
        match self {
            Isa::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Sse2 | Isa::Avx2 => false,
        }
    }

    /// The highest level this CPU runs.
    fn best() -> Isa {
        Isa::ALL.into_iter().rev().find(|isa| isa.supported()).unwrap_or(Isa::Scalar)
    }

    /// The level for a `WELDSEAM_ISA` value: the one it names, lowered to
    /// the best this CPU runs; the best for no value or one that names no
    /// level (the fast paths cannot fail, and every level gives the same
    /// results, so a wrong value costs speed at most).
    fn chosen_by(value: Option<&str>) -> Isa {
        let best = Isa::best();
        value.and_then(Isa::parse).map_or(best, |named| named.min(best))
    }
}

/// The level chosen once for the process; see the module documentation.
static CHOSEN: OnceLock<Isa> = OnceLock::new();

/// A level forced by `with_isa` (in tests), as its index in [`Isa::ALL`] plus one;
/// zero when none is.
static FORCED: AtomicU8 = AtomicU8::new(0);

/// The instruction set the fast paths run on now.
#[inline]
pub(crate) fn isa() -> Isa {
    match FORCED.load(Ordering::Relaxed) {
        0 => *CHOSEN.get_or_init(|| Isa::chosen_by(std::env::var(ISA_VARIABLE).ok().as_deref())),
        k => Isa::ALL[k as usize - 1],
    }
}

/// Whether the AVX2 paths may also fuse multiply and add (FMA), for the
/// kernels whose fused form is a documented bound rather than the
/// predicate itself.
#[inline]
pub(crate) fn fused() -> bool {
    static FMA: OnceLock<bool> = OnceLock::new();
    #[cfg(target_arch = "x86_64")]
    let fma = *FMA.get_or_init(|| std::arch::is_x86_feature_detected!("fma"));
    #[cfg(not(target_arch = "x86_64"))]
    let fma = *FMA.get_or_init(|| false);
    isa() == Isa::Avx2 && fma
}

/// Runs `compute` with the fast paths on `level`, or returns `None` when
/// this CPU does not run it. Forcing is process-wide (rayon's workers
/// must see it too), so forced computations take turns; a computation
/// that forces nothing may meanwhile run on the forced level, which gives
/// it the same results.
#[cfg(test)]
pub(crate) fn with_isa<R>(level: Isa, compute: impl FnOnce() -> R) -> Option<R> {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    /// Lifts the force when the computation ends, panicking or not.
    struct Lift;
    impl Drop for Lift {
        fn drop(&mut self) {
            FORCED.store(0, Ordering::Relaxed);
        }
    }
    if !level.supported() {
        return None;
    }
    let _turn = TURN.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let index = Isa::ALL.iter().position(|&isa| isa == level).expect("every level is in ALL");
    FORCED.store(index as u8 + 1, Ordering::Relaxed);
    let _lift = Lift;
    Some(compute())
}

/// Runs `compute` once on every level this CPU runs, and returns the
/// levels it ran on and the ones it skipped, with the results.
#[cfg(test)]
pub(crate) fn on_every_isa<R>(mut compute: impl FnMut(Isa) -> R) -> (Vec<(Isa, R)>, Vec<Isa>) {
    let (mut ran, mut skipped) = (Vec::new(), Vec::new());
    for level in Isa::ALL {
        match with_isa(level, || compute(level)) {
            Some(result) => ran.push((level, result)),
            None => skipped.push(level),
        }
    }
    if !skipped.is_empty() {
        let names: Vec<_> = skipped.iter().map(|isa| isa.name()).collect();
        eprintln!("this CPU does not run {}: those paths were not tested here", names.join(", "));
    }
    (ran, skipped)
}

/// True when `q` lies within `radius_sq` (squared) of `p`: the predicate of
/// every neighbour count, grid or tree, scalar or vector. The difference
/// is `p - q` (its negation squares to the same bits, and a vector load
/// folds into this order), squared and summed x, y, z without fusing;
/// NaN compares false, so an invalid pixel is never within.
#[inline(always)]
pub(crate) fn within(p: &[f32; 3], q: &[f32; 3], radius_sq: f32) -> bool {
    let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    dx * dx + dy * dy + dz * dz <= radius_sq
}

/// Pixels of a grid row counted together by [`count_block`].
pub(crate) const BLOCK: usize = 8;

/// An organized cloud's coordinates as three row-major planes, which the
/// block counts load lanes from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Planes<'a> {
    pub xs: &'a [f32],
    pub ys: &'a [f32],
    pub zs: &'a [f32],
}

impl Planes<'_> {
    /// Point `i`, row-major.
    #[inline(always)]
    pub(crate) fn point(&self, i: usize) -> Point {
        [self.xs[i], self.ys[i], self.zs[i]]
    }
}

/// For the [`BLOCK`] pixels from index `first`, the pixels within
/// `radius_sq` of each among those at the same offsets from it, where
/// `ranges` gives the offsets as index ranges of the first pixel's
/// neighbours. Every range, shifted by up to `BLOCK - 1`, must lie inside
/// the planes (it panics otherwise).
#[inline]
pub(crate) fn count_block(
    planes: Planes,
    first: usize,
    ranges: impl Iterator<Item = (usize, usize)> + Clone,
    radius_sq: f32,
) -> [u32; BLOCK] {
    match isa() {
        // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { avx2::count_block(planes, first, ranges, radius_sq) },
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => unsafe { sse2::count_block(planes, first, ranges, radius_sq) },
        _ => scalar::count_block(planes, first, ranges, radius_sq),
    }
}

/// [`count_block`] over runs `(offset from first, length)` with the
/// squared distance fused into two multiply-adds, where the chosen level
/// is AVX2 and the CPU fuses ([`fused`]); `None` elsewhere. It rounds
/// differently from [`within`]: the caller lowers `radius_sq` by enough
/// to count no point the predicate leaves out.
///
/// # Safety
/// Every run's pixels, and the `BLOCK - 1` after each, must lie inside
/// the planes.
#[inline]
pub(crate) unsafe fn count_runs_fused(
    planes: Planes,
    first: usize,
    runs: &[(isize, usize)],
    radius_sq: f32,
) -> Option<[u32; BLOCK]> {
    #[cfg(target_arch = "x86_64")]
    if fused() {
        // SAFETY: the CPU runs AVX2 and FMA (`fused`), and the runs lie
        // inside the planes by the caller's promise.
        return Some(unsafe { avx2::count_runs_fused(planes, first, runs, radius_sq) });
    }
    let _ = (planes, first, runs, radius_sq);
    None
}

/// Runs `loop_body`, plain Rust that the compiler vectorises, compiled
/// for AVX2 where that is the chosen level: for loops whose every lane
/// does the same unfused operations as the scalar form, so the level
/// changes the speed and never the result.
#[inline]
pub(crate) fn vectorised<R>(loop_body: impl FnOnce() -> R) -> R {
    match isa() {
        // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { avx2::compiled(loop_body) },
        _ => loop_body(),
    }
}

/// The corner of a row's members: their least depth and largest `|x|` and
/// `|y|`, NaN skipped; `None` when the row has no member. Its window holds
/// every member's own.
#[inline]
pub(crate) fn members_corner<const N: usize>(
    labels: &[u32],
    points: &[Point],
    plate_labels: [u32; N],
) -> Option<Point> {
    let n = labels.len().min(points.len());
    let (mut corner, done) = match isa() {
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 | Isa::Avx2 => {
            let done = n / 4 * 4;
            // SAFETY: SSE2 is part of the x86_64 baseline.
            (unsafe { sse2::members_corner(&labels[..done], &points[..done], plate_labels) }, done)
        }
        _ => (scalar::Corner::default(), 0),
    };
    for (&label, p) in labels[done..n].iter().zip(&points[done..n]) {
        if plate_labels.contains(&label) {
            corner.add(p);
        }
    }
    corner.any.then_some([corner.x_max, corner.y_max, corner.z_min])
}

pub(crate) use scalar::RowBounds;
pub use scalar::{cross, cross_agrees};

impl<const N: usize> RowBounds<'_, N> {
    /// [`RowBounds::open_members`] for the columns `cols` (a multiple of
    /// four, every window inside the row and of `area` pixels) with the
    /// threshold `ratio · full[c]`, four columns at a time; false, with
    /// nothing appended, where the level has no vector form.
    #[inline]
    pub(crate) fn open_members_in_quads(
        &self,
        cols: std::ops::Range<usize>,
        area: u32,
        full: &[u16],
        ratio: f64,
        open: &mut Vec<(u32, u8)>,
    ) -> bool {
        match isa() {
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 | Isa::Avx2 => {
                // SAFETY: SSE2 is part of the x86_64 baseline.
                unsafe { sse2::open_members(self, cols, area, full, ratio, open) };
                true
            }
            _ => false,
        }
    }
}

/// A labelled organized cloud: the points and one label per point.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LabelledGrid<'a> {
    pub points: &'a [Point],
    pub labels: &'a [u32],
    pub width: usize,
    pub height: usize,
}

/// The question [`labelled_count_at_most`] answers for one pixel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LabelledWindow {
    /// The pixel's index, row-major.
    pub centre: usize,
    /// The window's half-size in columns and rows.
    pub window: (usize, usize),
    /// The label the neighbours counted must have.
    pub label: u32,
    pub radius_sq: f32,
    /// The count the answer is about.
    pub threshold: f64,
}

/// True when the pixel of `query` has at most `query.threshold`
/// neighbours labelled `query.label` within `query.radius_sq` over its
/// window, clipped to the image: the count of the predicate over that
/// window, stopped once it exceeds the threshold.
#[inline]
pub(crate) fn labelled_count_at_most(grid: &LabelledGrid, query: &LabelledWindow) -> bool {
    match isa() {
        // Where AVX2 runs, the four-lane form counts the edge criterion's
        // rows too: an eight-lane form over the vector trait took 150 ms a
        // plan on the bench's frames where this takes 15 (its rows are a
        // dozen pixels, and the eight-lane point load did not pay there).
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 | Isa::Sse2 => unsafe { sse2::labelled_count_at_most(grid, query) },
        _ => scalar::labelled_count_at_most(grid, query),
    }
}

/// The nearest and farthest valid depth of a block's lanes: a NaN
/// (invalid) lane never counts, and a block without a valid lane gives
/// `(inf, -inf)`.
#[inline(always)]
pub(crate) fn depth_range(z: &[f32; BLOCK]) -> (f32, f32) {
    match isa() {
        // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { avx2::depth_range(z) },
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => unsafe { sse2::depth_range(z) },
        _ => scalar::depth_range(z),
    }
}

/// The box of the points of one quad ([`QUAD`] columns over a band of
/// rows) that have a ray: finite, and deeper than the band's least depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct QuadBox {
    /// Per coordinate, the least and greatest over those points
    /// (`inf`, `-inf` for none).
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// How many points have a ray, and how many are finite.
    pub binned: u32,
    pub finite: u32,
}

/// The columns of a quad.
pub(crate) const QUAD: usize = 4;

impl QuadBox {
    /// The box of no point.
    pub(crate) const EMPTY: QuadBox =
        QuadBox { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3], binned: 0, finite: 0 };
}

/// The boxes of a band of rows' quads: `out[q]` is the box of columns
/// `QUAD * q` to `QUAD * q + QUAD` (fewer for the last of a row no whole
/// number of quads long) of every row, over the points whose coordinates
/// are all finite (an empty pixel's are NaN) and whose depth exceeds
/// `min_depth`. Every row is as long as the first, and `out` holds a box
/// for each of its quads. The lane forms give the same boxes as the
/// scalar one, a zero's sign aside (a least of `0.0` and `-0.0` is
/// either).
pub(crate) fn quad_boxes(rows: &[&[Point]], min_depth: f32, out: &mut [QuadBox]) {
    let columns = rows.first().map_or(0, |row| row.len());
    assert!(rows.iter().all(|row| row.len() == columns), "a band's rows are equally long");
    assert_eq!(out.len(), columns.div_ceil(QUAD), "a box for every quad");
    match isa() {
        // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { avx2::quad_boxes(rows, min_depth, out) },
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => unsafe { sse2::quad_boxes(rows, min_depth, out) },
        _ => scalar::quad_boxes(rows, 0, min_depth, out),
    }
}

/// The robust plane criterion's normal test, the rule it adds to the
/// paper's count (Eq. 14): the grid normal from the central differences
/// at a step must lie within the angle whose squared cosine is `cos_sq`
/// of the unit `reference`, the workpiece's normal.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NormalTest {
    pub reference: [f32; 3],
    pub cos_sq: f32,
}

/// Bit `l` of each field is lane `l`'s answer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct LaneMasks {
    /// The lane and its four neighbours at the step are valid.
    pub complete: u32,
    /// The lane's grid normal passes the test (meaningful when complete).
    pub facing: u32,
}

/// [`NormalTest`] for the [`BLOCK`] pixels from index `first` of planes
/// `width` pixels wide, each against its neighbours `step` pixels left,
/// right, up and down, which must all lie inside the planes (it panics
/// otherwise). The same bits on every level: the scalar form is the
/// criterion's own `cross_agrees(cross(du, dv), ..)` lane by lane.
#[inline(always)]
pub(crate) fn normal_test(planes: Planes, width: usize, first: usize, step: usize, test: &NormalTest) -> LaneMasks {
    match isa() {
        // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { avx2::normal_test(planes, width, first, step, test) },
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => unsafe { sse2::normal_test(planes, width, first, step, test) },
        _ => scalar::normal_test(planes, width, first, step, test),
    }
}

/// What a full-count memo key measures a point by: tiles per unit of
/// `x / z` and of `y / z`, and depth steps per millimetre.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TileScales {
    pub tiles_per_x: f32,
    pub tiles_per_y: f32,
    pub steps_per_mm: f32,
}

/// The full-count memo key of a valid point: its tile row and column
/// (16 bits each, from the floors of `y / z` and `x / z` in tiles) and
/// its depth step (rounded). Every path computes keys with this function
/// or [`tile_keys`], which gives the same keys.
#[inline(always)]
pub(crate) fn tile_key(p: &Point, scales: &TileScales) -> u64 {
    scalar::tile_key(p, scales)
}

/// [`tile_key`] of the [`BLOCK`] points given as coordinate lanes.
#[inline(always)]
pub(crate) fn tile_keys(lanes: &[[f32; BLOCK]; 3], scales: &TileScales) -> [u64; BLOCK] {
    match isa() {
        // SAFETY: the CPU runs AVX2: `isa` gives no level it lacks.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { avx2::tile_keys(lanes, scales) },
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => unsafe { sse2::tile_keys(lanes, scales) },
        _ => scalar::tile_keys(lanes, scales),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_named_level_is_lowered_to_what_the_cpu_runs() {
        let best = Isa::best();
        assert_eq!(Isa::chosen_by(None), best);
        assert_eq!(Isa::chosen_by(Some("scalar")), Isa::Scalar);
        assert_eq!(Isa::chosen_by(Some(" AVX2 ")), Isa::Avx2.min(best));
        assert_eq!(Isa::chosen_by(Some("sse2")), Isa::Sse2.min(best));
        assert_eq!(Isa::chosen_by(Some("neon")), best, "an unknown name keeps the best");
        assert!(best.supported() && Isa::Scalar.supported());
    }

    #[test]
    fn forcing_a_level_holds_for_the_computation_and_is_lifted_after() {
        let (ran, skipped) = on_every_isa(|level| (level, isa()));
        assert!(ran.iter().all(|(level, (inside, seen))| level == inside && inside == seen));
        assert_eq!(ran.len() + skipped.len(), Isa::ALL.len());
        assert_eq!(ran[0].0, Isa::Scalar, "every CPU runs the scalar form");
        let rayon_sees = with_isa(Isa::Scalar, || rayon::join(isa, isa)).unwrap();
        assert_eq!(rayon_sees, (Isa::Scalar, Isa::Scalar), "forcing reaches rayon's workers");
    }

    #[test]
    fn floor_i32_floors_and_clamps() {
        for x in [-3.5f32, -3.0, -2.5, -0.5, -0.0, 0.0, 0.25, 0.5, 1.0, 1.5, 2.5, 2.999_999_8, 1234.5, -1234.5] {
            assert_eq!(scalar::floor_i32(x), x.floor() as i32, "{x}");
        }
        assert_eq!(scalar::floor_i32(1e9), 4_000_000);
        assert_eq!(scalar::floor_i32(f32::NEG_INFINITY), -4_000_000);
        assert_eq!(scalar::floor_i32(f32::NAN), -4_000_000);
    }

    #[test]
    fn the_predicate_counts_the_rim_and_never_an_invalid_pixel() {
        let p = [1.0, 2.0, 600.0];
        assert!(within(&p, &[1.0, 2.0, 601.0], 1.0), "on the rim");
        assert!(!within(&p, &[1.0, 2.0, 601.0001], 1.0));
        assert!(!within(&p, &[f32::NAN; 3], f32::INFINITY));
        assert!(!within(&[f32::NAN; 3], &p, f32::INFINITY));
    }

    #[test]
    fn every_form_of_the_span_count_equals_the_scalar_predicate() {
        // Distances on both sides of the radius, exact ties, invalid
        // points and other labels, over every span length to 23 and every
        // start, so that each lane position meets each case.
        let p = [0.25f32, -0.5, 600.0];
        let offsets = [0.0f32, 0.5, 0.999_999, 1.0, 1.000_001, 0.6, 0.8, 2.0, 0.7];
        let points: Vec<Point> = (0..40)
            .map(|k| {
                let d = offsets[k % offsets.len()];
                match k % 4 {
                    _ if k % 11 == 3 => [f32::NAN; 3],
                    0 => [p[0] + d, p[1], p[2]],
                    1 => [p[0], p[1] - d, p[2]],
                    2 => [p[0], p[1], p[2] + d],
                    _ => [p[0] + 0.6 * d, p[1] + 0.8 * d, p[2]],
                }
            })
            .collect();
        let labels: Vec<u32> = (0..40).map(|k| if k % 5 == 2 { 3 } else { 1 }).collect();
        let mut counted = 0;
        for start in 0..17 {
            for len in 0..24.min(40 - start) {
                let span = start..start + len;
                let (points, labels) = (&points[span.clone()], &labels[span]);
                let scalar = scalar::count_span(&p, points, labels, 1, 1.0);
                #[cfg(target_arch = "x86_64")]
                {
                    // SAFETY: SSE2 is part of the x86_64 baseline.
                    let quads = unsafe { sse2::count_span(&p, points, labels, 1, 1.0) };
                    assert_eq!(quads, scalar, "SSE2, {start} + {len}");
                }
                counted += scalar;
            }
        }
        assert!(counted > 1000);
    }

    /// A fixed pseudo-random sequence for the SIMD tests.
    fn noise(n: usize, seed: u64) -> Vec<u32> {
        let mut x = seed;
        (0..n)
            .map(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (x >> 33) as u32
            })
            .collect()
    }

    #[test]
    fn every_form_of_the_members_corner_equals_the_scalar_one() {
        let n = 64;
        let r = noise(4 * n, 7);
        let labels: Vec<u32> = r[..n].iter().map(|v| v % 4).collect();
        let points: Vec<Point> = (0..n)
            .map(|k| {
                let v = |j: usize| (r[n + 3 * k + j] % 2000) as f32 - 1000.0;
                if r[k].is_multiple_of(9) { [f32::NAN; 3] } else { [v(0), v(1), v(2).abs() + 1.0] }
            })
            .collect();
        for len in (0..=n).step_by(4) {
            for plates in [[1, 2], [3, 7], [8, 9]] {
                let mut scalar = scalar::Corner::default();
                for (l, p) in labels[..len].iter().zip(&points[..len]) {
                    if plates.contains(l) {
                        scalar.add(p);
                    }
                }
                let scalar = scalar.any.then_some([scalar.x_max, scalar.y_max, scalar.z_min]);
                let (ran, _skipped) = on_every_isa(|_| members_corner(&labels[..len], &points[..len], plates));
                for (isa, corner) in ran {
                    assert_eq!(corner, scalar, "{len} pixels, plates {plates:?}, {isa:?}");
                }
            }
        }
    }

    #[test]
    fn four_column_bounds_equal_the_scalar_ones() {
        fn check<const N: usize>(plate_labels: [u32; N], seed: u64) -> usize {
            let w = 70;
            let r = noise(4 * w, seed);
            let labels: Vec<u32> = r[..w].iter().map(|v| if v % 7 == 0 { 5 } else { v % 2 }).collect();
            let counts: Vec<u16> = r[w..2 * w].iter().map(|v| (v % 120) as u16).collect();
            let full: Vec<u16> = r[2 * w..3 * w].iter().map(|v| (v % 100 + 40) as u16).collect();
            let mut opened = 0;
            for (wx, window_rows) in [(0, 1), (2, 5), (6, 13), (9, 3)] {
                // Column sums of `window_rows` rows, made up from the row's
                // own codes at different multiples.
                let field = 32 / N as u32;
                let columns: Vec<u32> = (0..w)
                    .map(|c| {
                        let code = |k: usize| (labels[c] == plate_labels[k]) as u32;
                        let rows = (r[3 * w + c] as usize % window_rows) as u32 + code(0).max(code(N - 1));
                        (0..N).map(|k| (code(k) * rows) << (k as u32 * field)).sum()
                    })
                    .collect();
                let prefix: Vec<u32> = std::iter::once(0)
                    .chain(columns.iter().scan(0u32, |s, &c| {
                        *s = s.wrapping_add(c);
                        Some(*s)
                    }))
                    .collect();
                let bounds =
                    RowBounds { plate_labels, prefix: &prefix, labels: &labels, counts: &counts, wx, window_rows };
                let area = ((2 * wx + 1) * window_rows) as u32;
                let quads = wx..wx + (w - 2 * wx) / 4 * 4;
                for ratio in [0.2, 0.75, 1.3] {
                    let mut scalar = Vec::new();
                    bounds.open_members(quads.clone(), |c| ratio * full[c] as f64, &mut scalar);
                    let mut simd = Vec::new();
                    if !bounds.open_members_in_quads(quads.clone(), area, &full, ratio, &mut simd) {
                        simd.clone_from(&scalar);
                    }
                    assert_eq!(simd, scalar, "wx {wx}, {window_rows} rows, ratio {ratio}");
                    opened += simd.len();
                }
            }
            opened
        }
        // Some members open and some settled in each case.
        for opened in [check([1], 3), check([0, 1], 4), check([1, 0], 5)] {
            assert!((20..600).contains(&opened), "{opened} opened");
        }
    }

    /// A coordinate as a frame may hold it: a plain value, a zero of
    /// either sign, an empty pixel's NaN, an infinity, or a depth at the
    /// camera's plane.
    fn coordinate() -> impl proptest::strategy::Strategy<Value = f32> {
        use proptest::prelude::*;
        prop_oneof![
            6 => -400.0f32..400.0,
            1 => Just(f32::NAN),
            1 => prop_oneof![Just(0.0f32), Just(-0.0), Just(f32::INFINITY), Just(f32::NEG_INFINITY), Just(0.5)],
        ]
    }

    use proptest::strategy::Strategy;

    proptest::proptest! {
        #[test]
        fn every_form_of_the_quad_boxes_equals_the_scalar_one(
            band in (0usize..45, 1usize..=4).prop_flat_map(|(columns, rows)| {
                proptest::collection::vec(
                    proptest::collection::vec(proptest::array::uniform3(coordinate()), columns..=columns), rows..=rows)
            }),
        ) {
            let rows: Vec<&[Point]> = band.iter().map(Vec::as_slice).collect();
            let quads = rows[0].len().div_ceil(QUAD);
            let (ran, _skipped) = on_every_isa(|_| {
                let mut out = vec![QuadBox::EMPTY; quads];
                quad_boxes(&rows, 0.5, &mut out);
                out
            });
            let mut scalar = vec![QuadBox::EMPTY; quads];
            scalar::quad_boxes(&rows, 0, 0.5, &mut scalar);
            for (isa, boxes) in ran {
                // `==` on the floats: a zero's sign aside, the same boxes.
                proptest::prop_assert_eq!(&boxes, &scalar, "{:?}", isa);
            }
            // Point by point: every point with a ray is inside its quad's
            // box, and the counts are the points'.
            for (q, b) in scalar.iter().enumerate() {
                let points = rows.iter().flat_map(|row| &row[q * QUAD..((q + 1) * QUAD).min(row.len())]);
                let finite: Vec<&Point> = points.filter(|p| p.iter().all(|c| c.is_finite())).collect();
                let with_ray: Vec<&Point> = finite.iter().copied().filter(|p| p[2] > 0.5).collect();
                proptest::prop_assert_eq!((b.finite as usize, b.binned as usize), (finite.len(), with_ray.len()));
                for k in 0..3 {
                    let least = with_ray.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min);
                    let greatest = with_ray.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max);
                    proptest::prop_assert!(b.min[k] == least && b.max[k] == greatest);
                }
            }
        }
    }
}
