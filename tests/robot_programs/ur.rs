//! deploy/robots/ur/weld_seam.script transcribed statement by statement
//! onto the emulated controller of [`super::urscript`]: each statement
//! tagged with its line and text in the program file (checked by
//! [`super::transcription`]), URScript's numbers as f64, its lists as
//! vectors (an index out of range panics, as the controller would stop).
//! A condition is a block that tags its line where it is evaluated, so
//! each `elif` and `while` line is seen to run.
#![allow(clippy::blocks_in_conditions)]

use super::urscript::{Pose, Ur, int_to_str, norm, point_dist, pose_to_str};

/// What a test sets instead of the cell settings at the program's top.
pub struct Settings {
    pub daemon_ip: String,
    pub daemon_port: f64,
    pub joint: String,
    pub dry_run: bool,
}

/// The program's settings as the test reads them back.
pub const WELD_SPEED: f64 = 0.008;
pub const BLEND_RADIUS: f64 = 0.0004;
pub const ARC_OUTPUT: u32 = 0;

/// Runs the program; returns its `result`.
pub fn weld_seam(u: &mut Ur, s: &Settings) -> f64 {
    u.at(242, r#"weld_seam()"#);
    u.at(29, r#"def weld_seam():"#);
    u.at(31, r#"DAEMON_IP = "192.168.1.10""#);
    let daemon_ip = s.daemon_ip.clone();
    u.at(32, r#"DAEMON_PORT = 7303"#);
    let daemon_port = s.daemon_port;
    u.at(33, r#"JOINT = "lap""#);
    let joint = s.joint.clone();
    u.at(34, r#"DRY_RUN = True"#);
    let dry_run = s.dry_run;
    u.at(35, r#"WELD_SPEED = 0.008"#);
    let weld_speed = WELD_SPEED;
    u.at(36, r#"WELD_ACCEL = 0.5"#);
    let weld_accel = 0.5;
    u.at(37, r#"BLEND_RADIUS = 0.0004"#);
    let blend_radius = BLEND_RADIUS;
    u.at(38, r#"APPROACH_SPEED = 0.05"#);
    let approach_speed = 0.05;
    u.at(39, r#"APPROACH_ACCEL = 0.5"#);
    let approach_accel = 0.5;
    u.at(40, r#"ARC_OUTPUT = 0"#);
    let arc_output = ARC_OUTPUT as f64;
    u.at(41, r#"ARC_SETTLE = 0.3"#);
    let arc_settle = 0.3;
    u.at(42, r#"REPLY_TIMEOUT = 30"#);
    let reply_timeout = 30.0;
    u.at(43, r#"MAX_LINES = 2000"#);
    let max_lines = 2000.0;
    u.at(44, r#"CHECK_TOLERANCE = 0.0001"#);
    let check_tolerance = 0.0001;
    u.at(46, r#"poses = make_list(MAX_LINES, p[0, 0, 0, 0, 0, 0], MAX_LINES)"#);
    let mut poses: Vec<Pose> = vec![[0.0; 6]; max_lines as usize];
    u.at(47, r#"kinds = make_list(MAX_LINES, 0, MAX_LINES)"#);
    let mut kinds: Vec<f64> = vec![0.0; max_lines as usize];
    u.at(48, r#"seams = make_list(MAX_LINES, 0, MAX_LINES)"#);
    let mut seams: Vec<f64> = vec![0.0; max_lines as usize];
    u.at(50, r#"speeds = make_list(MAX_LINES, 0, MAX_LINES)"#);
    let mut speeds: Vec<f64> = vec![0.0; max_lines as usize];
    u.at(51, r#"amps = make_list(MAX_LINES, 0, MAX_LINES)"#);
    let mut amps: Vec<f64> = vec![0.0; max_lines as usize];
    u.at(52, r#"freqs = make_list(MAX_LINES, 0, MAX_LINES)"#);
    let mut freqs: Vec<f64> = vec![0.0; max_lines as usize];
    u.at(53, r#"process = False"#);
    let mut process = false;
    u.at(54, r#"result = 0"#);
    let mut result = 0.0;
    u.at(55, r#"count = 0"#);
    let mut count = 0.0;
    u.at(56, r#"seam_count = 0"#);
    let mut seam_count = 0.0;
    u.at(57, r#"reason = """#);
    let mut reason = String::new();

    u.at(59, r#"if not socket_open(DAEMON_IP, DAEMON_PORT, "weldseam"):"#);
    if !u.socket_open(&daemon_ip, daemon_port, "weldseam") {
        u.at(60, r#"result = 1"#);
        result = 1.0;
    }
    u.at(62, r#"if result == 0:"#);
    if result == 0.0 {
        u.at(63, r#"socket_send_line("HELLO,ur,PROCESS", "weldseam")"#);
        u.socket_send_line("HELLO,ur,PROCESS", "weldseam");
        u.at(64, r#"hello = socket_read_ascii_float(3, "weldseam", REPLY_TIMEOUT)"#);
        let hello = u.socket_read_ascii_float(3, "weldseam", reply_timeout);
        if {
            u.at(65, r#"if hello[0] == 0:"#);
            hello[0] == 0.0
        } {
            u.at(66, r#"result = 3"#);
            result = 3.0;
        } else if {
            u.at(67, r#"elif hello[0] != 3:"#);
            hello[0] != 3.0
        } {
            u.at(68, r#"result = 4"#);
            result = 4.0;
        } else if {
            u.at(69, r#"elif hello[1] < 0:"#);
            hello[1] < 0.0
        } {
            u.at(70, r#"result = hello[1]"#);
            result = hello[1];
        } else if {
            u.at(71, r#"elif hello[2] != 2:"#);
            hello[2] != 2.0
        } {
            u.at(72, r#"result = 8"#);
            result = 8.0;
        } else {
            u.at(74, r#"process = hello[3] == 1"#);
            process = hello[3] == 1.0;
        }
    }

    u.at(78, r#"if result == 0:"#);
    if result == 0.0 {
        u.at(79, r#"capture = get_actual_tool_flange_pose()"#);
        let capture = u.get_actual_tool_flange_pose();
        u.at(80, r#"if not socket_send_line(str_cat(str_cat("TRIGGER,", JOINT), str_cat(",", to_str(capture))), "weldseam"):"#);
        let line = format!("TRIGGER,{joint},{}", pose_to_str(&capture));
        if !u.socket_send_line(&line, "weldseam") {
            u.at(81, r#"result = 2"#);
            result = 2.0;
        }
    }
    u.at(84, r#"if result == 0:"#);
    if result == 0.0 {
        u.at(85, r#"status = socket_read_ascii_float(3, "weldseam", REPLY_TIMEOUT)"#);
        let status = u.socket_read_ascii_float(3, "weldseam", reply_timeout);
        if {
            u.at(86, r#"if status[0] == 0:"#);
            status[0] == 0.0
        } {
            u.at(87, r#"result = 3"#);
            result = 3.0;
        } else if {
            u.at(88, r#"elif status[0] != 3:"#);
            status[0] != 3.0
        } {
            u.at(89, r#"result = 4"#);
            result = 4.0;
        } else if {
            u.at(90, r#"elif status[1] < 0:"#);
            status[1] < 0.0
        } {
            u.at(91, r#"result = status[1]"#);
            result = status[1];
        } else if {
            u.at(92, r#"elif status[3] > MAX_LINES:"#);
            status[3] > max_lines
        } {
            u.at(93, r#"result = 5"#);
            result = 5.0;
            u.at(94, r#"socket_send_line("DROP", "weldseam")"#);
            u.socket_send_line("DROP", "weldseam");
            u.at(95, r#"socket_read_ascii_float(3, "weldseam", REPLY_TIMEOUT)"#);
            u.socket_read_ascii_float(3, "weldseam", reply_timeout);
        } else {
            u.at(97, r#"seam_count = status[2]"#);
            seam_count = status[2];
            u.at(98, r#"count = status[3]"#);
            count = status[3];
        }
    }

    u.at(102, r#"k = 0"#);
    let mut k = 0.0;
    while {
        u.at(103, r#"while result == 0 and k < count:"#);
        result == 0.0 && k < count
    } {
        u.at(104, r#"if not socket_send_line("NEXT", "weldseam"):"#);
        if !u.socket_send_line("NEXT", "weldseam") {
            u.at(105, r#"result = 2"#);
            result = 2.0;
        }
        u.at(107, r#"if result == 0:"#);
        if result == 0.0 {
            u.at(108, r#"w = socket_read_ascii_float(9, "weldseam", REPLY_TIMEOUT)"#);
            let w = u.socket_read_ascii_float(9, "weldseam", reply_timeout);
            let i = k as usize;
            if {
                u.at(109, r#"if w[0] == 0:"#);
                w[0] == 0.0
            } {
                u.at(110, r#"result = 3"#);
                result = 3.0;
            } else if {
                u.at(111, r#"elif w[0] != 9:"#);
                w[0] != 9.0
            } {
                u.at(112, r#"result = 4"#);
                result = 4.0;
            } else if {
                u.at(113, r#"elif w[1] < 0:"#);
                w[1] < 0.0
            } {
                u.at(114, r#"result = w[1]"#);
                result = w[1];
            } else if {
                u.at(115, r#"elif w[3] != count - k - 1:"#);
                w[3] != count - k - 1.0
            } {
                u.at(116, r#"result = 7"#);
                result = 7.0;
            } else if {
                u.at(117, r#"elif k == 0 and (w[1] != 1 or w[2] != 1):"#);
                k == 0.0 && (w[1] != 1.0 || w[2] != 1.0)
            } {
                u.at(118, r#"result = 7"#);
                result = 7.0;
            } else if {
                u.at(119, r#"elif k > 0 and w[1] == 1 and (kinds[k - 1] != 3 or w[2] != seams[k - 1] + 1):"#);
                k > 0.0 && w[1] == 1.0 && (kinds[i - 1] != 3.0 || w[2] != seams[i - 1] + 1.0)
            } {
                u.at(120, r#"result = 7"#);
                result = 7.0;
            } else if {
                u.at(121, r#"elif k > 0 and ((process and kinds[k - 1] == 2) != (w[1] == 4)):"#);
                k > 0.0 && ((process && kinds[i - 1] == 2.0) != (w[1] == 4.0))
            } {
                u.at(122, r#"result = 7"#);
                result = 7.0;
            } else if {
                u.at(123, r#"elif k > 0 and w[1] != 1 and (kinds[k - 1] == 3 or w[2] != seams[k - 1] or (w[1] == 3 and kinds[k - 1] != 2 and kinds[k - 1] != 4)):"#);
                k > 0.0
                    && w[1] != 1.0
                    && (kinds[i - 1] == 3.0
                        || w[2] != seams[i - 1]
                        || (w[1] == 3.0 && kinds[i - 1] != 2.0 && kinds[i - 1] != 4.0))
            } {
                u.at(124, r#"result = 7"#);
                result = 7.0;
            } else {
                u.at(126, r#"if w[1] == 4:"#);
                if w[1] == 4.0 {
                    u.at(127, r#"speeds[k] = w[4]"#);
                    speeds[i] = w[4];
                    u.at(128, r#"amps[k] = w[5]"#);
                    amps[i] = w[5];
                    u.at(129, r#"freqs[k] = w[6]"#);
                    freqs[i] = w[6];
                } else {
                    u.at(131, r#"poses[k] = p[w[4], w[5], w[6], w[7], w[8], w[9]]"#);
                    poses[i] = [w[4], w[5], w[6], w[7], w[8], w[9]];
                }
                u.at(133, r#"kinds[k] = w[1]"#);
                kinds[i] = w[1];
                u.at(134, r#"seams[k] = w[2]"#);
                seams[i] = w[2];
                u.at(135, r#"k = k + 1"#);
                k += 1.0;
            }
        }
    }
    u.at(139, r#"if result == 0 and count > 0 and (kinds[count - 1] != 3 or seams[count - 1] != seam_count):"#);
    if result == 0.0 && count > 0.0 && {
        let last = count as usize - 1;
        kinds[last] != 3.0 || seams[last] != seam_count
    } {
        u.at(140, r#"result = 7"#);
        result = 7.0;
    }

    u.at(143, r#"s = 1"#);
    let mut seam = 1.0;
    while {
        u.at(144, r#"while result == 0 and s <= seam_count:"#);
        result == 0.0 && seam <= seam_count
    } {
        u.at(145, r#"n = 0"#);
        let mut n = 0.0;
        u.at(146, r#"sx = 0"#);
        let mut sx = 0.0;
        u.at(147, r#"sy = 0"#);
        let mut sy = 0.0;
        u.at(148, r#"sz = 0"#);
        let mut sz = 0.0;
        u.at(149, r#"j = 0"#);
        let mut j = 0.0;
        while {
            u.at(150, r#"while j < count:"#);
            j < count
        } {
            let i = j as usize;
            u.at(151, r#"if seams[j] == s and kinds[j] != 4:"#);
            if seams[i] == seam && kinds[i] != 4.0 {
                u.at(152, r#"n = n + 1"#);
                n += 1.0;
                u.at(153, r#"sx = sx + poses[j][0]"#);
                sx += poses[i][0];
                u.at(154, r#"sy = sy + poses[j][1]"#);
                sy += poses[i][1];
                u.at(155, r#"sz = sz + poses[j][2]"#);
                sz += poses[i][2];
            }
            u.at(157, r#"j = j + 1"#);
            j += 1.0;
        }
        u.at(159, r#"if not socket_send_line(str_cat("CHECK,", to_str(s)), "weldseam"):"#);
        if !u.socket_send_line(&format!("CHECK,{}", int_to_str(seam)), "weldseam") {
            u.at(160, r#"result = 2"#);
            result = 2.0;
        }
        u.at(162, r#"if result == 0:"#);
        if result == 0.0 {
            u.at(163, r#"c = socket_read_ascii_float(5, "weldseam", REPLY_TIMEOUT)"#);
            let c = u.socket_read_ascii_float(5, "weldseam", reply_timeout);
            if {
                u.at(164, r#"if c[0] == 0:"#);
                c[0] == 0.0
            } {
                u.at(165, r#"result = 3"#);
                result = 3.0;
            } else if {
                u.at(166, r#"elif c[0] != 5:"#);
                c[0] != 5.0
            } {
                u.at(167, r#"result = 4"#);
                result = 4.0;
            } else if {
                u.at(168, r#"elif c[1] < 0:"#);
                c[1] < 0.0
            } {
                u.at(169, r#"result = c[1]"#);
                result = c[1];
            } else if {
                u.at(170, r#"elif c[2] != n or n == 0:"#);
                c[2] != n || n == 0.0
            } {
                u.at(171, r#"result = 6"#);
                result = 6.0;
            } else if {
                u.at(172, r#"elif norm(sx / n - c[3]) > CHECK_TOLERANCE or norm(sy / n - c[4]) > CHECK_TOLERANCE or norm(sz / n - c[5]) > CHECK_TOLERANCE:"#);
                norm(sx / n - c[3]) > check_tolerance
                    || norm(sy / n - c[4]) > check_tolerance
                    || norm(sz / n - c[5]) > check_tolerance
            } {
                u.at(173, r#"result = 6"#);
                result = 6.0;
            }
        }
        u.at(176, r#"s = s + 1"#);
        seam += 1.0;
    }

    u.at(179, r#"if result < 0:"#);
    if result < 0.0 {
        u.at(180, r#"socket_send_line("WHY", "weldseam")"#);
        u.socket_send_line("WHY", "weldseam");
        u.at(181, r#"reason = socket_read_line("weldseam", REPLY_TIMEOUT)"#);
        reason = u.socket_read_line("weldseam", reply_timeout);
        u.at(182, r#"if reason == "":"#);
        if reason.is_empty() {
            u.at(183, r#"reason = socket_read_line("weldseam", REPLY_TIMEOUT)"#);
            reason = u.socket_read_line("weldseam", reply_timeout);
        }
    }
    u.at(186, r#"socket_close("weldseam")"#);
    u.socket_close("weldseam");
    u.at(187, r#"if result != 0:"#);
    if result != 0.0 {
        u.at(188, r#"popup(str_cat(str_cat("weldseam result ", to_str(result)), str_cat(": ", reason)), "weldseam", error=True)"#);
        u.popup(&format!("weldseam result {}: {reason}", int_to_str(result)));
        u.at(189, r#"halt()"#);
        u.halt();
        return result;
    }

    u.at(192, r#"j = 0"#);
    let mut j = 0.0;
    u.at(193, r#"before = 0"#);
    let mut before = 0;
    while {
        u.at(194, r#"while j < count:"#);
        j < count
    } {
        let i = j as usize;
        u.at(197, r#"v = WELD_SPEED"#);
        let mut v = weld_speed;
        u.at(198, r#"after = j + 1"#);
        let mut after = i + 1;
        u.at(199, r#"if kinds[j] == 2:"#);
        if kinds[i] == 2.0 {
            u.at(200, r#"if kinds[j + 1] == 4:"#);
            if kinds[i + 1] == 4.0 {
                u.at(201, r#"after = j + 2"#);
                after = i + 2;
                u.at(202, r#"if speeds[j + 1] > 0:"#);
                if speeds[i + 1] > 0.0 {
                    u.at(203, r#"v = speeds[j + 1]"#);
                    v = speeds[i + 1];
                }
                // WEAVE: the weave is in the path; the line's is 0.
                let _weave = (amps[i + 1], freqs[i + 1]);
            }
        }
        if {
            u.at(208, r#"if kinds[j] == 1:"#);
            kinds[i] == 1.0
        } {
            u.at(209, r#"movel(poses[j], a=APPROACH_ACCEL, v=APPROACH_SPEED)"#);
            u.movel(209, &poses[i], approach_accel, approach_speed, 0.0);
        } else if {
            u.at(210, r#"elif kinds[j] == 3:"#);
            kinds[i] == 3.0
        } {
            u.at(211, r#"set_standard_digital_out(ARC_OUTPUT, False)"#);
            u.set_standard_digital_out(arc_output, false);
            u.at(212, r#"movel(poses[j], a=APPROACH_ACCEL, v=APPROACH_SPEED)"#);
            u.movel(212, &poses[i], approach_accel, approach_speed, 0.0);
        } else if {
            u.at(213, r#"elif kinds[j - 1] == 1:"#);
            kinds[i - 1] == 1.0
        } {
            u.at(214, r#"movel(poses[j], a=APPROACH_ACCEL, v=APPROACH_SPEED)"#);
            u.movel(214, &poses[i], approach_accel, approach_speed, 0.0);
            u.at(216, r#"if not DRY_RUN:"#);
            if !dry_run {
                u.at(217, r#"set_standard_digital_out(ARC_OUTPUT, True)"#);
                u.set_standard_digital_out(arc_output, true);
                u.at(218, r#"sleep(ARC_SETTLE)"#);
                u.sleep(arc_settle);
            }
        } else if {
            u.at(220, r#"elif kinds[after] == 3:"#);
            kinds[after] == 3.0
        } {
            u.at(221, r#"movep(poses[j], a=WELD_ACCEL, v=v, r=0)"#);
            u.movep(221, &poses[i], weld_accel, v, 0.0);
            u.at(223, r#"set_standard_digital_out(ARC_OUTPUT, False)"#);
            u.set_standard_digital_out(arc_output, false);
        } else {
            u.at(227, r#"r = BLEND_RADIUS"#);
            let mut r = blend_radius;
            u.at(228, r#"shorter = point_dist(poses[before], poses[j])"#);
            let mut shorter = point_dist(&poses[before], &poses[i]);
            u.at(229, r#"if point_dist(poses[j], poses[after]) < shorter:"#);
            if point_dist(&poses[i], &poses[after]) < shorter {
                u.at(230, r#"shorter = point_dist(poses[j], poses[after])"#);
                shorter = point_dist(&poses[i], &poses[after]);
            }
            u.at(232, r#"if 0.25 * shorter < r:"#);
            if 0.25 * shorter < r {
                u.at(233, r#"r = 0.25 * shorter"#);
                r = 0.25 * shorter;
            }
            u.at(235, r#"movep(poses[j], a=WELD_ACCEL, v=v, r=r)"#);
            u.movep(235, &poses[i], weld_accel, v, r);
        }
        u.at(238, r#"before = j"#);
        before = i;
        u.at(239, r#"j = after"#);
        j = after as f64;
    }
    result
}

#[test]
fn the_transcription_follows_the_program_line_by_line() {
    let source = include_str!("ur.rs");
    let transcription = &source[..source.find("#[test]").unwrap()];
    let statements = super::transcription::check("ur/weld_seam.script", transcription, super::urscript::is_statement)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(statements > 100, "{statements}");
}
