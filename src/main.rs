//! The `weldseam` command line: plan a weld from a file, simulate a scan,
//! run the cell daemon and its mock camera and controller,
//! evaluate accuracy, run the demo, calibrate the hand-eye.

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
    /// Show what the planner sees in a cloud file: organization, units, depth, frame, intrinsics, spacing.
    Inspect(cli::inspect::InspectArgs),
    /// Plan the seeded suite of simulated scenes and print the accuracy table.
    Eval(cli::eval::EvalArgs),
    /// Render a simulated camera frame (organized PCD, or a variant as PCD or PLY) and its ground truth (JSON).
    Simulate(cli::simulate::SimulateArgs),
    /// Hand-eye calibration: solve End_T_Camera (AX = XB) from robot poses and target poses or sphere clouds.
    Calibrate(cli::calibrate::CalibrateArgs),
    /// Run the cell daemon: camera and controller links over TCP.
    Serve(cli::serve::ServeArgs),
    /// A mock camera: send point-cloud files or simulated scenes to the daemon.
    Camera(cli::camera::CameraArgs),
    /// A mock robot controller: request one trajectory (or ping) and print the reply.
    Controller(cli::controller::ControllerArgs),
    /// Measure the planner on simulated frames and print the performance tables.
    Bench(cli::bench::BenchArgs),
    /// The planner's rules: every one, one by id in full, or docs/RULES.md's text.
    Rules(cli::rules::RulesArgs),
    /// The daemon's plan records: list them, or export one's frame (PCD) and request and answer (JSON).
    Records(cli::records::RecordsArgs),
    /// Plan a recorded frame again with its request and configuration; exit 1 if the plan changed.
    Replay(cli::records::ReplayArgs),
}

impl Command {
    /// The commands that plan (or send) frame after frame, whose next frame
    /// reuses the buffers the last one freed (`cli::memory`). A one-shot
    /// command has no next frame: kept memory would only raise its peak.
    fn plans_frame_after_frame(&self) -> bool {
        match self {
            Command::Demo(_) | Command::Eval(_) | Command::Serve(_) | Command::Camera(_) | Command::Bench(_) => true,
            Command::Plan(_)
            | Command::Inspect(_)
            | Command::Simulate(_)
            | Command::Controller(_)
            | Command::Calibrate(_)
            | Command::Rules(_)
            | Command::Records(_)
            | Command::Replay(_) => false,
        }
    }

    /// The long-running services log what they do; one-shot commands only
    /// what goes wrong.
    fn log_level(&self) -> &'static str {
        match self {
            Command::Demo(_)
            | Command::Plan(_)
            | Command::Eval(_)
            | Command::Inspect(_)
            | Command::Simulate(_)
            | Command::Controller(_)
            | Command::Calibrate(_)
            | Command::Bench(_)
            | Command::Rules(_)
            | Command::Records(_)
            | Command::Replay(_) => "warn",
            Command::Serve(_) | Command::Camera(_) => "info",
        }
    }
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    if cli.command.plans_frame_after_frame() {
        cli::memory::keep_freed_memory();
    }
    if let Err(e) = logging::init(cli.log_format, cli.command.log_level()) {
        eprintln!("error: {e:#}");
        return std::process::ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Demo(args) => cli::demo::run(args),
        Command::Plan(args) => cli::plan::run(args),
        Command::Eval(args) => cli::eval::run(args),
        Command::Inspect(args) => cli::inspect::run(args),
        Command::Simulate(args) => cli::simulate::run(args),
        Command::Calibrate(args) => cli::calibrate::run(args),
        Command::Serve(args) => cli::serve::run(args),
        Command::Camera(args) => cli::camera::run(args),
        Command::Controller(args) => cli::controller::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Rules(args) => cli::rules::run(args),
        Command::Records(args) => cli::records::run(args),
        Command::Replay(args) => cli::records::replay(args),
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

#[cfg(test)]
mod tests {
    use clap::Parser;
    use clap::error::ErrorKind;
    use weldseam::config::Method;

    use super::{Cli, Command};

    const POSE: &str = "--pose=-613.5,-284.8,296.3,178.3,1.0,-107.1";

    fn parse(args: &[&str]) -> Result<Command, clap::Error> {
        Cli::try_parse_from(std::iter::once("weldseam").chain(args.iter().copied())).map(|c| c.command)
    }

    #[test]
    fn an_unknown_method_is_refused_by_every_subcommand_that_takes_one() {
        for args in [
            &["plan", "--cloud", "a.pcd", "--joint", "lap", POSE, "--method", "fast"][..],
            &["serve", "--method", "fast"][..],
        ] {
            let e = parse(args).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::InvalidValue, "{args:?}: {e}");
            assert!(e.to_string().contains("robust") && e.to_string().contains("paper"), "{e}");
        }
    }

    #[test]
    fn the_method_flag_overrides_the_config_in_plan_and_serve() {
        let Command::Serve(serve) = parse(&["serve", "--method", "paper"]).unwrap() else { panic!("not serve") };
        assert_eq!(serve.config.load().unwrap().pipeline.method, Method::Paper);
        let plan = ["plan", "--cloud", "a.pcd", "--joint", "lap", POSE, "--method", "paper"];
        let Command::Plan(plan) = parse(&plan).unwrap() else { panic!("not plan") };
        assert_eq!(plan.config.load().unwrap().pipeline.method, Method::Paper);
        let Command::Serve(serve) = parse(&["serve"]).unwrap() else { panic!("not serve") };
        assert_eq!(serve.config.load().unwrap().pipeline.method, Method::Robust);
    }

    #[test]
    fn plan_and_controller_take_the_same_request_flags() {
        let flags = ["--step", "2.5", "--work-angle", "-10", "--travel-angle", "15", "--groove-depth", "3"];
        let plan: Vec<&str> =
            ["plan", "--cloud", "a.pcd", "--joint", "v-butt", POSE].into_iter().chain(flags).collect();
        let controller: Vec<&str> = ["controller", "--joint", "v-butt", POSE].into_iter().chain(flags).collect();
        let Command::Plan(plan) = parse(&plan).unwrap() else { panic!("not plan") };
        let Command::Controller(controller) = parse(&controller).unwrap() else { panic!("not controller") };
        for r in [&plan.request, &controller.request] {
            assert_eq!(
                (r.step, r.work_angle, r.travel_angle, r.groove_depth),
                (Some(2.5), Some(-10.0), Some(15.0), Some(3.0))
            );
        }
        // One parser for the hand-eye in both: it counts the numbers.
        for sub in [&["plan", "--cloud", "a.pcd", "--joint", "lap", POSE][..], &["controller", "--ping"][..]] {
            let args: Vec<&str> = sub.iter().copied().chain(["--hand-eye", "1,0,0"]).collect();
            let e = parse(&args).unwrap_err().to_string();
            assert!(e.contains("needs 16"), "{sub:?}: {e}");
        }
    }
}
