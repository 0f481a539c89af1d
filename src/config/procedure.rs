//! The weld procedure: a table written as a welding procedure
//! specification (WPS) is, read from TOML and validated once.
//!
//! A procedure names its wires (each with its synergic line: the arc
//! voltage and current at a wire feed speed) and, per joint type and
//! plate thickness range, an entry: the travel speed and wire feed ranges,
//! the bead sizes one pass may lay, the torch angles, the widest gap it
//! welds, for fillets the leg and, where it is not the procedure's
//! `[torch]`, the entry's own torch (its contact tip distance, nozzle and
//! tip; [`Procedure::torch_for`]). The numbers are data: the example
//! shipped in config/procedures/gmaw-mild-steel.toml documents each field.
//! After [`Procedure::from_toml`] every range is ordered, every figure is
//! positive and finite, every entry's wire exists and no two entries of a
//! joint type claim the same thickness, so the rest of the process model
//! never checks them again.

use serde::Deserialize;

use crate::joint::JointType;

/// The example procedure shipped with weldseam (mild-steel GMAW with
/// 1.0 and 1.2 mm wire).
pub const EXAMPLE: &str = include_str!("../../config/procedures/gmaw-mild-steel.toml");

/// What is wrong with a procedure file: the field and the limit it breaks.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProcedureError {
    #[error("the procedure is not valid TOML for its schema: {0}")]
    Parse(String),
    #[error("{field} is {value}: {limit}")]
    Value { field: String, value: f64, limit: &'static str },
    #[error("{field}: the range [{min}, {max}] is empty (min above max)")]
    Range { field: String, min: f64, max: f64 },
    #[error("entry {entry} ({joint}) names wire {diameter_mm} mm, which the procedure has no [[wire]] for")]
    UnknownWire { entry: usize, joint: &'static str, diameter_mm: f64 },
    #[error("entry {entry} ({joint}) feeds wire at {feed:?} m/min, beyond its synergic line's {line:?}")]
    FeedBeyondLine { entry: usize, joint: &'static str, feed: [f64; 2], line: [f64; 2] },
    #[error("wire {diameter_mm} mm: its synergic line needs at least two points in rising wire feed order")]
    SynergicLine { diameter_mm: f64 },
    #[error("entries {first} and {second} ({joint}) both claim plates {thickness_mm} mm thick")]
    Overlap { first: usize, second: usize, joint: &'static str, thickness_mm: f64 },
    #[error("entry {entry} ({joint}) lacks {field}, which a {joint} entry needs")]
    Missing { entry: usize, joint: &'static str, field: &'static str },
    #[error("the procedure has no [[entry]]")]
    Empty,
}

/// A weld procedure, validated.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Procedure {
    /// What the procedure is: process, base metal, wire, gas, position.
    pub name: String,
    /// The share of the wire fed that ends in the weld.
    pub deposition_efficiency: f64,
    /// The cap's height above the plates over a groove or square butt, mm.
    pub cap_height_mm: f64,
    /// How far the cap runs onto each plate beyond the joint's edge, mm.
    pub cap_overlap_mm: f64,
    /// How far a fillet's face bulges beyond the flat face, mm.
    pub fillet_convexity_mm: f64,
    /// The torch, as a solid the planner keeps clear of the workpiece.
    pub torch: Torch,
    #[serde(rename = "wire")]
    pub wires: Vec<Wire>,
    #[serde(rename = "entry")]
    pub entries: Vec<Entry>,
    /// The TOML text it was read from, which a plan record keeps so a
    /// replay plans with this procedure whatever its file says later.
    #[serde(skip)]
    source: String,
}

/// The torch's solid along its axis from the aim point: nothing up to
/// the contact tip's end or the nozzle's, whichever is nearer, an
/// extended tip's end (a cylinder) where the tip reaches past the nozzle,
/// the nozzle (a cylinder), then the neck and body (a cone widening from
/// the nozzle's radius; 0 degrees: a cylinder).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Torch {
    /// Contact tip to work distance, mm: the wire's stick-out, and where
    /// the tip is recessed, the recess up to the nozzle's end.
    pub contact_tip_to_work_mm: f64,
    /// From the aim point to the nozzle's end, mm: more than the contact
    /// tip's distance where the tip is extended past the nozzle.
    pub nozzle_to_work_mm: f64,
    pub nozzle_diameter_mm: f64,
    /// The contact tip's outside diameter where it reaches past the
    /// nozzle's end, mm: needed, and only read, for an extended tip
    /// (`nozzle_to_work_mm` above `contact_tip_to_work_mm`).
    #[serde(default)]
    pub contact_tip_diameter_mm: Option<f64>,
    pub nozzle_length_mm: f64,
    pub body_length_mm: f64,
    pub body_half_angle_deg: f64,
    /// Clearance kept round the solid for the cloud's noise and the
    /// robot's path error, mm.
    pub margin_mm: f64,
    /// How far the planner may move the procedure's work angle, and the
    /// travel angles it may use, to clear the workpiece, degrees.
    pub work_deviation_deg: f64,
    pub travel_angle_range_deg: [f64; 2],
}

impl Torch {
    /// How far the contact tip reaches past the nozzle's end, mm, and its
    /// diameter there; `None` for a tip flush with the nozzle or recessed.
    pub fn extended_tip(&self) -> Option<(f64, f64)> {
        let extension = self.nozzle_to_work_mm - self.contact_tip_to_work_mm;
        (extension > 0.0).then_some(extension).zip(self.contact_tip_diameter_mm)
    }

    /// Where the solid begins along its axis from the aim point, mm: the
    /// extended tip's end, or else the nozzle's.
    pub fn solid_start_mm(&self) -> f64 {
        if self.extended_tip().is_some() { self.contact_tip_to_work_mm } else { self.nozzle_to_work_mm }
    }

    /// Where the solid ends along its axis from the aim point, mm: the
    /// body's far end.
    pub fn solid_end_mm(&self) -> f64 {
        self.nozzle_to_work_mm + self.nozzle_length_mm + self.body_length_mm
    }

    /// This torch with an entry's own parts and stand-off in place of
    /// these; the clearance margin and the angle limits stay the
    /// procedure's.
    fn with(&self, own: &EntryTorch) -> Torch {
        Torch {
            contact_tip_to_work_mm: own.contact_tip_to_work_mm.unwrap_or(self.contact_tip_to_work_mm),
            nozzle_to_work_mm: own.nozzle_to_work_mm.unwrap_or(self.nozzle_to_work_mm),
            nozzle_diameter_mm: own.nozzle_diameter_mm.unwrap_or(self.nozzle_diameter_mm),
            contact_tip_diameter_mm: own.contact_tip_diameter_mm.or(self.contact_tip_diameter_mm),
            nozzle_length_mm: own.nozzle_length_mm.unwrap_or(self.nozzle_length_mm),
            body_length_mm: own.body_length_mm.unwrap_or(self.body_length_mm),
            body_half_angle_deg: own.body_half_angle_deg.unwrap_or(self.body_half_angle_deg),
            ..*self
        }
    }

    /// Every figure in range, each error naming `prefix` and the field.
    fn validate(&self, prefix: &str) -> Result<(), ProcedureError> {
        let f = |name: &str| format!("{prefix}{name}");
        positive(&f("contact_tip_to_work_mm"), self.contact_tip_to_work_mm)?;
        positive(&f("nozzle_to_work_mm"), self.nozzle_to_work_mm)?;
        positive(&f("nozzle_diameter_mm"), self.nozzle_diameter_mm)?;
        if let Some(d) = self.contact_tip_diameter_mm {
            positive(&f("contact_tip_diameter_mm"), d)?;
            if d >= self.nozzle_diameter_mm {
                let limit = "must be less than the nozzle's diameter (the tip sits inside the nozzle)";
                return Err(value(&f("contact_tip_diameter_mm"), d, limit));
            }
        }
        if self.nozzle_to_work_mm > self.contact_tip_to_work_mm && self.contact_tip_diameter_mm.is_none() {
            let limit = "exceeds contact_tip_to_work_mm, an extended tip: give contact_tip_diameter_mm, the tip's \
                         solid past the nozzle";
            return Err(value(&f("nozzle_to_work_mm"), self.nozzle_to_work_mm, limit));
        }
        positive(&f("nozzle_length_mm"), self.nozzle_length_mm)?;
        non_negative(&f("body_length_mm"), self.body_length_mm)?;
        if !(0.0..60.0).contains(&self.body_half_angle_deg) {
            return Err(value(&f("body_half_angle_deg"), self.body_half_angle_deg, "must lie in [0, 60) degrees"));
        }
        // The solid is sampled every few millimetres over its surface at
        // every torch checked: a length or a width off by a unit (metres
        // written as micrometres) would be sampled without bound.
        if self.solid_end_mm() > TORCH_MAX_LENGTH_MM {
            let limit = "makes the torch's solid, nozzle_to_work_mm + nozzle_length_mm + body_length_mm from the aim \
                         point, longer than 500 mm (TORCH_MAX_LENGTH_MM)";
            return Err(value(&f("body_length_mm"), self.body_length_mm, limit));
        }
        if self.far_end_diameter_mm() > TORCH_MAX_DIAMETER_MM {
            let limit = "makes the torch wider than 150 mm at the body's far end (TORCH_MAX_DIAMETER_MM): \
                         nozzle_diameter_mm, widened by body_half_angle_deg over body_length_mm";
            return Err(value(&f("nozzle_diameter_mm"), self.nozzle_diameter_mm, limit));
        }
        Ok(())
    }

    /// The solid's diameter at the body's far end, mm, the margin aside.
    fn far_end_diameter_mm(&self) -> f64 {
        self.nozzle_diameter_mm + 2.0 * self.body_length_mm * self.body_half_angle_deg.to_radians().tan()
    }
}

/// The longest a torch's solid may run from the aim point, mm: a robot
/// torch's nozzle, neck and the body's near part, which is what can meet
/// the workpiece, are a few hundred millimetres; the wrist beyond them is
/// the robot's reach to check, not the torch's.
pub const TORCH_MAX_LENGTH_MM: f64 = 500.0;

/// The widest a torch's solid may be at the body's far end, mm: a torch's
/// neck and body are some tens of millimetres across.
pub const TORCH_MAX_DIAMETER_MM: f64 = 150.0;

/// The widest clearance margin, mm: one kept round the torch for the
/// cloud's noise and the robot's path error is a few millimetres; it
/// widens every sample ring of the solid.
pub const TORCH_MAX_MARGIN_MM: f64 = 20.0;

/// An entry's own torch: the parts and stand-off its joints are welded
/// with where they differ from the procedure's `[torch]` (a field left
/// out is the procedure's). The clearance margin and the angle limits are
/// the cell's, the procedure's for every entry.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EntryTorch {
    pub contact_tip_to_work_mm: Option<f64>,
    pub nozzle_to_work_mm: Option<f64>,
    pub nozzle_diameter_mm: Option<f64>,
    pub contact_tip_diameter_mm: Option<f64>,
    pub nozzle_length_mm: Option<f64>,
    pub body_length_mm: Option<f64>,
    pub body_half_angle_deg: Option<f64>,
}

