//! The `weldseam` command line.

mod cli;

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

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Simulate(args) => cli::simulate::run(&args),
    }
}
