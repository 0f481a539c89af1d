//! A connection speaking the wire protocol over a TCP stream: a reader that
//! owns its receive buffer and turns bytes into messages, and a writer.
//! Used by the daemon's links and by the mock camera and controller.
//!
//! Frames are read straight into their point buffer in chunks, never
//! through serde per point, and buffers grow with the bytes that have
//! arrived rather than with the lengths a header announces. A peer may be
//! idle between messages as long as it likes, but once a message has begun
//! every read must make progress within the stall timeout, and the whole
//! message must arrive within its [`MessageDeadline`]: a peer that trickles
//! one byte at a time is never silent, so the stall timeout alone would
//! keep it forever. Errors are curated: each maps to a protocol
//! [`ErrorCode`] and a sentence, and says whether the framing survived (so
//! the connection can go on after a typed reply).

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use prometheus_client::metrics::counter::Counter;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use weldseam_proto::frame::{
    self, DecodeError, EncodeError, FramingError, HEADER_BYTES, Header, MAX_CONTROL_MESSAGE_BYTES,
};
use weldseam_proto::message::{FRAME_META_BYTES, Frame, Hello, POINT_BYTES, Point, Role, Tag};
use weldseam_proto::session::{self, Session};
use weldseam_proto::{ErrorCode, Message};

/// Point bytes read per call when receiving a frame (a multiple of 12).
const POINT_CHUNK_BYTES: usize = POINT_BYTES * 16 * 1024;

/// How far the receive buffer may run ahead of the bytes received: a
/// header announcing megabytes costs nothing until they arrive.
const READ_AHEAD_BYTES: usize = 64 * 1024;

/// The time a whole message may take: a fixed allowance plus its length at
/// a minimum transfer rate, counted from its first byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageDeadline {
    /// The allowance of every message, however short.
    pub base: Duration,
    /// The slowest rate accepted for the message's bytes.
    pub min_bytes_per_s: u64,
}

impl MessageDeadline {
    /// The time allowed for a message of `bytes` bytes (header included).
    pub fn allowance(&self, bytes: u64) -> Duration {
        let rate = self.min_bytes_per_s.max(1);
        // Below one second per rate's worth of bytes: nanoseconds, in u128
        // so no rate can overflow it.
        let nanos = (u128::from(bytes % rate) * 1_000_000_000 / u128::from(rate)) as u64;
        let transfer = Duration::from_secs(bytes / rate).saturating_add(Duration::from_nanos(nanos));
        self.base.saturating_add(transfer)
    }
}

/// Why a message could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The peer closed the connection partway through a message.
    #[error("the connection closed in the middle of a message")]
    Truncated,
    /// The peer sent nothing for the stall timeout partway through a message.
    #[error("the peer sent nothing for {} ms in the middle of a message", .0.as_millis())]
    Stalled(Duration),
    /// The message did not arrive whole within its deadline, although the
    /// peer kept sending.
    #[error(
        "a {bytes}-byte message did not arrive within {} ms of its first byte (allowed: {} ms plus its length at \
         {min_bytes_per_s} bytes/s)",
        .allowed.as_millis(), .base.as_millis()
    )]
    TooSlow { bytes: u64, allowed: Duration, base: Duration, min_bytes_per_s: u64 },
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
            ReadError::Truncated | ReadError::Stalled(_) | ReadError::TooSlow { .. } | ReadError::Io(_) => None,
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
    /// The peer kept reading, but too slowly to take the message within
    /// its deadline.
    #[error("the peer took more than {} ms to accept a {bytes}-byte message", .allowed.as_millis())]
    TooSlow { bytes: u64, allowed: Duration },
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
    /// The whole-message bound; None bounds only the silences (for clients
    /// reading a daemon they trust).
    deadline: Option<MessageDeadline>,
    /// When the message being read must be complete, and its length.
    due: Option<(Instant, u64)>,
    /// Counts every byte received, for the metrics.
    bytes_in: Option<Counter>,
    /// Receive buffer for control bodies and frame chunks; reused.
    buffer: Vec<u8>,
    /// The version and capabilities agreed in the Hello; until then each
    /// message is read as its header's version says.
    session: Option<Session>,
    /// The version of the last header read, which a refusal before the
    /// Hello is answered in.
    last_version: Option<u16>,
}

