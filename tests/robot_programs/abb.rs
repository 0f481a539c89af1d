//! deploy/robots/abb/WeldSeam.mod transcribed statement by statement onto
//! the emulated controller of [`super::rapid`]: each statement tagged with
//! its line and text in the module (checked by [`super::transcription`]);
//! RAPID's arrays are 1-based (index 0 of each vector is unused, and an
//! index out of range panics as the controller would stop); a socket
//! error propagates with `?` to FetchPlan's ERROR handler, as RAPID
//! raises it to the routine's handler.
#![allow(clippy::blocks_in_conditions)]

use super::rapid::{Errno, Rapid, RobTarget, cat, num_to_str, str_find, str_part, str_to_val};

/// What a test sets instead of the cell settings at the module's top.
pub struct Settings {
    pub daemon_ip: String,
    pub daemon_port: f64,
    pub joint: String,
    pub dry_run: bool,
}

pub const WELD_SPEED: f64 = 8.0;
/// vWeld's and vApproach's TCP speeds, zWeld's radius, mm.
pub const V_WELD: f64 = 8.0;
pub const V_APPROACH: f64 = 50.0;
pub const Z_WELD: f64 = 0.4;

/// The module's data.
struct Module {
    daemon_ip: String,
    daemon_port: f64,
    joint: String,
    dry_run: bool,
    reply_time: f64,
    max_lines: f64,
    check_tolerance: f64,
    path: Vec<RobTarget>,
    kind: Vec<f64>,
    seam_of: Vec<f64>,
    count: f64,
    seam_count: f64,
    result: f64,
    reason: String,
    field: [f64; 11],
    fields: f64,
    connected: bool,
    weld_speed: f64,
    speed: Vec<f64>,
    weave_amp: Vec<f64>,
    weave_freq: Vec<f64>,
    process: bool,
    /// wvWeld's weave_shape, weave_type, weave_length and weave_width.
    wv_weld: [f64; 4],
    /// vSeam's v_tcp.
    v_seam: f64,
}

