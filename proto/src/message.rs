//! The messages of the camera and controller links, their numeric tags and
//! the error codes. Field order in each struct is the order on the wire
//! (see PROTOCOL.md); a field is added only with a new protocol version or
//! behind a capability (see [`crate::session`] and PROTOCOL.md's policy).

use serde::{Deserialize, Serialize};

use crate::plan::{Joint, PlanResult};

/// A point of a frame: camera frame, x, y, z. NaN (or `0, 0, 0`) marks a
/// pixel without a return.
pub type Point = [f32; 3];

/// The numeric tag in every message header, naming the message type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u16)]
pub enum Tag {
    Hello = 1,
    HelloAck = 2,
    Error = 3,
    Ping = 4,
    Status = 5,
    Frame = 16,
    Trigger = 17,
    FrameAck = 18,
    PlanRequest = 32,
    PlanReply = 33,
}

impl Tag {
    pub const ALL: [Tag; 10] = [
        Tag::Hello,
        Tag::HelloAck,
        Tag::Error,
        Tag::Ping,
        Tag::Status,
        Tag::Frame,
        Tag::Trigger,
        Tag::FrameAck,
        Tag::PlanRequest,
        Tag::PlanReply,
    ];

    /// The tag for a header's number, if it is one this version knows.
    pub fn from_u16(n: u16) -> Option<Tag> {
        Tag::ALL.into_iter().find(|t| *t as u16 == n)
    }

    pub fn name(self) -> &'static str {
        match self {
            Tag::Hello => "Hello",
            Tag::HelloAck => "HelloAck",
            Tag::Error => "Error",
            Tag::Ping => "Ping",
            Tag::Status => "Status",
            Tag::Frame => "Frame",
            Tag::Trigger => "Trigger",
            Tag::FrameAck => "FrameAck",
            Tag::PlanRequest => "PlanRequest",
            Tag::PlanReply => "PlanReply",
        }
    }
}

/// Which link a peer means to be.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Role {
    /// Wire value 0: a camera or a bridge in front of one; pushes frames.
    Camera,
    /// Wire value 1: a robot controller; asks for trajectories.
    Controller,
}

impl Role {
    pub fn name(self) -> &'static str {
        match self {
            Role::Camera => "camera",
            Role::Controller => "controller",
        }
    }
}

/// The first message on every connection, from the connecting peer. Its
/// layout depends on its header's version (see [`crate::session`]):
/// version 7 ends after `name`; version 8 adds `capabilities`.
#[derive(Debug, Clone, PartialEq)]
pub struct Hello {
    /// The newest version the peer speaks; the header carries the same.
    pub protocol_version: u16,
    pub role: Role,
    /// The peer's name. A camera's name is how a plan request names it
    /// (see [`PlanRequest::camera`]); a controller's is for logs.
    pub name: String,
    /// The [`crate::session::capability`] bits the peer asks for (version
    /// 8 on; 0 in a version 7 Hello, which has no such field).
    pub capabilities: u64,
}

impl Hello {
    /// A Hello of this crate's newest version, asking for `capabilities`.
    pub fn new(role: Role, name: impl Into<String>, capabilities: u64) -> Hello {
        Hello { protocol_version: crate::session::PROTOCOL_VERSION, role, name: name.into(), capabilities }
    }
}

/// The daemon's answer to an accepted [`Hello`]: the version the
/// connection speaks from now on and the capabilities granted.
#[derive(Debug, Clone, PartialEq)]
pub struct HelloAck {
    /// The version both speak: the lower of the peer's and the daemon's.
    pub protocol_version: u16,
    /// The daemon's name and version, for logs.
    pub server: String,
    /// The capabilities granted: those asked that the daemon has (version
    /// 8 on; 0 for version 7, whose HelloAck ends after `server`).
    pub capabilities: u64,
    /// Present exactly when [`crate::session::capability::LIMITS`] is
    /// granted.
    pub limits: Option<DaemonLimits>,
}

