//! The subcommands of the `weldseam` command line, one module each.

pub mod simulate;
