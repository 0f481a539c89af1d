//! Framing: the fixed message header, the one bincode configuration, and
//! the encoding and decoding of message bodies. Pure functions over byte
//! slices; the connections that own sockets and buffers live elsewhere.
//!
//! Every message is a 16-byte [`Header`] followed by `length` payload bytes.
//! The payload of every message but [`Tag::Frame`] is the bincode encoding
//! of its struct in [`wire_config`]. A frame's payload is its
//! [`FrameMeta`] (bincode, 40 bytes) followed by the raw points.

use bincode::config::{Configuration, Fixint, Limit, LittleEndian};

use crate::message::{
    CloudFrame, ErrorReply, FRAME_META_BYTES, Frame, FrameAck, FrameMeta, Hello, HelloAck, Message, POINT_BYTES,
    PlanReply, PlanRequest, Point, Status, Tag, Trigger, Units,
};

/// The first four bytes of every message.
pub const MAGIC: [u8; 4] = *b"WSEM";

/// The protocol version this crate speaks, in every header and hello.
/// Version 2 changed PlanRequest and Status and added FrameAck; version 3
/// added the frame's cloud frame and the request's region of interest;
/// version 4 added each seam's quality figures and warnings to the plan
/// reply; version 5 added `auto` joints, each seam's joint evidence, the
/// measured groove and the request's pose in a convention it names;
/// version 6 names the tee joint (`t_fillet`, joint code 4). See
/// PROTOCOL.md, "Changes from version 5".
pub const PROTOCOL_VERSION: u16 = 7;

/// Bytes of a message header.
pub const HEADER_BYTES: usize = 16;

/// The largest payload of any message other than a frame.
pub const MAX_CONTROL_MESSAGE_BYTES: usize = 4 << 20;

/// The default largest frame payload (128 MiB); the daemon's is configured.
pub const DEFAULT_MAX_FRAME_BYTES: u64 = 128 << 20;

/// The bincode configuration of every message body: little endian,
/// fixed-width integers (u16 is 2 bytes, u32 4, u64 8; enum variants and
/// lengths as u32 and u64), at most [`MAX_CONTROL_MESSAGE_BYTES`].
pub type WireConfig = Configuration<LittleEndian, Fixint, Limit<MAX_CONTROL_MESSAGE_BYTES>>;

/// The one configuration used for every encoding and decoding.
pub const fn wire_config() -> WireConfig {
    bincode::config::standard().with_little_endian().with_fixed_int_encoding().with_limit::<MAX_CONTROL_MESSAGE_BYTES>()
}

/// A message header: magic, version, tag and payload length.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    pub version: u16,
    /// The raw tag; see [`Tag::from_u16`].
    pub tag: u16,
    pub length: u64,
}

impl Header {
    pub fn new(tag: Tag, length: u64) -> Self {
        Header { version: PROTOCOL_VERSION, tag: tag as u16, length }
    }

    /// Bytes 0..4 magic, 4..6 version, 6..8 tag, 8..16 length; little endian.
    pub fn to_bytes(&self) -> [u8; HEADER_BYTES] {
        let mut b = [0u8; HEADER_BYTES];
        b[0..4].copy_from_slice(&MAGIC);
        b[4..6].copy_from_slice(&self.version.to_le_bytes());
        b[6..8].copy_from_slice(&self.tag.to_le_bytes());
        b[8..16].copy_from_slice(&self.length.to_le_bytes());
        b
    }

    /// Parses and checks a header: magic, version and the payload limit of
    /// its tag (`max_frame_bytes` for frames). An unknown tag is not a
    /// framing error: its payload can be skipped.
    pub fn parse(b: &[u8; HEADER_BYTES], max_frame_bytes: u64) -> Result<Header, FramingError> {
        let [m0, m1, m2, m3, v0, v1, t0, t1, l0, l1, l2, l3, l4, l5, l6, l7] = *b;
        if [m0, m1, m2, m3] != MAGIC {
            return Err(FramingError::BadMagic([m0, m1, m2, m3]));
        }
        let version = u16::from_le_bytes([v0, v1]);
        if version != PROTOCOL_VERSION {
            return Err(FramingError::UnsupportedVersion(version));
        }
        let header = Header {
            version,
            tag: u16::from_le_bytes([t0, t1]),
            length: u64::from_le_bytes([l0, l1, l2, l3, l4, l5, l6, l7]),
        };
        let limit = payload_limit(Tag::from_u16(header.tag), max_frame_bytes);
        if header.length > limit {
            return Err(FramingError::TooLarge { tag: header.tag, length: header.length, limit });
        }
        Ok(header)
    }
}

