//! The subcommands of the `weldseam` binary. This is the program's edge:
//! it reads files and flags, prints, and reports errors with anyhow context;
//! everything else lives in the library.

pub mod args;
pub mod bench;
pub mod calibrate;
pub mod camera;
pub mod controller;
pub mod demo;
pub mod errors;
pub mod eval;
pub mod eval_blocks;
pub mod eval_curved;
pub mod eval_family;
pub mod eval_groove_width;
pub mod eval_process;
pub mod eval_real;
pub mod eval_web_near_edge;
pub mod inspect;
pub mod logging;
pub mod memory;
pub mod plan;
pub mod plan_json;
pub mod records;
pub mod rules;
pub mod serve;
pub mod simulate;
pub mod simulate_calibration;
pub mod table;
