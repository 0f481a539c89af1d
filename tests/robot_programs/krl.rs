//! The KUKA primitives `deploy/robots/kuka/WeldSeam.src` uses, emulated as
//! documented, for its transcription (`kuka.rs`) to run on:
//!
//! - KUKA.Ethernet KRL (KST EthernetKRL 2.2, 2012, and 3.0, 2017): the XML
//!   channel file (`EXTERNAL` IP/PORT/TYPE, where TYPE names the external
//!   system's role; `INTERNAL` BUFFERING Limit 1..512 default 16,
//!   BUFFSIZE Limit default 16384 bytes, TIMEOUT Connect, ALIVE Set_Flag:
//!   the flag is TRUE while the connection stands); a RAW `STREAM` element
//!   received up to its end string `EOS` (the end string is not part of the
//!   data), at most `Size` bytes, whose `Set_Flag` sets `$FLAG[n]` when an
//!   element has arrived; `EKI_Init` reads the file, `EKI_Open` connects,
//!   `EKI_Send` with a CHAR array sends it as it is (up to its first NUL),
//!   `EKI_GetString` takes the oldest element (FIFO) and returns
//!   `EKI_STATUS` with `Buff` (elements left), `Read`, `Msg_No` (0, or
//!   the error's number) and `Connected`; `EKI_Close`, `EKI_Clear`.
//!   EKI functions are executed in the advance run; they never block.
//! - KRL (KSS 8 "Operating and Programming Instructions for System
//!   Integrators"): `$FLAG[1..1024]`; `$TIMER[n]` in ms, counting while
//!   `$TIMER_STOP[n]` is FALSE, `$TIMER_FLAG[n]` TRUE once `$TIMER[n]` >= 0;
//!   `WAIT FOR` stops the advance run until its condition holds (checked
//!   every interpolation cycle, 12 ms); `SREAD`/`SWRITE` with `%d`, `%f`,
//!   `%.nf`, `%s`, `%c`, returning a `STATE_T` whose `HITS` counts the
//!   items read or written; CHAR arrays of a fixed size (`StrClear` sets
//!   every element to 0); REAL is 32-bit; `LIN ... C_DIS` blends at
//!   `$APO.CDIS` mm only when the advance run (`$ADVANCE`, 0..5) has
//!   planned the next motion: an instruction that stops the advance run
//!   (WAIT, an `$OUT` assignment without CONTINUE, a read of `$POS_ACT`)
//!   makes the robot stop exactly at the motion before it.

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use weldseam::geometry::Isometry3;
use weldseam::geometry::conventions::PoseConvention;

use super::harness::SendHook;
use super::robot::{Event, Trace};

/// The interpolation cycle: how often a WAIT FOR condition is looked at.
const IPO_CYCLE: Duration = Duration::from_millis(12);

/// A KRL `CHAR name[size]`.
#[derive(Clone, Debug)]
pub struct Chars(pub Vec<u8>);

impl Chars {
    pub fn new(size: usize) -> Chars {
        Chars(vec![0; size])
    }

    /// `StrClear(name[])`.
    pub fn clear(&mut self) {
        self.0.fill(0);
    }

    /// `name[] = "text"`: the characters from the first element; the rest
    /// keeps what it held (a text longer than the array is an error).
    pub fn assign(&mut self, text: &str) {
        assert!(text.len() <= self.0.len(), "{text:?} does not fit CHAR[{}]", self.0.len());
        self.0[..text.len()].copy_from_slice(text.as_bytes());
    }

    /// The characters up to the first NUL.
    pub fn text(&self) -> String {
        let end = self.0.iter().position(|b| *b == 0).unwrap_or(self.0.len());
        String::from_utf8_lossy(&self.0[..end]).into_owned()
    }
}

/// A KRL `E6POS`'s Cartesian part: X, Y, Z (mm), A, B, C (deg), REALs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct E6Pos {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    pub a: f32,
    pub b: f32,
    pub c: f32,
}

impl E6Pos {
    pub fn numbers(&self) -> [f64; 6] {
        [self.x, self.y, self.z, self.a, self.b, self.c].map(f64::from)
    }

    pub fn of(iso: &Isometry3<f64>) -> E6Pos {
        let n = PoseConvention::KUKA.numbers(iso);
        E6Pos { x: n[0] as f32, y: n[1] as f32, z: n[2] as f32, a: n[3] as f32, b: n[4] as f32, c: n[5] as f32 }
    }
}

