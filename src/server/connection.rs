//! A connection speaking the wire protocol over a TCP stream: a reader that
//! owns its receive buffer and turns bytes into messages, and a writer.
//! Used by the daemon's links and by the mock camera and controller.
//!
//! Frames are read straight into their point buffer in chunks, never
//! through serde per point. A peer may be idle between messages as long
//! as it likes, but once a message has begun every read must make
//! progress within the stall timeout. Errors are curated: each maps to a
//! protocol [`ErrorCode`] and a sentence, and says whether the framing
//! survived (so the connection can go on after a typed reply).

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use weldseam_proto::frame::{
    self, DecodeError, EncodeError, FramingError, HEADER_BYTES, Header, MAX_CONTROL_MESSAGE_BYTES,
};
use weldseam_proto::message::{FRAME_META_BYTES, Frame, Hello, POINT_BYTES, Point, Role, Tag};
use weldseam_proto::{ErrorCode, Message, PROTOCOL_VERSION};

/// Point bytes read per call when receiving a frame (a multiple of 12).
const POINT_CHUNK_BYTES: usize = POINT_BYTES * 16 * 1024;

/// Why a message could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The peer closed the connection partway through a message.
    #[error("the connection closed in the middle of a message")]
    Truncated,
    /// The peer sent nothing for the stall timeout partway through a message.
    #[error("the peer sent nothing for {} ms in the middle of a message", .0.as_millis())]
    Stalled(Duration),
    /// The header is untrustworthy; the stream cannot be followed further.
    #[error(transparent)]
    Framing(#[from] FramingError),
    /// The body is invalid but was consumed whole; the stream is intact.
    #[error(transparent)]
    Decode(#[from] DecodeError),
    /// The socket failed.
    #[error("connection error: {0}")]
    Io(#[from] std::io::Error),
}

impl ReadError {
    /// True when the stream is still in step, so the connection can go on
    /// after an error reply.
    pub fn framing_intact(&self) -> bool {
        matches!(self, ReadError::Decode(_))
    }

    /// The code of the error reply this deserves, if the peer can still
    /// be told anything.
    pub fn reply_code(&self) -> Option<ErrorCode> {
        match self {
            ReadError::Framing(e) => Some(e.code()),
            ReadError::Decode(e) => Some(e.code()),
            ReadError::Truncated | ReadError::Stalled(_) | ReadError::Io(_) => None,
        }
    }
}

/// Why a message could not be sent.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The message could not be encoded.
    #[error(transparent)]
    Encode(#[from] EncodeError),
    /// The peer read nothing for the stall timeout.
    #[error("the peer accepted no data for {} ms", .0.as_millis())]
    Stalled(Duration),
    /// The socket failed.
    #[error("connection error: {0}")]
    Io(#[from] std::io::Error),
}

/// A message read, with how many bytes it took and how long it took to
/// arrive from its first byte.
#[derive(Debug)]
pub struct Received {
    pub message: Message,
    pub bytes: u64,
    pub elapsed: Duration,
}

/// Reads messages from a stream.
#[derive(Debug)]
pub struct MessageReader<R> {
    stream: R,
    stall: Duration,
    max_frame_bytes: u64,
    /// Receive buffer for control bodies and frame chunks; reused.
    buffer: Vec<u8>,
}

impl<R: AsyncRead + Unpin> MessageReader<R> {
    pub fn new(stream: R, stall: Duration, max_frame_bytes: u64) -> Self {
        MessageReader { stream, stall, max_frame_bytes, buffer: Vec::new() }
    }

    /// Reads into `range` of the buffer (grown to fit) until it is full;
    /// each read must progress within the stall timeout.
    async fn fill(&mut self, range: std::ops::Range<usize>) -> Result<(), ReadError> {
        self.grow(range.end);
        let mut at = range.start;
        while at < range.end {
            let read = self.stream.read(&mut self.buffer[at..range.end]);
            let n = tokio::time::timeout(self.stall, read).await.map_err(|_| ReadError::Stalled(self.stall))??;
            if n == 0 {
                return Err(ReadError::Truncated);
            }
            at += n;
        }
        Ok(())
    }

    /// Reads and drops `n` payload bytes, to keep the stream in step after
    /// an invalid body.
    async fn skip(&mut self, mut n: u64) -> Result<(), ReadError> {
        self.grow(POINT_CHUNK_BYTES);
        while n > 0 {
            let take = n.min(POINT_CHUNK_BYTES as u64) as usize;
            self.fill(0..take).await?;
            n -= take as u64;
        }
        Ok(())
    }

    fn grow(&mut self, len: usize) {
        if self.buffer.len() < len {
            self.buffer.resize(len, 0);
        }
    }

    /// Reads the next message; `Ok(None)` when the peer closed cleanly
    /// between messages.
    pub async fn read(&mut self) -> Result<Option<Received>, ReadError> {
        self.grow(HEADER_BYTES);
        // Idle time before a message's first byte is not a stall.
        let n = self.stream.read(&mut self.buffer[..1]).await?;
        if n == 0 {
            return Ok(None);
        }
        let started = Instant::now();
        self.fill(1..HEADER_BYTES).await?;
        let mut head = [0u8; HEADER_BYTES];
        head.copy_from_slice(&self.buffer[..HEADER_BYTES]);
        let header = Header::parse(&head, self.max_frame_bytes)?;
        let message = if header.tag == Tag::Frame as u16 {
            self.read_frame(header.length).await?
        } else {
            // Header::parse bounds every non-frame payload by the control limit.
            let len = header.length.min(MAX_CONTROL_MESSAGE_BYTES as u64) as usize;
            self.grow(len);
            self.fill(0..len).await?;
            frame::decode_body(header.tag, &self.buffer[..len])?
        };
        Ok(Some(Received { message, bytes: HEADER_BYTES as u64 + header.length, elapsed: started.elapsed() }))
    }

    async fn read_frame(&mut self, length: u64) -> Result<Message, ReadError> {
        if length < FRAME_META_BYTES as u64 {
            self.skip(length).await?;
            return Err(DecodeError::Malformed {
                tag: Tag::Frame.name(),
                reason: format!("the payload is {length} bytes, shorter than the {FRAME_META_BYTES}-byte frame header"),
            }
            .into());
        }
        self.fill(0..FRAME_META_BYTES).await?;
        let rest = length - FRAME_META_BYTES as u64;
        let checked = frame::decode_frame_meta(&self.buffer[..FRAME_META_BYTES])
            .and_then(|meta| Ok((meta, frame::check_frame_meta(&meta, length)?)));
        let (meta, (point_bytes, units)) = match checked {
            Ok(ok) => ok,
            Err(e) => {
                self.skip(rest).await?;
                return Err(e.into());
            }
        };
        let count = (point_bytes / POINT_BYTES as u64) as usize;
        let mut points: Vec<Point> = Vec::with_capacity(count);
        self.grow(POINT_CHUNK_BYTES);
        let mut left = point_bytes;
        while left > 0 {
            let take = left.min(POINT_CHUNK_BYTES as u64) as usize;
            self.fill(0..take).await?;
            frame::points_from_le(&self.buffer[..take], units.to_mm(), &mut points);
            left -= take as u64;
        }
        Ok(Message::Frame(Frame { meta, points }))
    }
}

/// Writes messages to a stream.
#[derive(Debug)]
pub struct MessageWriter<W> {
    stream: W,
    stall: Duration,
}

impl<W: AsyncWrite + Unpin> MessageWriter<W> {
    pub fn new(stream: W, stall: Duration) -> Self {
        MessageWriter { stream, stall }
    }

    /// Sends one message; the peer must accept it within the stall timeout
    /// per chunk the socket takes.
    pub async fn send(&mut self, message: &Message) -> Result<(), WriteError> {
        let bytes = frame::encode(message)?;
        for chunk in bytes.chunks(POINT_CHUNK_BYTES) {
            tokio::time::timeout(self.stall, self.stream.write_all(chunk))
                .await
                .map_err(|_| WriteError::Stalled(self.stall))??;
        }
        tokio::time::timeout(self.stall, self.stream.flush()).await.map_err(|_| WriteError::Stalled(self.stall))??;
        Ok(())
    }

    /// Closes the sending side.
    pub async fn shutdown(&mut self) {
        let _ = tokio::time::timeout(self.stall, self.stream.shutdown()).await;
    }
}

/// Why the opening hello was refused.
#[derive(Debug, thiserror::Error)]
pub enum HandshakeError {
    /// The peer closed before saying hello.
    #[error("the peer closed the connection before its hello")]
    Closed,
    /// Nothing arrived within the stall timeout.
    #[error("no hello within {} ms", .0.as_millis())]
    Timeout(Duration),
    /// The hello could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The first message was not a hello, or named the wrong version or role.
    #[error("{message}")]
    Refused { code: ErrorCode, message: String },
}

/// A TCP connection split into its reader and writer.
#[derive(Debug)]
pub struct Connection {
    pub peer: SocketAddr,
    pub reader: MessageReader<OwnedReadHalf>,
    pub writer: MessageWriter<OwnedWriteHalf>,
}

impl Connection {
    pub fn new(stream: TcpStream, peer: SocketAddr, stall: Duration, max_frame_bytes: u64) -> Self {
        let _ = stream.set_nodelay(true);
        let (r, w) = stream.into_split();
        Connection { peer, reader: MessageReader::new(r, stall, max_frame_bytes), writer: MessageWriter::new(w, stall) }
    }

    /// Waits for the peer's hello (within `stall`) and checks its version
    /// and role. The caller answers with an ack or the error.
    pub async fn expect_hello(&mut self, role: Role, stall: Duration) -> Result<Hello, HandshakeError> {
        let received = tokio::time::timeout(stall, self.reader.read())
            .await
            .map_err(|_| HandshakeError::Timeout(stall))??
            .ok_or(HandshakeError::Closed)?;
        let hello = match received.message {
            Message::Hello(h) => h,
            other => {
                return Err(HandshakeError::Refused {
                    code: ErrorCode::UnexpectedMessage,
                    message: format!("the first message must be a Hello, not a {}", other.tag().name()),
                });
            }
        };
        if hello.protocol_version != PROTOCOL_VERSION {
            return Err(HandshakeError::Refused {
                code: ErrorCode::UnsupportedVersion,
                message: format!(
                    "protocol version {} is not supported; this daemon speaks version {PROTOCOL_VERSION}",
                    hello.protocol_version
                ),
            });
        }
        if hello.role != role {
            return Err(HandshakeError::Refused {
                code: ErrorCode::UnexpectedMessage,
                message: format!("this is the {} port, but the peer says it is a {}", role.name(), hello.role.name()),
            });
        }
        Ok(hello)
    }
}
