//! `cargo xtask`: project tasks that need more than `cargo test`: the firmware under QEMU,
//! instruction counts, cross builds. Run `cargo xtask --help`.

mod budgets;
mod demo;
mod demo_f64;
mod demo_ref;
mod insncount;
mod lidar;
mod lidar_ref;
mod track;
mod willow;

use clap::{Parser, Subcommand};
use std::collections::BTreeMap;
use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

/// The firmware's target: Cortex-M4F (QEMU `mps2-an386`).
const FIRMWARE_TARGET: &str = "thumbv7em-none-eabihf";
/// Targets the library must build for.
const CROSS_TARGETS: [&str; 4] = [
    "thumbv7em-none-eabihf",
    "thumbv7m-none-eabi",
    "thumbv6m-none-eabi",
    "riscv32imc-unknown-none-elf",
];
/// Seconds before a QEMU run is killed (a hung program then fails with status 124).
const QEMU_TIMEOUT_S: &str = "120";
/// Beams per scan of the synthetic regions (0–3) in `firmware/src/bin/insns.rs`.
const INSNS_BEAMS: u64 = 360;
/// What each measured region of `insns.rs` does, in order, and what its count is divided by
/// (the program prints the divisors on its `insns divisors:` line).
const INSNS_REGIONS: [(&str, &str); 18] = [
    ("empty loop (sum of ranges)", "beam"),
    ("ln per beam (math::ln)", "beam"),
    ("exp per beam (math::exp)", "beam"),
    ("beam mixture, given z*", "beam"),
    ("LF prepare, 8 real scans", "beam slot"),
    ("empty loop, prepared endpoints", "beam"),
    ("LF prepared score", "beam"),
    ("LF prepared, no beams (per pose)", "pose"),
    ("LF per-pose path (score)", "beam"),
    // The race (docs/race.md): real scans, real map, z* cast on the device.
    ("beam model + ray cast, Intel", "beam"),
    // The likelihood field over the same map stored tiled (distance encoding 2).
    ("LF prepared score, tiled blob", "beam"),
    ("LF prepared, no beams, tiled", "pose"),
    // LiDAR streams of the 8 real scans (beamfield::lidar).
    ("empty loop over LD06 bytes", "byte"),
    ("LD06 decode", "byte"),
    ("LD06 decode + assembly", "byte"),
    ("RPLIDAR decode + assembly", "byte"),
    ("XV-11 decode + assembly", "byte"),
    ("YDLIDAR decode + assembly", "byte"),
];

type Result<T = ()> = std::result::Result<T, String>;

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
        board: demo::Board,
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
    /// on the host with the same library code, and fail on any difference in the printed bit
    /// patterns, or when the tracking RMSE is over its bound.
    ///
    /// The input is firmware/assets/track.rs (`cargo xtask track-assets`; a host test checks it
    /// is current).
    Track {
        /// Board (QEMU machine and memory layout).
        #[arg(long, value_enum, default_value = "mps2-an386")]
        board: demo::Board,
        /// Run under QEMU's counting plugin instead (xtask/insncount; needs gcc and
        /// llvm-tools) and print the instructions per particle per update, scoring included
        /// and excluded, and the program's RAM; the bit-equality check still runs.
        #[arg(long)]
        insns: bool,
    },
    /// Regenerate firmware/assets/track.rs (the track's scans, logged poses and synthesized
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
    /// stream, and checks the report: every byte received in order (count and CRC-32); the
    /// host's recomputation (decode, assembly, scores, counters) to the printed digits; what the
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
    /// Regenerate firmware/assets/ (Intel map blob and scans) from the Intel log in data/.
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
        } => qemu(&bin, &machine, !debug),
        Task::Insns { machine } => insns(&machine),
        Task::Count { elf, machine } => insncount::count(&elf, &machine),
        Task::Cross => cross(),
        Task::Demo { board, encoding } => demo::demo(board, encoding),
        Task::Willow => willow::willow(),
        Task::Budgets { machine, features } => budgets::budgets(&machine, features.as_deref()),
        Task::Nopanic { show_failure } => budgets::nopanic(show_failure),
        Task::Lidar { no_count, split } => lidar::lidar(!no_count, split),
        Task::DemoAssets => demo::demo_assets(),
        Task::Track { board, insns } => {
            if insns {
                track::track_insns(board)
            } else {
                track::track(board)
            }
        }
        Task::TrackAssets => track::track_assets(),
        Task::Refcases { check } => refcases(check),
        Task::Modelcases { check } => modelcases(check),
        Task::Ci => refcases(true)
            .and_then(|()| modelcases(true))
            .and_then(|()| cross())
            .and_then(|()| qemu("check", "mps2-an386", true))
            .and_then(|()| qemu("models", "mps2-an386", true))
            .and_then(|()| insns("mps2-an386"))
            .and_then(|()| budgets::budgets("mps2-an386", None))
            .and_then(|()| budgets::nopanic(false))
            .and_then(|()| budgets::nopanic(true)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

fn show(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

/// Runs a command, echoing it, and fails unless it exits 0.
fn run(cmd: &mut Command) -> Result {
    eprintln!("+ {}", show(cmd));
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start `{}`: {e}", show(cmd)))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{}` failed ({status})", show(cmd)))
    }
}

