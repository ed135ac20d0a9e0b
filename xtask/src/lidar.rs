//! `cargo xtask lidar`: the sensor path through a real emulated peripheral. A byte stream is
//! sent into USART1 of QEMU's `netduinoplus2` (STM32F405) through a socket chardev, the
//! firmware (`firmware/src/bin/lidar_uart.rs`) receives it with its register-level driver and
//! reports, and the report is checked here against what was sent.

use super::{capture, ensure_qemu, ensure_target, repo_root, scratch, show, Result};
use super::{cargo, FIRMWARE_TARGET, QEMU_TIMEOUT_S};
use std::fs::{self, File};
use std::io::Write;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The firmware program.
const BIN: &str = "lidar_uart";
/// The line the firmware prints once its receiver is on (bytes sent earlier are lost).
const READY: &str = "lidar_uart: ready";
/// The test harness's header before the stream: this tag and the length (u32, little-endian).
const MAGIC: &[u8; 4] = b"BFLD";
/// Seconds to wait for the ready line.
const READY_TIMEOUT_S: u64 = 60;
/// CRC-32 (ISO-HDLC), as the firmware computes over what it received.
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Builds the firmware program for the STM32F405 layout and returns its ELF.
fn build() -> Result<PathBuf> {
    ensure_target(FIRMWARE_TARGET)?;
    let mut cmd = cargo();
    cmd.current_dir(repo_root().join("firmware"))
        .env("BEAMFIELD_MEMORY_X", repo_root().join("memory-stm32f405.x"))
        .args([
            "build",
            "--release",
            "--target",
            FIRMWARE_TARGET,
            "--bin",
            BIN,
            "--message-format=json-render-diagnostics",
        ]);
    eprintln!("+ (cd firmware && {})", show(&cmd));
    let out = capture(&mut cmd)?;
    out.lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|m| m["reason"] == "compiler-artifact" && m["target"]["name"] == BIN)
        .find_map(|m| m["executable"].as_str().map(PathBuf::from))
        .ok_or_else(|| format!("cargo built no `{BIN}` executable"))
}

/// A deterministic test stream (every byte value occurs): splitmix64 words, little-endian.
fn test_stream(len: usize) -> Vec<u8> {
    let mut rng = host_tests::splitmix::SplitMix64::new(0x5eed_1d06);
    let mut out = Vec::with_capacity(len + 8);
    while out.len() < len {
        out.extend_from_slice(&rng.next_u64().to_le_bytes());
    }
    out.truncate(len);
    out
}

/// What one QEMU run printed.
struct Run {
    code: i32,
    stdout: String,
    stderr: String,
    elapsed: Duration,
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

/// Starts QEMU with USART1 on a listening Unix socket, waits for the ready line in the
/// semihosting output (a file, never a pipe), connects, sends the header and `stream`, and
/// waits for QEMU to exit. `extra` is appended to QEMU's arguments (the counting plugin).
fn run_qemu(elf: &Path, stream: &[u8], extra: &[String]) -> Result<Run> {
    let dir = scratch()?;
    let sock = dir.join("usart1.sock");
    let (out_p, err_p) = (dir.join("lidar.stdout"), dir.join("lidar.stderr"));
    let file = |p: &Path| File::create(p).map_err(|e| format!("{}: {e}", p.display()));
    let mut cmd = Command::new("timeout");
    cmd.args([
        QEMU_TIMEOUT_S,
        "qemu-system-arm",
        "-machine",
        "netduinoplus2",
    ])
    .args(["-nographic", "-monitor", "none"])
    .args(["-semihosting-config", "enable=on,target=native"])
    .args(["-icount", "shift=0"])
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
    let child = cmd
        .spawn()
        .map_err(|e| format!("cannot start `{}`: {e}", show(&cmd)))?;
    let mut guard = Guard(Some(child));
    let read = |p: &Path| fs::read_to_string(p).unwrap_or_default();

    // The ready line, or QEMU's end, or the deadline.
    loop {
        if read(&out_p).lines().any(|l| l.starts_with(READY)) {
            break;
        }
        let exited = guard
            .0
            .as_mut()
            .and_then(|c| c.try_wait().ok().flatten())
            .is_some();
        if exited || started.elapsed() > Duration::from_secs(READY_TIMEOUT_S) {
            let why = if exited { "QEMU exited" } else { "timed out" };
            return Err(format!(
                "{why} before the firmware's ready line:\n{}{}",
                read(&out_p),
                read(&err_p)
            ));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    eprintln!(
        "xtask: firmware ready after {:.1} s; sending {} bytes into USART1",
        started.elapsed().as_secs_f64(),
        stream.len()
    );
    let mut conn = UnixStream::connect(&sock).map_err(|e| format!("{}: {e}", sock.display()))?;
    // QEMU takes a byte only when the firmware has read the previous one: a write blocks until
    // the firmware catches up, and fails if QEMU goes away.
    conn.set_write_timeout(Some(Duration::from_secs(
        QEMU_TIMEOUT_S.parse().unwrap_or(120),
    )))
    .map_err(|e| e.to_string())?;
    let len = u32::try_from(stream.len()).map_err(|_| "stream longer than 4 GiB")?;
    let mut sent_at = Instant::now();
    let send = (|| -> std::io::Result<()> {
        conn.write_all(MAGIC)?;
        conn.write_all(&len.to_le_bytes())?;
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
        .map_err(|e| format!("waiting for QEMU: {e}"))?;
    let elapsed = started.elapsed();
    drop(conn);
    let (stdout, stderr) = (read(&out_p), read(&err_p));
    let _ = fs::remove_dir_all(&dir);
    if let Err(e) = send {
        return Err(format!(
            "sending the stream failed ({e}); the firmware printed:\n{stdout}{stderr}"
        ));
    }
    Ok(Run {
        code: status.and_then(|s| s.code()).unwrap_or(137),
        stdout,
        stderr,
        elapsed,
    })
}

/// Runs the transport check: sends a deterministic test stream of `len` bytes and checks that
/// the firmware received every byte in order (count and CRC-32).
pub fn lidar(len: usize) -> Result {
    ensure_qemu()?;
    let elf = build()?;
    let stream = test_stream(len);
    let run = run_qemu(&elf, &stream, &[])?;
    print!("{}", run.stdout);
    match run.code {
        0 => {}
        124 => return Err(format!("`{BIN}` did not finish within {QEMU_TIMEOUT_S} s")),
        c => {
            eprint!("{}", run.stderr);
            return Err(format!("`{BIN}` exited {c} under QEMU (netduinoplus2)"));
        }
    }
    let line = run
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("stream: received "))
        .ok_or("the firmware printed no `stream: received` line")?;
    let bytes: usize = line
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| format!("cannot read the byte count in {line:?}"))?;
    let crc = line
        .rsplit_once("crc32 ")
        .map(|(_, c)| c.trim())
        .ok_or_else(|| format!("cannot read the CRC in {line:?}"))?;
    let want = format!("{:08x}", CRC32.checksum(&stream));
    if bytes != stream.len() || crc != want {
        return Err(format!(
            "transport: sent {} bytes with crc32 {want}, the firmware received {bytes} with crc32 {crc}",
            stream.len()
        ));
    }
    println!(
        "transport: the firmware received all {} bytes in order through USART1 (crc32 {want} on both sides), {:.1} s in QEMU ({:.1} KB/s)",
        stream.len(),
        run.elapsed.as_secs_f64(),
        stream.len() as f64 / 1e3 / run.elapsed.as_secs_f64()
    );
    Ok(())
}