/// A wire and its synergic line.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wire {
    pub diameter_mm: f64,
    /// Working points in rising wire feed order; straight between them.
    pub synergic: Vec<ArcPoint>,
}

/// One working point of a synergic line.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArcPoint {
    pub wire_feed_m_min: f64,
    pub voltage_v: f64,
    pub current_a: f64,
}

/// A travel speed range with the speed used when the bead allows it.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedRange {
    pub min: f64,
    pub nominal: f64,
    pub max: f64,
}

/// One line of the procedure: a joint type over a plate thickness range.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    #[serde(deserialize_with = "joint_by_name")]
    pub joint: JointType,
    /// Plate thickness, [min, max) mm (the last entry of a joint type
    /// includes its max).
    pub thickness_mm: [f64; 2],
    pub wire_diameter_mm: f64,
    pub travel_speed_mm_s: SpeedRange,
    pub wire_feed_m_min: [f64; 2],
    /// One pass's cross-section, [min, max] mm².
    pub bead_area_mm2: [f64; 2],
    /// V-grooves: the root pass's cross-section, mm².
    #[serde(default)]
    pub root_bead_area_mm2: Option<f64>,
    /// V-grooves: the cross-section fill and cap passes are laid out at, mm².
    #[serde(default)]
    pub fill_bead_area_mm2: Option<f64>,
    /// A layer wider than this is laid as beads side by side, mm.
    pub max_bead_width_mm: f64,
    /// The widest root gap this entry welds, mm.
    pub max_gap_mm: f64,
    /// Fillets: the leg size, mm.
    #[serde(default)]
    pub leg_mm: Option<f64>,
    /// Fillets: the gap above which the leg grows by the excess, mm.
    #[serde(default)]
    pub leg_gap_allowance_mm: Option<f64>,
    /// Torch tilt across the seam from the joint's bisector, degrees.
    pub work_angle_deg: f64,
    /// A wide layer's side beads tilt this far towards their groove face.
    #[serde(default)]
    pub side_bead_work_angle_deg: f64,
    /// Push angle along the seam, degrees.
    pub travel_angle_deg: f64,
    /// How the torch weaves where the gap calls for it (none if absent).
    #[serde(default)]
    pub weave: Option<WeaveSpec>,
    /// The torch this entry's joints are welded with, where it is not
    /// the procedure's ([`Procedure::torch_for`]).
    #[serde(default)]
    pub torch: Option<EntryTorch>,
}

