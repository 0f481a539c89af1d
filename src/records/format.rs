//! One plan record as bytes: a header that names the format and its
//! version, then the record in bincode 2 (its standard configuration,
//! through serde).
//!
//! The header is `WELDSEAM-RECORD` and a little-endian `u32` version. A
//! build reads the versions it knows and says which it found of any
//! other, so a record from a newer build is refused by name, never
//! misread.
//!
//! - Format 1: the record, its plan in the binary link's layout, which
//!   leaves out what travels behind capabilities: each seam's figures
//!   along it and its weld process, and the rule ids of warnings and of
//!   joints left unplanned.
//! - Format 2 (written now): format 1's bytes, then those left-out fields
//!   ([`Carried`]) and the weld procedure's text, so a record holds
//!   everything the plan carried and what planned it. A format 1 record
//!   still reads, without them, and says so ([`Record::format`]).

use serde::{Deserialize, Serialize};
use weldseam_proto::along_seam::{JointFigures, SeamProcess};
use weldseam_proto::message::{FrameMeta, PlanRequest as WireRequest, Point};
use weldseam_proto::plan::PlanResult;

use crate::cloud::PointCloud;
use crate::convert::from_proto::FrameInput;
use crate::convert::{from_proto, to_proto};
use crate::pipeline::PlanRequest;

/// The bytes every record file starts with.
pub const MAGIC: &[u8; 15] = b"WELDSEAM-RECORD";

/// The record format this build writes.
pub const FORMAT_VERSION: u32 = 2;

/// The oldest record format this build reads (every one up to
/// [`FORMAT_VERSION`]).
pub const OLDEST_FORMAT_READ: u32 = 1;

/// The largest record this build reads: a frame of the largest payload the
/// daemon accepts (`server.max_frame_bytes` at its most) and room for the rest.
pub const MAX_RECORD_BYTES: u64 = (4 << 30) + (64 << 20);

/// What one plan was: the frame as received, the request, the
/// configuration and what was answered.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// When the answer was sent, microseconds since the Unix epoch.
    pub time_us: u64,
    /// The link the request came on: `controller` or `text`.
    pub link: String,
    pub request_id: u64,
    /// The request as the controller link carries it (what the daemon
    /// planned with, in the wire's form, the frame left to the record).
    pub request: WireRequest,
    /// The frame's header as the camera sent it.
    pub frame: FrameMeta,
    /// The camera's Hello name.
    pub camera: String,
    /// Its points, as received.
    pub points: Vec<Point>,
    /// [`crate::config::Config::planning_hash`] of the configuration that planned.
    pub config_hash: String,
    /// That configuration's file, when the daemon was started from one;
    /// None for the built-in defaults.
    pub config_text: Option<String>,
    pub outcome: Outcome,
    /// The weld procedure's TOML text, when one was configured (format 2):
    /// `config_text` only names its file, which may change. Stored after
    /// the record, with [`Carried`].
    #[serde(skip)]
    pub procedure_text: Option<String>,
    /// The format the record was read from ([`FORMAT_VERSION`] for one
    /// made by this build): a format 1 record's plan lacks the fields
    /// format 2 added. Not itself stored: the header says it.
    #[serde(skip)]
    pub format: u32,
}

/// What format 2 stores after the record: what the plan's binary layout
/// leaves out, and the procedure's text.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct Trailer {
    carried: Carried,
    procedure_text: Option<String>,
}

/// What a plan's binary layout leaves out, kept after the record in
/// format 2: per seam its figures along it, its process and its
/// warnings' rule ids, and the rule id of each joint left unplanned.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct Carried {
    seams: Vec<CarriedSeam>,
    unplanned_rules: Vec<Option<String>>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct CarriedSeam {
    along_seam: Option<Vec<JointFigures>>,
    process: Option<SeamProcess>,
    warning_rules: Vec<Option<String>>,
}

