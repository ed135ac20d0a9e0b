//! The localization-quality signal: after every update, from what the filter already knows,
//! whether it follows the robot ([`Quality::Tracking`]), doubts it ([`Quality::Uncertain`]) or
//! has lost it ([`Quality::Lost`]); and the recovery it drives (expansion resetting, then
//! free-space resetting, [`Resetting`]).
//!
//! # Inputs (no extra work per beam in the particle loop)
//! - **The share of beams the map explains** at the estimate: the beams whose endpoint, with the
//!   robot at the estimate, lies within [`QualityThresholds::explained_sigmas`] × σ_hit of an
//!   obstacle. One more pass over the scan's beams per update (not per particle), with
//!   [`Mcl::update_prepared`](super::Mcl::update_prepared) only; the other updates have none.
//!   Averaged over the updates with rate [`EXPLAINED_RATE`] (about the last two scans).
//! - **The likelihood per beam**: `ln w_avg / beams` (nats per scored beam, tempered as scored:
//!   the value the augmented-MCL recovery already follows), its fast and slow exponential
//!   averages (rates [`LIKELIHOOD_FAST_RATE`], [`LIKELIHOOD_SLOW_RATE`], as AMCL's
//!   `recovery_alpha_fast/slow` but on the logarithm). The drop `slow − fast` (nats per beam)
//!   says the recent scans fit worse than the usual ones.
//! - **The spread**: the standard deviations of the estimate (metres, the larger of x and y;
//!   radians) and the share of the weight within [`ESTIMATE_RADIUS_M`](super::ESTIMATE_RADIUS_M)
//!   of the heaviest particle (the concentration; a cloud split in two places has little).
//!
//! # Decision ([`QualityThresholds`], defaults in brackets)
//! With the explained share `e` (its average):
//! - `Lost` when `e < lost_explained` [0.35], or when `e < lost_explained_dropping` [0.5] and
//!   the likelihood per beam has dropped by more than `dropping_nats` [0.25 nats per beam],
//!   or when `e` has fallen more than `lost_explained_fall` [0.3] below its own slow average
//!   (rate [`EXPLAINED_SLOW_RATE`]), or when the share of beams that cross a mapped wall to
//!   reach their endpoint ([`ScanFit::through`], averaged at rate [`EXPLAINED_RATE`]) is above
//!   `lost_through` [0.12]: a robot where the estimate is would have seen those walls;
//! - `Uncertain` when `e < tracking_explained` [0.65], or the spread is above `spread_m` [0.25 m]
//!   or `spread_rad` [0.15 rad], or the concentration is below `concentration` [0.5];
//! - `Tracking` otherwise;
//!
//! and a `Lost` only after `lost_after` (3) updates in a row that meet one of its conditions
//! (`Uncertain` until then).
//!
//! Without it (updates by a model or a closure), the drop stands in for `e`: `Lost` above
//! `lost_drop_nats` [1.0 nats, in the units of the scores given], `Uncertain` above `uncertain_drop_nats` [0.3]; a
//! filter lost for long enough that the slow average has caught up then reads as tracking,
//! which the explained share does not.
//!
//! The quality score sent with it is the averaged explained share (1 − the drop, clamped to
//! `[0, 1]`, without it).
//!
//! The explained share sets clutter aside (`clutter_share` [0.3]): beams that end in front of a
//! mapped wall the map does not explain, up to that share of the scan, are not counted against
//! the estimate. A kidnapping into a place whose walls the old estimate half explains is then
//! still seen by the readings that pass through mapped walls (`lost_through`).
//!
//! The thresholds were chosen on the Intel lab (its log, its real wheel odometry and a
//! kidnapping in it) and checked on the other buildings' logs (docs/localization.md,
//! `host-tests/tests/intel_quality.rs`).

use super::unexplained::ScanFit;

