//! Summary statistics of a log (`beamfield log info`).

use super::CarmenLog;

/// A bounding box, metres.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize)]
pub struct Bounds {
    /// Smallest x.
    pub x_min: f64,
    /// Largest x.
    pub x_max: f64,
    /// Smallest y.
    pub y_min: f64,
    /// Largest y.
    pub y_max: f64,
}

/// Accumulates a bounding box.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Extent(Option<Bounds>);

impl Extent {
    pub(crate) fn add(&mut self, x: f64, y: f64) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let b = self.0.get_or_insert(Bounds {
            x_min: x,
            x_max: x,
            y_min: y,
            y_max: y,
        });
        b.x_min = b.x_min.min(x);
        b.x_max = b.x_max.max(x);
        b.y_min = b.y_min.min(y);
        b.y_max = b.y_max.max(y);
    }

    pub(crate) fn finish(self) -> Option<Bounds> {
        self.0
    }
}

/// The f64 with the same shortest decimal text as `v` (0.23f32 → 0.23, not 0.23000000417…),
/// for reports of values that were written in decimal.
pub fn decimal_f64(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

/// Serializes an f32 as the f64 with the same shortest decimal text (81.83, not
/// 81.83000183105469); non-finite values become `null`.
pub fn serialize_f32<S: serde::Serializer>(v: &f32, s: S) -> Result<S::Ok, S::Error> {
    let shortest = decimal_f64(*v);
    if shortest.is_finite() {
        s.serialize_f64(shortest)
    } else {
        s.serialize_none()
    }
}

/// What `beamfield log info` prints.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LogStats {
    /// FLASER scans.
    pub scans: usize,
    /// Beams per scan.
    pub beams: Option<usize>,
    /// All readings.
    pub readings: usize,
    /// Readings exactly at the max-range value.
    pub max_range_readings: usize,
    /// Readings above the max-range value (treated as max range by the models).
    pub above_max_range_readings: usize,
    /// NaN, infinite or negative readings (below the max range).
    pub invalid_readings: usize,
    /// Smallest valid reading, metres.
    #[serde(serialize_with = "serialize_f32")]
    pub min_range_m: f32,
    /// Largest reading below the max-range value, metres.
    #[serde(serialize_with = "serialize_f32")]
    pub max_valid_range_m: f32,
    /// Laser pose extent, metres.
    pub pose_extent: Option<Bounds>,
    /// Smallest θ as written, radians.
    #[serde(serialize_with = "serialize_f32")]
    pub theta_min_rad: f32,
    /// Largest θ as written, radians.
    #[serde(serialize_with = "serialize_f32")]
    pub theta_max_rad: f32,
    /// Places where the ipc timestamp is smaller than the previous scan's.
    pub timestamp_steps_back: usize,
}

impl Default for LogStats {
    fn default() -> Self {
        Self {
            scans: 0,
            beams: None,
            readings: 0,
            max_range_readings: 0,
            above_max_range_readings: 0,
            invalid_readings: 0,
            min_range_m: f32::INFINITY,
            max_valid_range_m: f32::NEG_INFINITY,
            pose_extent: None,
            theta_min_rad: f32::INFINITY,
            theta_max_rad: f32::NEG_INFINITY,
            timestamp_steps_back: 0,
        }
    }
}

impl CarmenLog {
    /// Summary statistics of the log (for `beamfield log info`).
    pub fn stats(&self) -> LogStats {
        let mut s = LogStats {
            scans: self.scans.len(),
            beams: self.beams(),
            ..LogStats::default()
        };
        let max_range = self.max_range.value_m();
        let mut pose = Extent::default();
        let mut prev_t: Option<f64> = None;
        for scan in &self.scans {
            pose.add(decimal_f64(scan.pose.x_m), decimal_f64(scan.pose.y_m));
            s.theta_min_rad = s.theta_min_rad.min(scan.pose.theta_rad);
            s.theta_max_rad = s.theta_max_rad.max(scan.pose.theta_rad);
            if let Some(p) = prev_t {
                if scan.timestamp_s < p {
                    s.timestamp_steps_back += 1;
                }
            }
            prev_t = Some(scan.timestamp_s);
            s.readings += scan.ranges_m.len();
            for &r in &scan.ranges_m {
                match max_range {
                    Some(m) if r == m => s.max_range_readings += 1,
                    Some(m) if r > m => s.above_max_range_readings += 1,
                    _ => {
                        if r.is_finite() && r >= 0.0 {
                            s.min_range_m = s.min_range_m.min(r);
                            s.max_valid_range_m = s.max_valid_range_m.max(r);
                        } else {
                            s.invalid_readings += 1;
                        }
                    }
                }
            }
        }
        s.pose_extent = pose.finish();
        s
    }
}
