//! A planning result: seams with base-frame waypoints, quality figures and
//! per-stage timings. The JSON form is a contract for scripts calling
//! `weldseam plan --json`; field names only ever get added, never renamed.
//!
//! The same types are the binary link's PlanReply, whose layout within a
//! protocol version never changes: a field added for JSON only (a warning's
//! or a refusal's `rule`) is skipped by the binary form, and travels on the
//! wire behind its capability instead (`rule_ids`, see
//! [`crate::frame::encode_body_in`]). A seam's figures along it and its
//! process are in neither form of the seam: the binary link carries them
//! behind `along_seam`, and `plan --json` prints them beside the seam
//! ([`crate::along_seam`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::along_seam::{JointFigures, SeamProcess};

/// A plane weld joint type; JSON and wire names are `v_butt`, `i_butt`,
/// `lap`, `t_fillet` (version 6: named; version 7: planned).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Joint {
    VButt,
    IButt,
    Lap,
    TFillet,
}

/// One waypoint in the robot base frame: position in mm, torch
/// orientation as the configured Euler angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    pub xyz: [f64; 3],
    pub rpy_deg: [f64; 3],
}

/// One planned seam.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Seam {
    /// The joint planned: the one requested, or the one found for `auto`.
    pub joint: Joint,
    /// What the daemon saw that makes it this joint (the plates' layers,
    /// what lies between a butt joint's edges); absent from the paper's
    /// method.
    pub joint_evidence: Option<String>,
    /// Ordered along the seam, base frame.
    pub waypoints: Vec<Waypoint>,
    /// The seam's ends and the plate normal (into the workpiece), camera frame.
    pub start_camera: [f64; 3],
    pub end_camera: [f64; 3],
    pub normal_camera: [f64; 3],
    pub length_mm: f64,
    /// RMS residual of each weld edge's least-squares fit, mm.
    pub edge_fit_rms_mm: [f64; 2],
    /// Samples each edge fit used, and how many outliers it dropped.
    pub edge_samples: [u32; 2],
    pub edge_samples_dropped: [u32; 2],
    /// How much of the visible joint the seam spans and how much of the
    /// seam its edges were seen along; absent from the paper's method.
    pub coverage: Option<SeamCoverage>,
    /// What the fits say about the seam; absent from the paper's method.
    pub quality: Option<SeamQuality>,
    /// The quality gates the seam failed that the daemon's config makes
    /// warnings (`quality.warn_only`) rather than refusals.
    pub warnings: Vec<GateWarning>,
    /// The joint's figures at each waypoint (empty where none are
    /// measured); None where they were not carried. Not part of the
    /// seam's own layout in either form: the binary link carries them
    /// behind the `along_seam` capability, `plan --json` beside the seam
    /// ([`crate::along_seam`]).
    #[serde(skip)]
    pub along_seam: Option<Vec<JointFigures>>,
    /// The weld process along the seam, with a procedure configured and
    /// carried as `along_seam` is.
    #[serde(skip)]
    pub process: Option<SeamProcess>,
}

/// A figure's least, mean and greatest value along the seam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

/// A seam's quality figures, read from the pipeline's fits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SeamQuality {
    /// The cloud's point spacing at the seam, mm.
    pub point_spacing_mm: f64,
    /// Butt joints: the distance between the weld edges across the seam,
    /// mm (an I-butt's gap, a V-groove's top width).
    pub gap_mm: Option<Spread>,
    /// Butt joints: the plates' high-low misalignment, mm.
    pub misalignment_mm: Option<f64>,
    /// Lap joints: the step from the upper to the lower plate, mm.
    pub lap_step_mm: Option<f64>,
    /// How far behind the plates (the lower one of a lap) the surface they
    /// rest on lies, mm, when it is seen: the plates are at most that thick.
    pub depth_to_support_mm: Option<f64>,
    /// The angle between the two plates' planes, degrees.
    pub plate_angle_deg: f64,
    /// The seam's estimated position uncertainty (one sigma), across it
    /// and along the plate normal, mm; today one estimate from the edge
    /// fits' residual, not split by direction, so the two are equal.
    pub uncertainty_across_mm: f64,
    pub uncertainty_normal_mm: f64,
    /// V-butt joints: the groove angle (degrees) and its depth below the
    /// plates' top (mm) as measured; the depth only where a bevel face is
    /// seen down to the root.
    pub groove_angle_deg: Option<f64>,
    pub groove_depth_mm: Option<f64>,
}

/// A quality gate the seam failed, reported as a warning.
#[derive(Debug, Clone, PartialEq)]
pub struct GateWarning {
    /// The gate's name, as `quality.warn_only` and the error codes 60 to
    /// 66, 68 and 71 name it (e.g. `joint_coverage`).
    pub gate: String,
    /// The planner's rule that failed the seam (`family.decision`, as
    /// docs/RULES.md lists it). In JSON always; on the binary link only to
    /// a peer granted `rule_ids`, and None when decoded from one that was
    /// not.
    pub rule: Option<String>,
    pub value: f64,
    pub limit: f64,
    /// One sentence with the figure, its value and the limit.
    pub message: String,
}

/// [`GateWarning`] as JSON has it.
#[derive(Serialize, Deserialize)]
#[serde(rename = "GateWarning")]
struct GateWarningJson {
    gate: String,
    #[serde(default)]
    rule: Option<String>,
    value: f64,
    limit: f64,
    message: String,
}

/// [`GateWarning`]'s binary layout: every field but the rule.
type GateWarningWire = (String, f64, f64, String);

