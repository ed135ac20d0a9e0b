//! `cargo xtask`: project tasks that need more than `cargo test`: the firmware under QEMU,
//! instruction counts, cross builds. Run `cargo xtask --help`.
//!
//! This file is the command line only. The rooms: [`process`] (running commands),
//! [`toolchain`] (rustup targets, LLVM tools, gcc), [`qemu`] (boards and QEMU runs),
//! [`insncount`] (the counting plugin and the named regions), [`cross`] (firmware and
//! cross builds), [`elf`] (sections, symbols, memory layouts), [`error`] (the one error type),
//! [`report`] (the data the firmware programs send: link frames and test reports, decoded),
//! and one module per task.

mod budget_run;
mod budgets;
mod cases;
mod cross;
mod demo;
mod demo_f64;
mod demo_ref;
mod elf;
mod error;
mod insncount;
mod insns;
mod lidar;
mod lidar_ref;
mod nopanic;
mod process;
mod qemu;
mod report;
mod robot;
mod ros2;
mod toolchain;
mod track;
mod willow;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Project tasks for beamfield (firmware under QEMU, instruction counts, cross builds).
///
/// The firmware lives in `firmware/` (its own package and lockfile, excluded from the
/// workspace). QEMU is `qemu-system-arm` on the `mps2-an386` board (Cortex-M4 with FPU); its
/// output is written to files, never to a pipe, and every run is under a 120 s timeout.
#[derive(Parser)]
#[command(name = "cargo xtask", about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Task,
}

