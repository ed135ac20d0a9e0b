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
/// The sanity bound: every scan's best pose within this distance of its logged pose, metres:
/// five steps of the 2.5 cm grid (the log's poses disagree with the map by up to ~10 cm for
/// some scans, see docs/demo.md), with half a step of margin.
const ACCEPT_M: f32 = 0.125;
/// The same for the heading, degrees: two steps of the 0.5° grid with half a step of margin
/// (the segment has the robot turning on the spot at up to 30° per scan, and a scan taken while
/// turning is skewed).
const ACCEPT_DEG: f32 = 1.25;
/// The mean heading offset of the best poses over the segment, degrees, must be within this. A
/// scan assembled one beam (1°) off turns every best heading by about 1° and fails this.
const ACCEPT_MEAN_DEG: f32 = 0.5;
/// CRC-32 (ISO-HDLC), as the firmware computes over what it received.
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Builds the firmware program for the STM32F405 layout and returns its ELF.
fn build(split: bool) -> Result<PathBuf> {
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
    if split {
        cmd.args(["--features", "decode-split"]);
    }
    eprintln!("+ (cd firmware && {})", show(&cmd));
    let out = capture(&mut cmd)?;
    out.lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|m| m["reason"] == "compiler-artifact" && m["target"]["name"] == BIN)
        .find_map(|m| m["executable"].as_str().map(PathBuf::from))
        .ok_or_else(|| format!("cargo built no `{BIN}` executable"))
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