impl Serialize for GateWarning {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let GateWarning { gate, rule, value, limit, message } = self.clone();
        if s.is_human_readable() {
            GateWarningJson { gate, rule, value, limit, message }.serialize(s)
        } else {
            (gate, value, limit, message).serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for GateWarning {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        if d.is_human_readable() {
            let GateWarningJson { gate, rule, value, limit, message } = GateWarningJson::deserialize(d)?;
            Ok(GateWarning { gate, rule, value, limit, message })
        } else {
            let (gate, value, limit, message) = GateWarningWire::deserialize(d)?;
            Ok(GateWarning { gate, rule: None, value, limit, message })
        }
    }
}

/// A seam's coverage of the joint the camera saw.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SeamCoverage {
    /// The fraction of the seam's length each weld edge was seen along.
    pub edge: [f64; 2],
    /// The fraction of the visible joint (where both plates are seen
    /// beside the seam) the seam spans.
    pub joint: f64,
    /// The visible joint's length, mm.
    pub visible_joint_mm: f64,
    /// How much of the seam runs beyond the visible joint, mm.
    pub beyond_mm: f64,
}

/// Point counts through the pipeline.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCounts {
    pub valid: u64,
    pub plane: u64,
    pub clusters: u32,
    pub plates: [u64; 2],
    pub edges: [u64; 2],
    pub edge_lines: u32,
}

/// The result of planning one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanResult {
    /// Every seam planned, in the order to weld them (a frame of several
    /// workpieces has several; PROTOCOL.md states the order).
    pub seams: Vec<Seam>,
    /// The joints seen but not planned (version 7): each refused
    /// workpiece of a frame of several, with why. Empty for a frame of one
    /// workpiece, whose refusal is the reply's error instead.
    pub unplanned: Vec<UnplannedJoint>,
    /// Milliseconds per pipeline stage, plus `total`.
    pub timing_ms: BTreeMap<String, f64>,
    /// `robust` or `paper`.
    pub method: String,
    /// The Euler convention of every `rpy_deg`.
    pub euler_convention: String,
    pub points: PointCounts,
}

/// A joint seen in the frame but not planned, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnplannedJoint {
    /// `v_butt`, `i_butt`, `lap` or `t_fillet`, where the planner could
    /// tell the joint.
    pub joint: Option<String>,
    /// Where the joint lies in the camera frame (its plates' middle), mm.
    pub near_camera_mm: Option<[f64; 3]>,
    /// The error code a refusal of this joint alone would carry (as the
    /// wire's `ErrorCode` number).
    pub code: u16,
    /// The stage, the code's name, the gate and the sentence.
    pub refusal: Refusal,
}

/// Why a plan was refused, as `weldseam plan --json` prints it under
/// `error` and a plan's trace records it.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// The pipeline stage that refused, e.g. `background`.
    pub stage: String,
    /// The error code a controller would get, by name.
    pub code: String,
    /// The planner's rule that refused (`family.decision`, as
    /// docs/RULES.md lists it). In JSON always; on the binary link only to
    /// a peer granted `rule_ids`, and None when decoded from one that was
    /// not.
    pub rule: Option<String>,
    /// The quality gate that refused, when one did.
    pub gate: Option<String>,
    /// One sentence a person can act on.
    pub message: String,
}

/// [`Refusal`] as JSON has it.
#[derive(Serialize, Deserialize)]
#[serde(rename = "Refusal")]
struct RefusalJson {
    stage: String,
    code: String,
    #[serde(default)]
    rule: Option<String>,
    gate: Option<String>,
    message: String,
}

/// [`Refusal`]'s binary layout: every field but the rule.
type RefusalWire = (String, String, Option<String>, String);

impl Serialize for Refusal {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let Refusal { stage, code, rule, gate, message } = self.clone();
        if s.is_human_readable() {
            RefusalJson { stage, code, rule, gate, message }.serialize(s)
        } else {
            (stage, code, gate, message).serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for Refusal {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        if d.is_human_readable() {
            let RefusalJson { stage, code, rule, gate, message } = RefusalJson::deserialize(d)?;
            Ok(Refusal { stage, code, rule, gate, message })
        } else {
            let (stage, code, gate, message) = RefusalWire::deserialize(d)?;
            Ok(Refusal { stage, code, rule: None, gate, message })
        }
    }
}

impl PlanResult {
    /// The rule ids of every seam's warnings, seam by seam, as a PlanReply
    /// granted `rule_ids` carries them after its result.
    pub fn warning_rules(&self) -> Vec<Vec<String>> {
        self.seams.iter().map(|s| s.warnings.iter().map(|w| w.rule.clone().unwrap_or_default()).collect()).collect()
    }

    /// The rule ids of the unplanned joints, in order.
    pub fn unplanned_rules(&self) -> Vec<String> {
        self.unplanned.iter().map(|u| u.refusal.rule.clone().unwrap_or_default()).collect()
    }

    /// Sets the rules [`PlanResult::warning_rules`] and
    /// [`PlanResult::unplanned_rules`] give; false, and nothing set, when
    /// their counts are not those of the seams, warnings and joints.
    pub fn set_rules(&mut self, warnings: Vec<Vec<String>>, unplanned: Vec<String>) -> bool {
        let fits = warnings.len() == self.seams.len()
            && self.seams.iter().zip(&warnings).all(|(s, w)| s.warnings.len() == w.len())
            && unplanned.len() == self.unplanned.len();
        if !fits {
            return false;
        }
        for (seam, rules) in self.seams.iter_mut().zip(warnings) {
            for (warning, rule) in seam.warnings.iter_mut().zip(rules) {
                warning.rule = Some(rule);
            }
        }
        for (joint, rule) in self.unplanned.iter_mut().zip(unplanned) {
            joint.refusal.rule = Some(rule);
        }
        true
    }
}
