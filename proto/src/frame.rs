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
    CloudFrame, DaemonLimits, FRAME_META_BYTES, Frame, FrameAck, FrameMeta, Hello, HelloAck, Message, POINT_BYTES,
    PlanRequest, Point, Role, Status, Tag, Trigger, Units,
};
use crate::rule_ids;
pub use crate::session::PROTOCOL_VERSION;
use crate::session::{CAPABILITIES_SINCE, OLDEST_SERVED_VERSION, Session, capability};

/// The first four bytes of every message.
pub const MAGIC: [u8; 4] = *b"WSEM";

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

    /// A header of `session`'s version.
    pub fn in_session(session: Session, tag: Tag, length: u64) -> Self {
        Header { version: session.version, tag: tag as u16, length }
    }

    /// Parses and checks a header: magic, a version no older than
    /// [`OLDEST_SERVED_VERSION`] (a newer one is for the Hello's
    /// negotiation to answer; after it the connection checks its own) and
    /// the payload limit of its tag (`max_frame_bytes` for frames). An
    /// unknown tag is not a framing error: its payload can be skipped.
    pub fn parse(b: &[u8; HEADER_BYTES], max_frame_bytes: u64) -> Result<Header, FramingError> {
        let [m0, m1, m2, m3, v0, v1, t0, t1, l0, l1, l2, l3, l4, l5, l6, l7] = *b;
        if [m0, m1, m2, m3] != MAGIC {
            return Err(FramingError::BadMagic([m0, m1, m2, m3]));
        }
        let version = u16::from_le_bytes([v0, v1]);
        if version < OLDEST_SERVED_VERSION {
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
    /// The header's version is older than [`OLDEST_SERVED_VERSION`].
    #[error(
        "protocol version {0} is not supported; this daemon speaks version {PROTOCOL_VERSION} and serves peers of \
         version {OLDEST_SERVED_VERSION} and later (see \"Versions and capabilities\" in PROTOCOL.md)"
    )]
    UnsupportedVersion(u16),
    /// After the Hello, a header of another version than the one agreed.
    #[error("a message in a version {got} header, but this connection agreed on version {agreed} in its Hello")]
    VersionChanged { got: u16, agreed: u16 },
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

pub(crate) fn encode_struct<T: serde::Serialize>(tag: Tag, value: &T, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    bincode::serde::encode_into_std_write(value, out, wire_config())
        .map(|_| ())
        .map_err(|e| EncodeError { tag: tag.name(), reason: e.to_string() })
}

