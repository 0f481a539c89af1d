//! The text controller link: line-based ASCII that robot programs read
//! with their own primitives (UR's `socket_read_ascii_float`, RAPID's
//! `SocketReceive` and `StrToVal`, KRL's and KAREL's string reads). Pure
//! functions over lines: [`parse_request`] reads a robot's line, [`Reply`]
//! writes the daemon's in a [`Dialect`], within what that language can
//! read (ABB's 80 characters, UR's 30 numbers), every number finite and
//! with fixed decimals. ROBOTS.md documents the sessions.
//!
//! Every request line gets exactly one reply line, so a robot that reads
//! one line per line it sends never loses step. Every length limit here
//! counts the line's terminator.

use std::fmt::Write as _;

use crate::ErrorCode;

/// The text link's version, sent in the reply to `HELLO`.
pub const TEXT_PROTOCOL_VERSION: u32 = 2;

/// The most numbers one `socket_read_ascii_float` reads (URScript).
pub const UR_MAX_NUMBERS: usize = 30;

/// The longest string RAPID holds, and so the longest line `SocketReceive
/// \Str` can take whole, terminator included.
pub const ABB_MAX_LINE: usize = 80;

/// The longest string KRL's and KAREL's programs are given here (a KRL
/// `CHAR[254]`, a KAREL `STRING[254]`), terminator included.
pub const STRING_MAX_LINE: usize = 254;

/// The longest error line in any dialect: a reason an operator reads on a
/// pendant, which fits an 80-character RAPID string everywhere.
pub const MAX_ERROR_LINE: usize = 80;

/// The most numbers a request line may carry (a pose of 7 and a depth).
pub const MAX_REQUEST_NUMBERS: usize = 8;

/// How far a robot's own mean of a seam's written positions may lie from
/// the `CHECK` reply's, per axis, in mm (UR: this over 1000, in metres):
/// the reply's rounding to the position decimals (at most 0.005 mm) plus
/// what summing up to a few thousand positions in 32-bit REALs (KRL,
/// KAREL) may lose. A line lost, repeated or read into the wrong field
/// moves a mean by far more on any seam the dialects can store.
pub const CHECK_TOLERANCE_MM: f64 = 0.1;

/// A robot language, which fixes the pose convention, the units, the
/// decimals and the line framing of the replies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dialect {
    /// Universal Robots (URScript): `(n1,n2,...)`, metres and a rotation
    /// vector in radians.
    Ur,
    /// ABB RAPID: millimetres and a quaternion q1..q4 (w, x, y, z).
    Abb,
    /// KUKA KRL: millimetres, A, B, C in degrees.
    Kuka,
    /// FANUC KAREL: millimetres, W, P, R in degrees.
    Fanuc,
}

impl Dialect {
    pub const ALL: [Dialect; 4] = [Dialect::Ur, Dialect::Abb, Dialect::Kuka, Dialect::Fanuc];

    pub fn name(self) -> &'static str {
        match self {
            Dialect::Ur => "ur",
            Dialect::Abb => "abb",
            Dialect::Kuka => "kuka",
            Dialect::Fanuc => "fanuc",
        }
    }

    /// Reads `ur`, `abb`, `kuka` or `fanuc`, any case.
    pub fn from_name(name: &str) -> Option<Dialect> {
        Dialect::ALL.into_iter().find(|d| d.name().eq_ignore_ascii_case(name.trim()))
    }

    /// How many numbers a pose takes: 7 with ABB's quaternion, else 6.
    pub fn pose_numbers(self) -> usize {
        match self {
            Dialect::Abb => 7,
            _ => 6,
        }
    }

    /// Decimals of a pose's position and of its rotation numbers: 1 µm
    /// and about 6e-5° for UR (metres, radians); 0.01 mm and 1e-6 of a
    /// quaternion for ABB (so a waypoint fits 80 characters); 0.001 mm
    /// and 0.0001° for KUKA and FANUC.
    pub fn decimals(self) -> (usize, usize) {
        match self {
            Dialect::Ur => (6, 6),
            Dialect::Abb => (2, 6),
            Dialect::Kuka | Dialect::Fanuc => (3, 4),
        }
    }

    /// The longest reply line, terminator included.
    pub fn max_line(self) -> usize {
        match self {
            Dialect::Ur | Dialect::Kuka | Dialect::Fanuc => STRING_MAX_LINE,
            Dialect::Abb => ABB_MAX_LINE,
        }
    }

    /// What ends a reply line: LF for UR (its number read stops at the
    /// closing parenthesis, its line read at LF) and for FANUC (a KAREL
    /// `READ` of a string ends at LF and would keep a CR in the string);
    /// CR LF for ABB and KUKA (a RAPID string and an EKI stream element
    /// ending at CR LF).
    pub fn terminator(self) -> &'static str {
        match self {
            Dialect::Ur | Dialect::Fanuc => "\n",
            Dialect::Abb | Dialect::Kuka => "\r\n",
        }
    }
}

