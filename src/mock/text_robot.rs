//! A mock robot program on the text link: sends lines as a robot program
//! does and reads one reply line for each, for `weldseam controller
//! --text` and the tests. It also reads replies the way the robot
//! languages do ([`ur_read_ascii_float`]), so a test can hold the daemon's
//! lines to what a robot can parse, and tallies a seam's lines as a robot
//! program does to compare them with the daemon's `CHECK` ([`SeamTally`]).
//! [`TextRobot::pull_plan`] plays a robot program's whole pull after a
//! plan's ok line: every line stored, in order, each seam checked, the
//! process lines (travel speed and weave) kept beside their waypoints;
//! [`TextRobot::pull_plan_logged`] does the same and shows the caller
//! every line sent and received, as `weldseam controller --text` prints
//! its session.

use std::time::Duration;

use tokio::io::{AsyncBufReadExt, AsyncReadExt, AsyncWriteExt, BufReader};
use tokio::net::TcpStream;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};

use weldseam_proto::text::{CHECK_TOLERANCE_MM, Dialect, PROCESS_KIND, PointKind, waypoint_numbers};

use super::ClientError;

/// The longest reply line read, far above any dialect's.
const MAX_REPLY_BYTES: u64 = 4096;

/// A robot program's session with the text link.
#[derive(Debug)]
pub struct TextRobot {
    reader: BufReader<OwnedReadHalf>,
    writer: OwnedWriteHalf,
    /// How long one reply may take (a plan included).
    pub wait: Duration,
}

impl TextRobot {
    /// Connects to the text link at `addr`.
    pub async fn connect(addr: &str, wait: Duration) -> Result<Self, ClientError> {
        let stream =
            TcpStream::connect(addr).await.map_err(|source| ClientError::Connect { addr: addr.to_string(), source })?;
        let (read, writer) = stream.into_split();
        Ok(TextRobot { reader: BufReader::new(read), writer, wait })
    }

    /// Sends `line` with the terminator `end` (a robot's CR, LF or CR LF).
    pub async fn send(&mut self, line: &str, end: &str) -> Result<(), ClientError> {
        let bytes = format!("{line}{end}");
        self.writer.write_all(bytes.as_bytes()).await.map_err(|e| ClientError::Read(e.into()))
    }

    /// Reads the next reply line, its terminator included.
    pub async fn recv(&mut self) -> Result<String, ClientError> {
        let mut line = Vec::new();
        let mut limited = (&mut self.reader).take(MAX_REPLY_BYTES);
        match tokio::time::timeout(self.wait, limited.read_until(b'\n', &mut line)).await {
            Err(_) => Err(ClientError::Timeout(self.wait.as_millis())),
            Ok(Err(e)) => Err(ClientError::Read(e.into())),
            Ok(Ok(0)) => Err(ClientError::Closed),
            Ok(Ok(_)) => Ok(String::from_utf8_lossy(&line).into_owned()),
        }
    }

    /// Sends `line` ended by LF and reads its reply.
    pub async fn ask(&mut self, line: &str) -> Result<String, ClientError> {
        self.send(line, "\n").await?;
        self.recv().await
    }
}

/// One seam as a robot program stores it: its approach and retract poses,
/// and its weld waypoints each with the numbers of its process line
/// (speed, half-swing, frequency in the dialect's units) when the session
/// asked for them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PulledSeam {
    pub approach: Vec<f64>,
    pub weld: Vec<(Vec<f64>, Option<[f64; 3]>)>,
    pub retract: Vec<f64>,
}

