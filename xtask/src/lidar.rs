//! `cargo xtask lidar`: the sensor path through a real emulated peripheral. A byte stream is
//! sent into USART1 of QEMU's `netduinoplus2` (STM32F405) through a socket chardev, the
//! firmware (`firmware/src/bin/lidar_uart.rs`) receives it with its register-level driver and
//! reports, and the report is checked here against what was sent.

use crate::cross::build_program;
use crate::error::{Error, Result};
use crate::insncount::{qemu_args, Regions};
use crate::process::repo_root;
use crate::qemu::{ensure_qemu, failure, run_with_uart, Board};
use crate::report::readable;
use beamfield_fixtures::regions::lidar as regions;
use beamfield_fixtures::report::LidarChunk;
use std::fs;

/// The firmware program.
const BIN: &str = "lidar_uart";
/// The line the firmware prints once its receiver is on (bytes sent earlier are lost).
const READY: &str = "lidar_uart: ready";
/// The test harness's header before the stream: this tag and the length (u32, little-endian).
const MAGIC: &[u8; 4] = b"BFLD";
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

/// Runs the sensor path: streams the LD06 stream into the emulated USART, checks the transport
/// (count and CRC-32), the plan's expectations (frames, corrupted beams, no wrong beam, every
/// scan's best pose near its logged pose) and the host's recomputation to the printed digits,
/// and with `count` the instructions per received byte of decode + assembly.
/// With `split` (implies `count`), the firmware also counts a second decoder alone over the
/// same bytes.
pub fn lidar(count: bool, split: bool) -> Result {
    ensure_qemu()?;
    let count = count || split;
    let elf = build_program(
        Board::Netduinoplus2,
        BIN,
        if split { &["decode-split"] } else { &[] },
    )?;
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
        qemu_args(&elf, ", or run `cargo xtask lidar --no-count`")?
    } else {
        Vec::new()
    };
    let len =
        u32::try_from(stream.len()).map_err(|_| Error::Host("stream longer than 4 GiB".into()))?;
    let mut header = MAGIC.to_vec();
    header.extend_from_slice(&len.to_le_bytes());
    let uart = run_with_uart(&elf, READY, &header, stream, &extra)?;
    let run = &uart.finished;
    // The report, without the plugin's lines (they go to stderr) and the region names.
    print!("{}", readable(&run.stdout));
    if run.code != 0 {
        eprint!("{}", run.stderr);
        return Err(failure(
            run.code,
            &format!("`{BIN}`"),
            "netduinoplus2",
            "a scan could not be scored or did not match the log",
        ));
    }

    // The device's data: its reports, decoded (nothing below is read from its text).
    let device = crate::lidar_ref::DeviceReport::read(&run.stdout)?;

    // 1. Transport: every byte, in order.
    let want = CRC32.checksum(stream);
    let (bytes, crc) = (device.end.received as usize, device.end.crc32);
    if bytes != stream.len() || crc != want {
        return Err(Error::Mismatch(format!(
            "transport: sent {} bytes with crc32 {want:08x}, the firmware received {bytes} with crc32 {crc:08x}",
            stream.len()
        )));
    }
    println!(
        "transport: all {} bytes received in order through USART1 (crc32 {want:08x} on both sides), {:.1} s in QEMU ({:.1} KB/s end to end)",
        stream.len(),
        uart.elapsed.as_secs_f64(),
        stream.len() as f64 / 1e3 / uart.elapsed.as_secs_f64()
    );

    // 2. The host's recomputation.
    let blob_path = repo_root().join("firmware/assets/intel.bin");
    let blob = fs::read(&blob_path).map_err(|e| Error::io(&blob_path, e))?;
    let reference = crate::lidar_ref::reference(stream, &blob)?;
    let (scans, identical) = crate::lidar_ref::check(&device, &reference)?;
    println!(
        "host reference: the host decodes, assembles and scores the same stream with the same crate: all {scans} scans (points, beams, log comparison exactly; best pose to 0.5 mm and 0.05 deg, log-likelihood to 0.0005, ESS to 0.05; {identical} of them bit for bit) and the decoder's and assembler's counters (exactly) agree with the device's reports"
    );

    // 3. What the plan alone says (not the code under test).
    let flips = crate::lidar_ref::FLIPS.len() as u32;
    let frames_ok = (plan.frames as u32) - flips;
    let decoded = &reference.decoder;
    if decoded.frames_ok != frames_ok || decoded.bad_checksum != flips {
        return Err(Error::Requirement(format!(
            "the plan has {frames_ok} intact frames and {flips} corrupted ones; the decoder passed {} and rejected {}",
            decoded.frames_ok, decoded.bad_checksum
        )));
    }
    // Every frame of the plan is a 360-point revolution's at 3,600 °/s (11° per frame, the
    // plausible span at that speed is up to 28.8°): none may be taken for damage.
    if decoded.implausible_frames != 0 {
        return Err(Error::Requirement(format!(
            "the plan's frames are all plausible; the decoder took {} for damage",
            decoded.implausible_frames
        )));
    }
    if reference.scans.len() != plan.scans {
        return Err(Error::Requirement(format!(
            "{} revolutions sent, {} scans assembled",
            plan.scans,
            reference.scans.len()
        )));
    }
    let mut worst = (0.0f32, 0.0f32);
    for (k, s) in reference.scans.iter().enumerate() {
        let r = &s.report;
        if r.wrong != 0 || r.missing != plan.missing[k] {
            return Err(Error::Requirement(format!(
                "scan {k}: the plan leaves {} beams missing and none wrong; the device has {} missing, {} wrong",
                plan.missing[k], r.missing, r.wrong
            )));
        }
        worst = (worst.0.max(s.offset.0), worst.1.max(s.offset.1.abs()));
        if s.offset.0 > ACCEPT_M || s.offset.1.abs() > ACCEPT_DEG {
            return Err(Error::Requirement(format!(
                "scan {k}: best pose {:.1} cm and {:.1} deg from the logged pose (accepted: {} cm, {} deg)",
                s.offset.0 * 100.0,
                s.offset.1,
                ACCEPT_M * 100.0,
                ACCEPT_DEG
            )));
        }
    }
    let mean_deg = reference.scans.iter().map(|s| s.offset.1).sum::<f32>()
        / reference.scans.len().max(1) as f32;
    if mean_deg.abs() > ACCEPT_MEAN_DEG {
        return Err(Error::Requirement(format!(
            "the best headings are {mean_deg:.2} deg from the logged ones on average (accepted: {ACCEPT_MEAN_DEG} deg): are the scans turned?"
        )));
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
        let counted = Regions::read(&run.stdout, &run.stderr)?;
        let regions = device.end.regions as usize;
        if regions != counted.len() {
            return Err(Error::Regions(format!(
                "the firmware marked {regions} regions, the plugin counted {}",
                counted.len()
            )));
        }
        per_byte(&device.chunks, &counted, stream.len(), split)?;
    }
    Ok(())
}

