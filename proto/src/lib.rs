//! The weldseam wire protocol and report schema: the only serializable
//! types of the workspace. Domain types live in the `weldseam` library and
//! are converted to and from these at the boundary.
//!
//! - [`plan`]: a planned trajectory as the controller receives it and as
//!   `weldseam plan --json` prints it.

pub mod plan;
