//! A mock robot controller: connects to the controller link, says hello,
//! sends plan requests and pings and reads the replies.

use std::time::Duration;

use tokio::net::TcpStream;
use weldseam_proto::frame::DEFAULT_MAX_FRAME_BYTES;
use weldseam_proto::message::{Hello, PlanReply, PlanRequest, Role, Status};
use weldseam_proto::{Message, Session};

use super::ClientError;
use crate::server::connection::Connection;

/// How long any one message may take to arrive once begun.
const STALL: Duration = Duration::from_secs(30);

/// A connected controller.
#[derive(Debug)]
pub struct ControllerClient {
    conn: Connection,
    /// The daemon's name from its hello ack.
    pub server: String,
    /// The capabilities the daemon granted.
    pub capabilities: u64,
}

impl ControllerClient {
    /// Connects and completes the hello, asking for no capability.
    pub async fn connect(addr: &str, name: &str) -> Result<Self, ClientError> {
        ControllerClient::connect_asking(addr, name, 0).await
    }

    /// Connects and completes the hello, asking for `capabilities`
    /// ([`weldseam_proto::session::capability`]); every later message is
    /// read and written as the daemon's grant says.
    pub async fn connect_asking(addr: &str, name: &str, capabilities: u64) -> Result<Self, ClientError> {
        let stream =
            TcpStream::connect(addr).await.map_err(|source| ClientError::Connect { addr: addr.to_string(), source })?;
        let peer = stream.peer_addr().map_err(|source| ClientError::Connect { addr: addr.to_string(), source })?;
        let mut conn = Connection::new(stream, peer, STALL, DEFAULT_MAX_FRAME_BYTES);
        let hello = Hello::new(Role::Controller, name, capabilities);
        conn.writer.send(&Message::Hello(hello)).await?;
        match conn.reader.read().await? {
            Some(r) => match r.message {
                Message::HelloAck(ack) => {
                    let session = Session { version: ack.protocol_version, capabilities: ack.capabilities };
                    conn.reader.set_session(session);
                    conn.writer.set_session(session);
                    Ok(ControllerClient { conn, server: ack.server, capabilities: ack.capabilities })
                }
                Message::Error(e) => Err(ClientError::Refused(e)),
                other => Err(ClientError::Unexpected(other.tag().name())),
            },
            None => Err(ClientError::Closed),
        }
    }

    /// Sends any message.
    pub async fn send(&mut self, message: &Message) -> Result<(), ClientError> {
        Ok(self.conn.writer.send(message).await?)
    }

    /// Reads the next message.
    pub async fn recv(&mut self) -> Result<Message, ClientError> {
        Ok(self.conn.reader.read().await?.ok_or(ClientError::Closed)?.message)
    }

    /// Sends a plan request and waits (at most `wait`) for its reply.
    pub async fn plan(&mut self, request: PlanRequest, wait: Duration) -> Result<PlanReply, ClientError> {
        let id = request.request_id;
        self.send(&Message::PlanRequest(request)).await?;
        let answer = async {
            loop {
                match self.recv().await? {
                    Message::PlanReply(reply) if reply.request_id == id => return Ok(reply),
                    Message::Error(e) if e.request_id.is_none() || e.request_id == Some(id) => {
                        return Err(ClientError::Refused(e));
                    }
                    // Replies to other requests on this connection.
                    Message::PlanReply(_) | Message::Error(_) | Message::Status(_) => continue,
                    other => return Err(ClientError::Unexpected(other.tag().name())),
                }
            }
        };
        tokio::time::timeout(wait, answer).await.map_err(|_| ClientError::Timeout(wait.as_millis()))?
    }

    /// Pings and returns the daemon's status.
    pub async fn ping(&mut self, wait: Duration) -> Result<Status, ClientError> {
        self.send(&Message::Ping).await?;
        let answer = async {
            loop {
                match self.recv().await? {
                    Message::Status(s) => return Ok(s),
                    Message::Error(e) if e.request_id.is_none() => return Err(ClientError::Refused(e)),
                    Message::PlanReply(_) | Message::Error(_) => continue,
                    other => return Err(ClientError::Unexpected(other.tag().name())),
                }
            }
        };
        tokio::time::timeout(wait, answer).await.map_err(|_| ClientError::Timeout(wait.as_millis()))?
    }

    /// Pings until the daemon reports a camera connected, for at most
    /// `wait`: commissioning and tests start the camera and the controller
    /// together and need the camera in place before the first trigger.
    pub async fn wait_for_camera(&mut self, wait: Duration) -> Result<(), ClientError> {
        let deadline = tokio::time::Instant::now() + wait;
        loop {
            let left = deadline.saturating_duration_since(tokio::time::Instant::now());
            if self.ping(left.max(Duration::from_millis(1))).await?.camera_connected {
                return Ok(());
            }
            if tokio::time::Instant::now() >= deadline {
                return Err(ClientError::Timeout(wait.as_millis()));
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    }
}

/// The plan request a robot would send for a simulated scene: its joint,
/// groove depth and the flange pose at capture.
pub fn request_for_simulation(
    request_id: u64,
    joint: crate::joint::JointType,
    sim: &crate::sim::Simulation,
    frame: weldseam_proto::message::FrameSelect,
) -> PlanRequest {
    let request = crate::pipeline::PlanRequest::new(joint, sim.truth.groove_depth_mm, sim.pose);
    crate::convert::to_proto::plan_request(request_id, &request, frame)
}
