//! `deploy/robots/kuka/WeldSeam.src` and `WeldSeam.dat`, transcribed
//! statement by statement onto the emulated KRL and KUKA.Ethernet KRL
//! primitives of `krl.rs`; each statement tagged with its line and text in
//! the program file (`listing.rs` holds the tags to the files).

use super::krl::{Arg, Chars, E6Pos, Krl, int, real, sread, swrite};
use super::kuka_dat::DataList;

/// What a scenario sets in the program's settings block, as an integrator
/// would edit it; `None` keeps the shipped value.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    pub joint: Option<String>,
    pub reply_timeout_ms: Option<i32>,
    pub dry_run: Option<bool>,
}

/// The local variables of `WeldSeam()`.
#[derive(Default)]
struct Locals {
    line: Chars,
    reply: Chars,
    joint: Chars,
    capture: E6Pos,
    first: E6Pos,
    kind: i32,
    seam: i32,
    remaining: i32,
    code: i32,
    offset: usize,
    seams: i32,
    count: i32,
    i: i32,
    kk: i32,
    n: i32,
    lines: i32,
    x: f32,
    y: f32,
    z: f32,
    a: f32,
    b: f32,
    c: f32,
    sum_x: f32,
    sum_y: f32,
    sum_z: f32,
    hits: i32,
    arc_on: bool,
    weld_vel: f32,
    approach_vel: f32,
    blend_dist: f32,
    reply_timeout: i32,
    arc_out: usize,
    dry_run: bool,
    process: bool,
    nxt: i32,
    prv: i32,
    shorter: f32,
}

impl Default for Chars {
    fn default() -> Chars {
        Chars::new(254)
    }
}

