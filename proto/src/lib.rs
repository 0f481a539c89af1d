//! The weldseam wire protocol and report schema: the only serializable
//! types of the workspace. Domain types live in the `weldseam` library and
//! are converted to and from these at the boundary.
//!
//! - [`plan`]: a planned trajectory as the controller receives it and as
//!   `weldseam plan --json` prints it.
//! - [`message`]: the messages of the camera and controller links, their
//!   tags and error codes.
//! - [`frame`]: the message header, the bincode configuration and the
//!   encoding of bodies; see PROTOCOL.md for every byte.
//! - [`session`]: version and capability negotiation, the versions served.
//! - [`rule_ids`]: the fields the `rule_ids` capability appends to the
//!   Error and the PlanReply.
//! - [`along_seam`]: the joint's figures at each waypoint and the weld
//!   process, which the `along_seam` capability appends to the PlanReply
//!   and `weldseam plan --json` prints beside each seam.
//! - [`text`]: the text controller link's lines, which robot programs
//!   read with their own primitives; see ROBOTS.md.
//! - [`calibration`]: hand-eye calibration's capture files, its report
//!   and a simulated set's truth.
//! - [`trace`]: the figures of one plan stage by stage, as `plan --debug`
//!   and the daemon's `[debug]` section write them.

pub mod along_seam;
pub mod calibration;
pub mod frame;
pub mod message;
pub mod plan;
pub mod rule_ids;
pub mod session;
pub mod text;
pub mod trace;

pub use frame::MAX_CONTROL_MESSAGE_BYTES;
pub use message::{ErrorCode, Message};
pub use session::{OLDEST_SERVED_VERSION, PROTOCOL_VERSION, Session};
