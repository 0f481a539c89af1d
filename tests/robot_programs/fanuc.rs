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
    /// `WEAVE_MM` and `WEAVE_HZ`: the weave the TP program's schedules
    /// take.
    pub weave_mm: Option<f32>,
    pub weave_hz: Option<f32>,
}

/// The helper's program variables: they keep their values between calls.
pub struct Helper {
    joint: String,
    max_lines: i32,
    reply_ms: i32,
    poll_ms: i32,
    check_mm: f32,
    weave_mm: f32,
    weave_hz: f32,
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
    k.at(33, r#"PROGRAM weldseam"#);
    k.at(34, r#"%COMMENT = 'weldseam text'"#);
    k.at(35, r#"%NOLOCKGROUP"#);
    k.at(37, r#"TAG = 'C3:'"#);
    k.at(38, r#"JOINT = 'lap'"#);
    k.at(39, r#"MAX_LINES = 2000"#);
    k.at(40, r#"REPLY_MS = 20000"#);
    k.at(41, r#"POLL_MS = 8"#);
    k.at(42, r#"CHECK_MM = 0.1"#);
    k.at(46, r#"WEAVE_MM = 5.0"#);
    k.at(47, r#"WEAVE_HZ = 5.0"#);
    k.at(49, r#"sock : FILE"#);
    k.at(50, r#"opened : BOOLEAN"#);
    k.at(51, r#"reply : STRING[254]"#);
    k.at(52, r#"fields : ARRAY[10] OF REAL"#);
    k.at(53, r#"points : ARRAY[2000] OF XYZWPR"#);
    k.at(54, r#"kinds : ARRAY[2000] OF INTEGER"#);
    k.at(55, r#"seam_of : ARRAY[2000] OF INTEGER"#);
    k.at(56, r#"speeds : ARRAY[2000] OF REAL"#);
    k.at(57, r#"amps : ARRAY[2000] OF REAL"#);
    k.at(58, r#"freqs : ARRAY[2000] OF REAL"#);
    k.at(59, r#"process : BOOLEAN"#);
    k.at(60, r#"next_pr : INTEGER"#);
    k.at(61, r#"count, seams, mode, line_no, ptype, result, status : INTEGER"#);
    k.at(62, r#"rval : REAL"#);
    k.at(63, r#"sval : STRING[16]"#);
    k.at(64, r#"capture : XYZWPR"#);
    Helper {
        joint: ov.joint.clone().unwrap_or_else(|| "lap".into()),
        max_lines: 2000,
        reply_ms: ov.reply_ms.unwrap_or(20000),
        poll_ms: 8,
        check_mm: 0.1,
        weave_mm: ov.weave_mm.unwrap_or(5.0),
        weave_hz: ov.weave_hz.unwrap_or(5.0),
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
    k.at(69, r#"ROUTINE ask(request : STRING) : INTEGER"#);
    k.at(71, r#"waited, ahead, stat, comma, code : INTEGER"#);
    k.at(73, r#"WRITE sock(request, CR)"#);
    k.write_line(request);
    k.at(74, r#"IF IO_STATUS(sock) <> 0 THEN"#);
    if k.io_status() != 0 {
        k.at(75, r#"RETURN(2)"#);
        return 2;
    }
    k.at(77, r#"waited = 0"#);
    let mut waited = 0;
    k.at(78, r#"ahead = 0"#);
    let mut ahead = 0;
    k.at(79, r#"WHILE ahead = 0 DO"#);
    while ahead == 0 {
        k.at(80, r#"BYTES_AHEAD(sock, ahead, stat)"#);
        let stat;
        (ahead, stat) = k.bytes_ahead();
        k.at(81, r#"IF stat <> 0 THEN"#);
        if stat != 0 {
            k.at(82, r#"RETURN(2)"#);
            return 2;
        }
        k.at(84, r#"IF ahead = 0 THEN"#);
        if ahead == 0 {
            k.at(85, r#"IF waited >= REPLY_MS THEN"#);
            if waited >= h.reply_ms {
                k.at(86, r#"RETURN(3)"#);
                return 3;
            }
            k.at(88, r#"DELAY(POLL_MS)"#);
            std::thread::sleep(std::time::Duration::from_millis(h.poll_ms as u64));
            k.at(89, r#"waited = waited + POLL_MS"#);
            waited += h.poll_ms;
        }
    }
    k.at(92, r#"READ sock(reply, CR)"#);
    h.reply = k.read_line(254);
    k.at(93, r#"IF IO_STATUS(sock) <> 0 THEN"#);
    if k.io_status() != 0 {
        k.at(94, r#"RETURN(2)"#);
        return 2;
    }
    k.at(96, r#"IF SUB_STR(reply, 1, 1) <> '-' THEN"#);
    if sub_str(&h.reply, 1, 1) != "-" {
        k.at(97, r#"RETURN(0)"#);
        return 0;
    }
    k.at(99, r#"comma = INDEX(reply, ',')"#);
    let comma = index(&h.reply, ",");
    k.at(100, r#"IF comma < 3 THEN"#);
    if comma < 3 {
        k.at(101, r#"RETURN(4)"#);
        return 4;
    }
    k.at(103, r#"CNV_STR_INT(SUB_STR(reply, 2, comma - 2), code)"#);
    let code = cnv_str_int(&sub_str(&h.reply, 2, comma - 2));
    k.at(104, r#"IF UNINIT(code) THEN"#);
    let Some(code) = code else {
        k.at(105, r#"RETURN(4)"#);
        return 4;
    };
    k.at(107, r#"WRITE TPERROR(SUB_STR(reply, comma + 1, STR_LEN(reply) - comma), CR)"#);
    let reason = sub_str(&h.reply, comma + 1, str_len(&h.reply) - comma);
    k.tperror.push(reason);
    k.at(108, r#"RETURN(-code)"#);
    k.at(109, r#"END ask"#);
    -code
}

fn split(k: &mut Controller, h: &mut Helper, answer: &str) -> i32 {
    k.at(113, r#"ROUTINE split(answer : STRING) : INTEGER"#);
    k.at(115, r#"comma, n : INTEGER"#);
    k.at(116, r#"part : STRING[32]"#);
    k.at(117, r#"rest : STRING[254]"#);
    k.at(119, r#"n = 0"#);
    let mut n = 0;
    k.at(120, r#"rest = answer"#);
    let mut rest = answer.to_string();
    k.at(121, r#"WHILE STR_LEN(rest) > 0 DO"#);
    while str_len(&rest) > 0 {
        k.at(122, r#"IF n >= 10 THEN"#);
        if n >= 10 {
            k.at(123, r#"RETURN(0)"#);
            return 0;
        }
        k.at(125, r#"comma = INDEX(rest, ',')"#);
        let comma = index(&rest, ",");
        k.at(126, r#"IF comma = 0 THEN"#);
        let part;
        if comma == 0 {
            k.at(127, r#"part = rest"#);
            part = sub_str(&rest, 1, 32);
            k.at(128, r#"rest = ''"#);
            rest = String::new();
        } else {
            k.at(129, r#"ELSE"#);
            k.at(130, r#"part = SUB_STR(rest, 1, comma - 1)"#);
            part = sub_str(&rest, 1, (comma - 1).min(32));
            k.at(131, r#"rest = SUB_STR(rest, comma + 1, STR_LEN(rest) - comma)"#);
            rest = sub_str(&rest, comma + 1, str_len(&rest) - comma);
        }
        k.at(133, r#"n = n + 1"#);
        n += 1;
        k.at(134, r#"CNV_STR_REAL(part, fields[n])"#);
        h.fields[n as usize] = cnv_str_real(&part);
        k.at(135, r#"IF UNINIT(fields[n]) THEN"#);
        if h.fields[n as usize].is_none() {
            k.at(136, r#"RETURN(0)"#);
            return 0;
        }
    }
    k.at(139, r#"RETURN(n)"#);
    k.at(140, r#"END split"#);
    n
}

fn flange(k: &mut Controller, h: &mut Helper) -> i32 {
    k.at(146, r#"ROUTINE flange : INTEGER"#);
    k.at(148, r#"here, tool : POSITION"#);
    k.at(150, r#"IF $MNUFRAMENUM[1] <> 0 THEN"#);
    if k.uframe_num != 0 {
        k.at(151, r#"RETURN(10)"#);
        return 10;
    }
    k.at(153, r#"here = CURPOS(0, 0, 1)"#);
    let mut here: Isometry3<f64> = k.curpos();
    k.at(154, r#"IF $MNUTOOLNUM[1] <> 0 THEN"#);
    if k.utool_num != 0 {
        k.at(155, r#"tool = $MNUTOOL[1, $MNUTOOLNUM[1]]"#);
        let tool = k.tools[k.utool_num];
        k.at(156, r#"here = here : INV(tool)"#);
        here *= tool.inverse();
    }
    k.at(158, r#"capture = here"#);
    h.capture = Xyzwpr::of(&here);
    k.at(159, r#"RETURN(0)"#);
    k.at(160, r#"END flange"#);
    0
}

fn number(k: &mut Controller, line: &str, value: f32, decimals: usize) -> String {
    k.at(163, r#"ROUTINE number(line : STRING; value : REAL; decimals : INTEGER) : STRING"#);
    k.at(165, r#"text : STRING[32]"#);
    k.at(167, r#"CNV_REAL_STR(value, 1, decimals, text)"#);
    let text = cnv_real_str(value, 1, decimals);
    k.at(168, r#"RETURN(line + ',' + text)"#);
    k.at(169, r#"END number"#);
    format!("{line},{text}")
}

fn session(k: &mut Controller, h: &mut Helper) -> i32 {
    k.at(172, r#"ROUTINE session : INTEGER"#);
    k.at(174, r#"r, i, k, n : INTEGER"#);
    k.at(175, r#"sx, sy, sz : REAL"#);
    k.at(176, r#"first : XYZWPR"#);
    let mut first = Xyzwpr::default();
    k.at(177, r#"text : STRING[16]"#);
    k.at(178, r#"line : STRING[254]"#);
    k.at(180, r#"MSG_DISCO(TAG, status)"#);
    k.msg_disco("C3:");
    k.at(181, r#"MSG_CONNECT(TAG, status)"#);
    let status = k.msg_connect("C3:");
    k.at(182, r#"IF status <> 0 THEN"#);
    if status != 0 {
        k.at(183, r#"RETURN(1)"#);
        return 1;
    }
    k.at(185, r#"OPEN FILE sock('RW', TAG)"#);
    k.open_file();
    k.at(186, r#"IF IO_STATUS(sock) <> 0 THEN"#);
    if k.io_status() != 0 {
        k.at(187, r#"RETURN(1)"#);
        return 1;
    }
    k.at(189, r#"opened = TRUE"#);
    h.opened = true;
    k.at(190, r#"r = ask('HELLO,fanuc,PROCESS')"#);
    let mut r = ask(k, h, "HELLO,fanuc,PROCESS");
    k.at(191, r#"IF r <> 0 THEN"#);
    if r != 0 {
        k.at(192, r#"RETURN(r)"#);
        return r;
    }
    k.at(194, r#"IF split(reply) <> 3 THEN"#);
    let reply = h.reply.clone();
    if split(k, h, &reply) != 3 {
        k.at(195, r#"RETURN(4)"#);
        return 4;
    }
    k.at(197, r#"IF ROUND(fields[2]) <> 2 THEN"#);
    if round(h.fields[2]) != 2 {
        k.at(198, r#"RETURN(8)"#);
        return 8;
    }
    k.at(200, r#"process = (ROUND(fields[3]) = 1)"#);
    h.process = round(h.fields[3]) == 1;

    k.at(203, r#"r = flange"#);
    r = flange(k, h);
    k.at(204, r#"IF r <> 0 THEN"#);
    if r != 0 {
        k.at(205, r#"RETURN(r)"#);
        return r;
    }
    k.at(207, r#"line = 'TRIGGER,' + JOINT"#);
    let mut line = format!("TRIGGER,{}", h.joint);
    let c = h.capture;
    k.at(208, r#"line = number(line, capture.x, 3)"#);
    line = number(k, &line, c.x, 3);
    k.at(209, r#"line = number(line, capture.y, 3)"#);
    line = number(k, &line, c.y, 3);
    k.at(210, r#"line = number(line, capture.z, 3)"#);
    line = number(k, &line, c.z, 3);
    k.at(211, r#"line = number(line, capture.w, 4)"#);
    line = number(k, &line, c.w, 4);
    k.at(212, r#"line = number(line, capture.p, 4)"#);
    line = number(k, &line, c.p, 4);
    k.at(213, r#"line = number(line, capture.r, 4)"#);
    line = number(k, &line, c.r, 4);
    assert!(line.len() <= 254, "a STRING[254] holds the plan line");
    k.at(214, r#"r = ask(line)"#);
    r = ask(k, h, &line);
    k.at(215, r#"IF r <> 0 THEN"#);
    if r != 0 {
        k.at(216, r#"RETURN(r)"#);
        return r;
    }
    k.at(219, r#"IF split(reply) <> 3 THEN"#);
    let reply = h.reply.clone();
    if split(k, h, &reply) != 3 {
        k.at(220, r#"RETURN(4)"#);
        return 4;
    }
    k.at(222, r#"seams = ROUND(fields[2])"#);
    h.seams = round(h.fields[2]);
    k.at(223, r#"count = ROUND(fields[3])"#);
    h.count = round(h.fields[3]);
    k.at(224, r#"IF (seams < 1) OR (count < 3 * seams) THEN"#);
    if h.seams < 1 || h.count < 3 * h.seams {
        k.at(225, r#"RETURN(4)"#);
        return 4;
    }
    k.at(227, r#"IF count > MAX_LINES THEN"#);
    if h.count > h.max_lines {
        k.at(228, r#"r = ask('DROP')"#);
        ask(k, h, "DROP");
        k.at(229, r#"RETURN(5)"#);
        return 5;
    }

    k.at(234, r#"i = 0"#);
    let mut i = 0;
    k.at(235, r#"WHILE i < count DO"#);
    while i < h.count {
        k.at(236, r#"i = i + 1"#);
        i += 1;
        k.at(237, r#"r = ask('NEXT')"#);
        r = ask(k, h, "NEXT");
        k.at(238, r#"IF r <> 0 THEN"#);
        if r != 0 {
            k.at(239, r#"RETURN(r)"#);
            return r;
        }
        k.at(241, r#"n = split(reply)"#);
        let reply = h.reply.clone();
        let n = split(k, h, &reply);
        k.at(242, r#"IF (n <> 9) AND (n <> 6) THEN"#);
        if n != 9 && n != 6 {
            k.at(243, r#"RETURN(4)"#);
            return 4;
        }
        let u = i as usize;
        k.at(245, r#"kinds[i] = ROUND(fields[1])"#);
        h.kinds[u] = round(h.fields[1]);
        k.at(246, r#"seam_of[i] = ROUND(fields[2])"#);
        h.seam_of[u] = round(h.fields[2]);
        k.at(247, r#"IF ((n = 6) AND (kinds[i] <> 4)) OR ((n = 9) AND (kinds[i] = 4)) THEN"#);
        if (n == 6 && h.kinds[u] != 4) || (n == 9 && h.kinds[u] == 4) {
            k.at(248, r#"RETURN(4)"#);
            return 4;
        }
        k.at(250, r#"IF (kinds[i] < 1) OR (kinds[i] > 4) OR (seam_of[i] < 1) OR (seam_of[i] > seams) THEN"#);
        if h.kinds[u] < 1 || h.kinds[u] > 4 || h.seam_of[u] < 1 || h.seam_of[u] > h.seams {
            k.at(251, r#"RETURN(7)"#);
            return 7;
        }
        k.at(253, r#"IF ROUND(fields[3]) <> count - i THEN"#);
        if round(h.fields[3]) != h.count - i {
            k.at(254, r#"RETURN(7)"#);
            return 7;
        }
        let f = |n: usize| h.fields[n].expect("split read it");
        k.at(256, r#"IF kinds[i] = 4 THEN"#);
        if h.kinds[u] == 4 {
            k.at(259, r#"IF (NOT process) OR (i = 1) THEN"#);
            if !h.process || i == 1 {
                k.at(260, r#"RETURN(7)"#);
                return 7;
            }
            k.at(262, r#"IF kinds[i - 1] <> 2 THEN"#);
            if h.kinds[u - 1] != 2 {
                k.at(263, r#"RETURN(7)"#);
                return 7;
            }
            let (speed, amp, freq) = (f(4), f(5), f(6));
            k.at(265, r#"speeds[i] = fields[4]"#);
            h.speeds[u] = speed;
            k.at(266, r#"amps[i] = fields[5]"#);
            h.amps[u] = amp;
            k.at(267, r#"freqs[i] = fields[6]"#);
            h.freqs[u] = freq;
            k.at(270, r#"IF (amps[i] < 0) OR (amps[i] > WEAVE_MM) THEN"#);
            if h.amps[u] < 0.0 || h.amps[u] > h.weave_mm {
                k.at(271, r#"RETURN(11)"#);
                return 11;
            }
            k.at(273, r#"IF (amps[i] > 0) AND ((freqs[i] <= 0) OR (freqs[i] > WEAVE_HZ)) THEN"#);
            if h.amps[u] > 0.0 && (h.freqs[u] <= 0.0 || h.freqs[u] > h.weave_hz) {
                k.at(274, r#"RETURN(12)"#);
                return 12;
            }
        } else {
            k.at(276, r#"ELSE"#);
            let (x, y, z, w, p, rr) = (f(4), f(5), f(6), f(7), f(8), f(9));
            k.at(277, r#"points[i] = capture"#);
            h.points[u] = h.capture;
            k.at(278, r#"points[i].x = fields[4]"#);
            h.points[u].x = x;
            k.at(279, r#"points[i].y = fields[5]"#);
            h.points[u].y = y;
            k.at(280, r#"points[i].z = fields[6]"#);
            h.points[u].z = z;
            k.at(281, r#"points[i].w = fields[7]"#);
            h.points[u].w = w;
            k.at(282, r#"points[i].p = fields[8]"#);
            h.points[u].p = p;
            k.at(283, r#"points[i].r = fields[9]"#);
            h.points[u].r = rr;
        }
    }
    k.at(286, r#"IF kinds[count] <> 3 THEN"#);
    if h.kinds[h.count as usize] != 3 {
        k.at(287, r#"RETURN(7)"#);
        return 7;
    }

    k.at(294, r#"k = 0"#);
    let mut kk = 0;
    k.at(295, r#"WHILE k < seams DO"#);
    while kk < h.seams {
        k.at(296, r#"k = k + 1"#);
        kk += 1;
        k.at(297, r#"CNV_INT_STR(k, 1, 10, text)"#);
        let text = cnv_int_str(kk, 1);
        k.at(298, r#"r = ask('CHECK,' + text)"#);
        r = ask(k, h, &format!("CHECK,{text}"));
        k.at(299, r#"IF r <> 0 THEN"#);
        if r != 0 {
            k.at(300, r#"RETURN(r)"#);
            return r;
        }
        k.at(302, r#"IF split(reply) <> 5 THEN"#);
        let reply = h.reply.clone();
        if split(k, h, &reply) != 5 {
            k.at(303, r#"RETURN(4)"#);
            return 4;
        }
        k.at(305, r#"n = 0"#);
        let mut n = 0;
        k.at(306, r#"sx = 0"#);
        let mut sx = 0f32;
        k.at(307, r#"sy = 0"#);
        let mut sy = 0f32;
        k.at(308, r#"sz = 0"#);
        let mut sz = 0f32;
        k.at(309, r#"FOR i = 1 TO count DO"#);
        for i in 1..=h.count as usize {
            k.at(310, r#"IF (seam_of[i] = k) AND (kinds[i] <> 4) THEN"#);
            if h.seam_of[i] == kk && h.kinds[i] != 4 {
                k.at(311, r#"IF n = 0 THEN"#);
                if n == 0 {
                    k.at(312, r#"first = points[i]"#);
                    first = h.points[i];
                }
                k.at(314, r#"n = n + 1"#);
                n += 1;
                k.at(315, r#"sx = sx + (points[i].x - first.x)"#);
                sx += h.points[i].x - first.x;
                k.at(316, r#"sy = sy + (points[i].y - first.y)"#);
                sy += h.points[i].y - first.y;
                k.at(317, r#"sz = sz + (points[i].z - first.z)"#);
                sz += h.points[i].z - first.z;
            }
        }
        k.at(320, r#"IF (n <> ROUND(fields[2])) OR (n < 3) THEN"#);
        if n != round(h.fields[2]) || n < 3 {
            k.at(321, r#"RETURN(6)"#);
            return 6;
        }
        let f = |n: usize| h.fields[n].expect("split read it");
        let nf = n as f32;
        k.at(323, r#"sx = first.x + sx / n"#);
        sx = first.x + sx / nf;
        k.at(324, r#"sy = first.y + sy / n"#);
        sy = first.y + sy / nf;
        k.at(325, r#"sz = first.z + sz / n"#);
        sz = first.z + sz / nf;
        k.at(326, r#"IF (ABS(sx - fields[3]) > CHECK_MM) OR (ABS(sy - fields[4]) > CHECK_MM) OR (ABS(sz - fields[5]) > CHECK_MM) THEN"#);
        if (sx - f(3)).abs() > h.check_mm || (sy - f(4)).abs() > h.check_mm || (sz - f(5)).abs() > h.check_mm {
            k.at(327, r#"RETURN(6)"#);
            return 6;
        }
    }
    k.at(330, r#"RETURN(0)"#);
    k.at(331, r#"END session"#);
    0
}

fn report(k: &mut Controller, h: &Helper, code: i32) {
    k.at(335, r#"ROUTINE report(code : INTEGER)"#);
    k.at(337, r#"SELECT code OF"#);
    let text = match code {
        1 => {
            k.at(338, r#"CASE (1):"#);
            k.at(339, r#"WRITE TPERROR('no connection to the daemon (tag C3)', CR)"#);
            "no connection to the daemon (tag C3)"
        }
        2 => {
            k.at(340, r#"CASE (2):"#);
            k.at(341, r#"WRITE TPERROR('link to the daemon lost before the weld', CR)"#);
            "link to the daemon lost before the weld"
        }
        3 => {
            k.at(342, r#"CASE (3):"#);
            k.at(343, r#"WRITE TPERROR('no reply from the daemon in time', CR)"#);
            "no reply from the daemon in time"
        }
        4 | 7 => {
            k.at(344, r#"CASE (4, 7):"#);
            k.at(345, r#"WRITE TPERROR('a reply from the daemon not understood', CR)"#);
            "a reply from the daemon not understood"
        }
        5 => {
            k.at(346, r#"CASE (5):"#);
            k.at(347, r#"WRITE TPERROR('plan longer than MAX_LINES', CR)"#);
            "plan longer than MAX_LINES"
        }
        6 => {
            k.at(348, r#"CASE (6):"#);
            k.at(349, r#"WRITE TPERROR('a seam failed CHECK (count or means)', CR)"#);
            "a seam failed CHECK (count or means)"
        }
        8 => {
            k.at(350, r#"CASE (8):"#);
            k.at(351, r#"WRITE TPERROR('daemon speaks another link version', CR)"#);
            "daemon speaks another link version"
        }
        10 => {
            k.at(352, r#"CASE (10):"#);
            k.at(353, r#"WRITE TPERROR('select UFRAME_NUM=0 (world)', CR)"#);
            "select UFRAME_NUM=0 (world)"
        }
        11 => {
            k.at(354, r#"CASE (11):"#);
            k.at(355, r#"WRITE TPERROR('weave half-swing over WEAVE_MM ', WEAVE_MM::1::2, ' mm', CR)"#);
            k.tperror.push(format!("weave half-swing over WEAVE_MM {} mm", cnv_real_str(h.weave_mm, 1, 2)));
            ""
        }
        12 => {
            k.at(356, r#"CASE (12):"#);
            k.at(357, r#"WRITE TPERROR('weave Hz not over 0, up to WEAVE_HZ ', WEAVE_HZ::1::2, CR)"#);
            k.tperror.push(format!("weave Hz not over 0, up to WEAVE_HZ {}", cnv_real_str(h.weave_hz, 1, 2)));
            ""
        }
        _ => {
            k.at(358, r#"ELSE:"#);
            ""
        }
    };
    if !text.is_empty() {
        k.tperror.push(text.to_string());
    }
    k.at(360, r#"END report"#);
}

fn load(k: &mut Controller, h: &mut Helper, i: i32) {
    k.at(369, r#"ROUTINE load(i : INTEGER)"#);
    k.at(371, r#"pr, last, nxt : INTEGER"#);
    k.at(372, r#"travel, swing, hertz : REAL"#);
    k.at(374, r#"IF (i < 1) OR (i > count) THEN"#);
    if i < 1 || i > h.count {
        k.at(375, r#"SET_INT_REG(3, 0, status)"#);
        k.set_int_reg(3, 0);
        k.at(376, r#"RETURN"#);
        return;
    }
    let u = i as usize;
    k.at(378, r#"IF kinds[i] = 4 THEN"#);
    if h.kinds[u] == 4 {
        k.at(379, r#"SET_INT_REG(3, 4, status)"#);
        k.set_int_reg(3, 4);
        k.at(380, r#"RETURN"#);
        return;
    }
    k.at(382, r#"pr = next_pr"#);
    let pr = h.next_pr;
    k.at(383, r#"next_pr = 23 - pr"#);
    h.next_pr = 23 - pr;
    k.at(384, r#"SET_POS_REG(pr, points[i], status)"#);
    k.set_pos_reg(pr as usize, h.points[u]);
    k.at(386, r#"nxt = i + 1"#);
    let mut nxt = u + 1;
    k.at(387, r#"travel = 0"#);
    let mut travel = 0f32;
    k.at(388, r#"swing = 0"#);
    let mut swing = 0f32;
    k.at(389, r#"hertz = 0"#);
    let mut hertz = 0f32;
    k.at(390, r#"last = 0"#);
    let mut last = 0;
    k.at(391, r#"IF kinds[i] = 2 THEN"#);
    if h.kinds[u] == 2 {
        k.at(392, r#"IF kinds[i + 1] = 4 THEN"#);
        if h.kinds[u + 1] == 4 {
            k.at(393, r#"nxt = i + 2"#);
            nxt = u + 2;
            k.at(394, r#"travel = speeds[i + 1]"#);
            travel = h.speeds[u + 1];
            k.at(395, r#"swing = amps[i + 1]"#);
            swing = h.amps[u + 1];
            k.at(396, r#"hertz = freqs[i + 1]"#);
            hertz = h.freqs[u + 1];
        }
        k.at(398, r#"IF kinds[nxt] <> 2 THEN"#);
        if h.kinds[nxt] != 2 {
            k.at(399, r#"last = 1"#);
            last = 1;
        }
    }
    k.at(402, r#"SET_INT_REG(2, pr, status)"#);
    k.set_int_reg(2, pr);
    k.at(403, r#"SET_INT_REG(3, kinds[i], status)"#);
    k.set_int_reg(3, h.kinds[u]);
    k.at(404, r#"SET_INT_REG(4, seam_of[i], status)"#);
    k.set_int_reg(4, h.seam_of[u]);
    k.at(405, r#"SET_INT_REG(5, last, status)"#);
    k.set_int_reg(5, last);
    k.at(406, r#"SET_REAL_REG(7, travel, status)"#);
    k.set_real_reg(7, travel);
    k.at(407, r#"SET_REAL_REG(8, swing, status)"#);
    k.set_real_reg(8, swing);
    k.at(408, r#"SET_REAL_REG(11, hertz, status)"#);
    k.set_real_reg(11, hertz);
    k.at(409, r#"END load"#);
}

/// One `CALL WELDSEAM(...)`: the program's body, its arguments in
/// `k.tpe_params`.
pub fn weldseam(k: &mut Controller, h: &mut Helper) {
    k.at(412, r#"GET_TPE_PRM(1, ptype, mode, rval, sval, status)"#);
    let (ptype, mut mode, status) = k.get_tpe_prm(1);
    k.at(413, r#"IF (status <> 0) OR (ptype <> 1) THEN"#);
    if status != 0 || ptype != 1 {
        k.at(414, r#"mode = 1"#);
        mode = 1;
    }
    k.at(416, r#"IF mode = 2 THEN"#);
    if mode == 2 {
        k.at(417, r#"GET_TPE_PRM(2, ptype, line_no, rval, sval, status)"#);
        let (ptype, mut line_no, status) = k.get_tpe_prm(2);
        k.at(418, r#"IF (status <> 0) OR (ptype <> 1) THEN"#);
        if status != 0 || ptype != 1 {
            k.at(419, r#"line_no = 0"#);
            line_no = 0;
        }
        k.at(421, r#"load(line_no)"#);
        load(k, h, line_no);
    } else {
        k.at(422, r#"ELSE"#);
        k.at(423, r#"SET_INT_REG(9, 9, status)"#);
        k.set_int_reg(9, 9);
        k.at(424, r#"SET_INT_REG(10, 0, status)"#);
        k.set_int_reg(10, 0);
        k.at(425, r#"opened = FALSE"#);
        h.opened = false;
        k.at(426, r#"count = 0"#);
        h.count = 0;
        k.at(427, r#"process = FALSE"#);
        h.process = false;
        k.at(428, r#"next_pr = 12"#);
        h.next_pr = 12;
        k.at(429, r#"result = session"#);
        let result = session(k, h);
        k.at(430, r#"IF opened THEN"#);
        if h.opened {
            k.at(431, r#"CLOSE FILE sock"#);
            k.close_file();
        }
        k.at(433, r#"MSG_DISCO(TAG, status)"#);
        k.msg_disco("C3:");
        k.at(434, r#"IF result <> 0 THEN"#);
        if result != 0 {
            k.at(435, r#"count = 0"#);
            h.count = 0;
            k.at(436, r#"report(result)"#);
            report(k, h, result);
        }
        k.at(438, r#"SET_INT_REG(10, count, status)"#);
        k.set_int_reg(10, h.count);
        k.at(439, r#"SET_INT_REG(9, result, status)"#);
        k.set_int_reg(9, result);
    }
    k.at(441, r#"END weldseam"#);
}

/// The tags of this file against the shipped KAREL helper.
#[test]
fn the_transcription_follows_weldseam_kl_line_by_line() {
    let statement = |line: &str| !line.is_empty() && !line.starts_with("--") && !super::robot::is_closer(line);
    if let Err(e) = super::transcription::check("fanuc/weldseam.kl", include_str!("fanuc.rs"), statement) {
        panic!("{e}");
    }
}