/// `EKI_STATUS`: of its fields (Buff, Read, Msg_No, Connected, Counter)
/// the program reads `Msg_No`, 0 when the call succeeded.
#[derive(Clone, Copy, Debug, Default)]
pub struct EkiStatus {
    pub msg_no: i32,
}

/// The settings of the channel file the program uses.
#[derive(Clone, Debug)]
pub struct EkiConfig {
    pub buffering_limit: usize,
    pub buffsize: usize,
    pub connect_timeout_ms: u64,
    pub alive_flag: Option<usize>,
    pub tag: String,
    pub eos: Vec<u8>,
    pub size: usize,
    pub rx_flag: Option<usize>,
}

/// The value of `attribute` on the first `<element ...>` of `xml`.
fn attribute(xml: &str, element: &str, attribute: &str) -> Option<String> {
    let open = format!("<{element} ");
    let start = xml.find(&open)? + open.len();
    let end = start + xml[start..].find('>')?;
    let tag = &xml[start..end];
    let key = format!("{attribute}=\"");
    let at = tag.find(&key)? + key.len();
    Some(tag[at..at + tag[at..].find('"')?].to_string())
}

impl EkiConfig {
    /// Reads the settings of a channel file: the RAW receive element's
    /// attributes and the INTERNAL section's (defaults as documented).
    pub fn parse(xml: &str) -> EkiConfig {
        assert!(xml.contains("<TYPE>Server</TYPE>"), "the daemon is the server: TYPE Server");
        assert!(xml.contains("<RAW>"), "a RAW receive element");
        let number = |e: &str, a: &str, default: usize| attribute(xml, e, a).map_or(default, |v| v.parse().unwrap());
        let eos = attribute(xml, "ELEMENT", "EOS").expect("EOS on the stream element");
        assert_eq!(attribute(xml, "ELEMENT", "Type").as_deref(), Some("STREAM"));
        EkiConfig {
            buffering_limit: number("BUFFERING", "Limit", 16),
            buffsize: number("BUFFSIZE", "Limit", 16384),
            connect_timeout_ms: number("TIMEOUT", "Connect", 2000) as u64,
            alive_flag: attribute(xml, "ALIVE", "Set_Flag").map(|v| v.parse().unwrap()),
            tag: attribute(xml, "ELEMENT", "Tag").expect("Tag"),
            eos: eos.split(',').map(|b| b.trim().parse().unwrap()).collect(),
            size: number("ELEMENT", "Size", 16384),
            rx_flag: attribute(xml, "ELEMENT", "Set_Flag").map(|v| v.parse().unwrap()),
        }
    }
}

/// What the channel's receiver shares with the program: the elements
/// received, an error to report, and the flags it sets.
#[derive(Default)]
struct Received {
    elements: VecDeque<Vec<u8>>,
    error: i32,
}

/// The controller: flags, timers, outputs, the channel, the robot.
pub struct Krl {
    pub flags: Arc<Mutex<Vec<bool>>>,
    timers: Vec<(i64, Option<Instant>)>,
    pub outputs: Vec<bool>,
    pub trace: Trace,
    pub config: EkiConfig,
    /// Where the daemon listens (the XML's IP and PORT, set for the cell).
    pub address: String,
    stream: Option<TcpStream>,
    received: Arc<Mutex<Received>>,
    /// The flange in the robot base frame, and the tool table.
    pub flange: Isometry3<f64>,
    pub tool_data: Vec<Isometry3<f64>>,
    /// The tool of `$TOOL`: `None` for `$NULLFRAME`, else TOOL_DATA's index.
    pub tool: Option<usize>,
    pub advance: i32,
    pub apo_cdis: f32,
    /// `$APO.CDIS` at each LIN, in the order of the trace's moves (0 for
    /// a LIN without C_DIS).
    pub cdis_at_moves: Vec<f32>,
    pub vel_cp: f32,
    /// Messages shown on the smartHMI.
    pub messages: Vec<String>,
    /// Called with each line before it is sent (a scenario's fault).
    pub on_send: Option<SendHook>,
}