/// What a waypoint line's point is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointKind {
    /// Above the seam's first waypoint, backed off along the torch axis:
    /// move here first (not welding).
    Approach = 1,
    /// On the seam: weld through these in order.
    Weld = 2,
    /// Above the seam's last waypoint: move here after the weld.
    Retract = 3,
}

/// The kind number of a process line (after the waypoint kinds 1 to 3).
pub const PROCESS_KIND: u8 = 4;

/// The option of `HELLO` that asks for a process line after every weld
/// waypoint line.
pub const PROCESS_OPTION: &str = "PROCESS";

/// A robot's request, one line.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// `HELLO,<dialect>[,PROCESS]`: the robot's language for this session,
    /// and whether it reads a process line (travel speed and weave) after
    /// each weld waypoint line.
    Hello { dialect: Dialect, process: bool },
    /// `PLAN,<joint>,<pose>[,<groove depth>]`: plan the next frame the
    /// camera sends, taken at this pose.
    Plan(PlanLine),
    /// `TRIGGER,<joint>,<pose>[,<groove depth>]`: trigger the camera now
    /// and plan its frame, taken at this pose.
    Trigger(PlanLine),
    /// `NEXT`: the next waypoint of the plan.
    Next,
    /// `CHECK,<seam>`: the number of waypoint lines of seam `<seam>` (from
    /// 1) of the session's last plan and the means of their positions.
    Check(u32),
    /// `DROP`: forget the waypoints not yet pulled.
    Drop,
    /// `WHY`: the last error line's reason, as text.
    Why,
    /// `PING`: an ok line with the cameras connected and the plan queue.
    Ping,
}

/// The fields of a plan or trigger line.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanLine {
    /// The joint's name as written; the library parses it.
    pub joint: String,
    /// The capture pose's numbers in the dialect's convention and units.
    pub pose: Vec<f64>,
    /// The groove depth in the dialect's length unit, when given.
    pub groove_depth: Option<f64>,
}

/// Why a line is not a request; the session answers an error line and
/// goes on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LineError {
    #[error("unknown command {0:?}: expected HELLO, PLAN, TRIGGER, NEXT, CHECK, DROP, WHY or PING")]
    UnknownCommand(String),
    #[error("unknown dialect {0:?}: expected ur, abb, kuka or fanuc")]
    UnknownDialect(String),
    #[error("unknown HELLO option {0:?}: expected PROCESS")]
    UnknownOption(String),
    #[error("{command} takes {expected} fields after it, got {got}")]
    FieldCount { command: &'static str, expected: String, got: usize },
    #[error("field {index} ({text:?}) is not a number")]
    NotANumber { index: usize, text: String },
    #[error("field {index} is not finite")]
    NotFinite { index: usize },
    #[error("the seam number {0:?} is not a whole number from 1")]
    NotASeam(String),
    #[error("name the dialect first: HELLO,ur|abb|kuka|fanuc")]
    NoDialect,
}

impl LineError {
    /// The error code of its error line.
    pub fn code(&self) -> ErrorCode {
        match self {
            LineError::UnknownCommand(_) => ErrorCode::UnknownMessage,
            LineError::NoDialect => ErrorCode::UnexpectedMessage,
            _ => ErrorCode::Malformed,
        }
    }
}

/// A number as a robot program writes it: sign, digits, a point, an
/// exponent; never `nan` or `inf`, which Rust's parser would take.
fn number(index: usize, field: &str) -> Result<f64, LineError> {
    let plain = !field.is_empty()
        && field.bytes().all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E'))
        && field.bytes().any(|b| b.is_ascii_digit());
    let lowered = field.to_ascii_lowercase();
    if lowered.contains("nan") || lowered.contains("inf") {
        return Err(LineError::NotFinite { index });
    }
    let value: f64 = match plain {
        true => field.parse().map_err(|_| LineError::NotANumber { index, text: field.into() })?,
        false => return Err(LineError::NotANumber { index, text: field.into() }),
    };
    if value.is_finite() { Ok(value) } else { Err(LineError::NotFinite { index }) }
}

