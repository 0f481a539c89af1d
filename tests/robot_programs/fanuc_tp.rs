//! `deploy/robots/fanuc/WELD_SEAM.LS`, the TP program, transcribed line
//! by line onto the emulated TP primitives of `karel.rs`: the program
//! counter walks the TP lines, `JMP LBL[n]` goes to the line that reads
//! `LBL[n]`, each statement tagged with its line and text in the file.

use super::fanuc::{Helper, weldseam};
use super::karel::{Controller, Register};
use super::robot::Event;

const FILE: &str = "fanuc/WELD_SEAM.LS";

/// The TP line number of `LBL[n]`, as the TP interpreter finds it.
fn lbl(n: usize) -> usize {
    let (_, text) = super::transcription::program(FILE);
    let label = format!(":  LBL[{n}] ;");
    let line = text.lines().find(|l| l.trim_start().ends_with(&label)).unwrap_or_else(|| panic!("no LBL[{n}]"));
    line.trim_start().split(':').next().unwrap().parse().unwrap()
}

fn r(tp: &Controller, n: usize) -> i32 {
    tp.r[n].int()
}

/// Runs WELD_SEAM from its first line to its end; `dry_run` as the
/// integrator sets R[23] in the settings block.
pub fn weld_seam(tp: &mut Controller, h: &mut Helper, dry_run: bool) {
    let mut pc = 1;
    while pc <= 96 {
        let mut next = pc + 1;
        match pc {
            3 => {
                tp.at(7, r#"3:  R[20:ws weld mm/s]=8    ;"#);
                tp.r[20] = Register::Int(8);
            }
            4 => {
                tp.at(8, r#"4:  R[21:ws approach mm/s]=250    ;"#);
                tp.r[21] = Register::Int(250);
            }
            5 => {
                tp.at(9, r#"5:  R[22:ws blend CNT]=100    ;"#);
                tp.r[22] = Register::Int(100);
            }
            6 => {
                tp.at(10, r#"6:  R[23:ws dry run]=0    ;"#);
                tp.r[23] = Register::Int(i32::from(dry_run));
            }
            12 => {
                tp.at(16, r#"12:  UTOOL_NUM=1 ;"#);
                tp.utool_num = 1;
            }
            13 => {
                tp.at(17, r#"13:  UFRAME_NUM=0 ;"#);
                tp.uframe_num = 0;
            }
            14 => {
                tp.at(18, r#"14:  R[9:ws result]=9    ;"#);
                tp.r[9] = Register::Int(9);
            }
            15 => {
                tp.at(19, r#"15:  CALL WELDSEAM(1) ;"#);
                tp.tpe_params = vec![1];
                weldseam(tp, h);
            }
            16 => {
                tp.at(20, r#"16:  IF R[9:ws result]<0,JMP LBL[98] ;"#);
                if r(tp, 9) < 0 {
                    next = lbl(98);
                }
            }
            17 => {
                tp.at(21, r#"17:  IF R[9:ws result]>0,JMP LBL[99] ;"#);
                if r(tp, 9) > 0 {
                    next = lbl(99);
                }
            }
            20 => {
                tp.at(24, r#"20:  R[1:ws line]=0    ;"#);
                tp.r[1] = Register::Int(0);
            }
            21 => tp.at(25, r#"21:  LBL[1] ;"#),
            22 => {
                tp.at(26, r#"22:  R[1:ws line]=R[1:ws line]+1    ;"#);
                tp.r[1] = Register::Int(r(tp, 1) + 1);
            }
            23 => {
                tp.at(27, r#"23:  IF R[1:ws line]>R[10:ws lines],JMP LBL[90] ;"#);
                if r(tp, 1) > r(tp, 10) {
                    next = lbl(90);
                }
            }
            24 => {
                tp.at(28, r#"24:  CALL WELDSEAM(2,R[1:ws line]) ;"#);
                tp.tpe_params = vec![2, r(tp, 1)];
                weldseam(tp, h);
            }
            25..=29 => {
                tp.at(29, r#"25:  SELECT R[3:ws kind]=1,JMP LBL[10] ;"#);
                tp.at(30, r#"26:         =2,JMP LBL[20] ;"#);
                tp.at(31, r#"27:         =3,JMP LBL[30] ;"#);
                tp.at(32, r#"28:         =4,JMP LBL[1] ;"#);
                tp.at(33, r#"29:         ELSE,JMP LBL[99] ;"#);
                next = match r(tp, 3) {
                    1 => lbl(10),
                    2 => lbl(20),
                    3 => lbl(30),
                    4 => lbl(1),
                    _ => lbl(99),
                };
            }
            31 => tp.at(35, r#"31:  LBL[10] ;"#),
            32 => {
                tp.at(36, r#"32:L PR[R[2:ws pr]] R[21:ws approach mm/s]mm/sec FINE    ;"#);
                tp.linear(36, r(tp, 2) as usize, tp.r[21].value(), false);
            }
            33 => {
                tp.at(37, r#"33:  R[6:ws arc]=0    ;"#);
                tp.r[6] = Register::Int(0);
            }
            34 => {
                tp.at(38, r#"34:  JMP LBL[1] ;"#);
                next = lbl(1);
            }
            38 => tp.at(42, r#"38:  LBL[20] ;"#),
            39 => {
                tp.at(43, r#"39:  IF R[7:ws speed mm/s]>0,JMP LBL[23] ;"#);
                if tp.r[7].value() > 0.0 {
                    next = lbl(23);
                }
            }
            40 => {
                tp.at(44, r#"40:  R[7:ws speed mm/s]=R[20:ws weld mm/s]    ;"#);
                tp.r[7] = tp.r[20];
            }
            41 => tp.at(45, r#"41:  LBL[23] ;"#),
            42 => {
                tp.at(46, r#"42:  IF R[6:ws arc]=1,JMP LBL[22] ;"#);
                if r(tp, 6) == 1 {
                    next = lbl(22);
                }
            }
            43 => {
                tp.at(47, r#"43:L PR[R[2:ws pr]] R[21:ws approach mm/s]mm/sec FINE    ;"#);
                tp.linear(47, r(tp, 2) as usize, tp.r[21].value(), false);
            }
            45 => {
                tp.at(49, r#"45:  IF R[23:ws dry run]=1,JMP LBL[21] ;"#);
                if r(tp, 23) == 1 {
                    next = lbl(21);
                }
            }
            46 => {
                tp.at(50, r#"46:  Arc Start[1] ;"#);
                tp.trace.advance_stop();
                tp.trace.push(Event::ArcOn);
            }
            47 => tp.at(51, r#"47:  LBL[21] ;"#),
            48 => {
                tp.at(52, r#"48:  R[6:ws arc]=1    ;"#);
                tp.r[6] = Register::Int(1);
            }
            49 => {
                tp.at(53, r#"49:  IF R[5:ws last weld]=1,JMP LBL[24] ;"#);
                if r(tp, 5) == 1 {
                    next = lbl(24);
                }
            }
            50 => {
                tp.at(54, r#"50:  JMP LBL[1] ;"#);
                next = lbl(1);
            }
            57 => tp.at(61, r#"57:  LBL[22] ;"#),
            58 => {
                tp.at(62, r#"58:  IF R[8:ws weave mm]>0,JMP LBL[26] ;"#);
                if tp.r[8].value() > 0.0 {
                    next = lbl(26);
                }
            }
            59 => {
                tp.at(63, r#"59:  Weave End ;"#);
                tp.weave_end();
            }
            60 => {
                tp.at(64, r#"60:  JMP LBL[27] ;"#);
                next = lbl(27);
            }
            61 => tp.at(65, r#"61:  LBL[26] ;"#),
            62 => {
                tp.at(66, r#"62:  IF R[2:ws pr]=12,JMP LBL[28] ;"#);
                if r(tp, 2) == 12 {
                    next = lbl(28);
                }
            }
            63 => {
                tp.at(67, r#"63:  $WVSCH[1].$FREQUENCY=R[11:ws weave Hz] ;"#);
                tp.set_weave_schedule(1, 1, tp.r[11].value());
            }
            64 => {
                tp.at(68, r#"64:  $WVSCH[1].$AMPLITUDE=R[8:ws weave mm] ;"#);
                tp.set_weave_schedule(1, 0, tp.r[8].value());
            }
            65 => {
                tp.at(69, r#"65:  Weave Sine[1] ;"#);
                tp.weave_sine(69, 1);
            }
            66 => {
                tp.at(70, r#"66:  JMP LBL[27] ;"#);
                next = lbl(27);
            }
            67 => tp.at(71, r#"67:  LBL[28] ;"#),
            68 => {
                tp.at(72, r#"68:  $WVSCH[2].$FREQUENCY=R[11:ws weave Hz] ;"#);
                tp.set_weave_schedule(2, 1, tp.r[11].value());
            }
            69 => {
                tp.at(73, r#"69:  $WVSCH[2].$AMPLITUDE=R[8:ws weave mm] ;"#);
                tp.set_weave_schedule(2, 0, tp.r[8].value());
            }
            70 => {
                tp.at(74, r#"70:  Weave Sine[2] ;"#);
                tp.weave_sine(74, 2);
            }
            71 => tp.at(75, r#"71:  LBL[27] ;"#),
            72 => {
                tp.at(76, r#"72:  IF R[5:ws last weld]=1,JMP LBL[24] ;"#);
                if r(tp, 5) == 1 {
                    next = lbl(24);
                }
            }
            73 => {
                tp.at(77, r#"73:L PR[R[2:ws pr]] R[7:ws speed mm/s]mm/sec CNT R[22:ws blend CNT]    ;"#);
                tp.linear(77, r(tp, 2) as usize, tp.r[7].value(), r(tp, 22) > 0);
            }
            74 => {
                tp.at(78, r#"74:  JMP LBL[1] ;"#);
                next = lbl(1);
            }
            75 => tp.at(79, r#"75:  LBL[24] ;"#),
            76 => {
                tp.at(80, r#"76:L PR[R[2:ws pr]] R[7:ws speed mm/s]mm/sec FINE    ;"#);
                tp.linear(80, r(tp, 2) as usize, tp.r[7].value(), false);
            }
            77 => {
                tp.at(81, r#"77:  Weave End ;"#);
                tp.weave_end();
            }
            79 => {
                tp.at(83, r#"79:  IF R[23:ws dry run]=1,JMP LBL[25] ;"#);
                if r(tp, 23) == 1 {
                    next = lbl(25);
                }
            }
            80 => {
                tp.at(84, r#"80:  Arc End[1] ;"#);
                tp.trace.advance_stop();
                tp.trace.push(Event::ArcOff);
            }
            81 => tp.at(85, r#"81:  LBL[25] ;"#),
            82 => {
                tp.at(86, r#"82:  R[6:ws arc]=0    ;"#);
                tp.r[6] = Register::Int(0);
            }
            83 => {
                tp.at(87, r#"83:  JMP LBL[1] ;"#);
                next = lbl(1);
            }
            85 => tp.at(89, r#"85:  LBL[30] ;"#),
            86 => {
                tp.at(90, r#"86:L PR[R[2:ws pr]] R[21:ws approach mm/s]mm/sec FINE    ;"#);
                tp.linear(90, r(tp, 2) as usize, tp.r[21].value(), false);
            }
            87 => {
                tp.at(91, r#"87:  JMP LBL[1] ;"#);
                next = lbl(1);
            }
            90 => tp.at(94, r#"90:  LBL[98] ;"#),
            91 => {
                tp.at(95, r#"91:  UALM[1] ;"#);
                tp.alarms.push(1);
            }
            92 => {
                tp.at(96, r#"92:  JMP LBL[90] ;"#);
                next = lbl(90);
            }
            94 => tp.at(98, r#"94:  LBL[99] ;"#),
            95 => {
                tp.at(99, r#"95:  UALM[2] ;"#);
                tp.alarms.push(2);
            }
            96 => tp.at(100, r#"96:  LBL[90] ;"#),
            // Comment lines (`!`): nothing to run.
            _ => {}
        }
        pc = next;
    }
    tp.trace.advance_stop();
}

/// The tags of this file against the shipped TP program: every line but
/// the comments is a statement.
#[test]
fn the_transcription_follows_weld_seam_ls_line_by_line() {
    let statement = |line: &str| {
        let mut parts = line.splitn(2, ':');
        let number = parts.next().unwrap_or("");
        let body = parts.next().unwrap_or("").trim_start();
        !number.is_empty() && number.chars().all(|c| c.is_ascii_digit()) && !body.starts_with('!')
    };
    if let Err(e) = super::transcription::check(FILE, include_str!("fanuc_tp.rs"), statement) {
        panic!("{e}");
    }
}
