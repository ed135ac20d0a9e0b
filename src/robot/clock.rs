//! The device's clock: the LiDAR's own timestamps, unwrapped into microseconds since the first
//! one, with a step that no sensor makes held back until the next stamp confirms it.

/// Largest step between two consecutive stamps taken as it comes, ms: longer ones (a wrong
/// stamp in a CRC-valid frame, a stamp that went back, the sensor's return after a silence)
/// wait for the next stamp to confirm them ([`ScanClock::advance`]).
pub const MAX_STEP_MS: u32 = 1_000;

/// Turns a sensor's wrapping millisecond timestamps (the LD06's run from 0 to 29,999) into a
/// monotonic count of microseconds.
///
/// The first timestamp seen is taken as is (`t = raw · 1000 µs`); each later one adds its
/// forward distance from the previous one modulo the wrap. A sensor timestamp does not go
/// backwards, so a step "back" is read as a forward step across the wrap: the clock only ever
/// moves forward, and a gap of more than one wrap period (30 s for the LD06) is invisible.
///
/// A step longer than [`MAX_STEP_MS`] is not taken at once: the stamp is held, and taken only if
/// the next stamp follows it within [`MAX_STEP_MS`] (the sensor came back after a silence, or
/// restarted its count). Otherwise it was one wrong stamp: it is dropped and counted
/// ([`ScanClock::outliers`]), and the clock goes on from where it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanClock {
    wrap_ms: u32,
    last_raw_ms: Option<u32>,
    now_us: u64,
    /// A stamp further than [`MAX_STEP_MS`] from the last one, and its forward step, ms.
    held: Option<(u32, u32)>,
    outliers: u32,
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
            held: None,
            outliers: 0,
        }
    }

    /// The forward distance from stamp `from` to stamp `to` modulo the wrap, ms.
    fn forward(&self, from: u32, to: u32) -> u32 {
        (to + self.wrap_ms - from) % self.wrap_ms
    }

    /// Advances to the sensor timestamp `raw_ms` and returns the time in microseconds (see the
    /// type's docs for the steps held back).
    pub fn advance(&mut self, raw_ms: u16) -> u64 {
        let raw = u32::from(raw_ms) % self.wrap_ms;
        let Some(prev) = self.last_raw_ms else {
            self.last_raw_ms = Some(raw);
            self.now_us = u64::from(raw) * 1000;
            return self.now_us;
        };
        let step = self.forward(prev, raw);
        let taken = if step <= MAX_STEP_MS.min(self.wrap_ms / 2) {
            if self.held.take().is_some() {
                self.outliers = self.outliers.wrapping_add(1);
            }
            Some(step)
        } else {
            match self.held {
                Some((held, held_step)) if self.forward(held, raw) <= MAX_STEP_MS => {
                    self.held = None;
                    Some(held_step + self.forward(held, raw))
                }
                Some(_) => {
                    self.outliers = self.outliers.wrapping_add(1);
                    self.held = Some((raw, step));
                    None
                }
                None => {
                    self.held = Some((raw, step));
                    None
                }
            }
        };
        if let Some(step) = taken {
            self.last_raw_ms = Some(raw);
            self.now_us = self.now_us.saturating_add(u64::from(step) * 1000);
        }
        self.now_us
    }

    /// The time of a stamp `raw_ms` within [`MAX_STEP_MS`] before or after the last one taken,
    /// microseconds; `None` before the first stamp or for a stamp further away (a stamp the
    /// clock would not take).
    pub fn time_of(&self, raw_ms: u16) -> Option<u64> {
        let last = self.last_raw_ms?;
        let raw = u32::from(raw_ms) % self.wrap_ms;
        let (back, ahead) = (self.forward(raw, last), self.forward(last, raw));
        let limit = MAX_STEP_MS.min(self.wrap_ms / 2);
        if back <= limit {
            self.now_us.checked_sub(u64::from(back) * 1000)
        } else if ahead <= limit {
            Some(self.now_us.saturating_add(u64::from(ahead) * 1000))
        } else {
            None
        }
    }

    /// The time of the last timestamp, microseconds (0 before the first).
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// Whether any timestamp was seen.
    pub fn started(&self) -> bool {
        self.last_raw_ms.is_some()
    }

    /// Stamps dropped as wrong: a step longer than [`MAX_STEP_MS`] that the next stamp did not
    /// confirm.
    pub fn outliers(&self) -> u32 {
        self.outliers
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
    fn a_confirmed_step_back_is_a_forward_step_across_the_wrap() {
        let mut c = ScanClock::new(30_000);
        c.advance(1_000);
        // Held until the next stamp follows it.
        assert_eq!(c.advance(500), 1_000_000);
        assert_eq!(c.advance(503), 1_000_000 + 29_500_000 + 3_000);
        assert_eq!(c.outliers(), 0);
    }

    #[test]
    fn one_wrong_stamp_is_dropped_and_counted() {
        let mut c = ScanClock::new(30_000);
        c.advance(5_000);
        assert_eq!(c.advance(5_003), 5_003_000);
        assert_eq!(c.advance(2_003), 5_003_000);
        assert_eq!(c.advance(5_006), 5_006_000);
        assert_eq!(c.outliers(), 1);
        assert_eq!(c.time_of(5_001), Some(5_001_000));
        assert_eq!(c.time_of(5_010), Some(5_010_000));
        assert_eq!(c.time_of(2_003), None);
    }

    #[test]
    fn a_silence_is_taken_once_the_sensor_goes_on() {
        let mut c = ScanClock::new(30_000);
        c.advance(1_000);
        assert_eq!(c.advance(6_000), 1_000_000);
        assert_eq!(c.advance(6_003), 6_003_000);
        assert_eq!(c.outliers(), 0);
    }
}
