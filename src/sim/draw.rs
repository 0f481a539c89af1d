//! Which draw of a seeded suite a run plans: the documented one, or a
//! fresh one that nobody has looked at.
//!
//! Every suite is drawn from fixed seeds, so its scenes are the same on
//! every call: the tables of docs/ACCURACY.md were measured on them, the
//! planner's rules were built looking at their tuning scenes, and a change
//! is checked against them plan for plan. That makes the documented draw a
//! regression test, and its few `-holdout` scenes the only evidence on
//! scenes nothing was tuned on.
//!
//! A fresh draw keeps the suite's strata (joint, standoff, tilt, fault,
//! the framing each scene must meet) and redraws everything random from
//! seeds derived from the documented ones and the draw's number, so a
//! rate (of confident wrong seams, say) can be measured on as many unseen
//! scenes as a run has time for, and a rule checked on scenes it was not
//! built on. Its scenes are all unseen: their names end in `-freshN`
//! instead of `-holdout`, and `weldseam simulate --scene` reads the
//! number back from the name.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

/// Which draw of a suite.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Draw {
    /// The suite as documented: its own seeds.
    #[default]
    Documented,
    /// Fresh draw number N (any N; the command line takes 1 and up): the
    /// same strata, every random choice redrawn.
    Fresh(u32),
}

/// Keeps a fresh draw's seeds apart from any suite's documented seeds,
/// which are small constants.
const FRESH_KEY: u64 = 0xf7e5_4d7a_0c1e_a2b9;

/// What a fresh scene's name ends in, before its number.
const FRESH_SUFFIX: &str = "-fresh";
/// What a documented held-out scene's name ends in.
const HOLDOUT_SUFFIX: &str = "-holdout";

impl Draw {
    /// The seed to draw from where the documented suite draws from
    /// `documented`: that seed itself, or one of ChaCha8's output words
    /// keyed by it, on the draw's own stream.
    pub fn seed(self, documented: u64) -> u64 {
        match self {
            Draw::Documented => documented,
            Draw::Fresh(number) => {
                let mut rng = ChaCha8Rng::seed_from_u64(documented ^ FRESH_KEY);
                rng.set_stream(u64::from(number));
                rng.next_u64()
            }
        }
    }

    /// What a scene's name ends in: `-holdout` for a documented held-out
    /// scene, nothing for a documented tuning scene, `-freshN` for every
    /// scene of fresh draw N.
    pub fn suffix(self, held_out: bool) -> String {
        match self {
            Draw::Documented if held_out => HOLDOUT_SUFFIX.to_string(),
            Draw::Documented => String::new(),
            Draw::Fresh(number) => format!("{FRESH_SUFFIX}{number}"),
        }
    }

    /// The draw a scene's name comes from: fresh draw N for a name ending
    /// in `-freshN`, the documented draw for any other.
    pub fn of_scene(name: &str) -> Draw {
        name.rsplit_once(FRESH_SUFFIX).and_then(|(_, number)| number.parse().ok()).map_or(Draw::Documented, Draw::Fresh)
    }
}

/// Whether nothing was tuned on the scene of this name: a documented
/// held-out scene, or any scene of a fresh draw.
pub fn is_unseen(name: &str) -> bool {
    name.ends_with(HOLDOUT_SUFFIX) || Draw::of_scene(name) != Draw::Documented
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_documented_draw_keeps_the_suites_seeds_and_fresh_draws_do_not() {
        assert_eq!(Draw::Documented.seed(0x5eed_2024), 0x5eed_2024);
        let fresh: Vec<u64> = (1..=4).map(|n| Draw::Fresh(n).seed(0x5eed_2024)).collect();
        assert!(fresh.iter().all(|s| *s != 0x5eed_2024));
        let mut distinct = fresh.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), fresh.len(), "each fresh draw has its own seed: {fresh:x?}");
        assert_ne!(Draw::Fresh(1).seed(1), Draw::Fresh(1).seed(2), "and each suite's seed its own");
        assert_eq!(Draw::Fresh(3).seed(7), Draw::Fresh(3).seed(7), "the same on every call");
    }

    #[test]
    fn a_scenes_name_says_which_draw_it_came_from() {
        assert_eq!(Draw::Documented.suffix(false), "");
        assert_eq!(Draw::Documented.suffix(true), "-holdout");
        assert_eq!(Draw::Fresh(12).suffix(false), "-fresh12");
        assert_eq!(Draw::Fresh(12).suffix(true), "-fresh12");
        for draw in [Draw::Documented, Draw::Fresh(1), Draw::Fresh(40)] {
            let name = format!("consumer-v-butt-08-d467-t13{}", draw.suffix(true));
            assert_eq!(Draw::of_scene(&name), draw, "{name}");
            assert!(is_unseen(&name), "{name}");
        }
        assert!(!is_unseen("lap-07-d612-t18-lower-side"));
        assert_eq!(Draw::of_scene("t-fillet-03-d600-t10-fresh"), Draw::Documented);
        assert_eq!(Draw::of_scene("t-fillet-03-d600-t10-freshly"), Draw::Documented);
    }
}
