//! weldseam: teach-free plane weld trajectory planning from the point
//! clouds of an eye-in-hand structured-light camera.
//!
//! The library turns a camera-frame point cloud and the robot pose at
//! capture into base-frame welding waypoints for plane V-butt, I-butt and
//! lap joints, after the method of "A point cloud-based welding trajectory
//! planning method for plane welds", made robust where the method as
//! written breaks, and for the fillet roots of tees and inside corners,
//! which the method does not plan. Every refusal names the rule that made
//! it ([`rules`]). See docs/ARCHITECTURE.md for the code map.

pub mod calibration;
pub mod camera;
pub mod cloud;
pub mod config;
pub mod convert;
pub mod debug_dir;
pub mod eval;
pub mod geometry;
pub mod joint;
pub(crate) mod kernels;
pub mod mock;
pub mod pipeline;
pub mod process;
pub mod records;
pub mod report;
pub mod rules;
pub mod server;
pub mod sim;
