//! The wire protocol between the weldseam daemon, 3D cameras and robot
//! controllers. Filled in by the cell daemon work; empty until then so the
//! workspace layout is fixed from the start.
