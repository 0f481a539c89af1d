//! The `along_seam` capability's fields: per seam, the joint's figures at
//! every waypoint (gap, high-low, a V-groove's cross-section, a lap's
//! step, each with its standard error) and, with a weld procedure
//! configured, the process (per waypoint the passes and their arc
//! settings, the torch's angles, and the stretches cut).
//!
//! A capability appends its fields after every field a message had, in
//! the order of the capabilities' bits, so a peer that did not ask reads
//! exactly the bytes it read before: a PlanReply granted `along_seam`
//! ends, after the `rule_ids` fields when those are granted too, with an
//! `Option` of one [`AlongSeam`] per seam. It is absent (`00`) when the
//! reply would pass [`MAX_CONTROL_MESSAGE_BYTES`] with it (a long seam at
//! a fine step with many passes), or when a seam was handed to the
//! encoder without its figures; the seams' own fields are then `None`.
//!
//! The same types are what `weldseam plan --json` prints beside each
//! seam (`along_seam`, `process`), under the same field names.

use serde::{Deserialize, Serialize};

use crate::frame::{DecodeError, EncodeError, MAX_CONTROL_MESSAGE_BYTES, decode_prefix, encode_struct};
use crate::message::{PlanReply, Tag};
use crate::plan::Seam;
use crate::session::{Session, capability};

/// A figure and its standard error (one sigma), in the figure's unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    pub value: f64,
    pub sigma: f64,
}

/// The joint at one waypoint, each figure absent where the points near
/// the waypoint do not give it (or it does not apply to the joint).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct JointFigures {
    /// Butt joints: the distance between the weld edges across the seam,
    /// mm (an I-butt's gap, a V-groove's opening at the plates' top).
    pub gap_mm: Option<Measured>,
    /// Butt joints: the plates' height difference along the normal, mm.
    pub high_low_mm: Option<Measured>,
    /// V-butt joints: the groove's cross-section from the plates' top to
    /// its root, mm², with its angle (degrees) and depth (mm).
    pub groove_area_mm2: Option<Measured>,
    pub groove_angle_deg: Option<f64>,
    pub groove_depth_mm: Option<f64>,
    /// Lap joints: the step from the upper plate's edge down to the lower
    /// plate, mm.
    pub lap_step_mm: Option<Measured>,
}

/// The weld process along one seam.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeamProcess {
    /// The procedure's name, as its file gives it.
    pub procedure: String,
    /// Per waypoint, in the waypoints' order; absent where it is cut.
    pub waypoints: Vec<Option<WaypointProcess>>,
    /// The stretches cut from the weld, in order along the seam.
    pub cut: Vec<CutStretch>,
}

/// What one waypoint is welded with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WaypointProcess {
    /// The plates' thickness the procedure's entry was chosen by, mm.
    pub thickness_mm: f64,
    /// The joint's own cross-section and the crown over it, mm².
    pub joint_area_mm2: f64,
    pub crown_area_mm2: f64,
    /// The torch's work and travel angles of the pass the waypoints
    /// trace, degrees, after any change to clear the workpiece.
    pub work_angle_deg: f64,
    pub travel_angle_deg: f64,
    /// Whether those angles were moved from the procedure's to clear the
    /// workpiece (the waypoint's orientation follows them).
    pub re_angled: bool,
    /// The passes, root first.
    pub passes: Vec<Pass>,
}

/// A pass's place in a layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PassKind {
    Root,
    Fill,
    Cap,
    /// The only pass of a joint one bead fills.
    Single,
}

/// One pass at a waypoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pass {
    pub kind: PassKind,
    /// The layer, from 0 at the root, and the bead within it, from the
    /// first plate's side.
    pub layer: u32,
    pub bead: u32,
    /// The aim point: across the seam from the groove's centre line
    /// (negative towards the first plate) and up from the root, mm.
    pub lateral_mm: f64,
    pub height_mm: f64,
    /// The pass's work angle, degrees.
    pub work_angle_deg: f64,
    pub travel_speed_mm_s: f64,
    pub wire_feed_m_min: f64,
    pub voltage_v: f64,
    pub current_a: f64,
    /// The cross-section the joint asks of this bead and the one these
    /// settings deposit, mm².
    pub target_area_mm2: f64,
    pub deposited_area_mm2: f64,
    /// The torch's swing across the seam, where the procedure weaves.
    pub weave: Option<Weave>,
}

/// A weave's shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WeavePattern {
    Triangle,
    Sine,
    Trapezoid,
}

/// The torch's swing across the seam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Weave {
    pub pattern: WeavePattern,
    /// Half the swing, mm.
    pub amplitude_mm: f64,
    /// Travel along the seam per cycle, mm.
    pub wavelength_mm: f64,
    /// Travel while the torch dwells at each side, mm (trapezoid only).
    pub dwell_mm: f64,
    /// Cycles per second at the pass's travel speed.
    pub frequency_hz: f64,
}

