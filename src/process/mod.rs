//! The welding process: from a joint as measured to the passes that weld
//! it and the arc's settings for each, under a weld procedure written as a
//! WPS is.
//!
//! The planner measures the joint (gap, groove angle and depth, plate
//! thickness, lap step); this module turns one station's measurement into
//! a [`Layout`]: one pass, or a V-groove's root, fill and cap passes, each
//! with its aim point, work angle, travel speed, wire feed, voltage and
//! current. It reads only its arguments and the [`Procedure`] (the WPS
//! table, in `config::procedure`, read from TOML and validated once); it
//! knows nothing of clouds.
//!
//! - [`section`]: a joint's cross-section, the metal it takes;
//! - [`deposit`]: a bead's cross-section to wire feed and travel speed,
//!   and the synergic line to voltage and current;
//! - [`layout`]: the passes, layer by layer for a V-groove;
//! - [`weave`]: the torch's swing across the seam, following the gap;
//! - [`clearance`]: the torch as a solid against the measured cloud, its
//!   angles moved where it touches, stretches cut where nothing clears;
//! - [`rays`]: the cloud indexed by the camera's rays, which the torch's
//!   solid is checked against;
//! - [`shadow`]: the space behind what the camera saw, which the torch
//!   treats as solid.
//!
//! docs/PROCESS.md explains the model for a welding engineer, with the
//! example procedure (config/procedures/gmaw-mild-steel.toml).

pub mod blocks;
pub mod clearance;
pub mod deposit;
pub mod layout;
pub mod rays;
pub mod section;
pub mod shadow;
pub mod weave;

pub use crate::config::procedure::{Procedure, ProcedureError};
pub use deposit::{ArcSettings, DepositError};
pub use layout::{Layout, Pass, PassKind};
pub use section::{JointSection, VGroove};

use crate::joint::JointType;

