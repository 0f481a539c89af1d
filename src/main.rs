//! The `weldseam` command line: plan a weld from a file, simulate a scan,
//! run the cell daemon and its mock camera and controller,
//! evaluate accuracy, run the demo.

mod cli;

use clap::{Parser, Subcommand};

use cli::logging::{self, LogFormat};

#[derive(Debug, Parser)]
#[command(name = "weldseam", version, about = "Teach-free plane weld trajectory planning from 3D camera point clouds")]
struct Cli {
    /// Log line format on stderr.
    #[arg(long, global = true, value_enum, default_value_t = LogFormat::Text)]
    log_format: LogFormat,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the whole cell over loopback: daemon, mock camera and mock controller plan a simulated scene of each joint.
    Demo(cli::demo::DemoArgs),
    /// Plan the welding trajectory of one point-cloud file.
    Plan(cli::plan::PlanArgs),
    /// Plan the seeded suite of simulated scenes and print the accuracy table.
    Eval(cli::eval::EvalArgs),
    /// Render a simulated camera frame (organized PCD) and its ground truth (JSON).
    Simulate(cli::simulate::SimulateArgs),
    /// Run the cell daemon: camera and controller links over TCP.
    Serve(cli::serve::ServeArgs),
    /// A mock camera: send point-cloud files or simulated scenes to the daemon.
    Camera(cli::camera::CameraArgs),
    /// A mock robot controller: request one trajectory (or ping) and print the reply.
    Controller(cli::controller::ControllerArgs),
    /// Measure the planner on simulated frames and print the performance tables.
    Bench(cli::bench::BenchArgs),
}

fn main() -> std::process::ExitCode {
    cli::memory::keep_freed_memory();
    let cli = Cli::parse();
    let level = match cli.command {
        Command::Demo(_)
        | Command::Plan(_)
        | Command::Eval(_)
        | Command::Simulate(_)
        | Command::Controller(_)
        | Command::Bench(_) => "warn",
        Command::Serve(_) | Command::Camera(_) => "info",
    };
    if let Err(e) = logging::init(cli.log_format, level) {
        eprintln!("error: {e:#}");
        return std::process::ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Demo(args) => cli::demo::run(args),
        Command::Plan(args) => cli::plan::run(args),
        Command::Eval(args) => cli::eval::run(args),
        Command::Simulate(args) => cli::simulate::run(args),
        Command::Serve(args) => cli::serve::run(args),
        Command::Camera(args) => cli::camera::run(args),
        Command::Controller(args) => cli::controller::run(args),
        Command::Bench(args) => cli::bench::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // A reader that stops early (`| head`) is not an error of ours.
        Err(e) if is_broken_pipe(&e) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", cli::errors::render(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}