impl Carried {
    /// The left-out fields of `outcome`'s plan (none of a refusal).
    fn of(outcome: &Outcome) -> Carried {
        let Outcome::Planned(result) = outcome else { return Carried::default() };
        Carried {
            seams: result
                .seams
                .iter()
                .map(|s| CarriedSeam {
                    along_seam: s.along_seam.clone(),
                    process: s.process.clone(),
                    warning_rules: s.warnings.iter().map(|w| w.rule.clone()).collect(),
                })
                .collect(),
            unplanned_rules: result.unplanned.iter().map(|u| u.refusal.rule.clone()).collect(),
        }
    }

    /// Puts them back into `outcome`'s plan; Err when they do not fit it
    /// (another count of seams, warnings or unplanned joints).
    fn restore(self, outcome: &mut Outcome) -> Result<(), FormatError> {
        let Outcome::Planned(result) = outcome else {
            return if self == Carried::default() { Ok(()) } else { Err(FormatError::Carried) };
        };
        if self.seams.len() != result.seams.len() || self.unplanned_rules.len() != result.unplanned.len() {
            return Err(FormatError::Carried);
        }
        for (seam, carried) in result.seams.iter_mut().zip(self.seams) {
            if carried.warning_rules.len() != seam.warnings.len() {
                return Err(FormatError::Carried);
            }
            seam.along_seam = carried.along_seam;
            seam.process = carried.process;
            for (warning, rule) in seam.warnings.iter_mut().zip(carried.warning_rules) {
                warning.rule = rule;
            }
        }
        for (unplanned, rule) in result.unplanned.iter_mut().zip(self.unplanned_rules) {
            unplanned.refusal.rule = rule;
        }
        Ok(())
    }
}

/// What the daemon answered.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Outcome {
    Planned(PlanResult),
    Refused {
        /// The error code's name.
        code: String,
        /// The planner's rule that refused, when one did.
        rule: Option<String>,
        reason: String,
    },
}

impl Outcome {
    /// `planned`, or the refusal's code.
    pub fn name(&self) -> &str {
        match self {
            Outcome::Planned(_) => "planned",
            Outcome::Refused { code, .. } => code,
        }
    }
}

