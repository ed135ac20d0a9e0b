//! The sensor path through a real peripheral: an LD06 LiDAR byte stream received through
//! USART1 of the STM32F405 (QEMU `netduinoplus2`, run by `cargo xtask lidar`), decoded,
//! assembled into scans and scored against the Intel map linked into flash.
//!
//! The program sets up the receiver ([`beamfield_firmware::usart`]), prints its ready line
//! through semihosting (bytes sent before the receiver is on are lost, so the host waits for
//! it), then reads the stream: an 8-byte header of the test harness (`BFLD` and the stream's
//! length in bytes, little-endian u32; a real sensor sends none, it is how the program knows
//! where the test ends) followed by the sensor's bytes.
//!
//! The bytes are taken in chunks of up to [`CHUNK`] bytes into RAM (as a DMA or interrupt ring
//! buffer would hand them over) and pushed through the library's LD06 decoder into a
//! `ScanAssembler` on the Intel log's layout (180 beams, −90° … +89° counter-clockwise, sensor
//! at the centre), a chunk at a time (`Ld06Decoder::feed`). Decoding and assembly run between
//! the instruction-count markers; the scans finished in the chunk are queued and then scored
//! (`fixtures/src/lidar_plan.rs`, shared with the host's recomputation): the demo's tempered likelihood field at every pose of its coarse grid around
//! the scan's logged pose, and compared beam by beam with the log's ranges
//! (`fixtures/assets/lidar_segment.rs`: the 24 consecutive scans of the log the host encoded, with their
//! logged poses). After each chunk, with the feature `decode-split`, a
//! second decoder alone goes over the chunk (to split the cost between decoding and assembly),
//! then the chunk's CRC-32 is counted as a baseline. At the end: the assembler's pending revolution, the decoder's and the
//! assembler's counters, and the byte count and CRC-32 of everything received, which the host
//! compares with what it sent.
//!
//! The results go to the host as data (`beamfield_fixtures::report`): a [`LidarScan`] report
//! per scored scan, a [`LidarChunk`] per chunk, a [`LidarEnd`] with the counters and the
//! stream's byte count, CRC-32 and regions, each a `report: <hex>` line outside the counted
//! regions; the lines in words beside them are for a person.
//!
//! Exit status 1 when a scan could not be scored, had a beam that differs from the log, or more
//! scans were assembled than sent.
#![no_std]
#![no_main]

use beamfield::lidar::ld06::Ld06Decoder;
use beamfield::lidar::ScanAssembler;
use beamfield::{Pose, Scan};
use beamfield_firmware::usart::{UsartRx, LD06_CONFIG};
use beamfield_firmware::{bench_mark_end, exit, println, send_report, start_region, Fixed};
use beamfield_fixtures::regions::lidar;
use beamfield_fixtures::report::{LidarChunk, LidarEnd, LidarScan, Report};
use cortex_m_rt::entry;
use panic_semihosting as _;

use beamfield_fixtures::demo_plan::{offset, POSES};
use beamfield_fixtures::lidar_plan;
use lidar_plan::segment::{MAX_RANGE_M, SCANS};
use lidar_plan::{Setup, BEAMS};

/// The 5 cm distance field of the Intel map (the demo's).
static BLOB: &[u8] = include_bytes!("../../assets/intel.bin");