/// Reads one request line (without its terminator). Fields are separated
/// by commas; spaces around them, the command's case and the brackets of
/// a URScript pose (`p[0.1, 0.2, ...]`, as `to_str` writes it) are ignored.
/// `dialect` is the session's, None before a `HELLO`; it fixes how many
/// numbers a pose has.
pub fn parse_request(line: &str, dialect: Option<Dialect>) -> Result<Request, LineError> {
    let cleaned: String = line.chars().filter(|c| !matches!(c, '[' | ']')).collect();
    let mut fields = cleaned.split(',').map(str::trim);
    let command = fields.next().unwrap_or("").to_ascii_uppercase();
    let rest: Vec<&str> = fields.collect();
    // A URScript pose's `p` prefix stays on the first number: `p0.1`.
    let unprefixed = |f: &str| f.strip_prefix(['p', 'P']).unwrap_or(f).to_string();
    let bare = |name: &'static str, request: Request| match rest.as_slice() {
        [] | [""] => Ok(request),
        _ => Err(LineError::FieldCount { command: name, expected: "no".into(), got: rest.len() }),
    };
    match command.as_str() {
        "HELLO" => {
            let (name, process) = match rest.as_slice() {
                [name] => (name, false),
                [name, option] if option.eq_ignore_ascii_case(PROCESS_OPTION) => (name, true),
                [_, option] => return Err(LineError::UnknownOption(printable(option, 24))),
                _ => {
                    return Err(LineError::FieldCount { command: "HELLO", expected: "1 or 2".into(), got: rest.len() });
                }
            };
            let dialect = Dialect::from_name(name).ok_or_else(|| LineError::UnknownDialect(name.to_string()))?;
            Ok(Request::Hello { dialect, process })
        }
        "PLAN" | "TRIGGER" => {
            let dialect = dialect.ok_or(LineError::NoDialect)?;
            let name = if command == "PLAN" { "PLAN" } else { "TRIGGER" };
            let pose_len = dialect.pose_numbers();
            if !(1 + pose_len..=2 + pose_len).contains(&rest.len()) {
                return Err(LineError::FieldCount {
                    command: name,
                    expected: format!(
                        "{} or {} (joint, {pose_len} pose numbers, groove depth)",
                        1 + pose_len,
                        2 + pose_len
                    ),
                    got: rest.len(),
                });
            }
            let mut numbers = Vec::with_capacity(MAX_REQUEST_NUMBERS);
            for (k, field) in rest[1..].iter().enumerate() {
                let field = if k == 0 { unprefixed(field) } else { field.to_string() };
                numbers.push(number(k + 2, &field)?);
            }
            let groove_depth = (numbers.len() > pose_len).then(|| numbers[pose_len]);
            numbers.truncate(pose_len);
            let plan = PlanLine { joint: rest[0].to_string(), pose: numbers, groove_depth };
            Ok(if name == "PLAN" { Request::Plan(plan) } else { Request::Trigger(plan) })
        }
        "NEXT" => bare("NEXT", Request::Next),
        "CHECK" => match rest.as_slice() {
            [seam] => match seam.parse::<u32>() {
                Ok(number) if seam.bytes().all(|b| b.is_ascii_digit()) => Ok(Request::Check(number)),
                _ => Err(LineError::NotASeam(printable(seam, 12))),
            },
            _ => Err(LineError::FieldCount { command: "CHECK", expected: "1".into(), got: rest.len() }),
        },
        "DROP" => bare("DROP", Request::Drop),
        "WHY" => bare("WHY", Request::Why),
        "PING" => bare("PING", Request::Ping),
        _ => Err(LineError::UnknownCommand(printable(&command, 24))),
    }
}

