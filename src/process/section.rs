//! The joint's cross-section at one place along the seam: how much weld
//! metal it takes to fill it and crown it.
//!
//! Areas are per unit length of seam (mm², the same as mm³ per mm):
//!
//! - single-V groove with root gap g, root face (land) f, included angle α
//!   and plate thickness t, at height y above the root:
//!   width w(y) = g below f, g + 2 (y − f) tan(α/2) above;
//!   area below y: A(y) = g·y + (y − f)² tan(α/2) for y > f;
//! - square (I) butt: g·t;
//! - fillet (tee, inside corner, lap) of leg L: L²/2, the leg raised by a
//!   root gap beyond the procedure's allowance (AWS D1.1), a lap's leg no
//!   longer than its upper plate is thick;
//! - the crown over a groove or square butt, a parabolic segment two
//!   thirds of its width (the joint's top width and the overlap onto each
//!   plate) times its height; a fillet's convexity, the same over the
//!   fillet's face (L·√2 wide).

use crate::config::procedure::Procedure;

/// A joint's cross-section at one station, from the joint as measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointSection {
    /// A single-V groove.
    VGroove(VGroove),
    /// A square butt: plates `thickness_mm` thick, `gap_mm` apart.
    SquareButt { thickness_mm: f64, gap_mm: f64 },
    /// A fillet of `leg_mm` (before any gap allowance) over a root gap.
    Fillet { leg_mm: f64, gap_mm: f64 },
}

/// A single-V groove's geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VGroove {
    pub thickness_mm: f64,
    pub included_angle_deg: f64,
    pub root_gap_mm: f64,
    /// The root face (land): how high the plates' square edges stand
    /// below the bevels.
    pub root_face_mm: f64,
}

impl VGroove {
    fn tan_half(&self) -> f64 {
        (self.included_angle_deg.to_radians() / 2.0).tan()
    }

    /// The groove's width at `y` mm above the root.
    pub fn width_at(&self, y: f64) -> f64 {
        self.root_gap_mm + 2.0 * (y - self.root_face_mm).max(0.0) * self.tan_half()
    }

    /// The groove's width at the plates' top.
    pub fn top_width(&self) -> f64 {
        self.width_at(self.thickness_mm)
    }

    /// The groove's area below `y` mm above the root.
    pub fn area_below(&self, y: f64) -> f64 {
        let y = y.clamp(0.0, self.thickness_mm);
        self.root_gap_mm * y + (y - self.root_face_mm).max(0.0).powi(2) * self.tan_half()
    }

    /// The groove's whole area, up to the plates' top.
    pub fn area(&self) -> f64 {
        self.area_below(self.thickness_mm)
    }

    /// The height below which the groove holds `area` (the inverse of
    /// [`VGroove::area_below`]), clamped to the plates' top.
    pub fn height_holding(&self, area: f64) -> f64 {
        if area <= 0.0 {
            return 0.0;
        }
        if area >= self.area() {
            return self.thickness_mm;
        }
        let (g, f, k) = (self.root_gap_mm, self.root_face_mm, self.tan_half());
        let in_land = g * f;
        if area <= in_land {
            return area / g;
        }
        // k u² + g u = area − g f, u the height above the land.
        let rest = area - in_land;
        let u = if k > 0.0 { (-g + (g * g + 4.0 * k * rest).sqrt()) / (2.0 * k) } else { rest / g };
        f + u
    }
}

impl JointSection {
    /// The joint's own cross-section: the opening to fill (a fillet's
    /// flat-faced triangle), mm².
    pub fn joint_area(&self, allowance_mm: f64) -> f64 {
        match *self {
            JointSection::VGroove(g) => g.area(),
            JointSection::SquareButt { thickness_mm, gap_mm } => gap_mm * thickness_mm,
            JointSection::Fillet { .. } => self.fillet_leg(allowance_mm).powi(2) / 2.0,
        }
    }

