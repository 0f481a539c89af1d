//! The integration-test binary: every suite is a module here so the crate
//! is linked once for all of them.

mod bench;
mod calibration;
mod cli;
mod consumer_camera;
mod corners;
mod daemon;
mod eval_suites;
mod faults;
mod fuzz;
mod golden;
mod hostile_clouds;
mod joints;
mod layers;
mod measured_clouds;
mod operator_page;
mod parsers;
mod peers;
mod pictures;
mod pipeline;
mod quality;
mod records;
mod requests;
mod robot_programs;
mod roi;
mod rules;
mod scenes;
mod serve_order;
mod several_seams;
mod text_link;
mod text_link_process;
mod transcript;
mod units_frames;
mod unorganized;
mod util;
mod versions;