/// A weave's shape, as a controller's weave function names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WeavePattern {
    Triangle,
    Sine,
    /// A swing with a dwell at each side.
    Trapezoid,
}

/// When and how an entry weaves.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeaveSpec {
    pub pattern: WeavePattern,
    /// Weave where the root gap is wider than this, mm.
    pub above_gap_mm: f64,
    /// The swing's half-width per millimetre of gap (0.5: the torch
    /// reaches each edge of the gap).
    pub amplitude_per_gap: f64,
    /// The widest half-swing, mm.
    pub max_amplitude_mm: f64,
    /// Travel along the seam per cycle, mm.
    pub wavelength_mm: f64,
    /// Trapezoid: how long the torch dwells at each side, s.
    #[serde(default)]
    pub dwell_s: f64,
}

fn joint_by_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<JointType, D::Error> {
    let name = String::deserialize(d)?;
    JointType::NAMED.into_iter().find(|j| j.name() == name).ok_or_else(|| {
        serde::de::Error::custom(format!("unknown joint `{name}`: one of v_butt, i_butt, lap, t_fillet"))
    })
}

impl Procedure {
    /// The shipped example, which the tests hold valid.
    pub fn example() -> Procedure {
        Procedure::from_toml(EXAMPLE).expect("the shipped example procedure is valid (tested)")
    }