/// A run of waypoints cut from the weld, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CutStretch {
    /// The first and last waypoint cut, indices into the seam's waypoints.
    pub first: u64,
    pub last: u64,
    /// The planner's rule that cut it (`process.torch_blocked`).
    pub rule: String,
    /// The figure and the limit, or what is missing, at its first waypoint.
    pub reason: String,
    /// Where the torch touches the workpiece, camera frame, mm, for a
    /// torch no angle clears.
    pub contact_camera_mm: Option<[f64; 3]>,
}

/// One seam's fields on a connection granted `along_seam`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlongSeam {
    /// One per waypoint; empty where the planner measures none (the
    /// paper's method, a tee's fillet).
    pub figures: Vec<JointFigures>,
    /// Absent without a weld procedure configured.
    pub process: Option<SeamProcess>,
}

/// Why a seam's fields do not fit it, or None.
fn misfit(seam: &Seam, along: &AlongSeam) -> Option<String> {
    let n = seam.waypoints.len();
    if !along.figures.is_empty() && along.figures.len() != n {
        return Some(format!("{} figures for {n} waypoints", along.figures.len()));
    }
    let process = along.process.as_ref()?;
    if process.waypoints.len() != n {
        return Some(format!("a process of {} waypoints for {n}", process.waypoints.len()));
    }
    let cut_past_end = process.cut.iter().any(|c| c.first > c.last || c.last >= n as u64);
    cut_past_end.then(|| format!("a cut stretch outside the seam's {n} waypoints"))
}

/// Appends the capability's fields to `out`, which holds the reply's
/// earlier fields.
pub(crate) fn encode(session: Session, m: &PlanReply, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    if !session.has(capability::ALONG_SEAM) {
        return Ok(());
    }
    let seams = &m.result.seams;
    let along: Option<Vec<AlongSeam>> = seams
        .iter()
        .map(|s| s.along_seam.clone().map(|figures| AlongSeam { figures, process: s.process.clone() }))
        .collect();
    let mut fields = Vec::new();
    encode_struct(Tag::PlanReply, &along, &mut fields)?;
    if out.len() + fields.len() > MAX_CONTROL_MESSAGE_BYTES {
        fields.clear();
        encode_struct(Tag::PlanReply, &None::<Vec<AlongSeam>>, &mut fields)?;
    }
    out.extend_from_slice(&fields);
    Ok(())
}

