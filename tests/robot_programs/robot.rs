//! What an emulated controller records while a transcribed program runs:
//! the statements it executed, the lines it sent and read, the motions it
//! commanded (with whether each blends into the next) and the arc's
//! switching; and the checks the scenarios make on that record.

/// A KRL or KAREL line that closes a block or opens a section
/// (`ENDIF`, `ENDWHILE`, `BEGIN`, `VAR`...): no behaviour of its own, so
/// a transcription need not tag it (a line added or removed around it
/// moves every tag after it all the same).
pub fn is_closer(line: &str) -> bool {
    let word = line.split([' ', ';', '(']).next().unwrap_or("");
    matches!(
        word.to_ascii_uppercase().as_str(),
        "ENDIF" | "ENDWHILE" | "ENDFOR" | "ENDSWITCH" | "ENDSELECT" | "BEGIN" | "VAR" | "CONST" | "ENDDAT"
    )
}

/// One thing the program did, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A line of the program file was executed.
    Statement(usize),
    /// A line handed to the network.
    Sent(String),
    /// A network read: the reply line the program took.
    Read(String),
    /// A motion statement.
    Move(Move),
    ArcOn,
    ArcOff,
}

/// A commanded motion: the target's six numbers as the program holds them
/// (X, Y, Z mm and three angles in degrees, the vendor's order).
#[derive(Debug, Clone, PartialEq)]
pub struct Move {
    pub line: usize,
    pub pose: [f64; 6],
    pub speed_mm_s: f64,
    /// The program asked to blend (C_DIS, CNT).
    pub blend_asked: bool,
    /// The controller could blend: the asked blend and nothing that stops
    /// the advance run (look-ahead) before the next motion.
    pub blended: bool,
}

/// The record of one run.
#[derive(Debug, Default)]
pub struct Trace {
    pub events: Vec<Event>,
    /// The index in `events` of the last motion, while it may still blend.
    pending_blend: Option<usize>,
    /// Whether the advance run may see past the pending motion.
    pub look_ahead: bool,
}

impl Trace {
    pub fn statement(&mut self, line: usize) {
        self.events.push(Event::Statement(line));
    }

    /// A motion statement: the previous motion blends into it when it
    /// asked to and nothing stopped the advance run in between.
    pub fn motion(&mut self, line: usize, pose: [f64; 6], speed_mm_s: f64, blend_asked: bool) {
        if let Some(k) = self.pending_blend.take()
            && let Event::Move(m) = &mut self.events[k]
        {
            m.blended = self.look_ahead;
        }
        self.events.push(Event::Move(Move { line, pose, speed_mm_s, blend_asked, blended: false }));
        if blend_asked {
            self.pending_blend = Some(self.events.len() - 1);
        }
    }

    /// Something that stops the advance run (a WAIT, an output without
    /// CONTINUE, a read of the actual position): the robot stops at the
    /// motion before it, whatever it asked.
    pub fn advance_stop(&mut self) {
        self.pending_blend = None;
    }

    pub fn push(&mut self, event: Event) {
        if matches!(event, Event::Sent(_) | Event::Read(_)) {
            self.advance_stop();
        }
        self.events.push(event);
    }

    pub fn moves(&self) -> Vec<&Move> {
        self.events.iter().filter_map(|e| if let Event::Move(m) = e { Some(m) } else { None }).collect()
    }

    pub fn sent(&self) -> Vec<&str> {
        self.events.iter().filter_map(|e| if let Event::Sent(s) = e { Some(s.as_str()) } else { None }).collect()
    }

    pub fn reads(&self) -> Vec<&str> {
        self.events.iter().filter_map(|e| if let Event::Read(s) = e { Some(s.as_str()) } else { None }).collect()
    }

    /// Each weld, from arc on to arc off: the motions between them and
    /// whether the network was touched. Fails on an arc left on.
    pub fn welds(&self) -> Result<Vec<Weld>, String> {
        let mut welds = Vec::new();
        let mut current: Option<Weld> = None;
        for event in &self.events {
            match (event, current.as_mut()) {
                (Event::ArcOn, None) => current = Some(Weld::default()),
                (Event::ArcOn, Some(_)) => return Err("arc on twice".into()),
                (Event::ArcOff, Some(_)) => welds.push(current.take().expect("a weld")),
                (Event::ArcOff, None) => return Err("arc off without arc on".into()),
                (Event::Move(m), Some(w)) => w.moves.push(m.clone()),
                (Event::Sent(_) | Event::Read(_), Some(w)) => w.network += 1,
                _ => {}
            }
        }
        match current {
            Some(_) => Err("the program ended with the arc on".into()),
            None => Ok(welds),
        }
    }
}

/// One arc-on stretch.
#[derive(Debug, Default)]
pub struct Weld {
    pub moves: Vec<Move>,
    /// Lines sent or read while the arc burned.
    pub network: usize,
}

impl Weld {
    /// Every motion but the last (the seam's end, where the arc goes off)
    /// blends into the next: one bead without a stop.
    pub fn continuous(&self) -> bool {
        let n = self.moves.len();
        n >= 1 && self.moves[..n - 1].iter().all(|m| m.blended) && !self.moves[n - 1].blend_asked
    }
}

/// A blend asked for is granted only when nothing stopped the advance
/// run before the next motion.
#[test]
fn an_advance_stop_between_two_motions_makes_an_exact_stop() {
    let mut trace = Trace { look_ahead: true, ..Trace::default() };
    trace.motion(1, [0.0; 6], 8.0, true);
    trace.motion(2, [1.0; 6], 8.0, true);
    trace.advance_stop();
    trace.motion(3, [2.0; 6], 8.0, false);
    let moves = trace.moves();
    assert_eq!(moves.iter().map(|m| m.blended).collect::<Vec<_>>(), [true, false, false]);
}
