//! The shipped robot programs of deploy/robots/, each run statement by
//! statement on an emulation of its controller's documented primitives
//! against `weldseam serve` on loopback, through the scenarios of
//! [`harness::Scenario`].

mod abb;
mod abb_runs;
mod fanuc;
mod fanuc_tp;
mod fanuc_weave;
mod harness;
mod karel;
mod kf_scenarios;
mod krl;
mod kuka;
mod kuka_dat;
mod rapid;
mod robot;
mod transcription;
mod ur;
mod ur_runs;
mod urscript;
mod woven;
