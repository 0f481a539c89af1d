//! `deploy/robots/fanuc/weldseam.kl`, the KAREL helper, transcribed
//! statement by statement onto the emulated KAREL primitives of
//! `karel.rs`, each statement tagged with its line and text in the file;
//! the TP program that calls it is in `fanuc_tp.rs`.

use weldseam::geometry::Isometry3;

use super::karel::{Controller, Xyzwpr, cnv_int_str, cnv_real_str, cnv_str_int, cnv_str_real, index, str_len, sub_str};

/// What a scenario sets in the helper's CONST block, as an integrator
/// would edit it; `None` keeps the shipped value.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    pub joint: Option<String>,
    pub reply_ms: Option<i32>,
}

/// The helper's program variables: they keep their values between calls.
pub struct Helper {
    joint: String,
    max_lines: i32,
    reply_ms: i32,
    poll_ms: i32,
    check_mm: f32,
    opened: bool,
    reply: String,
    fields: [Option<f32>; 11],
    points: Vec<Xyzwpr>,
    kinds: Vec<i32>,
    seam_of: Vec<i32>,
    speeds: Vec<f32>,
    amps: Vec<f32>,
    freqs: Vec<f32>,
    process: bool,
    next_pr: i32,
    count: i32,
    seams: i32,
    capture: Xyzwpr,
}