    /// Reads and validates a procedure.
    pub fn from_toml(text: &str) -> Result<Procedure, ProcedureError> {
        let mut procedure: Procedure = toml::from_str(text).map_err(|e| ProcedureError::Parse(e.to_string()))?;
        procedure.validate()?;
        procedure.source = text.to_string();
        Ok(procedure)
    }

    /// The TOML text it was read from; [`Procedure::from_toml`] of it gives
    /// this procedure unless its fields were changed after reading.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The entry for a joint type and plate thickness, if any.
    pub fn entry(&self, joint: JointType, thickness_mm: f64) -> Option<&Entry> {
        let of_joint: Vec<&Entry> = self.entries.iter().filter(|e| e.joint == joint).collect();
        let top = of_joint.iter().map(|e| e.thickness_mm[1]).fold(f64::NEG_INFINITY, f64::max);
        of_joint.into_iter().find(|e| {
            let [lo, hi] = e.thickness_mm;
            thickness_mm >= lo && (thickness_mm < hi || (hi == top && thickness_mm == hi))
        })
    }

    /// The thickness ranges a joint type has entries for, in rising order.
    pub fn thickness_ranges(&self, joint: JointType) -> Vec<[f64; 2]> {
        let mut ranges: Vec<[f64; 2]> =
            self.entries.iter().filter(|e| e.joint == joint).map(|e| e.thickness_mm).collect();
        ranges.sort_by(|a, b| a[0].total_cmp(&b[0]));
        ranges
    }

