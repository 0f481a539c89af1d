//! The FANUC primitives `deploy/robots/fanuc/weldseam.kl` and
//! `WELD_SEAM.LS` use, emulated as documented, for their transcriptions
//! (`fanuc.rs`) to run on:
//!
//! - KAREL (FANUC "KAREL Reference Manual", MARRC75KR07091E, ch. 7 "File
//!   input/output operations", appendix A): socket messaging (option R648):
//!   `MSG_CONNECT(tag, status)` connects a client tag (status 0 when
//!   connected), `MSG_DISCO`; `OPEN FILE f ('RW', tag)`, `IO_STATUS(f)` (0
//!   after a good operation); `WRITE f(text, CR)` buffers the text and the
//!   CR item ends the line and sends the buffer; `READ f(s, CR)` reads a
//!   STRING up to the end of the line (LF, 10) into `s`, at most its
//!   declared length, and the CR item skips past the line's end, so a CR
//!   (13) before the LF stays in the string; a READ blocks until the line
//!   ends; `BYTES_AHEAD(f, n, status)` the bytes received and not yet
//!   read, without waiting (a connection the peer closed gives a non-zero
//!   status, HOST-213 "read direction shut down by peer", 67213);
//!   `DELAY(ms)`; `CNV_STR_REAL`/`CNV_STR_INT` leave the target
//!   uninitialized when the string is not a number (`UNINIT` tells);
//!   `CNV_REAL_STR(v, length, decimals, s)` and `CNV_INT_STR`; STRING
//!   functions `SUB_STR(s, start, length)`, `INDEX(s, pattern)` (0 when
//!   absent), `STR_LEN`; REAL is 32-bit; `SET_INT_REG(n, v, status)`,
//!   `SET_REAL_REG(n, v, status)`, `SET_POS_REG(n, xyzwpr, status)`; `GET_TPE_PRM(k, type, int, real,
//!   string, status)` (type 1 INTEGER; status non-zero without the
//!   argument); `CURPOS(0, 0, group)`: the TCP of the selected tool frame
//!   (`$MNUTOOLNUM[g]`, the frames in `$MNUTOOL[g, n]`) in the selected user
//!   frame (`$MNUFRAMENUM[g]`); POSITION `:` (relative, the right one in
//!   the left one's frame) and `INV`; `WRITE TPERROR(...)` the error line.
//! - TP (FANUC "Operator's Manual, ArcTool"): `R[n]`, `PR[n]` (a motion to
//!   a PR moves the selected tool to it in the selected user frame, its
//!   value taken when the motion statement executes), `UTOOL_NUM`,
//!   `UFRAME_NUM`, `CALL prog(args)`, `IF ..., JMP LBL[n]`, `SELECT`, `L
//!   ... mm/sec FINE` (stops at the point) and `CNT n` (blends into the
//!   next motion, which the look-ahead reads while this one runs), the
//!   speed a number or a register (`R[n]mm/sec`, read, as the PR, when
//!   the motion statement executes),
//!   `Arc Start[n]`, `Arc End[n]`, `UALM[n]` (a user alarm: the program
//!   pauses).
//! - ArcTool's weave, in the forms ArcTool programs write it (FANUC's own
//!   page for it was not at hand): `Weave Sine[n]` weaves every motion
//!   after it with weave schedule n, its frequency (Hz) and amplitude (mm)
//!   as the schedule holds them when that motion statement executes, until
//!   `Weave End`; `$WVSCH[n].$FREQUENCY` and `$WVSCH[n].$AMPLITUDE` are
//!   schedule n's figures, written from a register. Neither stops the
//!   look-ahead; a schedule rewritten while a blending motion still weaves
//!   with it would change that motion's weave under way.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use weldseam::geometry::Isometry3;
use weldseam::geometry::conventions::PoseConvention;

use super::harness::SendHook;
use super::robot::{Event, Trace};

/// KAREL's XYZWPR: X, Y, Z (mm), W, P, R (deg), REALs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Xyzwpr {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    pub w: f32,
    pub p: f32,
    pub r: f32,
}

impl Xyzwpr {
    pub fn numbers(&self) -> [f64; 6] {
        [self.x, self.y, self.z, self.w, self.p, self.r].map(f64::from)
    }

