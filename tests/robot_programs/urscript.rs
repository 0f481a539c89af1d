//! An emulated Universal Robots controller: exactly the URScript
//! functions deploy/robots/ur/weld_seam.script calls, with the semantics
//! the URScript manual gives them (Universal Robots, "The URScript
//! Programming Language", e-Series 5.x: module interfaces for the socket
//! functions, module motion for movel/movep, module urmath for norm and
//! make_list, module interfaces for set_standard_digital_out and popup),
//! on a real TCP socket to the daemon; and the record of what the program
//! did: the statements run, lines sent and read, motions and the arc.

use std::collections::HashMap;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use weldseam::geometry::Isometry3;
use weldseam::geometry::conventions::PoseConvention;
use weldseam::geometry::pose::EulerConvention;

use super::harness::SendHook;

/// `socket_read_ascii_float` reads at most this many numbers (manual:
/// "A maximum of 30 values can be read in one command").
pub const MAX_FLOATS: usize = 30;

/// A URScript pose: x, y, z in metres and a rotation vector in radians.
pub type Pose = [f64; 6];

/// One thing the program did, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    Statement(usize),
    Sent(String),
    /// A socket read and the bytes it took.
    Read(String),
    Move(Move),
    Output {
        pin: u32,
        on: bool,
    },
    Sleep,
    Popup(String),
    Halt,
}

/// A commanded motion of the TCP.
#[derive(Debug, Clone, PartialEq)]
pub struct Move {
    pub line: usize,
    pub process: bool,
    /// The TCP's target in the base frame, mm.
    pub target: Isometry3<f64>,
    pub speed: f64,
    pub blend: f64,
    /// The controller blends this motion into the next one: a blend radius
    /// and nothing that waits (a read, a sleep, a popup) before the next
    /// motion.
    pub blended: bool,
}

struct Socket {
    stream: TcpStream,
    buffer: Vec<u8>,
}

/// The emulated controller.
pub struct Ur {
    pub events: Vec<Event>,
    sockets: HashMap<String, Socket>,
    /// The flange in the base frame at the program's start, mm.
    pub flange: Isometry3<f64>,
    /// The TCP (the torch tip) in the flange frame, mm.
    pub tcp: Isometry3<f64>,
    /// Called with each line before it is sent.
    pub on_send: Option<SendHook>,
    /// Problems the real controller would stop the program for.
    pub faults: Vec<String>,
    /// The motion that may still blend into the next, by index in `events`.
    pending: Option<usize>,
}

fn iso(pose: &Pose) -> Isometry3<f64> {
    PoseConvention::UR.to_robot_pose(pose, EulerConvention::default()).unwrap().to_isometry(EulerConvention::default())
}

impl Ur {
    pub fn new(flange: Isometry3<f64>, tcp: Isometry3<f64>) -> Ur {
        Ur {
            events: Vec::new(),
            sockets: HashMap::new(),
            flange,
            tcp,
            on_send: None,
            faults: Vec::new(),
            pending: None,
        }
    }

    /// A statement of the program file runs: its line and text (the text
    /// is for the transcription checker).
    pub fn at(&mut self, line: usize, text: &str) {
        let _ = text;
        self.events.push(Event::Statement(line));
    }

    fn waited(&mut self, event: Event) {
        self.pending = None;
        self.events.push(event);
    }

    /// `socket_open(address, port, socket_name)`: True when connected,
    /// False when not (manual: "Returns False if failed").
    pub fn socket_open(&mut self, address: &str, port: f64, name: &str) -> bool {
        let Ok(addr) = format!("{address}:{port}").parse() else { return false };
        match TcpStream::connect_timeout(&addr, Duration::from_secs(2)) {
            Ok(stream) => {
                self.sockets.insert(name.into(), Socket { stream, buffer: Vec::new() });
                true
            }
            Err(_) => false,
        }
    }