/// Runs the sensor path: streams the LD06 stream into the emulated USART, checks the transport
/// (count and CRC-32), the plan's expectations (frames, corrupted beams, no wrong beam, every
/// scan's best pose near its logged pose) and the host's recomputation to the printed digits,
/// and with `count` the instructions per received byte of decode + assembly.
/// With `split` (implies `count`), the firmware also counts a second decoder alone over the
/// same bytes.
pub fn lidar(count: bool, split: bool) -> Result {
    ensure_qemu()?;
    let count = count || split;
    let elf = build(split)?;
    let plan = crate::lidar_ref::stream()?;
    let stream = &plan.bytes;
    eprintln!(
        "xtask: LD06 stream: {} real Intel scans as {} frames, {} bytes of noise, {} corrupted frames: {} bytes",
        plan.scans,
        plan.frames,
        plan.noise,
        crate::lidar_ref::FLIPS.len(),
        stream.len()
    );
    let extra = if count {
        crate::insncount::qemu_args(&elf, ", or run `cargo xtask lidar --no-count`")?
    } else {
        Vec::new()
    };
    let run = run_qemu(&elf, stream, &extra)?;
    // The report, without the plugin's lines (they go to stderr).
    print!("{}", run.stdout);
    match run.code {
        0 => {}
        124 => return Err(format!("`{BIN}` did not finish within {QEMU_TIMEOUT_S} s")),
        c => {
            eprint!("{}", run.stderr);
            return Err(format!(
                "`{BIN}` exited {c} under QEMU (netduinoplus2): a scan could not be scored or did not match the log"
            ));
        }
    }

    // 1. Transport: every byte, in order.
    let line = run
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("stream: received "))
        .ok_or("the firmware printed no `stream: received` line")?;
    let bytes = line
        .split_whitespace()
        .next()
        .and_then(|n| n.parse::<usize>().ok())
        .ok_or_else(|| format!("cannot read the byte count in {line:?}"))?;
    let crc = between(line, "crc32 ")
        .and_then(|t| t.split(';').next())
        .ok_or_else(|| format!("cannot read the CRC in {line:?}"))?;
    let want = format!("{:08x}", CRC32.checksum(stream));
    if bytes != stream.len() || crc != want {
        return Err(format!(
            "transport: sent {} bytes with crc32 {want}, the firmware received {bytes} with crc32 {crc}",
            stream.len()
        ));
    }
    println!(
        "transport: all {} bytes received in order through USART1 (crc32 {want} on both sides), {:.1} s in QEMU ({:.1} KB/s end to end)",
        stream.len(),
        run.elapsed.as_secs_f64(),
        stream.len() as f64 / 1e3 / run.elapsed.as_secs_f64()
    );

    // 2. The host's recomputation, to the printed digits.
    let blob_path = repo_root().join("firmware/assets/intel.bin");
    let blob = fs::read(&blob_path).map_err(|e| format!("{}: {e}", blob_path.display()))?;
    let reference = crate::lidar_ref::reference(stream, &blob)?;
    let scans = crate::lidar_ref::check(&run.stdout, &reference)?;
    println!(
        "host reference: the host decodes, assembles and scores the same stream with the same crate: all {scans} scans (points, beams, log comparison, best pose, log-likelihood, ESS) and the decoder's and assembler's counters agree with the device's report to the printed digits"
    );

    // 3. What the plan alone says (not the code under test).
    let flips = crate::lidar_ref::FLIPS.len() as u32;
    let frames_ok = (plan.frames as u32) - flips;
    if reference.frames_ok != frames_ok || reference.bad_checksum != flips {
        return Err(format!(
            "the plan has {frames_ok} intact frames and {flips} corrupted ones; the decoder passed {} and rejected {}",
            reference.frames_ok, reference.bad_checksum
        ));
    }
    // Every frame of the plan is a 360-point revolution's at 3,600 °/s (11° per frame, the
    // plausible span at that speed is up to 28.8°): none may be taken for damage.
    if reference.implausible_frames != 0 {
        return Err(format!(
            "the plan's frames are all plausible; the decoder took {} for damage",
            reference.implausible_frames
        ));
    }
    if reference.scans.len() != plan.scans {
        return Err(format!(
            "{} revolutions sent, {} scans assembled",
            plan.scans,
            reference.scans.len()
        ));
    }
    let mut worst = (0.0f32, 0.0f32);
    for (k, s) in reference.scans.iter().enumerate() {
        if s.wrong != 0 || s.missing != plan.missing[k] {
            return Err(format!(
                "scan {k}: the plan leaves {} beams missing and none wrong; the device has {} missing, {} wrong",
                plan.missing[k], s.missing, s.wrong
            ));
        }
        worst = (worst.0.max(s.offset.0), worst.1.max(s.offset.1.abs()));
        if s.offset.0 > ACCEPT_M || s.offset.1.abs() > ACCEPT_DEG {
            return Err(format!(
                "scan {k}: best pose {:.1} cm and {:.1} deg from the logged pose (accepted: {} cm, {} deg)",
                s.offset.0 * 100.0,
                s.offset.1,
                ACCEPT_M * 100.0,
                ACCEPT_DEG
            ));
        }
    }
    let mean_deg = reference.scans.iter().map(|s| s.offset.1).sum::<f32>()
        / reference.scans.len().max(1) as f32;
    if mean_deg.abs() > ACCEPT_MEAN_DEG {
        return Err(format!(
            "the best headings are {mean_deg:.2} deg from the logged ones on average (accepted: {ACCEPT_MEAN_DEG} deg): are the scans turned?"
        ));
    }
    println!(
        "plan: {frames_ok} frames decoded and {flips} rejected for their checksum as corrupted, none rejected as implausible; every beam of the {} scans equals the log's range to the millimetre except the {} in corrupted frames; every best pose within {} cm and {} deg of the logged pose (worst {:.1} cm, {:.1} deg), mean heading offset {:.2} deg (accepted: {} deg)",
        plan.scans,
        plan.missing.iter().map(|&m| u32::from(m)).sum::<u32>(),
        ACCEPT_M * 100.0,
        ACCEPT_DEG,
        worst.0 * 100.0,
        worst.1,
        mean_deg,
        ACCEPT_MEAN_DEG
    );

    // 4. Instructions per received byte: decode + assembly against the CRC-32 baseline.
    if count {
        let counts = crate::insncount::region_counts(&run.stderr);
        let regions = line
            .rsplit_once("; ")
            .and_then(|(_, t)| t.strip_suffix(" counted regions"))
            .and_then(|n| n.parse::<usize>().ok())
            .ok_or_else(|| format!("cannot read the counted regions in {line:?}"))?;
        if regions != counts.len() {
            return Err(format!(
                "the firmware marked {regions} regions, the plugin counted {}",
                counts.len()
            ));
        }
        per_byte(&run.stdout, &counts, stream.len(), split)?;
    }
    Ok(())
}