/// Runs a command and returns its stdout (stderr passes through).
fn capture(cmd: &mut Command) -> Result<String> {
    let out = cmd
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot start `{}`: {e}", show(cmd)))?;
    if !out.status.success() {
        return Err(format!("`{}` failed ({})", show(cmd), out.status));
    }
    String::from_utf8(out.stdout).map_err(|e| format!("`{}`: {e}", show(cmd)))
}

fn ensure_target(target: &str) -> Result {
    let installed = capture(Command::new("rustup").args(["target", "list", "--installed"]))
        .map_err(|e| {
            format!("{e}\n  (without rustup, install the Rust standard library for {target})")
        })?;
    if installed.lines().any(|l| l.trim() == target) {
        return Ok(());
    }
    run(Command::new("rustup").args(["target", "add", target]))
}

fn ensure_qemu() -> Result {
    let ok = Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if ok {
        Ok(())
    } else {
        Err("qemu-system-arm not found. Install it:\n  \
             Debian/Ubuntu: sudo apt-get install -y --no-install-recommends qemu-system-arm\n  \
             Fedora: sudo dnf install qemu-system-arm    macOS: brew install qemu"
            .to_string())
    }
}

/// Builds the firmware's binaries and returns their ELF paths by name.
fn build_firmware(release: bool, features: Option<&str>) -> Result<BTreeMap<String, PathBuf>> {
    ensure_target(FIRMWARE_TARGET)?;
    let dir = repo_root().join("firmware");
    let mut cmd = cargo();
    cmd.current_dir(&dir).args([
        "build",
        "--target",
        FIRMWARE_TARGET,
        "--bins",
        "--message-format=json-render-diagnostics",
    ]);
    if release {
        cmd.arg("--release");
    }
    if let Some(f) = features {
        cmd.args(["--features", f]);
    }
    eprintln!("+ (cd firmware && {})", show(&cmd));
    let out = capture(&mut cmd)?;
    let mut elves = BTreeMap::new();
    for line in out.lines() {
        let Ok(msg) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if msg["reason"] != "compiler-artifact" {
            continue;
        }
        if let (Some(name), Some(exe)) =
            (msg["target"]["name"].as_str(), msg["executable"].as_str())
        {
            elves.insert(name.to_string(), PathBuf::from(exe));
        }
    }
    Ok(elves)
}

/// A scratch directory for QEMU's output files (never a pipe: docs/firmware.md).
fn scratch() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("beamfield-xtask-{}", std::process::id()));
    fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    Ok(dir)
}

/// Runs `cmd` with stdout and stderr sent to files; returns (exit code, stdout, stderr).
fn run_to_files(cmd: &mut Command, name: &str) -> Result<(i32, String, String)> {
    let dir = scratch()?;
    let (out_p, err_p) = (
        dir.join(format!("{name}.stdout")),
        dir.join(format!("{name}.stderr")),
    );
    let file = |p: &Path| File::create(p).map_err(|e| format!("{}: {e}", p.display()));
    cmd.stdin(Stdio::null())
        .stdout(file(&out_p)?)
        .stderr(file(&err_p)?);
    eprintln!("+ {} >{} 2>{}", show(cmd), out_p.display(), err_p.display());
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start `{}`: {e}", show(cmd)))?;
    let read = |p: &Path| fs::read_to_string(p).unwrap_or_default();
    let (out, err) = (read(&out_p), read(&err_p));
    let _ = fs::remove_dir_all(&dir);
    // A signal (no code) is reported as 128 + 9, like a shell would for a kill.
    Ok((status.code().unwrap_or(137), out, err))
}