impl Krl {
    pub fn new(xml: &str, address: &str, flange: Isometry3<f64>, torch: Isometry3<f64>) -> Krl {
        let mut tool_data = vec![Isometry3::identity(); 17];
        tool_data[1] = torch;
        Krl {
            flags: Arc::new(Mutex::new(vec![false; 1025])),
            timers: vec![(0, None); 33],
            outputs: vec![false; 4097],
            trace: Trace::default(),
            config: EkiConfig::parse(xml),
            address: address.to_string(),
            stream: None,
            received: Arc::default(),
            flange,
            tool_data,
            tool: Some(1),
            advance: 1,
            apo_cdis: 0.0,
            cdis_at_moves: Vec::new(),
            vel_cp: 0.0,
            messages: Vec::new(),
            on_send: None,
        }
    }

    /// Tags a statement: the transcription's link to the program's line.
    pub fn at(&mut self, line: usize, _text: &str) {
        self.trace.statement(line);
    }

    pub fn flag(&self, n: usize) -> bool {
        self.flags.lock().unwrap()[n]
    }

    pub fn set_flag(&mut self, n: usize, value: bool) {
        self.flags.lock().unwrap()[n] = value;
    }

    /// `$TIMER[n]` in ms.
    pub fn timer(&self, n: usize) -> i64 {
        let (base, since) = self.timers[n];
        base + since.map_or(0, |t| t.elapsed().as_millis() as i64)
    }

    pub fn set_timer(&mut self, n: usize, ms: i64) {
        let running = self.timers[n].1.is_some();
        self.timers[n] = (ms, running.then(Instant::now));
    }

    pub fn set_timer_stop(&mut self, n: usize, stop: bool) {
        let value = self.timer(n);
        self.timers[n] = (value, (!stop).then(Instant::now));
    }

    pub fn timer_flag(&self, n: usize) -> bool {
        self.timer(n) >= 0
    }

    /// `WAIT FOR condition`: stops the advance run, then looks at the
    /// condition every interpolation cycle.
    pub fn wait_for(&mut self, condition: impl Fn(&Krl) -> bool) {
        self.trace.advance_stop();
        while !condition(self) {
            std::thread::sleep(IPO_CYCLE);
        }
    }

    /// `$OUT[n] = value` (without CONTINUE: stops the advance run).
    pub fn set_output(&mut self, n: usize, value: bool) {
        self.trace.advance_stop();
        self.outputs[n] = value;
        self.trace.push(if value { Event::ArcOn } else { Event::ArcOff });
    }

    /// `$POS_ACT` with the current `$TOOL` in `$BASE` = the robot base
    /// (stops the advance run).
    pub fn pos_act(&mut self) -> E6Pos {
        self.trace.advance_stop();
        let tcp = match self.tool {
            Some(k) => self.flange * self.tool_data[k],
            None => self.flange,
        };
        E6Pos::of(&tcp)
    }

    /// `LIN target` or `LIN target C_DIS`: the robot moves the tool there.
    pub fn lin(&mut self, line: usize, target: &E6Pos, c_dis: bool) {
        self.trace.look_ahead = self.advance >= 1 && self.apo_cdis > 0.0;
        self.trace.motion(line, target.numbers(), f64::from(self.vel_cp) * 1000.0, c_dis);
        self.cdis_at_moves.push(if c_dis { self.apo_cdis } else { 0.0 });
        let pose = PoseConvention::KUKA.to_isometry(&target.numbers()).unwrap();
        let tool = self.tool.map_or(Isometry3::identity(), |k| self.tool_data[k]);
        self.flange = pose * tool.inverse();
    }

    /// `EKI_Init(name)`: the channel file is read (here: given to `new`).
    pub fn eki_init(&mut self, _name: &str) -> EkiStatus {
        *self.received.lock().unwrap() = Received::default();
        EkiStatus::default()
    }

    /// `EKI_Open(name)`: connects to the external server within TIMEOUT
    /// Connect; starts receiving into the element's memory.
    pub fn eki_open(&mut self, _name: &str) -> EkiStatus {
        let timeout = Duration::from_millis(self.config.connect_timeout_ms);
        let address = self.address.parse().expect("the daemon's address");
        let stream = match TcpStream::connect_timeout(&address, timeout) {
            Ok(s) => s,
            Err(_) => return EkiStatus { msg_no: 14 },
        };
        let reader = stream.try_clone().unwrap();
        self.stream = Some(stream);
        if let Some(f) = self.config.alive_flag {
            self.set_flag(f, true);
        }
        let (received, flags, config) = (self.received.clone(), self.flags.clone(), self.config.clone());
        std::thread::spawn(move || receive(reader, config, received, flags));
        EkiStatus::default()
    }