/// The rate of the averaged explained share (per update): `e ← e + r·(eₖ − e)`.
pub const EXPLAINED_RATE: f32 = 0.5;
/// The fast average's rate of the likelihood per beam (per update).
pub const LIKELIHOOD_FAST_RATE: f32 = 0.3;
/// The slow average's rate of the likelihood per beam (per update).
pub const LIKELIHOOD_SLOW_RATE: f32 = 0.02;
/// Rate of the slow average of the explained share
/// ([`QualityThresholds::lost_explained_fall`]).
pub const EXPLAINED_SLOW_RATE: f32 = 0.02;

/// What the filter thinks of its own estimate after an update.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Quality {
    /// The estimate follows the robot: the map explains the scan there and the cloud is tight.
    Tracking,
    /// The scan fits only partly, or the cloud is wide or split (also before the first update).
    #[default]
    Uncertain,
    /// The map does not explain the scan at the estimate: the filter has lost the robot.
    Lost,
}

/// The thresholds of the decision (see the module docs). Validated by
/// [`QualityThresholds::validate`] when given to [`MclConfig::with_quality`](super::MclConfig::with_quality).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QualityThresholds {
    /// A beam is explained when its endpoint lies within this many σ_hit of an obstacle
    /// (dimensionless, > 0).
    pub explained_sigmas: f32,
    /// Averaged explained share (0 to 1) below which the state is `Uncertain`.
    pub tracking_explained: f32,
    /// Averaged explained share (0 to 1) below which the state is `Lost`.
    pub lost_explained: f32,
    /// Averaged explained share (0 to 1) below which the state is `Lost` when the likelihood
    /// per beam is also dropping by more than `dropping_nats` (a kidnapping into a place the
    /// map half explains).
    pub lost_explained_dropping: f32,
    /// The drop of the likelihood per beam (`slow − fast`, nats per beam) that, with
    /// `lost_explained_dropping`, is `Lost`.
    pub dropping_nats: f32,
    /// A fall of the averaged explained share below its slow average (rate
    /// [`EXPLAINED_SLOW_RATE`], about the last 50 scans) larger than this (0 to 1) is `Lost`:
    /// a kidnapping into a place the map half explains, seen before the likelihood's slower
    /// averages notice (1: off).
    pub lost_explained_fall: f32,
    /// An average share of beams (0 to 1; 1: off) that reach their endpoint through a mapped
    /// wall ([`ScanFit::through`], averaged at rate [`EXPLAINED_RATE`]) above which the state
    /// is `Lost`: with the robot where the estimate is, those walls would have stopped the
    /// beams. Clutter in front of walls does not raise it; a map that misses an opening, glass
    /// or an open door does, for the beams that pass there.
    pub lost_through: f32,
    /// Updates in a row that meet a `Lost` condition before the state is `Lost` (they report
    /// `Uncertain` until then; at least 1): a scan or two the map explains poorly while the
    /// estimate is right (a doorway, people) is not a loss.
    pub lost_after: u8,
    /// Estimate standard deviation (metres) above which the state is at best `Uncertain`.
    pub spread_m: f32,
    /// Heading standard deviation (radians) above which the state is at best `Uncertain`.
    pub spread_rad: f32,
    /// Share of the weight near the estimate (0 to 1) below which the state is at best
    /// `Uncertain`.
    pub concentration: f32,
    /// Without an explained share: drop of the likelihood (nats, in the units of the scores
    /// given: per beam for [`Mcl::update_prepared`](super::Mcl::update_prepared), per scan for
    /// closures and models) above which the state is `Uncertain`.
    pub uncertain_drop_nats: f32,
    /// Without an explained share: drop (nats, as `uncertain_drop_nats`) above which the state
    /// is `Lost`.
    pub lost_drop_nats: f32,
    /// The largest share of a scan's beams (0 to below 1; 0: off) set aside as clutter before
    /// the explained share is taken: beams the map does not explain but whose ray
    /// reaches the endpoint without crossing a mapped wall ([`ScanFit::short`]: something
    /// unmapped in front of the wall, near the sensor). The share that decides is then
    /// `explained / (1 − min(short, clutter_share))` ([`QualityThresholds::explained_share`]):
    /// a scan half hidden by unmapped things near the laser is judged by the half the map
    /// should explain, while readings through mapped walls (a pose that is off) and clutter
    /// beyond the allowance still count against it.
    pub clutter_share: f32,
}

