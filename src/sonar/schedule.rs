//! Firing schedule of an ultrasonic ring (docs/models.md#sonar).
//!
//! A schedule is an ordered list of groups `G_0 … G_{T−1}` of transducer indices. The groups are
//! fired one after the other, `interval_s` apart, and the cycle repeats: group `g` fires at
//! `t = g·interval_s` (mod the cycle period `T·interval_s`). An echo lingers for the *echo
//! lifetime* `L = 2·z_max / c` (seconds; `c` the speed of sound, 343 m/s by default).
//!
//! # Overlap weight
//! When transducer `i` (in group `g`) fires, every other transducer `j` counts as co-fired with
//! weight `w_ij ∈ [0, 1]`:
//! - `j` in the same group: `w_ij = 1`;
//! - `j` in another group `h`: with `Δt = ((g − h) mod T)·interval_s` the time since `j`'s most
//!   recent pulse, `w_ij = clamp((L − Δt)/L, 0, 1)`, the fraction of `j`'s echo lifetime that is
//!   still ahead when `i` fires (older pulses of `j` are ignored: they have less time left);
//! - `j` in no group (a disabled transducer): `w_ij = 0`.
//!
//! Groups fired *after* `i` do not count: a driver reads group `g` before it fires group `g+1`.
//! The *co-fired count* of `i` is the number of `j ≠ i` with `w_ij > 0`; the *effective* co-fired
//! count is `Σ_j w_ij`.
//!
//! Capacity: at most `M` transducers and `G` groups; no allocation.

use crate::sonar::ring::Ring;
use heapless::Vec;

/// Default speed of sound in air at 20 °C, m/s.
pub const SPEED_OF_SOUND_M_PER_S: f32 = 343.0;

/// Marker for a transducer that is in no group.
const UNSCHEDULED: u16 = u16::MAX;

/// Why a schedule was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ScheduleError {
    /// No group at all.
    NoGroups,
    /// More groups than the capacity `G`.
    TooManyGroups {
        /// How many were given.
        given: usize,
        /// The compile-time capacity.
        capacity: usize,
    },
    /// A group with no transducer (its index).
    EmptyGroup(usize),
    /// A transducer index not in the ring.
    IndexOutOfRange {
        /// The group it appeared in.
        group: usize,
        /// The offending index.
        index: usize,
    },
    /// A transducer listed twice in one cycle.
    Duplicate {
        /// The transducer.
        index: usize,
        /// The group of its second appearance.
        group: usize,
    },
    /// The interval between groups is negative or not finite.
    BadInterval,
    /// The speed of sound is not finite or ≤ 0.
    BadSpeedOfSound,
    /// The ring has more transducers than the schedule's capacity `M`.
    RingTooLarge {
        /// Transducers in the ring.
        ring: usize,
        /// The compile-time capacity.
        capacity: usize,
    },
}

impl core::fmt::Display for ScheduleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoGroups => f.write_str("schedule has no group"),
            Self::TooManyGroups { given, capacity } => {
                write!(f, "{given} groups given, capacity is {capacity}")
            }
            Self::EmptyGroup(g) => write!(f, "group {g} is empty"),
            Self::IndexOutOfRange { group, index } => {
                write!(f, "transducer {index} in group {group} is not in the ring")
            }
            Self::Duplicate { index, group } => {
                write!(
                    f,
                    "transducer {index} fired twice in one cycle (again in group {group})"
                )
            }
            Self::BadInterval => f.write_str("interval must be finite and >= 0"),
            Self::BadSpeedOfSound => f.write_str("speed of sound must be finite and > 0"),
            Self::RingTooLarge { ring, capacity } => {
                write!(
                    f,
                    "ring has {ring} transducers, schedule capacity is {capacity}"
                )
            }
        }
    }
}

impl core::error::Error for ScheduleError {}

/// A validated firing schedule for a ring of at most `M` transducers, with at most `G` groups.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule<const M: usize, const G: usize> {
    /// Transducer indices, group after group.
    members: Vec<u16, M>,
    /// Start of each group in `members`.
    starts: Vec<u16, G>,
    /// The group of each transducer of the ring, or [`UNSCHEDULED`].
    group_of: Vec<u16, M>,
    interval_s: f32,
    echo_lifetime_s: f32,
}

