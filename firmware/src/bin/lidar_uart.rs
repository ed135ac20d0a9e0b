//! The sensor path through a real peripheral: a LiDAR byte stream received through USART1 of
//! the STM32F405 (QEMU `netduinoplus2`, run by `cargo xtask lidar`).
//!
//! The program sets up the receiver ([`beamfield_firmware::usart`]), prints its ready line
//! through semihosting (bytes sent before the receiver is on are lost, so the host waits for
//! it), then reads the stream: an 8-byte header of the test harness (`BFLD` and the stream's
//! length in bytes, little-endian u32; a real sensor needs none, it is how the program knows
//! where the test ends) followed by the sensor's bytes. They are taken in chunks of up to
//! [`CHUNK`] bytes into RAM, and each chunk is processed between the instruction-count markers
//! (so a counting run measures the processing, not the waiting for bytes). At the end it
//! prints the byte count and the CRC-32 of what it received, which the host compares with what
//! it sent.
#![no_std]
#![no_main]

use beamfield_firmware::usart::{UsartRx, LD06_CONFIG};
use beamfield_firmware::{bench_mark_end, bench_mark_start, exit, println};
use cortex_m_rt::entry;
use panic_semihosting as _;

/// Bytes received before a chunk is processed.
const CHUNK: usize = 4096;
/// The test harness's header: this tag, then the stream's length (u32, little-endian).
const MAGIC: [u8; 4] = *b"BFLD";
/// CRC-32 (ISO-HDLC, the zlib/PNG one) of the received bytes, for the transport check.
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

#[entry]
fn main() -> ! {
    let Some(dp) = stm32f4::stm32f405::Peripherals::take() else {
        println!("lidar_uart: device peripherals taken twice");
        exit(false)
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
        "lidar_uart: ready: USART1 receiving 8N1 at {} baud on PA10",
        LD06_CONFIG.baud
    );

    // Header: the tag (anything before it is skipped), then the length.
    let mut window = [0u8; 4];
    let mut reads = 0u32;
    while window != MAGIC {
        window = [window[1], window[2], window[3], rx.read_wfi()];
        reads += 1;
    }
    let mut len = [0u8; 4];
    for b in len.iter_mut() {
        *b = rx.read_wfi();
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
    let mut chunks = 0u32;
    while done < total {
        let n = (total - done).min(CHUNK);
        let chunk = &mut buf[..n];
        for b in chunk.iter_mut() {
            *b = rx.read_wfi();
        }
        bench_mark_start();
        core::hint::black_box(&*chunk);
        bench_mark_end();
        digest.update(chunk);
        done += n;
        chunks += 1;
    }
    println!(
        "stream: received {} bytes in {} chunks, crc32 {:08x}",
        done,
        chunks,
        digest.finalize()
    );
    let _ = rx.release();
    exit(true)
}