/// The text after `key` in `line`.
fn between<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.find(key).map(|i| &line[i + key.len()..])
}

/// Splits the plugin's regions into decode + assembly, decode alone (with `split`) and the CRC
/// baseline, following the firmware's `chunk` lines (each chunk: the decode + assembly region,
/// then with `split` the decoder alone, then the CRC; at the end, the assembler's finish), and
/// prints the per-byte figures.
fn per_byte(out: &str, counts: &[u64], bytes: usize, split: bool) -> Result {
    let (decode, alone, crc) = split_regions(out, counts, bytes, split)?;
    let b = bytes as f64;
    let split_note = if split {
        format!(
            ", of which the decoder alone {:.1} (a second decoder over the same bytes; this build's inlining differs from the default one's)",
            alone as f64 / b
        )
    } else {
        String::new()
    };
    println!(
        "instructions (QEMU plugin, exact): LD06 decode + scan assembly {decode} for {bytes} received bytes = {:.1} per byte{split_note}; {:.2}x the same run's table-driven CRC-32 over the same bytes ({:.1} per byte); receiving and scoring not counted",
        decode as f64 / b,
        decode as f64 / crc as f64,
        crc as f64 / b
    );
    Ok(())
}

/// The sums of the counted regions: (decode + assembly, decoder alone, CRC baseline), following
/// the firmware's `chunk` lines (see [`per_byte`]).
fn split_regions(out: &str, counts: &[u64], bytes: usize, split: bool) -> Result<(u64, u64, u64)> {
    let extra = usize::from(split);
    let chunks: Vec<(u64, usize)> = out
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("chunk ")?;
            let (_, rest) = rest.split_once(": ")?;
            let mut w = rest.split_whitespace();
            let n = w.next()?.parse().ok()?;
            let s = w.nth(1)?.parse().ok()?;
            Some((n, s))
        })
        .collect();
    let want: usize = chunks.len() * (2 + extra) + 1;
    if counts.len() != want {
        return Err(format!(
            "the firmware's chunk lines call for {want} counted regions, the plugin reported {}",
            counts.len()
        ));
    }
    let (mut decode, mut alone, mut crc) = (0u64, 0u64, 0u64);
    let mut it = counts.iter();
    for _ in &chunks {
        decode += it.next().copied().unwrap_or(0);
        if split {
            alone += it.next().copied().unwrap_or(0);
        }
        crc += it.next().copied().unwrap_or(0);
    }
    decode += it.next().copied().unwrap_or(0);
    let received: u64 = chunks.iter().map(|&(n, _)| n).sum();
    if received != bytes as u64 {
        return Err(format!(
            "chunk lines add up to {received} bytes, {bytes} were sent"
        ));
    }
    Ok((decode, alone, crc))
}

#[cfg(test)]
mod tests {
    use super::split_regions;

    #[test]
    fn regions_follow_the_chunk_lines() {
        let out =
            "chunk 0: 10 bytes, 1 scans finished\nscan 0 ...\nchunk 1: 5 bytes, 0 scans finished\n";
        // Per chunk: decode + assembly, then the CRC; at the end, the finish.
        let counts = [300, 7, 50, 3, 4];
        assert_eq!(split_regions(out, &counts, 15, false), Ok((354, 0, 10)));
        // With the split, the decoder alone comes before each CRC.
        let counts = [300, 60, 7, 50, 30, 3, 4];
        assert_eq!(split_regions(out, &counts, 15, true), Ok((354, 90, 10)));
        // A region too many or a byte count that disagrees is an error.
        assert!(split_regions(out, &[1, 2, 3, 4, 5, 6], 15, false).is_err());
        assert!(split_regions(out, &[300, 7, 50, 3, 4], 16, false).is_err());
    }
}