fn qemu(bin: &str, machine: &str, release: bool) -> Result {
    ensure_qemu()?;
    let elves = build_firmware(release, None)?;
    let elf = elves.get(bin).ok_or_else(|| {
        format!(
            "no firmware program `{bin}`; there are: {}",
            elves.keys().cloned().collect::<Vec<_>>().join(", ")
        )
    })?;
    let (code, out, err) = run_to_files(
        Command::new("timeout")
            .args([QEMU_TIMEOUT_S, "qemu-system-arm"])
            .args([
                "-machine",
                machine,
                "-nographic",
                "-semihosting-config",
                "enable=on,target=native",
                "-icount",
                "shift=0",
                "-kernel",
            ])
            .arg(elf),
        bin,
    )?;
    print!("{out}");
    eprint!("{err}");
    match code {
        0 => {
            eprintln!("xtask: `{bin}` exited 0 under QEMU ({machine})");
            Ok(())
        }
        124 => Err(format!(
            "`{bin}` did not finish within {QEMU_TIMEOUT_S} s (hung?)"
        )),
        134 => Err(format!(
            "QEMU stopped with a CPU lockup: does memory.x fit the `{machine}` board?"
        )),
        c => Err(format!("`{bin}` exited {c} under QEMU ({machine})")),
    }
}

/// `llvm-nm` from PATH, else the one of the Rust sysroot (`rustup component add llvm-tools`).
fn llvm_nm() -> PathBuf {
    let on_path = Command::new("llvm-nm")
        .arg("--version")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if on_path {
        return PathBuf::from("llvm-nm");
    }
    let sysroot = capture(Command::new("rustc").args(["--print", "sysroot"])).unwrap_or_default();
    let host = capture(Command::new("rustc").args(["--print", "host-tuple"]))
        .unwrap_or_else(|_| "x86_64-unknown-linux-gnu".to_string());
    Path::new(sysroot.trim()).join(format!("lib/rustlib/{}/bin/llvm-nm", host.trim()))
}

fn ensure_llvm_nm() -> Result {
    if Command::new("llvm-nm")
        .arg("--version")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
    {
        return Ok(());
    }
    let sysroot = capture(Command::new("rustc").args(["--print", "sysroot"]))?;
    let host = capture(Command::new("rustc").args(["--print", "host-tuple"]))
        .unwrap_or_else(|_| "x86_64-unknown-linux-gnu".to_string());
    let nm = Path::new(sysroot.trim()).join(format!("lib/rustlib/{}/bin/llvm-nm", host.trim()));
    if nm.is_file() {
        return Ok(());
    }
    run(Command::new("rustup").args(["component", "add", "llvm-tools"]))
}

fn insns(machine: &str) -> Result {
    ensure_qemu()?;
    ensure_llvm_nm()?;
    // Regions 10-11 read a tiled blob: one build with the tiled reader measures both encodings.
    let elves = build_firmware(true, Some("tiled"))?;
    let elf = elves
        .get("insns")
        .ok_or("the firmware has no `insns` program")?;
    let (code, out, err) = insncount::run_counted(elf, machine, "insns")?;
    print!("{out}");
    if code != 0 {
        eprint!("{err}");
        return Err(format!("the counting run exited {code}"));
    }
    let counts = insncount::region_counts(&err);
    if counts.len() != INSNS_REGIONS.len() {
        eprint!("{err}");
        return Err(format!(
            "expected {} measured regions, the plugin reported {}",
            INSNS_REGIONS.len(),
            counts.len()
        ));
    }
    let divisors: Vec<u64> = out
        .lines()
        .find_map(|l| l.strip_prefix("insns divisors: "))
        .ok_or("the program printed no `insns divisors:` line")?
        .split_whitespace()
        .map(|d| d.parse::<u64>().map_err(|e| format!("divisor {d}: {e}")))
        .collect::<Result<_>>()?;
    if divisors.len() != INSNS_REGIONS.len() || divisors.contains(&0) {
        return Err(format!("bad divisors {divisors:?}"));
    }
    let per_beam = |n: u64| n as f64 / INSNS_BEAMS as f64;
    println!(
        "\ninstructions on {machine} ({FIRMWARE_TARGET}, release); regions 0-3: {INSNS_BEAMS} synthetic beams; 4-9: Intel map and real scans; 10-11: the same map tiled; 12-17: LiDAR streams of the real scans:"
    );
    println!(
        "{:<3} {:<34} {:>12} {:>10} {:>10} per",
        "#", "region", "total", "divisor", "ratio"
    );
    for (i, ((name, per), (n, d))) in INSNS_REGIONS
        .iter()
        .zip(counts.iter().zip(&divisors))
        .enumerate()
    {
        println!(
            "{i:<3} {name:<34} {n:>12} {d:>10} {:>10.1} {per}",
            *n as f64 / *d as f64
        );
    }
    let per = |i: usize| counts[i] as f64 / divisors[i] as f64;
    let pose_work = counts[7] as f64 / divisors[7] as f64;
    let beams_per_pose = divisors[6] as f64 / divisors[7] as f64;
    println!(
        "likelihood field, prepared: {:.1} instructions per beam ({:.1} with the per-pose work of {:.0} spread over {:.1} beams); per-pose path: {:.1} per beam ({:.1}x); empty loop over the endpoints: {:.1}",
        (counts[6] as f64 - counts[7] as f64) / divisors[6] as f64,
        per(6),
        pose_work,
        beams_per_pose,
        per(8),
        counts[8] as f64 / counts[6] as f64,
        per(5)
    );
    println!(
        "likelihood field, prepared, tiled blob (encoding 2, same codes): {:.1} instructions per beam ({:.1} with the per-pose work), {:.2}x the raw blob's {:.1}",
        (counts[10] as f64 - counts[11] as f64) / divisors[10] as f64,
        per(10),
        (counts[10] as f64 - counts[11] as f64) / (counts[6] as f64 - counts[7] as f64),
        (counts[6] as f64 - counts[7] as f64) / divisors[6] as f64,
    );
    let (empty, ln, mixture) = (counts[0], counts[1], counts[3]);
    println!(
        "beam mixture: {:.1} instructions per beam ({:.1} above the empty loop; {:.2}x one ln per beam)",
        per_beam(mixture),
        per_beam(mixture.saturating_sub(empty)),
        mixture as f64 / ln as f64
    );
    println!(
        "beam model with on-device ray casting (real Intel map and scans): {:.1} instructions per beam (the mixture alone, given z*, on the synthetic scan: {:.1})",
        per(9),
        per_beam(mixture)
    );
    println!(
        "LiDAR streams, instructions per received byte: LD06 decode {:.1}, LD06 decode + assembly {:.1} ({:.1}x the empty byte loop of {:.1}), RPLIDAR {:.1}, XV-11 {:.1}, YDLIDAR {:.1}",
        per(13),
        per(14),
        per(14) / per(12),
        per(12),
        per(15),
        per(16),
        per(17)
    );
    Ok(())
}