impl<const M: usize, const G: usize> Schedule<M, G> {
    /// A schedule for `ring`: `groups[g]` lists the transducers fired together in group `g`,
    /// `interval_s` (seconds, ≥ 0) separates consecutive groups, and the echo lifetime is
    /// `2·max_range/speed_of_sound` ([`SPEED_OF_SOUND_M_PER_S`] is the usual value).
    ///
    /// # Errors
    /// [`ScheduleError::NoGroups`], [`ScheduleError::TooManyGroups`],
    /// [`ScheduleError::EmptyGroup`], [`ScheduleError::IndexOutOfRange`],
    /// [`ScheduleError::Duplicate`], [`ScheduleError::BadInterval`],
    /// [`ScheduleError::BadSpeedOfSound`], [`ScheduleError::RingTooLarge`].
    pub fn new<const R: usize>(
        ring: &Ring<R>,
        groups: &[&[usize]],
        interval_s: f32,
        speed_of_sound_m_per_s: f32,
    ) -> Result<Self, ScheduleError> {
        if groups.is_empty() {
            return Err(ScheduleError::NoGroups);
        }
        if groups.len() > G {
            return Err(ScheduleError::TooManyGroups {
                given: groups.len(),
                capacity: G,
            });
        }
        if !(interval_s.is_finite() && interval_s >= 0.0) {
            return Err(ScheduleError::BadInterval);
        }
        if !(speed_of_sound_m_per_s.is_finite() && speed_of_sound_m_per_s > 0.0) {
            return Err(ScheduleError::BadSpeedOfSound);
        }
        let n = ring.len();
        if n > M {
            return Err(ScheduleError::RingTooLarge {
                ring: n,
                capacity: M,
            });
        }
        let mut group_of: Vec<u16, M> = Vec::new();
        for _ in 0..n {
            // Cannot fail: at most M pushes.
            let _ = group_of.push(UNSCHEDULED);
        }
        let mut members: Vec<u16, M> = Vec::new();
        let mut starts: Vec<u16, G> = Vec::new();
        for (g, group) in groups.iter().enumerate() {
            if group.is_empty() {
                return Err(ScheduleError::EmptyGroup(g));
            }
            let start = u16::try_from(members.len()).unwrap_or(u16::MAX);
            starts
                .push(start)
                .map_err(|_| ScheduleError::TooManyGroups {
                    given: groups.len(),
                    capacity: G,
                })?;
            let g16 = u16::try_from(g).unwrap_or(u16::MAX);
            for &index in group.iter() {
                let out = ScheduleError::IndexOutOfRange { group: g, index };
                let slot = if index < n {
                    group_of.get_mut(index).ok_or(out)?
                } else {
                    return Err(out);
                };
                if *slot != UNSCHEDULED {
                    return Err(ScheduleError::Duplicate { index, group: g });
                }
                *slot = g16;
                let i16 = u16::try_from(index).map_err(|_| out)?;
                // Each transducer appears once and index < n ≤ M, so this cannot overflow.
                members.push(i16).map_err(|_| out)?;
            }
        }
        Ok(Self {
            members,
            starts,
            group_of,
            interval_s,
            echo_lifetime_s: 2.0 * ring.max_range_m() / speed_of_sound_m_per_s,
        })
    }

    /// Number of groups `T` (≥ 1).
    pub fn group_count(&self) -> usize {
        self.starts.len()
    }

    /// The transducers of group `g` (empty for `g ≥ T`).
    pub fn group(&self, g: usize) -> &[u16] {
        let start = self
            .starts
            .get(g)
            .map_or(self.members.len(), |&s| usize::from(s));
        let end = self
            .starts
            .get(g + 1)
            .map_or(self.members.len(), |&s| usize::from(s));
        self.members.get(start..end).unwrap_or(&[])
    }

