//! QEMU: the boards, running a firmware image with its output in files (optionally under the
//! counting plugin or with USART1 on a socket), the errors of a failed run, and
//! `cargo xtask qemu`.

use crate::cross::build_firmware;
use crate::error::{Error, Result};
use crate::process::{repo_root, run_to_files, scratch, show, spawn_error, Finished};
use std::fs::{self, File};
use std::io::Write;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Seconds before a QEMU run is killed (a hung program then fails with status 124).
pub const QEMU_TIMEOUT_S: u64 = 120;

/// A board the programs run on: QEMU machine, memory layout, SysTick clock.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Board {
    /// ARM MPS2+ AN386: Cortex-M4F, 4 MiB code, 4 MiB SRAM, 25 MHz (the repository's memory.x).
    #[value(name = "mps2-an386")]
    Mps2An386,
    /// STM32F405 (Netduino Plus 2): 1 MiB flash, 128 KiB of its SRAM used (memory-stm32f405.x).
    #[value(name = "netduinoplus2")]
    Netduinoplus2,
    /// STM32L475 (B-L475E-IOT01A kit): 1 MiB flash, 96 KiB SRAM1 (memory-stm32l475.x); its
    /// RCC is modelled, and the robot firmware sets up 80 MHz.
    #[value(name = "b-l475e-iot01a")]
    BL475eIot01a,
}

impl Board {
    /// QEMU's name of the machine.
    pub fn machine(self) -> &'static str {
        match self {
            Board::Mps2An386 => "mps2-an386",
            Board::Netduinoplus2 => "netduinoplus2",
            Board::BL475eIot01a => "b-l475e-iot01a",
        }
    }

    /// The memory layout the firmware is linked with for this board.
    pub fn memory_x(self) -> PathBuf {
        repo_root().join(match self {
            Board::Mps2An386 => "memory.x",
            Board::Netduinoplus2 => "memory-stm32f405.x",
            Board::BL475eIot01a => "memory-stm32l475.x",
        })
    }

    /// SysTick's clock in QEMU's model of the board, Hz (on the `b-l475e-iot01a`, the 80 MHz
    /// the robot firmware sets up; the machine starts at the MSI's 4 MHz).
    pub fn core_hz(self) -> u64 {
        match self {
            Board::Mps2An386 => 25_000_000,
            Board::Netduinoplus2 => 168_000_000,
            Board::BL475eIot01a => 80_000_000,
        }
    }

    /// The robot firmware's cargo feature that selects this board (`firmware/src/boards/`).
    pub fn robot_feature(self) -> Option<&'static str> {
        match self {
            Board::BL475eIot01a => Some("board-b-l475e-iot01a"),
            _ => None,
        }
    }
}

/// The QEMU every task runs: `qemu-system-arm` from `PATH`, or the program named by the
/// environment variable `BEAMFIELD_QEMU` (to run the same task on another QEMU version, e.g.
/// one unpacked beside the system's).
pub fn qemu_program() -> std::ffi::OsString {
    std::env::var_os("BEAMFIELD_QEMU").unwrap_or_else(|| "qemu-system-arm".into())
}

/// Fails unless QEMU (see [`qemu_program`]) runs, saying how to install it; prints which QEMU
/// version the task runs on (instruction counts do not depend on it; timing does).
pub fn ensure_qemu() -> Result {
    let program = qemu_program();
    let version = Command::new(&program).arg("--version").output();
    match version {
        Ok(out) if out.status.success() => {
            let text = String::from_utf8_lossy(&out.stdout);
            eprintln!(
                "xtask: {}",
                text.lines().next().unwrap_or("QEMU (no version printed)")
            );
            Ok(())
        }
        _ => Err(Error::Missing(format!(
            "{} not found or does not run. Install it:\n  \
             Debian 12 whose QEMU tools come from bookworm-backports (`qemu-img --version` says 10.x): \
             add the bookworm-backports suite to apt's sources, then \
             sudo apt-get install -y --no-install-recommends -t bookworm-backports qemu-system-arm\n  \
             other Debian/Ubuntu: sudo apt-get install -y --no-install-recommends qemu-system-arm\n  \
             Fedora: sudo dnf install qemu-system-arm    macOS: brew install qemu\n  \
             (QEMU 7.2 to 10.x work; BEAMFIELD_QEMU names another qemu-system-arm)",
            program.to_string_lossy()
        ))),
    }
}