    pub fn of(iso: &Isometry3<f64>) -> Xyzwpr {
        let n = PoseConvention::FANUC.numbers(iso);
        Xyzwpr { x: n[0] as f32, y: n[1] as f32, z: n[2] as f32, w: n[3] as f32, p: n[4] as f32, r: n[5] as f32 }
    }

    pub fn isometry(&self) -> Isometry3<f64> {
        PoseConvention::FANUC.to_isometry(&self.numbers()).unwrap()
    }
}

/// A register's value: an INTEGER or a REAL.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Register {
    Int(i32),
    Real(f32),
}

impl Register {
    /// The value where the program keeps an integer (a line number, a
    /// kind, a code); a REAL there is the program's mistake.
    pub fn int(self) -> i32 {
        match self {
            Register::Int(v) => v,
            Register::Real(v) => panic!("R[] holds the REAL {v} where an INTEGER is read"),
        }
    }

    /// The value as a number, whichever it holds (a speed, a comparison).
    pub fn value(self) -> f64 {
        match self {
            Register::Int(v) => f64::from(v),
            Register::Real(v) => f64::from(v),
        }
    }
}

/// A socket messaging client tag's file.
pub struct SockFile {
    stream: TcpStream,
    received: Vec<u8>,
    closed: bool,
    pub io_status: i32,
}

/// The status BYTES_AHEAD and READ give once the peer closed.
pub const HOST_213: i32 = 67213;

/// How long a READ waits for the rest of a line before the emulation
/// calls it a hang: the daemon writes each line at once.
const READ_HANG: Duration = Duration::from_secs(30);

impl SockFile {
    /// Takes what has arrived without waiting.
    fn pull(&mut self) {
        self.stream.set_nonblocking(true).unwrap();
        let mut chunk = [0u8; 4096];
        loop {
            match self.stream.read(&mut chunk) {
                Ok(0) => {
                    self.closed = true;
                    break;
                }
                Ok(n) => self.received.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                Err(_) => {
                    self.closed = true;
                    break;
                }
            }
        }
        self.stream.set_nonblocking(false).unwrap();
    }
}

/// The controller: registers, position registers, frames, the robot, the
/// open socket file, and the record of the run.
pub struct Controller {
    pub r: Vec<Register>,
    pub pr: Vec<Xyzwpr>,
    pub utool_num: usize,
    pub uframe_num: usize,
    /// `$MNUTOOL[1, n]`: tool frames 1..10 (index 0 unused).
    pub tools: Vec<Isometry3<f64>>,
    /// The flange in the world frame.
    pub flange: Isometry3<f64>,
    /// Where client tag C3 connects.
    pub address: String,
    pub sock: Option<SockFile>,
    pub trace: Trace,
    /// TP arguments of the KAREL program being called.
    pub tpe_params: Vec<i32>,
    pub tperror: Vec<String>,
    pub alarms: Vec<usize>,
    /// Called with each line before it is sent (a scenario's fault).
    pub on_send: Option<SendHook>,
    /// The PR the last motion goes to when it asked to blend (CNT): the
    /// robot is still on its way there while the program runs on, so
    /// writing that PR would change a move under way.
    pub blending_to: Option<usize>,
    /// Weave schedules 1..10 (index 0 unused): `$AMPLITUDE` (mm) and
    /// `$FREQUENCY` (Hz).
    pub wvsch: Vec<[f64; 2]>,
    /// The schedule `Weave Sine[n]` set, until `Weave End`.
    pub weaving: Option<usize>,
    /// The schedule the last motion weaves with when it asked to blend:
    /// it is still under way while the program runs on.
    blending_weave: Option<usize>,
    /// The weave laid on each motion statement, as (amplitude mm,
    /// frequency Hz); `None` where the motion does not weave.
    pub weave_at_moves: Vec<Option<[f64; 2]>>,
}

impl Controller {
    pub fn new(address: &str, flange: Isometry3<f64>, torch: Isometry3<f64>) -> Controller {
        let mut tools = vec![Isometry3::identity(); 11];
        tools[1] = torch;
        let mut trace = Trace::default();
        trace.look_ahead = true;
        Controller {
            r: vec![Register::Int(0); 201],
            pr: vec![Xyzwpr::default(); 101],
            utool_num: 0,
            uframe_num: 0,
            tools,
            flange,
            address: address.to_string(),
            sock: None,
            trace,
            tpe_params: Vec::new(),
            tperror: Vec::new(),
            alarms: Vec::new(),
            on_send: None,
            blending_to: None,
            wvsch: vec![[0.0; 2]; 11],
            weaving: None,
            blending_weave: None,
            weave_at_moves: Vec::new(),
        }
    }