/// Loads the module and runs main; returns `result` and the reason shown.
pub fn run(r: &mut Rapid, s: &Settings) -> (f64, String) {
    r.at(1, r#"MODULE WeldSeam"#);
    r.at(34, r#"CONST string DAEMON_IP := "192.168.1.10";"#);
    r.at(35, r#"CONST num DAEMON_PORT := 7303;"#);
    r.at(36, r#"CONST string JOINT := "lap";"#);
    r.at(37, r#"CONST bool DRY_RUN := TRUE;"#);
    r.at(38, r#"CONST num WELD_SPEED := 8;"#);
    r.at(39, r#"CONST speeddata vWeld := [8, 50, 5000, 1000];"#);
    r.at(40, r#"CONST zonedata zWeld := [FALSE, 0.4, 0.4, 0.4, 0.04, 0.4, 0.04];"#);
    r.at(41, r#"CONST speeddata vApproach := [50, 200, 5000, 1000];"#);
    r.at(42, r#"CONST num REPLY_TIME := 30;"#);
    r.at(43, r#"CONST num MAX_LINES := 2000;"#);
    r.at(44, r#"CONST num CHECK_TOLERANCE := 0.1;"#);
    r.at(
        49,
        r#"PERS tooldata tWeldGun := [TRUE, [[0, 0, 350], [1, 0, 0, 0]], [3, [0, 0, 100], [1, 0, 0, 0], 0, 0, 0]];"#,
    );
    r.at(54, r#"VAR robtarget path{MAX_LINES};"#);
    r.at(55, r#"VAR num kind{MAX_LINES};"#);
    r.at(56, r#"VAR num seamOf{MAX_LINES};"#);
    r.at(57, r#"VAR num speed{MAX_LINES};"#);
    r.at(58, r#"VAR num weaveAmp{MAX_LINES};"#);
    r.at(59, r#"VAR num weaveFreq{MAX_LINES};"#);
    r.at(60, r#"VAR bool process;"#);
    r.at(61, r#"VAR weavedata wvWeld;"#);
    r.at(62, r#"VAR speeddata vSeam;"#);
    r.at(63, r#"VAR num count;"#);
    r.at(64, r#"VAR num seamCount;"#);
    r.at(65, r#"VAR num result;"#);
    r.at(66, r#"VAR string reason;"#);
    r.at(67, r#"VAR socketdev sock;"#);
    r.at(68, r#"VAR num field{10};"#);
    r.at(69, r#"VAR num fields;"#);
    r.at(70, r#"VAR bool connected;"#);
    let max_lines = 2000.0;
    let zero = RobTarget { trans: [0.0; 3], rot: [1.0, 0.0, 0.0, 0.0] };
    let mut m = Module {
        daemon_ip: s.daemon_ip.clone(),
        daemon_port: s.daemon_port,
        joint: s.joint.clone(),
        dry_run: s.dry_run,
        reply_time: 30.0,
        max_lines,
        check_tolerance: 0.1,
        path: vec![zero; max_lines as usize + 1],
        kind: vec![0.0; max_lines as usize + 1],
        seam_of: vec![0.0; max_lines as usize + 1],
        count: 0.0,
        seam_count: 0.0,
        result: 0.0,
        reason: String::new(),
        field: [0.0; 11],
        fields: 0.0,
        connected: false,
        weld_speed: 0.0,
        speed: vec![0.0; max_lines as usize + 1],
        weave_amp: vec![0.0; max_lines as usize + 1],
        weave_freq: vec![0.0; max_lines as usize + 1],
        process: false,
        wv_weld: [0.0; 4],
        v_seam: 0.0,
    };
    main(r, &mut m);
    (m.result, m.reason)
}

fn main(r: &mut Rapid, m: &mut Module) {
    r.at(72, r#"PROC main()"#);
    r.at(73, r#"result := 0;"#);
    m.result = 0.0;
    r.at(74, r#"reason := "";"#);
    m.reason = String::new();
    r.at(75, r#"FetchPlan;"#);
    fetch_plan(r, m);
    r.at(76, r#"SocketClose sock;"#);
    r.socket_close();
    r.at(77, r#"IF result <> 0 THEN"#);
    if m.result != 0.0 {
        r.at(78, r#"TPWrite "weldseam result " \Num:=result;"#);
        r.tp_write(&format!("weldseam result {}", m.result));
        r.at(79, r#"TPWrite reason;"#);
        r.tp_write(&m.reason.clone());
        r.at(80, r#"Stop;"#);
        r.stop();
        r.at(81, r#"RETURN;"#);
        return;
    }
    r.at(83, r#"Weld;"#);
    weld(r, m);
}

fn fetch_plan(r: &mut Rapid, m: &mut Module) {
    r.at(88, r#"PROC FetchPlan()"#);
    r.at(89, r#"VAR robtarget capture;"#);
    r.at(90, r#"VAR string line;"#);
    r.at(91, r#"VAR num k;"#);
    r.at(92, r#"VAR num s;"#);
    r.at(93, r#"VAR num n;"#);
    r.at(94, r#"VAR num sx;"#);
    r.at(95, r#"VAR num sy;"#);
    r.at(96, r#"VAR num sz;"#);
    let body = |r: &mut Rapid, m: &mut Module| -> Result<(), Errno> {
        r.at(98, r#"connected := FALSE;"#);
        m.connected = false;
        r.at(99, r#"SocketCreate sock;"#);
        r.socket_create();
        r.at(100, r#"SocketConnect sock, DAEMON_IP, DAEMON_PORT \Time:=5;"#);
        r.socket_connect(&m.daemon_ip, m.daemon_port, 5.0)?;
        r.at(101, r#"connected := TRUE;"#);
        m.connected = true;
        r.at(102, r#"SocketSend sock \Str:="HELLO,abb,PROCESS\0D\0A";"#);
        r.socket_send("HELLO,abb,PROCESS\r\n")?;
        r.at(103, r#"line := Receive();"#);
        let mut line = receive(r, m)?;
        r.at(104, r#"IF NOT Numbers(line) THEN"#);
        if !numbers(r, m, &line) {
            r.at(105, r#"RETURN;"#);
            return Ok(());
        }
        r.at(107, r#"IF field{2} <> 2 THEN"#);
        if m.field[2] != 2.0 {
            r.at(108, r#"result := 8;"#);
            m.result = 8.0;
            r.at(109, r#"RETURN;"#);
            return Ok(());
        }
        r.at(111, r#"process := field{3} = 1;"#);
        m.process = m.field[3] == 1.0;
        r.at(113, r#"capture := CRobT(\Tool:=tool0 \WObj:=wobj0);"#);
        let capture = r.crobt_flange();
        r.at(114, r#"SocketSend sock \Str:="TRIGGER," + JOINT + ",";"#);
        r.socket_send(&cat(&cat("TRIGGER,", &m.joint), ","))?;
        r.at(115, r#"SocketSend sock \Str:=NumToStr(capture.trans.x, 2) + "," + NumToStr(capture.trans.y, 2) + "," + NumToStr(capture.trans.z, 2) + ",";"#);
        let [x, y, z] = capture.trans;
        let piece = cat(&cat(&cat(&cat(&cat(&num_to_str(x, 2), ","), &num_to_str(y, 2)), ","), &num_to_str(z, 2)), ",");
        r.socket_send(&piece)?;
        r.at(116, r#"SocketSend sock \Str:=NumToStr(capture.rot.q1, 6) + "," + NumToStr(capture.rot.q2, 6) + ",";"#);
        let [q1, q2, q3, q4] = capture.rot;
        r.socket_send(&cat(&cat(&cat(&num_to_str(q1, 6), ","), &num_to_str(q2, 6)), ","))?;
        r.at(
            117,
            r#"SocketSend sock \Str:=NumToStr(capture.rot.q3, 6) + "," + NumToStr(capture.rot.q4, 6) + "\0D\0A";"#,
        );
        r.socket_send(&cat(&cat(&cat(&num_to_str(q3, 6), ","), &num_to_str(q4, 6)), "\r\n"))?;
        r.at(118, r#"line := Receive();"#);
        line = receive(r, m)?;
        r.at(119, r#"IF NOT Numbers(line) THEN"#);
        if !numbers(r, m, &line) {
            r.at(120, r#"RETURN;"#);
            return Ok(());
        }
        r.at(122, r#"seamCount := field{2};"#);
        m.seam_count = m.field[2];
        r.at(123, r#"count := field{3};"#);
        m.count = m.field[3];
        r.at(124, r#"IF count > MAX_LINES THEN"#);
        if m.count > m.max_lines {
            r.at(125, r#"result := 5;"#);
            m.result = 5.0;
            r.at(126, r#"SocketSend sock \Str:="DROP\0D\0A";"#);
            r.socket_send("DROP\r\n")?;
            r.at(127, r#"line := Receive();"#);
            receive(r, m)?;
            r.at(128, r#"RETURN;"#);
            return Ok(());
        }
        let mut k = 1.0;
        while {
            r.at(130, r#"FOR k FROM 1 TO count DO"#);
            k <= m.count
        } {
            let i = k as usize;
            r.at(131, r#"SocketSend sock \Str:="NEXT\0D\0A";"#);
            r.socket_send("NEXT\r\n")?;
            r.at(132, r#"line := Receive();"#);
            line = receive(r, m)?;
            r.at(133, r#"IF NOT Numbers(line) THEN"#);
            if !numbers(r, m, &line) {
                r.at(134, r#"RETURN;"#);
                return Ok(());
            }
            let f = m.field;
            r.at(136, r#"IF (field{1} = 4 AND fields <> 6) OR (field{1} <> 4 AND fields <> 10) OR field{3} <> count - k THEN"#);
            if (f[1] == 4.0 && m.fields != 6.0) || (f[1] != 4.0 && m.fields != 10.0) || f[3] != m.count - k {
                r.at(137, r#"result := 7;"#);
                m.result = 7.0;
                r.at(138, r#"RETURN;"#);
                return Ok(());
            }
            if {
                r.at(140, r#"IF k = 1 THEN"#);
                k == 1.0
            } {
                r.at(141, r#"IF field{1} <> 1 OR field{2} <> 1 THEN"#);
                if f[1] != 1.0 || f[2] != 1.0 {
                    r.at(142, r#"result := 7;"#);
                    m.result = 7.0;
                    r.at(143, r#"RETURN;"#);
                    return Ok(());
                }
            } else if {
                r.at(145, r#"ELSEIF field{1} = 1 THEN"#);
                f[1] == 1.0
            } {
                r.at(146, r#"IF kind{k - 1} <> 3 OR field{2} <> seamOf{k - 1} + 1 THEN"#);
                if m.kind[i - 1] != 3.0 || f[2] != m.seam_of[i - 1] + 1.0 {
                    r.at(147, r#"result := 7;"#);
                    m.result = 7.0;
                    r.at(148, r#"RETURN;"#);
                    return Ok(());
                }
            } else if {
                r.at(150, r#"ELSEIF (process AND kind{k - 1} = 2 AND field{1} <> 4) OR ((NOT process OR kind{k - 1} <> 2) AND field{1} = 4) THEN"#);
                (m.process && m.kind[i - 1] == 2.0 && f[1] != 4.0)
                    || ((!m.process || m.kind[i - 1] != 2.0) && f[1] == 4.0)
            } {
                r.at(151, r#"result := 7;"#);
                m.result = 7.0;
                r.at(152, r#"RETURN;"#);
                return Ok(());
            } else if {
                r.at(153, r#"ELSEIF kind{k - 1} = 3 OR field{2} <> seamOf{k - 1} OR (field{1} = 3 AND kind{k - 1} <> 2 AND kind{k - 1} <> 4) THEN"#);
                m.kind[i - 1] == 3.0
                    || f[2] != m.seam_of[i - 1]
                    || (f[1] == 3.0 && m.kind[i - 1] != 2.0 && m.kind[i - 1] != 4.0)
            } {
                r.at(154, r#"result := 7;"#);
                m.result = 7.0;
                r.at(155, r#"RETURN;"#);
                return Ok(());
            }
            r.at(157, r#"path{k} := capture;"#);
            m.path[i] = capture;
            r.at(158, r#"kind{k} := field{1};"#);
            m.kind[i] = f[1];
            r.at(159, r#"seamOf{k} := field{2};"#);
            m.seam_of[i] = f[2];
            r.at(160, r#"IF field{1} = 4 THEN"#);
            if f[1] == 4.0 {
                r.at(161, r#"speed{k} := field{4};"#);
                m.speed[i] = f[4];
                r.at(162, r#"weaveAmp{k} := field{5};"#);
                m.weave_amp[i] = f[5];
                r.at(163, r#"weaveFreq{k} := field{6};"#);
                m.weave_freq[i] = f[6];
            } else {
                r.at(165, r#"path{k}.trans := [field{4}, field{5}, field{6}];"#);
                m.path[i].trans = [f[4], f[5], f[6]];
                r.at(166, r#"path{k}.rot := [field{7}, field{8}, field{9}, field{10}];"#);
                m.path[i].rot = [f[7], f[8], f[9], f[10]];
            }
            k += 1.0;
        }
        r.at(169, r#"IF count > 0 THEN"#);
        if m.count > 0.0 {
            let last = m.count as usize;
            r.at(170, r#"IF kind{count} <> 3 OR seamOf{count} <> seamCount THEN"#);
            if m.kind[last] != 3.0 || m.seam_of[last] != m.seam_count {
                r.at(171, r#"result := 7;"#);
                m.result = 7.0;
                r.at(172, r#"RETURN;"#);
                return Ok(());
            }
        }
        let mut s = 1.0;
        while {
            r.at(175, r#"FOR s FROM 1 TO seamCount DO"#);
            s <= m.seam_count
        } {
            r.at(176, r#"n := 0;"#);
            let mut n = 0.0;
            r.at(177, r#"sx := 0;"#);
            let mut sx = 0.0;
            r.at(178, r#"sy := 0;"#);
            let mut sy = 0.0;
            r.at(179, r#"sz := 0;"#);
            let mut sz = 0.0;
            let mut k = 1.0;
            while {
                r.at(180, r#"FOR k FROM 1 TO count DO"#);
                k <= m.count
            } {
                let i = k as usize;
                r.at(181, r#"IF seamOf{k} = s AND kind{k} <> 4 THEN"#);
                if m.seam_of[i] == s && m.kind[i] != 4.0 {
                    r.at(182, r#"n := n + 1;"#);
                    n += 1.0;
                    r.at(183, r#"sx := sx + path{k}.trans.x;"#);
                    sx += m.path[i].trans[0];
                    r.at(184, r#"sy := sy + path{k}.trans.y;"#);
                    sy += m.path[i].trans[1];
                    r.at(185, r#"sz := sz + path{k}.trans.z;"#);
                    sz += m.path[i].trans[2];
                }
                k += 1.0;
            }
            r.at(188, r#"SocketSend sock \Str:="CHECK," + NumToStr(s, 0) + "\0D\0A";"#);
            r.socket_send(&cat(&cat("CHECK,", &num_to_str(s, 0)), "\r\n"))?;
            r.at(189, r#"line := Receive();"#);
            line = receive(r, m)?;
            r.at(190, r#"IF NOT Numbers(line) THEN"#);
            if !numbers(r, m, &line) {
                r.at(191, r#"RETURN;"#);
                return Ok(());
            }
            let f = m.field;
            r.at(193, r#"IF fields <> 5 OR n = 0 OR field{2} <> n THEN"#);
            if m.fields != 5.0 || n == 0.0 || f[2] != n {
                r.at(194, r#"result := 6;"#);
                m.result = 6.0;
                r.at(195, r#"RETURN;"#);
                return Ok(());
            }
            r.at(197, r#"IF Abs(sx / n - field{3}) > CHECK_TOLERANCE OR Abs(sy / n - field{4}) > CHECK_TOLERANCE OR Abs(sz / n - field{5}) > CHECK_TOLERANCE THEN"#);
            let tolerance = m.check_tolerance;
            if (sx / n - f[3]).abs() > tolerance
                || (sy / n - f[4]).abs() > tolerance
                || (sz / n - f[5]).abs() > tolerance
            {
                r.at(198, r#"result := 6;"#);
                m.result = 6.0;
                r.at(199, r#"RETURN;"#);
                return Ok(());
            }
            s += 1.0;
        }
        Ok(())
    };
    if let Err(errno) = body(r, m) {
        if {
            r.at(203, r#"IF NOT connected THEN"#);
            !m.connected
        } {
            r.at(204, r#"result := 1;"#);
            m.result = 1.0;
        } else if {
            r.at(205, r#"ELSEIF ERRNO = ERR_SOCK_TIMEOUT THEN"#);
            errno == Errno::SockTimeout
        } {
            r.at(206, r#"result := 3;"#);
            m.result = 3.0;
        } else if {
            r.at(207, r#"ELSEIF ERRNO = ERR_SOCK_CLOSED THEN"#);
            errno == Errno::SockClosed
        } {
            r.at(208, r#"result := 2;"#);
            m.result = 2.0;
        } else {
            r.at(210, r#"result := 4;"#);
            m.result = 4.0;
        }
        r.at(212, r#"RETURN;"#);
    }
}

fn receive(r: &mut Rapid, m: &Module) -> Result<String, Errno> {
    r.at(217, r#"FUNC string Receive()"#);
    r.at(218, r#"VAR string line := "";"#);
    let mut line = String::new();
    r.at(219, r#"VAR string part;"#);
    while {
        r.at(221, r#"WHILE StrFind(line, 1, "\0A") > StrLen(line) DO"#);
        str_find(&line, 1.0, "\n") > line.len() as f64
    } {
        r.at(222, r#"SocketReceive sock \Str:=part \Time:=REPLY_TIME;"#);
        let part = r.socket_receive(m.reply_time)?;
        r.at(223, r#"IF StrLen(line) + StrLen(part) > 80 THEN"#);
        if line.len() + part.len() > 80 {
            r.at(224, r#"RETURN "";"#);
            return Ok(String::new());
        }
        r.at(226, r#"line := line + part;"#);
        line = cat(&line, &part);
    }
    r.at(228, r#"RETURN line;"#);
    Ok(line)
}

fn numbers(r: &mut Rapid, m: &mut Module, line: &str) -> bool {
    r.at(235, r#"FUNC bool Numbers(string line)"#);
    r.at(236, r#"VAR num start := 1;"#);
    let mut start = 1.0;
    r.at(237, r#"VAR num comma;"#);
    r.at(238, r#"VAR num stop;"#);
    r.at(239, r#"VAR string text;"#);
    r.at(241, r#"fields := 0;"#);
    m.fields = 0.0;
    r.at(242, r#"stop := StrFind(line, 1, "\0D\0A");"#);
    let stop = str_find(line, 1.0, "\r\n");
    r.at(243, r#"IF stop > StrLen(line) THEN"#);
    if stop > line.len() as f64 {
        r.at(244, r#"result := 4;"#);
        m.result = 4.0;
        r.at(245, r#"RETURN FALSE;"#);
        return false;
    }
    while {
        r.at(247, r#"WHILE start <= stop AND fields < 10 DO"#);
        start <= stop && m.fields < 10.0
    } {
        r.at(248, r#"comma := StrFind(line, start, ",");"#);
        let mut comma = str_find(line, start, ",");
        r.at(249, r#"IF comma > stop THEN"#);
        if comma > stop {
            r.at(250, r#"comma := stop;"#);
            comma = stop;
        }
        r.at(252, r#"text := StrPart(line, start, comma - start);"#);
        let text = str_part(line, start, comma - start);
        r.at(253, r#"fields := fields + 1;"#);
        m.fields += 1.0;
        let k = m.fields as usize;
        r.at(254, r#"IF NOT StrToVal(text, field{fields}) THEN"#);
        let Some(value) = str_to_val(&text) else {
            r.at(255, r#"result := 4;"#);
            m.result = 4.0;
            r.at(256, r#"RETURN FALSE;"#);
            return false;
        };
        m.field[k] = value;
        r.at(258, r#"IF fields = 1 AND field{1} < 0 THEN"#);
        if m.fields == 1.0 && m.field[1] < 0.0 {
            r.at(259, r#"result := field{1};"#);
            m.result = m.field[1];
            r.at(260, r#"reason := StrPart(line, comma + 1, stop - comma - 1);"#);
            m.reason = str_part(line, comma + 1.0, stop - comma - 1.0);
            r.at(261, r#"RETURN FALSE;"#);
            return false;
        }
        r.at(263, r#"start := comma + 1;"#);
        start = comma + 1.0;
    }
    r.at(265, r#"IF start <= stop THEN"#);
    if start <= stop {
        r.at(266, r#"result := 4;"#);
        m.result = 4.0;
        r.at(267, r#"RETURN FALSE;"#);
        return false;
    }
    r.at(269, r#"RETURN TRUE;"#);
    true
}

fn weld(r: &mut Rapid, m: &mut Module) {
    r.at(273, r#"PROC Weld()"#);
    r.at(274, r#"VAR num i;"#);
    r.at(275, r#"VAR num after;"#);
    r.at(277, r#"ConfL \Off;"#);
    let fine = None;
    let z_weld = Some(Z_WELD);
    let mut k = 1.0;
    while {
        r.at(278, r#"FOR i FROM 1 TO count DO"#);
        k <= m.count
    } {
        let i = k as usize;
        if {
            r.at(279, r#"IF kind{i} = 4 THEN"#);
            m.kind[i] == 4.0
        } {
        } else if {
            r.at(281, r#"ELSEIF kind{i} = 1 OR kind{i} = 3 THEN"#);
            m.kind[i] == 1.0 || m.kind[i] == 3.0
        } {
            r.at(282, r#"MoveL path{i}, vApproach, fine, tWeldGun \WObj:=wobj0;"#);
            r.move_l(282, &m.path[i], V_APPROACH, fine);
        } else if {
            r.at(283, r#"ELSEIF kind{i - 1} = 1 THEN"#);
            m.kind[i - 1] == 1.0
        } {
            r.at(285, r#"IF DRY_RUN THEN"#);
            if m.dry_run {
                r.at(286, r#"MoveL path{i}, vApproach, fine, tWeldGun \WObj:=wobj0;"#);
                r.move_l(286, &m.path[i], V_APPROACH, fine);
            } else {
                r.at(288, r#"wdWeld.weld_speed := WELD_SPEED;"#);
                m.weld_speed = WELD_SPEED;
                r.at(289, r#"ArcLStart path{i}, vApproach, smWeld, wdWeld, fine, tWeldGun \WObj:=wobj0;"#);
                r.arc_l_start(289, &m.path[i], V_APPROACH, fine);
            }
        } else {
            r.at(293, r#"after := i + 1;"#);
            let mut next = i + 1;
            r.at(294, r#"IF kind{i + 1} = 4 THEN"#);
            if m.kind[i + 1] == 4.0 {
                r.at(295, r#"after := i + 2;"#);
                next = i + 2;
            }
            r.at(297, r#"SetProcess i;"#);
            set_process(r, m, i);
            // `\Weave:=wvWeld`: the weave the controller lays, as its
            // width and cycle length, none at weave_shape 0.
            let weave = (m.wv_weld[0] != 0.0).then_some([m.wv_weld[3], m.wv_weld[2]]);
            if {
                r.at(298, r#"IF kind{after} = 3 THEN"#);
                m.kind[next] == 3.0
            } {
                r.at(300, r#"IF DRY_RUN THEN"#);
                if m.dry_run {
                    r.at(301, r#"MoveL path{i}, vSeam, fine, tWeldGun \WObj:=wobj0;"#);
                    r.move_l(301, &m.path[i], m.v_seam, fine);
                } else {
                    r.at(303, r#"ArcLEnd path{i}, vSeam, smWeld, wdWeld \Weave:=wvWeld, fine, tWeldGun \WObj:=wobj0;"#);
                    r.arc_l_end(303, &m.path[i], m.weld_speed, fine, weave);
                }
            } else if {
                r.at(305, r#"ELSEIF DRY_RUN THEN"#);
                m.dry_run
            } {
                r.at(306, r#"MoveL path{i}, vSeam, zWeld, tWeldGun \WObj:=wobj0;"#);
                r.move_l(306, &m.path[i], m.v_seam, z_weld);
            } else {
                r.at(308, r#"ArcL path{i}, vSeam, smWeld, wdWeld \Weave:=wvWeld, zWeld, tWeldGun \WObj:=wobj0;"#);
                r.arc_l(308, &m.path[i], m.weld_speed, z_weld, weave);
            }
        }
        k += 1.0;
    }
}

fn set_process(r: &mut Rapid, m: &mut Module, i: usize) {
    r.at(317, r#"PROC SetProcess(num i)"#);
    r.at(318, r#"vSeam := vWeld;"#);
    m.v_seam = V_WELD;
    r.at(319, r#"wdWeld.weld_speed := WELD_SPEED;"#);
    m.weld_speed = WELD_SPEED;
    r.at(320, r#"wvWeld.weave_shape := 0;"#);
    m.wv_weld[0] = 0.0;
    r.at(321, r#"IF kind{i + 1} = 4 THEN"#);
    if m.kind[i + 1] == 4.0 {
        r.at(322, r#"IF speed{i + 1} > 0 THEN"#);
        if m.speed[i + 1] > 0.0 {
            r.at(323, r#"wdWeld.weld_speed := speed{i + 1};"#);
            m.weld_speed = m.speed[i + 1];
            r.at(324, r#"vSeam.v_tcp := speed{i + 1};"#);
            m.v_seam = m.speed[i + 1];
            r.at(325, r#"IF weaveAmp{i + 1} > 0 AND weaveFreq{i + 1} > 0 THEN"#);
            if m.weave_amp[i + 1] > 0.0 && m.weave_freq[i + 1] > 0.0 {
                r.at(326, r#"wvWeld.weave_shape := 1;"#);
                m.wv_weld[0] = 1.0;
                r.at(327, r#"wvWeld.weave_type := 0;"#);
                m.wv_weld[1] = 0.0;
                r.at(328, r#"wvWeld.weave_length := speed{i + 1} / weaveFreq{i + 1};"#);
                m.wv_weld[2] = m.speed[i + 1] / m.weave_freq[i + 1];
                r.at(329, r#"wvWeld.weave_width := 2 * weaveAmp{i + 1};"#);
                m.wv_weld[3] = 2.0 * m.weave_amp[i + 1];
            }
        }
    }
}

#[test]
fn the_transcription_follows_the_module_line_by_line() {
    let source = include_str!("abb.rs");
    let transcription = &source[..source.find("#[test]").unwrap()];
    let statements = super::transcription::check("abb/WeldSeam.mod", transcription, super::rapid::is_statement)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(statements > 150, "{statements}");
}
