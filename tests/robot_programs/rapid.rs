//! An emulated ABB controller: exactly the RAPID instructions and
//! functions deploy/robots/abb/WeldSeam.mod uses, with the semantics of
//! ABB's "Technical reference manual - RAPID Instructions, Functions and
//! Data types" (RobotWare 6): SocketCreate/SocketConnect/SocketSend/
//! SocketReceive (socket option 616-1; `\Str` strings of at most 80
//! characters, `\Time` raising ERR_SOCK_TIMEOUT, a closed peer
//! ERR_SOCK_CLOSED), StrFind/StrPart/StrLen/StrToVal/NumToStr, a string
//! longer than 80 characters a run-time error, CRobT, MoveL with zonedata
//! (`fine` a stop point, a zone a fly-by point), TPWrite and Stop; and
//! ArcWare's ArcLStart (the arc struck at the end of its motion), ArcL
//! and ArcLEnd (the arc ended at its point), from the "Application
//! manual - Arc and Arc Sensor". Plus the record of what the program did.

use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use weldseam::geometry::Isometry3;
use weldseam::geometry::conventions::PoseConvention;
use weldseam::geometry::pose::EulerConvention;
use weldseam::mock::text_robot::rapid_num;

use super::harness::SendHook;

/// The longest RAPID string.
pub const MAX_STRING: usize = 80;

/// A robtarget's position and orientation (mm, quaternion q1..q4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobTarget {
    pub trans: [f64; 3],
    pub rot: [f64; 4],
}

/// A RAPID run-time error a routine's ERROR handler sees as ERRNO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Errno {
    SockTimeout,
    SockClosed,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    Statement(usize),
    Sent(String),
    Read(String),
    Move(Move),
    ArcOn,
    ArcOff,
    TpWrite(String),
    Stop,
}

/// A commanded motion of the TCP.
#[derive(Debug, Clone, PartialEq)]
pub struct Move {
    pub line: usize,
    pub target: Isometry3<f64>,
    /// mm/s: the speeddata's, or under the arc the welddata's weld_speed.
    pub speed: f64,
    /// The zone's radius, None for `fine`.
    pub zone: Option<f64>,
    pub welding: bool,
    /// ArcWare's weave under the arc (`\Weave:=`), as its width and
    /// cycle length, mm; None without one.
    pub weave: Option<[f64; 2]>,
    /// A fly-by point the robot passes without stopping: a zone, and
    /// nothing that waits before the next motion.
    pub blended: bool,
}

pub struct Rapid {
    pub events: Vec<Event>,
    socket: Option<TcpStream>,
    pub flange: Isometry3<f64>,
    pub on_send: Option<SendHook>,
    pending: Option<usize>,
    arc: bool,
}

fn iso(t: &RobTarget) -> Isometry3<f64> {
    let n = [t.trans[0], t.trans[1], t.trans[2], t.rot[0], t.rot[1], t.rot[2], t.rot[3]];
    PoseConvention::ABB.to_robot_pose(&n, EulerConvention::default()).unwrap().to_isometry(EulerConvention::default())
}

impl Rapid {
    pub fn new(flange: Isometry3<f64>) -> Rapid {
        Rapid { events: Vec::new(), socket: None, flange, on_send: None, pending: None, arc: false }
    }

    pub fn at(&mut self, line: usize, text: &str) {
        let _ = text;
        self.events.push(Event::Statement(line));
    }

    fn waited(&mut self, event: Event) {
        self.pending = None;
        self.events.push(event);
    }

    pub fn socket_create(&mut self) {
        self.socket = None;
    }

    /// `SocketConnect`: a refused or unreachable peer raises an error
    /// (the program maps any error before it is connected to "no
    /// connection").
    pub fn socket_connect(&mut self, address: &str, port: f64, time: f64) -> Result<(), Errno> {
        let addr = format!("{address}:{port}").parse().map_err(|_| Errno::SockClosed)?;
        let stream =
            TcpStream::connect_timeout(&addr, Duration::from_secs_f64(time)).map_err(|_| Errno::SockTimeout)?;
        self.socket = Some(stream);
        Ok(())
    }

    /// `SocketSend \Str`: the string as it is (no line end of its own).
    pub fn socket_send(&mut self, text: &str) -> Result<(), Errno> {
        assert!(text.len() <= MAX_STRING, "a string over 80 characters: {text:?}");
        if let Some(hook) = self.on_send.as_mut() {
            hook(text);
        }
        self.events.push(Event::Sent(text.into()));
        let socket = self.socket.as_mut().ok_or(Errno::SockClosed)?;
        socket.write_all(text.as_bytes()).map_err(|_| Errno::SockClosed)
    }