    /// The torch an entry's joints are welded with: the procedure's, with
    /// the entry's own parts and stand-off where it gives them.
    pub fn torch_for(&self, entry: &Entry) -> Torch {
        entry.torch.as_ref().map_or(self.torch, |own| self.torch.with(own))
    }

    /// The wire of an entry (validated to exist).
    pub fn wire(&self, entry: &Entry) -> &Wire {
        self.wires
            .iter()
            .find(|w| w.diameter_mm == entry.wire_diameter_mm)
            .expect("validated: every entry's wire exists")
    }

    fn validate(&self) -> Result<(), ProcedureError> {
        fraction("deposition_efficiency", self.deposition_efficiency)?;
        non_negative("cap_height_mm", self.cap_height_mm)?;
        non_negative("cap_overlap_mm", self.cap_overlap_mm)?;
        non_negative("fillet_convexity_mm", self.fillet_convexity_mm)?;
        let t = &self.torch;
        t.validate("torch.")?;
        non_negative("torch.margin_mm", t.margin_mm)?;
        if t.margin_mm > TORCH_MAX_MARGIN_MM {
            return Err(value("torch.margin_mm", t.margin_mm, "must be at most 20 mm (TORCH_MAX_MARGIN_MM)"));
        }
        angle("torch.work_deviation_deg", t.work_deviation_deg)?;
        range("torch.travel_angle_range_deg", t.travel_angle_range_deg)?;
        angle("torch.travel_angle_range_deg", t.travel_angle_range_deg[0])?;
        angle("torch.travel_angle_range_deg", t.travel_angle_range_deg[1])?;
        for (k, wire) in self.wires.iter().enumerate() {
            positive(&format!("wire {} diameter_mm", k + 1), wire.diameter_mm)?;
            let rising = wire.synergic.windows(2).all(|w| w[1].wire_feed_m_min > w[0].wire_feed_m_min);
            if wire.synergic.len() < 2 || !rising {
                return Err(ProcedureError::SynergicLine { diameter_mm: wire.diameter_mm });
            }
            for p in &wire.synergic {
                positive("synergic wire_feed_m_min", p.wire_feed_m_min)?;
                positive("synergic voltage_v", p.voltage_v)?;
                positive("synergic current_a", p.current_a)?;
            }
        }
        if self.entries.is_empty() {
            return Err(ProcedureError::Empty);
        }
        for (k, e) in self.entries.iter().enumerate() {
            e.validate(k + 1)?;
            if e.torch.is_some() {
                self.torch_for(e).validate(&format!("entry {} ({}) torch.", k + 1, e.joint.name()))?;
            }
            let Some(wire) = self.wires.iter().find(|w| w.diameter_mm == e.wire_diameter_mm) else {
                return Err(ProcedureError::UnknownWire {
                    entry: k + 1,
                    joint: e.joint.name(),
                    diameter_mm: e.wire_diameter_mm,
                });
            };
            // The arc's working point is read off the synergic line, never
            // extrapolated beyond it.
            let line = [wire.synergic[0].wire_feed_m_min, wire.synergic[wire.synergic.len() - 1].wire_feed_m_min];
            if e.wire_feed_m_min[0] < line[0] || e.wire_feed_m_min[1] > line[1] {
                return Err(ProcedureError::FeedBeyondLine {
                    entry: k + 1,
                    joint: e.joint.name(),
                    feed: e.wire_feed_m_min,
                    line,
                });
            }
            for (j, other) in self.entries.iter().enumerate().take(k) {
                let overlap = other.joint == e.joint
                    && e.thickness_mm[0] < other.thickness_mm[1]
                    && other.thickness_mm[0] < e.thickness_mm[1];
                if overlap {
                    return Err(ProcedureError::Overlap {
                        first: j + 1,
                        second: k + 1,
                        joint: e.joint.name(),
                        thickness_mm: e.thickness_mm[0].max(other.thickness_mm[0]),
                    });
                }
            }
        }
        Ok(())
    }
}