/// Why a record could not be read.
#[derive(Debug, thiserror::Error)]
pub enum FormatError {
    #[error("not a weldseam plan record (it does not start with {})", String::from_utf8_lossy(MAGIC))]
    NotARecord,
    #[error("record format {found}; this build reads formats {OLDEST_FORMAT_READ} to {FORMAT_VERSION}")]
    Version { found: u32 },
    #[error("the record is {bytes} bytes, over the {MAX_RECORD_BYTES} bytes a record may have")]
    TooLarge { bytes: u64 },
    #[error("the record is damaged: {0}")]
    Decode(#[from] bincode::error::DecodeError),
    #[error("cannot encode the record: {0}")]
    Encode(#[from] bincode::error::EncodeError),
    #[error("the record's frame does not have width x height points")]
    FrameSize,
    #[error("the record is damaged: its plan's fields beside the seams do not fit its seams")]
    Carried,
}

impl Record {
    /// The record's bytes, header first.
    pub fn encode(&self) -> Result<Vec<u8>, FormatError> {
        let mut bytes = Vec::with_capacity(64 + self.points.len() * 12);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        let trailer = Trailer { carried: Carried::of(&self.outcome), procedure_text: self.procedure_text.clone() };
        bincode::serde::encode_into_std_write((self, &trailer), &mut bytes, bincode::config::standard())?;
        Ok(bytes)
    }

    /// Reads a record's bytes, checking the header and the version.
    pub fn decode(bytes: &[u8]) -> Result<Record, FormatError> {
        if bytes.len() as u64 > MAX_RECORD_BYTES {
            return Err(FormatError::TooLarge { bytes: bytes.len() as u64 });
        }
        let rest = bytes.strip_prefix(MAGIC.as_slice()).ok_or(FormatError::NotARecord)?;
        let version: [u8; 4] = rest.get(..4).and_then(|v| v.try_into().ok()).ok_or(FormatError::NotARecord)?;
        let found = u32::from_le_bytes(version);
        let config = bincode::config::standard().with_limit::<{ MAX_RECORD_BYTES as usize }>();
        let body = &rest[4..];
        let mut record: Record = match found {
            1 => bincode::serde::decode_from_slice(body, config)?.0,
            2 => {
                let ((mut record, trailer), _): ((Record, Trailer), _) =
                    bincode::serde::decode_from_slice(body, config)?;
                trailer.carried.restore(&mut record.outcome)?;
                record.procedure_text = trailer.procedure_text;
                record
            }
            _ => return Err(FormatError::Version { found }),
        };
        record.format = found;
        Ok(record)
    }

    /// The outcome's bytes as format 2 stores them: the plan in the binary
    /// layout, then what that layout leaves out. Two outcomes with the
    /// same bytes are the same plan bit for bit.
    pub fn outcome_bytes(outcome: &Outcome) -> Option<Vec<u8>> {
        bincode::serde::encode_to_vec((outcome, Carried::of(outcome)), bincode::config::standard()).ok()
    }

    /// `outcome` as a format 1 record held it: the plan without what the
    /// binary layout leaves out.
    pub fn as_format_1(outcome: &Outcome) -> Outcome {
        let mut outcome = outcome.clone();
        if let Outcome::Planned(result) = &mut outcome {
            for seam in &mut result.seams {
                (seam.along_seam, seam.process) = (None, None);
                seam.warnings.iter_mut().for_each(|w| w.rule = None);
            }
            result.unplanned.iter_mut().for_each(|u| u.refusal.rule = None);
        }
        outcome
    }

    /// The frame as the pipeline takes it: the cloud and its units and frame.
    pub fn cloud(&self) -> Result<(PointCloud, FrameInput), FormatError> {
        let frame = weldseam_proto::message::Frame { meta: self.frame, points: self.points.clone() };
        from_proto::frame(frame).ok_or(FormatError::FrameSize)
    }

    /// The frame's points and header in the wire's form.
    pub fn frame_of(cloud: &PointCloud, input: FrameInput, meta: FrameMeta) -> (FrameMeta, Vec<Point>) {
        let frame = to_proto::frame_in(cloud, input, meta.frame_id, meta.trigger_id, meta.capture_time_us);
        (frame.meta, frame.points)
    }

    /// The request in the wire's form.
    pub fn wire_request(request_id: u64, request: &PlanRequest) -> WireRequest {
        to_proto::plan_request(request_id, request, weldseam_proto::message::FrameSelect::NextFrame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose::RobotPose;
    use crate::joint::JointType;

    fn record() -> Record {
        let pose = RobotPose { xyz_mm: [1.0, 2.0, 3.0], angles_deg: [0.0, 10.0, 0.0] };
        let request = PlanRequest::new(JointType::Lap, None, pose);
        let meta =
            FrameMeta { frame_id: 4, trigger_id: 1, capture_time_us: 5, width: 2, height: 1, units: 0, cloud_frame: 0 };
        Record {
            time_us: 9,
            link: "controller".into(),
            request_id: 3,
            request: Record::wire_request(3, &request),
            frame: meta,
            camera: "cam".into(),
            points: vec![[0.0, 0.0, 300.0], [f32::NAN, 1.0, 2.0]],
            config_hash: "abc".into(),
            config_text: None,
            outcome: Outcome::Refused {
                code: "plan_failed".into(),
                rule: Some("frame.no_valid_point".into()),
                reason: "x".into(),
            },
            procedure_text: None,
            format: FORMAT_VERSION,
        }
    }

    /// A planned outcome with every field the binary layout leaves out set.
    fn planned() -> Outcome {
        use weldseam_proto::along_seam::{CutStretch, Measured};
        use weldseam_proto::plan::{GateWarning, Joint, PointCounts, Refusal, Seam, UnplannedJoint, Waypoint};
        let figures = JointFigures { gap_mm: Some(Measured { value: 1.5, sigma: 0.1 }), ..Default::default() };
        let seam = Seam {
            joint: Joint::IButt,
            joint_evidence: None,
            waypoints: vec![Waypoint { xyz: [1.0, 2.0, 3.0], rpy_deg: [180.0, 0.0, 0.0] }; 2],
            start_camera: [0.0; 3],
            end_camera: [0.0, 10.0, 0.0],
            normal_camera: [0.0, 0.0, 1.0],
            length_mm: 10.0,
            edge_fit_rms_mm: [0.1, 0.1],
            edge_samples: [5, 5],
            edge_samples_dropped: [0, 0],
            coverage: None,
            quality: None,
            warnings: vec![GateWarning {
                gate: "joint_coverage".into(),
                rule: Some("seam.stops_short_of_joint".into()),
                value: 0.5,
                limit: 0.8,
                message: "m".into(),
            }],
            along_seam: Some(vec![figures, JointFigures::default()]),
            process: Some(SeamProcess {
                procedure: "p".into(),
                waypoints: vec![None, None],
                cut: vec![CutStretch {
                    first: 0,
                    last: 1,
                    rule: "process.torch_blocked".into(),
                    reason: "r".into(),
                    contact_camera_mm: Some([1.0, 2.0, 3.0]),
                }],
            }),
        };
        let unplanned = UnplannedJoint {
            joint: Some("lap".into()),
            near_camera_mm: None,
            code: 67,
            refusal: Refusal {
                stage: "background".into(),
                code: "joint_mismatch".into(),
                rule: Some("joint.not_requested".into()),
                gate: None,
                message: "m".into(),
            },
        };
        Outcome::Planned(PlanResult {
            seams: vec![seam],
            unplanned: vec![unplanned],
            timing_ms: Default::default(),
            method: "robust".into(),
            euler_convention: "xyz".into(),
            points: PointCounts::default(),
        })
    }

    #[test]
    fn a_plan_reads_back_with_its_figures_process_and_rule_ids_and_format_1_still_reads() {
        let r = Record { points: Vec::new(), outcome: planned(), procedure_text: Some("name = 1".into()), ..record() };
        let bytes = r.encode().unwrap();
        assert_eq!(Record::decode(&bytes).unwrap(), r);
        // Format 1 was the record alone, the plan in the binary layout.
        let mut old = MAGIC.to_vec();
        old.extend_from_slice(&1u32.to_le_bytes());
        bincode::serde::encode_into_std_write(&r, &mut old, bincode::config::standard()).unwrap();
        let back = Record::decode(&old).unwrap();
        assert_eq!((back.format, back.procedure_text.as_deref()), (1, None));
        let Outcome::Planned(result) = &back.outcome else { panic!("{back:?}") };
        assert!(result.seams[0].along_seam.is_none() && result.seams[0].process.is_none());
        assert_eq!(result.seams[0].warnings[0].rule, None);
        assert_eq!(result.seams[0].waypoints[1].xyz, [1.0, 2.0, 3.0]);
    }

    #[test]
    fn a_record_reads_back_and_a_record_of_another_format_is_named() {
        let r = record();
        let bytes = r.encode().unwrap();
        let back = Record::decode(&bytes).unwrap();
        // NaN is not equal to itself: compare the bits.
        assert_eq!(back.points[1][0].to_bits(), r.points[1][0].to_bits());
        assert_eq!(Record { points: Vec::new(), ..back }, Record { points: Vec::new(), ..r });
        let mut other = bytes.clone();
        other[MAGIC.len()..MAGIC.len() + 4].copy_from_slice(&7u32.to_le_bytes());
        assert_eq!(Record::decode(&other).unwrap_err().to_string(), "record format 7; this build reads formats 1 to 2");
        assert!(matches!(Record::decode(b"PCD"), Err(FormatError::NotARecord)));
        assert!(matches!(Record::decode(&bytes[..bytes.len() - 3]), Err(FormatError::Decode(_))));
    }
}