    /// `SocketReceive \Str \Time`: waits for data and returns what has
    /// arrived, at most 80 characters; ERR_SOCK_TIMEOUT after `time`
    /// seconds with none, ERR_SOCK_CLOSED when the peer has closed.
    pub fn socket_receive(&mut self, time: f64) -> Result<String, Errno> {
        self.pending = None;
        let socket = self.socket.as_mut().ok_or(Errno::SockClosed)?;
        let mut chunk = [0u8; MAX_STRING];
        let _ = socket.set_read_timeout(Some(Duration::from_secs_f64(time)));
        match socket.read(&mut chunk) {
            Ok(0) => {
                self.waited(Event::Read(String::new()));
                Err(Errno::SockClosed)
            }
            Ok(n) => {
                let text = String::from_utf8_lossy(&chunk[..n]).into_owned();
                self.waited(Event::Read(text.clone()));
                Ok(text)
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => Err(Errno::SockTimeout),
            Err(_) => Err(Errno::SockClosed),
        }
    }

    pub fn socket_close(&mut self) {
        self.socket = None;
    }

    /// `CRobT(\Tool:=tool0 \WObj:=wobj0)`: the flange.
    pub fn crobt_flange(&self) -> RobTarget {
        let n = PoseConvention::ABB.numbers(&self.flange);
        RobTarget { trans: [n[0], n[1], n[2]], rot: [n[3], n[4], n[5], n[6]] }
    }

    fn motion(&mut self, line: usize, target: &RobTarget, speed: f64, zone: Option<f64>, welding: bool) {
        self.woven(line, target, speed, zone, welding, None);
    }

    fn woven(
        &mut self,
        line: usize,
        target: &RobTarget,
        speed: f64,
        zone: Option<f64>,
        welding: bool,
        weave: Option<[f64; 2]>,
    ) {
        if let Some(k) = self.pending.take()
            && let Event::Move(previous) = &mut self.events[k]
        {
            previous.blended = true;
        }
        let target = iso(target);
        self.events.push(Event::Move(Move { line, target, speed, zone, welding, weave, blended: false }));
        if zone.is_some() {
            self.pending = Some(self.events.len() - 1);
        }
    }

    /// `MoveL target, speed, zone, tool`: `zone` None is `fine`.
    pub fn move_l(&mut self, line: usize, target: &RobTarget, speed: f64, zone: Option<f64>) {
        assert!(!self.arc, "line {line}: MoveL with the arc on");
        self.motion(line, target, speed, zone, false);
    }

    /// `ArcLStart`: moves (not welding) and strikes the arc at the point.
    pub fn arc_l_start(&mut self, line: usize, target: &RobTarget, speed: f64, zone: Option<f64>) {
        self.motion(line, target, speed, zone, false);
        self.arc = true;
        self.waited(Event::ArcOn);
    }

    /// `ArcL`: welds to the point at the welddata's weld speed, weaving
    /// as its `\Weave` says.
    pub fn arc_l(
        &mut self,
        line: usize,
        target: &RobTarget,
        weld_speed: f64,
        zone: Option<f64>,
        weave: Option<[f64; 2]>,
    ) {
        assert!(self.arc, "line {line}: ArcL without ArcLStart");
        self.woven(line, target, weld_speed, zone, true, weave);
    }

    /// `ArcLEnd`: welds to the point and ends the arc there.
    pub fn arc_l_end(
        &mut self,
        line: usize,
        target: &RobTarget,
        weld_speed: f64,
        zone: Option<f64>,
        weave: Option<[f64; 2]>,
    ) {
        assert!(self.arc, "line {line}: ArcLEnd without ArcLStart");
        self.woven(line, target, weld_speed, zone, true, weave);
        self.arc = false;
        self.events.push(Event::ArcOff);
    }

    pub fn tp_write(&mut self, text: &str) {
        self.waited(Event::TpWrite(text.into()));
    }

    pub fn stop(&mut self) {
        self.waited(Event::Stop);
    }
}

/// `a + b` on strings: a result over 80 characters is a run-time error
/// that stops the program.
pub fn cat(a: &str, b: &str) -> String {
    let joined = format!("{a}{b}");
    assert!(joined.len() <= MAX_STRING, "string too long ({} characters): {joined:?}", joined.len());
    joined
}

/// `StrFind(Str, ChPos, Set)`: the first position from `ch_pos` (from 1)
/// of a character of `set`, or StrLen + 1.
pub fn str_find(s: &str, ch_pos: f64, set: &str) -> f64 {
    let from = ch_pos as usize;
    assert!(from >= 1 && from <= s.len() + 1, "StrFind position {from} outside {s:?}");
    s.bytes().enumerate().skip(from - 1).find(|(_, b)| set.as_bytes().contains(b)).map_or(s.len() + 1, |(k, _)| k + 1)
        as f64
}

/// `StrPart(Str, ChPos, Len)`: a run-time error outside the string.
pub fn str_part(s: &str, ch_pos: f64, len: f64) -> String {
    let (from, len) = (ch_pos as usize, len as usize);
    assert!(from >= 1 && from - 1 + len <= s.len(), "StrPart({s:?}, {from}, {len}) outside the string");
    s[from - 1..from - 1 + len].to_string()
}

/// `StrToVal(Str, Val)` for a num: TRUE and the value for a RAPID num
/// literal.
pub fn str_to_val(s: &str) -> Option<f64> {
    rapid_num(s).then(|| s.parse().unwrap())
}

/// `NumToStr(Val, Dec)`: rounded to `dec` decimals.
pub fn num_to_str(v: f64, dec: usize) -> String {
    let s = format!("{v:.dec$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

/// Whether a line of a RAPID module is a statement (not blank, not a
/// comment, not a block's end or `ELSE`, not the `ERROR` label).
pub fn is_statement(line: &str) -> bool {
    let word = line.split([' ', ';']).next().unwrap_or("");
    !line.is_empty()
        && !line.starts_with('!')
        && !matches!(word, "ENDIF" | "ENDWHILE" | "ENDFOR" | "ENDPROC" | "ENDFUNC" | "ENDMODULE" | "ELSE" | "ERROR")
}
