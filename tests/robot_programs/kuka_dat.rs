//! `deploy/robots/kuka/WeldSeam.dat`, the data list of WeldSeam.src,
//! transcribed line by line: the arrays the plan is stored in and the
//! result the program branches on.

use super::krl::{E6Pos, Krl};

/// The data list `WeldSeam.dat`.
pub struct DataList {
    pub ws_max_lines: i32,
    pub ws_path: Vec<E6Pos>,
    pub ws_kind: Vec<i32>,
    pub ws_seam: Vec<i32>,
    pub ws_speed: Vec<f32>,
    pub ws_weave_amp: Vec<f32>,
    pub ws_weave_freq: Vec<f32>,
    pub ws_result: i32,
}

pub fn data_list(d: &mut Krl) -> DataList {
    d.at(1, r#"&ACCESS RVP"#);
    d.at(2, r#"DEFDAT WeldSeam"#);
    d.at(7, r#"DECL CONST INT WS_MAX_LINES = 2000"#);
    d.at(8, r#"DECL E6POS WsPath[2000]"#);
    d.at(9, r#"DECL INT WsKind[2000]"#);
    d.at(10, r#"DECL INT WsSeam[2000]"#);
    d.at(14, r#"DECL REAL WsSpeed[2000]"#);
    d.at(15, r#"DECL REAL WsWeaveAmp[2000]"#);
    d.at(16, r#"DECL REAL WsWeaveFreq[2000]"#);
    d.at(20, r#"DECL INT WsResult = 0"#);
    // KRL arrays count from 1: element 0 is never used.
    DataList {
        ws_max_lines: 2000,
        ws_path: vec![E6Pos::default(); 2001],
        ws_kind: vec![0; 2001],
        ws_seam: vec![0; 2001],
        ws_speed: vec![0.0; 2001],
        ws_weave_amp: vec![0.0; 2001],
        ws_weave_freq: vec![0.0; 2001],
        ws_result: 0,
    }
}

/// The tags of this file against the shipped data list.
#[test]
fn the_transcription_follows_weld_seam_dat_line_by_line() {
    let statement = |line: &str| !line.is_empty() && !line.starts_with(';') && !super::robot::is_closer(line);
    if let Err(e) = super::transcription::check("kuka/WeldSeam.dat", include_str!("kuka_dat.rs"), statement) {
        panic!("{e}");
    }
}