/// The largest payload a message with `tag` may have.
pub fn payload_limit(tag: Option<Tag>, max_frame_bytes: u64) -> u64 {
    match tag {
        Some(Tag::Frame) => max_frame_bytes,
        _ => MAX_CONTROL_MESSAGE_BYTES as u64,
    }
}

/// A header that cannot be trusted: the stream's framing is lost and the
/// connection must close after the error reply.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FramingError {
    /// The first four bytes are not [`MAGIC`].
    #[error("the message does not start with the magic bytes \"WSEM\" (got {0:02x?})")]
    BadMagic([u8; 4]),
    /// The header's version is not [`PROTOCOL_VERSION`].
    #[error(
        "protocol version {0} is not supported; this daemon speaks version {PROTOCOL_VERSION} \
         (see \"Changes from version 2\" in PROTOCOL.md)"
    )]
    UnsupportedVersion(u16),
    /// The payload length is over the limit for the tag.
    #[error("a message of tag {tag} announces {length} payload bytes, over the limit of {limit}")]
    TooLarge { tag: u16, length: u64, limit: u64 },
}

/// A body that could not be decoded. The payload has been consumed whole,
/// so the framing is intact and the connection may go on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The tag names no message type this version knows.
    #[error("message tag {0} is unknown")]
    UnknownTag(u16),
    /// The body does not decode as the tag's struct, or has bytes left over.
    #[error("the {tag} message could not be decoded: {reason}")]
    Malformed { tag: &'static str, reason: String },
    /// width x height x 12 plus the 40-byte frame header is not the payload length.
    #[error("frame {frame_id} is {width} x {height} points, which needs {expected} payload bytes, but {actual} came")]
    FrameSize { frame_id: u64, trigger_id: u64, width: u32, height: u32, expected: u64, actual: u64 },
    /// The frame's units code is neither 0 (mm) nor 1 (m).
    #[error("frame {frame_id} has units code {units}; expected 0 (millimetres), 1 (metres) or 2 (auto)")]
    UnknownUnits { frame_id: u64, trigger_id: u64, units: u32 },
    /// The frame's cloud frame code is neither 0 (camera) nor 1 (base).
    #[error("frame {frame_id} has cloud frame code {cloud_frame}; expected 0 (camera) or 1 (base)")]
    UnknownCloudFrame { frame_id: u64, trigger_id: u64, cloud_frame: u32 },
}

/// A message could not be encoded (never happens for well-formed values).
#[derive(Debug, thiserror::Error)]
#[error("cannot encode a {tag} message: {reason}")]
pub struct EncodeError {
    pub tag: &'static str,
    pub reason: String,
}

fn encode_struct<T: serde::Serialize>(tag: Tag, value: &T, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    bincode::serde::encode_into_std_write(value, out, wire_config())
        .map(|_| ())
        .map_err(|e| EncodeError { tag: tag.name(), reason: e.to_string() })
}

fn decode_struct<T: serde::de::DeserializeOwned>(tag: Tag, payload: &[u8]) -> Result<T, DecodeError> {
    let (value, used) = bincode::serde::decode_from_slice(payload, wire_config())
        .map_err(|e| DecodeError::Malformed { tag: tag.name(), reason: describe_bincode(&e) })?;
    if used != payload.len() {
        return Err(DecodeError::Malformed {
            tag: tag.name(),
            reason: format!("{} bytes are left over after the message's {used}", payload.len() - used),
        });
    }
    Ok(value)
}

/// A short, stable description of a bincode decoding failure.
fn describe_bincode(e: &bincode::error::DecodeError) -> String {
    use bincode::error::DecodeError as E;
    match e {
        E::UnexpectedEnd { .. } => "the body is shorter than the message needs".into(),
        E::LimitExceeded => "a length inside the body is over the message limit".into(),
        E::UnexpectedVariant { found, .. } => format!("variant number {found} is not defined"),
        E::Utf8 { .. } => "a text field is not valid UTF-8".into(),
        E::InvalidBooleanValue(v) => format!("{v} is not a boolean (0 or 1)"),
        E::InvalidCharEncoding(_) => "a character field is invalid".into(),
        _ => "the body does not match the message layout".into(),
    }
}