    /// `EKI_Send(name, data[])`: the CHAR array as it is, to its first NUL.
    pub fn eki_send(&mut self, _name: &str, data: &Chars) -> EkiStatus {
        let text = data.text();
        if let Some(hook) = self.on_send.as_mut() {
            hook(&text);
        }
        self.trace.push(Event::Sent(text.clone()));
        match self.stream.as_mut().map(|s| s.write_all(text.as_bytes())) {
            Some(Ok(())) => EkiStatus::default(),
            _ => EkiStatus { msg_no: 2 },
        }
    }

    /// `EKI_GetString(name, tag, out[])`: the oldest element of the tag.
    pub fn eki_get_string(&mut self, _name: &str, tag: &str, out: &mut Chars) -> EkiStatus {
        assert_eq!(tag, self.config.tag);
        let mut received = self.received.lock().unwrap();
        if received.error != 0 {
            return EkiStatus { msg_no: received.error };
        }
        let Some(element) = received.elements.pop_front() else {
            return EkiStatus { msg_no: 1 };
        };
        let n = element.len().min(out.0.len());
        out.0[..n].copy_from_slice(&element[..n]);
        drop(received);
        self.trace.push(Event::Read(String::from_utf8_lossy(&element).into_owned()));
        EkiStatus::default()
    }

    /// `EKI_Close(name)` and `EKI_Clear(name)`.
    pub fn eki_close(&mut self, _name: &str) -> EkiStatus {
        if let Some(s) = self.stream.take() {
            let _ = s.shutdown(std::net::Shutdown::Both);
        }
        EkiStatus::default()
    }

    /// `MsgNotify(text, source)`.
    pub fn msg_notify(&mut self, text: &str) {
        self.messages.push(text.to_string());
    }
}

/// The channel's receiver: splits the stream at the end string into
/// elements of at most `Size` bytes, keeps at most BUFFERING Limit of them
/// and sets the element's flag; at the connection's end clears the ALIVE
/// flag.
fn receive(mut stream: TcpStream, config: EkiConfig, received: Arc<Mutex<Received>>, flags: Arc<Mutex<Vec<bool>>>) {
    let mut pending: Vec<u8> = Vec::new();
    let mut chunk = [0u8; 512];
    loop {
        let n = match stream.read(&mut chunk) {
            Ok(0) | Err(_) => break,
            Ok(n) => n,
        };
        pending.extend_from_slice(&chunk[..n]);
        while let Some(end) = pending.windows(config.eos.len()).position(|w| w == config.eos.as_slice()) {
            let element: Vec<u8> = pending.drain(..end + config.eos.len()).take(end).collect();
            let mut r = received.lock().unwrap();
            if element.len() > config.size || r.elements.len() >= config.buffering_limit {
                r.error = 8;
            } else {
                r.elements.push_back(element);
            }
            drop(r);
            if let Some(f) = config.rx_flag {
                flags.lock().unwrap()[f] = true;
            }
        }
        if pending.len() > config.buffsize {
            received.lock().unwrap().error = 8;
            pending.clear();
        }
    }
    if let Some(f) = config.alive_flag {
        flags.lock().unwrap()[f] = false;
    }
}

/// `STATE_T` of SREAD/SWRITE: the items read or written.
#[derive(Clone, Copy, Debug, Default)]
pub struct State {
    pub hits: i32,
}

/// A value SREAD read.
#[derive(Clone, Copy, Debug)]
pub enum Value {
    Int(i32),
    Real(f32),
}