/// `timeout 120 QEMU -machine MACHINE` with semihosting and `-icount shift=0`
/// (one instruction is one nanosecond of virtual time), without the kernel.
fn qemu_command(machine: &str) -> Command {
    let mut cmd = Command::new("timeout");
    cmd.arg(QEMU_TIMEOUT_S.to_string())
        .arg(qemu_program())
        .args(["-machine", machine])
        .args([
            "-nographic",
            "-semihosting-config",
            "enable=on,target=native",
        ])
        .args(["-icount", "shift=0"]);
    cmd
}

/// Runs `elf` on QEMU's `machine`, with `extra` QEMU arguments (the counting plugin's), its
/// output in files named after `name`.
pub fn run_elf(elf: &Path, machine: &str, extra: &[String], name: &str) -> Result<Finished> {
    let mut cmd = qemu_command(machine);
    cmd.args(extra).arg("-kernel").arg(elf);
    run_to_files(&mut cmd, name)
}

/// The error for a firmware program (`what`, e.g. "the demo") that exited `code` (not 0) under
/// QEMU on `machine`: 124 is `timeout` killing it after [`QEMU_TIMEOUT_S`] seconds, 134 a CPU
/// lockup (QEMU aborts), any other code the program's own failure, explained by `cause`.
pub fn failure(code: i32, what: &str, machine: &str, cause: &str) -> Error {
    Error::Qemu(match code {
        124 => format!("{what} did not finish within {QEMU_TIMEOUT_S} s (hung?)"),
        134 => format!(
            "QEMU stopped with a CPU lockup on `{machine}`: does the memory layout fit the board?"
        ),
        c => format!("{what} exited {c} under QEMU ({machine}): {cause}"),
    })
}

/// `cargo xtask qemu`: builds the firmware's programs and runs `bin` on `machine`, printing its
/// output; fails unless it exits 0.
pub fn qemu(bin: &str, machine: &str, release: bool) -> Result {
    ensure_qemu()?;
    let elves = build_firmware(release, None)?;
    let elf = elves.get(bin).ok_or_else(|| {
        Error::Host(format!(
            "no firmware program `{bin}`; there are: {}",
            elves.keys().cloned().collect::<Vec<_>>().join(", ")
        ))
    })?;
    let run = run_elf(elf, machine, &[], bin)?;
    print!("{}", run.stdout);
    eprint!("{}", run.stderr);
    match run.code {
        0 => {
            eprintln!("xtask: `{bin}` exited 0 under QEMU ({machine})");
            Ok(())
        }
        c => Err(failure(c, &format!("`{bin}`"), machine, "see its output")),
    }
}

/// A run with USART1 on a socket: what it printed and how long it took.
pub struct UartRun {
    /// Exit code, stdout, stderr.
    pub finished: Finished,
    /// From QEMU's start to its end.
    pub elapsed: Duration,
}

/// Kills the QEMU child when dropped early (an error on the way), so none is left running.
struct Guard(Option<Child>);

