//! The shipped robot programs of `deploy/robots/`, run statement by
//! statement on emulations of their controllers' documented primitives
//! against the daemon on loopback.

mod fanuc;
mod fanuc_tp;
mod karel;
mod kf_scenarios;
mod krl;
mod kuka;
mod listing;
mod robot;