/// `SREAD(text[], state, offset, format, ...)`: reads from `offset`
/// (advanced past what was read) the `%d` and `%f` items of `format`, the
/// other characters of the format matched as they are; stops at the first
/// item that does not match. Leading blanks of a number are skipped.
pub fn sread(text: &Chars, offset: &mut usize, format: &str) -> (State, Vec<Value>) {
    let bytes = text.text().into_bytes();
    let mut values = Vec::new();
    let mut f = format.as_bytes().iter().peekable();
    let mut at = *offset;
    while let Some(&c) = f.next() {
        if c == b'%' {
            let kind = *f.next().expect("a conversion");
            while at < bytes.len() && bytes[at] == b' ' {
                at += 1;
            }
            let start = at;
            let numeric = |b: u8| {
                b.is_ascii_digit() || b == b'-' || b == b'+' || (kind == b'f' && (b == b'.' || b == b'e' || b == b'E'))
            };
            while at < bytes.len() && numeric(bytes[at]) {
                at += 1;
            }
            let field = std::str::from_utf8(&bytes[start..at]).unwrap();
            let value = match kind {
                b'd' => field.parse().ok().map(Value::Int),
                b'f' => field.parse().ok().map(Value::Real),
                _ => panic!("SREAD %{} not emulated", kind as char),
            };
            match value {
                Some(v) => values.push(v),
                None => break,
            }
        } else if bytes.get(at) == Some(&c) {
            at += 1;
        } else {
            break;
        }
    }
    *offset = at;
    (State { hits: values.len() as i32 }, values)
}

/// The INT read as item `k`, or `old` when SREAD did not reach it.
pub fn int(values: &[Value], k: usize, old: i32) -> i32 {
    match values.get(k) {
        Some(Value::Int(v)) => *v,
        _ => old,
    }
}

/// The REAL read as item `k`, or `old` when SREAD did not reach it.
pub fn real(values: &[Value], k: usize, old: f32) -> f32 {
    match values.get(k) {
        Some(Value::Real(v)) => *v,
        _ => old,
    }
}

/// An argument of SWRITE.
pub enum Arg<'a> {
    Int(i32),
    Real(f32),
    Text(&'a Chars),
}

/// `SWRITE(text[], state, offset, format, ...)`: writes at `offset`;
/// `%d`, `%.nf` (REAL to n decimals), `%s` (a CHAR array), `%c` (an INT
/// as its character). Characters beyond the array are not written.
pub fn swrite(text: &mut Chars, offset: &mut usize, format: &str, args: &[Arg]) -> State {
    let mut out = String::new();
    let mut args = args.iter();
    let mut hits = 0;
    let mut f = format.chars().peekable();
    while let Some(c) = f.next() {
        if c != '%' {
            out.push(c);
            continue;
        }
        let mut spec = String::new();
        while let Some(&d) = f.peek() {
            f.next();
            if d.is_ascii_alphabetic() {
                spec.push(d);
                break;
            }
            spec.push(d);
        }
        let arg = args.next().expect("an argument for each item");
        let written = match (spec.chars().last(), arg) {
            (Some('d'), Arg::Int(v)) => v.to_string(),
            (Some('f'), Arg::Real(v)) => {
                let decimals: usize = spec.trim_start_matches('.').trim_end_matches('f').parse().unwrap_or(6);
                format!("{v:.decimals$}")
            }
            (Some('s'), Arg::Text(t)) => t.text(),
            (Some('c'), Arg::Int(v)) => char::from(*v as u8).to_string(),
            _ => panic!("SWRITE %{spec} not emulated for this argument"),
        };
        out.push_str(&written);
        hits += 1;
    }
    for b in out.bytes() {
        if *offset < text.0.len() {
            text.0[*offset] = b;
            *offset += 1;
        }
    }
    State { hits }
}

/// SREAD counts the items it read and stops at the first that does not
/// match; SWRITE writes REALs to the decimals asked and INTs as characters
/// with `%c`.
#[test]
fn sread_and_swrite_as_documented() {
    let mut line = Chars::new(254);
    line.assign("2,1,11,850.032,-150.072,-244.000,114.9999,0.0000,-179.9998");
    let mut offset = 0;
    let (state, values) = sread(&line, &mut offset, "%d,%d,%d,%f,%f,%f,%f,%f,%f");
    assert_eq!(state.hits, 9);
    assert_eq!((int(&values, 2, 0), real(&values, 3, 0.0)), (11, 850.032));
    let mut error = Chars::new(254);
    error.assign("-44,no fresh frame in 5000 ms");
    offset = 0;
    let (state, values) = sread(&error, &mut offset, "%d,%d,%d");
    assert_eq!((state.hits, int(&values, 0, 0)), (1, -44));
    let mut out = Chars::new(16);
    offset = 0;
    swrite(&mut out, &mut offset, "%.3f%c%c", &[Arg::Real(1.25), Arg::Int(13), Arg::Int(10)]);
    assert_eq!(out.text(), "1.250\r\n");
}
