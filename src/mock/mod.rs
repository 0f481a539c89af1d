//! Mock peers of the cell daemon, for commissioning and tests: a camera
//! that pushes frames over the camera link and answers triggers, a
//! controller that sends plan requests and pings, and a robot program on
//! the text link. The first two speak the wire protocol through the same
//! connection type as the daemon.

pub mod camera;
pub mod controller;
pub mod load;
pub mod text_robot;

use weldseam_proto::message::ErrorReply;

use crate::server::connection::{HandshakeError, ReadError, WriteError};

/// Why a mock peer's exchange with the daemon failed.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// No connection could be made.
    #[error("cannot connect to {addr}: {source}")]
    Connect {
        addr: String,
        #[source]
        source: std::io::Error,
    },
    /// The daemon answered with a typed error.
    #[error("the daemon answered error {}: {}", .0.code, .0.message)]
    Refused(ErrorReply),
    /// The daemon closed the connection.
    #[error("the daemon closed the connection")]
    Closed,
    /// A message could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A message could not be sent.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The daemon sent a message that makes no sense here.
    #[error("unexpected {0} message from the daemon")]
    Unexpected(&'static str),
    /// No answer within the time allowed.
    #[error("no answer from the daemon within {0} ms")]
    Timeout(u128),
}

impl From<HandshakeError> for ClientError {
    fn from(e: HandshakeError) -> Self {
        match e {
            HandshakeError::Read(r) => ClientError::Read(r),
            _ => ClientError::Closed,
        }
    }
}