/// Reads the capability's fields from the start of `payload` into
/// `reply`'s seams; returns the bytes they took.
pub(crate) fn decode(session: Session, payload: &[u8], reply: &mut PlanReply) -> Result<usize, DecodeError> {
    if !session.has(capability::ALONG_SEAM) {
        return Ok(0);
    }
    let tag = Tag::PlanReply;
    let malformed = |reason: String| DecodeError::Malformed { tag: tag.name(), reason };
    let (along, used) = decode_prefix::<Option<Vec<AlongSeam>>>(tag, payload)?;
    let Some(along) = along else { return Ok(used) };
    let seams = &mut reply.result.seams;
    if along.len() != seams.len() {
        return Err(malformed(format!("along_seam has {} seams for the reply's {}", along.len(), seams.len())));
    }
    for (k, (seam, along)) in seams.iter_mut().zip(along).enumerate() {
        if let Some(why) = misfit(seam, &along) {
            return Err(malformed(format!("along_seam of seam {k}: {why}")));
        }
        (seam.along_seam, seam.process) = (Some(along.figures), along.process);
    }
    Ok(used)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use proptest::prelude::*;

    use super::*;
    use crate::frame::{decode_body_in, encode_body_in};
    use crate::message::Message;
    use crate::plan::{Joint, PlanResult, PointCounts, Waypoint};

    fn seam(waypoints: usize) -> Seam {
        Seam {
            joint: Joint::VButt,
            joint_evidence: None,
            waypoints: vec![Waypoint { xyz: [1.0, 2.0, 3.0], rpy_deg: [180.0, 0.0, 0.0] }; waypoints],
            start_camera: [0.0; 3],
            end_camera: [0.0; 3],
            normal_camera: [0.0, 0.0, 1.0],
            length_mm: 1.0,
            edge_fit_rms_mm: [0.1; 2],
            edge_samples: [10; 2],
            edge_samples_dropped: [0; 2],
            coverage: None,
            quality: None,
            warnings: vec![],
            along_seam: None,
            process: None,
        }
    }

    fn reply(seams: Vec<Seam>) -> PlanReply {
        PlanReply {
            request_id: 1,
            frame_id: 2,
            result: PlanResult {
                seams,
                unplanned: vec![],
                timing_ms: BTreeMap::new(),
                method: "robust".into(),
                euler_convention: "zyx".into(),
                points: PointCounts::default(),
            },
        }
    }

    fn session(capabilities: u64) -> Session {
        Session { version: crate::PROTOCOL_VERSION, capabilities }
    }

    fn round_trip(session: Session, m: &PlanReply) -> PlanReply {
        let message = Message::PlanReply(m.clone());
        let body = encode_body_in(session, &message).unwrap();
        match decode_body_in(session, Tag::PlanReply as u16, &body).unwrap() {
            Message::PlanReply(r) => r,
            other => panic!("{other:?}"),
        }
    }

    fn measured() -> impl Strategy<Value = Option<Measured>> {
        proptest::option::of((-1e3..1e3f64, 0.0..10.0f64).prop_map(|(value, sigma)| Measured { value, sigma }))
    }

    fn figures() -> impl Strategy<Value = JointFigures> {
        let angle = proptest::option::of(0.0..180.0f64);
        let depth = proptest::option::of(0.0..50.0f64);
        (measured(), measured(), measured(), angle, depth, measured()).prop_map(|(g, h, a, angle, depth, l)| {
            JointFigures {
                gap_mm: g,
                high_low_mm: h,
                groove_area_mm2: a,
                groove_angle_deg: angle,
                groove_depth_mm: depth,
                lap_step_mm: l,
            }
        })
    }

    fn pass() -> impl Strategy<Value = Pass> {
        let kind = prop_oneof![Just(PassKind::Root), Just(PassKind::Fill), Just(PassKind::Cap), Just(PassKind::Single)];
        let pattern =
            prop_oneof![Just(WeavePattern::Triangle), Just(WeavePattern::Sine), Just(WeavePattern::Trapezoid)];
        let weave = proptest::option::of((pattern, 0.0..5.0f64, 1.0..10.0f64, 0.0..2.0f64, 0.0..5.0f64).prop_map(
            |(pattern, amplitude_mm, wavelength_mm, dwell_mm, frequency_hz)| Weave {
                pattern,
                amplitude_mm,
                wavelength_mm,
                dwell_mm,
                frequency_hz,
            },
        ));
        (kind, 0..8u32, 0..4u32, proptest::array::uniform10(-1e3..1e3f64), weave).prop_map(
            |(kind, layer, bead, x, weave)| Pass {
                kind,
                layer,
                bead,
                lateral_mm: x[0],
                height_mm: x[1],
                work_angle_deg: x[2],
                travel_speed_mm_s: x[3],
                wire_feed_m_min: x[4],
                voltage_v: x[5],
                current_a: x[6],
                target_area_mm2: x[7],
                deposited_area_mm2: x[8],
                weave,
            },
        )
    }

    fn waypoint_process() -> impl Strategy<Value = Option<WaypointProcess>> {
        let welded = (proptest::array::uniform5(0.0..100.0f64), any::<bool>(), proptest::collection::vec(pass(), 1..6))
            .prop_map(|(x, re_angled, passes)| WaypointProcess {
                thickness_mm: x[0],
                joint_area_mm2: x[1],
                crown_area_mm2: x[2],
                work_angle_deg: x[3],
                travel_angle_deg: x[4],
                re_angled,
                passes,
            });
        proptest::option::of(welded)
    }

    /// A seam of 1 to 12 waypoints with figures (or none measured) and,
    /// perhaps, a process whose cuts lie within it.
    fn seam_along() -> impl Strategy<Value = Seam> {
        (1..12usize).prop_flat_map(|n| {
            let figures = prop_oneof![Just(vec![]), proptest::collection::vec(figures(), n)];
            let cut =
                (0..n as u64, 0..n as u64, ".{0,12}", proptest::option::of(proptest::array::uniform3(-1e3..1e3f64)))
                    .prop_map(|(a, b, reason, contact)| CutStretch {
                        first: a.min(b),
                        last: a.max(b),
                        rule: "process.torch_blocked".into(),
                        reason,
                        contact_camera_mm: contact,
                    });
            let process = proptest::option::of(
                (".{0,12}", proptest::collection::vec(waypoint_process(), n), proptest::collection::vec(cut, 0..3))
                    .prop_map(|(procedure, waypoints, cut)| SeamProcess { procedure, waypoints, cut }),
            );
            (figures, process).prop_map(move |(figures, process)| {
                let mut s = seam(n);
                (s.along_seam, s.process) = (Some(figures), process);
                s
            })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        #[test]
        fn figures_and_processes_survive_the_wire_only_when_granted(
            seams in proptest::collection::vec(seam_along(), 0..4),
            rules in any::<bool>(),
        ) {
            let m = reply(seams);
            let base = if rules { capability::RULE_IDS } else { 0 };
            prop_assert_eq!(round_trip(session(base | capability::ALONG_SEAM), &m), m.clone());
            // Not granted: the seams' own fields only, the bytes of before.
            let plain = round_trip(session(base), &m);
            prop_assert!(plain.result.seams.iter().all(|s| s.along_seam.is_none() && s.process.is_none()));
            let mut stripped = m.clone();
            for s in &mut stripped.result.seams {
                (s.along_seam, s.process) = (None, None);
            }
            let bytes = |s: Session, m: &PlanReply| encode_body_in(s, &Message::PlanReply(m.clone())).unwrap();
            prop_assert_eq!(bytes(session(base), &m), bytes(session(base), &stripped));
            let granted = bytes(session(base | capability::ALONG_SEAM), &m);
            prop_assert!(granted.starts_with(&bytes(session(base), &m)), "appended after every field");
        }
    }

    #[test]
    fn a_seam_without_its_figures_or_a_reply_over_the_limit_carries_none() {
        let granted = session(capability::ALONG_SEAM);
        let mut m = reply(vec![seam(2), seam(3)]);
        m.result.seams[0].along_seam = Some(vec![JointFigures::default(); 2]);
        // The second seam was handed over without its figures.
        let read = round_trip(granted, &m);
        assert!(read.result.seams.iter().all(|s| s.along_seam.is_none()));
        let body = encode_body_in(granted, &Message::PlanReply(m.clone())).unwrap();
        assert_eq!(body.last(), Some(&0), "along_seam absent");

        // A seam of 20000 waypoints, each of ten passes: far over 4 MiB.
        let n = 20_000;
        let mut big = seam(n);
        big.along_seam = Some(vec![JointFigures::default(); n]);
        let pass = Pass {
            kind: PassKind::Fill,
            layer: 1,
            bead: 0,
            lateral_mm: 0.0,
            height_mm: 0.0,
            work_angle_deg: 0.0,
            travel_speed_mm_s: 5.0,
            wire_feed_m_min: 8.0,
            voltage_v: 24.0,
            current_a: 200.0,
            target_area_mm2: 20.0,
            deposited_area_mm2: 20.0,
            weave: None,
        };
        let welded = WaypointProcess {
            thickness_mm: 20.0,
            joint_area_mm2: 200.0,
            crown_area_mm2: 20.0,
            work_angle_deg: 0.0,
            travel_angle_deg: 0.0,
            re_angled: false,
            passes: vec![pass; 10],
        };
        big.process = Some(SeamProcess { procedure: "thick".into(), waypoints: vec![Some(welded); n], cut: vec![] });
        let m = reply(vec![big]);
        let body = encode_body_in(granted, &Message::PlanReply(m.clone())).unwrap();
        assert!(body.len() <= MAX_CONTROL_MESSAGE_BYTES, "{} bytes", body.len());
        assert_eq!(body.last(), Some(&0), "along_seam absent");
        let read = round_trip(granted, &m);
        assert_eq!((read.result.seams[0].along_seam.as_ref(), read.result.seams[0].process.as_ref()), (None, None));
    }

    #[test]
    fn figures_that_do_not_fit_their_seam_are_malformed() {
        let granted = session(capability::ALONG_SEAM);
        let decode = |seams: Vec<AlongSeam>, of: Vec<Seam>| {
            let mut body = encode_body_in(session(0), &Message::PlanReply(reply(of))).unwrap();
            encode_struct(Tag::PlanReply, &Some(seams), &mut body).unwrap();
            decode_body_in(granted, Tag::PlanReply as u16, &body)
        };
        let fits = AlongSeam { figures: vec![JointFigures::default(); 2], process: None };
        assert!(decode(vec![fits.clone()], vec![seam(2)]).is_ok());
        let cases = [
            (vec![fits.clone()], vec![seam(3)]),
            (vec![fits.clone(), fits.clone()], vec![seam(2)]),
            (
                vec![AlongSeam {
                    figures: vec![],
                    process: Some(SeamProcess { procedure: "p".into(), waypoints: vec![None], cut: vec![] }),
                }],
                vec![seam(2)],
            ),
            (
                vec![AlongSeam {
                    figures: vec![],
                    process: Some(SeamProcess {
                        procedure: "p".into(),
                        waypoints: vec![None, None],
                        cut: vec![CutStretch {
                            first: 1,
                            last: 2,
                            rule: "process.torch_blocked".into(),
                            reason: String::new(),
                            contact_camera_mm: None,
                        }],
                    }),
                }],
                vec![seam(2)],
            ),
        ];
        for (along, seams) in cases {
            let got = decode(along.clone(), seams);
            assert!(matches!(got, Err(DecodeError::Malformed { .. })), "{along:?}: {got:?}");
        }
    }
}