/// Appends the frame payload's points as little-endian f32 triples.
pub fn points_to_le(points: &[Point], out: &mut Vec<u8>) {
    out.reserve(points.len() * POINT_BYTES);
    for p in points {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}

/// Appends the points of `bytes` (little-endian f32 triples) to `out`,
/// scaled by `scale`. Trailing bytes short of a point are ignored; callers
/// pass whole points.
pub fn points_from_le(bytes: &[u8], scale: f32, out: &mut Vec<Point>) {
    out.extend(bytes.chunks_exact(POINT_BYTES).map(|c| {
        let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]) * scale;
        [f(0), f(4), f(8)]
    }));
}

/// Decodes the 40 bytes of a frame's meta.
pub fn decode_frame_meta(bytes: &[u8]) -> Result<FrameMeta, DecodeError> {
    decode_struct(Tag::Frame, bytes)
}

/// What a checked frame meta says of the points that follow it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameLayout {
    /// Bytes of points after the meta.
    pub point_bytes: u64,
    pub units: Units,
    pub cloud_frame: CloudFrame,
}

/// Checks a frame's meta against its payload length and its units and
/// cloud frame codes.
pub fn check_frame_meta(meta: &FrameMeta, payload_len: u64) -> Result<FrameLayout, DecodeError> {
    let expected = (meta.width as u64)
        .checked_mul(meta.height as u64)
        .and_then(|n| n.checked_mul(POINT_BYTES as u64))
        .and_then(|n| n.checked_add(FRAME_META_BYTES as u64));
    if expected != Some(payload_len) {
        return Err(DecodeError::FrameSize {
            frame_id: meta.frame_id,
            trigger_id: meta.trigger_id,
            width: meta.width,
            height: meta.height,
            expected: expected.unwrap_or(u64::MAX),
            actual: payload_len,
        });
    }
    let units = Units::from_u32(meta.units).ok_or(DecodeError::UnknownUnits {
        frame_id: meta.frame_id,
        trigger_id: meta.trigger_id,
        units: meta.units,
    })?;
    let cloud_frame = CloudFrame::from_u32(meta.cloud_frame).ok_or(DecodeError::UnknownCloudFrame {
        frame_id: meta.frame_id,
        trigger_id: meta.trigger_id,
        cloud_frame: meta.cloud_frame,
    })?;
    Ok(FrameLayout { point_bytes: payload_len - FRAME_META_BYTES as u64, units, cloud_frame })
}

/// The payload of `msg`, without the header.
pub fn encode_body(msg: &Message) -> Result<Vec<u8>, EncodeError> {
    let tag = msg.tag();
    let mut out = Vec::new();
    match msg {
        Message::Hello(m) => encode_struct(tag, m, &mut out)?,
        Message::HelloAck(m) => encode_struct(tag, m, &mut out)?,
        Message::Error(m) => encode_struct(tag, m, &mut out)?,
        Message::Ping => {}
        Message::Status(m) => encode_struct(tag, m, &mut out)?,
        Message::Frame(f) => {
            encode_struct(tag, &f.meta, &mut out)?;
            points_to_le(&f.points, &mut out);
        }
        Message::Trigger(m) => encode_struct(tag, m, &mut out)?,
        Message::FrameAck(m) => encode_struct(tag, m, &mut out)?,
        Message::PlanRequest(m) => encode_struct(tag, m, &mut out)?,
        Message::PlanReply(m) => encode_struct(tag, m, &mut out)?,
    }
    Ok(out)
}

/// The whole message: header and payload.
pub fn encode(msg: &Message) -> Result<Vec<u8>, EncodeError> {
    let body = encode_body(msg)?;
    let mut out = Vec::with_capacity(HEADER_BYTES + body.len());
    out.extend_from_slice(&Header::new(msg.tag(), body.len() as u64).to_bytes());
    out.extend_from_slice(&body);
    Ok(out)
}

/// The oldest version whose Error message this crate can write: the
/// Error body (code, request id, sentence) is laid out the same in every
/// version so far.
pub const OLDEST_ERROR_VERSION: u16 = 1;

/// An Error refusing a peer that speaks `peer_version`, in a header of
/// that version when it is one whose Error layout this crate knows, so an
/// old peer's own decoder can read why it was refused instead of failing
/// on the header. Other versions get this crate's header.
pub fn encode_version_refusal(peer_version: u16, message: &Message) -> Result<Vec<u8>, EncodeError> {
    let mut bytes = encode(message)?;
    if matches!(message, Message::Error(_)) && (OLDEST_ERROR_VERSION..PROTOCOL_VERSION).contains(&peer_version) {
        bytes[4..6].copy_from_slice(&peer_version.to_le_bytes());
    }
    Ok(bytes)
}