pub(crate) fn decode_struct<T: serde::de::DeserializeOwned>(tag: Tag, payload: &[u8]) -> Result<T, DecodeError> {
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

/// Decodes a `T` at the start of `payload`; returns it and the bytes it took.
pub(crate) fn decode_prefix<T: serde::de::DeserializeOwned>(
    tag: Tag,
    payload: &[u8],
) -> Result<(T, usize), DecodeError> {
    bincode::serde::decode_from_slice(payload, wire_config())
        .map_err(|e| DecodeError::Malformed { tag: tag.name(), reason: describe_bincode(&e) })
}

/// Fails when `used` is not the whole payload.
pub(crate) fn whole(tag: Tag, payload: &[u8], used: usize) -> Result<(), DecodeError> {
    if used != payload.len() {
        return Err(DecodeError::Malformed {
            tag: tag.name(),
            reason: format!("{} bytes are left over after the message's {used}", payload.len() - used),
        });
    }
    Ok(())
}

/// A Hello in a header of `version`: version 7's fields, then from
/// version 8 the capabilities. A Hello of a version newer than this
/// crate's may carry fields after those it knows: every version keeps the
/// Hello's fields and appends only, so they are skipped.
fn decode_hello(version: u16, payload: &[u8]) -> Result<Hello, DecodeError> {
    let tag = Tag::Hello;
    let (hello, used) = if version < CAPABILITIES_SINCE {
        let ((protocol_version, role, name), used) = decode_prefix::<(u16, Role, String)>(tag, payload)?;
        (Hello { protocol_version, role, name, capabilities: 0 }, used)
    } else {
        let ((protocol_version, role, name, capabilities), used) =
            decode_prefix::<(u16, Role, String, u64)>(tag, payload)?;
        (Hello { protocol_version, role, name, capabilities }, used)
    };
    if version <= PROTOCOL_VERSION {
        whole(tag, payload, used)?;
    }
    Ok(hello)
}

/// A HelloAck of `version`: version 7's fields, then from version 8 the
/// capabilities granted and what they add, in the order of their bits.
fn decode_hello_ack(version: u16, payload: &[u8]) -> Result<HelloAck, DecodeError> {
    let tag = Tag::HelloAck;
    if version < CAPABILITIES_SINCE {
        let ((protocol_version, server), used) = decode_prefix::<(u16, String)>(tag, payload)?;
        whole(tag, payload, used)?;
        return Ok(HelloAck { protocol_version, server, capabilities: 0, limits: None });
    }
    let ((protocol_version, server, capabilities), mut used) = decode_prefix::<(u16, String, u64)>(tag, payload)?;
    let mut limits = None;
    if capabilities & capability::LIMITS != 0 {
        let (l, n) = decode_prefix::<DaemonLimits>(tag, &payload[used..])?;
        (limits, used) = (Some(l), used + n);
    }
    whole(tag, payload, used)?;
    Ok(HelloAck { protocol_version, server, capabilities, limits })
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

/// The payload of `msg` in this crate's newest version, without the header.
pub fn encode_body(msg: &Message) -> Result<Vec<u8>, EncodeError> {
    encode_body_in(Session::NEWEST, msg)
}

/// The payload of `msg` as a connection of `session` lays it out. Only the
/// Hello and HelloAck differ between versions 7 and 8 (a HelloAck's own
/// `capabilities` say what follows them); the Error and the PlanReply end
/// with the rule ids on a connection granted `rule_ids` ([`rule_ids`]),
/// and the PlanReply then with the figures along its seams and their
/// process on one granted `along_seam` ([`crate::along_seam`]).
pub fn encode_body_in(session: Session, msg: &Message) -> Result<Vec<u8>, EncodeError> {
    let tag = msg.tag();
    let mut out = Vec::new();
    let since_8 = session.version >= CAPABILITIES_SINCE;
    match msg {
        Message::Hello(m) if since_8 => {
            encode_struct(tag, &(m.protocol_version, m.role, &m.name, m.capabilities), &mut out)?
        }
        Message::Hello(m) => encode_struct(tag, &(m.protocol_version, m.role, &m.name), &mut out)?,
        Message::HelloAck(m) if since_8 => {
            encode_struct(tag, &(m.protocol_version, &m.server, m.capabilities), &mut out)?;
            match (m.capabilities & capability::LIMITS != 0, &m.limits) {
                (true, Some(limits)) => encode_struct(tag, limits, &mut out)?,
                (false, None) => {}
                _ => {
                    let reason = "limits are present exactly when the limits capability is granted".into();
                    return Err(EncodeError { tag: tag.name(), reason });
                }
            }
        }
        Message::HelloAck(m) => encode_struct(tag, &(m.protocol_version, &m.server), &mut out)?,
        Message::Error(m) => rule_ids::encode_error(session, m, &mut out)?,
        Message::Ping => {}
        Message::Status(m) => encode_struct(tag, m, &mut out)?,
        Message::Frame(f) => {
            encode_struct(tag, &f.meta, &mut out)?;
            points_to_le(&f.points, &mut out);
        }
        Message::Trigger(m) => encode_struct(tag, m, &mut out)?,
        Message::FrameAck(m) => encode_struct(tag, m, &mut out)?,
        Message::PlanRequest(m) => encode_struct(tag, m, &mut out)?,
        Message::PlanReply(m) => rule_ids::encode_plan_reply(session, m, &mut out)?,
    }
    Ok(out)
}

/// The whole message, header and payload, in this crate's newest version.
pub fn encode(msg: &Message) -> Result<Vec<u8>, EncodeError> {
    encode_in(Session::NEWEST, msg)
}

/// The whole message as a connection of `session` sends it.
pub fn encode_in(session: Session, msg: &Message) -> Result<Vec<u8>, EncodeError> {
    let body = encode_body_in(session, msg)?;
    let mut out = Vec::with_capacity(HEADER_BYTES + body.len());
    out.extend_from_slice(&Header::in_session(session, msg.tag(), body.len() as u64).to_bytes());
    out.extend_from_slice(&body);
    Ok(out)
}

/// The oldest version whose Error message this crate can write: the
/// Error body (code, request id, sentence) is laid out the same in every
/// version so far.
pub const OLDEST_ERROR_VERSION: u16 = 1;

/// An Error refusing a peer whose message came in a header of
/// `peer_version`, before any version was agreed: in a header of that
/// version when it is one whose Error layout this crate knows (every one
/// up to its newest), so the peer's own decoder can read why it was
/// refused instead of failing on the header. A newer version gets this
/// crate's newest header.
pub fn encode_version_refusal(peer_version: u16, message: &Message) -> Result<Vec<u8>, EncodeError> {
    let mut bytes = encode(message)?;
    if matches!(message, Message::Error(_)) && (OLDEST_ERROR_VERSION..=PROTOCOL_VERSION).contains(&peer_version) {
        bytes[4..6].copy_from_slice(&peer_version.to_le_bytes());
    }
    Ok(bytes)
}

/// Decodes a payload of this crate's newest version whose header carried
/// `tag`.
pub fn decode_body(tag: u16, payload: &[u8]) -> Result<Message, DecodeError> {
    decode_body_in(Session::NEWEST, tag, payload)
}

/// Decodes a payload whose header carried `tag`, on a connection of
/// `session` (before the Hello is answered: the header's version, no
/// capabilities). Frames in metres are converted to millimetres (see
/// [`Units::decode_scale`]).
pub fn decode_body_in(session: Session, tag: u16, payload: &[u8]) -> Result<Message, DecodeError> {
    let version = session.version;
    let Some(t) = Tag::from_u16(tag) else {
        return Err(DecodeError::UnknownTag(tag));
    };
    Ok(match t {
        Tag::Hello => Message::Hello(decode_hello(version, payload)?),
        Tag::HelloAck => Message::HelloAck(decode_hello_ack(version, payload)?),
        Tag::Error => Message::Error(rule_ids::decode_error(session, payload)?),
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
        Tag::PlanReply => Message::PlanReply(rule_ids::decode_plan_reply(session, payload)?),
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
    Ok(decode_body_in(Session::of(header.version), header.tag, payload)?)
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
            FramingError::UnsupportedVersion(_) | FramingError::VersionChanged { .. } => ErrorCode::UnsupportedVersion,
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
    use crate::session::capability;

    fn round_trip(msg: Message) {
        let bytes = encode(&msg).unwrap();
        assert_eq!(decode(&bytes, DEFAULT_MAX_FRAME_BYTES).unwrap(), msg);
    }

    #[test]
    fn every_message_round_trips() {
        round_trip(Message::Hello(Hello::new(Role::Camera, "cam", capability::LIMITS)));
        round_trip(Message::HelloAck(HelloAck {
            protocol_version: PROTOCOL_VERSION,
            server: "weldseam".into(),
            capabilities: 0,
            limits: None,
        }));
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
    fn a_version_7_hello_and_ack_have_no_capabilities_and_a_newer_hello_is_read_by_its_prefix() {
        let v7 = Session::V7;
        let hello =
            Message::Hello(Hello { protocol_version: 7, role: Role::Controller, name: "plc".into(), capabilities: 0 });
        let bytes = encode_in(v7, &hello).unwrap();
        // Header, then 2 + 4 + 8 + 3 bytes: version 7's layout exactly.
        assert_eq!(bytes.len(), HEADER_BYTES + 17);
        assert_eq!(decode(&bytes, 100), Ok(hello.clone()));
        let ack =
            Message::HelloAck(HelloAck { protocol_version: 7, server: "w".into(), capabilities: 0, limits: None });
        let bytes = encode_in(v7, &ack).unwrap();
        assert_eq!(bytes.len(), HEADER_BYTES + 11);
        assert_eq!(decode(&bytes, 100), Ok(ack));
        // Version 8 appends the capabilities; a version 7 Hello with them is malformed.
        let asked = Message::Hello(Hello::new(Role::Camera, "cam", capability::LIMITS));
        let mut v8 = encode(&asked).unwrap();
        assert_eq!(v8.len(), HEADER_BYTES + 2 + 4 + 8 + 3 + 8);
        v8[4] = 7;
        assert!(matches!(decode(&v8, 100), Err(WireError::Decode(DecodeError::Malformed { .. }))));
        // A version 9 Hello with a field after those of version 8: read,
        // the field skipped.
        v8[4] = 9;
        v8[16] = 9;
        v8.extend_from_slice(&[1, 2, 3]);
        v8[8] += 3;
        let Ok(Message::Hello(h)) = decode(&v8, 100) else { panic!("a newer Hello is read") };
        assert_eq!((h.protocol_version, h.capabilities, h.name.as_str()), (9, capability::LIMITS, "cam"));
    }

    #[test]
    fn limits_follow_a_hello_ack_exactly_when_granted() {
        let limits = DaemonLimits {
            max_frame_bytes: 1 << 27,
            max_message_bytes: 1 << 22,
            plan_queue_depth: 4,
            max_requests_per_connection: 2,
            fresh_frame_timeout_ms: 5000,
            max_request_timeout_ms: 30000,
            capture_time_tolerance_ms: 200,
            frame_history: 8,
            frame_history_bytes: 1 << 27,
            stall_timeout_ms: 5000,
        };
        let granted = HelloAck {
            protocol_version: PROTOCOL_VERSION,
            server: "w".into(),
            capabilities: capability::LIMITS,
            limits: Some(limits),
        };
        round_trip(Message::HelloAck(granted.clone()));
        let inconsistent = HelloAck { limits: None, ..granted.clone() };
        assert!(encode(&Message::HelloAck(inconsistent)).is_err());
        let unasked = HelloAck { capabilities: 0, ..granted };
        assert!(encode(&Message::HelloAck(unasked)).is_err());
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
        bytes[4] = 6;
        assert!(matches!(decode(&bytes, 100), Err(WireError::Framing(FramingError::UnsupportedVersion(6)))));
        // A newer version's header is for the negotiation to answer.
        bytes[4] = 9;
        assert_eq!(decode(&bytes, 100), Ok(Message::Ping));
        bytes[4] = 1;
        let refusal = decode(&bytes, 100).unwrap_err().to_string();
        let current = format!("version {PROTOCOL_VERSION}");
        assert!(refusal.contains("version 1 is not supported") && refusal.contains(&current), "{refusal}");
        for old in 2..OLDEST_SERVED_VERSION as u8 {
            bytes[4] = old;
            let refusal = decode(&bytes, 100).unwrap_err().to_string();
            assert!(refusal.contains(&format!("version {old} is not supported")) && refusal.contains(&current));
        }
        let big = Header::new(Tag::Frame, 101).to_bytes();
        assert!(matches!(decode(&big, 100), Err(WireError::Framing(FramingError::TooLarge { .. }))));
        let hello = encode(&Message::Hello(Hello::new(Role::Camera, "x", 0)));
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
        assert_eq!(version_of(&encode_version_refusal(7, &refusal).unwrap()), 7);
        // A version this crate does not know, or a message that is not an
        // Error, keeps this crate's header.
        assert_eq!(version_of(&encode_version_refusal(PROTOCOL_VERSION + 1, &refusal).unwrap()), PROTOCOL_VERSION);
        assert_eq!(version_of(&encode_version_refusal(1, &Message::Ping).unwrap()), PROTOCOL_VERSION);
    }
}
