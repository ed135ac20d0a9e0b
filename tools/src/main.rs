//! `beamfield`: the host command-line tool. Run `beamfield --help`.

use clap::{Parser, Subcommand};
use serde::Serialize;
use std::fmt::Display;
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
    Field(beamfield_tools::cmd::field::FieldArgs),
    /// Log-likelihood of one scan of a CARMEN log at a pose (likelihood field over a blob),
    /// optionally a score surface around it (--grid: CSV and PNG).
    Score(beamfield_tools::cmd::score::ScoreArgs),
    /// The smallest tempering κ whose credible sets over a local pose grid hold the logged
    /// poses at the requested rate; coverage at κ = 1 and at κ, and a coverage-vs-κ PNG.
    Calibrate(beamfield_tools::cmd::calibrate::CalibrateArgs),
    /// Monte Carlo localization over a whole CARMEN log against its logged poses (odometry
    /// synthesized from them with the motion model's noise): tracking error, global
    /// localization, kidnapping; a PNG of the tracks over the map.
    Track(Box<beamfield_tools::cmd::track::TrackArgs>),
    /// Fit the beam model's intrinsics (EM) to a CARMEN log, z* ray cast through a blob.
    Fit(beamfield_tools::cmd::fit::FitArgs),
    /// Ultrasonic ring tools (firing schedules and crosstalk).
    #[command(subcommand)]
    Sonar(beamfield_tools::cmd::sonar::SonarCommand),
    /// Build maps: `map from-log` turns a CARMEN laser log with known poses into a ROS
    /// map_server map (YAML + PGM).
    Map {
        #[command(subcommand)]
        command: beamfield_tools::cmd::map::MapCommand,
    },
    /// Inspect laser logs: `log info` summarizes a CARMEN log (scans, beams, max-range value,
    /// pose extent, malformed lines).
    Log {
        #[command(subcommand)]
        command: beamfield_tools::cmd::log::LogCommand,
    },
    /// LiDAR byte streams: `lidar encode` writes a CARMEN log's scans as an LD06, RPLIDAR or
    /// XV-11 stream; `lidar decode` decodes a stream into scans and counters.
    #[command(subcommand)]
    Lidar(beamfield_tools::cmd::lidar::LidarCommand),
    /// The device's link to ROS 2, as nav2_amcl speaks it: estimates on amcl_pose, the
    /// map → odom transform on /tf, initialpose and nav2_amcl's services to the device
    /// (docs/nav2.md).
    #[cfg(feature = "bridge")]
    Bridge(beamfield_bridge::BridgeArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        #[cfg(feature = "bridge")]
        Command::Bridge(args) => bridge(&args, cli.json),
        Command::Info => finish(
            "beamfield info",
            Ok::<_, std::convert::Infallible>(beamfield_tools::cmd::info::run()),
            cli.json,
        ),
        Command::Field(args) => {
            let r = beamfield_tools::cmd::field::run(args, cli.json);
            match &r {
                Ok(report) if report.streamed() => ExitCode::SUCCESS,
                _ => finish("beamfield field", r, cli.json),
            }
        }
        Command::Score(args) => finish(
            "beamfield score",
            beamfield_tools::cmd::score::run(&args),
            cli.json,
        ),
        Command::Calibrate(args) => finish(
            "beamfield calibrate",
            beamfield_tools::cmd::calibrate::run(&args),
            cli.json,
        ),
        Command::Track(args) => {
            let r = beamfield_tools::cmd::track::run(&args);
            let lost = r.as_ref().ok().and_then(|t| t.lost_line());
            let code = finish("beamfield track", r, cli.json);
            match lost {
                Some(line) if code == ExitCode::SUCCESS => {
                    eprintln!("beamfield track: {line}");
                    if args.bag.is_some() {
                        ExitCode::from(beamfield_tools::cmd::track::EXIT_LOST)
                    } else {
                        code
                    }
                }
                _ => code,
            }
        }
        Command::Fit(args) => finish(
            "beamfield fit",
            beamfield_tools::cmd::fit::run(&args),
            cli.json,
        ),
        Command::Sonar(cmd) => finish(
            "beamfield sonar",
            beamfield_tools::cmd::sonar::run(&cmd),
            cli.json,
        ),
        Command::Map { command } => finish(
            "error",
            beamfield_tools::cmd::map::run_map(&command),
            cli.json,
        ),
        Command::Log { command } => finish(
            "error",
            beamfield_tools::cmd::log::run_log(&command),
            cli.json,
        ),
        Command::Lidar(cmd) => finish(
            "beamfield lidar",
            beamfield_tools::cmd::lidar::run(&cmd),
            cli.json,
        ),
    }
}

/// `beamfield bridge`: its report as every command's, and its own exit codes (docs/nav2.md,
/// "Exit codes and the report's counters"): 0 stopped as asked (`--seconds`, a lifecycle
/// shutdown, SIGINT or SIGTERM), 1 could not start, 2 usage error, 3 link lost; 130 or 143 when
/// a second SIGINT or SIGTERM ends it during its stop.
#[cfg(feature = "bridge")]
fn bridge(args: &beamfield_bridge::BridgeArgs, json: bool) -> ExitCode {
    // SIGINT and SIGTERM stop it with its report (exit code 0); a second one exits at once.
    let stop = match beamfield_bridge::stop::Stop::on_signals() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("beamfield bridge: {e}");
            return ExitCode::from(beamfield_bridge::EXIT_CANNOT_START);
        }
    };
    match beamfield_bridge::run_until(args, &stop) {
        Ok(report) => {
            let code = report.exit_code();
            if finish("beamfield bridge", Ok::<_, String>(report), json) == ExitCode::SUCCESS {
                ExitCode::from(code)
            } else {
                ExitCode::from(beamfield_bridge::EXIT_CANNOT_START)
            }
        }
        Err(e) => {
            eprintln!("beamfield bridge: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Prints a command's report once, as JSON (`--json`: keys in sorted order, as every report
/// has always printed them) or as text, and returns success; or prints the error on stderr
/// after `prefix` and returns failure.
fn finish<R: Serialize + Display, E: Display>(
    prefix: &str,
    r: Result<R, E>,
    json: bool,
) -> ExitCode {
    match r {
        Ok(report) => {
            if json {
                match serde_json::to_value(&report) {
                    Ok(v) => println!("{v}"),
                    Err(e) => {
                        eprintln!("{prefix}: the report cannot be written as JSON: {e}");
                        return ExitCode::FAILURE;
                    }
                }
            } else {
                println!("{report}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{prefix}: {e}");
            ExitCode::FAILURE
        }
    }
}