/// Decodes a payload whose header carried `tag`. Frames in metres are
/// converted to millimetres (see [`Units::decode_scale`]).
pub fn decode_body(tag: u16, payload: &[u8]) -> Result<Message, DecodeError> {
    let Some(t) = Tag::from_u16(tag) else {
        return Err(DecodeError::UnknownTag(tag));
    };
    Ok(match t {
        Tag::Hello => Message::Hello(decode_struct::<Hello>(t, payload)?),
        Tag::HelloAck => Message::HelloAck(decode_struct::<HelloAck>(t, payload)?),
        Tag::Error => Message::Error(decode_struct::<ErrorReply>(t, payload)?),
        Tag::Ping if payload.is_empty() => Message::Ping,
        Tag::Ping => {
            return Err(DecodeError::Malformed { tag: t.name(), reason: "a ping has an empty body".into() });
        }
        Tag::Status => Message::Status(decode_struct::<Status>(t, payload)?),
        Tag::Frame => {
            let (meta_bytes, point_bytes) = payload.split_at(payload.len().min(FRAME_META_BYTES));
            let meta = decode_frame_meta(meta_bytes)?;
            let layout = check_frame_meta(&meta, payload.len() as u64)?;
            let mut points = Vec::with_capacity(point_bytes.len() / POINT_BYTES);
            points_from_le(point_bytes, layout.units.decode_scale(), &mut points);
            Message::Frame(Frame { meta, points })
        }
        Tag::Trigger => Message::Trigger(decode_struct::<Trigger>(t, payload)?),
        Tag::FrameAck => Message::FrameAck(decode_struct::<FrameAck>(t, payload)?),
        Tag::PlanRequest => Message::PlanRequest(decode_struct::<PlanRequest>(t, payload)?),
        Tag::PlanReply => Message::PlanReply(decode_struct::<PlanReply>(t, payload)?),
    })
}

/// Decodes one whole message (header and payload) from `bytes`, for tests
/// and tools that hold a complete message in memory.
pub fn decode(bytes: &[u8], max_frame_bytes: u64) -> Result<Message, WireError> {
    let head: &[u8; HEADER_BYTES] =
        bytes.get(..HEADER_BYTES).and_then(|h| h.try_into().ok()).ok_or(WireError::Truncated)?;
    let header = Header::parse(head, max_frame_bytes)?;
    let payload = usize::try_from(header.length)
        .ok()
        .and_then(|n| bytes.get(HEADER_BYTES..HEADER_BYTES.checked_add(n)?))
        .ok_or(WireError::Truncated)?;
    Ok(decode_body(header.tag, payload)?)
}