/// The features a package declares (without `default`).
fn features_of(manifest: &Path, package: &str) -> Result<Vec<String>> {
    let meta = capture(
        cargo()
            .args([
                "metadata",
                "--no-deps",
                "--format-version",
                "1",
                "--manifest-path",
            ])
            .arg(manifest),
    )?;
    let meta: serde_json::Value = serde_json::from_str(&meta).map_err(|e| e.to_string())?;
    let pkg = meta["packages"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == package))
        .ok_or_else(|| format!("package {package} not in {}", manifest.display()))?;
    Ok(pkg["features"]
        .as_object()
        .map(|f| f.keys().filter(|k| *k != "default").cloned().collect())
        .unwrap_or_default())
}

fn cross() -> Result {
    let root = repo_root();
    let features = features_of(&root.join("Cargo.toml"), "beamfield")?;
    eprintln!("xtask: library features: {}", features.join(", "));
    for target in CROSS_TARGETS {
        ensure_target(target)?;
        let lib = || {
            let mut c = cargo();
            c.current_dir(&root)
                .args(["build", "-p", "beamfield", "--target", target]);
            c
        };
        run(&mut lib())?;
        for f in &features {
            run(lib().args(["--features", f]))?;
        }
        run(lib().arg("--all-features"))?;
    }
    // The firmware has no #[global_allocator]: a crate graph that used `alloc` would not link.
    let fw = features_of(&root.join("firmware/Cargo.toml"), "beamfield-firmware")?;
    // `deliberate-panic` exists to make the no-panic link fail (`cargo xtask nopanic
    // --show-failure`): it is not a feature a program is linked with.
    let fw: Vec<String> = fw.into_iter().filter(|f| f != "deliberate-panic").collect();
    for f in std::iter::once(None).chain(fw.iter().map(|f| Some(f.as_str()))) {
        build_firmware(true, f)?;
        eprintln!(
            "xtask: firmware linked without an allocator (features: {})",
            f.unwrap_or("none")
        );
    }
    Ok(())
}

fn refcases(check: bool) -> Result {
    generated_file(
        host_tests::firmware_cases::GENERATED_PATH,
        &host_tests::firmware_cases::render(),
        check,
        "refcases",
    )
}

fn modelcases(check: bool) -> Result {
    generated_file(
        host_tests::firmware_models::GENERATED_PATH,
        &host_tests::firmware_models::render(),
        check,
        "modelcases",
    )
}

/// Writes (or with `check`, only compares) a file the host generates for the firmware.
fn generated_file(relative: &str, want: &str, check: bool, task: &str) -> Result {
    let path = repo_root().join(relative);
    let have = fs::read_to_string(&path).unwrap_or_default();
    if have == want {
        eprintln!("xtask: {} is up to date", path.display());
        return Ok(());
    }
    if check {
        return Err(format!(
            "{} is stale: run `cargo xtask {task}` and commit it",
            path.display()
        ));
    }
    fs::write(&path, want).map_err(|e| format!("{}: {e}", path.display()))?;
    eprintln!("xtask: wrote {}", path.display());
    Ok(())
}