impl<R: AsyncRead + Unpin> MessageReader<R> {
    pub fn new(stream: R, stall: Duration, max_frame_bytes: u64) -> Self {
        MessageReader {
            stream,
            stall,
            max_frame_bytes,
            deadline: None,
            due: None,
            bytes_in: None,
            buffer: Vec::new(),
            session: None,
            last_version: None,
        }
    }

    /// From now on every message must come in `session`'s version, and is
    /// read as its layout and capabilities say.
    pub fn set_session(&mut self, session: Session) {
        self.session = Some(session);
    }

    /// The version of the last header read, if any.
    pub fn last_version(&self) -> Option<u16> {
        self.last_version
    }

    /// Bounds the time of every whole message, not only the silences.
    pub fn with_deadline(mut self, deadline: MessageDeadline) -> Self {
        self.deadline = Some(deadline);
        self
    }

    /// Counts the bytes received into `counter`.
    pub fn with_byte_counter(mut self, counter: Counter) -> Self {
        self.bytes_in = Some(counter);
        self
    }

    /// Bytes the receive buffer holds now (its capacity), so tests can
    /// check that memory follows the bytes received.
    pub fn buffer_capacity(&self) -> usize {
        self.buffer.capacity()
    }

    /// Starts the deadline of a message of `bytes` bytes begun at `started`.
    fn set_due(&mut self, started: Instant, bytes: u64) {
        // An allowance past the clock's range is no bound at all.
        self.due = self.deadline.and_then(|d| Some((started.checked_add(d.allowance(bytes))?, bytes)));
    }

    /// One read into `buffer[at..end]`, within the stall timeout and the
    /// message's deadline, whichever comes first.
    async fn read_some(&mut self, at: usize, end: usize) -> Result<usize, ReadError> {
        let stall_until = Instant::now() + self.stall;
        let (until, late) = match (self.due, self.deadline) {
            (Some((due, bytes)), Some(d)) if due < stall_until => (
                due,
                ReadError::TooSlow {
                    bytes,
                    allowed: d.allowance(bytes),
                    base: d.base,
                    min_bytes_per_s: d.min_bytes_per_s,
                },
            ),
            _ => (stall_until, ReadError::Stalled(self.stall)),
        };
        let read = self.stream.read(&mut self.buffer[at..end]);
        let n = tokio::time::timeout_at(until.into(), read).await.map_err(|_| late)??;
        if let Some(c) = &self.bytes_in {
            c.inc_by(n as u64);
        }
        Ok(n)
    }