/// Splits the counted regions into decode + assembly, decode alone (with `split`) and the CRC
/// baseline by name, checks them against the firmware's `LidarChunk` reports (each chunk: the decode +
/// assembly region, then with `split` the decoder alone, then the CRC; at the end, the
/// assembler's finish), and prints the per-byte figures.
fn per_byte(chunks: &[LidarChunk], counted: &Regions, bytes: usize, split: bool) -> Result {
    let (decode, alone, crc) = split_regions(chunks, counted, bytes, split)?;
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

/// The sums of the counted regions: (decode + assembly with the assembler's finish, decoder
/// alone, CRC baseline), each region taken by name and as many times as the firmware's
/// `LidarChunk` reports say (see [`per_byte`]).
fn split_regions(
    chunks: &[LidarChunk],
    counted: &Regions,
    bytes: usize,
    split: bool,
) -> Result<(u64, u64, u64)> {
    let expected: &[_] = if split {
        &regions::ALL
    } else {
        &[regions::DECODE_ASSEMBLE, regions::CRC, regions::FINISH]
    };
    counted.expect(expected)?;
    let (decode, decodes) = counted.sum(regions::DECODE_ASSEMBLE.name);
    let (alone, alones) = counted.sum(regions::DECODE_ALONE.name);
    let (crc, crcs) = counted.sum(regions::CRC.name);
    let finish = counted.once(regions::FINISH.name)?;
    let n = chunks.len();
    if (decodes, alones, crcs) != (n, if split { n } else { 0 }, n) {
        return Err(Error::Regions(format!(
            "the firmware's {n} chunk reports call for {n} decode and CRC regions each, it measured \
             {decodes} decode, {alones} decoder-alone and {crcs} CRC regions"
        )));
    }
    let received: u64 = chunks.iter().map(|c| u64::from(c.bytes)).sum();
    if received != bytes as u64 {
        return Err(Error::Mismatch(format!(
            "chunk reports add up to {received} bytes, {bytes} were sent"
        )));
    }
    Ok((decode + finish, alone, crc))
}

#[cfg(test)]
mod tests {
    use super::split_regions;
    use crate::insncount::Regions;
    use beamfield_fixtures::report::LidarChunk;

    /// The regions of `names` with the plugin's `counts`, as one run reports them.
    fn counted(names: &[&str], counts: &[u64]) -> Regions {
        let out: String = names.iter().map(|n| format!("region: {n}\n")).collect();
        let log: String = counts
            .iter()
            .enumerate()
            .map(|(k, c)| format!("insncount: region {k}: {c} instructions\n"))
            .collect();
        Regions::read(&out, &log).expect("as many names as counts")
    }

    #[test]
    fn regions_follow_the_chunk_reports() {
        let out = &[
            LidarChunk {
                bytes: 10,
                scans: 1,
            },
            LidarChunk { bytes: 5, scans: 0 },
        ];
        // Per chunk: decode + assembly, then the CRC; at the end, the finish.
        let plain = ["decode-assemble", "crc", "decode-assemble", "crc", "finish"];
        let r = counted(&plain, &[300, 7, 50, 3, 4]);
        assert_eq!(split_regions(out, &r, 15, false).ok(), Some((354, 0, 10)));
        // With the split, the decoder alone comes before each CRC.
        let split = [
            "decode-assemble",
            "decode-alone",
            "crc",
            "decode-assemble",
            "decode-alone",
            "crc",
            "finish",
        ];
        let r = counted(&split, &[300, 60, 7, 50, 30, 3, 4]);
        assert_eq!(split_regions(out, &r, 15, true).ok(), Some((354, 90, 10)));
        // A region too many, a region not expected or a byte count that disagrees is an error.
        let r = counted(&plain[..4], &[1, 2, 3, 4]);
        assert!(split_regions(out, &r, 15, false).is_err());
        let r = counted(&split, &[300, 60, 7, 50, 30, 3, 4]);
        assert!(split_regions(out, &r, 15, false).is_err());
        let r = counted(&plain, &[300, 7, 50, 3, 4]);
        assert!(split_regions(out, &r, 16, false).is_err());
    }
}
