//! The device's clock: the LiDAR's own timestamps, unwrapped into microseconds since the first
//! one.

/// Turns a sensor's wrapping millisecond timestamps (the LD06's run from 0 to 29,999) into a
/// monotonic count of microseconds.
///
/// The first timestamp seen is taken as is (`t = raw · 1000 µs`); each later one adds its
/// forward distance from the previous one modulo the wrap. A sensor timestamp does not go
/// backwards, so a step "back" is read as a forward step across the wrap: the clock only ever
/// moves forward, and a gap of more than one wrap period (30 s for the LD06) is invisible.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanClock {
    wrap_ms: u32,
    last_raw_ms: Option<u16>,
    now_us: u64,
}

impl ScanClock {
    /// A clock for timestamps that wrap at `wrap_ms` (0 is read as 65,536).
    pub const fn new(wrap_ms: u16) -> Self {
        Self {
            wrap_ms: if wrap_ms == 0 {
                1 << 16
            } else {
                wrap_ms as u32
            },
            last_raw_ms: None,
            now_us: 0,
        }
    }

    /// Advances to the sensor timestamp `raw_ms` and returns the time in microseconds.
    pub fn advance(&mut self, raw_ms: u16) -> u64 {
        let raw = u32::from(raw_ms) % self.wrap_ms;
        match self.last_raw_ms.replace(raw as u16) {
            None => self.now_us = u64::from(raw) * 1000,
            Some(prev) => {
                let step = (raw + self.wrap_ms - u32::from(prev) % self.wrap_ms) % self.wrap_ms;
                self.now_us = self.now_us.saturating_add(u64::from(step) * 1000);
            }
        }
        self.now_us
    }

    /// The time of the last timestamp, microseconds (0 before the first).
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// Whether any timestamp was seen.
    pub fn started(&self) -> bool {
        self.last_raw_ms.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwraps_across_the_wrap() {
        let mut c = ScanClock::new(30_000);
        assert_eq!(c.advance(29_900), 29_900_000);
        assert_eq!(c.advance(29_990), 29_990_000);
        assert_eq!(c.advance(40), 30_040_000);
        assert_eq!(c.advance(40), 30_040_000);
        assert_eq!(c.advance(100), 30_100_000);
    }

    #[test]
    fn a_step_back_is_a_forward_step_across_the_wrap() {
        let mut c = ScanClock::new(30_000);
        c.advance(1_000);
        assert_eq!(c.advance(999), 1_000_000 + 29_999_000);
    }
}