/// The daemon's limits a client must keep to, as configured (capability
/// `limits`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct DaemonLimits {
    /// The largest Frame payload on the camera link (`server.max_frame_bytes`).
    pub max_frame_bytes: u64,
    /// The largest payload of any other message ([`crate::MAX_CONTROL_MESSAGE_BYTES`]).
    pub max_message_bytes: u64,
    /// Requests waiting or planning in all (`server.plan_queue_depth`).
    pub plan_queue_depth: u32,
    /// Of those, per controller connection (`server.max_requests_per_connection`).
    pub max_requests_per_connection: u32,
    /// The frame wait of a request whose `timeout_ms` is 0 (`server.fresh_frame_timeout_ms`).
    pub fresh_frame_timeout_ms: u64,
    /// The longest `timeout_ms` accepted (`server.max_request_timeout_ms`).
    pub max_request_timeout_ms: u64,
    /// The camera clock's allowed difference (`server.capture_time_tolerance_ms`).
    pub capture_time_tolerance_ms: u64,
    /// Frames held for requests naming an id, at most (`server.frame_history`).
    pub frame_history: u32,
    /// Bytes of points those frames may hold (`server.frame_history_bytes`).
    pub frame_history_bytes: u64,
    /// Silence allowed in the middle of a message (`server.stall_timeout_ms`).
    pub stall_timeout_ms: u64,
}

/// The unit of a frame's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum Units {
    Millimetres = 0,
    Metres = 1,
    /// The daemon guesses millimetres or metres from the frame's distances,
    /// as `weldseam plan --units auto` does.
    Auto = 2,
}

impl Units {
    pub fn from_u32(n: u32) -> Option<Units> {
        match n {
            0 => Some(Units::Millimetres),
            1 => Some(Units::Metres),
            2 => Some(Units::Auto),
            _ => None,
        }
    }

    /// The factor applied to every coordinate as the frame is decoded:
    /// metres become millimetres at once; a frame whose units are to be
    /// guessed keeps its values for the planner to judge.
    pub fn decode_scale(self) -> f32 {
        match self {
            Units::Millimetres | Units::Auto => 1.0,
            Units::Metres => 1000.0,
        }
    }
}

/// The frame a Frame's coordinates are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum CloudFrame {
    /// The camera's optical frame, as cameras deliver frames.
    Camera = 0,
    /// The robot base frame: the plan request's pose and hand-eye bring
    /// the points into the camera frame before planning.
    Base = 1,
}

impl CloudFrame {
    pub fn from_u32(n: u32) -> Option<CloudFrame> {
        match n {
            0 => Some(CloudFrame::Camera),
            1 => Some(CloudFrame::Base),
            _ => None,
        }
    }
}

/// The fixed-size part of a frame message, before the points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameMeta {
    /// The camera's id of this frame; a controller may name it in a request.
    pub frame_id: u64,
    /// The id of the [`Trigger`] this frame answers, or 0 for a free-running
    /// frame (trigger ids start at 1).
    pub trigger_id: u64,
    /// Capture time, microseconds since the Unix epoch (camera clock).
    pub capture_time_us: u64,
    pub width: u32,
    pub height: u32,
    /// A [`Units`] value; kept numeric so an unknown one gets its own
    /// error code rather than a decoding failure.
    pub units: u32,
    /// A [`CloudFrame`] value, numeric for the same reason.
    pub cloud_frame: u32,
}

/// Bytes of an encoded [`FrameMeta`].
pub const FRAME_META_BYTES: usize = 40;

/// Bytes of one point on the wire: three little-endian f32.
pub const POINT_BYTES: usize = 12;

/// A frame of `width x height` points, row-major: an organized grid when
/// `height > 1`, an unorganized list of `width` points when `height == 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub meta: FrameMeta,
    pub points: Vec<Point>,
}

/// The daemon asks the camera for a capture; the answering frame carries
/// this id in [`FrameMeta::trigger_id`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Trigger {
    pub trigger_id: u64,
}

/// The daemon's answer to every frame whose header it could read: held
/// (code 0) or refused with an error code, and how many waiting requests
/// it was handed to.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameAck {
    pub frame_id: u64,
    pub trigger_id: u64,
    /// 0 when the frame is held; else the [`ErrorCode`] that refused it.
    pub code: u16,
    /// Waiting plan requests this frame was handed to (0 when refused, or
    /// when it qualified for none; it stays held for requests naming it).
    pub requests: u32,
    /// Why it was refused, or why it qualified for no waiting request;
    /// empty otherwise.
    pub message: String,
}