/// Any failure to decode a message held in memory.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    /// The header is untrustworthy.
    #[error(transparent)]
    Framing(#[from] FramingError),
    /// The body is invalid.
    #[error(transparent)]
    Decode(#[from] DecodeError),
    /// Fewer bytes than the header promises.
    #[error("the message is truncated")]
    Truncated,
}

impl FramingError {
    pub fn code(&self) -> crate::message::ErrorCode {
        use crate::message::ErrorCode;
        match self {
            FramingError::BadMagic(_) => ErrorCode::BadMagic,
            FramingError::UnsupportedVersion(_) => ErrorCode::UnsupportedVersion,
            FramingError::TooLarge { .. } => ErrorCode::TooLarge,
        }
    }
}

impl DecodeError {
    /// The frame and trigger ids of a refused frame whose header was read,
    /// so the camera's acknowledgement can name it.
    pub fn frame_ids(&self) -> Option<(u64, u64)> {
        match *self {
            DecodeError::FrameSize { frame_id, trigger_id, .. }
            | DecodeError::UnknownUnits { frame_id, trigger_id, .. }
            | DecodeError::UnknownCloudFrame { frame_id, trigger_id, .. } => Some((frame_id, trigger_id)),
            DecodeError::UnknownTag(_) | DecodeError::Malformed { .. } => None,
        }
    }

    pub fn code(&self) -> crate::message::ErrorCode {
        use crate::message::ErrorCode;
        match self {
            DecodeError::UnknownTag(_) => ErrorCode::UnknownMessage,
            DecodeError::Malformed { .. } => ErrorCode::Malformed,
            DecodeError::FrameSize { .. } => ErrorCode::FrameSizeMismatch,
            DecodeError::UnknownUnits { .. } => ErrorCode::UnknownUnits,
            DecodeError::UnknownCloudFrame { .. } => ErrorCode::UnknownCloudFrame,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::{ErrorCode, FrameSelect, PoseIn, Roi, Role};

    fn round_trip(msg: Message) {
        let bytes = encode(&msg).unwrap();
        assert_eq!(decode(&bytes, DEFAULT_MAX_FRAME_BYTES).unwrap(), msg);
    }

    #[test]
    fn every_message_round_trips() {
        round_trip(Message::Hello(Hello { protocol_version: 1, role: Role::Camera, name: "cam".into() }));
        round_trip(Message::HelloAck(HelloAck { protocol_version: 1, server: "weldseam".into() }));
        round_trip(Message::error(ErrorCode::Busy, Some(7), "busy"));
        round_trip(Message::Ping);
        round_trip(Message::Status(Status {
            uptime_ms: 5,
            frames_received: 2,
            plans_done: 1,
            queue_length: 0,
            camera_connected: true,
            cameras: 1,
            latest_frame_id: Some(3),
            latest_capture_time_us: Some(1_700_000_000_000_000),
        }));
        let meta =
            FrameMeta { frame_id: 3, trigger_id: 0, capture_time_us: 9, width: 2, height: 1, units: 0, cloud_frame: 1 };
        round_trip(Message::Frame(Frame { meta, points: vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]] }));
        round_trip(Message::Trigger(Trigger { trigger_id: 4 }));
        round_trip(Message::FrameAck(FrameAck {
            frame_id: 3,
            trigger_id: 4,
            code: 0,
            requests: 1,
            message: String::new(),
        }));
        round_trip(Message::PlanRequest(PlanRequest {
            request_id: 1,
            joint: 2,
            groove_depth_mm: None,
            pose: [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            step_mm: Some(2.0),
            work_angle_deg: None,
            travel_angle_deg: None,
            frame: FrameSelect::FrameId(12),
            timeout_ms: 0,
            camera: Some("left".into()),
            hand_eye: Some([1.0, 0.0, 0.0, 10.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
            start_near: Some([1.0, 2.0, 3.0]),
            roi: Some(Roi { min_mm: [-10.0, -20.0, 300.0], max_mm: [10.0, 20.0, 900.0], frame: 1 }),
            pose_in: Some(PoseIn {
                convention: "kuka_abc".into(),
                length_unit: 0,
                angle_unit: 0,
                values: vec![800.0, 0.0, 500.0, 0.0, 0.0, 180.0],
            }),
            one_seam: true,
        }));
    }

    #[test]
    fn frame_meta_has_its_documented_size() {
        let meta =
            FrameMeta { frame_id: 1, trigger_id: 2, capture_time_us: 3, width: 4, height: 5, units: 1, cloud_frame: 0 };
        let mut out = Vec::new();
        encode_struct(Tag::Frame, &meta, &mut out).unwrap();
        assert_eq!(out.len(), FRAME_META_BYTES);
    }

    #[test]
    fn metres_are_converted_to_millimetres() {
        let meta =
            FrameMeta { frame_id: 1, trigger_id: 0, capture_time_us: 0, width: 1, height: 1, units: 1, cloud_frame: 0 };
        let bytes = encode(&Message::Frame(Frame { meta, points: vec![[0.5, 0.25, 1.0]] })).unwrap();
        let Message::Frame(f) = decode(&bytes, DEFAULT_MAX_FRAME_BYTES).unwrap() else { panic!() };
        assert_eq!(f.points, vec![[500.0, 250.0, 1000.0]]);
        // Units to be guessed are the daemon's to judge: kept as sent.
        let meta = FrameMeta { units: Units::Auto as u32, ..meta };
        let bytes = encode(&Message::Frame(Frame { meta, points: vec![[0.5, 0.25, 1.0]] })).unwrap();
        let Message::Frame(f) = decode(&bytes, DEFAULT_MAX_FRAME_BYTES).unwrap() else { panic!() };
        assert_eq!(f.points, vec![[0.5, 0.25, 1.0]]);
    }

    #[test]
    fn bad_headers_and_bodies_are_typed() {
        let mut bytes = encode(&Message::Ping).unwrap();
        bytes[0] = b'X';
        assert!(matches!(decode(&bytes, 100), Err(WireError::Framing(FramingError::BadMagic(_)))));
        let mut bytes = encode(&Message::Ping).unwrap();
        bytes[4] = 9;
        assert!(matches!(decode(&bytes, 100), Err(WireError::Framing(FramingError::UnsupportedVersion(9)))));
        bytes[4] = 1;
        let refusal = decode(&bytes, 100).unwrap_err().to_string();
        let current = format!("version {PROTOCOL_VERSION}");
        assert!(refusal.contains("version 1 is not supported") && refusal.contains(&current), "{refusal}");
        for old in 2..PROTOCOL_VERSION as u8 {
            bytes[4] = old;
            let refusal = decode(&bytes, 100).unwrap_err().to_string();
            assert!(refusal.contains(&format!("version {old} is not supported")) && refusal.contains(&current));
        }
        let big = Header::new(Tag::Frame, 101).to_bytes();
        assert!(matches!(decode(&big, 100), Err(WireError::Framing(FramingError::TooLarge { .. }))));
        let hello = encode(&Message::Hello(Hello { protocol_version: 1, role: Role::Camera, name: "x".into() }));
        let mut hello = hello.unwrap();
        hello.pop();
        hello[8] -= 1;
        assert!(matches!(decode(&hello, 100), Err(WireError::Decode(DecodeError::Malformed { .. }))));
        let unknown = Header { version: PROTOCOL_VERSION, tag: 999, length: 0 }.to_bytes();
        assert_eq!(decode(&unknown, 100), Err(WireError::Decode(DecodeError::UnknownTag(999))));
    }

    #[test]
    fn frame_sizes_are_checked_without_overflow() {
        let meta = FrameMeta {
            frame_id: 1,
            trigger_id: 0,
            capture_time_us: 0,
            width: u32::MAX,
            height: u32::MAX,
            units: 0,
            cloud_frame: 0,
        };
        assert!(matches!(check_frame_meta(&meta, 100), Err(DecodeError::FrameSize { .. })));
        let meta = FrameMeta { width: 2, height: 1, units: 7, ..meta };
        assert!(matches!(check_frame_meta(&meta, 40 + 24), Err(DecodeError::UnknownUnits { .. })));
    }

    #[test]
    fn unknown_units_and_cloud_frames_have_their_own_codes() {
        let meta =
            FrameMeta { frame_id: 4, trigger_id: 2, capture_time_us: 0, width: 2, height: 1, units: 2, cloud_frame: 1 };
        let layout = check_frame_meta(&meta, 40 + 24).unwrap();
        assert_eq!((layout.point_bytes, layout.units, layout.cloud_frame), (24, Units::Auto, CloudFrame::Base));
        let unknown_frame = check_frame_meta(&FrameMeta { cloud_frame: 5, ..meta }, 40 + 24).unwrap_err();
        assert_eq!((unknown_frame.code(), unknown_frame.frame_ids()), (ErrorCode::UnknownCloudFrame, Some((4, 2))));
        assert!(unknown_frame.to_string().contains("cloud frame code 5"), "{unknown_frame}");
        let unknown_units = check_frame_meta(&FrameMeta { units: 3, ..meta }, 40 + 24).unwrap_err();
        assert_eq!(unknown_units.code(), ErrorCode::UnknownUnits);
        assert!(unknown_units.to_string().contains("2 (auto)"), "{unknown_units}");
    }

    #[test]
    fn error_codes_are_stable_and_distinct() {
        let mut seen = std::collections::HashSet::new();
        for c in ErrorCode::ALL {
            assert!(seen.insert(c.code()));
            assert_eq!(ErrorCode::from(c.code()), c);
        }
        assert_eq!(ErrorCode::from(999), ErrorCode::Other(999));
    }

    #[test]
    fn version_refusals_speak_the_old_peers_header_only_when_they_can() {
        let refusal = Message::error(ErrorCode::UnsupportedVersion, None, "speak version 3");
        let version_of = |bytes: &[u8]| u16::from_le_bytes([bytes[4], bytes[5]]);
        let old = encode_version_refusal(1, &refusal).unwrap();
        assert_eq!(version_of(&old), 1);
        assert_eq!(version_of(&encode_version_refusal(2, &refusal).unwrap()), 2);
        assert_eq!(&old[6..], &encode(&refusal).unwrap()[6..], "the same tag, length and body");
        // A version this crate does not know, or a message that is not an
        // Error, keeps this crate's header.
        assert_eq!(version_of(&encode_version_refusal(9, &refusal).unwrap()), PROTOCOL_VERSION);
        assert_eq!(version_of(&encode_version_refusal(1, &Message::Ping).unwrap()), PROTOCOL_VERSION);
    }
}