impl Entry {
    fn validate(&self, k: usize) -> Result<(), ProcedureError> {
        let f = |name: &str| format!("entry {k} ({}) {name}", self.joint.name());
        range(&f("thickness_mm"), self.thickness_mm)?;
        positive(&f("thickness_mm"), self.thickness_mm[0])?;
        positive(&f("wire_diameter_mm"), self.wire_diameter_mm)?;
        let s = self.travel_speed_mm_s;
        positive(&f("travel_speed_mm_s.min"), s.min)?;
        range(&f("travel_speed_mm_s (min, nominal)"), [s.min, s.nominal])?;
        range(&f("travel_speed_mm_s (nominal, max)"), [s.nominal, s.max])?;
        positive(&f("wire_feed_m_min"), self.wire_feed_m_min[0])?;
        range(&f("wire_feed_m_min"), self.wire_feed_m_min)?;
        positive(&f("bead_area_mm2"), self.bead_area_mm2[0])?;
        range(&f("bead_area_mm2"), self.bead_area_mm2)?;
        positive(&f("max_bead_width_mm"), self.max_bead_width_mm)?;
        non_negative(&f("max_gap_mm"), self.max_gap_mm)?;
        angle(&f("work_angle_deg"), self.work_angle_deg)?;
        angle(&f("side_bead_work_angle_deg"), self.side_bead_work_angle_deg)?;
        angle(&f("travel_angle_deg"), self.travel_angle_deg)?;
        if let Some(w) = &self.weave {
            non_negative(&f("weave.above_gap_mm"), w.above_gap_mm)?;
            positive(&f("weave.amplitude_per_gap"), w.amplitude_per_gap)?;
            positive(&f("weave.max_amplitude_mm"), w.max_amplitude_mm)?;
            positive(&f("weave.wavelength_mm"), w.wavelength_mm)?;
            non_negative(&f("weave.dwell_s"), w.dwell_s)?;
        }
        let missing = |field| ProcedureError::Missing { entry: k, joint: self.joint.name(), field };
        match self.joint {
            JointType::VButt => {
                for (name, area) in [
                    ("root_bead_area_mm2", self.root_bead_area_mm2.ok_or(missing("root_bead_area_mm2"))?),
                    ("fill_bead_area_mm2", self.fill_bead_area_mm2.ok_or(missing("fill_bead_area_mm2"))?),
                ] {
                    within_bead(&f(name), area, self.bead_area_mm2)?;
                }
            }
            JointType::TFillet | JointType::Lap => {
                positive(&f("leg_mm"), self.leg_mm.ok_or(missing("leg_mm"))?)?;
                non_negative(
                    &f("leg_gap_allowance_mm"),
                    self.leg_gap_allowance_mm.ok_or(missing("leg_gap_allowance_mm"))?,
                )?;
            }
            JointType::IButt => {}
        }
        Ok(())
    }
}

fn value(field: &str, value: f64, limit: &'static str) -> ProcedureError {
    ProcedureError::Value { field: field.to_string(), value, limit }
}

fn positive(field: &str, v: f64) -> Result<(), ProcedureError> {
    if v.is_finite() && v > 0.0 { Ok(()) } else { Err(value(field, v, "must be a finite figure above 0")) }
}