impl QualityThresholds {
    /// The defaults (module docs).
    pub const DEFAULT: Self = Self {
        explained_sigmas: 3.0,
        tracking_explained: 0.65,
        lost_explained: 0.35,
        lost_explained_dropping: 0.5,
        dropping_nats: 0.25,
        lost_explained_fall: 0.4,
        lost_through: 0.12,
        lost_after: 3,
        spread_m: 0.25,
        spread_rad: 0.15,
        concentration: 0.5,
        uncertain_drop_nats: 0.3,
        lost_drop_nats: 1.0,
        clutter_share: 0.3,
    };

    /// The explained share that decides (0 to 1): `fit.explained / (1 − min(fit.short,
    /// clutter_share))`, clamped to `[0, 1]` (`fit.explained` itself with `clutter_share` 0).
    pub fn explained_share(&self, fit: &ScanFit) -> f32 {
        let rest = 1.0 - fit.short.min(self.clutter_share).max(0.0);
        if rest > 0.0 {
            (fit.explained / rest).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// True when every value is in range: shares in `[0, 1]` with `lost ≤ tracking`, the rest
    /// positive (not NaN), `uncertain_drop ≤ lost_drop`.
    pub fn validate(&self) -> bool {
        let unit = |v: f32| (0.0..=1.0).contains(&v);
        let pos = |v: f32| v > 0.0 && !v.is_nan();
        unit(self.tracking_explained)
            && unit(self.lost_explained)
            && self.lost_explained <= self.tracking_explained
            && unit(self.lost_explained_dropping)
            && pos(self.dropping_nats)
            && unit(self.lost_explained_fall)
            && unit(self.lost_through)
            && self.lost_after >= 1
            && unit(self.concentration)
            && pos(self.explained_sigmas)
            && pos(self.spread_m)
            && pos(self.spread_rad)
            && pos(self.uncertain_drop_nats)
            && pos(self.lost_drop_nats)
            && self.uncertain_drop_nats <= self.lost_drop_nats
            && (0.0..1.0).contains(&self.clutter_share)
    }
}

impl Default for QualityThresholds {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The quality signal of one update ([`Update::quality`](super::Update::quality),
/// [`Mcl::quality`](super::Mcl::quality)).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QualityReport {
    /// The decision.
    pub state: Quality,
    /// A score in `[0, 1]` (1 best): the averaged explained share, or `1 − drop` without it.
    pub score: f32,
    /// Share of this scan's beams the map explains at the estimate (0 to 1), clutter set aside
    /// ([`QualityThresholds::explained_share`]); NaN when the update had no scan to measure it
    /// on (a model or closure update).
    pub explained: f32,
    /// Its average over the updates (rate [`EXPLAINED_RATE`]); NaN before the first measured.
    pub explained_avg: f32,
    /// How this scan fits the map at the estimate, before clutter is set aside ([`ScanFit`]:
    /// all NaN without a scan).
    pub fit: ScanFit,
    /// This update's likelihood per beam, `ln w_avg / beams`, nats.
    pub ln_beam: f32,
    /// Its fast average (rate [`LIKELIHOOD_FAST_RATE`]), nats.
    pub ln_beam_fast: f32,
    /// Its slow average (rate [`LIKELIHOOD_SLOW_RATE`]), nats.
    pub ln_beam_slow: f32,
    /// The estimate's standard deviation in position (the larger of x and y), metres.
    pub spread_m: f32,
    /// The estimate's standard deviation in heading, radians.
    pub spread_rad: f32,
    /// Share of the weight within the estimate's neighbourhood (0 to 1).
    pub concentration: f32,
}

/// The running averages behind the signal (in [`Mcl`](super::Mcl)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct QualityState {
    explained_avg: f32,
    explained_slow: f32,
    /// Average share of beams through mapped walls.
    through_avg: f32,
    fast: f32,
    slow: f32,
    /// Updates in a row that met a `Lost` condition.
    lost_conditions: u8,
}

impl QualityState {
    pub(super) const NEW: Self = Self {
        explained_avg: f32::NAN,
        explained_slow: f32::NAN,
        through_avg: f32::NAN,
        fast: f32::NAN,
        slow: f32::NAN,
        lost_conditions: 0,
    };

    /// Folds one update in and decides.
    pub(super) fn observe(
        &mut self,
        t: &QualityThresholds,
        ln_beam: f32,
        fit: Option<ScanFit>,
        covariance: &[[f32; 3]; 3],
        concentration: f32,
    ) -> QualityReport {
        let follow = |avg: f32, v: f32, rate: f32| {
            if !v.is_finite() {
                avg
            } else if avg.is_nan() {
                v
            } else {
                avg + rate * (v - avg)
            }
        };
        self.fast = follow(self.fast, ln_beam, LIKELIHOOD_FAST_RATE);
        self.slow = follow(self.slow, ln_beam, LIKELIHOOD_SLOW_RATE);
        let explained = fit.map(|f| t.explained_share(&f));
        let e = explained.unwrap_or(f32::NAN);
        self.explained_avg = follow(self.explained_avg, e, EXPLAINED_RATE);
        self.explained_slow = follow(self.explained_slow, e, EXPLAINED_SLOW_RATE);
        self.through_avg = follow(
            self.through_avg,
            fit.map_or(f32::NAN, |f| f.through),
            EXPLAINED_RATE,
        );
        let [vx, vy, vt] = super::estimate::diagonal_variances(covariance);
        let spread_m = crate::math::sqrt(vx.max(vy));
        let spread_rad = crate::math::sqrt(vt);
        let wide = !(spread_m <= t.spread_m
            && spread_rad <= t.spread_rad
            && concentration >= t.concentration);
        let drop = if self.slow.is_finite() && self.fast.is_finite() {
            (self.slow - self.fast).max(0.0)
        } else {
            0.0
        };
        let (state, score) = if explained.is_some() && !self.explained_avg.is_nan() {
            let a = self.explained_avg;
            let state = if a < t.lost_explained
                || (a < t.lost_explained_dropping && drop > t.dropping_nats)
                || self.explained_slow - a > t.lost_explained_fall
                || self.through_avg > t.lost_through
            {
                Quality::Lost
            } else if a < t.tracking_explained || wide {
                Quality::Uncertain
            } else {
                Quality::Tracking
            };
            (state, a.clamp(0.0, 1.0))
        } else {
            let state = if drop > t.lost_drop_nats {
                Quality::Lost
            } else if drop > t.uncertain_drop_nats || wide {
                Quality::Uncertain
            } else {
                Quality::Tracking
            };
            (state, (1.0 - drop).clamp(0.0, 1.0))
        };
        let state = if state == Quality::Lost {
            self.lost_conditions = self.lost_conditions.saturating_add(1);
            if self.lost_conditions >= t.lost_after {
                Quality::Lost
            } else {
                Quality::Uncertain
            }
        } else {
            self.lost_conditions = 0;
            state
        };
        QualityReport {
            state,
            score,
            explained: e,
            explained_avg: self.explained_avg,
            fit: fit.unwrap_or(ScanFit {
                explained: f32::NAN,
                short: f32::NAN,
                through: f32::NAN,
            }),
            ln_beam,
            ln_beam_fast: self.fast,
            ln_beam_slow: self.slow,
            spread_m,
            spread_rad,
            concentration,
        }
    }
}

/// Recovery in fixed memory, driven by the quality signal ([`MclConfig::with_resetting`](super::MclConfig::with_resetting);
/// off unless given).
///
/// **Expansion resetting** (Ueda et al., IROS 2004, as in emcl2): when this scan's explained
/// share at the estimate is below [`Resetting::expand_below`] (or, without it, the likelihood
/// drop is above the `lost_drop_nats` threshold), the cloud no longer covers the robot: the
/// update resamples the set by the weights it has, moves every particle by a normal step of
/// σ [`Resetting::sigma_m`] (x and y) and [`Resetting::sigma_rad`] (heading), and weighs it
/// again by the same scan (one more scoring pass, at those updates only). Same particle count,
/// in place. Each further expansion in a row doubles the σ, up to 2^[`Resetting::max_doublings`]
/// times.
///
/// **Free-space resetting**, the last resort: after [`Resetting::reset_after`] updates in a row
/// that reported [`Quality::Lost`] (expansion has not found the robot), the update replaces the
/// share [`Resetting::reset_fraction`] of the set by poses from the
/// [`FreeSpace`](crate::field::FreeSpace) passed to the update (none without one), and the
/// count starts again, as does the expansions' σ. With [`Resetting::reset_candidates`] `k` > 1
/// the new poses are chosen, not just drawn: `k` poses uniform over the free space are drawn and
/// scored by this update's scan for every place to fill, and the best-scoring ones are kept
/// (a sensor resetting in fixed memory: the candidates are scored one at a time and only the
/// kept ones are stored, in the set itself). That costs `k` scorings per replaced particle, at
/// reset updates only; with `k` ≤ 1 the poses are uniform draws, kept whatever they score.
///
/// **Spread over updates**: with [`Resetting::candidates_per_update`] `b` > 0, a reset scores
/// at most `b` candidates per update: the first `b` at the update that starts it, the rest
/// over the following updates, `b` each, against each update's own scan (the kept poses move
/// with the odometry in between and are scored by the update's ordinary weighing pass, so a
/// continuing reset costs `b` scorings more than an ordinary update and no second pass). The
/// weights stay uniform while it continues; it stops when all `m·k` candidates are scored or
/// at the first update that reports [`Quality::Tracking`]. `b` = 0 scores all of them at once.
///
/// **Settle guard**: while the quality has been `Tracking` for [`Resetting::settled_after`]
/// updates in a row, augmented MCL (Table 8.3) injects no random particles (a random particle
/// winning one scan is how a settled filter gets hijacked); the guard lifts at the first update
/// that is not `Tracking`. 0 turns the guard off.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Resetting {
    /// Explained share (0 to 1) of one scan below which the cloud is expanded.
    pub expand_below: f32,
    /// σ of the first expansion in x and y, metres.
    pub sigma_m: f32,
    /// σ of the first expansion in heading, radians.
    pub sigma_rad: f32,
    /// How many times the σ doubles over expansions in a row.
    pub max_doublings: u8,
    /// Updates in a row reported `Lost` before a free-space reset (0: never reset).
    pub reset_after: u16,
    /// Share of the particles a free-space reset replaces (0 to 1).
    pub reset_fraction: f32,
    /// Candidate poses drawn and scored per replaced particle at a free-space reset, the best
    /// kept (0 or 1: uniform draws, unscored).
    pub reset_candidates: u16,
    /// The most candidates scored per update (0: all at the update that starts the reset).
    pub candidates_per_update: u32,

    /// Updates in a row of `Tracking` after which random injections stop (0: no guard).
    pub settled_after: u16,
}

impl Resetting {
    /// The defaults: expand below 0.4 explained, σ 0.1 m and 0.05 rad doubling up to 8 times
    /// as much (0.8 m, 0.4 rad), a free-space reset of the whole set after 2 updates in a row
    /// reported `Lost`, the best of 100 candidates for each particle it replaces, all scored at
    /// the update that starts the reset (`candidates_per_update` 0: spreading them over
    /// updates bounds the cost of an update but slows the recovery from a kidnapping, see
    /// `docs/localization.md`), the settle guard after 20 updates of `Tracking`.
    pub const DEFAULT: Self = Self {
        expand_below: 0.4,
        sigma_m: 0.1,
        sigma_rad: 0.05,
        max_doublings: 3,
        reset_after: 2,
        reset_fraction: 1.0,
        reset_candidates: 100,
        candidates_per_update: 0,
        settled_after: 20,
    };

