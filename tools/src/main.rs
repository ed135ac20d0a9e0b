//! `beamfield`: the host command-line tool. Run `beamfield --help`.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Host tools for beamfield: build distance-field blobs from maps, read logs, score scans,
/// fit and calibrate the sensor models that run on the microcontroller.
#[derive(Parser)]
#[command(name = "beamfield", version, about, long_about = None)]
struct Cli {
    /// Print machine-readable JSON instead of text.
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the tool's version and the crate's build configuration.
    Info,
    /// Distance-field blobs for the likelihood field: build one from a ROS map, query it,
    /// render it as a picture.
    Field(beamfield_tools::field_cmd::FieldArgs),
    /// Fit the beam model's intrinsics (EM) to a CARMEN log, z* ray cast through a blob.
    Fit(beamfield_tools::beam_fit::FitArgs),
    /// Ultrasonic ring tools (firing schedules and crosstalk).
    #[command(subcommand)]
    Sonar(beamfield_tools::sonar::SonarCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Info => {
            let version = env!("CARGO_PKG_VERSION");
            if cli.json {
                println!("{}", serde_json::json!({ "version": version }));
            } else {
                println!("beamfield {version}");
            }
            ExitCode::SUCCESS
        }
        Command::Field(args) => match beamfield_tools::field_cmd::run(args, cli.json) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("beamfield field: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Fit(args) => match beamfield_tools::beam_fit::run(&args, cli.json) {
            Ok(out) => {
                println!("{out}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("beamfield fit: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Sonar(cmd) => match beamfield_tools::sonar::run(&cmd, cli.json) {
            Ok(out) => {
                println!("{out}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("beamfield sonar: {e}");
                ExitCode::FAILURE
            }
        },
    }
}
