//! Decoding a LiDAR byte stream: the protocol's decoder and the scan assembler fed chunk by
//! chunk, within the capture and scan limits.

use super::{Format, LidarError};
use beamfield::lidar::ld06::Ld06Decoder;
use beamfield::lidar::rplidar::RplidarDecoder;
use beamfield::lidar::xv11::Xv11Decoder;
use beamfield::lidar::ydlidar::YdlidarDecoder;
use beamfield::lidar::{
    AssemblerConfig, AssemblerStats, DecoderStats, LidarPoint, Revolution, ScanAssembler,
};
use beamfield::BeamLayout;
use std::path::Path;

/// One of the four decoders.
#[derive(Clone, Debug)]
pub enum AnyDecoder {
    /// LD06 family.
    Ld06(Ld06Decoder),
    /// RPLIDAR (waiting for the scan descriptor).
    Rplidar(RplidarDecoder),
    /// XV-11.
    Xv11(Xv11Decoder),
    /// YDLIDAR, triangulation angle correction (boxed: it holds a 520-byte packet buffer).
    Ydlidar(Box<YdlidarDecoder>),
}

impl AnyDecoder {
    /// A fresh decoder for `format`.
    pub fn new(format: Format) -> Self {
        match format {
            Format::Ld06 => Self::Ld06(Ld06Decoder::new()),
            Format::Rplidar => Self::Rplidar(RplidarDecoder::new()),
            Format::Xv11 => Self::Xv11(Xv11Decoder::new()),
            Format::Ydlidar => Self::Ydlidar(Box::new(YdlidarDecoder::new())),
        }
    }

    /// Feeds bytes (see each decoder's `feed`).
    pub fn feed(&mut self, bytes: &[u8], on_point: impl FnMut(LidarPoint)) {
        match self {
            Self::Ld06(d) => d.feed(bytes, on_point),
            Self::Rplidar(d) => d.feed(bytes, on_point),
            Self::Xv11(d) => d.feed(bytes, on_point),
            Self::Ydlidar(d) => d.feed(bytes, on_point),
        }
    }

    /// The end of a recording: hands out what a decoder holds back (the YDLIDAR decoder's last
    /// packet, which waits for the next packet's header); nothing for the others.
    pub fn finish(&mut self, on_point: impl FnMut(LidarPoint)) {
        if let Self::Ydlidar(d) = self {
            d.flush(on_point);
        }
    }

    /// The decoder's counters.
    pub fn stats(&self) -> DecoderStats {
        match self {
            Self::Ld06(d) => d.stats(),
            Self::Rplidar(d) => d.stats(),
            Self::Xv11(d) => d.stats(),
            Self::Ydlidar(d) => d.stats(),
        }
    }
}

/// The scans decoded from a stream.
#[derive(Clone, Debug)]
pub struct Decoded {
    /// Each emitted scan's ranges (NaN for empty beams).
    pub scans: Vec<Vec<f32>>,
    /// Each emitted scan's revolution record.
    pub revolutions: Vec<Revolution>,
    /// The decoder's counters at the end.
    pub decoder: DecoderStats,
    /// The assembler's counters at the end.
    pub assembler: AssemblerStats,
}

/// A decoder and an assembler fed a stream chunk by chunk, keeping at most `max_scans` scans.
pub struct StreamDecoder<const N: usize> {
    decoder: AnyDecoder,
    assembler: ScanAssembler<N>,
    scans: Vec<Vec<f32>>,
    revolutions: Vec<Revolution>,
    max_scans: usize,
    overflow: bool,
}

impl<const N: usize> StreamDecoder<N> {
    /// A decoder for `format` assembling on `layout`, keeping at most `max_scans` scans.
    ///
    /// # Errors
    /// [`LidarError::Assembler`] for a layout the assembler cannot bin.
    pub fn new(
        format: Format,
        layout: &BeamLayout<N>,
        config: AssemblerConfig,
        max_scans: usize,
    ) -> Result<Self, LidarError> {
        Ok(Self {
            decoder: AnyDecoder::new(format),
            assembler: ScanAssembler::new(layout, config).map_err(LidarError::Assembler)?,
            scans: Vec::new(),
            revolutions: Vec::new(),
            max_scans,
            overflow: false,
        })
    }

    /// Feeds `bytes` (`None`: the end of the stream) and keeps the scans completed.
    fn run(&mut self, bytes: Option<&[u8]>) -> Result<(), LidarError> {
        let Self {
            decoder,
            assembler,
            scans,
            revolutions,
            max_scans,
            overflow,
        } = self;
        let mut keep = |assembler: &ScanAssembler<N>| {
            if scans.len() >= *max_scans {
                *overflow = true;
            } else {
                scans.push(assembler.scan().ranges_m().to_vec());
                revolutions.push(assembler.revolution());
            }
        };
        let mut on_point = |p| {
            if assembler.push(p).is_some() {
                keep(assembler);
            }
        };
        match bytes {
            Some(b) => decoder.feed(b, &mut on_point),
            None => {
                decoder.finish(&mut on_point);
                if assembler.finish().is_some() {
                    keep(assembler);
                }
            }
        }
        if *overflow {
            Err(LidarError::TooManyScans)
        } else {
            Ok(())
        }
    }

