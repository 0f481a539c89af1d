//! The passes that weld one station of a joint: one bead for a square
//! butt or a fillet, layers of beads for a V-groove larger than one bead.
//!
//! A V-groove is filled from its root up, layer by layer, the way a
//! welder builds it: the root pass (the entry's root bead), then fill
//! layers of the entry's fill bead, each layer laid as as many beads side
//! by side as its width needs (no bead wider than `max_bead_width_mm`),
//! and last the cap layer, which fills what is left of the groove and
//! crowns it. Each layer's height is where the groove holds the metal laid
//! so far ([`VGroove::height_holding`]), so the layout follows the groove
//! measured, not a fixed table of passes.
//!
//! A pass's aim point is the middle of its share of the surface it is laid
//! on (the top of the layer below), given across the seam from the
//! groove's centre line and up from the root; it always lies inside the
//! groove. A layer's outer beads tilt towards their groove face by the
//! entry's `side_bead_work_angle_deg`, so the arc wets the face.

use super::deposit::{ArcSettings, DepositError, settings_for};
use super::section::VGroove;
use super::weave::Weave;
use crate::config::procedure::{Entry, Procedure};

/// Which pass of the weld this is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassKind {
    Root,
    Fill,
    Cap,
    /// The only pass of a joint one bead fills.
    Single,
}

/// One pass at a station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pass {
    pub kind: PassKind,
    /// The layer, from 0 at the root, and the bead within it, from the
    /// side of the first plate (negative `lateral_mm`).
    pub layer: usize,
    pub bead: usize,
    pub beads_in_layer: usize,
    /// The aim point: across the seam from the groove's centre line, mm,
    /// and up from the root, mm.
    pub lateral_mm: f64,
    pub height_mm: f64,
    /// Work angle, degrees: the entry's, plus a side bead's tilt towards
    /// its face (negative towards the first plate).
    pub work_angle_deg: f64,
    pub settings: ArcSettings,
    /// The torch's swing across the seam, where the procedure weaves.
    pub weave: Option<Weave>,
}

/// The passes of one station and the areas they answer.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub passes: Vec<Pass>,
    /// The groove's (or joint's) own cross-section, mm².
    pub joint_area_mm2: f64,
    /// The crown over it, mm².
    pub crown_area_mm2: f64,
}

impl Layout {
    /// What the passes deposit together, mm².
    pub fn deposited_area_mm2(&self) -> f64 {
        self.passes.iter().map(|p| p.settings.deposited_area_mm2).sum()
    }
}

/// One bead for the whole joint.
pub fn single_pass(
    procedure: &Procedure,
    entry: &Entry,
    joint_area_mm2: f64,
    crown_area_mm2: f64,
) -> Result<Layout, DepositError> {
    let settings = settings_for(procedure, entry, joint_area_mm2 + crown_area_mm2)?;
    let pass = Pass {
        kind: PassKind::Single,
        layer: 0,
        bead: 0,
        beads_in_layer: 1,
        lateral_mm: 0.0,
        height_mm: 0.0,
        work_angle_deg: entry.work_angle_deg,
        settings,
        weave: None,
    };
    Ok(Layout { passes: vec![pass], joint_area_mm2, crown_area_mm2 })
}