#[derive(Subcommand)]
enum Task {
    /// Build a firmware program (default: the reference check) and run it under QEMU.
    ///
    /// Installs the rustup target thumbv7em-none-eabihf if it is missing; says how to install
    /// qemu-system-arm if that is missing. Prints the program's semihosting output and exits
    /// with its status (0: every case within tolerance).
    Qemu {
        /// Which program of firmware/src/bin to run.
        #[arg(long, default_value = "check")]
        bin: String,
        /// QEMU machine (mps2-an386: Cortex-M4F; mps2-an500: Cortex-M7).
        #[arg(long, default_value = "mps2-an386")]
        machine: String,
        /// Build with the dev profile instead of release.
        #[arg(long)]
        debug: bool,
    },
    /// Count guest instructions per beam of the beam mixture and of the likelihood field
    /// (prepared and per-pose paths, real map and scans), with baselines, under QEMU.
    ///
    /// Builds firmware/src/bin/insns.rs (release) and runs it with the repository's counting
    /// plugin (xtask/insncount/, built with gcc on first use; llvm-nm from `rustup component
    /// add llvm-tools` is installed if missing). Counts are exact and repeat run to run;
    /// they are instructions, not cycles.
    Insns {
        /// QEMU machine.
        #[arg(long, default_value = "mps2-an386")]
        machine: String,
    },
    /// Build the library for every bare-metal target, without and with each feature and with
    /// all of them; then link the firmware with each optional feature (proof: no allocator).
    Cross,
    /// Run the pose-scoring demo (firmware/src/bin/demo.rs) under QEMU and print its report.
    ///
    /// Installs the rustup target if missing; says how to install qemu-system-arm if missing.
    /// Reports, per embedded real scan, whether the best pose is within 5 cm and 1° of the
    /// logged pose (counted, not enforced); exits non-zero only if the device could not score
    /// a scan or normalize its weights, or QEMU failed.
    Demo {
        /// Board (QEMU machine and memory layout).
        #[arg(long, value_enum, default_value = "mps2-an386")]
        board: qemu::Board,
        /// How the Intel field is linked: raw (one byte per cell) or tiled (the same codes in
        /// deduplicated 4 × 4 tiles, checked against the host's run on the raw field).
        #[arg(long, value_enum, default_value = "raw")]
        encoding: demo::DemoEncoding,
    },
    /// The Willow Garage map (1.10 MB raw, more than an STM32F405's flash) linked tiled with the
    /// STM32F405 layout, run on QEMU's netduinoplus2: a scan cast through it and scored at 125
    /// poses, every score compared bit for bit with the host's.
    Willow,
    /// Track a real Intel log segment with the localizer on the device
    /// (firmware/src/bin/track.rs: 90 scans, 500 particles) under QEMU, recompute the same track
    /// on the host with the same library code, and fail on any difference in the reported
    /// values (the device's Estimate frames and track reports, decoded, bit for bit), or when
    /// the tracking RMSE is over its bound.
    ///
    /// The input is fixtures/assets/track.rs (`cargo xtask track-assets`; a host test checks it
    /// is current).
    Track {
        /// Board (QEMU machine and memory layout).
        #[arg(long, value_enum, default_value = "mps2-an386")]
        board: qemu::Board,
        /// Run under QEMU's counting plugin instead (xtask/insncount; needs gcc and
        /// llvm-tools) and print the instructions per particle per update, scoring included
        /// and excluded, and the program's RAM; the bit-equality check still runs.
        #[arg(long)]
        insns: bool,
    },
    /// Regenerate fixtures/assets/track.rs (the track's scans, logged poses and synthesized
    /// odometry) from the Intel log in data/.
    TrackAssets,
    /// Budgets of the scoring core against the demo's targets, as a table: .text/.rodata/.bss
    /// (size_core minus size_skeleton), stack high-water marks (painted stack), instructions
    /// per pose and per beam (QEMU counting plugin), no heap, fits the STM32F405 layout.
    ///
    /// Exits non-zero only when a hard requirement fails (a heap, an image that does not fit);
    /// targets not met yet are printed as OVER.
    Budgets {
        /// QEMU machine for the instruction counts and the stack.
        #[arg(long, default_value = "mps2-an386")]
        machine: String,
        /// Firmware features to build with (e.g. `micromath`: micromath's sin/cos).
        #[arg(long)]
        features: Option<String>,
    },
    /// Link-time proof that the scoring core cannot panic: builds size_core (release, LTO)
    /// with a panic handler that calls an undefined function; it must link.
    Nopanic {
        /// Instead, add a deliberate panicking index and check that the link then FAILS on the
        /// undefined symbol (the proof can fail).
        #[arg(long)]
        show_failure: bool,
    },
    /// The sensor path through an emulated peripheral: stream bytes into USART1 of QEMU's
    /// netduinoplus2 (STM32F405) and check what the firmware (firmware/src/bin/lidar_uart.rs)
    /// reports.
    ///
    /// The stream is 24 consecutive real Intel-lab scans written as LD06 frames by the
    /// library's encoder,
    /// with line noise and 3 corrupted frames. Builds the program for the STM32F405 layout,
    /// starts QEMU with USART1 on a Unix socket, waits for the firmware's ready line, sends the
    /// stream, and checks the device's reports (data lines, decoded): every byte received in
    /// order (count and CRC-32); the host's recomputation (decode, assembly, scores, counters)
    /// within the readable line's last digit, integers exactly; what the
    /// stream's plan says (frames rejected, beams missing, none wrong, best poses near the
    /// logged ones); and prints the instructions per received byte of decode + assembly (QEMU
    /// counting plugin, needs gcc and llvm-nm).
    Lidar {
        /// Skip the instruction count (no gcc needed).
        #[arg(long)]
        no_count: bool,
        /// Also count the LD06 decoder alone (firmware feature `decode-split`; the extra pass
        /// changes what is inlined into the main path, so its figure differs a little).
        #[arg(long, conflicts_with = "no_count")]
        split: bool,
    },
    /// The ROS 2 bridge against a ROS 2 peer nobody here wrote, on 127.0.0.1 only: the robot
    /// application in QEMU (`robot --bridge-port`), `beamfield bridge` on its link, and
    /// host-tests/python/ros2_peer.py (PyPI cyclonedds) receiving amcl_pose and /tf, sending
    /// initialpose (a good one, then a NaN one) and calling request_nomotion_update.
    Ros2 {
        /// Scans of the Intel log to send.
        #[arg(long, value_name = "N", default_value_t = 300)]
        scans: usize,
    },
    /// Regenerate the demo assets from the Intel log in data/: the map blobs (firmware/assets/)
    /// and the scans (fixtures/assets/).
    /// The robot application on the STM32F405 (QEMU `netduinoplus2`): the Intel lab log sent
    /// as an LD06 stream at 10 Hz into USART1 and 50 Hz wheel-encoder odometry of an imperfect
    /// differential drive (and commands, and bad input) into USART2; the estimates read back
    /// from USART3, recomputed on the host bit for bit, and compared with the logged poses.
    Robot {
        /// Send only the log's first N scans (all 910 by default).
        #[arg(long, value_name = "N")]
        scans: Option<usize>,
        /// No kidnap: no global localization and no second initial pose.
        #[arg(long)]
        no_kidnap: bool,
        /// Count the instructions of every stage: the time budget of a revolution.
        #[arg(long)]
        count: bool,
        /// Count the receive interrupt handlers instead (their longest path).
        #[arg(long, conflicts_with = "count")]
        isr: bool,
        /// Send a ROS 2 bag (an .mcap file or a rosbag2 directory) instead of the Intel log:
        /// its scans as LD06 revolutions, its odometry as WheelOdometry, compared with
        /// --reference-topic (the firmware's field is the Intel lab's: a bag of that building).
        #[arg(long, value_name = "BAG", requires = "reference_topic")]
        bag: Option<PathBuf>,
        /// The bag's LaserScan topic.
        #[arg(long, default_value = "/scan")]
        scan_topic: String,
        /// The bag's Odometry topic.
        #[arg(long, default_value = "/odom")]
        odom_topic: String,
        /// The bag's reference pose topic (PoseWithCovarianceStamped or PoseStamped).
        #[arg(long)]
        reference_topic: Option<String>,
        /// Offer the device's link on 127.0.0.1:PORT to `beamfield bridge --connect`: its
        /// output is forwarded there, the bridge's frames go into USART2 (paced by the device).
        #[arg(long, value_name = "PORT", conflicts_with = "host_only")]
        bridge_port: Option<u16>,
        /// Only the host: the streams, the replay and its accuracy, without QEMU.
        #[arg(long, conflicts_with_all = ["count", "isr"])]
        host_only: bool,
        /// Board: netduinoplus2 (STM32F405) or b-l475e-iot01a (STM32L475 at 80 MHz).
        #[arg(long, value_enum, default_value = "netduinoplus2")]
        board: qemu::Board,
    },
    DemoAssets,
    /// Regenerate firmware/src/reference_cases.rs from the host's f64 reference.
    Refcases {
        /// Only check that the checked-in file is up to date (exit 1 if not).
        #[arg(long)]
        check: bool,
    },
    /// Regenerate firmware/src/model_cases.rs (the models program's cases) from the host.
    Modelcases {
        /// Only check that the checked-in file is up to date (exit 1 if not).
        #[arg(long)]
        check: bool,
    },
    /// Run a firmware image under QEMU with the counting plugin (xtask/insncount, built with
    /// gcc on first use) and print the instructions of every region between its
    /// `bench_mark_start` and `bench_mark_end` calls. Fails if it reports no region or exits
    /// non-zero.
    Count {
        /// The firmware ELF (e.g. firmware/target/thumbv6m-none-eabi/release/fixed_m0).
        elf: PathBuf,
        /// QEMU machine (mps2-an386, netduinoplus2, lm3s6965evb, microbit, ...).
        #[arg(long, default_value = "mps2-an386")]
        machine: String,
    },
    /// The firmware part of CI: refcases --check, modelcases --check, cross, qemu (check and
    /// models), insns, budgets, nopanic (and nopanic --show-failure).
    Ci,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Task::Qemu {
            bin,
            machine,
            debug,
        } => qemu::qemu(&bin, &machine, !debug),
        Task::Insns { machine } => insns::insns(&machine),
        Task::Count { elf, machine } => insncount::count(&elf, &machine),
        Task::Cross => cross::cross(),
        Task::Demo { board, encoding } => demo::demo(board, encoding),
        Task::Willow => willow::willow(),
        Task::Budgets { machine, features } => budgets::budgets(&machine, features.as_deref()),
        Task::Nopanic { show_failure } => nopanic::nopanic(show_failure),
        Task::Lidar { no_count, split } => lidar::lidar(!no_count, split),
        Task::Robot {
            scans,
            no_kidnap,
            count,
            isr,
            host_only,
            bridge_port,
            bag,
            scan_topic,
            odom_topic,
            reference_topic,
            board,
        } => bridge_port
            .map(robot::bridge::listen)
            .transpose()
            .and_then(|listener| {
                robot::robot(
                    robot::Options {
                        scans,
                        no_kidnap,
                        count,
                        isr,
                        host_only,
                        bridge: listener.is_some(),
                        board,
                        bag: bag.map(|path| robot::BagInput {
                            path,
                            topics: beamfield_bag::Topics {
                                scan: scan_topic,
                                odom: odom_topic,
                                reference: reference_topic,
                                ..beamfield_bag::Topics::default()
                            },
                        }),
                    },
                    listener.as_ref(),
                )
            }),
        Task::Ros2 { scans } => ros2::ros2(scans),
        Task::DemoAssets => demo::demo_assets(),
        Task::Track { board, insns } => {
            if insns {
                track::track_insns(board)
            } else {
                track::track(board)
            }
        }
        Task::TrackAssets => track::track_assets(),
        Task::Refcases { check } => cases::refcases(check),
        Task::Modelcases { check } => cases::modelcases(check),
        Task::Ci => cases::refcases(true)
            .and_then(|()| cases::modelcases(true))
            .and_then(|()| cross::cross())
            .and_then(|()| qemu::qemu("check", "mps2-an386", true))
            .and_then(|()| qemu::qemu("models", "mps2-an386", true))
            .and_then(|()| insns::insns("mps2-an386"))
            .and_then(|()| budgets::budgets("mps2-an386", None))
            .and_then(|()| nopanic::nopanic(false))
            .and_then(|()| nopanic::nopanic(true)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: error: {e}");
            ExitCode::FAILURE
        }
    }
}
