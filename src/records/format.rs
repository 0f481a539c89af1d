//! One plan record as bytes: a header that names the format and its
//! version, then the record in bincode 2 (its standard configuration,
//! through serde).
//!
//! The header is `WELDSEAM-RECORD` and a little-endian `u32` version. A
//! build reads only the version it writes and says which it found, so a
//! record from another build is refused by name, never misread.

use serde::{Deserialize, Serialize};
use weldseam_proto::message::{FrameMeta, PlanRequest as WireRequest, Point};
use weldseam_proto::plan::PlanResult;

use crate::cloud::PointCloud;
use crate::convert::from_proto::FrameInput;
use crate::convert::{from_proto, to_proto};
use crate::pipeline::PlanRequest;

/// The bytes every record file starts with.
pub const MAGIC: &[u8; 15] = b"WELDSEAM-RECORD";

/// The record format this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

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
    #[error("record format {found}; this build reads format {FORMAT_VERSION}")]
    Version { found: u32 },
    #[error("the record is {bytes} bytes, over the {MAX_RECORD_BYTES} bytes a record may have")]
    TooLarge { bytes: u64 },
    #[error("the record is damaged: {0}")]
    Decode(#[from] bincode::error::DecodeError),
    #[error("cannot encode the record: {0}")]
    Encode(#[from] bincode::error::EncodeError),
    #[error("the record's frame does not have width x height points")]
    FrameSize,
}

impl Record {
    /// The record's bytes, header first.
    pub fn encode(&self) -> Result<Vec<u8>, FormatError> {
        let mut bytes = Vec::with_capacity(64 + self.points.len() * 12);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bincode::serde::encode_into_std_write(self, &mut bytes, bincode::config::standard())?;
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
        if found != FORMAT_VERSION {
            return Err(FormatError::Version { found });
        }
        let config = bincode::config::standard().with_limit::<{ MAX_RECORD_BYTES as usize }>();
        let (record, _) = bincode::serde::decode_from_slice(&rest[4..], config)?;
        Ok(record)
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
        }
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
        assert_eq!(Record::decode(&other).unwrap_err().to_string(), "record format 7; this build reads format 1");
        assert!(matches!(Record::decode(b"PCD"), Err(FormatError::NotARecord)));
        assert!(matches!(Record::decode(&bytes[..bytes.len() - 3]), Err(FormatError::Decode(_))));
    }
}