/// Why a robot program would stop a pull, with its result code's cause.
#[derive(Debug, thiserror::Error)]
pub enum PullError {
    #[error(transparent)]
    Link(#[from] ClientError),
    /// An error line where a waypoint or check line belongs.
    #[error("the daemon refused: {0}")]
    Refused(String),
    /// A line out of order (code 7) or not understood (code 4).
    #[error("line {line:?}: {why}")]
    Order { line: String, why: &'static str },
    /// A seam failed `CHECK` (code 6).
    #[error("seam {seam}: {why}")]
    Check { seam: u32, why: String },
}

/// A reply's numbers as the dialect's program reads them: URScript's
/// `socket_read_ascii_float(n)` for a line of `n` numbers, the others'
/// fields split at the commas.
pub fn reply_numbers(reply: &str, dialect: Dialect, n: usize) -> Option<Vec<f64>> {
    match dialect {
        Dialect::Ur => {
            let read = ur_read_ascii_float(reply, n);
            (read[0] > 0.0).then(|| read[1..].to_vec())
        }
        _ => reply.trim_end_matches(['\r', '\n']).split(',').map(|f| f.trim().parse::<f64>().ok()).collect(),
    }
}

impl TextRobot {
    /// Pulls the `lines` waypoint lines of a plan's ok line as a robot
    /// program does and checks each seam with `CHECK`: every seam from
    /// approach through its weld waypoints to retract, seam numbers from
    /// 1 in order, `remaining` counting down to 0, and with `process` each
    /// weld waypoint line followed by its process line.
    pub async fn pull_plan(
        &mut self,
        dialect: Dialect,
        lines: u64,
        process: bool,
    ) -> Result<Vec<PulledSeam>, PullError> {
        self.pull_plan_logged(dialect, lines, process, |_, _| {}).await
    }

    /// [`TextRobot::pull_plan`], handing `log` each line sent and the
    /// reply it got, in order, as they pass (a failed read is not handed).
    pub async fn pull_plan_logged(
        &mut self,
        dialect: Dialect,
        lines: u64,
        process: bool,
        mut log: impl FnMut(&str, &str),
    ) -> Result<Vec<PulledSeam>, PullError> {
        let mut seams: Vec<PulledSeam> = Vec::new();
        let mut tallies: Vec<SeamTally> = Vec::new();
        let width = waypoint_numbers(dialect);
        let mut awaiting_process = false;
        for pulled in 1..=lines {
            let line = self.ask("NEXT").await?;
            log("NEXT", &line);
            let order = |why| PullError::Order { line: line.clone(), why };
            let n = reply_numbers(&line, dialect, width).ok_or_else(|| order("not a number list"))?;
            let [kind, seam, remaining, rest @ ..] = n.as_slice() else { return Err(order("too few numbers")) };
            if *kind < 0.0 {
                return Err(PullError::Refused(line.trim_end().to_string()));
            }
            if *remaining != (lines - pulled) as f64 {
                return Err(order("remaining does not count down"));
            }
            let seam = *seam as u32;
            let kind = *kind as u8;
            if awaiting_process != (kind == PROCESS_KIND) {
                return Err(order("a process line not after its weld line"));
            }
            if kind == PointKind::Approach as u8 {
                if seam as usize != seams.len() + 1 {
                    return Err(order("a seam out of order"));
                }
                seams.push(PulledSeam { approach: rest.to_vec(), ..Default::default() });
                tallies.push(SeamTally::default());
            } else if seams.len() != seam as usize {
                return Err(order("a line of another seam than the one pulled"));
            }
            let (Some(current), Some(tally)) = (seams.last_mut(), tallies.last_mut()) else {
                return Err(order("no approach first"));
            };
            let position = |rest: &[f64]| [rest[0], rest[1], rest[2]];
            match kind {
                k if k == PointKind::Approach as u8 => tally.add(position(rest)),
                k if k == PointKind::Weld as u8 && current.retract.is_empty() => {
                    tally.add(position(rest));
                    current.weld.push((rest.to_vec(), None));
                    awaiting_process = process;
                }
                k if k == PointKind::Retract as u8 && !current.weld.is_empty() => {
                    tally.add(position(rest));
                    current.retract = rest.to_vec();
                }
                PROCESS_KIND => {
                    let last = current.weld.last_mut().ok_or_else(|| order("a process line before any weld line"))?;
                    last.1 = Some([rest[0], rest[1], rest[2]]);
                    awaiting_process = false;
                }
                _ => return Err(order("a kind not where it belongs")),
            }
        }
        for (seam, tally) in (1u32..).zip(&tallies) {
            let ask = format!("CHECK,{seam}");
            let check = self.ask(&ask).await?;
            log(&ask, &check);
            let numbers = reply_numbers(&check, dialect, 5).unwrap_or_default();
            tally.agrees(&numbers, dialect).map_err(|why| PullError::Check { seam, why })?;
        }
        Ok(seams)
    }
}

/// What URScript's `socket_read_ascii_float(n)` returns for a reply:
/// `[count, v1, ...]`, or `[0]` when the message is not `(`, up to 30
/// numbers separated by commas, `)` (it would then be `[0, nan, ...]`).
pub fn ur_read_ascii_float(reply: &str, n: usize) -> Vec<f64> {
    let failed = vec![0.0];
    let Some(body) = reply.trim_end_matches(['\r', '\n']).strip_prefix('(').and_then(|b| b.strip_suffix(')')) else {
        return failed;
    };
    let values: Option<Vec<f64>> =
        body.split(',').map(|v| v.trim().parse::<f64>().ok().filter(|v| v.is_finite())).collect();
    match values {
        Some(values) if values.len() <= weldseam_proto::text::UR_MAX_NUMBERS && values.len() <= n => {
            std::iter::once(values.len() as f64).chain(values).collect()
        }
        _ => failed,
    }
}

/// Whether `field` is a number RAPID's `StrToVal` reads into a `num`: an
/// optional minus, digits, and an optional point with digits.
pub fn rapid_num(field: &str) -> bool {
    let digits = field.strip_prefix('-').unwrap_or(field);
    let (whole, fraction) = digits.split_once('.').unwrap_or((digits, "0"));
    !whole.is_empty()
        && !fraction.is_empty()
        && whole.bytes().all(|b| b.is_ascii_digit())
        && fraction.bytes().all(|b| b.is_ascii_digit())
}

/// A robot program's own count of one seam's waypoint lines and sums of
/// their positions, to hold against the daemon's `CHECK` reply.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeamTally {
    pub lines: u64,
    sums: [f64; 3],
}

impl SeamTally {
    /// Counts one waypoint line's position (its first three pose numbers).
    pub fn add(&mut self, position: [f64; 3]) {
        self.lines += 1;
        for (sum, v) in self.sums.iter_mut().zip(position) {
            *sum += v;
        }
    }

    /// Whether the `CHECK` reply's numbers `[0, n, cx, cy, cz]` agree: the
    /// same count and each mean within ROBOTS.md's tolerance (0.1 mm, UR
    /// in metres). Err names the first difference.
    pub fn agrees(&self, check: &[f64], dialect: Dialect) -> Result<(), String> {
        let [status, lines, means @ ..] = check else {
            return Err(format!("a check reply has five numbers, got {check:?}"));
        };
        if *status != 0.0 || means.len() != 3 {
            return Err(format!("the check was refused or malformed: {check:?}"));
        }
        if *lines != self.lines as f64 {
            return Err(format!("the daemon counts {lines} lines, the robot stored {}", self.lines));
        }
        let tolerance = match dialect {
            Dialect::Ur => CHECK_TOLERANCE_MM / 1000.0,
            _ => CHECK_TOLERANCE_MM,
        };
        for (axis, (sum, mean)) in self.sums.iter().zip(means).enumerate() {
            let own = sum / self.lines.max(1) as f64;
            if (own - mean).abs() > tolerance {
                return Err(format!("mean {axis} is {own} here, {mean} at the daemon (tolerance {tolerance})"));
            }
        }
        Ok(())
    }
}