/// The declarations: PROGRAM, its CONST and VAR sections.
pub fn load_program(k: &mut Controller, ov: &Overrides) -> Helper {
    k.at(30, r#"PROGRAM weldseam"#);
    k.at(31, r#"%COMMENT = 'weldseam text'"#);
    k.at(32, r#"%NOLOCKGROUP"#);
    k.at(34, r#"TAG = 'C3:'"#);
    k.at(35, r#"JOINT = 'lap'"#);
    k.at(36, r#"MAX_LINES = 2000"#);
    k.at(37, r#"REPLY_MS = 20000"#);
    k.at(38, r#"POLL_MS = 8"#);
    k.at(39, r#"CHECK_MM = 0.1"#);
    k.at(41, r#"sock : FILE"#);
    k.at(42, r#"opened : BOOLEAN"#);
    k.at(43, r#"reply : STRING[254]"#);
    k.at(44, r#"fields : ARRAY[10] OF REAL"#);
    k.at(45, r#"points : ARRAY[2000] OF XYZWPR"#);
    k.at(46, r#"kinds : ARRAY[2000] OF INTEGER"#);
    k.at(47, r#"seam_of : ARRAY[2000] OF INTEGER"#);
    k.at(48, r#"speeds : ARRAY[2000] OF REAL"#);
    k.at(49, r#"amps : ARRAY[2000] OF REAL"#);
    k.at(50, r#"freqs : ARRAY[2000] OF REAL"#);
    k.at(51, r#"process : BOOLEAN"#);
    k.at(52, r#"next_pr : INTEGER"#);
    k.at(53, r#"count, seams, mode, line_no, ptype, result, status : INTEGER"#);
    k.at(54, r#"rval : REAL"#);
    k.at(55, r#"sval : STRING[16]"#);
    k.at(56, r#"capture : XYZWPR"#);
    Helper {
        joint: ov.joint.clone().unwrap_or_else(|| "lap".into()),
        max_lines: 2000,
        reply_ms: ov.reply_ms.unwrap_or(20000),
        poll_ms: 8,
        check_mm: 0.1,
        opened: false,
        reply: String::new(),
        fields: [None; 11],
        // KAREL arrays count from 1: element 0 is never used.
        points: vec![Xyzwpr::default(); 2001],
        kinds: vec![0; 2001],
        seam_of: vec![0; 2001],
        speeds: vec![0.0; 2001],
        amps: vec![0.0; 2001],
        freqs: vec![0.0; 2001],
        process: false,
        next_pr: 0,
        count: 0,
        seams: 0,
        capture: Xyzwpr::default(),
    }
}

fn round(v: Option<f32>) -> i32 {
    v.expect("an initialized REAL").round() as i32
}

fn ask(k: &mut Controller, h: &mut Helper, request: &str) -> i32 {
    k.at(61, r#"ROUTINE ask(request : STRING) : INTEGER"#);
    k.at(63, r#"waited, ahead, stat, comma, code : INTEGER"#);
    k.at(65, r#"WRITE sock(request, CR)"#);
    k.write_line(request);
    k.at(66, r#"IF IO_STATUS(sock) <> 0 THEN"#);
    if k.io_status() != 0 {
        k.at(67, r#"RETURN(2)"#);
        return 2;
    }
    k.at(69, r#"waited = 0"#);
    let mut waited = 0;
    k.at(70, r#"ahead = 0"#);
    let mut ahead = 0;
    k.at(71, r#"WHILE ahead = 0 DO"#);
    while ahead == 0 {
        k.at(72, r#"BYTES_AHEAD(sock, ahead, stat)"#);
        let stat;
        (ahead, stat) = k.bytes_ahead();
        k.at(73, r#"IF stat <> 0 THEN"#);
        if stat != 0 {
            k.at(74, r#"RETURN(2)"#);
            return 2;
        }
        k.at(76, r#"IF ahead = 0 THEN"#);
        if ahead == 0 {
            k.at(77, r#"IF waited >= REPLY_MS THEN"#);
            if waited >= h.reply_ms {
                k.at(78, r#"RETURN(3)"#);
                return 3;
            }
            k.at(80, r#"DELAY(POLL_MS)"#);
            std::thread::sleep(std::time::Duration::from_millis(h.poll_ms as u64));
            k.at(81, r#"waited = waited + POLL_MS"#);
            waited += h.poll_ms;
        }
    }
    k.at(84, r#"READ sock(reply, CR)"#);
    h.reply = k.read_line(254);
    k.at(85, r#"IF IO_STATUS(sock) <> 0 THEN"#);
    if k.io_status() != 0 {
        k.at(86, r#"RETURN(2)"#);
        return 2;
    }
    k.at(88, r#"IF SUB_STR(reply, 1, 1) <> '-' THEN"#);
    if sub_str(&h.reply, 1, 1) != "-" {
        k.at(89, r#"RETURN(0)"#);
        return 0;
    }
    k.at(91, r#"comma = INDEX(reply, ',')"#);
    let comma = index(&h.reply, ",");
    k.at(92, r#"IF comma < 3 THEN"#);
    if comma < 3 {
        k.at(93, r#"RETURN(4)"#);
        return 4;
    }
    k.at(95, r#"CNV_STR_INT(SUB_STR(reply, 2, comma - 2), code)"#);
    let code = cnv_str_int(&sub_str(&h.reply, 2, comma - 2));
    k.at(96, r#"IF UNINIT(code) THEN"#);
    let Some(code) = code else {
        k.at(97, r#"RETURN(4)"#);
        return 4;
    };
    k.at(99, r#"WRITE TPERROR(SUB_STR(reply, comma + 1, STR_LEN(reply) - comma), CR)"#);
    let reason = sub_str(&h.reply, comma + 1, str_len(&h.reply) - comma);
    k.tperror.push(reason);
    k.at(100, r#"RETURN(-code)"#);
    k.at(101, r#"END ask"#);
    -code
}

fn split(k: &mut Controller, h: &mut Helper, answer: &str) -> i32 {
    k.at(105, r#"ROUTINE split(answer : STRING) : INTEGER"#);
    k.at(107, r#"comma, n : INTEGER"#);
    k.at(108, r#"part : STRING[32]"#);
    k.at(109, r#"rest : STRING[254]"#);
    k.at(111, r#"n = 0"#);
    let mut n = 0;
    k.at(112, r#"rest = answer"#);
    let mut rest = answer.to_string();
    k.at(113, r#"WHILE STR_LEN(rest) > 0 DO"#);
    while str_len(&rest) > 0 {
        k.at(114, r#"IF n >= 10 THEN"#);
        if n >= 10 {
            k.at(115, r#"RETURN(0)"#);
            return 0;
        }
        k.at(117, r#"comma = INDEX(rest, ',')"#);
        let comma = index(&rest, ",");
        k.at(118, r#"IF comma = 0 THEN"#);
        let part;
        if comma == 0 {
            k.at(119, r#"part = rest"#);
            part = sub_str(&rest, 1, 32);
            k.at(120, r#"rest = ''"#);
            rest = String::new();
        } else {
            k.at(121, r#"ELSE"#);
            k.at(122, r#"part = SUB_STR(rest, 1, comma - 1)"#);
            part = sub_str(&rest, 1, (comma - 1).min(32));
            k.at(123, r#"rest = SUB_STR(rest, comma + 1, STR_LEN(rest) - comma)"#);
            rest = sub_str(&rest, comma + 1, str_len(&rest) - comma);
        }
        k.at(125, r#"n = n + 1"#);
        n += 1;
        k.at(126, r#"CNV_STR_REAL(part, fields[n])"#);
        h.fields[n as usize] = cnv_str_real(&part);
        k.at(127, r#"IF UNINIT(fields[n]) THEN"#);
        if h.fields[n as usize].is_none() {
            k.at(128, r#"RETURN(0)"#);
            return 0;
        }
    }
    k.at(131, r#"RETURN(n)"#);
    k.at(132, r#"END split"#);
    n
}

fn flange(k: &mut Controller, h: &mut Helper) -> i32 {
    k.at(138, r#"ROUTINE flange : INTEGER"#);
    k.at(140, r#"here, tool : POSITION"#);
    k.at(142, r#"IF $MNUFRAMENUM[1] <> 0 THEN"#);
    if k.uframe_num != 0 {
        k.at(143, r#"RETURN(10)"#);
        return 10;
    }
    k.at(145, r#"here = CURPOS(0, 0, 1)"#);
    let mut here: Isometry3<f64> = k.curpos();
    k.at(146, r#"IF $MNUTOOLNUM[1] <> 0 THEN"#);
    if k.utool_num != 0 {
        k.at(147, r#"tool = $MNUTOOL[1, $MNUTOOLNUM[1]]"#);
        let tool = k.tools[k.utool_num];
        k.at(148, r#"here = here : INV(tool)"#);
        here *= tool.inverse();
    }
    k.at(150, r#"capture = here"#);
    h.capture = Xyzwpr::of(&here);
    k.at(151, r#"RETURN(0)"#);
    k.at(152, r#"END flange"#);
    0
}

fn number(k: &mut Controller, line: &str, value: f32, decimals: usize) -> String {
    k.at(155, r#"ROUTINE number(line : STRING; value : REAL; decimals : INTEGER) : STRING"#);
    k.at(157, r#"text : STRING[32]"#);
    k.at(159, r#"CNV_REAL_STR(value, 1, decimals, text)"#);
    let text = cnv_real_str(value, 1, decimals);
    k.at(160, r#"RETURN(line + ',' + text)"#);
    k.at(161, r#"END number"#);
    format!("{line},{text}")
}

fn session(k: &mut Controller, h: &mut Helper) -> i32 {
    k.at(164, r#"ROUTINE session : INTEGER"#);
    k.at(166, r#"r, i, k, n : INTEGER"#);
    k.at(167, r#"sx, sy, sz : REAL"#);
    k.at(168, r#"first : XYZWPR"#);
    let mut first = Xyzwpr::default();
    k.at(169, r#"text : STRING[16]"#);
    k.at(170, r#"line : STRING[254]"#);
    k.at(172, r#"MSG_DISCO(TAG, status)"#);
    k.msg_disco("C3:");
    k.at(173, r#"MSG_CONNECT(TAG, status)"#);
    let status = k.msg_connect("C3:");
    k.at(174, r#"IF status <> 0 THEN"#);
    if status != 0 {
        k.at(175, r#"RETURN(1)"#);
        return 1;
    }
    k.at(177, r#"OPEN FILE sock('RW', TAG)"#);
    k.open_file();
    k.at(178, r#"IF IO_STATUS(sock) <> 0 THEN"#);
    if k.io_status() != 0 {
        k.at(179, r#"RETURN(1)"#);
        return 1;
    }
    k.at(181, r#"opened = TRUE"#);
    h.opened = true;
    k.at(182, r#"r = ask('HELLO,fanuc,PROCESS')"#);
    let mut r = ask(k, h, "HELLO,fanuc,PROCESS");
    k.at(183, r#"IF r <> 0 THEN"#);
    if r != 0 {
        k.at(184, r#"RETURN(r)"#);
        return r;
    }
    k.at(186, r#"IF split(reply) <> 3 THEN"#);
    let reply = h.reply.clone();
    if split(k, h, &reply) != 3 {
        k.at(187, r#"RETURN(4)"#);
        return 4;
    }
    k.at(189, r#"IF ROUND(fields[2]) <> 2 THEN"#);
    if round(h.fields[2]) != 2 {
        k.at(190, r#"RETURN(8)"#);
        return 8;
    }
    k.at(192, r#"process = (ROUND(fields[3]) = 1)"#);
    h.process = round(h.fields[3]) == 1;

    k.at(195, r#"r = flange"#);
    r = flange(k, h);
    k.at(196, r#"IF r <> 0 THEN"#);
    if r != 0 {
        k.at(197, r#"RETURN(r)"#);
        return r;
    }
    k.at(199, r#"line = 'TRIGGER,' + JOINT"#);
    let mut line = format!("TRIGGER,{}", h.joint);
    let c = h.capture;
    k.at(200, r#"line = number(line, capture.x, 3)"#);
    line = number(k, &line, c.x, 3);
    k.at(201, r#"line = number(line, capture.y, 3)"#);
    line = number(k, &line, c.y, 3);
    k.at(202, r#"line = number(line, capture.z, 3)"#);
    line = number(k, &line, c.z, 3);
    k.at(203, r#"line = number(line, capture.w, 4)"#);
    line = number(k, &line, c.w, 4);
    k.at(204, r#"line = number(line, capture.p, 4)"#);
    line = number(k, &line, c.p, 4);
    k.at(205, r#"line = number(line, capture.r, 4)"#);
    line = number(k, &line, c.r, 4);
    assert!(line.len() <= 254, "a STRING[254] holds the plan line");
    k.at(206, r#"r = ask(line)"#);
    r = ask(k, h, &line);
    k.at(207, r#"IF r <> 0 THEN"#);
    if r != 0 {
        k.at(208, r#"RETURN(r)"#);
        return r;
    }
    k.at(211, r#"IF split(reply) <> 3 THEN"#);
    let reply = h.reply.clone();
    if split(k, h, &reply) != 3 {
        k.at(212, r#"RETURN(4)"#);
        return 4;
    }
    k.at(214, r#"seams = ROUND(fields[2])"#);
    h.seams = round(h.fields[2]);
    k.at(215, r#"count = ROUND(fields[3])"#);
    h.count = round(h.fields[3]);
    k.at(216, r#"IF (seams < 1) OR (count < 3 * seams) THEN"#);
    if h.seams < 1 || h.count < 3 * h.seams {
        k.at(217, r#"RETURN(4)"#);
        return 4;
    }
    k.at(219, r#"IF count > MAX_LINES THEN"#);
    if h.count > h.max_lines {
        k.at(220, r#"r = ask('DROP')"#);
        ask(k, h, "DROP");
        k.at(221, r#"RETURN(5)"#);
        return 5;
    }

    k.at(226, r#"i = 0"#);
    let mut i = 0;
    k.at(227, r#"WHILE i < count DO"#);
    while i < h.count {
        k.at(228, r#"i = i + 1"#);
        i += 1;
        k.at(229, r#"r = ask('NEXT')"#);
        r = ask(k, h, "NEXT");
        k.at(230, r#"IF r <> 0 THEN"#);
        if r != 0 {
            k.at(231, r#"RETURN(r)"#);
            return r;
        }
        k.at(233, r#"n = split(reply)"#);
        let reply = h.reply.clone();
        let n = split(k, h, &reply);
        k.at(234, r#"IF (n <> 9) AND (n <> 6) THEN"#);
        if n != 9 && n != 6 {
            k.at(235, r#"RETURN(4)"#);
            return 4;
        }
        let u = i as usize;
        k.at(237, r#"kinds[i] = ROUND(fields[1])"#);
        h.kinds[u] = round(h.fields[1]);
        k.at(238, r#"seam_of[i] = ROUND(fields[2])"#);
        h.seam_of[u] = round(h.fields[2]);
        k.at(239, r#"IF ((n = 6) AND (kinds[i] <> 4)) OR ((n = 9) AND (kinds[i] = 4)) THEN"#);
        if (n == 6 && h.kinds[u] != 4) || (n == 9 && h.kinds[u] == 4) {
            k.at(240, r#"RETURN(4)"#);
            return 4;
        }
        k.at(242, r#"IF (kinds[i] < 1) OR (kinds[i] > 4) OR (seam_of[i] < 1) OR (seam_of[i] > seams) THEN"#);
        if h.kinds[u] < 1 || h.kinds[u] > 4 || h.seam_of[u] < 1 || h.seam_of[u] > h.seams {
            k.at(243, r#"RETURN(7)"#);
            return 7;
        }
        k.at(245, r#"IF ROUND(fields[3]) <> count - i THEN"#);
        if round(h.fields[3]) != h.count - i {
            k.at(246, r#"RETURN(7)"#);
            return 7;
        }
        let f = |n: usize| h.fields[n].expect("split read it");
        k.at(248, r#"IF kinds[i] = 4 THEN"#);
        if h.kinds[u] == 4 {
            k.at(251, r#"IF (NOT process) OR (i = 1) THEN"#);
            if !h.process || i == 1 {
                k.at(252, r#"RETURN(7)"#);
                return 7;
            }
            k.at(254, r#"IF kinds[i - 1] <> 2 THEN"#);
            if h.kinds[u - 1] != 2 {
                k.at(255, r#"RETURN(7)"#);
                return 7;
            }
            let (speed, amp, freq) = (f(4), f(5), f(6));
            k.at(257, r#"speeds[i] = fields[4]"#);
            h.speeds[u] = speed;
            k.at(258, r#"amps[i] = fields[5]"#);
            h.amps[u] = amp;
            k.at(259, r#"freqs[i] = fields[6]"#);
            h.freqs[u] = freq;
        } else {
            k.at(260, r#"ELSE"#);
            let (x, y, z, w, p, rr) = (f(4), f(5), f(6), f(7), f(8), f(9));
            k.at(261, r#"points[i] = capture"#);
            h.points[u] = h.capture;
            k.at(262, r#"points[i].x = fields[4]"#);
            h.points[u].x = x;
            k.at(263, r#"points[i].y = fields[5]"#);
            h.points[u].y = y;
            k.at(264, r#"points[i].z = fields[6]"#);
            h.points[u].z = z;
            k.at(265, r#"points[i].w = fields[7]"#);
            h.points[u].w = w;
            k.at(266, r#"points[i].p = fields[8]"#);
            h.points[u].p = p;
            k.at(267, r#"points[i].r = fields[9]"#);
            h.points[u].r = rr;
        }
    }
    k.at(270, r#"IF kinds[count] <> 3 THEN"#);
    if h.kinds[h.count as usize] != 3 {
        k.at(271, r#"RETURN(7)"#);
        return 7;
    }

    k.at(278, r#"k = 0"#);
    let mut kk = 0;
    k.at(279, r#"WHILE k < seams DO"#);
    while kk < h.seams {
        k.at(280, r#"k = k + 1"#);
        kk += 1;
        k.at(281, r#"CNV_INT_STR(k, 1, 10, text)"#);
        let text = cnv_int_str(kk, 1);
        k.at(282, r#"r = ask('CHECK,' + text)"#);
        r = ask(k, h, &format!("CHECK,{text}"));
        k.at(283, r#"IF r <> 0 THEN"#);
        if r != 0 {
            k.at(284, r#"RETURN(r)"#);
            return r;
        }
        k.at(286, r#"IF split(reply) <> 5 THEN"#);
        let reply = h.reply.clone();
        if split(k, h, &reply) != 5 {
            k.at(287, r#"RETURN(4)"#);
            return 4;
        }
        k.at(289, r#"n = 0"#);
        let mut n = 0;
        k.at(290, r#"sx = 0"#);
        let mut sx = 0f32;
        k.at(291, r#"sy = 0"#);
        let mut sy = 0f32;
        k.at(292, r#"sz = 0"#);
        let mut sz = 0f32;
        k.at(293, r#"FOR i = 1 TO count DO"#);
        for i in 1..=h.count as usize {
            k.at(294, r#"IF (seam_of[i] = k) AND (kinds[i] <> 4) THEN"#);
            if h.seam_of[i] == kk && h.kinds[i] != 4 {
                k.at(295, r#"IF n = 0 THEN"#);
                if n == 0 {
                    k.at(296, r#"first = points[i]"#);
                    first = h.points[i];
                }
                k.at(298, r#"n = n + 1"#);
                n += 1;
                k.at(299, r#"sx = sx + (points[i].x - first.x)"#);
                sx += h.points[i].x - first.x;
                k.at(300, r#"sy = sy + (points[i].y - first.y)"#);
                sy += h.points[i].y - first.y;
                k.at(301, r#"sz = sz + (points[i].z - first.z)"#);
                sz += h.points[i].z - first.z;
            }
        }
        k.at(304, r#"IF (n <> ROUND(fields[2])) OR (n < 3) THEN"#);
        if n != round(h.fields[2]) || n < 3 {
            k.at(305, r#"RETURN(6)"#);
            return 6;
        }
        let f = |n: usize| h.fields[n].expect("split read it");
        let nf = n as f32;
        k.at(307, r#"sx = first.x + sx / n"#);
        sx = first.x + sx / nf;
        k.at(308, r#"sy = first.y + sy / n"#);
        sy = first.y + sy / nf;
        k.at(309, r#"sz = first.z + sz / n"#);
        sz = first.z + sz / nf;
        k.at(310, r#"IF (ABS(sx - fields[3]) > CHECK_MM) OR (ABS(sy - fields[4]) > CHECK_MM) OR (ABS(sz - fields[5]) > CHECK_MM) THEN"#);
        if (sx - f(3)).abs() > h.check_mm || (sy - f(4)).abs() > h.check_mm || (sz - f(5)).abs() > h.check_mm {
            k.at(311, r#"RETURN(6)"#);
            return 6;
        }
    }
    k.at(314, r#"RETURN(0)"#);
    k.at(315, r#"END session"#);
    0
}

fn report(k: &mut Controller, code: i32) {
    k.at(319, r#"ROUTINE report(code : INTEGER)"#);
    k.at(321, r#"SELECT code OF"#);
    let text = match code {
        1 => {
            k.at(322, r#"CASE (1):"#);
            k.at(323, r#"WRITE TPERROR('no connection to the daemon (tag C3)', CR)"#);
            "no connection to the daemon (tag C3)"
        }
        2 => {
            k.at(324, r#"CASE (2):"#);
            k.at(325, r#"WRITE TPERROR('link to the daemon lost before the weld', CR)"#);
            "link to the daemon lost before the weld"
        }
        3 => {
            k.at(326, r#"CASE (3):"#);
            k.at(327, r#"WRITE TPERROR('no reply from the daemon in time', CR)"#);
            "no reply from the daemon in time"
        }
        4 | 7 => {
            k.at(328, r#"CASE (4, 7):"#);
            k.at(329, r#"WRITE TPERROR('a reply from the daemon not understood', CR)"#);
            "a reply from the daemon not understood"
        }
        5 => {
            k.at(330, r#"CASE (5):"#);
            k.at(331, r#"WRITE TPERROR('plan longer than MAX_LINES', CR)"#);
            "plan longer than MAX_LINES"
        }
        6 => {
            k.at(332, r#"CASE (6):"#);
            k.at(333, r#"WRITE TPERROR('a seam failed CHECK (count or means)', CR)"#);
            "a seam failed CHECK (count or means)"
        }
        8 => {
            k.at(334, r#"CASE (8):"#);
            k.at(335, r#"WRITE TPERROR('daemon speaks another link version', CR)"#);
            "daemon speaks another link version"
        }
        10 => {
            k.at(336, r#"CASE (10):"#);
            k.at(337, r#"WRITE TPERROR('select UFRAME_NUM=0 (world)', CR)"#);
            "select UFRAME_NUM=0 (world)"
        }
        _ => {
            k.at(338, r#"ELSE:"#);
            ""
        }
    };
    if !text.is_empty() {
        k.tperror.push(text.to_string());
    }
    k.at(340, r#"END report"#);
}

fn load(k: &mut Controller, h: &mut Helper, i: i32) {
    k.at(349, r#"ROUTINE load(i : INTEGER)"#);
    k.at(351, r#"pr, last, nxt : INTEGER"#);
    k.at(352, r#"travel, swing, hertz : REAL"#);
    k.at(354, r#"IF (i < 1) OR (i > count) THEN"#);
    if i < 1 || i > h.count {
        k.at(355, r#"SET_INT_REG(3, 0, status)"#);
        k.set_int_reg(3, 0);
        k.at(356, r#"RETURN"#);
        return;
    }
    let u = i as usize;
    k.at(358, r#"IF kinds[i] = 4 THEN"#);
    if h.kinds[u] == 4 {
        k.at(359, r#"SET_INT_REG(3, 4, status)"#);
        k.set_int_reg(3, 4);
        k.at(360, r#"RETURN"#);
        return;
    }
    k.at(362, r#"pr = next_pr"#);
    let pr = h.next_pr;
    k.at(363, r#"next_pr = 23 - pr"#);
    h.next_pr = 23 - pr;
    k.at(364, r#"SET_POS_REG(pr, points[i], status)"#);
    k.set_pos_reg(pr as usize, h.points[u]);
    k.at(366, r#"nxt = i + 1"#);
    let mut nxt = u + 1;
    k.at(367, r#"travel = 0"#);
    let mut travel = 0f32;
    k.at(368, r#"swing = 0"#);
    let mut swing = 0f32;
    k.at(369, r#"hertz = 0"#);
    let mut hertz = 0f32;
    k.at(370, r#"last = 0"#);
    let mut last = 0;
    k.at(371, r#"IF kinds[i] = 2 THEN"#);
    if h.kinds[u] == 2 {
        k.at(372, r#"IF kinds[i + 1] = 4 THEN"#);
        if h.kinds[u + 1] == 4 {
            k.at(373, r#"nxt = i + 2"#);
            nxt = u + 2;
            k.at(374, r#"travel = speeds[i + 1]"#);
            travel = h.speeds[u + 1];
            k.at(375, r#"swing = amps[i + 1]"#);
            swing = h.amps[u + 1];
            k.at(376, r#"hertz = freqs[i + 1]"#);
            hertz = h.freqs[u + 1];
        }
        k.at(378, r#"IF kinds[nxt] <> 2 THEN"#);
        if h.kinds[nxt] != 2 {
            k.at(379, r#"last = 1"#);
            last = 1;
        }
    }
    k.at(382, r#"SET_INT_REG(2, pr, status)"#);
    k.set_int_reg(2, pr);
    k.at(383, r#"SET_INT_REG(3, kinds[i], status)"#);
    k.set_int_reg(3, h.kinds[u]);
    k.at(384, r#"SET_INT_REG(4, seam_of[i], status)"#);
    k.set_int_reg(4, h.seam_of[u]);
    k.at(385, r#"SET_INT_REG(5, last, status)"#);
    k.set_int_reg(5, last);
    k.at(386, r#"SET_REAL_REG(7, travel, status)"#);
    k.set_real_reg(7, travel);
    k.at(387, r#"SET_REAL_REG(8, swing, status)"#);
    k.set_real_reg(8, swing);
    k.at(388, r#"SET_REAL_REG(11, hertz, status)"#);
    k.set_real_reg(11, hertz);
    k.at(389, r#"END load"#);
}

/// One `CALL WELDSEAM(...)`: the program's body, its arguments in
/// `k.tpe_params`.
pub fn weldseam(k: &mut Controller, h: &mut Helper) {
    k.at(392, r#"GET_TPE_PRM(1, ptype, mode, rval, sval, status)"#);
    let (ptype, mut mode, status) = k.get_tpe_prm(1);
    k.at(393, r#"IF (status <> 0) OR (ptype <> 1) THEN"#);
    if status != 0 || ptype != 1 {
        k.at(394, r#"mode = 1"#);
        mode = 1;
    }
    k.at(396, r#"IF mode = 2 THEN"#);
    if mode == 2 {
        k.at(397, r#"GET_TPE_PRM(2, ptype, line_no, rval, sval, status)"#);
        let (ptype, mut line_no, status) = k.get_tpe_prm(2);
        k.at(398, r#"IF (status <> 0) OR (ptype <> 1) THEN"#);
        if status != 0 || ptype != 1 {
            k.at(399, r#"line_no = 0"#);
            line_no = 0;
        }
        k.at(401, r#"load(line_no)"#);
        load(k, h, line_no);
    } else {
        k.at(402, r#"ELSE"#);
        k.at(403, r#"SET_INT_REG(9, 9, status)"#);
        k.set_int_reg(9, 9);
        k.at(404, r#"SET_INT_REG(10, 0, status)"#);
        k.set_int_reg(10, 0);
        k.at(405, r#"opened = FALSE"#);
        h.opened = false;
        k.at(406, r#"count = 0"#);
        h.count = 0;
        k.at(407, r#"process = FALSE"#);
        h.process = false;
        k.at(408, r#"next_pr = 12"#);
        h.next_pr = 12;
        k.at(409, r#"result = session"#);
        let result = session(k, h);
        k.at(410, r#"IF opened THEN"#);
        if h.opened {
            k.at(411, r#"CLOSE FILE sock"#);
            k.close_file();
        }
        k.at(413, r#"MSG_DISCO(TAG, status)"#);
        k.msg_disco("C3:");
        k.at(414, r#"IF result <> 0 THEN"#);
        if result != 0 {
            k.at(415, r#"count = 0"#);
            h.count = 0;
            k.at(416, r#"report(result)"#);
            report(k, result);
        }
        k.at(418, r#"SET_INT_REG(10, count, status)"#);
        k.set_int_reg(10, h.count);
        k.at(419, r#"SET_INT_REG(9, result, status)"#);
        k.set_int_reg(9, result);
    }
    k.at(421, r#"END weldseam"#);
}

/// The tags of this file against the shipped KAREL helper.
#[test]
fn the_transcription_follows_weldseam_kl_line_by_line() {
    let statement = |line: &str| !line.is_empty() && !line.starts_with("--") && !super::robot::is_closer(line);
    if let Err(e) = super::transcription::check("fanuc/weldseam.kl", include_str!("fanuc.rs"), statement) {
        panic!("{e}");
    }
}
