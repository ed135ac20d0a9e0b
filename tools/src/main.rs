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
    /// Print the tool's version and the build configuration: the beamfield library's version and
    /// features, its trigonometry backend, the blob format version, the build profile and the
    /// target.
    Info,
    /// Distance-field blobs for the likelihood field: build one from a ROS map, query it,
    /// render it as a picture.
    Field(beamfield_tools::field_cmd::FieldArgs),
    /// Log-likelihood of one scan of a CARMEN log at a pose (likelihood field over a blob),
    /// optionally a score surface around it (--grid: CSV and PNG).
    Score(beamfield_tools::score_cmd::ScoreArgs),
    /// The smallest tempering κ whose credible sets over a local pose grid hold the logged
    /// poses at the requested rate; coverage at κ = 1 and at κ, and a coverage-vs-κ PNG.
    Calibrate(beamfield_tools::score_cmd::CalibrateArgs),
    /// Monte Carlo localization over a whole CARMEN log against its logged poses (odometry
    /// synthesized from them with the motion model's noise): tracking error, global
    /// localization, kidnapping; a PNG of the tracks over the map.
    Track(beamfield_tools::track::TrackArgs),
    /// Fit the beam model's intrinsics (EM) to a CARMEN log, z* ray cast through a blob.
    Fit(beamfield_tools::beam_fit::FitArgs),
    /// Ultrasonic ring tools (firing schedules and crosstalk).
    #[command(subcommand)]
    Sonar(beamfield_tools::sonar::SonarCommand),
    /// Build maps: `map from-log` turns a CARMEN laser log with known poses into a ROS
    /// map_server map (YAML + PGM).
    Map {
        #[command(subcommand)]
        command: beamfield_tools::carmen_cli::MapCommand,
    },
    /// Inspect laser logs: `log info` summarizes a CARMEN log (scans, beams, max-range value,
    /// pose extent, malformed lines).
    Log {
        #[command(subcommand)]
        command: beamfield_tools::carmen_cli::LogCommand,
    },
    /// LiDAR byte streams: `lidar encode` writes a CARMEN log's scans as an LD06, RPLIDAR or
    /// XV-11 stream; `lidar decode` decodes a stream into scans and counters.
    #[command(subcommand)]
    Lidar(beamfield_tools::lidar_cmd::LidarCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Info => {
            println!("{}", beamfield_tools::cmd::info::render(cli.json));
            ExitCode::SUCCESS
        }
        Command::Field(args) => match beamfield_tools::field_cmd::run(args, cli.json) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("beamfield field: {e}");
                ExitCode::FAILURE
            }
        },
        Command::Score(args) => print_or_fail(
            "score",
            beamfield_tools::score_cmd::run_score(&args, cli.json),
        ),
        Command::Calibrate(args) => print_or_fail(
            "calibrate",
            beamfield_tools::score_cmd::run_calibrate(&args, cli.json),
        ),
        Command::Track(args) => match beamfield_tools::track::run(&args, cli.json) {
            Ok(out) => {
                println!("{out}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("beamfield track: {e}");
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
        Command::Map { command } => beamfield_tools::carmen_cli::run_map(command, cli.json),
        Command::Log { command } => beamfield_tools::carmen_cli::run_log(command, cli.json),
        Command::Lidar(cmd) => match beamfield_tools::lidar_cmd::run(&cmd, cli.json) {
            Ok(out) => {
                println!("{out}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("beamfield lidar: {e}");
                ExitCode::FAILURE
            }
        },
    }
}

fn print_or_fail(
    name: &str,
    r: Result<String, beamfield_tools::score_cmd::ScoreCmdError>,
) -> ExitCode {
    match r {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("beamfield {name}: {e}");
            ExitCode::FAILURE
        }
    }
}