impl FrameAck {
    /// The refusal's code, or None when the frame is held.
    pub fn refusal(&self) -> Option<ErrorCode> {
        (self.code != 0).then(|| ErrorCode::from(self.code))
    }
}

/// Which frame a plan request is computed from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum FrameSelect {
    /// Wire value 0: trigger a fresh capture and use the frame answering it.
    #[default]
    Trigger,
    /// Wire value 1: the first frame that arrives after the request.
    NextFrame,
    /// Wire value 2 then a u64: this frame, if the daemon still holds it.
    FrameId(u64),
}

/// Wire numbers of the joint types in a [`PlanRequest`].
pub mod joint_code {
    pub const V_BUTT: u32 = 0;
    pub const I_BUTT: u32 = 1;
    pub const LAP: u32 = 2;
    /// The daemon decides the type from the frame (version 5); the reply's
    /// seam names the type found and the evidence.
    pub const AUTO: u32 = 3;
    /// A tee joint's fillet welds (named in version 6, planned from
    /// version 7): each root the camera sees is a seam.
    pub const T_FILLET: u32 = 4;
    /// A set of types the daemon decides among, as with [`AUTO`]: `SET`
    /// plus, for each type in it, one shifted left by the type's code
    /// (`SET | 1 << V_BUTT | 1 << LAP` is `0x105`, V-butt or lap). A
    /// workpiece of a type outside the set is refused with 67
    /// `joint_mismatch`. Added within version 7; an older daemon answers 41
    /// `unknown_joint`.
    pub const SET: u32 = 0x100;
}

/// A controller's request for a trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanRequest {
    /// Echoed in the reply or error.
    pub request_id: u64,
    /// A [`joint_code`] value; kept numeric so an unknown joint gets its
    /// own error rather than a decoding failure.
    pub joint: u32,
    /// Groove depth of a V-butt joint, mm. When absent the daemon measures
    /// it where the groove's root is seen, else refuses; when given, it is
    /// checked against the measurement (error 68 beyond
    /// `quality.max_groove_depth_difference_mm`).
    pub groove_depth_mm: Option<f64>,
    /// Flange pose at capture: x, y, z in mm, rx, ry, rz in degrees, in the
    /// daemon's configured Euler convention; ignored when `pose_in` is given.
    pub pose: [f64; 6],
    /// Waypoint spacing, mm; the configured one when absent.
    pub step_mm: Option<f64>,
    pub work_angle_deg: Option<f64>,
    pub travel_angle_deg: Option<f64>,
    pub frame: FrameSelect,
    /// How long to wait for a fresh frame, ms; 0 = the daemon's default.
    /// Over the daemon's `server.max_request_timeout_ms` is refused.
    pub timeout_ms: u32,
    /// The camera (its Hello name) to trigger or take the frame from; any
    /// connected camera when absent.
    pub camera: Option<String>,
    /// `End_T_Camera` for this request, row-major 4x4 (mm), instead of the
    /// daemon's `robot.hand_eye`.
    pub hand_eye: Option<[f64; 16]>,
    /// The waypoints start at the seam's end nearest this point (robot
    /// base frame, mm); else at the documented default end.
    pub start_near: Option<[f64; 3]>,
    /// Only the frame's points inside this box are planned; the daemon's
    /// `pipeline.roi` when absent.
    pub roi: Option<Roi>,
    /// The flange pose at capture in a convention the request names (a
    /// controller's own), instead of `pose`.
    pub pose_in: Option<PoseIn>,
    /// Reply with one seam only (version 7): the one nearest `start_near`
    /// (the first of the documented order without it). The frame's other
    /// workpieces are planned and their seams dropped.
    pub one_seam: bool,
}

