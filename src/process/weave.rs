//! Weaving: the torch swinging across the seam as it travels, to bridge a
//! gap or spread a wide bead.
//!
//! A weave is a lateral offset as a function of the distance travelled
//! along the seam: one cycle every `wavelength_mm`, swinging to
//! `amplitude_mm` each side of the seam's line. The pattern is a
//! triangle (constant lateral speed), a sine, or a trapezoid that dwells
//! at each side for `dwell_s`, which at the travel speed is a stretch of
//! seam with the torch held at the side, so the arc wets the plate's edge.
//! The amplitude follows the measured gap: none up to the procedure's
//! `above_gap_mm`, then `amplitude_per_gap` for every millimetre of gap,
//! up to `max_amplitude_mm`.
//!
//! The weave is given to a controller either as these parameters, for
//! its own weave function, or written into the waypoints as points
//! sampled along it ([`Weave::sample`]).

use crate::config::procedure::{WeavePattern, WeaveSpec};

/// A weave as laid on one stretch of seam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weave {
    pub pattern: WeavePattern,
    /// Half the swing, mm: the torch reaches this far each side.
    pub amplitude_mm: f64,
    /// Travel along the seam per cycle, mm.
    pub wavelength_mm: f64,
    /// Travel along the seam while the torch dwells at each side, mm
    /// (trapezoid only; 0 otherwise).
    pub dwell_mm: f64,
}

impl Weave {
    /// The weave a procedure's spec lays over a gap at a travel speed, or
    /// `None` where the gap does not call for one.
    pub fn for_gap(spec: &WeaveSpec, gap_mm: f64, travel_speed_mm_s: f64) -> Option<Weave> {
        if gap_mm <= spec.above_gap_mm {
            return None;
        }
        let amplitude_mm = (spec.amplitude_per_gap * gap_mm).min(spec.max_amplitude_mm);
        let dwell_mm = match spec.pattern {
            // Two dwells per cycle, never more than half of it.
            WeavePattern::Trapezoid => (spec.dwell_s * travel_speed_mm_s).min(spec.wavelength_mm / 4.0),
            WeavePattern::Triangle | WeavePattern::Sine => 0.0,
        };
        Some(Weave { pattern: spec.pattern, amplitude_mm, wavelength_mm: spec.wavelength_mm, dwell_mm })
    }

    /// The weave's frequency at a travel speed, Hz.
    pub fn frequency_hz(&self, travel_speed_mm_s: f64) -> f64 {
        travel_speed_mm_s / self.wavelength_mm
    }

    /// The lateral offset after `s` mm of travel, mm: 0 at the start,
    /// rising to the positive side first.
    pub fn offset(&self, s: f64) -> f64 {
        let phase = (s / self.wavelength_mm).rem_euclid(1.0);
        match self.pattern {
            WeavePattern::Sine => self.amplitude_mm * (std::f64::consts::TAU * phase).sin(),
            WeavePattern::Triangle => self.amplitude_mm * triangle(phase),
            WeavePattern::Trapezoid => {
                // A quarter cycle is a swing from the line to a side and
                // half a dwell there: the swing takes what the dwell
                // leaves.
                let dwell = self.dwell_mm / self.wavelength_mm;
                let swing = 0.25 - dwell / 2.0;
                let quarter = |q: f64| if q < swing { q / swing } else { 1.0 };
                let a = self.amplitude_mm;
                match phase {
                    p if p < 0.25 => a * quarter(p),
                    p if p < 0.5 => a * quarter(0.5 - p),
                    p if p < 0.75 => -a * quarter(p - 0.5),
                    p => -a * quarter(1.0 - p),
                }
            }
        }
    }

    /// Points along `length_mm` of seam, `per_cycle` per cycle and the
    /// stretch's end: (distance along the seam, lateral offset).
    pub fn sample(&self, length_mm: f64, per_cycle: usize) -> Vec<(f64, f64)> {
        let step = self.wavelength_mm / per_cycle.max(4) as f64;
        let n = (length_mm / step).ceil().max(1.0) as usize;
        (0..=n).map(|k| (k as f64 * step).min(length_mm)).map(|s| (s, self.offset(s))).collect()
    }
}

/// A unit triangle wave: 0 at phase 0, 1 at a quarter, −1 at three.
fn triangle(phase: f64) -> f64 {
    if phase < 0.25 {
        4.0 * phase
    } else if phase < 0.75 {
        2.0 - 4.0 * phase
    } else {
        4.0 * phase - 4.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(pattern: WeavePattern) -> WeaveSpec {
        WeaveSpec {
            pattern,
            above_gap_mm: 1.5,
            amplitude_per_gap: 0.6,
            max_amplitude_mm: 2.5,
            wavelength_mm: 4.0,
            dwell_s: 0.1,
        }
    }

    #[test]
    fn no_weave_up_to_the_gap_then_an_amplitude_that_follows_it() {
        let s = spec(WeavePattern::Triangle);
        assert!(Weave::for_gap(&s, 1.5, 6.0).is_none());
        let w = Weave::for_gap(&s, 2.0, 6.0).unwrap();
        assert!((w.amplitude_mm - 1.2).abs() < 1e-12);
        let wide = Weave::for_gap(&s, 8.0, 6.0).unwrap();
        assert_eq!(wide.amplitude_mm, 2.5);
        assert!((w.frequency_hz(6.0) - 1.5).abs() < 1e-12);
    }

    #[test]
    fn every_pattern_swings_to_its_amplitude_each_side_and_back() {
        for pattern in [WeavePattern::Triangle, WeavePattern::Sine, WeavePattern::Trapezoid] {
            let w = Weave::for_gap(&spec(pattern), 3.0, 6.0).unwrap();
            let a = w.amplitude_mm;
            let points = w.sample(40.0, 64);
            let most = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
            let least = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            assert!((most - a).abs() < 1e-9 && (least + a).abs() < 1e-9, "{pattern:?}: {least} to {most}");
            assert!(w.offset(0.0).abs() < 1e-12 && w.offset(w.wavelength_mm / 2.0).abs() < 1e-9, "{pattern:?}");
            assert!(points.iter().all(|p| p.1.abs() <= a + 1e-12));
            // Continuous: no jump between samples bigger than the swing allows.
            let step = points[1].0 - points[0].0;
            let steepest = 4.0 * a / w.wavelength_mm * 2.0;
            assert!(points.windows(2).all(|q| (q[1].1 - q[0].1).abs() <= steepest * step + 1e-9), "{pattern:?}");
            assert_eq!(points.last().unwrap().0, 40.0);
        }
    }

    #[test]
    fn a_trapezoid_dwells_at_each_side_for_its_travel() {
        let w = Weave::for_gap(&spec(WeavePattern::Trapezoid), 3.0, 6.0).unwrap();
        // 0.1 s at 6 mm/s: 0.6 mm of seam at each side.
        assert!((w.dwell_mm - 0.6).abs() < 1e-12);
        let at_side = |s0: f64| (0..=10).all(|k| (w.offset(s0 + 0.06 * k as f64).abs() - w.amplitude_mm).abs() < 1e-9);
        assert!(at_side(1.0 - 0.3), "positive side");
        assert!(at_side(3.0 - 0.3), "negative side");
    }
}