/// Why a station cannot be welded under the procedure: the figure and the
/// limit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProcessError {
    #[error("the procedure has no {joint} entry for plates {thickness_mm:.1} mm thick (its entries cover {ranges})")]
    NoEntry { joint: &'static str, thickness_mm: f64, ranges: String },
    #[error("the root gap is {gap_mm:.2} mm, over the procedure's {limit_mm:.2} mm for this joint")]
    GapOverLimit { gap_mm: f64, limit_mm: f64 },
    #[error(transparent)]
    Deposit(#[from] DepositError),
}

/// The passes that weld one station of a joint of `thickness_mm` plates
/// (a lap: the upper plate's) whose cross-section there is `section`.
pub fn weld_station(
    procedure: &Procedure,
    joint: JointType,
    thickness_mm: f64,
    section: &JointSection,
) -> Result<Layout, ProcessError> {
    let entry = procedure.entry(joint, thickness_mm).ok_or_else(|| ProcessError::NoEntry {
        joint: joint.name(),
        thickness_mm,
        ranges: procedure
            .thickness_ranges(joint)
            .iter()
            .map(|[a, b]| format!("{a} to {b} mm"))
            .collect::<Vec<_>>()
            .join(", "),
    })?;
    let gap = section.gap_mm();
    if gap > entry.max_gap_mm {
        return Err(ProcessError::GapOverLimit { gap_mm: gap, limit_mm: entry.max_gap_mm });
    }
    let allowance = entry.leg_gap_allowance_mm.unwrap_or(0.0);
    // A lap's fillet is built against the upper plate's edge: its leg is
    // no longer than that plate is thick.
    let section = match (*section, joint) {
        (JointSection::Fillet { leg_mm, gap_mm }, JointType::Lap) => {
            JointSection::Fillet { leg_mm: leg_mm.min(thickness_mm), gap_mm }
        }
        (s, _) => s,
    };
    let crown = section.crown_area(procedure, allowance);
    let mut layout = match section {
        JointSection::VGroove(g) => layout::v_groove(procedure, entry, &g, crown)?,
        _ => layout::single_pass(procedure, entry, section.joint_area(allowance), crown)?,
    };
    // The pass laid in the gap itself bridges it by weaving; the passes
    // above lie on metal already laid.
    if let Some(spec) = &entry.weave {
        for pass in layout.passes.iter_mut().filter(|p| matches!(p.kind, PassKind::Single | PassKind::Root)) {
            pass.weave = weave::Weave::for_gap(spec, gap, pass.settings.travel_speed_mm_s);
        }
    }
    Ok(layout)
}

/// A fillet's section at a station under the procedure's leg for the
/// joint and thickness, or `None` when the procedure has no entry.
pub fn fillet_section(procedure: &Procedure, joint: JointType, thickness_mm: f64, gap_mm: f64) -> Option<JointSection> {
    let leg_mm = procedure.entry(joint, thickness_mm)?.leg_mm?;
    Some(JointSection::Fillet { leg_mm, gap_mm })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The case: a square butt whose gap opens from 0.5 to 3 mm
    /// along the seam. At every station the metal the settings deposit
    /// (wire feed, wire diameter, travel speed) follows the joint's
    /// cross-section with its crown within 10 %.
    #[test]
    fn the_deposit_follows_a_gap_that_opens_along_the_seam() {
        let p = Procedure::example();
        let mut speeds = Vec::new();
        for k in 0..=50 {
            let gap_mm = 0.5 + 2.5 * k as f64 / 50.0;
            let section = JointSection::SquareButt { thickness_mm: 3.0, gap_mm };
            let layout = weld_station(&p, JointType::IButt, 3.0, &section).unwrap();
            let wanted = layout.joint_area_mm2 + layout.crown_area_mm2;
            let got = layout.deposited_area_mm2();
            assert!((got - wanted).abs() / wanted < 0.10, "gap {gap_mm:.2}: {got:.2} mm² for {wanted:.2}");
            // The settings are what the entry allows, and the deposit is
            // the balance of wire and travel.
            let s = layout.passes[0].settings;
            let e = p.entry(JointType::IButt, 3.0).unwrap();
            let d = deposit::deposited_area(&p, e, s.wire_feed_m_min, s.travel_speed_mm_s);
            assert!((d - got).abs() < 1e-9);
            speeds.push(s.travel_speed_mm_s);
        }
        // A wider gap takes more metal: the torch never speeds up as it opens.
        assert!(speeds.windows(2).all(|w| w[1] <= w[0] + 1e-12), "{speeds:?}");
    }

    #[test]
    fn a_square_butt_weaves_only_where_its_gap_is_wide() {
        let p = Procedure::example();
        let at = |gap_mm| {
            let section = JointSection::SquareButt { thickness_mm: 3.0, gap_mm };
            weld_station(&p, JointType::IButt, 3.0, &section).unwrap().passes[0].weave
        };
        assert_eq!(at(1.0), None);
        let w = at(3.0).expect("a 3 mm gap is woven");
        // The example: half the gap each side, at most 2 mm.
        assert!((w.amplitude_mm - 1.5).abs() < 1e-12, "{w:?}");
        assert_eq!(w.pattern, crate::config::procedure::WeavePattern::Trapezoid);
    }

    #[test]
    fn a_fillet_gap_over_the_limit_is_refused_and_under_it_raises_the_leg() {
        let p = Procedure::example();
        let section = fillet_section(&p, JointType::TFillet, 10.0, 5.0).unwrap();
        let e = weld_station(&p, JointType::TFillet, 10.0, &section).unwrap_err();
        assert_eq!(e, ProcessError::GapOverLimit { gap_mm: 5.0, limit_mm: 4.8 });
        assert_eq!(e.to_string(), "the root gap is 5.00 mm, over the procedure's 4.80 mm for this joint");
        let tight =
            weld_station(&p, JointType::TFillet, 10.0, &fillet_section(&p, JointType::TFillet, 10.0, 0.5).unwrap());
        let open =
            weld_station(&p, JointType::TFillet, 10.0, &fillet_section(&p, JointType::TFillet, 10.0, 3.0).unwrap());
        // 6 mm leg, then 6 + (3 − 1.6) = 7.4 mm.
        assert!((tight.unwrap().joint_area_mm2 - 18.0).abs() < 1e-9);
        assert!((open.unwrap().joint_area_mm2 - 7.4f64.powi(2) / 2.0).abs() < 1e-9);
    }

    #[test]
    fn a_thickness_with_no_entry_names_the_ranges_there_are() {
        let p = Procedure::example();
        let e = weld_station(
            &p,
            JointType::VButt,
            50.0,
            &JointSection::VGroove(VGroove {
                thickness_mm: 50.0,
                included_angle_deg: 60.0,
                root_gap_mm: 0.0,
                root_face_mm: 0.0,
            }),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "the procedure has no v_butt entry for plates 50.0 mm thick (its entries cover 5 to 12 mm, 12 to 40 mm)"
        );
    }

    #[test]
    fn a_lap_fillet_is_no_larger_than_its_upper_plate_is_thick() {
        let p = Procedure::example();
        let section = fillet_section(&p, JointType::Lap, 3.0, 0.0).unwrap();
        let layout = weld_station(&p, JointType::Lap, 3.0, &section).unwrap();
        assert!((layout.joint_area_mm2 - 4.5).abs() < 1e-9, "{}", layout.joint_area_mm2);
    }
}