/// A pose written in a named convention and units: the robot's own
/// numbers, which the daemon converts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseIn {
    /// How the rotation is written: `extrinsic_` or `intrinsic_` and the
    /// three axes in some order (`intrinsic_zyx`), `kuka_abc`, `fanuc_wpr`,
    /// `rotation_vector`, `quaternion_wxyz`, `quaternion_xyzw`, or the
    /// config's `zyx` and `xyz`.
    pub convention: String,
    /// A [`LengthUnit`] value: 0 millimetres, 1 metres.
    pub length_unit: u32,
    /// An [`AngleUnit`] value: 0 degrees, 1 radians; ignored by quaternions.
    pub angle_unit: u32,
    /// x, y, z, then the rotation's 3 numbers (4 for a quaternion).
    pub values: Vec<f64>,
}

/// Wire values of [`PoseIn::length_unit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    Millimetres = 0,
    Metres = 1,
}

impl LengthUnit {
    pub fn from_u32(v: u32) -> Option<Self> {
        match v {
            0 => Some(LengthUnit::Millimetres),
            1 => Some(LengthUnit::Metres),
            _ => None,
        }
    }
}

/// Wire values of [`PoseIn::angle_unit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AngleUnit {
    Degrees = 0,
    Radians = 1,
}

impl AngleUnit {
    pub fn from_u32(v: u32) -> Option<Self> {
        match v {
            0 => Some(AngleUnit::Degrees),
            1 => Some(AngleUnit::Radians),
            _ => None,
        }
    }
}

/// A region of interest: an axis-aligned box in the camera or the robot
/// base frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Roi {
    /// The box's least x, y, z, mm.
    pub min_mm: [f64; 3],
    /// The box's greatest x, y, z, mm.
    pub max_mm: [f64; 3],
    /// A [`CloudFrame`] value: the frame the box is given in; numeric so an
    /// unknown one is refused by name rather than as a decoding failure.
    pub frame: u32,
}

impl PlanRequest {
    /// The joint type, if [`PlanRequest::joint`] is a known type's code
    /// (not [`joint_code::AUTO`]).
    pub fn joint_type(&self) -> Option<Joint> {
        match self.joint {
            joint_code::V_BUTT => Some(Joint::VButt),
            joint_code::I_BUTT => Some(Joint::IButt),
            joint_code::LAP => Some(Joint::Lap),
            joint_code::T_FILLET => Some(Joint::TFillet),
            _ => None,
        }
    }

    /// Whether the request leaves the joint type to the daemon.
    pub fn is_auto_joint(&self) -> bool {
        self.joint == joint_code::AUTO
    }

    /// The types of a [`joint_code::SET`] value, or None when
    /// [`PlanRequest::joint`] is not one (or names an unknown type, or
    /// none).
    pub fn joint_set(&self) -> Option<Vec<Joint>> {
        let bits = self.joint.checked_sub(joint_code::SET).filter(|b| *b < joint_code::SET && *b != 0)?;
        let known = [Joint::VButt, Joint::IButt, Joint::Lap, Joint::TFillet];
        let mask: u32 = known.iter().map(|&j| 1 << PlanRequest::joint_code(j)).sum();
        (bits & !mask == 0)
            .then(|| known.into_iter().filter(|&j| bits & 1 << PlanRequest::joint_code(j) != 0).collect())
    }

    /// The [`joint_code::SET`] value of `joints`.
    pub fn joint_set_code(joints: &[Joint]) -> u32 {
        joints.iter().fold(joint_code::SET, |code, &j| code | 1 << PlanRequest::joint_code(j))
    }

    pub fn joint_code(joint: Joint) -> u32 {
        match joint {
            Joint::VButt => joint_code::V_BUTT,
            Joint::IButt => joint_code::I_BUTT,
            Joint::Lap => joint_code::LAP,
            Joint::TFillet => joint_code::T_FILLET,
        }
    }
}

/// A planned trajectory, answering the request with the same id.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanReply {
    pub request_id: u64,
    /// The frame the plan was computed from.
    pub frame_id: u64,
    pub result: PlanResult,
}

/// The daemon's state, answering a ping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Status {
    pub uptime_ms: u64,
    pub frames_received: u64,
    pub plans_done: u64,
    /// Plan jobs waiting or running.
    pub queue_length: u32,
    pub camera_connected: bool,
    /// Cameras connected now.
    pub cameras: u32,
    /// The id of the newest frame held, and its capture time (camera
    /// clock, microseconds since the Unix epoch).
    pub latest_frame_id: Option<u64>,
    pub latest_capture_time_us: Option<u64>,
}