    /// Iterator over the groups, in firing order.
    pub fn groups(&self) -> impl Iterator<Item = &[u16]> + '_ {
        (0..self.group_count()).map(|g| self.group(g))
    }

    /// The group transducer `i` fires in, or `None` when it is in no group (or not in the ring).
    pub fn group_of(&self, i: usize) -> Option<usize> {
        match self.group_of.get(i) {
            Some(&g) if g != UNSCHEDULED => Some(usize::from(g)),
            _ => None,
        }
    }

    /// Number of transducers of the ring this schedule was built for.
    pub fn ring_len(&self) -> usize {
        self.group_of.len()
    }

    /// Interval between consecutive groups, seconds.
    pub fn interval_s(&self) -> f32 {
        self.interval_s
    }

    /// Echo lifetime `2·z_max/c`, seconds.
    pub fn echo_lifetime_s(&self) -> f32 {
        self.echo_lifetime_s
    }

    /// Cycle period `T·interval_s`, seconds.
    pub fn cycle_period_s(&self) -> f32 {
        self.group_count() as f32 * self.interval_s
    }

    /// Full scans per second, `1/(T·interval_s)`; `+∞` for a zero interval (the schedule then
    /// does not limit the rate).
    pub fn scan_rate_hz(&self) -> f32 {
        1.0 / self.cycle_period_s()
    }

    /// The overlap weight `w_ij ∈ [0, 1]` with which `j` counts as co-fired when `i` fires (see
    /// the module docs). 0 for `i == j` and for unscheduled or out-of-range transducers.
    pub fn overlap_weight(&self, i: usize, j: usize) -> f32 {
        if i == j {
            return 0.0;
        }
        let (Some(g), Some(h)) = (self.group_of(i), self.group_of(j)) else {
            return 0.0;
        };
        if g == h {
            return 1.0;
        }
        let t = self.group_count();
        let steps = (g + t - h) % t;
        let dt = steps as f32 * self.interval_s;
        if self.echo_lifetime_s <= 0.0 {
            return 0.0;
        }
        ((self.echo_lifetime_s - dt) / self.echo_lifetime_s).clamp(0.0, 1.0)
    }

    /// Co-fired count of `i`: how many other transducers have `w_ij > 0`.
    pub fn cofired_count(&self, i: usize) -> u16 {
        let n = (0..self.ring_len())
            .filter(|&j| self.overlap_weight(i, j) > 0.0)
            .count();
        u16::try_from(n).unwrap_or(u16::MAX)
    }

    /// Effective co-fired count of `i`: `Σ_j w_ij`.
    pub fn effective_cofired(&self, i: usize) -> f32 {
        (0..self.ring_len())
            .map(|j| self.overlap_weight(i, j))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring() -> Ring<8> {
        Ring::uniform(8, 0.0, core::f32::consts::FRAC_PI_4, 0.2, 0.3, 3.43).unwrap()
    }

    #[test]
    fn validation_table() {
        let r = ring();
        type S = Schedule<8, 4>;
        assert_eq!(
            S::new(&r, &[], 0.1, 343.0).err(),
            Some(ScheduleError::NoGroups)
        );
        let five: [&[usize]; 5] = [&[0], &[1], &[2], &[3], &[4]];
        assert_eq!(
            S::new(&r, &five, 0.1, 343.0).err(),
            Some(ScheduleError::TooManyGroups {
                given: 5,
                capacity: 4
            })
        );
        assert_eq!(
            S::new(&r, &[&[0], &[]], 0.1, 343.0).err(),
            Some(ScheduleError::EmptyGroup(1))
        );
        assert_eq!(
            S::new(&r, &[&[0], &[8]], 0.1, 343.0).err(),
            Some(ScheduleError::IndexOutOfRange { group: 1, index: 8 })
        );
        assert_eq!(
            S::new(&r, &[&[0, 4], &[1, 4]], 0.1, 343.0).err(),
            Some(ScheduleError::Duplicate { index: 4, group: 1 })
        );
        for iv in [-0.01, f32::NAN, f32::INFINITY] {
            assert_eq!(
                S::new(&r, &[&[0]], iv, 343.0).err(),
                Some(ScheduleError::BadInterval)
            );
        }
        for c in [0.0, f32::NAN] {
            assert_eq!(
                S::new(&r, &[&[0]], 0.1, c).err(),
                Some(ScheduleError::BadSpeedOfSound)
            );
        }
        assert_eq!(
            Schedule::<4, 4>::new(&r, &[&[0]], 0.1, 343.0).err(),
            Some(ScheduleError::RingTooLarge {
                ring: 8,
                capacity: 4
            })
        );
    }

    #[test]
    fn overlap_weights_by_hand() {
        // z_max 3.43 m, c 343 m/s: lifetime 20 ms. Interval 5 ms, four groups.
        let r = ring();
        let s =
            Schedule::<8, 4>::new(&r, &[&[0, 4], &[1, 5], &[2, 6], &[3]], 0.005, 343.0).unwrap();
        assert!((s.echo_lifetime_s() - 0.02).abs() < 1e-7);
        assert_eq!(s.group(1), &[1, 5]);
        assert_eq!(s.group(3), &[3]);
        assert_eq!(s.group_of(7), None);
        // Same group.
        assert_eq!(s.overlap_weight(0, 4), 1.0);
        // 2 fires 5 ms after 1: 15 of 20 ms left.
        assert!((s.overlap_weight(2, 1) - 0.75).abs() < 1e-6);
        // 2 fires 10 ms after 0.
        assert!((s.overlap_weight(2, 0) - 0.5).abs() < 1e-6);
        // 0 fires 5 ms after 3 (cyclic), 10 ms after group 2, 15 ms after group 1.
        assert!((s.overlap_weight(0, 3) - 0.75).abs() < 1e-6);
        assert!((s.overlap_weight(0, 1) - 0.25).abs() < 1e-6);
        assert_eq!(s.overlap_weight(0, 7), 0.0);
        assert_eq!(s.overlap_weight(0, 0), 0.0);
        // 0: 4 (1) + 3 (0.75) + 2, 6 (0.5 each) + 1, 5 (0.25 each) = 3.25, six neighbours.
        assert_eq!(s.cofired_count(0), 6);
        assert!((s.effective_cofired(0) - 3.25).abs() < 1e-5);
        assert!((s.scan_rate_hz() - 50.0).abs() < 1e-3);
        // Interval ≥ lifetime: only the own group counts.
        let slow = Schedule::<8, 4>::new(&r, &[&[0, 4], &[1, 5]], 0.02, 343.0).unwrap();
        assert_eq!(slow.overlap_weight(1, 0), 0.0);
        assert_eq!(slow.cofired_count(1), 1);
    }
}