    /// Tags a statement of either program: the KAREL helper's tags are
    /// `k.at`, the TP program's `tp.at`.
    pub fn at(&mut self, line: usize, _text: &str) {
        self.trace.statement(line);
    }

    pub fn msg_connect(&mut self, _tag: &str) -> i32 {
        match TcpStream::connect(&self.address) {
            Ok(stream) => {
                self.sock = Some(SockFile { stream, received: Vec::new(), closed: false, io_status: 0 });
                0
            }
            Err(_) => 67231,
        }
    }

    pub fn msg_disco(&mut self, _tag: &str) -> i32 {
        if let Some(s) = self.sock.take() {
            let _ = s.stream.shutdown(std::net::Shutdown::Both);
        }
        0
    }

    /// `OPEN FILE f ('RW', tag)`: the file of a connected tag.
    pub fn open_file(&mut self) {
        if let Some(s) = self.sock.as_mut() {
            s.io_status = 0;
        }
    }

    pub fn io_status(&self) -> i32 {
        self.sock.as_ref().map_or(2014, |s| s.io_status)
    }

    pub fn close_file(&mut self) {}

    /// `WRITE f(text, CR)`: the CR item ends the line (written as CR) and
    /// sends it.
    pub fn write_line(&mut self, text: &str) {
        if let Some(hook) = self.on_send.as_mut() {
            hook(text);
        }
        self.trace.push(Event::Sent(text.to_string()));
        if let Some(s) = self.sock.as_mut() {
            s.io_status = match s.stream.write_all(format!("{text}\r").as_bytes()) {
                Ok(()) => 0,
                Err(_) => HOST_213,
            };
        }
    }

    /// `BYTES_AHEAD(f, n, status)`.
    pub fn bytes_ahead(&mut self) -> (i32, i32) {
        let Some(s) = self.sock.as_mut() else { return (0, 2014) };
        s.pull();
        if s.received.is_empty() && s.closed {
            return (0, HOST_213);
        }
        (s.received.len() as i32, 0)
    }