/// What went wrong, as a stable number a PLC program can switch on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(from = "u16", into = "u16")]
pub enum ErrorCode {
    /// 1: the header does not start with the magic bytes; the connection closes.
    BadMagic,
    /// 2: the Hello's version is older than the oldest served, or a
    /// message after it leaves the version agreed; the connection closes.
    UnsupportedVersion,
    /// 3: the header's tag names no message type.
    UnknownMessage,
    /// 4: the message body could not be decoded (truncated, trailing or
    /// invalid bytes).
    Malformed,
    /// 5: the payload length exceeds the limit; the connection closes.
    TooLarge,
    /// 6: the message is not allowed here: not a hello first, a hello with
    /// the wrong role, or a message of the other link.
    UnexpectedMessage,
    /// 20: width x height does not match the frame's point payload.
    FrameSizeMismatch,
    /// 21: the frame has no valid point.
    EmptyFrame,
    /// 22: the frame's units code is unknown.
    UnknownUnits,
    /// 23: the frame's capture time is ahead of the daemon's clock by
    /// more than the tolerance; a camera clock that cannot be trusted.
    BadCaptureTime,
    /// 24: the frame's cloud frame code is unknown.
    UnknownCloudFrame,
    /// 40: a request field is out of range (NaN pose, a groove deeper than 100 mm...).
    BadRequest,
    /// 41: the joint code is unknown.
    UnknownJoint,
    /// 42: the named frame id is not (or no longer) held by the daemon.
    UnknownFrame,
    /// 43: no camera is connected, so no fresh frame can be had.
    NoCamera,
    /// 44: no fresh frame arrived within the request's timeout.
    FrameTimeout,
    /// 45: the plan queue is full; retry later.
    Busy,
    /// 46: the pipeline found no seam in the frame.
    PlanFailed,
    /// 47: the daemon is shutting down.
    ShuttingDown,
    /// 48: an internal fault; the daemon's log has the cause.
    Internal,
    /// 49: the frame answering the request's trigger was not captured
    /// within the fresh window (before the request, or clock skew).
    StaleFrame,
    /// 50: the plan ran longer than the daemon's `server.plan_timeout_ms`
    /// and was stopped; the next plan started.
    PlanTimeout,
    /// 60: a seam was found but refused: a weld edge's fit residual is
    /// above `quality.max_edge_fit_rms_spacings`.
    EdgeFitResidual,
    /// 61: refused: a weld edge was seen along too little of the seam.
    EdgeCoverage,
    /// 62: refused: the seam spans too little of the joint the camera saw.
    JointCoverage,
    /// 63: refused: the butt plates' high-low misalignment is above its limit.
    Misalignment,
    /// 64: refused: the I-butt gap is wider than `quality.max_gap_mm`.
    GapWidth,
    /// 65: refused: the plates' planes are not parallel.
    PlateAngle,
    /// 66: refused: the seam's position is too uncertain.
    PositionUncertainty,
    /// 67: refused: the plates seen are not those of the joint requested.
    JointMismatch,
    /// 68: refused: the groove depth given differs from the one measured.
    GrooveDepth,
    /// 69: refused: `auto` was asked for and the joint type cannot be told.
    JointUnknown,
    /// 70: refused: the plates are a corner joint's that the request does
    /// not plan (an outside corner, or an inside one asked as a butt or lap).
    CornerJoint,
    /// 71: refused: a weld edge's boundary samples lie beyond its fitted
    /// line, towards the other plate, in a larger share than
    /// `quality.max_edge_samples_beyond`, or on two lines further apart
    /// than `quality.max_edge_step_spacings`: the edge was cut short along
    /// part of it, and which line is the plate's edge is not clear.
    EdgeCutShort,
    /// 72: refused: the I-butt gap, at its widest, is narrower than
    /// `quality.min_gap_spacings` point spacings: narrower than the cloud
    /// resolves.
    GapUnresolved,
    /// Any other number, from a newer peer.
    Other(u16),
}