impl Drop for Guard {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Seconds to wait for the firmware's ready line.
const READY_TIMEOUT_S: u64 = 60;

/// Starts `elf` on the `netduinoplus2` with USART1 on a listening Unix socket, waits for a line
/// starting with `ready` in the semihosting output (a file, never a pipe), connects, sends
/// `header` and `stream`, and waits for QEMU to exit. `extra` is appended to QEMU's arguments
/// (the counting plugin).
pub fn run_with_uart(
    elf: &Path,
    ready: &str,
    header: &[u8],
    stream: &[u8],
    extra: &[String],
) -> Result<UartRun> {
    let dir = scratch()?;
    let sock = dir.join("usart1.sock");
    let (out_p, err_p) = (dir.join("uart.stdout"), dir.join("uart.stderr"));
    let file = |p: &Path| File::create(p).map_err(|e| Error::io(p, e));
    let mut cmd = qemu_command("netduinoplus2");
    cmd.args(["-monitor", "none"])
        .arg("-chardev")
        .arg(format!(
            "socket,id=usart1,path={},server=on,wait=off",
            sock.display()
        ))
        .args(["-serial", "chardev:usart1"])
        .args(extra)
        .arg("-kernel")
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(file(&out_p)?)
        .stderr(file(&err_p)?);
    eprintln!(
        "+ {} >{} 2>{}",
        show(&cmd),
        out_p.display(),
        err_p.display()
    );
    let started = Instant::now();
    let child = cmd.spawn().map_err(|e| spawn_error(&cmd, e))?;
    let mut guard = Guard(Some(child));
    let read = |p: &Path| fs::read_to_string(p).unwrap_or_default();

    // The ready line, or QEMU's end, or the deadline.
    wait_ready(&mut guard, &out_p, &err_p, ready, started)?;
    eprintln!(
        "xtask: firmware ready after {:.1} s; sending {} bytes into USART1",
        started.elapsed().as_secs_f64(),
        stream.len()
    );
    let mut conn = UnixStream::connect(&sock).map_err(|e| Error::io(&sock, e))?;
    // QEMU takes a byte only when the firmware has read the previous one: a write blocks until
    // the firmware catches up, and fails if QEMU goes away.
    conn.set_write_timeout(Some(Duration::from_secs(QEMU_TIMEOUT_S)))
        .map_err(|e| Error::io(&sock, e))?;
    let mut sent_at = Instant::now();
    let send = (|| -> std::io::Result<()> {
        conn.write_all(header)?;
        for (i, piece) in stream.chunks(8192).enumerate() {
            conn.write_all(piece)?;
            if sent_at.elapsed() > Duration::from_secs(5) {
                eprintln!("xtask: sent {} of {} bytes", (i + 1) * 8192, stream.len());
                sent_at = Instant::now();
            }
        }
        conn.flush()
    })();
    // Keep the connection open until QEMU ends: the bytes still in the socket are read then.
    let status = guard
        .0
        .take()
        .map(|mut c| c.wait())
        .transpose()
        .map_err(|e| Error::Spawn {
            command: "waiting for QEMU".into(),
            source: e,
        })?;
    let elapsed = started.elapsed();
    drop(conn);
    let (stdout, stderr) = (read(&out_p), read(&err_p));
    let _ = fs::remove_dir_all(&dir);
    if let Err(e) = send {
        return Err(Error::Qemu(format!(
            "sending the stream failed ({e}); the firmware printed:\n{stdout}{stderr}"
        )));
    }
    Ok(UartRun {
        finished: Finished {
            code: status.and_then(|s| s.code()).unwrap_or(137),
            stdout,
            stderr,
        },
        elapsed,
    })
}

/// Waits until the program's stdout file `out_p` has a line starting with `ready`; an error
/// when QEMU exits or [`READY_TIMEOUT_S`] passes first (with what it printed).
fn wait_ready(
    guard: &mut Guard,
    out_p: &Path,
    err_p: &Path,
    ready: &str,
    started: Instant,
) -> Result {
    let read = |p: &Path| fs::read_to_string(p).unwrap_or_default();
    loop {
        if read(out_p).lines().any(|l| l.starts_with(ready)) {
            return Ok(());
        }
        let exited = guard
            .0
            .as_mut()
            .and_then(|c| c.try_wait().ok().flatten())
            .is_some();
        if exited || started.elapsed() > Duration::from_secs(READY_TIMEOUT_S) {
            let why = if exited { "QEMU exited" } else { "timed out" };
            return Err(Error::Qemu(format!(
                "{why} before the firmware's ready line:\n{}{}",
                read(out_p),
                read(err_p)
            )));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A run of the robot application: what it printed, what it sent on USART3, how long it took.
pub struct RobotRun {
    /// Exit code, stdout, stderr.
    pub finished: Finished,
    /// The bytes of USART3.
    pub usart3: Vec<u8>,
    /// What went into USART2: the link stream given, or with a bridge, that stream with the
    /// bridge's frames between its own.
    pub usart2: crate::robot::bridge::Written,
    /// From QEMU's start to its end.
    pub elapsed: Duration,
}

/// A firmware image for a board, and the line it prints when it is ready for input.
pub struct Firmware<'a> {
    /// The board it was built for.
    pub board: Board,
    /// The ELF.
    pub elf: &'a Path,
    /// The start of its ready line.
    pub ready: &'a str,
}

/// Starts `firmware` on its board with USART1 and USART2 on listening Unix sockets and
/// USART3 into a file; waits for the `ready` line; then writes `lidar` into USART1 and `link`
/// into USART2, each from its own thread (QEMU takes a byte only when the firmware has read the
/// previous one, so each write blocks until the firmware catches up), and waits for QEMU to
/// exit (the firmware ends once both lines have been silent, feature `emulator`), at most
/// `timeout_s`. With `bridge`, USART3 is forwarded to it and its frames go into USART2
/// (`crate::robot::bridge`).
pub fn run_robot(
    firmware: Firmware<'_>,
    lidar: &[u8],
    link: &[u8],
    extra: &[String],
    timeout_s: u64,
    bridge: Option<std::net::TcpStream>,
) -> Result<RobotRun> {
    use crate::robot::bridge::{self, Shared, Written};
    let Firmware { board, elf, ready } = firmware;
    use std::sync::Arc;
    let dir = scratch()?;
    let (s1, s2, out3) = (
        dir.join("usart1.sock"),
        dir.join("usart2.sock"),
        dir.join("usart3.bin"),
    );
    let (out_p, err_p) = (dir.join("robot.stdout"), dir.join("robot.stderr"));
    let file = |p: &Path| File::create(p).map_err(|e| Error::io(p, e));
    // Without `-icount`: the application's output follows from the bytes alone (the host
    // recomputes it), the counting plugin's counts do not depend on timing, and QEMU delivers
    // the serial bytes about twice as fast with the guest's clock on the host's.
    let mut cmd = Command::new("timeout");
    cmd.arg(timeout_s.to_string()).arg(qemu_program()).args([
        "-machine",
        board.machine(),
        "-nographic",
        "-semihosting-config",
        "enable=on,target=native",
    ]);
    cmd.args(["-monitor", "none"]);
    for (id, sock) in [("usart1", &s1), ("usart2", &s2)] {
        cmd.arg("-chardev").arg(format!(
            "socket,id={id},path={},server=on,wait=off",
            sock.display()
        ));
    }
    cmd.arg("-chardev")
        .arg(format!("file,id=usart3,path={}", out3.display()))
        .args(["-serial", "chardev:usart1"])
        .args(["-serial", "chardev:usart2"])
        .args(["-serial", "chardev:usart3"])
        .args(extra)
        .arg("-kernel")
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(file(&out_p)?)
        .stderr(file(&err_p)?);
    eprintln!(
        "+ {} >{} 2>{}",
        show(&cmd),
        out_p.display(),
        err_p.display()
    );
    let started = Instant::now();
    let child = cmd.spawn().map_err(|e| spawn_error(&cmd, e))?;
    let mut guard = Guard(Some(child));
    let read = |p: &Path| fs::read_to_string(p).unwrap_or_default();
    wait_ready(&mut guard, &out_p, &err_p, ready, started)?;
    eprintln!(
        "xtask: firmware ready after {:.1} s; sending {} bytes into USART1 and {} into USART2",
        started.elapsed().as_secs_f64(),
        lidar.len(),
        link.len()
    );
    let connect = |p: &Path| -> Result<UnixStream> {
        let c = UnixStream::connect(p).map_err(|e| Error::io(p, e))?;
        c.set_write_timeout(Some(Duration::from_secs(timeout_s)))
            .map_err(|e| Error::io(p, e))?;
        Ok(c)
    };
    let (mut c1, mut c2) = (connect(&s1)?, connect(&s2)?);
    let shared = Arc::new(Shared {
        device_us: Default::default(),
        done: Default::default(),
        from_bridge: Default::default(),
    });
    let forwarding = match bridge {
        Some(conn) => {
            let reader = conn.try_clone().map_err(|e| Error::Host(e.to_string()))?;
            let sh = shared.clone();
            std::thread::spawn(move || bridge::read_bridge(reader, sh));
            let (sh, path) = (shared.clone(), out3.clone());
            Some(std::thread::spawn(move || {
                bridge::forward_output(&path, conn, sh)
            }))
        }
        None => None,
    };
    let paced = forwarding.is_some();
    // The LiDAR's first bytes go in before the link's: the firmware takes a LiDAR that has sent
    // no valid frame for a second (counted from its start) as silent and then reads the link
    // whatever its odometry window holds, which the host's replay does not do.
    let (lidar_started, link_may_start) = std::sync::mpsc::channel::<()>();
    let (sent, status) = std::thread::scope(|scope| {
        let sh = &shared;
        let w2 = scope.spawn(move || -> std::io::Result<(UnixStream, Written)> {
            // Ended without a word (the LiDAR's writer failed): go on, its error is reported.
            let _ = link_may_start.recv();
            let written = if paced {
                bridge::write_paced(&mut c2, link, sh)?
            } else {
                c2.write_all(link)?;
                Written {
                    bytes: link.to_vec(),
                    bridge_frames: 0,
                    first_bridge_at_us: None,
                }
            };
            c2.flush()?;
            Ok((c2, written))
        });
        let w1 = scope.spawn(move || -> std::io::Result<UnixStream> {
            let mut at = Instant::now();
            for (i, piece) in lidar.chunks(16384).enumerate() {
                c1.write_all(piece)?;
                if i == 0 {
                    c1.flush()?;
                    let _ = lidar_started.send(());
                }
                if at.elapsed() > Duration::from_secs(10) {
                    eprintln!(
                        "xtask: sent {} of {} LiDAR bytes",
                        (i + 1) * 16384,
                        lidar.len()
                    );
                    at = Instant::now();
                }
            }
            c1.flush()?;
            Ok(c1)
        });
        // Keep the connections open until QEMU ends: the bytes still in the sockets are read.
        let status = guard.0.take().map(|mut c| c.wait()).transpose();
        let sent = (w1.join(), w2.join());
        (sent, status)
    });
    shared
        .done
        .store(true, std::sync::atomic::Ordering::Release);
    if let Some(f) = forwarding {
        let _ = f.join();
    }
    let status = status.map_err(|e| Error::Spawn {
        command: "waiting for QEMU".into(),
        source: e,
    })?;
    let elapsed = started.elapsed();
    let (stdout, stderr) = (read(&out_p), read(&err_p));
    let usart3 = fs::read(&out3).map_err(|e| Error::io(&out3, e))?;
    let _ = fs::remove_dir_all(&dir);
    let failed = |what: &str, e: std::io::Error| {
        Error::Qemu(format!(
            "sending into {what} failed ({e}); the firmware printed:\n{stdout}{stderr}"
        ))
    };
    match sent.0 {
        Ok(Ok(_)) => {}
        Ok(Err(e)) => return Err(failed("USART1", e)),
        Err(_) => return Err(Error::Host("the USART1 writer thread panicked".into())),
    }
    let usart2 = match sent.1 {
        Ok(Ok((_, w))) => w,
        Ok(Err(e)) => return Err(failed("USART2", e)),
        Err(_) => return Err(Error::Host("the USART2 writer thread panicked".into())),
    };
    Ok(RobotRun {
        finished: Finished {
            code: status.and_then(|s| s.code()).unwrap_or(137),
            stdout,
            stderr,
        },
        usart3,
        usart2,
        elapsed,
    })
}