/// Runs `WeldSeam()` and returns `WsResult`.
pub fn weld_seam(k: &mut Krl, dat: &mut DataList, ov: &Overrides) -> i32 {
    let mut v = Locals { joint: Chars::new(32), ..Locals::default() };
    k.at(1, r#"&ACCESS RVP"#);
    k.at(2, r#"DEF WeldSeam()"#);
    k.at(29, r#"DECL EKI_STATUS RET"#);
    k.at(30, r#"DECL CHAR Line[254], Reply[254], Joint[32]"#);
    k.at(31, r#"DECL E6POS Capture, First"#);
    k.at(32, r#"DECL INT Kind, Seam, Remaining, Code, Offset, Seams, Count, I, K, N, Lines, Nxt, Prv"#);
    k.at(33, r#"DECL REAL X, Y, Z, A, B, C, SumX, SumY, SumZ, Shorter"#);
    k.at(34, r#"DECL STATE_T St"#);
    k.at(35, r#"DECL BOOL ArcOn"#);
    k.at(36, r#"DECL REAL WeldVel, ApproachVel, BlendDist"#);
    k.at(37, r#"DECL INT ReplyTimeout, ArcOut"#);
    k.at(38, r#"DECL BOOL DryRun"#);
    k.at(39, r#"DECL BOOL Process"#);
    k.at(41, r#"INI"#);
    k.at(43, r#"StrClear(Joint[])"#);
    v.joint.clear();
    k.at(44, r#"Joint[] = "lap"       ; the joint type, or the types a fixture holds (v_butt+lap)"#);
    v.joint.assign(ov.joint.as_deref().unwrap_or("lap"));
    k.at(45, r#"WeldVel = 0.008       ; weld speed, m/s (8 mm/s)"#);
    v.weld_vel = 0.008;
    k.at(46, r#"ApproachVel = 0.25    ; approach and retract speed, m/s"#);
    v.approach_vel = 0.25;
    k.at(47, r#"BlendDist = 1.0       ; C_DIS blend distance on the seam, mm"#);
    v.blend_dist = 1.0;
    k.at(48, r#"ReplyTimeout = 20000  ; longest wait for one reply line, ms (a plan takes seconds)"#);
    v.reply_timeout = ov.reply_timeout_ms.unwrap_or(20000);
    k.at(49, r#"ArcOut = 33           ; welder's arc-on output without ArcTech"#);
    v.arc_out = 33;
    k.at(50, r#"DryRun = FALSE        ; TRUE: move along the seam without the arc (first runs)"#);
    v.dry_run = ov.dry_run.unwrap_or(false);
    k.at(52, r#"$TOOL = TOOL_DATA[1]   ; the torch"#);
    k.tool = Some(1);
    k.at(53, r#"$BASE = BASE_DATA[0]   ; the robot base: the daemon's waypoints are in it"#);
    k.at(54, r#"WsResult = 0"#);
    dat.ws_result = 0;

    k.at(56, r#"RET = EKI_Init("WeldSeam")"#);
    k.eki_init("WeldSeam");
    k.at(57, r#"RET = EKI_Open("WeldSeam")"#);
    let ret = k.eki_open("WeldSeam");
    k.at(58, r#"IF RET.Msg_No <> 0 THEN"#);
    if ret.msg_no != 0 {
        k.at(59, r#"WsResult = 1"#);
        dat.ws_result = 1;
    }
    k.at(61, r#"IF WsResult == 0 THEN"#);
    if dat.ws_result == 0 {
        k.at(62, r#"StrClear(Line[])"#);
        v.line.clear();
        k.at(63, r#"Line[] = "HELLO,kuka,PROCESS""#);
        v.line.assign("HELLO,kuka,PROCESS");
        k.at(64, r#"Ask(Line[], Reply[], ReplyTimeout)"#);
        ask(k, dat, &v.line, &mut v.reply, v.reply_timeout);
    }
    k.at(66, r#"IF WsResult == 0 THEN"#);
    if dat.ws_result == 0 {
        k.at(67, r#"Offset = 0"#);
        v.offset = 0;
        k.at(68, r#"SREAD(Reply[], St, Offset, "%d,%d,%d", Code, N, K)"#);
        let (st, r) = sread(&v.reply, &mut v.offset, "%d,%d,%d");
        (v.code, v.n, v.kk, v.hits) = (int(&r, 0, v.code), int(&r, 1, v.n), int(&r, 2, v.kk), st.hits);
        k.at(69, r#"IF (St.HITS <> 3) OR (N <> 2) THEN"#);
        if v.hits != 3 || v.n != 2 {
            k.at(70, r#"WsResult = 8"#);
            dat.ws_result = 8;
        }
        k.at(72, r#"Process = K == 1"#);
        v.process = v.kk == 1;
    }

    k.at(77, r#"IF WsResult == 0 THEN"#);
    if dat.ws_result == 0 {
        k.at(78, r#"$TOOL = $NULLFRAME"#);
        k.tool = None;
        k.at(79, r#"Capture = $POS_ACT"#);
        v.capture = k.pos_act();
        k.at(80, r#"$TOOL = TOOL_DATA[1]"#);
        k.tool = Some(1);
        k.at(81, r#"Offset = 0"#);
        v.offset = 0;
        k.at(82, r#"StrClear(Line[])"#);
        v.line.clear();
        k.at(83, r#"SWRITE(Line[], St, Offset, "TRIGGER,%s,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f", Joint[], Capture.X, Capture.Y, Capture.Z, Capture.A, Capture.B, Capture.C)"#);
        let c = v.capture;
        let args = [
            Arg::Text(&v.joint),
            Arg::Real(c.x),
            Arg::Real(c.y),
            Arg::Real(c.z),
            Arg::Real(c.a),
            Arg::Real(c.b),
            Arg::Real(c.c),
        ];
        swrite(&mut v.line, &mut v.offset, "TRIGGER,%s,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f", &args);
        k.at(84, r#"Ask(Line[], Reply[], ReplyTimeout)"#);
        ask(k, dat, &v.line, &mut v.reply, v.reply_timeout);
    }
    k.at(87, r#"IF WsResult == 0 THEN"#);
    if dat.ws_result == 0 {
        k.at(88, r#"Offset = 0"#);
        v.offset = 0;
        k.at(89, r#"SREAD(Reply[], St, Offset, "%d,%d,%d", Code, Seams, Count)"#);
        let (st, r) = sread(&v.reply, &mut v.offset, "%d,%d,%d");
        (v.code, v.seams, v.count, v.hits) = (int(&r, 0, v.code), int(&r, 1, v.seams), int(&r, 2, v.count), st.hits);
        k.at(90, r#"IF (St.HITS <> 3) OR (Seams < 1) OR (Count < 3 * Seams) THEN"#);
        if v.hits != 3 || v.seams < 1 || v.count < 3 * v.seams {
            k.at(91, r#"WsResult = 4"#);
            dat.ws_result = 4;
        }
    }
    k.at(94, r#"IF (WsResult == 0) AND (Count > WS_MAX_LINES) THEN"#);
    if dat.ws_result == 0 && v.count > dat.ws_max_lines {
        k.at(95, r#"StrClear(Line[])"#);
        v.line.clear();
        k.at(96, r#"Line[] = "DROP""#);
        v.line.assign("DROP");
        k.at(97, r#"Ask(Line[], Reply[], ReplyTimeout)"#);
        ask(k, dat, &v.line, &mut v.reply, v.reply_timeout);
        k.at(98, r#"WsResult = 5"#);
        dat.ws_result = 5;
    }

    k.at(104, r#"I = 0"#);
    v.i = 0;
    k.at(105, r#"WHILE (WsResult == 0) AND (I < Count)"#);
    while dat.ws_result == 0 && v.i < v.count {
        k.at(106, r#"I = I + 1"#);
        v.i += 1;
        k.at(107, r#"StrClear(Line[])"#);
        v.line.clear();
        k.at(108, r#"Line[] = "NEXT""#);
        v.line.assign("NEXT");
        k.at(109, r#"Ask(Line[], Reply[], ReplyTimeout)"#);
        ask(k, dat, &v.line, &mut v.reply, v.reply_timeout);
        k.at(110, r#"IF WsResult == 0 THEN"#);
        if dat.ws_result == 0 {
            k.at(111, r#"Offset = 0"#);
            v.offset = 0;
            k.at(
                112,
                r#"SREAD(Reply[], St, Offset, "%d,%d,%d,%f,%f,%f,%f,%f,%f", Kind, Seam, Remaining, X, Y, Z, A, B, C)"#,
            );
            let (st, r) = sread(&v.reply, &mut v.offset, "%d,%d,%d,%f,%f,%f,%f,%f,%f");
            (v.kind, v.seam, v.remaining) = (int(&r, 0, v.kind), int(&r, 1, v.seam), int(&r, 2, v.remaining));
            (v.x, v.y, v.z) = (real(&r, 3, v.x), real(&r, 4, v.y), real(&r, 5, v.z));
            (v.a, v.b, v.c, v.hits) = (real(&r, 6, v.a), real(&r, 7, v.b), real(&r, 8, v.c), st.hits);
            k.at(113, r#"IF (St.HITS <> 9) AND ((St.HITS <> 6) OR (Kind <> 4)) THEN"#);
            if v.hits != 9 && (v.hits != 6 || v.kind != 4) {
                k.at(114, r#"WsResult = 4"#);
                dat.ws_result = 4;
            }
        }
        k.at(117, r#"IF (WsResult == 0) AND ((Kind < 1) OR (Kind > 4) OR (Seam < 1) OR (Seam > Seams) OR (Remaining <> Count - I)) THEN"#);
        if dat.ws_result == 0
            && (v.kind < 1 || v.kind > 4 || v.seam < 1 || v.seam > v.seams || v.remaining != v.count - v.i)
        {
            k.at(118, r#"WsResult = 7"#);
            dat.ws_result = 7;
        }
        k.at(120, r#"IF (WsResult == 0) AND (Kind == 4) AND ((NOT Process) OR (I == 1)) THEN"#);
        if dat.ws_result == 0 && v.kind == 4 && (!v.process || v.i == 1) {
            k.at(121, r#"WsResult = 7"#);
            dat.ws_result = 7;
        }
        k.at(123, r#"IF (WsResult == 0) AND (Kind == 4) THEN"#);
        if dat.ws_result == 0 && v.kind == 4 {
            k.at(124, r#"IF WsKind[I - 1] <> 2 THEN"#);
            if dat.ws_kind[v.i as usize - 1] != 2 {
                k.at(125, r#"WsResult = 7"#);
                dat.ws_result = 7;
            }
        }
        k.at(128, r#"IF (WsResult == 0) AND (Kind == 4) THEN"#);
        if dat.ws_result == 0 && v.kind == 4 {
            let i = v.i as usize;
            k.at(129, r#"WsKind[I] = Kind"#);
            dat.ws_kind[i] = v.kind;
            k.at(130, r#"WsSeam[I] = Seam"#);
            dat.ws_seam[i] = v.seam;
            k.at(131, r#"WsSpeed[I] = X"#);
            dat.ws_speed[i] = v.x;
            k.at(132, r#"WsWeaveAmp[I] = Y"#);
            dat.ws_weave_amp[i] = v.y;
            k.at(133, r#"WsWeaveFreq[I] = Z"#);
            dat.ws_weave_freq[i] = v.z;
        }
        k.at(135, r#"IF (WsResult == 0) AND (Kind <> 4) THEN"#);
        if dat.ws_result == 0 && v.kind != 4 {
            let i = v.i as usize;
            k.at(136, r#"WsPath[I] = Capture"#);
            dat.ws_path[i] = v.capture;
            k.at(137, r#"WsPath[I].X = X"#);
            dat.ws_path[i].x = v.x;
            k.at(138, r#"WsPath[I].Y = Y"#);
            dat.ws_path[i].y = v.y;
            k.at(139, r#"WsPath[I].Z = Z"#);
            dat.ws_path[i].z = v.z;
            k.at(140, r#"WsPath[I].A = A"#);
            dat.ws_path[i].a = v.a;
            k.at(141, r#"WsPath[I].B = B"#);
            dat.ws_path[i].b = v.b;
            k.at(142, r#"WsPath[I].C = C"#);
            dat.ws_path[i].c = v.c;
            k.at(143, r#"WsKind[I] = Kind"#);
            dat.ws_kind[i] = v.kind;
            k.at(144, r#"WsSeam[I] = Seam"#);
            dat.ws_seam[i] = v.seam;
        }
    }
    k.at(147, r#"IF WsResult == 0 THEN"#);
    if dat.ws_result == 0 {
        k.at(148, r#"IF WsKind[Count] <> 3 THEN"#);
        if dat.ws_kind[v.count as usize] != 3 {
            k.at(149, r#"WsResult = 7"#);
            dat.ws_result = 7;
        }
    }

    k.at(156, r#"K = 0"#);
    v.kk = 0;
    k.at(157, r#"WHILE (WsResult == 0) AND (K < Seams)"#);
    while dat.ws_result == 0 && v.kk < v.seams {
        k.at(158, r#"K = K + 1"#);
        v.kk += 1;
        k.at(159, r#"Offset = 0"#);
        v.offset = 0;
        k.at(160, r#"StrClear(Line[])"#);
        v.line.clear();
        k.at(161, r#"SWRITE(Line[], St, Offset, "CHECK,%d", K)"#);
        swrite(&mut v.line, &mut v.offset, "CHECK,%d", &[Arg::Int(v.kk)]);
        k.at(162, r#"Ask(Line[], Reply[], ReplyTimeout)"#);
        ask(k, dat, &v.line, &mut v.reply, v.reply_timeout);
        k.at(163, r#"IF WsResult == 0 THEN"#);
        if dat.ws_result == 0 {
            k.at(164, r#"Offset = 0"#);
            v.offset = 0;
            k.at(165, r#"SREAD(Reply[], St, Offset, "%d,%d,%f,%f,%f", Code, N, X, Y, Z)"#);
            let (st, r) = sread(&v.reply, &mut v.offset, "%d,%d,%f,%f,%f");
            (v.code, v.n, v.hits) = (int(&r, 0, v.code), int(&r, 1, v.n), st.hits);
            (v.x, v.y, v.z) = (real(&r, 2, v.x), real(&r, 3, v.y), real(&r, 4, v.z));
            k.at(166, r#"IF St.HITS <> 5 THEN"#);
            if v.hits != 5 {
                k.at(167, r#"WsResult = 4"#);
                dat.ws_result = 4;
            }
        }
        k.at(170, r#"IF WsResult == 0 THEN"#);
        if dat.ws_result == 0 {
            k.at(171, r#"SumX = 0.0"#);
            v.sum_x = 0.0;
            k.at(172, r#"SumY = 0.0"#);
            v.sum_y = 0.0;
            k.at(173, r#"SumZ = 0.0"#);
            v.sum_z = 0.0;
            k.at(174, r#"Lines = 0"#);
            v.lines = 0;
            k.at(175, r#"FOR I = 1 TO Count"#);
            for i in 1..=v.count as usize {
                k.at(176, r#"IF (WsSeam[I] == K) AND (WsKind[I] <> 4) THEN"#);
                if dat.ws_seam[i] == v.kk && dat.ws_kind[i] != 4 {
                    k.at(177, r#"IF Lines == 0 THEN"#);
                    if v.lines == 0 {
                        k.at(178, r#"First = WsPath[I]"#);
                        v.first = dat.ws_path[i];
                    }
                    k.at(180, r#"Lines = Lines + 1"#);
                    v.lines += 1;
                    k.at(181, r#"SumX = SumX + (WsPath[I].X - First.X)"#);
                    v.sum_x += dat.ws_path[i].x - v.first.x;
                    k.at(182, r#"SumY = SumY + (WsPath[I].Y - First.Y)"#);
                    v.sum_y += dat.ws_path[i].y - v.first.y;
                    k.at(183, r#"SumZ = SumZ + (WsPath[I].Z - First.Z)"#);
                    v.sum_z += dat.ws_path[i].z - v.first.z;
                }
            }
            k.at(186, r#"IF (Lines <> N) OR (N < 3) THEN"#);
            if v.lines != v.n || v.n < 3 {
                k.at(187, r#"WsResult = 6"#);
                dat.ws_result = 6;
            } else {
                k.at(188, r#"ELSE"#);
                let n = v.n as f32;
                k.at(189, r#"IF (ABS(First.X + SumX / N - X) > 0.1) OR (ABS(First.Y + SumY / N - Y) > 0.1) OR (ABS(First.Z + SumZ / N - Z) > 0.1) THEN"#);
                let f = v.first;
                if (f.x + v.sum_x / n - v.x).abs() > 0.1
                    || (f.y + v.sum_y / n - v.y).abs() > 0.1
                    || (f.z + v.sum_z / n - v.z).abs() > 0.1
                {
                    k.at(190, r#"WsResult = 6"#);
                    dat.ws_result = 6;
                }
            }
        }
    }
    k.at(195, r#"RET = EKI_Close("WeldSeam")"#);
    k.eki_close("WeldSeam");
    k.at(196, r#"RET = EKI_Clear("WeldSeam")"#);
    k.eki_close("WeldSeam");

    k.at(198, r#"IF WsResult <> 0 THEN"#);
    if dat.ws_result != 0 {
        k.at(199, r#"Report(WsResult, Reply[])"#);
        report(k, dat.ws_result, &v.reply);
        k.at(200, r#"RETURN"#);
        return dat.ws_result;
    }

    k.at(206, r#"$ADVANCE = 3"#);
    k.advance = 3;
    k.at(207, r#"$APO.CDIS = BlendDist"#);
    k.apo_cdis = v.blend_dist;
    k.at(208, r#"ArcOn = FALSE"#);
    v.arc_on = false;
    k.at(209, r#"FOR I = 1 TO Count"#);
    for i in 1..=v.count as usize {
        k.at(210, r#"SWITCH WsKind[I]"#);
        match dat.ws_kind[i] {
            1 => {
                k.at(211, r#"CASE 1"#);
                k.at(212, r#"$VEL.CP = ApproachVel"#);
                k.vel_cp = v.approach_vel;
                k.at(213, r#"LIN WsPath[I]"#);
                k.lin(213, &dat.ws_path[i], false);
            }
            2 => {
                k.at(214, r#"CASE 2"#);
                k.at(216, r#"Nxt = I + 1"#);
                v.nxt = i as i32 + 1;
                k.at(217, r#"IF WsKind[I + 1] == 4 THEN"#);
                if dat.ws_kind[i + 1] == 4 {
                    k.at(218, r#"Nxt = I + 2"#);
                    v.nxt = i as i32 + 2;
                }
                k.at(220, r#"IF NOT ArcOn THEN"#);
                if !v.arc_on {
                    k.at(221, r#"$VEL.CP = ApproachVel"#);
                    k.vel_cp = v.approach_vel;
                    k.at(222, r#"LIN WsPath[I]"#);
                    k.lin(222, &dat.ws_path[i], false);
                    k.at(224, r#"IF NOT DryRun THEN"#);
                    if !v.dry_run {
                        k.at(225, r#"$OUT[ArcOut] = TRUE"#);
                        k.set_output(v.arc_out, true);
                    }
                    k.at(227, r#"ArcOn = TRUE"#);
                    v.arc_on = true;
                    k.at(228, r#"$VEL.CP = WeldVel"#);
                    k.vel_cp = v.weld_vel;
                } else {
                    k.at(229, r#"ELSE"#);
                    k.at(231, r#"$VEL.CP = WeldVel"#);
                    k.vel_cp = v.weld_vel;
                    k.at(232, r#"IF WsKind[I + 1] == 4 THEN"#);
                    if dat.ws_kind[i + 1] == 4 {
                        k.at(233, r#"IF WsSpeed[I + 1] > 0.0 THEN"#);
                        if dat.ws_speed[i + 1] > 0.0 {
                            k.at(234, r#"$VEL.CP = WsSpeed[I + 1] / 1000.0"#);
                            k.vel_cp = dat.ws_speed[i + 1] / 1000.0;
                        }
                    }
                    k.at(237, r#"IF WsKind[Nxt] == 2 THEN"#);
                    if dat.ws_kind[v.nxt as usize] == 2 {
                        k.at(239, r#"Prv = I - 1"#);
                        v.prv = i as i32 - 1;
                        k.at(240, r#"IF WsKind[Prv] == 4 THEN"#);
                        if dat.ws_kind[v.prv as usize] == 4 {
                            k.at(241, r#"Prv = I - 2"#);
                            v.prv = i as i32 - 2;
                        }
                        k.at(243, r#"Shorter = Dist(WsPath[Prv], WsPath[I])"#);
                        v.shorter = dist(k, &dat.ws_path[v.prv as usize], &dat.ws_path[i]);
                        k.at(244, r#"IF Dist(WsPath[I], WsPath[Nxt]) < Shorter THEN"#);
                        if dist(k, &dat.ws_path[i], &dat.ws_path[v.nxt as usize]) < v.shorter {
                            k.at(245, r#"Shorter = Dist(WsPath[I], WsPath[Nxt])"#);
                            v.shorter = dist(k, &dat.ws_path[i], &dat.ws_path[v.nxt as usize]);
                        }
                        k.at(247, r#"$APO.CDIS = BlendDist"#);
                        k.apo_cdis = v.blend_dist;
                        k.at(248, r#"IF 0.25 * Shorter < BlendDist THEN"#);
                        if 0.25 * v.shorter < v.blend_dist {
                            k.at(249, r#"$APO.CDIS = 0.25 * Shorter"#);
                            k.apo_cdis = 0.25 * v.shorter;
                        }
                        k.at(252, r#"LIN WsPath[I] C_DIS"#);
                        k.lin(252, &dat.ws_path[i], true);
                    } else {
                        k.at(253, r#"ELSE"#);
                        k.at(254, r#"LIN WsPath[I]"#);
                        k.lin(254, &dat.ws_path[i], false);
                        k.at(256, r#"IF NOT DryRun THEN"#);
                        if !v.dry_run {
                            k.at(257, r#"$OUT[ArcOut] = FALSE"#);
                            k.set_output(v.arc_out, false);
                        }
                        k.at(259, r#"ArcOn = FALSE"#);
                        v.arc_on = false;
                    }
                }
            }
            3 => {
                k.at(262, r#"CASE 3"#);
                k.at(263, r#"IF ArcOn THEN"#);
                if v.arc_on {
                    k.at(265, r#"IF NOT DryRun THEN"#);
                    if !v.dry_run {
                        k.at(266, r#"$OUT[ArcOut] = FALSE"#);
                        k.set_output(v.arc_out, false);
                    }
                    k.at(268, r#"ArcOn = FALSE"#);
                    v.arc_on = false;
                }
                k.at(270, r#"$VEL.CP = ApproachVel"#);
                k.vel_cp = v.approach_vel;
                k.at(271, r#"LIN WsPath[I]"#);
                k.lin(271, &dat.ws_path[i], false);
            }
            4 => {
                k.at(272, r#"CASE 4"#);
            }
            other => panic!("SWITCH without a CASE for {other}: KRL stops with an error"),
        }
    }
    k.at(276, r#"END"#);
    k.trace.advance_stop();
    dat.ws_result
}

/// `Ask(Request[], Answer[], Timeout)`.
fn ask(k: &mut Krl, dat: &mut DataList, request: &Chars, answer: &mut Chars, timeout: i32) {
    k.at(282, r#"DEF Ask(Request[]:OUT, Answer[]:OUT, Timeout:IN)"#);
    k.at(283, r#"DECL CHAR Request[], Answer[]"#);
    k.at(284, r#"DECL INT Timeout, Offset, Code"#);
    k.at(285, r#"DECL EKI_STATUS RET"#);
    k.at(286, r#"DECL CHAR Sent[256]"#);
    let mut sent = Chars::new(256);
    k.at(287, r#"DECL STATE_T St"#);
    k.at(288, r#"$FLAG[1] = FALSE"#);
    k.set_flag(1, false);
    k.at(289, r#"StrClear(Sent[])"#);
    sent.clear();
    k.at(290, r#"Offset = 0"#);
    let mut offset = 0;
    k.at(291, r#"SWRITE(Sent[], St, Offset, "%s%c%c", Request[], 13, 10)"#);
    swrite(&mut sent, &mut offset, "%s%c%c", &[Arg::Text(request), Arg::Int(13), Arg::Int(10)]);
    k.at(292, r#"RET = EKI_Send("WeldSeam", Sent[])"#);
    k.eki_send("WeldSeam", &sent);
    k.at(293, r#"$TIMER_STOP[1] = TRUE"#);
    k.set_timer_stop(1, true);
    k.at(294, r#"$TIMER[1] = -Timeout"#);
    k.set_timer(1, -i64::from(timeout));
    k.at(295, r#"$TIMER_STOP[1] = FALSE"#);
    k.set_timer_stop(1, false);
    k.at(296, r#"WAIT FOR $FLAG[1] OR $TIMER_FLAG[1] OR NOT $FLAG[2]"#);
    k.wait_for(|k| k.flag(1) || k.timer_flag(1) || !k.flag(2));
    k.at(297, r#"$TIMER_STOP[1] = TRUE"#);
    k.set_timer_stop(1, true);
    k.at(298, r#"IF NOT $FLAG[1] THEN"#);
    if !k.flag(1) {
        k.at(299, r#"IF $FLAG[2] THEN"#);
        if k.flag(2) {
            k.at(300, r#"WsResult = 3"#);
            dat.ws_result = 3;
        } else {
            k.at(301, r#"ELSE"#);
            k.at(302, r#"WsResult = 2"#);
            dat.ws_result = 2;
        }
        k.at(304, r#"RETURN"#);
        return;
    }
    k.at(306, r#"$FLAG[1] = FALSE"#);
    k.set_flag(1, false);
    k.at(307, r#"StrClear(Answer[])"#);
    answer.clear();
    k.at(308, r#"RET = EKI_GetString("WeldSeam", "Line", Answer[])"#);
    let ret = k.eki_get_string("WeldSeam", "Line", answer);
    k.at(309, r#"IF RET.Msg_No <> 0 THEN"#);
    if ret.msg_no != 0 {
        k.at(310, r#"WsResult = 2"#);
        dat.ws_result = 2;
        k.at(311, r#"RETURN"#);
        return;
    }
    k.at(313, r#"IF Answer[1] == "-" THEN"#);
    if answer.0[0] == b'-' {
        k.at(314, r#"Offset = 0"#);
        offset = 0;
        k.at(315, r#"SREAD(Answer[], St, Offset, "%d", Code)"#);
        let (st, r) = sread(answer, &mut offset, "%d");
        let code = int(&r, 0, 0);
        k.at(316, r#"WsResult = Code"#);
        dat.ws_result = code;
        k.at(317, r#"IF (St.HITS <> 1) OR (Code >= 0) THEN"#);
        if st.hits != 1 || code >= 0 {
            k.at(318, r#"WsResult = 4"#);
            dat.ws_result = 4;
        }
    }
    k.at(321, r#"END"#);
}

/// `Report(Result, Answer[])`.
fn report(k: &mut Krl, result: i32, answer: &Chars) {
    k.at(331, r#"DEF Report(Result:IN, Answer[]:OUT)"#);
    k.at(332, r#"DECL INT Result"#);
    k.at(333, r#"DECL CHAR Answer[]"#);
    k.at(334, r#"SWITCH Result"#);
    match result {
        1 => {
            k.at(335, r#"CASE 1"#);
            k.at(336, r#"MsgNotify("EKI channel WeldSeam did not open: check WeldSeam.xml and the daemon's address", "weldseam")"#);
            k.msg_notify("EKI channel WeldSeam did not open: check WeldSeam.xml and the daemon's address");
        }
        2 => {
            k.at(337, r#"CASE 2"#);
            k.at(338, r#"MsgNotify("link to the daemon lost before the weld: the torch did not move", "weldseam")"#);
            k.msg_notify("link to the daemon lost before the weld: the torch did not move");
        }
        3 => {
            k.at(339, r#"CASE 3"#);
            k.at(340, r#"MsgNotify("no reply from the daemon in time: the torch did not move", "weldseam")"#);
            k.msg_notify("no reply from the daemon in time: the torch did not move");
        }
        4 | 7 => {
            k.at(341, r#"CASE 4, 7"#);
            k.at(342, r#"MsgNotify("a reply from the daemon not understood: the torch did not move", "weldseam")"#);
            k.msg_notify("a reply from the daemon not understood: the torch did not move");
        }
        5 => {
            k.at(343, r#"CASE 5"#);
            k.at(
                344,
                r#"MsgNotify("plan too long for WS_MAX_LINES in WeldSeam.dat: the torch did not move", "weldseam")"#,
            );
            k.msg_notify("plan too long for WS_MAX_LINES in WeldSeam.dat: the torch did not move");
        }
        6 => {
            k.at(345, r#"CASE 6"#);
            k.at(346, r#"MsgNotify("a seam failed CHECK (count or means): the torch did not move", "weldseam")"#);
            k.msg_notify("a seam failed CHECK (count or means): the torch did not move");
        }
        8 => {
            k.at(347, r#"CASE 8"#);
            k.at(348, r#"MsgNotify("the daemon speaks another text link version (2 expected)", "weldseam")"#);
            k.msg_notify("the daemon speaks another text link version (2 expected)");
        }
        _ => {
            k.at(349, r#"DEFAULT"#);
            k.at(350, r#"MsgNotify(Answer[], "weldseam")"#);
            k.msg_notify(&answer.text());
        }
    }
    k.at(352, r#"END"#);
}

/// `Dist(P, Q)`: the distance between two poses' positions, mm, in
/// 32-bit REALs.
fn dist(k: &mut Krl, p: &E6Pos, q: &E6Pos) -> f32 {
    k.at(324, r#"DEFFCT REAL Dist(P:IN, Q:IN)"#);
    k.at(325, r#"DECL E6POS P, Q"#);
    k.at(326, r#"RETURN SQRT((P.X - Q.X) * (P.X - Q.X) + (P.Y - Q.Y) * (P.Y - Q.Y) + (P.Z - Q.Z) * (P.Z - Q.Z))"#);
    let d = ((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z)).sqrt();
    k.at(327, r#"ENDFCT"#);
    d
}

/// The tags of this file against the shipped KRL program.
#[test]
fn the_transcription_follows_weld_seam_src_line_by_line() {
    let statement = |line: &str| !line.is_empty() && !line.starts_with(';') && !super::robot::is_closer(line);
    if let Err(e) = super::transcription::check("kuka/WeldSeam.src", include_str!("kuka.rs"), statement) {
        panic!("{e}");
    }
}