    /// True when every value is in range: shares in `[0, 1]`, σ finite and positive,
    /// `max_doublings ≤ 16`.
    pub fn validate(&self) -> bool {
        let unit = |v: f32| (0.0..=1.0).contains(&v);
        let pos = |v: f32| v.is_finite() && v > 0.0;
        unit(self.expand_below)
            && unit(self.reset_fraction)
            && pos(self.sigma_m)
            && pos(self.sigma_rad)
            && self.max_doublings <= 16
    }
}

impl Default for Resetting {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fit with share `e` explained and the rest through walls (no clutter).
    fn fit(e: f32) -> Option<ScanFit> {
        Some(ScanFit {
            explained: e,
            short: 0.0,
            through: 1.0 - e,
        })
    }

    const TIGHT: [[f32; 3]; 3] = [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]];

    #[test]
    fn defaults_validate_and_bad_values_do_not() {
        assert!(QualityThresholds::DEFAULT.validate());
        assert!(Resetting::DEFAULT.validate());
        let t = QualityThresholds {
            lost_explained: 0.9,
            ..QualityThresholds::DEFAULT
        };
        assert!(!t.validate());
        let t = QualityThresholds {
            dropping_nats: f32::NAN,
            ..QualityThresholds::DEFAULT
        };
        assert!(!t.validate());
        let t = QualityThresholds {
            lost_after: 0,
            ..QualityThresholds::DEFAULT
        };
        assert!(!t.validate());
        let r = Resetting {
            sigma_m: f32::INFINITY,
            ..Resetting::DEFAULT
        };
        assert!(!r.validate());
    }

