//! The `weldseam` command line.

mod cli;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(
    name = "weldseam",
    version,
    about = "Plane weld trajectory planning from point clouds"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a simulated camera frame and its ground truth.
    Simulate(cli::simulate::SimulateArgs),
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Simulate(args) => cli::simulate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // One line with the whole cause chain, as users of a command
            // expect, rather than a debug dump.
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