impl ErrorCode {
    pub const ALL: [ErrorCode; 35] = [
        ErrorCode::BadMagic,
        ErrorCode::UnsupportedVersion,
        ErrorCode::UnknownMessage,
        ErrorCode::Malformed,
        ErrorCode::TooLarge,
        ErrorCode::UnexpectedMessage,
        ErrorCode::FrameSizeMismatch,
        ErrorCode::EmptyFrame,
        ErrorCode::UnknownUnits,
        ErrorCode::BadCaptureTime,
        ErrorCode::UnknownCloudFrame,
        ErrorCode::BadRequest,
        ErrorCode::UnknownJoint,
        ErrorCode::UnknownFrame,
        ErrorCode::NoCamera,
        ErrorCode::FrameTimeout,
        ErrorCode::Busy,
        ErrorCode::PlanFailed,
        ErrorCode::ShuttingDown,
        ErrorCode::Internal,
        ErrorCode::StaleFrame,
        ErrorCode::PlanTimeout,
        ErrorCode::EdgeFitResidual,
        ErrorCode::EdgeCoverage,
        ErrorCode::JointCoverage,
        ErrorCode::Misalignment,
        ErrorCode::GapWidth,
        ErrorCode::PlateAngle,
        ErrorCode::PositionUncertainty,
        ErrorCode::JointMismatch,
        ErrorCode::GrooveDepth,
        ErrorCode::JointUnknown,
        ErrorCode::CornerJoint,
        ErrorCode::EdgeCutShort,
        ErrorCode::GapUnresolved,
    ];

    pub fn code(self) -> u16 {
        match self {
            ErrorCode::BadMagic => 1,
            ErrorCode::UnsupportedVersion => 2,
            ErrorCode::UnknownMessage => 3,
            ErrorCode::Malformed => 4,
            ErrorCode::TooLarge => 5,
            ErrorCode::UnexpectedMessage => 6,
            ErrorCode::FrameSizeMismatch => 20,
            ErrorCode::EmptyFrame => 21,
            ErrorCode::UnknownUnits => 22,
            ErrorCode::BadCaptureTime => 23,
            ErrorCode::UnknownCloudFrame => 24,
            ErrorCode::BadRequest => 40,
            ErrorCode::UnknownJoint => 41,
            ErrorCode::UnknownFrame => 42,
            ErrorCode::NoCamera => 43,
            ErrorCode::FrameTimeout => 44,
            ErrorCode::Busy => 45,
            ErrorCode::PlanFailed => 46,
            ErrorCode::ShuttingDown => 47,
            ErrorCode::Internal => 48,
            ErrorCode::StaleFrame => 49,
            ErrorCode::PlanTimeout => 50,
            ErrorCode::EdgeFitResidual => 60,
            ErrorCode::EdgeCoverage => 61,
            ErrorCode::JointCoverage => 62,
            ErrorCode::Misalignment => 63,
            ErrorCode::GapWidth => 64,
            ErrorCode::PlateAngle => 65,
            ErrorCode::PositionUncertainty => 66,
            ErrorCode::JointMismatch => 67,
            ErrorCode::GrooveDepth => 68,
            ErrorCode::JointUnknown => 69,
            ErrorCode::CornerJoint => 70,
            ErrorCode::EdgeCutShort => 71,
            ErrorCode::GapUnresolved => 72,
            ErrorCode::Other(n) => n,
        }
    }

