//! The `weldseam` command line.

fn main() {}