fn non_negative(field: &str, v: f64) -> Result<(), ProcedureError> {
    if v.is_finite() && v >= 0.0 { Ok(()) } else { Err(value(field, v, "must be a finite figure of 0 or more")) }
}

fn fraction(field: &str, v: f64) -> Result<(), ProcedureError> {
    if v > 0.0 && v <= 1.0 { Ok(()) } else { Err(value(field, v, "must lie in (0, 1]")) }
}

fn angle(field: &str, v: f64) -> Result<(), ProcedureError> {
    if v.is_finite() && v.abs() < 45.0 { Ok(()) } else { Err(value(field, v, "must lie within ±45 degrees")) }
}

fn range(field: &str, [min, max]: [f64; 2]) -> Result<(), ProcedureError> {
    if !min.is_finite() || !max.is_finite() {
        return Err(value(field, if min.is_finite() { max } else { min }, "must be finite"));
    }
    if min > max { Err(ProcedureError::Range { field: field.to_string(), min, max }) } else { Ok(()) }
}

fn within_bead(field: &str, v: f64, [min, max]: [f64; 2]) -> Result<(), ProcedureError> {
    if v >= min && v <= max { Ok(()) } else { Err(value(field, v, "must lie within the entry's bead_area_mm2")) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_example_procedure_is_valid_and_covers_every_joint() {
        let p = Procedure::example();
        for joint in JointType::NAMED {
            assert!(!p.thickness_ranges(joint).is_empty(), "{} has no entry", joint.name());
        }
        assert_eq!(p.entry(JointType::VButt, 20.0).unwrap().wire_diameter_mm, 1.2);
        assert_eq!(p.entry(JointType::IButt, 3.0).unwrap().wire_diameter_mm, 1.0);
        // A thickness on a boundary belongs to the entry that starts there,
        // and the top of the last range is included.
        assert_eq!(p.entry(JointType::TFillet, 8.0).unwrap().leg_mm, Some(6.0));
        assert_eq!(p.entry(JointType::TFillet, 20.0).unwrap().leg_mm, Some(6.0));
        assert!(p.entry(JointType::TFillet, 20.5).is_none());
        assert!(p.entry(JointType::IButt, 1.0).is_none());
    }

    fn example_with(from: &str, to: &str) -> Result<Procedure, ProcedureError> {
        assert!(EXAMPLE.contains(from), "the example has {from:?}");
        Procedure::from_toml(&EXAMPLE.replacen(from, to, 1))
    }

    #[test]
    fn a_bad_figure_is_refused_with_the_field_and_the_limit() {
        let e = example_with("deposition_efficiency = 0.95", "deposition_efficiency = 1.5").unwrap_err();
        assert_eq!(e.to_string(), "deposition_efficiency is 1.5: must lie in (0, 1]");
        let e = example_with("wire_feed_m_min = [2.5, 8.0]", "wire_feed_m_min = [8.0, 2.5]").unwrap_err();
        assert!(matches!(e, ProcedureError::Range { .. }), "{e}");
        let e = example_with("thickness_mm = [4.0, 6.0]", "thickness_mm = [3.0, 6.0]").unwrap_err();
        assert_eq!(e, ProcedureError::Overlap { first: 1, second: 2, joint: "i_butt", thickness_mm: 3.0 });
        let e = example_with("wire_diameter_mm = 1.2\ntravel", "wire_diameter_mm = 0.9\ntravel").unwrap_err();
        assert!(matches!(e, ProcedureError::UnknownWire { diameter_mm, .. } if diameter_mm == 0.9), "{e}");
        let e = example_with("wire_feed_m_min = [2.5, 10.0]", "wire_feed_m_min = [2.5, 12.0]").unwrap_err();
        assert!(matches!(e, ProcedureError::FeedBeyondLine { line: [2.5, 11.0], .. }), "{e}");
        let e = example_with("root_bead_area_mm2 = 15.0\n", "").unwrap_err();
        assert!(matches!(e, ProcedureError::Missing { field: "root_bead_area_mm2", .. }), "{e}");
        let e = example_with("leg_mm = 4.0", "leg_mm = -4.0").unwrap_err();
        assert!(e.to_string().contains("leg_mm is -4"), "{e}");
    }

    #[test]
    fn a_torch_too_long_or_too_wide_to_sample_is_refused_with_its_limit() {
        let e = example_with("body_length_mm = 80.0", "body_length_mm = 80000000.0").unwrap_err();
        assert!(
            matches!(&e, ProcedureError::Value { field, .. } if field == "torch.body_length_mm")
                && e.to_string().contains("500 mm"),
            "{e}"
        );
        let e = example_with("body_half_angle_deg = 12.0", "body_half_angle_deg = 59.0").unwrap_err();
        assert!(e.to_string().contains("wider than 150 mm"), "{e}");
        let e = example_with("margin_mm = 2.0", "margin_mm = 2000.0").unwrap_err();
        assert_eq!(e.to_string(), "torch.margin_mm is 2000: must be at most 20 mm (TORCH_MAX_MARGIN_MM)");
        // An entry's own torch is held to the same bounds.
        let e = example_with("nozzle_to_work_mm = 19.1", "nozzle_to_work_mm = 600.0").unwrap_err();
        assert!(e.to_string().contains("entry 4 (v_butt) torch.body_length_mm"), "{e}");
    }

    #[test]
    fn an_entry_welds_with_its_own_torch_checked_as_the_procedures_is() {
        let p = Procedure::example();
        // The thin V entry keeps the procedure's torch; the thick one
        // extends its tip past the nozzle, with the procedure's nozzle,
        // margin and angle limits.
        assert_eq!(p.torch_for(p.entry(JointType::VButt, 10.0).unwrap()), p.torch);
        let thick = p.torch_for(p.entry(JointType::VButt, 20.0).unwrap());
        let (extension, diameter) = thick.extended_tip().expect("an extended tip");
        assert!((extension - 6.4).abs() < 1e-9 && diameter == 8.0, "{thick:?}");
        assert_eq!(
            Torch { contact_tip_to_work_mm: 15.0, nozzle_to_work_mm: 12.0, contact_tip_diameter_mm: None, ..thick },
            p.torch
        );
        let e = example_with(", contact_tip_diameter_mm = 8.0 }", " }").unwrap_err();
        assert!(
            matches!(&e, ProcedureError::Value { field, .. } if field == "entry 4 (v_butt) torch.nozzle_to_work_mm"),
            "{e}"
        );
        let e = example_with("contact_tip_diameter_mm = 8.0", "contact_tip_diameter_mm = 16.0").unwrap_err();
        assert_eq!(
            e.to_string(),
            "entry 4 (v_butt) torch.contact_tip_diameter_mm is 16: must be less than the nozzle's diameter (the tip \
             sits inside the nozzle)"
        );
        // The margin is the cell's, not an entry's to lower.
        let e = example_with("contact_tip_diameter_mm = 8.0", "contact_tip_diameter_mm = 8.0, margin_mm = 0.5")
            .unwrap_err();
        assert!(e.to_string().contains("margin_mm"), "{e}");
        let e = example_with("nozzle_to_work_mm = 12.0", "nozzle_to_work_mm = 16.0").unwrap_err();
        assert!(matches!(&e, ProcedureError::Value { field, .. } if field == "torch.nozzle_to_work_mm"), "{e}");
    }

    #[test]
    fn unknown_fields_and_joints_are_named() {
        let e = example_with("cap_height_mm", "cap_hieght_mm").unwrap_err();
        assert!(e.to_string().contains("cap_hieght_mm"), "{e}");
        let e = example_with("joint = \"lap\"", "joint = \"corner\"").unwrap_err();
        assert!(e.to_string().contains("unknown joint `corner`"), "{e}");
    }
}