    /// A snake_case name for logs and JSON.
    pub fn name(self) -> &'static str {
        match self {
            ErrorCode::BadMagic => "bad_magic",
            ErrorCode::UnsupportedVersion => "unsupported_version",
            ErrorCode::UnknownMessage => "unknown_message",
            ErrorCode::Malformed => "malformed",
            ErrorCode::TooLarge => "too_large",
            ErrorCode::UnexpectedMessage => "unexpected_message",
            ErrorCode::FrameSizeMismatch => "frame_size_mismatch",
            ErrorCode::EmptyFrame => "empty_frame",
            ErrorCode::UnknownUnits => "unknown_units",
            ErrorCode::BadCaptureTime => "bad_capture_time",
            ErrorCode::UnknownCloudFrame => "unknown_cloud_frame",
            ErrorCode::BadRequest => "bad_request",
            ErrorCode::UnknownJoint => "unknown_joint",
            ErrorCode::UnknownFrame => "unknown_frame",
            ErrorCode::NoCamera => "no_camera",
            ErrorCode::FrameTimeout => "frame_timeout",
            ErrorCode::Busy => "busy",
            ErrorCode::PlanFailed => "plan_failed",
            ErrorCode::ShuttingDown => "shutting_down",
            ErrorCode::Internal => "internal",
            ErrorCode::StaleFrame => "stale_frame",
            ErrorCode::PlanTimeout => "plan_timeout",
            ErrorCode::EdgeFitResidual => "edge_fit_residual",
            ErrorCode::EdgeCoverage => "edge_coverage",
            ErrorCode::JointCoverage => "joint_coverage",
            ErrorCode::Misalignment => "misalignment",
            ErrorCode::GapWidth => "gap_width",
            ErrorCode::PlateAngle => "plate_angle",
            ErrorCode::PositionUncertainty => "position_uncertainty",
            ErrorCode::JointMismatch => "joint_mismatch",
            ErrorCode::GrooveDepth => "groove_depth",
            ErrorCode::JointUnknown => "joint_unknown",
            ErrorCode::CornerJoint => "corner_joint",
            ErrorCode::EdgeCutShort => "edge_cut_short",
            ErrorCode::GapUnresolved => "gap_unresolved",
            ErrorCode::Other(_) => "other",
        }
    }
}

impl From<u16> for ErrorCode {
    fn from(n: u16) -> Self {
        ErrorCode::ALL.into_iter().find(|c| c.code() == n).unwrap_or(ErrorCode::Other(n))
    }
}

impl From<ErrorCode> for u16 {
    fn from(c: ErrorCode) -> u16 {
        c.code()
    }
}

impl std::fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", self.code(), self.name())
    }
}

/// A typed error reply. Its binary layout is `code`, `request_id` and
/// `message`, then `rule` on a connection granted `rule_ids` only.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorReply {
    pub code: ErrorCode,
    /// The request this error answers, when it answers one.
    pub request_id: Option<u64>,
    /// One sentence a person understands.
    pub message: String,
    /// The planner's rule that refused the request (`family.decision`),
    /// when a rule did: sent only to a peer granted `rule_ids`.
    pub rule: Option<String>,
}

/// Every message of the protocol.
// A PlanRequest (with its hand-eye and region of interest) is a few hundred
// bytes larger than the smallest messages; a message lives only from its
// decoding to its handling, one per connection at a time, so boxing it
// would cost an allocation per message to save nothing that matters.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    Hello(Hello),
    HelloAck(HelloAck),
    Error(ErrorReply),
    /// Empty body.
    Ping,
    Status(Status),
    Frame(Frame),
    Trigger(Trigger),
    FrameAck(FrameAck),
    PlanRequest(PlanRequest),
    PlanReply(PlanReply),
}

impl Message {
    pub fn tag(&self) -> Tag {
        match self {
            Message::Hello(_) => Tag::Hello,
            Message::HelloAck(_) => Tag::HelloAck,
            Message::Error(_) => Tag::Error,
            Message::Ping => Tag::Ping,
            Message::Status(_) => Tag::Status,
            Message::Frame(_) => Tag::Frame,
            Message::Trigger(_) => Tag::Trigger,
            Message::FrameAck(_) => Tag::FrameAck,
            Message::PlanRequest(_) => Tag::PlanRequest,
            Message::PlanReply(_) => Tag::PlanReply,
        }
    }

    /// A typed error reply.
    pub fn error(code: ErrorCode, request_id: Option<u64>, message: impl Into<String>) -> Message {
        Message::Error(ErrorReply { code, request_id, message: message.into(), rule: None })
    }

    /// A typed error reply refusing a request by the planner's `rule`.
    pub fn refusal(code: ErrorCode, request_id: Option<u64>, message: impl Into<String>, rule: &str) -> Message {
        Message::Error(ErrorReply { code, request_id, message: message.into(), rule: Some(rule.into()) })
    }
}
