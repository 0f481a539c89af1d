//! From a bead's cross-section to the arc's settings: the wire feed and
//! travel speed that deposit it, and the voltage and current the wire's
//! synergic line gives at that feed.
//!
//! The balance is of volume per unit time: the wire brings
//! η · (π d² / 4) · v_wire of metal (η the deposition efficiency, d the
//! wire's diameter), and the torch spreads it over v_travel of seam, so
//! the bead's cross-section is
//!
//! ```text
//! A = η · π d² / 4 · v_wire / v_travel
//! ```
//!
//! The travel speed is the entry's nominal one where the wire feed range
//! allows; a larger bead first slows the torch (down to the entry's
//! minimum), a smaller one speeds it (up to the maximum). A bead larger
//! than the entry lays at its slowest speed and fastest feed is refused;
//! one smaller than the smallest it lays is laid at that smallest (the
//! settings say so: `deposited_area_mm2` above `target_area_mm2`).

use crate::config::procedure::{Entry, Procedure};

/// What the arc is set to for one bead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcSettings {
    pub travel_speed_mm_s: f64,
    pub wire_feed_m_min: f64,
    pub voltage_v: f64,
    pub current_a: f64,
    /// The cross-section the joint asked of this bead, mm².
    pub target_area_mm2: f64,
    /// The cross-section these settings deposit, mm².
    pub deposited_area_mm2: f64,
}

/// Why a bead cannot be laid under the procedure.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DepositError {
    #[error(
        "a bead of {area_mm2:.1} mm² is beyond what the procedure lays in one pass: {most_mm2:.1} mm² at its slowest travel and fastest wire feed"
    )]
    BeadTooLarge { area_mm2: f64, most_mm2: f64 },
}

/// Wire feed in m/min as mm/s.
fn mm_s(m_min: f64) -> f64 {
    m_min * 1000.0 / 60.0
}

/// The cross-section deposited at a wire feed and travel speed, mm².
pub fn deposited_area(procedure: &Procedure, entry: &Entry, wire_feed_m_min: f64, travel_speed_mm_s: f64) -> f64 {
    metal_per_wire_mm(procedure, entry) * mm_s(wire_feed_m_min) / travel_speed_mm_s
}

/// Weld metal per millimetre of wire fed, mm².
fn metal_per_wire_mm(procedure: &Procedure, entry: &Entry) -> f64 {
    procedure.deposition_efficiency * std::f64::consts::PI * entry.wire_diameter_mm.powi(2) / 4.0
}

/// The settings that deposit `area_mm2` under `entry`.
pub fn settings_for(procedure: &Procedure, entry: &Entry, area_mm2: f64) -> Result<ArcSettings, DepositError> {
    let per_wire = metal_per_wire_mm(procedure, entry);
    let speed = entry.travel_speed_mm_s;
    let [feed_min, feed_max] = entry.wire_feed_m_min.map(mm_s);
    let most = per_wire * feed_max / speed.min;
    if area_mm2 > most {
        return Err(DepositError::BeadTooLarge { area_mm2, most_mm2: most });
    }
    // The smallest bead laid: the entry's, or the slowest feed at the
    // fastest travel, whichever is larger.
    let least = entry.bead_area_mm2[0].max(per_wire * feed_min / speed.max);
    let area = area_mm2.max(least);
    let mut travel = speed.nominal;
    let mut feed = area * travel / per_wire;
    if feed > feed_max {
        feed = feed_max;
        travel = per_wire * feed / area;
    } else if feed < feed_min {
        feed = feed_min;
        travel = per_wire * feed / area;
    }
    let feed_m_min = feed * 60.0 / 1000.0;
    let (voltage_v, current_a) = working_point(procedure, entry, feed_m_min);
    Ok(ArcSettings {
        travel_speed_mm_s: travel,
        wire_feed_m_min: feed_m_min,
        voltage_v,
        current_a,
        target_area_mm2: area_mm2,
        deposited_area_mm2: per_wire * feed / travel,
    })
}

/// Voltage and current on the entry's wire's synergic line at a feed
/// (validated to lie within the line).
fn working_point(procedure: &Procedure, entry: &Entry, feed_m_min: f64) -> (f64, f64) {
    let line = &procedure.wire(entry).synergic;
    let k = line.windows(2).position(|w| feed_m_min <= w[1].wire_feed_m_min).unwrap_or(line.len() - 2);
    let (a, b) = (line[k], line[k + 1]);
    let s = ((feed_m_min - a.wire_feed_m_min) / (b.wire_feed_m_min - a.wire_feed_m_min)).clamp(0.0, 1.0);
    (a.voltage_v + s * (b.voltage_v - a.voltage_v), a.current_a + s * (b.current_a - a.current_a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::JointType;

    #[test]
    fn the_settings_deposit_the_area_asked_within_the_entry() {
        let p = Procedure::example();
        let e = p.entry(JointType::VButt, 20.0).unwrap();
        for area in [8.0, 15.0, 30.0, 40.0] {
            let s = settings_for(&p, e, area).unwrap();
            assert!((s.deposited_area_mm2 - area).abs() < 1e-9, "{area}: {s:?}");
            assert!((deposited_area(&p, e, s.wire_feed_m_min, s.travel_speed_mm_s) - area).abs() < 1e-9);
            assert!(
                s.wire_feed_m_min >= e.wire_feed_m_min[0] - 1e-12 && s.wire_feed_m_min <= e.wire_feed_m_min[1] + 1e-12
            );
            let v = e.travel_speed_mm_s;
            assert!(s.travel_speed_mm_s >= v.min - 1e-12 && s.travel_speed_mm_s <= v.max + 1e-12, "{s:?}");
        }
    }

    #[test]
    fn a_bead_too_large_is_refused_and_one_too_small_laid_at_the_smallest() {
        let p = Procedure::example();
        let e = p.entry(JointType::VButt, 20.0).unwrap();
        let err = settings_for(&p, e, 80.0).unwrap_err();
        let DepositError::BeadTooLarge { most_mm2, .. } = err;
        assert!(most_mm2 < 80.0 && most_mm2 > 40.0, "{err}");
        let s = settings_for(&p, e, 2.0).unwrap();
        assert_eq!(s.target_area_mm2, 2.0);
        assert!((s.deposited_area_mm2 - e.bead_area_mm2[0]).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn voltage_and_current_follow_the_synergic_line() {
        let p = Procedure::example();
        let e = p.entry(JointType::VButt, 20.0).unwrap();
        // 1.2 mm wire: 5 m/min is a point of the line (21.5 V, 200 A).
        let (v, i) = working_point(&p, e, 5.0);
        assert!((v - 21.5).abs() < 1e-12 && (i - 200.0).abs() < 1e-12);
        // Halfway between 5 and 8 m/min.
        let (v, i) = working_point(&p, e, 6.5);
        assert!((v - 24.0).abs() < 1e-12 && (i - 232.5).abs() < 1e-12);
    }
}