/// A reply line of the daemon.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// `0,a,b`: done. After `HELLO`: the text protocol version and 0; after
    /// `PLAN` or `TRIGGER`: the seams and the waypoint lines to pull; after
    /// `PING`: the cameras connected and the requests in the plan queue;
    /// after `DROP`: the waypoint lines dropped and 0.
    Ok(u64, u64),
    /// `0,n,cx,cy,cz`: the answer to `CHECK`: the seam's waypoint lines
    /// (approach, weld waypoints, retract) and the means of the x, y, z
    /// positions as written on them, written with the position decimals.
    Check { lines: u64, mean: [f64; 3] },
    /// `kind,seam,remaining,pose...`: one point of a plan.
    Waypoint {
        kind: PointKind,
        /// The seam it belongs to, from 1.
        seam: u32,
        /// Waypoint lines still to pull after this one, in all seams.
        remaining: u64,
        /// The pose in the dialect's convention and units.
        pose: Vec<f64>,
    },
    /// `4,seam,remaining,speed,amplitude,frequency`: how the torch travels
    /// into the weld waypoint on the line before it, in a session whose
    /// `HELLO` asked for them: the travel speed (the dialect's length unit
    /// per second), the weave's half-swing (its length unit) and frequency
    /// (Hz), 0 where no procedure gives them. A UR line has 9 numbers
    /// (zeros after the frequency), as a waypoint line.
    Process {
        seam: u32,
        remaining: u64,
        /// Travel speed, half-swing and frequency, in the dialect's units.
        motion: [f64; 3],
    },
    /// `-code,reason`: the request failed; the session goes on. The reason
    /// leads with the cause and is cut at a word boundary to fit
    /// [`MAX_ERROR_LINE`]. In the UR dialect there is no reason (read it
    /// with `WHY`), and the line has as many numbers as the reply it
    /// stands for, `numbers`, zeros after the code, so the robot's
    /// `socket_read_ascii_float(n)` reads it.
    Error { code: u16, reason: String, numbers: usize },
    /// The answer to `WHY`: text only, not a number list.
    Text(String),
}

/// How many numbers an ok line has.
pub const OK_NUMBERS: usize = 3;

/// How many numbers a `CHECK` reply has.
pub const CHECK_NUMBERS: usize = 5;

/// The `CHECK` replies of a plan's waypoint lines, one per seam in seam
/// order: each seam's line count and the means of the positions as the
/// lines write them (rounded to the dialect's position decimals), so a
/// robot that stored the lines it read can compare its own sums.
pub fn seam_checks(lines: &[Reply], dialect: Dialect) -> Vec<Reply> {
    let (position, _) = dialect.decimals();
    let mut checks: Vec<(u32, u64, [f64; 3])> = Vec::new();
    for line in lines {
        let Reply::Waypoint { seam, pose, .. } = line else { continue };
        if checks.last().is_none_or(|(s, _, _)| s != seam) {
            checks.push((*seam, 0, [0.0; 3]));
        }
        let (_, count, sums) = checks.last_mut().expect("pushed above");
        *count += 1;
        for (sum, v) in sums.iter_mut().zip(pose) {
            *sum += fixed(*v, position).parse::<f64>().unwrap_or(f64::NAN);
        }
    }
    checks.into_iter().map(|(_, lines, sums)| Reply::Check { lines, mean: sums.map(|s| s / lines as f64) }).collect()
}

/// The decimals of a process line's weave frequency, Hz.
pub const FREQUENCY_DECIMALS: usize = 3;

/// How many numbers a waypoint line has in `dialect`.
pub fn waypoint_numbers(dialect: Dialect) -> usize {
    3 + dialect.pose_numbers()
}