    #[test]
    fn explained_share_decides_with_hysteresis() {
        let t = QualityThresholds::DEFAULT;
        let mut q = QualityState::NEW;
        for _ in 0..5 {
            let r = q.observe(&t, -1.0, fit(0.95), &TIGHT, 1.0);
            assert_eq!(r.state, Quality::Tracking);
            assert!((r.score - 0.95).abs() < 1e-3);
        }
        // One scan the map barely explains: the average dips, one update meets a Lost
        // condition, reported Uncertain (hysteresis).
        let r = q.observe(&t, -1.0, fit(0.0), &TIGHT, 1.0);
        assert_eq!(r.state, Quality::Uncertain, "{r:?}");
        let r = q.observe(&t, -1.0, fit(0.95), &TIGHT, 1.0);
        assert_ne!(r.state, Quality::Lost, "{r:?}");
        // A lasting loss.
        let mut last = Quality::Tracking;
        for _ in 0..4 {
            last = q.observe(&t, -3.0, fit(0.1), &TIGHT, 1.0).state;
        }
        assert_eq!(last, Quality::Lost);
        // A wide cloud is at best uncertain.
        let mut q = QualityState::NEW;
        let wide = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1e-4]];
        assert_eq!(
            q.observe(&t, -1.0, fit(0.95), &wide, 1.0).state,
            Quality::Uncertain
        );
        assert_eq!(
            q.observe(&t, -1.0, fit(0.95), &TIGHT, 0.2).state,
            Quality::Uncertain
        );
    }

    #[test]
    fn clutter_is_set_aside_up_to_its_share() {
        // The allowance the real-odometry study chose, the default.
        let t = QualityThresholds::DEFAULT;
        assert_eq!(t.clutter_share, 0.3);
        let fit = |explained: f32, short: f32| ScanFit {
            explained,
            short,
            through: 1.0 - explained - short,
        };
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        // Half the scan hidden by clutter in front of the walls: 0.3 of it set aside.
        assert!(close(t.explained_share(&fit(0.45, 0.55)), 0.45 / 0.7));
        // Readings through walls are not set aside.
        assert!(close(t.explained_share(&fit(0.45, 0.0)), 0.45));
        // Beyond the allowance (0.3) short readings count against the pose.
        assert!(close(t.explained_share(&fit(0.14, 0.86)), 0.2));
        let off = QualityThresholds {
            clutter_share: 0.0,
            ..t
        };
        assert!(close(off.explained_share(&fit(0.45, 0.55)), 0.45));
        assert!(!QualityThresholds {
            clutter_share: 1.0,
            ..t
        }
        .validate());
        // The clutter scans of the real Intel odometry (35–50 % explained, the rest short) do
        // not make a tracked filter Lost; without the allowance they do.
        for (thresholds, lost) in [(t, false), (off, true)] {
            let mut q = QualityState::NEW;
            for _ in 0..20 {
                q.observe(&thresholds, -1.0, Some(fit(0.95, 0.0)), &TIGHT, 1.0);
            }
            let mut any = false;
            for _ in 0..6 {
                let r = q.observe(&thresholds, -1.2, Some(fit(0.37, 0.62)), &TIGHT, 1.0);
                any |= r.state == Quality::Lost;
            }
            assert_eq!(any, lost, "clutter_share {}", thresholds.clutter_share);
        }
    }

    #[test]
    fn readings_through_mapped_walls_are_lost_where_clutter_is_set_aside() {
        // A kidnapping into a place the old estimate half explains: half the beams explained,
        // 0.3 short of a wall (set aside as clutter: the explained share is 0.5 / 0.7 = 0.71,
        // above `tracking_explained`), 0.2 through mapped walls.
        let t = QualityThresholds::DEFAULT;
        let kidnapped = ScanFit {
            explained: 0.5,
            short: 0.3,
            through: 0.2,
        };
        let clean = ScanFit {
            explained: 0.93,
            short: 0.0,
            through: 0.07,
        };
        let off = QualityThresholds {
            lost_through: 1.0,
            ..t
        };
        for (thresholds, lost_at) in [(t, Some(2)), (off, None)] {
            let mut q = QualityState::NEW;
            for _ in 0..20 {
                let r = q.observe(&thresholds, -1.0, Some(clean), &TIGHT, 1.0);
                assert_eq!(r.state, Quality::Tracking, "{r:?}");
            }
            let first_lost = (0..10).find(|_| {
                q.observe(&thresholds, -1.0, Some(kidnapped), &TIGHT, 1.0)
                    .state
                    == Quality::Lost
            });
            // Lost at the third update that meets the condition (the average of the share
            // through walls passes 0.12 at the first).
            assert_eq!(
                first_lost, lost_at,
                "lost_through {}",
                thresholds.lost_through
            );
        }
        assert!(!QualityThresholds {
            lost_through: 1.5,
            ..t
        }
        .validate());
    }

    #[test]
    fn without_a_scan_the_likelihood_drop_decides() {
        let t = QualityThresholds::DEFAULT;
        let mut q = QualityState::NEW;
        for _ in 0..50 {
            assert_eq!(
                q.observe(&t, -100.0, None, &TIGHT, 1.0).state,
                Quality::Tracking
            );
        }
        let mut states = [Quality::Tracking; 3];
        for s in &mut states {
            *s = q.observe(&t, -110.0, None, &TIGHT, 1.0).state;
        }
        // Lost from the third update that meets the condition (`lost_after` 3).
        assert_eq!(
            states,
            [Quality::Uncertain, Quality::Uncertain, Quality::Lost]
        );
        let r = q.observe(&t, f32::NAN, None, &TIGHT, 1.0);
        assert!(r.score.is_finite() && (0.0..=1.0).contains(&r.score));
    }
}