    /// The weld metal above the joint: a groove's or butt's crown, a
    /// fillet's convexity, mm².
    pub fn crown_area(&self, procedure: &Procedure, allowance_mm: f64) -> f64 {
        let segment = |width: f64, height: f64| 2.0 / 3.0 * width * height;
        match *self {
            JointSection::VGroove(g) => {
                segment(g.top_width() + 2.0 * procedure.cap_overlap_mm, procedure.cap_height_mm)
            }
            JointSection::SquareButt { gap_mm, .. } => {
                segment(gap_mm + 2.0 * procedure.cap_overlap_mm, procedure.cap_height_mm)
            }
            JointSection::Fillet { .. } => {
                segment(self.fillet_leg(allowance_mm) * std::f64::consts::SQRT_2, procedure.fillet_convexity_mm)
            }
        }
    }

    /// All the metal one weld of this joint deposits, mm².
    pub fn weld_area(&self, procedure: &Procedure, allowance_mm: f64) -> f64 {
        self.joint_area(allowance_mm) + self.crown_area(procedure, allowance_mm)
    }

    /// A fillet's leg after the gap allowance: raised by the gap beyond
    /// `allowance_mm`. Other joints: 0.
    pub fn fillet_leg(&self, allowance_mm: f64) -> f64 {
        match *self {
            JointSection::Fillet { leg_mm, gap_mm } => leg_mm + (gap_mm - allowance_mm).max(0.0),
            _ => 0.0,
        }
    }

    /// The root gap the procedure's limit is read against.
    pub fn gap_mm(&self) -> f64 {
        match *self {
            JointSection::VGroove(g) => g.root_gap_mm,
            JointSection::SquareButt { gap_mm, .. } | JointSection::Fillet { gap_mm, .. } => gap_mm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn groove(t: f64, angle: f64, gap: f64, land: f64) -> VGroove {
        VGroove { thickness_mm: t, included_angle_deg: angle, root_gap_mm: gap, root_face_mm: land }
    }

    #[test]
    fn a_v_groove_area_is_its_rectangle_and_two_triangles() {
        // 20 mm plate, 60 degrees, no gap, no land: t² tan 30°.
        let g = groove(20.0, 60.0, 0.0, 0.0);
        assert!((g.area() - 400.0 * 30f64.to_radians().tan()).abs() < 1e-9);
        assert!((g.top_width() - 40.0 * 30f64.to_radians().tan()).abs() < 1e-9);
        // 2 mm gap and 1.5 mm land: the gap's rectangle plus the bevels'
        // triangles above the land.
        let g = groove(12.0, 60.0, 2.0, 1.5);
        let expected = 2.0 * 12.0 + 10.5f64.powi(2) * 30f64.to_radians().tan();
        assert!((g.area() - expected).abs() < 1e-9);
    }

    #[test]
    fn the_height_holding_an_area_inverts_the_area_below_a_height() {
        for g in [groove(20.0, 60.0, 0.0, 0.0), groove(12.0, 45.0, 2.0, 1.5), groove(8.0, 70.0, 1.0, 0.0)] {
            for k in 0..=40 {
                let y = g.thickness_mm * k as f64 / 40.0;
                let back = g.height_holding(g.area_below(y));
                // Inside a land with no gap, every height holds nothing.
                if g.root_gap_mm > 0.0 || y >= g.root_face_mm {
                    assert!((back - y).abs() < 1e-9, "{g:?}: {y} came back as {back}");
                }
            }
        }
    }

    #[test]
    fn a_fillet_leg_grows_by_the_gap_beyond_the_allowance() {
        let f = JointSection::Fillet { leg_mm: 6.0, gap_mm: 1.0 };
        assert_eq!(f.fillet_leg(1.6), 6.0);
        let f = JointSection::Fillet { leg_mm: 6.0, gap_mm: 3.0 };
        assert!((f.fillet_leg(1.6) - 7.4).abs() < 1e-12);
    }
}