/// Why a reply cannot be written in a dialect: such a reply becomes an
/// error line instead.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FormatError {
    #[error("a {what} is not finite")]
    NotFinite { what: &'static str },
    #[error("the line would be {len} characters, over the {limit} {dialect} reads")]
    TooLong { len: usize, limit: usize, dialect: &'static str },
    #[error("the line would have {count} numbers, over the {limit} UR reads")]
    TooManyNumbers { count: usize, limit: usize },
}

/// `v` with `decimals` fixed decimals, never `-0.000`.
fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

/// `text` as printable ASCII without commas (so a robot splitting the line
/// on commas reads it as one field), at most `max` characters.
pub fn printable(text: &str, max: usize) -> String {
    text.chars()
        .map(|c| match c {
            ',' => ';',
            c if c.is_ascii_graphic() || c == ' ' => c,
            _ => '?',
        })
        .take(max)
        .collect()
}

/// `text` as [`printable`], cut at the last word boundary within `max`
/// characters when it is longer, so a pendant shows whole words (a word
/// longer than half the room is cut inside).
pub fn printable_words(text: &str, max: usize) -> String {
    let whole = printable(text, usize::MAX);
    if whole.len() <= max {
        return whole;
    }
    let cut = &whole[..max];
    let at_word = match whole.as_bytes()[max] {
        b' ' => Some(max),
        _ => cut.rfind(' ').filter(|at| *at >= max / 2),
    };
    let kept = at_word.map_or(cut, |at| &cut[..at]);
    kept.trim_end_matches([' ', ';', ':', '(']).to_string()
}

impl Reply {
    /// The line in `dialect`, terminator included.
    pub fn format(&self, dialect: Dialect) -> Result<String, FormatError> {
        let fields: Vec<String> = match self {
            Reply::Ok(a, b) => vec!["0".into(), a.to_string(), b.to_string()],
            Reply::Waypoint { kind, seam, remaining, pose } => {
                if pose.iter().any(|v| !v.is_finite()) {
                    return Err(FormatError::NotFinite { what: "waypoint's pose" });
                }
                let (position, rotation) = dialect.decimals();
                let mut fields = vec![(*kind as u8).to_string(), seam.to_string(), remaining.to_string()];
                fields.extend(pose.iter().enumerate().map(|(k, v)| fixed(*v, if k < 3 { position } else { rotation })));
                fields
            }
            Reply::Process { seam, remaining, motion } => {
                if motion.iter().any(|v| !v.is_finite()) {
                    return Err(FormatError::NotFinite { what: "process line's number" });
                }
                let (position, _) = dialect.decimals();
                let mut fields = vec![PROCESS_KIND.to_string(), seam.to_string(), remaining.to_string()];
                fields.push(fixed(motion[0], position));
                fields.push(fixed(motion[1], position));
                fields.push(fixed(motion[2], FREQUENCY_DECIMALS));
                if dialect == Dialect::Ur {
                    // As many numbers as a waypoint line, so one
                    // `socket_read_ascii_float` reads every line pulled.
                    fields.resize(waypoint_numbers(dialect), "0".into());
                }
                fields
            }
            Reply::Error { code, reason, numbers } => {
                let code = format!("-{code}");
                match dialect {
                    Dialect::Ur => std::iter::once(code)
                        .chain(std::iter::repeat_n("0".into(), numbers.saturating_sub(1)))
                        .collect(),
                    _ => {
                        let room = MAX_ERROR_LINE.min(dialect.max_line()) - code.len() - 1 - dialect.terminator().len();
                        vec![code, printable_words(reason, room)]
                    }
                }
            }
            Reply::Text(text) => {
                let room = MAX_ERROR_LINE.min(dialect.max_line()) - dialect.terminator().len();
                let text = match printable_words(text, room) {
                    // A robot that reads lines until a non-empty one (UR,
                    // after a number list's LF) never waits for ever.
                    empty if empty.is_empty() => "no reason".to_string(),
                    text => text,
                };
                return Ok(format!("{text}{}", dialect.terminator()));
            }
            Reply::Check { lines, mean } => {
                if mean.iter().any(|v| !v.is_finite()) {
                    return Err(FormatError::NotFinite { what: "check's mean" });
                }
                let (position, _) = dialect.decimals();
                std::iter::once("0".to_string())
                    .chain(std::iter::once(lines.to_string()))
                    .chain(mean.iter().map(|v| fixed(*v, position)))
                    .collect()
            }
        };
        let mut line = String::with_capacity(96);
        let body = fields.join(",");
        match dialect {
            Dialect::Ur => {
                if fields.len() > UR_MAX_NUMBERS {
                    return Err(FormatError::TooManyNumbers { count: fields.len(), limit: UR_MAX_NUMBERS });
                }
                let _ = write!(line, "({body})");
            }
            _ => line.push_str(&body),
        }
        line.push_str(dialect.terminator());
        if line.len() > dialect.max_line() {
            return Err(FormatError::TooLong { len: line.len(), limit: dialect.max_line(), dialect: dialect.name() });
        }
        Ok(line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_parse_in_every_dialect() {
        let ur = parse_request("TRIGGER,lap,p[0.8, 0, 0.5, 3.1, 0, 0]", Some(Dialect::Ur)).unwrap();
        assert_eq!(
            ur,
            Request::Trigger(PlanLine {
                joint: "lap".into(),
                pose: vec![0.8, 0.0, 0.5, 3.1, 0.0, 0.0],
                groove_depth: None
            })
        );
        let abb = parse_request("plan, v_butt, 800,0,500, 0,1,0,0, 4", Some(Dialect::Abb)).unwrap();
        let Request::Plan(p) = abb else { panic!("{abb:?}") };
        assert_eq!((p.pose.len(), p.groove_depth), (7, Some(4.0)));
        assert_eq!(parse_request("HELLO,KUKA", None), Ok(Request::Hello { dialect: Dialect::Kuka, process: false }));
        assert_eq!(
            parse_request("hello, abb, process", None),
            Ok(Request::Hello { dialect: Dialect::Abb, process: true })
        );
        assert!(matches!(parse_request("HELLO,ur,SPEED", None), Err(LineError::UnknownOption(_))));
        assert!(matches!(parse_request("HELLO,ur,PROCESS,1", None), Err(LineError::FieldCount { .. })));
        assert_eq!(parse_request("next", Some(Dialect::Fanuc)), Ok(Request::Next));
    }

    #[test]
    fn malformed_lines_name_the_problem() {
        let kuka = Some(Dialect::Kuka);
        assert!(matches!(parse_request("FETCH", kuka), Err(LineError::UnknownCommand(_))));
        assert!(matches!(parse_request("PLAN,lap,1,2,3", kuka), Err(LineError::FieldCount { .. })));
        assert!(matches!(parse_request("PLAN,lap,1,2,x3,4,5,6", kuka), Err(LineError::NotANumber { index: 4, .. })));
        assert!(matches!(parse_request("PLAN,lap,1,2,NaN,4,5,6", kuka), Err(LineError::NotFinite { index: 4 })));
        assert!(matches!(parse_request("PLAN,lap,1,2,1e999,4,5,6", kuka), Err(LineError::NotFinite { index: 4 })));
        assert!(matches!(parse_request("PLAN,lap,1,2,3,4,5,6", None), Err(LineError::NoDialect)));
        assert!(matches!(parse_request("NEXT,1", kuka), Err(LineError::FieldCount { .. })));
        assert!(matches!(parse_request("HELLO,staubli", None), Err(LineError::UnknownDialect(_))));
    }

    #[test]
    fn replies_have_fixed_decimals_and_fit_their_dialect() {
        let worst = Reply::Waypoint {
            kind: PointKind::Retract,
            seam: 99,
            remaining: 99_999,
            pose: vec![-9999.994, -9999.994, -9999.994, -0.999_999, -0.999_999, -0.999_999, -0.999_999],
        };
        let line = worst.format(Dialect::Abb).unwrap();
        assert!(line.len() <= ABB_MAX_LINE, "{line:?}");
        let ur = Reply::Waypoint {
            kind: PointKind::Weld,
            seam: 1,
            remaining: 0,
            pose: vec![-0.0000001, 0.5, 0.25, 0.0, 3.0, -1.0],
        };
        assert_eq!(ur.format(Dialect::Ur).unwrap(), "(2,1,0,0.000000,0.500000,0.250000,0.000000,3.000000,-1.000000)\n");
        let nan = Reply::Waypoint { kind: PointKind::Weld, seam: 1, remaining: 0, pose: vec![f64::NAN; 6] };
        assert!(matches!(nan.format(Dialect::Kuka), Err(FormatError::NotFinite { .. })));
        let far = Reply::Waypoint { kind: PointKind::Weld, seam: 1, remaining: 0, pose: vec![-99999.0; 7] };
        assert!(matches!(far.format(Dialect::Abb), Err(FormatError::TooLong { .. })));
    }

    #[test]
    fn error_lines_fit_80_characters_and_ur_reads_them_as_numbers() {
        let long = Reply::Error { code: 46, reason: "frame 7, no seam: ".repeat(20), numbers: OK_NUMBERS };
        for dialect in Dialect::ALL {
            let line = long.format(dialect).unwrap();
            assert!(line.len() <= MAX_ERROR_LINE, "{dialect:?} {line:?}");
        }
        assert_eq!(long.format(Dialect::Ur).unwrap(), "(-46,0,0)\n");
        // Cut at a word boundary, the terminator counted.
        let abb = long.format(Dialect::Abb).unwrap();
        assert!(abb.ends_with("no seam\r\n") && abb.len() <= MAX_ERROR_LINE, "{abb:?}");
        let fanuc = long.format(Dialect::Fanuc).unwrap();
        assert!(fanuc.ends_with("no seam\n") && !fanuc.contains('\r'), "{fanuc:?}");
        let kuka = long.format(Dialect::Kuka).unwrap();
        assert!(kuka.starts_with("-46,frame 7; no seam") && kuka.matches(',').count() == 1, "{kuka}");
    }

    #[test]
    fn check_lines_count_a_seams_lines_and_average_their_written_positions() {
        assert_eq!(parse_request("CHECK,2", Some(Dialect::Abb)), Ok(Request::Check(2)));
        assert_eq!(parse_request("check, 1 ", None), Ok(Request::Check(1)));
        for bad in ["CHECK,1.5", "CHECK,-1", "CHECK,x", "CHECK,"] {
            assert!(matches!(parse_request(bad, None), Err(LineError::NotASeam(_))), "{bad}");
        }
        assert!(matches!(parse_request("CHECK", None), Err(LineError::FieldCount { .. })));
        assert!(matches!(parse_request("CHECK,1,2", None), Err(LineError::FieldCount { .. })));
        let point = |seam, x: f64| Reply::Waypoint {
            kind: PointKind::Weld,
            seam,
            remaining: 0,
            pose: vec![x, 2.0 * x, -x, 0.0, 0.0, 0.0, 1.0],
        };
        // As written with two decimals: 1.00 and 2.00 average 1.50; the
        // unrounded 1.004 and 1.996 would too, 1.006 rounds up.
        let lines = [point(1, 1.004), point(1, 1.996), point(2, 1.006)];
        let checks = seam_checks(&lines, Dialect::Abb);
        assert_eq!(checks.len(), 2);
        assert_eq!(checks[0].format(Dialect::Abb).unwrap(), "0,2,1.50,3.00,-1.50\r\n");
        assert_eq!(checks[1].format(Dialect::Abb).unwrap(), "0,1,1.01,2.01,-1.01\r\n");
        let ur = Reply::Check { lines: 3, mean: [0.5, -0.25, 1.0] };
        assert_eq!(ur.format(Dialect::Ur).unwrap(), "(0,3,0.500000,-0.250000,1.000000)\n");
        assert_eq!(ur.format(Dialect::Kuka).unwrap(), "0,3,0.500,-0.250,1.000\r\n");
    }

    #[test]
    fn process_lines_fit_every_dialect_and_ur_reads_them_as_waypoint_lines() {
        let line = Reply::Process { seam: 12, remaining: 1999, motion: [6.25, 1.5, 1.5625] };
        assert_eq!(line.format(Dialect::Abb).unwrap(), "4,12,1999,6.25,1.50,1.562\r\n");
        assert_eq!(line.format(Dialect::Kuka).unwrap(), "4,12,1999,6.250,1.500,1.562\r\n");
        assert_eq!(line.format(Dialect::Fanuc).unwrap(), "4,12,1999,6.250,1.500,1.562\n");
        let ur = Reply::Process { seam: 1, remaining: 3, motion: [0.00625, 0.0015, 1.5] };
        assert_eq!(ur.format(Dialect::Ur).unwrap(), "(4,1,3,0.006250,0.001500,1.500,0,0,0)\n");
        // The widest a process line gets: within ABB's 80 characters.
        let worst = Reply::Process { seam: 9999, remaining: 99_999, motion: [-99999.994, -99999.994, -99999.9994] };
        assert!(worst.format(Dialect::Abb).unwrap().len() <= ABB_MAX_LINE);
        let nan = Reply::Process { seam: 1, remaining: 0, motion: [f64::NAN, 0.0, 0.0] };
        assert!(matches!(nan.format(Dialect::Kuka), Err(FormatError::NotFinite { .. })));
    }

    #[test]
    fn a_reason_is_cut_at_a_word_and_never_empty() {
        assert_eq!(printable_words("a plate stands between", 14), "a plate stands");
        assert_eq!(printable_words("a plate stands between", 13), "a plate");
        assert_eq!(printable_words("abcdefghij", 4), "abcd");
        assert_eq!(printable_words("x, y", 80), "x; y");
        assert_eq!(Reply::Text(String::new()).format(Dialect::Ur).unwrap(), "no reason\n");
    }
}