    /// `READ f(s, CR)` into a STRING[`length`].
    pub fn read_line(&mut self, length: usize) -> String {
        let Some(s) = self.sock.as_mut() else { return String::new() };
        let started = std::time::Instant::now();
        loop {
            if let Some(end) = s.received.iter().position(|b| *b == b'\n') {
                let line: Vec<u8> = s.received.drain(..=end).take(end).collect();
                let text = String::from_utf8_lossy(&line[..line.len().min(length)]).into_owned();
                s.io_status = 0;
                self.trace.push(Event::Read(text.clone()));
                return text;
            }
            if s.closed || started.elapsed() > READ_HANG {
                s.io_status = HOST_213;
                return String::new();
            }
            s.pull();
            if !s.closed {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
    }

    /// `SET_INT_REG(n, v, status)`.
    pub fn set_int_reg(&mut self, n: usize, value: i32) {
        self.r[n] = Register::Int(value);
    }

    /// `SET_REAL_REG(n, v, status)`.
    pub fn set_real_reg(&mut self, n: usize, value: f32) {
        self.r[n] = Register::Real(value);
    }

    /// `SET_POS_REG(n, posn, status)`; never the target of the move still
    /// blending.
    pub fn set_pos_reg(&mut self, n: usize, pose: Xyzwpr) {
        assert_ne!(self.blending_to, Some(n), "PR[{n}] rewritten while the robot blends towards it");
        self.pr[n] = pose;
    }

    /// `GET_TPE_PRM(k, ...)`: (type, value, status).
    pub fn get_tpe_prm(&self, k: usize) -> (i32, i32, i32) {
        match self.tpe_params.get(k - 1) {
            Some(v) => (1, *v, 0),
            None => (0, 0, 17042),
        }
    }

    /// `CURPOS(0, 0, 1)`: the TCP of the selected tool in the selected
    /// user frame (only the world frame, 0, is emulated).
    pub fn curpos(&self) -> Isometry3<f64> {
        assert_eq!(self.uframe_num, 0, "CURPOS in a user frame is not emulated");
        let tool = if self.utool_num == 0 { Isometry3::identity() } else { self.tools[self.utool_num] };
        self.flange * tool
    }

    /// `L PR[n] speed FINE|CNT`: moves the selected tool to the PR's
    /// value as it is now.
    pub fn linear(&mut self, line: usize, pr: usize, speed_mm_s: f64, cnt: bool) {
        assert!(speed_mm_s > 0.0, "line {line}: a motion at {speed_mm_s} mm/sec");
        let target = self.pr[pr];
        self.blending_to = cnt.then_some(pr);
        self.blending_weave = if cnt { self.weaving } else { None };
        self.weave_at_moves.push(self.weaving.map(|n| self.wvsch[n]));
        self.trace.motion(line, target.numbers(), speed_mm_s, cnt);
        let tool = if self.utool_num == 0 { Isometry3::identity() } else { self.tools[self.utool_num] };
        self.flange = target.isometry() * tool.inverse();
    }
}

impl Controller {
    /// `$WVSCH[n].$AMPLITUDE=R[..]` (`field` 0) or `$WVSCH[n].$FREQUENCY=R[..]`
    /// (`field` 1); never the schedule of the motion still blending.
    pub fn set_weave_schedule(&mut self, n: usize, field: usize, value: f64) {
        assert_ne!(self.blending_weave, Some(n), "weave schedule {n} rewritten while a motion still weaves with it");
        self.wvsch[n][field] = value;
    }

    /// `Weave Sine[n]`: the motions from here on weave with schedule n,
    /// which must hold a weave (a swing and a frequency over 0).
    pub fn weave_sine(&mut self, line: usize, n: usize) {
        let [amplitude, frequency] = self.wvsch[n];
        assert!(amplitude > 0.0 && frequency > 0.0, "line {line}: Weave Sine[{n}] at {amplitude} mm, {frequency} Hz");
        self.weaving = Some(n);
    }

    /// `Weave End`: the motions from here on do not weave.
    pub fn weave_end(&mut self) {
        self.weaving = None;
    }
}

/// `CNV_STR_REAL(s, v)`: a sign, digits, a point and digits, an exponent;
/// anything else (a CR, a letter) leaves `v` uninitialized (`None`).
pub fn cnv_str_real(s: &str) -> Option<f32> {
    let t = s.trim_matches(' ');
    let ok = !t.is_empty()
        && t.chars().all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E'))
        && t.chars().any(|c| c.is_ascii_digit());
    if ok { t.parse().ok() } else { None }
}

/// `CNV_STR_INT(s, v)`.
pub fn cnv_str_int(s: &str) -> Option<i32> {
    let t = s.trim_matches(' ');
    if !t.is_empty() && t.chars().all(|c| c.is_ascii_digit() || c == '-' || c == '+') { t.parse().ok() } else { None }
}

/// `CNV_REAL_STR(v, length, decimals, s)`: at least `length` characters.
pub fn cnv_real_str(v: f32, length: usize, decimals: usize) -> String {
    format!("{v:>length$.decimals$}")
}

/// `CNV_INT_STR(v, length, base 10, s)`.
pub fn cnv_int_str(v: i32, length: usize) -> String {
    format!("{v:>length$}")
}

/// `SUB_STR(s, start, length)`: from the 1-based `start`, at most `length`
/// characters (an empty string past the end).
pub fn sub_str(s: &str, start: i32, length: i32) -> String {
    let start = (start.max(1) - 1) as usize;
    s.chars().skip(start).take(length.max(0) as usize).collect()
}

/// `INDEX(s, pattern)`: the 1-based position of the first match, or 0.
pub fn index(s: &str, pattern: &str) -> i32 {
    s.find(pattern).map_or(0, |k| k as i32 + 1)
}

pub fn str_len(s: &str) -> i32 {
    s.chars().count() as i32
}

/// The conversions as documented: a CR left by a CR LF line end makes the
/// last field no REAL (the failure of a CR LF reply), a plain number is
/// read, a field width pads on the left.
#[test]
fn karel_conversions_refuse_a_stray_cr() {
    assert_eq!(cnv_str_real("13\r"), None);
    assert_eq!(cnv_str_real("-244.000"), Some(-244.0));
    assert_eq!(cnv_str_int("44"), Some(44));
    assert_eq!(cnv_str_int("4x"), None);
    assert_eq!(cnv_real_str(-1.5, 1, 3), "-1.500");
    assert_eq!(sub_str("-44,no frame", 2, index("-44,no frame", ",") - 2), "44");
}