/// A V-groove's passes, layer by layer, from its measured geometry.
pub fn v_groove(
    procedure: &Procedure,
    entry: &Entry,
    groove: &VGroove,
    crown_area_mm2: f64,
) -> Result<Layout, DepositError> {
    let total = groove.area() + crown_area_mm2;
    if total <= entry.bead_area_mm2[1] {
        return single_pass(procedure, entry, groove.area(), crown_area_mm2);
    }
    let root_area = entry.root_bead_area_mm2.expect("validated: a v_butt entry has a root bead");
    let fill_area = entry.fill_bead_area_mm2.expect("validated: a v_butt entry has a fill bead");
    let beads_across = |width: f64| ((width / entry.max_bead_width_mm).ceil() as usize).max(1);

    // Layers as (bottom height, areas of its beads, kind).
    let mut layers: Vec<(f64, Vec<f64>, PassKind)> = vec![(0.0, vec![root_area], PassKind::Root)];
    let mut laid = root_area;
    loop {
        let bottom = groove.height_holding(laid);
        let left = groove.area() - laid;
        // A fill layer as wide as the groove is halfway up it.
        let mut beads = beads_across(groove.width_at(bottom));
        for _ in 0..2 {
            let top = groove.height_holding(laid + beads as f64 * fill_area);
            beads = beads_across(groove.width_at((bottom + top) / 2.0));
        }
        let layer = beads as f64 * fill_area;
        // The cap takes what is left when a fill layer would not leave a
        // cap layer's worth of groove under the crown.
        let cap_beads = beads_across(groove.top_width() + 2.0 * procedure.cap_overlap_mm);
        if left - layer < cap_beads as f64 * entry.bead_area_mm2[0] {
            let cap = left.max(0.0) + crown_area_mm2;
            let mut n = cap_beads.min(((cap / entry.bead_area_mm2[0]).floor() as usize).max(1));
            while cap / n as f64 > entry.bead_area_mm2[1] {
                n += 1;
            }
            layers.push((bottom, vec![cap / n as f64; n], PassKind::Cap));
            break;
        }
        layers.push((bottom, vec![fill_area; beads], PassKind::Fill));
        laid += layer;
    }

    let mut passes = Vec::new();
    for (layer, (bottom, areas, kind)) in layers.into_iter().enumerate() {
        let n = areas.len();
        let width = groove.width_at(bottom);
        for (bead, area) in areas.into_iter().enumerate() {
            let side = if n < 2 {
                0.0
            } else if bead == 0 {
                -entry.side_bead_work_angle_deg
            } else if bead == n - 1 {
                entry.side_bead_work_angle_deg
            } else {
                0.0
            };
            passes.push(Pass {
                kind,
                layer,
                bead,
                beads_in_layer: n,
                lateral_mm: -width / 2.0 + (bead as f64 + 0.5) * width / n as f64,
                height_mm: bottom,
                work_angle_deg: entry.work_angle_deg + side,
                settings: settings_for(procedure, entry, area)?,
                weave: None,
            });
        }
    }
    Ok(Layout { passes, joint_area_mm2: groove.area(), crown_area_mm2 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::JointType;
    use crate::process::section::JointSection;

    fn layout_of(t: f64, angle: f64, gap: f64, land: f64) -> (VGroove, Layout) {
        let p = Procedure::example();
        let e = p.entry(JointType::VButt, t).unwrap();
        let g = VGroove { thickness_mm: t, included_angle_deg: angle, root_gap_mm: gap, root_face_mm: land };
        let crown = JointSection::VGroove(g).crown_area(&p, 0.0);
        let layout = v_groove(&p, e, &g, crown).unwrap();
        (g, layout)
    }

    /// The case: a 20 mm plate with a 60 degree V-groove.
    #[test]
    fn a_thick_v_groove_is_filled_layer_by_layer_within_its_area() {
        let (g, layout) = layout_of(20.0, 60.0, 0.0, 0.0);
        let deposited = layout.deposited_area_mm2();
        let wanted = layout.joint_area_mm2 + layout.crown_area_mm2;
        assert!((deposited - wanted).abs() / wanted < 0.10, "{deposited} for {wanted}");
        // Below the crown, the beads fill the groove's measured area.
        let in_groove = deposited - layout.crown_area_mm2;
        assert!((in_groove - g.area()).abs() / g.area() < 0.10, "{in_groove} for {}", g.area());
        assert_eq!(layout.passes[0].kind, PassKind::Root);
        assert_eq!(layout.passes.last().unwrap().kind, PassKind::Cap);
        assert!(layout.passes.len() >= 6, "{} passes", layout.passes.len());
        for pass in &layout.passes {
            // Every aim point inside the groove, and no bead wider than the
            // procedure allows.
            assert!(pass.height_mm >= 0.0 && pass.height_mm < g.thickness_mm, "{pass:?}");
            assert!(pass.lateral_mm.abs() <= g.width_at(pass.height_mm) / 2.0 + 1e-9, "{pass:?}");
            let share = g.width_at(pass.height_mm) / pass.beads_in_layer as f64;
            assert!(share <= 12.0 + 1e-9 || pass.kind == PassKind::Cap, "{pass:?}");
        }
        // Layers rise, and their beads spread across as the groove widens.
        let heights: Vec<f64> = layout.passes.iter().map(|p| p.height_mm).collect();
        assert!(heights.windows(2).all(|w| w[1] >= w[0]));
        assert!(layout.passes.iter().any(|p| p.beads_in_layer >= 2));
    }

    #[test]
    fn side_beads_lean_towards_their_faces() {
        let (_, layout) = layout_of(20.0, 60.0, 0.0, 0.0);
        let wide = layout.passes.iter().filter(|p| p.beads_in_layer >= 2);
        for p in wide {
            if p.bead == 0 {
                assert!(p.lateral_mm < 0.0 && p.work_angle_deg < 0.0, "{p:?}");
            } else if p.bead == p.beads_in_layer - 1 {
                assert!(p.lateral_mm > 0.0 && p.work_angle_deg > 0.0, "{p:?}");
            }
        }
    }

    #[test]
    fn a_groove_one_bead_fills_is_one_pass() {
        let (g, layout) = layout_of(6.0, 60.0, 0.0, 2.0);
        assert_eq!(layout.passes.len(), 1, "{} mm² groove", g.area());
        assert_eq!(layout.passes[0].kind, PassKind::Single);
    }

    #[test]
    fn grooves_of_every_size_the_entry_covers_are_filled_within_ten_percent() {
        for t in [6.0, 8.0, 12.0, 16.0, 20.0, 25.0, 30.0, 40.0] {
            for angle in [45.0, 60.0, 70.0] {
                for (gap, land) in [(0.0, 0.0), (2.0, 1.5), (3.0, 2.0)] {
                    let (g, layout) = layout_of(t, angle, gap, land);
                    let wanted = layout.joint_area_mm2 + layout.crown_area_mm2;
                    let got = layout.deposited_area_mm2();
                    assert!((got - wanted).abs() / wanted < 0.10, "{g:?}: {got} for {wanted}");
                    for pass in &layout.passes {
                        assert!(pass.lateral_mm.abs() <= g.width_at(pass.height_mm) / 2.0 + 1e-9, "{g:?}: {pass:?}");
                    }
                }
            }
        }
    }
}