/// Bytes received before a chunk is processed.
const CHUNK: usize = 4096;
/// The test harness's header: this tag, then the stream's length (u32, little-endian).
const MAGIC: [u8; 4] = *b"BFLD";
/// CRC-32 (ISO-HDLC, the zlib/PNG one) of the received bytes, for the transport check.
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Scores and reports the `k`-th assembled scan; false when it could not be (no such scan in
/// the plan, weights not normalizable) or does not match the log.
fn report(k: usize, setup: &Setup<'_>, done: &Finished, weights: &mut [f32; POSES]) -> bool {
    let Some(demo) = SCANS.get(k) else {
        println!(
            "scan {}: more revolutions than the {} scans sent",
            k,
            SCANS.len()
        );
        return false;
    };
    let scan = &done.scan;
    let logged = Pose::new(demo.pose[0], demo.pose[1], demo.pose[2]);
    let m = lidar_plan::compare(scan, &demo.ranges_m, MAX_RANGE_M);
    let scored = match lidar_plan::score(setup, scan, &logged, weights) {
        Ok(s) => s,
        Err(e) => {
            println!("scan {}: weights not normalizable: {}", k, e);
            return false;
        }
    };
    let (d_m, dth_deg, _) = offset(&scored.best, &logged);
    send_report!(Report::LidarScan(LidarScan::of(
        u32::try_from(k).unwrap_or(u32::MAX),
        demo.log_index,
        done.points,
        &m,
        &scored
    )));
    println!(
        "scan {} (log line {}): {} points; {} beams valid; vs log: {} match, {} missing, {} wrong; best ({}, {}, {} deg) offset {} cm {} deg; log-likelihood {} ESS {}",
        k,
        demo.log_index,
        done.points,
        scored.valid,
        m.matching,
        m.missing,
        m.wrong,
        Fixed::new(f64::from(scored.best.x_m), 3),
        Fixed::new(f64::from(scored.best.y_m), 3),
        Fixed::new(f64::from(scored.best.theta_rad.to_degrees()), 1),
        Fixed::new(f64::from(d_m) * 100.0, 1),
        Fixed::new(f64::from(dth_deg), 1),
        Fixed::new(f64::from(scored.log_likelihood), 3),
        Fixed::new(f64::from(scored.ess), 1),
    );
    m.wrong == 0
}

/// A scan the assembler finished, kept until it is scored (outside the counted region).
#[derive(Clone)]
struct Finished {
    scan: Scan<BEAMS>,
    /// Points of its revolution.
    points: u32,
}

/// Scans finished within one chunk, in order. A chunk of [`CHUNK`] bytes holds at most three
/// whole LD06 revolutions of 1,410 bytes; a stream of shorter revolutions (a damaged line
/// cutting revolutions short) fills the queue and the rest are counted as dropped.
struct Queue {
    scans: [Option<Finished>; QUEUE],
    len: usize,
    dropped: u32,
}

/// Scans a chunk can finish before the queue is full.
const QUEUE: usize = 6;

/// Feeds `chunk` to the decoder (`Ld06Decoder::feed`, the slice interface a DMA or interrupt
/// buffer uses) and its points to the assembler, queueing every finished scan.
///
/// The counted work, kept out of line so that what the compiler makes of it does not depend on
/// the rest of `main`.
#[inline(never)]
fn decode_chunk(
    decoder: &mut Ld06Decoder,
    assembler: &mut ScanAssembler<BEAMS>,
    chunk: &[u8],
    queue: &mut Queue,
) {
    decoder.feed(chunk, |p| {
        if let Some(scan) = assembler.push(p) {
            let done = Finished {
                scan: scan.clone(),
                points: assembler.revolution().points,
            };
            match queue.scans.get_mut(queue.len) {
                Some(slot) => {
                    *slot = Some(done);
                    queue.len += 1;
                }
                None => queue.dropped += 1,
            }
        }
    });
}

/// The decoder alone over `chunk` (feature `decode-split`): the points it hands over.
#[cfg(feature = "decode-split")]
#[inline(never)]
fn decode_alone(decoder: &mut Ld06Decoder, chunk: &[u8]) -> u32 {
    let mut points = 0u32;
    decoder.feed(chunk, |_| points += 1);
    points
}

/// The baseline: the CRC-32 digest over `chunk` (out of line, like the counted work).
#[inline(never)]
fn crc_chunk(digest: &mut crc::Digest<'_, u32>, chunk: &[u8]) {
    digest.update(chunk);
}

#[entry]
fn main() -> ! {
    let Some(dp) = stm32f4::stm32f405::Peripherals::take() else {
        println!("lidar_uart: device peripherals taken twice");
        exit(false)
    };
    let setup = match lidar_plan::setup(BLOB, MAX_RANGE_M) {
        Ok(s) => s,
        Err(e) => {
            println!("lidar_uart: {}", e);
            exit(false)
        }
    };
    let mut assembler = match lidar_plan::assembler(&setup) {
        Ok(a) => a,
        Err(e) => {
            println!("lidar_uart: assembler rejected: {}", e);
            exit(false)
        }
    };
    let mut decoder = Ld06Decoder::new();
    #[cfg(feature = "decode-split")]
    let mut decode_only = Ld06Decoder::new();
    #[cfg(feature = "decode-split")]
    let mut decode_only_points = 0u32;
    let mut weights = [0.0f32; POSES];
    let mut queue = Queue {
        scans: [const { None }; QUEUE],
        len: 0,
        dropped: 0,
    };
    let mut rx = match UsartRx::new(dp.USART1, &dp.RCC, &dp.GPIOA, LD06_CONFIG) {
        Ok(rx) => rx,
        Err(e) => {
            println!("lidar_uart: USART1 rejected: {}", e);
            exit(false)
        }
    };
    rx.enable_wakeup();
    println!(
        "lidar_uart: ready: USART1 receiving 8N1 at {} baud on PA10; LD06 decoder, {}-beam Intel layout, {} poses per scan",
        LD06_CONFIG.baud, BEAMS, POSES
    );

    // Header: the tag (anything before it is skipped), then the length.
    let mut window = [0u8; 4];
    let mut reads = 0u32;
    while window != MAGIC {
        window = [window[1], window[2], window[3], rx.read_wfi()];
        reads += 1;
    }
    // The length through the driver's embedded-hal-nb interface (polling).
    let mut len = [0u8; 4];
    for b in len.iter_mut() {
        match embedded_hal_nb::nb::block!(embedded_hal_nb::serial::Read::read(&mut rx)) {
            Ok(byte) => *b = byte,
            Err(e) => {
                println!("lidar_uart: line error in the header: {:?}", e);
                exit(false)
            }
        }
    }
    let total = u32::from_le_bytes(len) as usize;
    println!(
        "stream: {} bytes announced ({} bytes before the header)",
        total,
        reads - 4
    );

    let mut buf = [0u8; CHUNK];
    let mut digest = CRC32.digest();
    let mut done = 0usize;
    let (mut chunks, mut regions) = (0u32, 0u32);
    let mut scans = 0usize;
    let mut ok = true;
    while done < total {
        let n = (total - done).min(CHUNK);
        let chunk = &mut buf[..n];
        for b in chunk.iter_mut() {
            *b = rx.read_wfi();
        }
        // Decode and assemble between the counting markers; the scans finished in the chunk
        // are scored after the region.
        start_region!(lidar::DECODE_ASSEMBLE.name);
        decode_chunk(&mut decoder, &mut assembler, chunk, &mut queue);
        bench_mark_end();
        regions += 1;
        let finished = queue.len;
        for done in queue.scans.iter_mut().take(finished) {
            if let Some(done) = done.take() {
                ok &= report(scans, &setup, &done, &mut weights);
                scans += 1;
            }
        }
        queue.len = 0;
        // With the feature `decode-split`: the decoder alone over the same bytes (a second
        // decoder, whose points are only counted), to split the cost between decoding and
        // assembly. Off by default: the second caller changes what the compiler inlines into
        // the main path, and so its count.
        #[cfg(feature = "decode-split")]
        {
            start_region!(lidar::DECODE_ALONE.name);
            decode_only_points += decode_alone(&mut decode_only, chunk);
            bench_mark_end();
            regions += 1;
        }
        // The baseline of the same run: a table-driven CRC-32 over the same bytes.
        start_region!(lidar::CRC.name);
        crc_chunk(&mut digest, chunk);
        bench_mark_end();
        regions += 1;
        send_report!(Report::LidarChunk(LidarChunk {
            bytes: u32::try_from(n).unwrap_or(u32::MAX),
            scans: u32::try_from(finished).unwrap_or(u32::MAX),
        }));
        println!("chunk {}: {} bytes, {} scans finished", chunks, n, finished);
        done += n;
        chunks += 1;
    }
    // The end of the recording: the pending revolution.
    start_region!(lidar::FINISH.name);
    let last = assembler.finish().is_some();
    bench_mark_end();
    regions += 1;
    if last {
        let done = Finished {
            scan: assembler.scan().clone(),
            points: assembler.revolution().points,
        };
        ok &= report(scans, &setup, &done, &mut weights);
        scans += 1;
    }
    if queue.dropped > 0 {
        println!(
            "lidar_uart: {} scans dropped (more than {} finished in one chunk)",
            queue.dropped, QUEUE
        );
        ok = false;
    }
    let d = decoder.stats();
    #[cfg(feature = "decode-split")]
    if decode_only.stats() != d || decode_only_points != d.points {
        println!("lidar_uart: the second decoder disagrees with the first");
        ok = false;
    }
    println!(
        "decoder: {} bytes, {} frames ok, {} bad checksums, {} bad frames, {} bytes skipped in {} resyncs, {} points",
        d.bytes, d.frames_ok, d.bad_checksum, d.bad_frames, d.skipped_bytes, d.resyncs, d.points
    );
    let a = assembler.stats();
    let crc32 = digest.finalize();
    send_report!(Report::LidarEnd(LidarEnd {
        decoder: d,
        assembler: a,
        received: u32::try_from(done).unwrap_or(u32::MAX),
        chunks,
        crc32,
        scans: u32::try_from(scans).unwrap_or(u32::MAX),
        regions,
        dropped: queue.dropped,
    }));
    println!(
        "assembler: {} points, {} accepted, {} flagged invalid, {} out of range, {} low quality, {} bad angle, {} outside the layout, {} replaced, {} revolutions",
        a.points,
        a.accepted,
        a.flagged_invalid,
        a.out_of_range,
        a.low_quality,
        a.bad_angle,
        a.outside_layout,
        a.replaced,
        a.revolutions
    );
    println!(
        "stream: received {} bytes in {} chunks, crc32 {:08x}; {} scans; {} counted regions",
        done, chunks, crc32, scans, regions
    );
    let _ = rx.release();
    exit(ok)
}
