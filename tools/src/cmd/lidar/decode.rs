//! `beamfield lidar decode`: a LiDAR byte stream decoded into scans, with the decoder's and
//! the assembler's counters; optionally one scan drawn as a polar plot.

use crate::lidar_stream::{
    decode_path, layout, looks_like, Decoded, Format, LayoutChoice, LidarError,
};
use beamfield::lidar::{AssemblerConfig, AssemblerStats, DecoderStats};
use clap::Args;
use serde::{Serialize, Serializer};
use std::fmt;
use std::path::PathBuf;

/// Arguments of `beamfield lidar decode`.
#[derive(Args, Debug)]
pub struct DecodeArgs {
    /// The stream file.
    pub stream: PathBuf,
    /// The sensor protocol.
    #[arg(long, value_enum)]
    pub format: Format,
    /// The beams to assemble on.
    #[arg(long, value_enum, default_value = "full")]
    pub layout: LayoutChoice,
    /// Maximum range of the layout, metres (default: the protocol's largest distance).
    #[arg(long, value_name = "M")]
    pub max_range: Option<f32>,
    /// Reject points nearer than this, metres.
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub min_range: f32,
    /// Reject points whose quality is below this (protocol units).
    #[arg(long, default_value_t = 0, value_name = "Q")]
    pub min_quality: u16,
    /// Draw this scan (index among the decoded ones; default: the last) as a polar plot.
    #[arg(long, value_name = "K")]
    pub scan: Option<usize>,
    /// Also print every scan's ranges (JSON: `scans[k].ranges_m`, null for empty beams).
    #[arg(long)]
    pub ranges: bool,
    /// Polar plot of one scan (PNG).
    #[arg(short, long, value_name = "polar.png")]
    pub output: Option<PathBuf>,
}
/// What `lidar decode` found.
#[derive(Debug)]
pub struct LidarDecodeReport {
    /// The protocol's name.
    pub format: &'static str,
    /// Bytes read.
    pub bytes: u64,
    /// The scans and counters.
    pub decoded: Decoded,
    /// Every scan's ranges are reported (`--ranges`).
    pub ranges: bool,
}

fn stats_json(d: &DecoderStats) -> serde_json::Value {
    serde_json::json!({
        "bytes": d.bytes,
        "frames_ok": d.frames_ok,
        "bad_checksum": d.bad_checksum,
        "bad_frames": d.bad_frames,
        "implausible_frames": d.implausible_frames,
        "skipped_bytes": d.skipped_bytes,
        "resyncs": d.resyncs,
        "points": d.points,
    })
}

fn assembler_json(a: &AssemblerStats) -> serde_json::Value {
    serde_json::json!({
        "points": a.points,
        "accepted": a.accepted,
        "flagged_invalid": a.flagged_invalid,
        "out_of_range": a.out_of_range,
        "low_quality": a.low_quality,
        "bad_angle": a.bad_angle,
        "outside_layout": a.outside_layout,
        "replaced": a.replaced,
        "revolutions": a.revolutions,
        "missed_revolutions": a.missed_revolutions,
    })
}

/// Runs `lidar decode`.
///
/// # Errors
/// [`LidarError`].
pub fn run(a: &DecodeArgs) -> Result<LidarDecodeReport, LidarError> {
    let max_range = a.max_range.unwrap_or(a.format.field_max_m() + 1.0);
    let layout = layout(a.layout, max_range)?;
    let config = AssemblerConfig {
        min_range_m: a.min_range,
        max_range_m: max_range,
        min_quality: a.min_quality,
        ..AssemblerConfig::for_layout(&layout)
    };
    crate::progress::note(&format!("decoding {} …", a.stream.display()));
    let capture = decode_path(
        &a.stream,
        a.format,
        &layout,
        config,
        crate::input::limits::MAX_CAPTURE_BYTES,
        crate::input::limits::MAX_DECODED_SCANS,
    )?;
    // Not one frame: the wrong --format (or not a LiDAR stream at all). Said as such, with the
    // protocol whose decoder does find frames, rather than "0 frames ok" and success.
    if capture.decoded.decoder.frames_ok == 0 {
        return Err(LidarError::NotThisFormat {
            path: a.stream.clone(),
            format: a.format,
            bytes: capture.bytes,
            looks_like: looks_like(&capture.head, a.format),
        });
    }
    let (d, bytes) = (capture.decoded, capture.bytes);
    if let Some(path) = &a.output {
        let k = a.scan.unwrap_or(d.scans.len().saturating_sub(1));
        let ranges = d.scans.get(k).ok_or_else(|| {
            LidarError::BadOption(format!("--scan {k}: only {} scans decoded", d.scans.len()))
        })?;
        crate::draw::polar::polar_png(
            path,
            &layout,
            ranges,
            &format!("{} scan {k}", a.format.name()),
        )
        .map_err(LidarError::Plot)?;
    }
    Ok(LidarDecodeReport {
        format: a.format.name(),
        bytes,
        decoded: d,
        ranges: a.ranges,
    })
}

impl Serialize for LidarDecodeReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let scans: Vec<serde_json::Value> = self
            .decoded
            .revolutions
            .iter()
            .zip(&self.decoded.scans)
            .map(|(r, s)| {
                let mut v = serde_json::json!({
                    "index": r.index,
                    "points": r.points,
                    "filled": r.filled,
                    "start_timestamp_ms": r.start_timestamp_ms,
                    "end_timestamp_ms": r.end_timestamp_ms,
                });
                if self.ranges {
                    v["ranges_m"] = s
                        .iter()
                        .map(|&x| {
                            if x.is_finite() {
                                serde_json::Value::from(f64::from(x))
                            } else {
                                serde_json::Value::Null
                            }
                        })
                        .collect();
                }
                v
            })
            .collect();
        serde_json::json!({
            "format": self.format,
            "bytes": self.bytes,
            "decoder": stats_json(&self.decoded.decoder),
            "assembler": assembler_json(&self.decoded.assembler),
            "scans": scans,
        })
        .serialize(s)
    }
}

impl fmt::Display for LidarDecodeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.decoded.decoder;
        let asm = &self.decoded.assembler;
        let mut out = format!(
        "{}: {} bytes, {} frames ok, {} bad checksum, {} bad frames, {} implausible frames, {} bytes skipped ({} resyncs)\n\
         {} points: {} binned, {} flagged invalid, {} out of range, {} low quality, {} outside the layout, {} replaced\n\
         {} scans ({} revolutions missed)",
        self.format,
        self.bytes,
        s.frames_ok,
        s.bad_checksum,
        s.bad_frames,
        s.implausible_frames,
        s.skipped_bytes,
        s.resyncs,
        asm.points,
        asm.accepted,
        asm.flagged_invalid,
        asm.out_of_range,
        asm.low_quality,
        asm.outside_layout,
        asm.replaced,
        self.decoded.scans.len(),
        asm.missed_revolutions,
    );
        if self.ranges {
            for r in &self.decoded.scans {
                out.push('\n');
                let line: Vec<String> = r.iter().map(|x| format!("{x}")).collect();
                out.push_str(&line.join(" "));
            }
        }
        f.write_str(&out)
    }
}