    /// Reads into `range` of the buffer until it is full, growing the
    /// buffer only a little ahead of the bytes received.
    async fn fill(&mut self, range: std::ops::Range<usize>) -> Result<(), ReadError> {
        let mut at = range.start;
        while at < range.end {
            let end = range.end.min(at.saturating_add(READ_AHEAD_BYTES).max(self.buffer.len()));
            self.grow(end);
            let n = self.read_some(at, end).await?;
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
        self.due = None;
        // Idle time before a message's first byte is not a stall.
        let n = self.stream.read(&mut self.buffer[..1]).await?;
        if n == 0 {
            return Ok(None);
        }
        if let Some(c) = &self.bytes_in {
            c.inc();
        }
        let started = Instant::now();
        self.set_due(started, HEADER_BYTES as u64);
        self.fill(1..HEADER_BYTES).await?;
        let mut head = [0u8; HEADER_BYTES];
        head.copy_from_slice(&self.buffer[..HEADER_BYTES]);
        // A header without the magic bytes has no version to speak of.
        if head[..4] == frame::MAGIC {
            self.last_version = Some(u16::from_le_bytes([head[4], head[5]]));
        }
        let header = Header::parse(&head, self.max_frame_bytes)?;
        if let Some(agreed) = self.session
            && header.version != agreed.version
        {
            return Err(FramingError::VersionChanged { got: header.version, agreed: agreed.version }.into());
        }
        let session = self.session.unwrap_or(Session::of(header.version));
        self.set_due(started, HEADER_BYTES as u64 + header.length);
        let message = if header.tag == Tag::Frame as u16 {
            self.read_frame(header.length).await?
        } else {
            // Header::parse bounds every non-frame payload by the control limit.
            let len = header.length.min(MAX_CONTROL_MESSAGE_BYTES as u64) as usize;
            self.fill(0..len).await?;
            frame::decode_body_in(session, header.tag, &self.buffer[..len])?
        };
        self.due = None;
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
        let (meta, layout) = match checked {
            Ok(ok) => ok,
            Err(e) => {
                self.skip(rest).await?;
                return Err(e.into());
            }
        };
        let point_bytes = layout.point_bytes;
        let count = (point_bytes / POINT_BYTES as u64) as usize;
        // The point buffer doubles as points arrive, up to exactly the
        // announced count: memory follows what the peer has sent, and a
        // full frame is copied about once on the way.
        let mut points: Vec<Point> = Vec::new();
        let mut left = point_bytes;
        while left > 0 {
            let take = left.min(POINT_CHUNK_BYTES as u64) as usize;
            self.fill(0..take).await?;
            let arriving = take / POINT_BYTES;
            if points.capacity() - points.len() < arriving {
                let target = (points.capacity() * 2).max(points.len() + arriving).min(count);
                points.reserve_exact(target - points.len());
            }
            frame::points_from_le(&self.buffer[..take], layout.units.decode_scale(), &mut points);
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
    /// The whole-message bound of a send; None bounds only the stalls.
    deadline: Option<MessageDeadline>,
    /// The version and capabilities messages are laid out in.
    session: Session,
}

impl<W: AsyncWrite + Unpin> MessageWriter<W> {
    pub fn new(stream: W, stall: Duration) -> Self {
        MessageWriter { stream, stall, deadline: None, session: Session::NEWEST }
    }

    /// Lays out every later message as `session` says.
    pub fn set_session(&mut self, session: Session) {
        self.session = session;
    }

    pub fn session(&self) -> Session {
        self.session
    }

    /// Bounds the time of every whole message sent, not only the stalls.
    pub fn with_deadline(mut self, deadline: MessageDeadline) -> Self {
        self.deadline = Some(deadline);
        self
    }

    /// Sends one message; the peer must accept it within the stall timeout
    /// per chunk the socket takes, and all of it within the deadline.
    pub async fn send(&mut self, message: &Message) -> Result<(), WriteError> {
        let bytes = frame::encode_in(self.session, message)?;
        self.send_encoded(&bytes).await
    }

    /// Sends a message already encoded, under the same bounds as
    /// [`MessageWriter::send`].
    pub async fn send_encoded(&mut self, bytes: &[u8]) -> Result<(), WriteError> {
        let total = bytes.len() as u64;
        let allowed = self.deadline.map(|d| d.allowance(total));
        let due = allowed.and_then(|a| Instant::now().checked_add(a));
        let stall = self.stall;
        let bound = |step: Instant| -> (Instant, WriteError) {
            let stall_until = step + stall;
            match (due, allowed) {
                (Some(due), Some(allowed)) if due < stall_until => (due, WriteError::TooSlow { bytes: total, allowed }),
                _ => (stall_until, WriteError::Stalled(stall)),
            }
        };
        for chunk in bytes.chunks(POINT_CHUNK_BYTES) {
            let (until, late) = bound(Instant::now());
            tokio::time::timeout_at(until.into(), self.stream.write_all(chunk)).await.map_err(|_| late)??;
        }
        let (until, late) = bound(Instant::now());
        tokio::time::timeout_at(until.into(), self.stream.flush()).await.map_err(|_| late)??;
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
    /// The first message was not a hello, or named a version not served
    /// or the wrong role.
    #[error("{message}")]
    Refused { code: ErrorCode, message: String },
}

/// The daemon's admission of a connection whose hello is valid, run just
/// before the hello is acknowledged: it takes the connection's slot on its
/// link, or says why there is none (answered with a busy error).
pub struct Admission(Box<dyn FnOnce() -> Result<(), String> + Send>);

impl Admission {
    pub fn new(admit: impl FnOnce() -> Result<(), String> + Send + 'static) -> Self {
        Admission(Box::new(admit))
    }
}

impl std::fmt::Debug for Admission {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Admission")
    }
}

/// A TCP connection split into its reader and writer.
#[derive(Debug)]
pub struct Connection {
    pub peer: SocketAddr,
    pub reader: MessageReader<OwnedReadHalf>,
    pub writer: MessageWriter<OwnedWriteHalf>,
    /// Run once by [`Connection::expect_hello`] on a valid hello.
    admission: Option<Admission>,
}

impl Connection {
    pub fn new(stream: TcpStream, peer: SocketAddr, stall: Duration, max_frame_bytes: u64) -> Self {
        let _ = stream.set_nodelay(true);
        let (r, w) = stream.into_split();
        Connection {
            peer,
            reader: MessageReader::new(r, stall, max_frame_bytes),
            writer: MessageWriter::new(w, stall),
            admission: None,
        }
    }

    /// Bounds every whole message, both ways, not only the silences.
    pub fn with_deadline(mut self, deadline: MessageDeadline) -> Self {
        self.reader.deadline = Some(deadline);
        self.writer.deadline = Some(deadline);
        self
    }

    /// Counts the bytes received into `counter`.
    pub fn with_byte_counter(mut self, counter: Counter) -> Self {
        self.reader.bytes_in = Some(counter);
        self
    }

    /// Runs `admission` when a valid hello arrives, before it is answered.
    pub fn with_admission(mut self, admission: Admission) -> Self {
        self.admission = Some(admission);
        self
    }

    /// Waits for the peer's hello (within `wait`), checks its role,
    /// negotiates the version and capabilities (see
    /// [`weldseam_proto::session`]) and runs the admission, if any. The
    /// caller answers with an ack in the session returned, or the error.
    pub async fn expect_hello(&mut self, role: Role, wait: Duration) -> Result<(Hello, Session), HandshakeError> {
        let received = tokio::time::timeout(wait, self.reader.read())
            .await
            .map_err(|_| HandshakeError::Timeout(wait))??
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
        let header_version = self.reader.last_version().unwrap_or(hello.protocol_version);
        let session = session::negotiate(&hello, header_version)
            .map_err(|e| HandshakeError::Refused { code: e.code(), message: e.to_string() })?;
        if hello.role != role {
            return Err(HandshakeError::Refused {
                code: ErrorCode::UnexpectedMessage,
                message: format!("this is the {} port, but the peer says it is a {}", role.name(), hello.role.name()),
            });
        }
        if let Some(Admission(admit)) = self.admission.take() {
            admit().map_err(|message| HandshakeError::Refused { code: ErrorCode::Busy, message })?;
        }
        Ok((hello, session))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_allowance_is_the_base_plus_the_length_at_the_minimum_rate() {
        let d = MessageDeadline { base: Duration::from_secs(10), min_bytes_per_s: 1 << 20 };
        assert_eq!(d.allowance(0), Duration::from_secs(10));
        assert_eq!(d.allowance(3 << 20), Duration::from_secs(13));
        assert_eq!(d.allowance(1 << 19), Duration::from_millis(10_500));
        let slowest = MessageDeadline { base: Duration::from_secs(10), min_bytes_per_s: 1 };
        assert_eq!(slowest.allowance(u64::MAX), Duration::MAX, "saturates rather than overflowing");
        let fastest = MessageDeadline { base: Duration::ZERO, min_bytes_per_s: u64::MAX };
        assert_eq!(fastest.allowance(u64::MAX - 1), Duration::from_nanos(999_999_999));
    }

    #[tokio::test]
    async fn a_message_trickled_without_pauses_is_cut_off_at_its_deadline() {
        let (mut peer, ours) = tokio::io::duplex(64);
        let deadline = MessageDeadline { base: Duration::from_millis(300), min_bytes_per_s: 1 << 20 };
        // Each byte comes well within the stall timeout.
        let mut reader = MessageReader::new(ours, Duration::from_secs(5), 1 << 20).with_deadline(deadline);
        let ping = frame::encode(&Message::Ping).unwrap();
        let trickle = tokio::spawn(async move {
            for b in ping {
                if peer.write_all(&[b]).await.is_err() {
                    break;
                }
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
            peer
        });
        let started = Instant::now();
        let e = reader.read().await.unwrap_err();
        assert!(matches!(e, ReadError::TooSlow { bytes: 16, .. }), "{e}");
        assert!(started.elapsed() < Duration::from_secs(5), "cut off by the deadline, not the stall timeout");
        assert!(e.to_string().contains("300 ms"), "{e}");
        drop(reader);
        trickle.await.unwrap();
    }
}
