//! Property tests of everything that reads the wire: arbitrary and
//! mutated bytes fed to the protocol's frame decoder and to the daemon's
//! message reader (over an in-memory stream delivering a few bytes at a
//! time) must never panic, and must never allocate much more than the
//! bytes they were given, whatever lengths the headers announce.
//!
//! 4,000 cases per property by default; set `PROPTEST_CASES` for more
//! (e.g. `PROPTEST_CASES=100000 cargo test --test tests fuzz::`).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use proptest::prelude::*;
use tokio::io::{AsyncRead, ReadBuf};
use weldseam::server::connection::{MessageDeadline, MessageReader};
use weldseam_proto::frame::{self, HEADER_BYTES, Header};
use weldseam_proto::message::{
    ErrorCode, FRAME_META_BYTES, Frame, FrameAck, FrameMeta, FrameSelect, Hello, HelloAck, POINT_BYTES, PlanRequest,
    PoseIn, Roi, Role, Status, Tag, Trigger,
};
use weldseam_proto::{Message, PROTOCOL_VERSION};

/// The frame limit of these tests: small, so a frame announcing the limit
/// would show in the allocations if it were reserved up front.
const MAX_FRAME_BYTES: u64 = 8 << 20;

/// What decoding or reading `n` input bytes may allocate at its peak: the
/// control-message limit (bincode reserves a string's or sequence's
/// announced length, within that limit, before it finds the body too
/// short) plus a small multiple of the input. A frame announcing
/// [`MAX_FRAME_BYTES`] must not be reserved before its points arrive.
fn allocation_bound(n: usize) -> usize {
    weldseam_proto::MAX_CONTROL_MESSAGE_BYTES + (1 << 20) + 16 * n
}

/// The largest receive buffer the reader may hold after `n` input bytes:
/// it reads at most 64 KiB ahead of what has arrived, and a vector at most
/// doubles when it grows.
fn receive_buffer_bound(n: usize) -> usize {
    2 * (n + (64 << 10)) + HEADER_BYTES
}

fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(4_000);
    ProptestConfig { cases, ..ProptestConfig::default() }
}

// ---------------------------------------------------------------------
// Allocation accounting per thread: the property bodies run on the test's
// own thread (the runtime below is single-threaded), so other tests of
// this binary running in parallel do not disturb the figures.

struct CountingAllocator;

thread_local! {
    static LIVE_BYTES: Cell<usize> = const { Cell::new(0) };
    static PEAK_BYTES: Cell<usize> = const { Cell::new(0) };
}

fn grew(n: usize) {
    let _ = LIVE_BYTES.try_with(|live| {
        let now = live.get() + n;
        live.set(now);
        let _ = PEAK_BYTES.try_with(|peak| peak.set(peak.get().max(now)));
    });
}

fn shrank(n: usize) {
    // Memory allocated on another thread may be freed on this one.
    let _ = LIVE_BYTES.try_with(|live| live.set(live.get().saturating_sub(n)));
}

// SAFETY: every call is passed to the system allocator unchanged; the
// accounting touches only const-initialised thread locals, which never
// allocate.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract is passed on.
        unsafe { System.dealloc(ptr, layout) };
        shrank(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract is passed on.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            // Both blocks may exist at once while the contents move.
            grew(new_size);
            shrank(layout.size());
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Runs `f` and returns its result and the most memory it had allocated
/// on this thread at any moment, above what was allocated before.
fn peak_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let before = LIVE_BYTES.with(Cell::get);
    PEAK_BYTES.with(|peak| peak.set(before));
    let out = f();
    let peak = PEAK_BYTES.with(Cell::get);
    (out, peak.saturating_sub(before))
}

// ---------------------------------------------------------------------
// Inputs: pure noise, a well-formed header before noise, and valid
// messages with bytes changed, inserted, removed or cut off.