    /// Feeds the next bytes of the stream.
    ///
    /// # Errors
    /// [`LidarError::TooManyScans`] once more than `max_scans` scans were assembled.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<(), LidarError> {
        self.run(Some(bytes))
    }

    /// The end of the stream: what the decoder held back, and the last, unfinished revolution.
    ///
    /// # Errors
    /// [`LidarError::TooManyScans`].
    pub fn finish(mut self) -> Result<Decoded, LidarError> {
        self.run(None)?;
        Ok(Decoded {
            decoder: self.decoder.stats(),
            assembler: self.assembler.stats(),
            scans: self.scans,
            revolutions: self.revolutions,
        })
    }
}

/// Decodes `bytes` in `format` and assembles the points on `layout` (the last, unfinished
/// revolution is emitted too).
///
/// # Errors
/// [`LidarError::Assembler`] for a layout the assembler cannot bin,
/// [`LidarError::TooManyScans`] past [`crate::input::limits::MAX_DECODED_SCANS`].
pub fn decode_stream<const N: usize>(
    format: Format,
    layout: &BeamLayout<N>,
    config: AssemblerConfig,
    bytes: &[u8],
) -> Result<Decoded, LidarError> {
    let mut d = StreamDecoder::new(
        format,
        layout,
        config,
        crate::input::limits::MAX_DECODED_SCANS,
    )?;
    d.feed(bytes)?;
    d.finish()
}

/// Bytes at the start of a capture that [`sniff`] tries every decoder on: 16 KiB, at least 340
/// frames of any of the protocols (an XV-11 packet is 22 bytes, a full YDLIDAR packet 90, an
/// LD06 frame 47), after the few hundred bytes a sensor may send before its first frame.
pub const SNIFF_BYTES: usize = 16 * 1024;

/// The frames each protocol's decoder finds in `head` (the start of a stream), in the order of
/// [`Format::ALL`].
pub fn sniff(head: &[u8]) -> Vec<(Format, u32)> {
    Format::ALL
        .iter()
        .map(|&f| {
            let mut d = AnyDecoder::new(f);
            d.feed(head, |_| {});
            d.finish(|_| {});
            (f, d.stats().frames_ok)
        })
        .collect()
}

/// The protocol other than `not` whose decoder finds the most frames in `head`; `None` when
/// none finds one.
pub fn looks_like(head: &[u8], not: Format) -> Option<Format> {
    sniff(head)
        .into_iter()
        .filter(|&(f, n)| f != not && n > 0)
        .max_by_key(|&(_, n)| n)
        .map(|(f, _)| f)
}

/// What [`decode_path`] read from a capture.
#[derive(Clone, Debug)]
pub struct Capture {
    /// The scans and counters.
    pub decoded: Decoded,
    /// Bytes read.
    pub bytes: u64,
    /// The first [`SNIFF_BYTES`] bytes (fewer for a shorter capture), kept for [`sniff`]: a
    /// FIFO or a device cannot be read twice.
    pub head: Vec<u8>,
}

/// Decodes the capture at `path` (a file, a FIFO or a device: read as a stream, in chunks, never
/// held whole) in `format` on `layout`; returns the scans, the number of bytes read and the
/// capture's first bytes.
///
/// # Errors
/// [`LidarError::Io`], [`LidarError::CaptureTooLarge`] past `max_bytes`,
/// [`LidarError::TooManyScans`] past `max_scans`, [`LidarError::Assembler`].
pub fn decode_path<const N: usize>(
    path: &Path,
    format: Format,
    layout: &BeamLayout<N>,
    config: AssemblerConfig,
    max_bytes: u64,
    max_scans: usize,
) -> Result<Capture, LidarError> {
    use std::io::Read;
    let io = |e| LidarError::Io(path.to_path_buf(), e);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut d = StreamDecoder::new(format, layout, config, max_scans)?;
    let mut chunk = vec![0u8; 64 * 1024];
    let mut head = Vec::new();
    let mut total = 0u64;
    loop {
        let n = match file.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e)),
        };
        total += n as u64;
        if total > max_bytes {
            return Err(LidarError::CaptureTooLarge(path.to_path_buf()));
        }
        let bytes = chunk.get(..n).unwrap_or(&[]);
        let keep = SNIFF_BYTES.saturating_sub(head.len()).min(bytes.len());
        head.extend_from_slice(bytes.get(..keep).unwrap_or(&[]));
        d.feed(bytes)?;
    }
    Ok(Capture {
        decoded: d.finish()?,
        bytes: total,
        head,
    })
}
