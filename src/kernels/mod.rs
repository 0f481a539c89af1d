//! The speed kernels' layer: which instruction set the fast paths run on,
//! and the one distance predicate that their exactness depends on.
//!
//! The instruction set is chosen once per process ([`isa`]): the best the
//! CPU runs, or a lower one named by the environment variable
//! `WELDSEAM_ISA` (`scalar`, `sse2` or `avx2`), read once. Every stage
//! asks [`isa`] rather than detecting the CPU itself, so a test can force
//! each level the machine runs and compare the results: every level
//! classifies every point identically (see the exactness invariant in
//! docs/ARCHITECTURE.md).
//!
//! The predicate "`q` lies within the radius of `p`" is [`within`] in
//! scalar form and [`sse2::within`] / [`avx2::within`] in four and eight
//! lanes: the same subtractions, multiplies, additions and ordered
//! compare in the same order, so the same decision bit for bit, NaN
//! (an invalid pixel) never within.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU8, Ordering};

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx2;
#[cfg(target_arch = "x86_64")]
pub(crate) mod sse2;

#[cfg(test)]
mod exactness;

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

/// A level forced by [`with_isa`], as its index in [`Isa::ALL`] plus one;
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
    fn the_predicate_counts_the_rim_and_never_an_invalid_pixel() {
        let p = [1.0, 2.0, 600.0];
        assert!(within(&p, &[1.0, 2.0, 601.0], 1.0), "on the rim");
        assert!(!within(&p, &[1.0, 2.0, 601.0001], 1.0));
        assert!(!within(&p, &[f32::NAN; 3], f32::INFINITY));
        assert!(!within(&[f32::NAN; 3], &p, f32::INFINITY));
    }
}