fn valid_messages() -> Vec<Vec<u8>> {
    let meta =
        FrameMeta { frame_id: 7, trigger_id: 1, capture_time_us: 5, width: 4, height: 3, units: 1, cloud_frame: 1 };
    let points = (0..12).map(|i| [i as f32, 0.5, 0.7]).collect();
    let messages = [
        Message::Hello(Hello {
            protocol_version: PROTOCOL_VERSION,
            role: Role::Camera,
            name: "cam-01".into(),
            capabilities: 0,
        }),
        Message::HelloAck(HelloAck {
            protocol_version: PROTOCOL_VERSION,
            server: "weldseam".into(),
            capabilities: 0,
            limits: None,
        }),
        Message::error(ErrorCode::Busy, Some(3), "busy"),
        Message::Ping,
        Message::Status(Status {
            uptime_ms: 1,
            frames_received: 2,
            plans_done: 3,
            queue_length: 4,
            camera_connected: true,
            cameras: 1,
            latest_frame_id: Some(6),
            latest_capture_time_us: Some(1_700_000_000_000_000),
        }),
        Message::FrameAck(FrameAck { frame_id: 6, trigger_id: 1, code: 0, requests: 1, message: "held".into() }),
        Message::Frame(Frame { meta, points }),
        Message::Trigger(Trigger { trigger_id: 9 }),
        Message::PlanRequest(PlanRequest {
            request_id: 11,
            joint: 2,
            groove_depth_mm: Some(3.0),
            pose: [800.0, 0.0, 500.0, 180.0, 0.0, 0.0],
            step_mm: None,
            work_angle_deg: Some(10.0),
            travel_angle_deg: None,
            frame: FrameSelect::FrameId(4),
            timeout_ms: 100,
            camera: Some("cam-01".into()),
            hand_eye: Some([1.0, 0.0, 0.0, 76.0, 0.0, 1.0, 0.0, -84.0, 0.0, 0.0, 1.0, 100.0, 0.0, 0.0, 0.0, 1.0]),
            start_near: Some([900.0, -100.0, -250.0]),
            roi: Some(Roi { min_mm: [-50.0, -40.0, 300.0], max_mm: [50.0, 40.0, 700.0], frame: 0 }),
            pose_in: Some(PoseIn {
                convention: "quaternion_wxyz".into(),
                length_unit: 0,
                angle_unit: 0,
                values: vec![800.0, 0.0, 500.0, 0.0, 1.0, 0.0, 0.0],
            }),
            one_seam: true,
        }),
    ];
    messages.iter().map(|m| frame::encode(m).unwrap()).collect()
}

#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Insert(usize, u8),
    Remove(usize),
    Cut(usize),
    /// Overwrites the header's length field.
    Length(u64),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, b)| Edit::Set(at, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(at, b)| Edit::Insert(at, b)),
        any::<usize>().prop_map(Edit::Remove),
        any::<usize>().prop_map(Edit::Cut),
        prop_oneof![0..4096u64, Just(u64::MAX), Just(MAX_FRAME_BYTES), Just(4 << 20), any::<u64>()]
            .prop_map(Edit::Length),
    ]
}

fn mutated(seeds: Vec<Vec<u8>>) -> impl Strategy<Value = Vec<u8>> {
    (0..seeds.len(), prop::collection::vec(edit(), 0..6), 1..4usize).prop_map(move |(seed, edits, copies)| {
        // A few messages in a row, the edits falling anywhere in them.
        let mut bytes: Vec<u8> = (0..copies).flat_map(|k| seeds[(seed + k) % seeds.len()].clone()).collect();
        for e in edits {
            let n = bytes.len().max(1);
            match e {
                Edit::Set(at, b) if !bytes.is_empty() => bytes[at % n] = b,
                Edit::Insert(at, b) => bytes.insert(at % (bytes.len() + 1), b),
                Edit::Remove(at) if !bytes.is_empty() => {
                    bytes.remove(at % n);
                }
                Edit::Cut(at) => bytes.truncate(at % (bytes.len() + 1)),
                Edit::Length(len) if bytes.len() >= HEADER_BYTES => bytes[8..16].copy_from_slice(&len.to_le_bytes()),
                _ => {}
            }
        }
        bytes
    })
}

fn header_then_noise() -> impl Strategy<Value = Vec<u8>> {
    let tag = prop_oneof![prop::sample::select(Tag::ALL.to_vec()).prop_map(|t| t as u16), any::<u16>()];
    let length = prop_oneof![0..256u64, 0..(8u64 << 20), Just(4 << 20), Just(MAX_FRAME_BYTES), any::<u64>()];
    (tag, length, prop::collection::vec(any::<u8>(), 0..2048)).prop_map(|(tag, length, body)| {
        let mut bytes = Header { version: PROTOCOL_VERSION, tag, length }.to_bytes().to_vec();
        bytes.extend_from_slice(&body);
        bytes
    })
}

