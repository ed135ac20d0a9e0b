//! Reader of the UCI "Wall-Following Robot Navigation" 24-sonar ring data
//! (`data/sonar_uci_wall_following/sensor_readings_24.data`, see its README).
//!
//! Rows are CRLF-terminated, 24 ranges in metres (US1…US24) and an action label. US1 points
//! forward and the numbering runs clockwise, 15° apart, so transducer `k` (0-based) is at
//! bearing `−15°·k` in the robot frame (x forward, y left, counter-clockwise angles). Values
//! `≥ 5.0` are max-range (no echo).

use beamfield::sonar::Ring;
use beamfield::{BeamLayout, Scan, SensorMount};

/// Number of sonars in the ring.
pub const UCI_SONARS: usize = 24;
/// The saturation value of the data set, metres.
pub const UCI_MAX_RANGE_M: f32 = 5.0;

/// One row: the 24 ranges and the label.
#[derive(Clone, Debug)]
pub struct UciRow {
    /// Ranges, metres, in transducer order.
    pub scan: Scan<UCI_SONARS>,
    /// The action label (`Move-Forward`, …).
    pub label: String,
}

/// A parse failure with its 1-based line number.
#[derive(Debug, PartialEq)]
pub enum UciError {
    /// A line not ended by CRLF.
    NotCrlf(usize),
    /// Not 25 fields.
    FieldCount(usize, usize),
    /// A range that is not a number.
    BadNumber(usize),
}

/// The layout of the ring: bearing of US(k+1) is `−15°·k`, max range 5 m, centred.
pub fn uci_layout() -> BeamLayout<UCI_SONARS> {
    BeamLayout::uniform(
        0.0,
        -15f32.to_radians(),
        UCI_SONARS,
        UCI_MAX_RANGE_M,
        SensorMount::CENTERED,
    )
    .expect("valid layout")
}

/// The ring (cone half-angle and mounting radius are not in the data set: 12.5° and 0.3 m are
/// assumptions, used only where a ring is required).
pub fn uci_ring() -> Ring<UCI_SONARS> {
    Ring::uniform(
        UCI_SONARS,
        0.0,
        -15f32.to_radians(),
        0.3,
        12.5f32.to_radians(),
        UCI_MAX_RANGE_M,
    )
    .expect("valid ring")
}

/// Parses the whole file.
///
/// # Errors
/// The first malformed line.
pub fn parse_uci(bytes: &[u8]) -> Result<Vec<UciRow>, UciError> {
    let text = String::from_utf8_lossy(bytes);
    let mut rows = Vec::new();
    let mut rest: &str = &text;
    let mut line_no = 0;
    while !rest.is_empty() {
        line_no += 1;
        let Some(end) = rest.find('\n') else {
            return Err(UciError::NotCrlf(line_no));
        };
        let line = &rest[..end];
        rest = &rest[end + 1..];
        let Some(line) = line.strip_suffix('\r') else {
            return Err(UciError::NotCrlf(line_no));
        };
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != UCI_SONARS + 1 {
            return Err(UciError::FieldCount(line_no, fields.len()));
        }
        let mut ranges = [0f32; UCI_SONARS];
        for (r, f) in ranges.iter_mut().zip(&fields) {
            *r = f.trim().parse().map_err(|_| UciError::BadNumber(line_no))?;
        }
        rows.push(UciRow {
            scan: Scan::from_ranges(&ranges).expect("24 fit"),
            label: fields[UCI_SONARS].trim().to_string(),
        });
    }
    Ok(rows)
}