    /// `socket_send_line(str, socket_name)`: the string and a newline;
    /// False when the socket is not open or the send fails.
    pub fn socket_send_line(&mut self, text: &str, name: &str) -> bool {
        if let Some(hook) = self.on_send.as_mut() {
            hook(text);
        }
        self.events.push(Event::Sent(text.into()));
        let Some(socket) = self.sockets.get_mut(name) else { return false };
        socket.stream.write_all(format!("{text}\n").as_bytes()).is_ok()
    }

    /// Reads until `done` finds what it needs in the buffer, the peer
    /// closes or `timeout` seconds pass; returns whether `done` did.
    fn fill(&mut self, name: &str, timeout: f64, done: impl Fn(&[u8]) -> bool) -> bool {
        let Some(socket) = self.sockets.get_mut(name) else { return false };
        let until = Instant::now() + Duration::from_secs_f64(timeout);
        while !done(&socket.buffer) {
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return false;
            }
            let _ = socket.stream.set_read_timeout(Some(left));
            let mut chunk = [0u8; 512];
            match socket.stream.read(&mut chunk) {
                Ok(0) => return false,
                Ok(n) => socket.buffer.extend_from_slice(&chunk[..n]),
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => return false,
                Err(_) => return false,
            }
        }
        true
    }

    fn take(&mut self, name: &str, through: usize) -> String {
        let socket = self.sockets.get_mut(name).expect("an open socket");
        let taken: Vec<u8> = socket.buffer.drain(..through).collect();
        String::from_utf8_lossy(&taken).into_owned()
    }

    /// `socket_read_ascii_float(number, socket_name, timeout)`: one list
    /// `(n1, n2, ...)` of at most `number` (at most 30) numbers. Returns
    /// `[count, n1, ...]`, or `[0, nan...]` on a timeout, a closed socket
    /// or a list it cannot read. Whitespace before the `(` is passed over
    /// (the LF a previous list left); the read ends at `)`, so the LF after
    /// it stays in the buffer.
    pub fn socket_read_ascii_float(&mut self, number: usize, name: &str, timeout: f64) -> Vec<f64> {
        self.pending = None;
        let failed = std::iter::once(0.0).chain(std::iter::repeat_n(f64::NAN, number)).collect::<Vec<_>>();
        if number > MAX_FLOATS {
            return failed;
        }
        let closed = |b: &[u8]| {
            let start = b.iter().position(|c| !c.is_ascii_whitespace());
            start.is_some_and(|s| b[s] != b'(' || b[s..].contains(&b')'))
        };
        if !self.fill(name, timeout, closed) {
            self.waited(Event::Read(String::new()));
            return failed;
        }
        let buffer = &self.sockets[name].buffer;
        let start = buffer.iter().position(|c| !c.is_ascii_whitespace()).unwrap();
        if buffer[start] != b'(' {
            let taken = self.take(name, start + 1);
            self.waited(Event::Read(taken));
            return failed;
        }
        let end = start + buffer[start..].iter().position(|c| *c == b')').unwrap();
        let taken = self.take(name, end + 1);
        self.waited(Event::Read(taken.clone()));
        let body = taken.trim_start().trim_start_matches('(').trim_end_matches(')');
        let values: Option<Vec<f64>> = body.split(',').map(|v| v.trim().parse::<f64>().ok()).collect();
        match values {
            Some(values) if values.len() <= number => std::iter::once(values.len() as f64).chain(values).collect(),
            _ => failed,
        }
    }

    /// `socket_read_line(socket_name, timeout)`: the bytes up to the next
    /// LF (or CR LF), without it; `""` on a timeout or a closed socket.
    pub fn socket_read_line(&mut self, name: &str, timeout: f64) -> String {
        if !self.fill(name, timeout, |b| b.contains(&b'\n')) {
            self.waited(Event::Read(String::new()));
            return String::new();
        }
        let end = self.sockets[name].buffer.iter().position(|c| *c == b'\n').unwrap();
        let taken = self.take(name, end + 1);
        self.waited(Event::Read(taken.clone()));
        taken.trim_end_matches('\n').trim_end_matches('\r').to_string()
    }

    pub fn socket_close(&mut self, name: &str) {
        self.sockets.remove(name);
    }

    /// `get_actual_tool_flange_pose()`: the flange, whatever the TCP.
    pub fn get_actual_tool_flange_pose(&self) -> Pose {
        let numbers = PoseConvention::UR.numbers(&self.flange);
        [numbers[0], numbers[1], numbers[2], numbers[3], numbers[4], numbers[5]]
    }

    fn motion(&mut self, line: usize, process: bool, pose: &Pose, speed: f64, blend: f64) {
        let target = iso(pose);
        if let Some(k) = self.pending.take()
            && let Event::Move(previous) = &mut self.events[k]
        {
            previous.blended = true;
        }
        // A blend radius must not reach past half the segment before or
        // after it (the controller stops with a blend overlap).
        let before = self.events.iter().rev().find_map(|e| match e {
            Event::Move(m) => Some(m.clone()),
            _ => None,
        });
        if let Some(previous) = &before {
            let segment = (target.translation.vector - previous.target.translation.vector).norm() / 1000.0;
            if previous.blend > 0.5 * segment + 1e-12 || blend > 0.5 * segment + 1e-12 {
                self.faults.push(format!("line {line}: a blend radius over half a {segment:.5} m segment"));
            }
        }
        self.events.push(Event::Move(Move { line, process, target, speed, blend, blended: false }));
        if blend > 0.0 {
            self.pending = Some(self.events.len() - 1);
        }
        self.flange = target * self.tcp.inverse();
    }

    /// `movel(pose, a, v, r)`: linear in tool space to the TCP pose.
    pub fn movel(&mut self, line: usize, pose: &Pose, _a: f64, v: f64, r: f64) {
        self.motion(line, false, pose, v, r);
    }

    /// `movep(pose, a, v, r)`: a process move at constant tool speed,
    /// blended with radius `r`.
    pub fn movep(&mut self, line: usize, pose: &Pose, _a: f64, v: f64, r: f64) {
        self.motion(line, true, pose, v, r);
    }

    pub fn set_standard_digital_out(&mut self, pin: f64, on: bool) {
        self.events.push(Event::Output { pin: pin as u32, on });
    }

    pub fn sleep(&mut self, _seconds: f64) {
        self.waited(Event::Sleep);
    }

    pub fn popup(&mut self, text: &str) {
        self.waited(Event::Popup(text.into()));
    }

    pub fn halt(&mut self) {
        self.waited(Event::Halt);
    }
}

/// `to_str(pose)`: `p[x, y, z, rx, ry, rz]`. The manual does not fix the
/// digits; six decimals (1 µm, 1 µrad) with trailing zeros cut is assumed.
pub fn pose_to_str(p: &Pose) -> String {
    let each: Vec<String> = p
        .iter()
        .map(|v| {
            let s = format!("{v:.6}");
            let s = s.trim_end_matches('0').trim_end_matches('.');
            if s == "-0" { "0".to_string() } else { s.to_string() }
        })
        .collect();
    format!("p[{}]", each.join(", "))
}

/// `to_str(integer)`.
pub fn int_to_str(v: f64) -> String {
    format!("{}", v as i64)
}

/// `norm(number)`: its absolute value.
/// `point_dist(p_from, p_to)`: the distance between two poses'
/// positions, m.
pub fn point_dist(a: &Pose, b: &Pose) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

pub fn norm(v: f64) -> f64 {
    v.abs()
}

/// Whether a line of a URScript file is a statement (not blank, not a
/// comment, not a block's `end` or `else:`).
pub fn is_statement(line: &str) -> bool {
    !line.is_empty() && !line.starts_with('#') && line != "end" && line != "else:"
}