/// A consistent frame header announcing up to [`MAX_FRAME_BYTES`], then
/// only a few of its points: a peer that promises much and sends little.
fn big_frame_begun() -> impl Strategy<Value = Vec<u8>> {
    let max_points = (MAX_FRAME_BYTES as usize - FRAME_META_BYTES) / POINT_BYTES;
    (1..2048u32, 0..2u32, prop::collection::vec(any::<u8>(), 0..4096))
        .prop_flat_map(move |(width, units, tail)| {
            (Just(width), 1..=(max_points as u32 / width).max(1), Just(units), Just(tail))
        })
        .prop_map(|(width, height, units, tail)| {
            let meta =
                FrameMeta { frame_id: 1, trigger_id: 0, capture_time_us: 0, width, height, units, cloud_frame: 0 };
            let length = (FRAME_META_BYTES + POINT_BYTES * width as usize * height as usize) as u64;
            let mut bytes = Header::new(Tag::Frame, length).to_bytes().to_vec();
            // The meta as the frame encoder writes it, from a one-point frame.
            let one = frame::encode(&Message::Frame(Frame {
                meta: FrameMeta { width: 1, height: 1, ..meta },
                points: vec![[0.0; 3]],
            }))
            .unwrap();
            bytes.extend_from_slice(&one[HEADER_BYTES..HEADER_BYTES + FRAME_META_BYTES]);
            bytes[HEADER_BYTES + 24..HEADER_BYTES + 28].copy_from_slice(&width.to_le_bytes());
            bytes[HEADER_BYTES + 28..HEADER_BYTES + 32].copy_from_slice(&height.to_le_bytes());
            bytes.extend_from_slice(&tail);
            bytes
        })
}

fn wire_input() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        1 => prop::collection::vec(any::<u8>(), 0..512),
        3 => header_then_noise(),
        2 => big_frame_begun(),
        4 => mutated(valid_messages()),
    ]
}

// ---------------------------------------------------------------------
// The message reader over an in-memory stream.

/// Hands out `data` at most `step` bytes per read, as a socket might.
struct Trickle<'a> {
    data: &'a [u8],
    step: usize,
}

impl AsyncRead for Trickle<'_> {
    fn poll_read(mut self: Pin<&mut Self>, _: &mut Context<'_>, buf: &mut ReadBuf<'_>) -> Poll<io::Result<()>> {
        let n = self.step.min(self.data.len()).min(buf.remaining());
        let (now, later) = self.data.split_at(n);
        buf.put_slice(now);
        self.data = later;
        Poll::Ready(Ok(()))
    }
}

/// Reads messages from `bytes` until the end or the first error, as the
/// daemon's links do; returns how many were read and the largest receive
/// buffer the reader held.
async fn read_all(bytes: &[u8], step: usize) -> (usize, usize) {
    let stream = Trickle { data: bytes, step };
    let deadline = MessageDeadline { base: Duration::from_secs(5), min_bytes_per_s: 1 << 20 };
    let mut reader = MessageReader::new(stream, Duration::from_secs(5), MAX_FRAME_BYTES).with_deadline(deadline);
    let mut read = 0;
    let mut largest_buffer = 0;
    // Every read consumes at least one byte, so this ends.
    for _ in 0..=bytes.len() {
        let result = reader.read().await;
        largest_buffer = largest_buffer.max(reader.buffer_capacity());
        match result {
            Ok(Some(_)) => read += 1,
            Ok(None) => break,
            Err(e) if e.framing_intact() => continue,
            Err(_) => break,
        }
    }
    (read, largest_buffer)
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn the_frame_decoder_never_panics_nor_allocates_beyond_its_input(bytes in wire_input()) {
        let (_, peak) = peak_allocation(|| {
            let _ = frame::decode(&bytes, MAX_FRAME_BYTES);
            if let Some(head) = bytes.get(..HEADER_BYTES) {
                let head: &[u8; HEADER_BYTES] = head.try_into().unwrap();
                if let Ok(header) = Header::parse(head, MAX_FRAME_BYTES) {
                    // The body decoder on whatever follows, however long.
                    let _ = frame::decode_body(header.tag, &bytes[HEADER_BYTES..]);
                }
            }
            let _ = frame::decode_frame_meta(&bytes);
        });
        let n = bytes.len();
        prop_assert!(peak <= allocation_bound(n), "{peak} bytes allocated for {n} bytes of input");
    }

    #[test]
    fn the_message_reader_never_panics_nor_allocates_beyond_its_input(
        bytes in wire_input(),
        step in prop_oneof![1..8usize, 8..4096usize, Just(usize::MAX)],
    ) {
        let runtime = tokio::runtime::Builder::new_current_thread().enable_time().build().unwrap();
        let ((_, largest_buffer), peak) = peak_allocation(|| runtime.block_on(read_all(&bytes, step)));
        prop_assert!(
            largest_buffer <= receive_buffer_bound(bytes.len()),
            "a {largest_buffer}-byte receive buffer for {} bytes of input", bytes.len()
        );
        let n = bytes.len();
        prop_assert!(peak <= allocation_bound(n), "{peak} bytes allocated for {n} bytes of input");
    }
}
