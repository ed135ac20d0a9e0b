//! The particle filter: Monte Carlo localization (Thrun Table 8.2) with augmented-MCL recovery
//! (Table 8.3), on caller-placed storage.

use super::adaptive::Prior;
use super::config::{MclConfig, MclError, Particles, Update, MAX_PARTICLES, RETRY_LEVEL_RATE};
use super::estimate::{Estimate, Moments};
use super::kld::BinCount;
use super::motion::{sample_words, OdometryStep};
use super::quality::{Quality, QualityReport, QualityState};
use super::resample::{apply_counts, low_variance_counts_of_total};
use super::unexplained::{classify, scan_fit, ScanFit, Unexplained};
use crate::field::FreeSpace;
use crate::gaussian::{standard_normal_pair, uniform_f32};
use crate::math;
use crate::math::fast::exp_nonpositive;
use crate::model::SensorModel;
use crate::pose::{wrap_angle, Pose};
use crate::raycast::RayCaster;
use crate::scan::{BeamLayout, Scan};
use crate::tempered::TemperedScan;
use rand_core::Rng;

/// The estimate after an update is taken over the particles within this distance (metres) of
/// the highest-weighted one …
pub const ESTIMATE_RADIUS_M: f32 = 1.0;
/// … and within this heading difference (radians, about 29°); see [`Estimate::around`].
pub const ESTIMATE_HALF_ANGLE_RAD: f32 = 0.5;

/// What [`Mcl::reweight`] found.
struct Reweighted {
    /// `ln Σ wᵢ p(z | xᵢ)`, nats.
    ln_total: f32,
    /// The sum of the unnormalized weights left in the store.
    sum: f32,
    /// The estimate, with the ESS.
    estimate: Estimate,
    /// Some particle scored NaN (a NaN or infinite particle, or a NaN score): its weight is 0
    /// and it must go.
    impossible: bool,
    /// The share of the weight near the estimate's centre (0 to 1).
    concentration: f32,
    /// The largest log-weight; with `from_uniform`, particle `i`'s log-likelihood is
    /// `max + ln wᵢ` (the weights left in the store).
    max: f32,
    /// The weights before this weighing were uniform.
    from_uniform: bool,
    /// The highest-weighted particle.
    best: Pose,
}

/// Monte Carlo localization over caller-placed [`Particles`].
///
/// One cycle: [`Mcl::predict`] with the odometry step, then one of the update methods
/// ([`Mcl::update_prepared`], [`Mcl::update_model`], [`Mcl::update_with`]) with the scan.
/// Every update reweights the particles (`wᵢ ← wᵢ·p(z | xᵢ)`, in log space, normalized
/// as [`normalize_log_weights`](crate::normalize_log_weights) does), computes the [`Estimate`] (over the neighbourhood of the
/// highest-weighted particle, [`ESTIMATE_RADIUS_M`], [`ESTIMATE_HALF_ANGLE_RAD`]: AMCL likewise
/// reports its heaviest cluster, not the mean of the whole set), and resamples (Table 4.4) when the
/// effective sample size falls below the configured fraction or when recovery asks for random
/// particles.
///
/// # Recovery (Table 8.3)
/// `w_slow` and `w_fast` follow the average likelihood `w_avg` with rates `α_slow < α_fast`
/// (kept as logarithms: a scan likelihood of e⁻³⁰⁰ is normal and underflows f32). Both start at
/// the first `w_avg`. With [`Mcl::update_prepared`] and [`Mcl::update_model`], `w_avg` is taken
/// per scored beam (`ln w_avg` divided by the beam count, the geometric mean over the beams), so
/// that a scan with more or fewer beams does not by itself look like a collapse;
/// [`Mcl::update_with`] uses the log-likelihoods as given. At each update, `m = ⌊n·max(0, 1 − w_fast/w_slow) + u⌋` (stochastic
/// rounding, `u` uniform) particles are replaced at resampling by poses uniform over the
/// [`FreeSpace`] passed to the update; with no free space, none are.
#[derive(Debug)]
pub struct Mcl<'p, const N: usize> {
    store: &'p mut Particles<N>,
    len: usize,
    config: MclConfig,
    /// The weights are all `1/len` (skip their logarithm at the next update).
    uniform: bool,
    ln_w_slow: f32,
    ln_w_fast: f32,
    estimate: Estimate,
    /// The retry's level: an exponential average of the scaled `ln w_avg` (`−∞`
    /// before the first update).
    ln_level: f32,
    /// The last odometry step's spread for the retry: σ in x and y (metres) and in heading.
    retry_sigma_xy_m: f32,
    retry_sigma_theta_rad: f32,
    /// The quality signal's averages and its last report.
    quality_state: QualityState,
    quality: QualityReport,
    /// The covariance reported with the last update ([`Update::covariance`]).
    reported: [[f32; 3]; 3],
    /// Expansion resets in a row; updates in a row reported `Tracking`, and `Lost`.
    expansions: u16,
    tracking_streak: u16,
    lost_streak: u16,
    /// The adaptive motion noise's variance scale (1 when off).
    noise_scale: f32,
    /// A motion was predicted since the last update.
    moved: bool,
    /// Candidates of a free-space reset still to be scored at later updates.
    reset_pending: u32,
}

impl<'p, const N: usize> Mcl<'p, N> {
    /// A filter on `store`, not yet initialized.
    ///
    /// # Errors
    /// [`MclError::ZeroParticles`] for `N = 0`, [`MclError::TooManyParticles`] for `N` above
    /// [`MAX_PARTICLES`].
    pub fn new(store: &'p mut Particles<N>, config: MclConfig) -> Result<Self, MclError> {
        if N == 0 {
            return Err(MclError::ZeroParticles);
        }
        if N > MAX_PARTICLES {
            return Err(MclError::TooManyParticles);
        }
        Ok(Self {
            store,
            len: 0,
            config,
            uniform: true,
            ln_w_slow: f32::NEG_INFINITY,
            ln_w_fast: f32::NEG_INFINITY,
            estimate: Estimate::default(),
            ln_level: f32::NEG_INFINITY,
            retry_sigma_xy_m: 0.0,
            retry_sigma_theta_rad: 0.0,
            quality_state: QualityState::NEW,
            quality: QualityReport::default(),
            reported: [[0.0; 3]; 3],
            expansions: 0,
            tracking_streak: 0,
            lost_streak: 0,
            noise_scale: 1.0,
            moved: false,
            reset_pending: 0,
        })
    }

    fn check_count(count: usize) -> Result<(), MclError> {
        if count == 0 {
            Err(MclError::ZeroParticles)
        } else if count > N {
            Err(MclError::TooManyParticles)
        } else {
            Ok(())
        }
    }

    fn reset_weights(&mut self, count: usize) {
        self.len = count;
        let w = 1.0 / count as f32;
        self.store
            .weights
            .iter_mut()
            .take(count)
            .for_each(|x| *x = w);
        self.uniform = true;
        self.ln_w_slow = f32::NEG_INFINITY;
        self.ln_w_fast = f32::NEG_INFINITY;
        self.ln_level = f32::NEG_INFINITY;
        self.quality_state = QualityState::NEW;
        self.quality = QualityReport::default();
        self.reported = [[0.0; 3]; 3];
        self.expansions = 0;
        self.tracking_streak = 0;
        self.lost_streak = 0;
        self.noise_scale = 1.0;
        self.moved = false;
        self.reset_pending = 0;
        self.estimate = Estimate::of(self.poses(), self.weights());
    }

    /// Initializes `count` particles around `mean`: normal in x, y (σ `sigma_xy_m`, metres) and
    /// heading (σ `sigma_theta_rad`), independent; equal weights.
    ///
    /// # Random numbers
    /// Four `next_u32` per particle (two [`standard_normal_pair`]s; the last value is unused).
    ///
    /// # Errors
    /// [`MclError::ZeroParticles`], [`MclError::TooManyParticles`], [`MclError::BadInitialPose`]
    /// (nothing is changed on error).
    pub fn init_gaussian<R: Rng + ?Sized>(
        &mut self,
        count: usize,
        mean: &Pose,
        sigma_xy_m: f32,
        sigma_theta_rad: f32,
        rng: &mut R,
    ) -> Result<(), MclError> {
        Self::check_count(count)?;
        let ok = |s: f32| s.is_finite() && s >= 0.0;
        if !(mean.is_finite() && ok(sigma_xy_m) && ok(sigma_theta_rad)) {
            return Err(MclError::BadInitialPose);
        }
        for p in self.store.poses.iter_mut().take(count) {
            let (a, b) = standard_normal_pair(rng);
            let (c, _) = standard_normal_pair(rng);
            *p = Pose {
                x_m: mean.x_m + sigma_xy_m * a,
                y_m: mean.y_m + sigma_xy_m * b,
                theta_rad: wrap_angle(mean.theta_rad + sigma_theta_rad * c),
            };
        }
        self.reset_weights(count);
        Ok(())
    }

    /// Initializes `count` particles uniformly over the free cells of `free`, headings uniform
    /// ([`FreeSpace::sample_pose`], four `next_u32` per particle); equal weights.
    ///
    /// # Errors
    /// [`MclError::ZeroParticles`], [`MclError::TooManyParticles`].
    pub fn init_uniform<R: Rng + ?Sized>(
        &mut self,
        count: usize,
        free: &FreeSpace<'_>,
        rng: &mut R,
    ) -> Result<(), MclError> {
        Self::check_count(count)?;
        for p in self.store.poses.iter_mut().take(count) {
            *p = free.sample_pose(rng);
        }
        self.reset_weights(count);
        Ok(())
    }

    /// The particles in use.
    pub fn poses(&self) -> &[Pose] {
        self.store.poses.get(..self.len).unwrap_or(&[])
    }

    /// Their weights (summing to 1).
    pub fn weights(&self) -> &[f32] {
        self.store.weights.get(..self.len).unwrap_or(&[])
    }

    /// The number of particles in use (0 before initialization).
    pub fn len(&self) -> usize {
        self.len
    }

    /// True before initialization.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The latest estimate (of the initial set, before any update). With
    /// [`MclConfig::with_unexplained`] on, [`Mcl::predict`] moves its pose by each odometry
    /// step (without noise; the covariance and ESS stay the update's): the predicted estimate,
    /// where the next update classifies the beams.
    pub fn estimate(&self) -> &Estimate {
        &self.estimate
    }

    /// The covariance reported with the last update ([`Update::covariance`]; all zeros before
    /// the first update after an initialization).
    pub fn reported_covariance(&self) -> &[[f32; 3]; 3] {
        &self.reported
    }

    /// The quality signal of the last update ([`QualityReport`]; the default, `Uncertain`
    /// with NaN statistics, before the first update after an initialization).
    pub fn quality(&self) -> &QualityReport {
        &self.quality
    }

    /// The variance scale of the odometry noise in use: 1 unless the adaptive motion noise
    /// ([`MclConfig::with_adaptive_noise`]) is on, then within its bounds (1 after an
    /// initialization).
    pub fn noise_scale(&self) -> f32 {
        self.noise_scale
    }

    /// Candidates of a free-space reset still to be scored at later updates
    /// ([`Resetting::candidates_per_update`](super::Resetting::candidates_per_update); 0 when
    /// no reset is in progress).
    pub fn reset_pending(&self) -> u32 {
        self.reset_pending
    }

    /// The configuration.
    pub fn config(&self) -> &MclConfig {
        &self.config
    }

    /// Replaces the configuration (odometry noise, resampling threshold, recovery, retry) from
    /// the next [`Mcl::predict`] or update on; the particles and their weights stay as they are.
    /// The recovery averages restart, as after an initialization.
    pub fn set_config(&mut self, config: MclConfig) {
        self.config = config;
        self.ln_w_slow = f32::NEG_INFINITY;
        self.ln_w_fast = f32::NEG_INFINITY;
        self.ln_level = f32::NEG_INFINITY;
    }

    /// Moves every particle by a sample of the odometry motion model (Table 5.6; the model of
    /// [`OdometryNoise::sample`](super::OdometryNoise::sample)), in particle order. A step of
    /// exactly zero (the robot did not move) leaves the particles alone and draws nothing, as
    /// AMCL does not update when the robot stands still. With the adaptive motion noise
    /// ([`MclConfig::with_adaptive_noise`]) the standard deviations are those of the model times
    /// `√`[`Mcl::noise_scale`].
    ///
    /// # Random numbers
    /// Each particle draws one `next_u64` whose low and high halves start the normals of δrot1
    /// and δtrans; the normal of δrot2 starts from a half of a word shared by two particles:
    /// particle 0 draws a second `next_u64` and uses its low half, particle 1 uses its high
    /// half, particle 2 draws again, and so on (1.5 `next_u64` per particle). A normal that
    /// needs the ziggurat's slow path (about one in 80) draws further `next_u32` right away,
    /// in particle order.
    pub fn predict<R: Rng + ?Sized>(&mut self, step: &OdometryStep, rng: &mut R) {
        if *step == OdometryStep::STILL {
            self.retry_sigma_xy_m = 0.0;
            self.retry_sigma_theta_rad = 0.0;
            return;
        }
        if self.config.unexplained().is_some() {
            // The predicted estimate, where the next update classifies the beams.
            self.estimate.pose = step.apply(&self.estimate.pose);
        }
        let sigmas = self.config.noise.sigmas(step);
        let sigmas = if self.config.adaptive_noise.is_some() {
            self.moved = true;
            let k = math::sqrt(self.noise_scale);
            (k * sigmas.0, k * sigmas.1, k * sigmas.2)
        } else {
            sigmas
        };
        if self.config.retry() {
            let (s_rot1, s_trans, s_rot2) = sigmas;
            self.retry_sigma_xy_m = s_trans.max(step.trans_m() * s_rot1);
            self.retry_sigma_theta_rad = math::sqrt(s_rot1 * s_rot1 + s_rot2 * s_rot2);
        }
        let mut spare: Option<u32> = None;
        for p in self.store.poses.iter_mut().take(self.len) {
            let pair = rng.next_u64();
            let third = match spare.take() {
                Some(w) => w,
                None => {
                    let next = rng.next_u64();
                    spare = Some((next >> 32) as u32);
                    next as u32
                }
            };
            *p = sample_words(
                p,
                step,
                sigmas,
                [pair as u32, (pair >> 32) as u32, third],
                rng,
            );
        }
    }

    /// Replaces every particle `x` by `f(x)` (heading wrapped), keeping weights and the
    /// recovery averages: for a map-frame correction, or to simulate a kidnapping in a test.
    /// A non-finite result leaves that particle where it was. Returns how many moved. With
    /// [`MclConfig::with_unexplained`] on, the estimate's pose moves with them.
    pub fn move_particles<F: FnMut(&Pose) -> Pose>(&mut self, mut f: F) -> usize {
        if self.config.unexplained().is_some() {
            let q = f(&self.estimate.pose);
            if q.is_finite() {
                self.estimate.pose = Pose::new(q.x_m, q.y_m, wrap_angle(q.theta_rad));
            }
        }
        let mut moved = 0;
        for p in self.store.poses.iter_mut().take(self.len) {
            let q = f(p);
            if q.is_finite() {
                *p = Pose::new(q.x_m, q.y_m, wrap_angle(q.theta_rad));
                moved += 1;
            }
        }
        moved
    }

    /// Reweights by a prepared tempered likelihood-field scan ([`TemperedScan::score`]; the
    /// fast path) and finishes the update (see [`Mcl::update_with`]). With
    /// [`MclConfig::with_unexplained`] on, the beams unmapped at the predicted estimate are left
    /// out of the weighing ([`Update::unexplained`] counts them; the quality signal's explained
    /// share is still taken over every beam).
    ///
    /// # Errors
    /// [`MclError::EmptyScan`] when the prepared scan keeps no beam (skipped, nothing
    /// changed), and as [`Mcl::update_with`].
    pub fn update_prepared<R: Rng + ?Sized, const S: usize>(
        &mut self,
        scan: &TemperedScan<'_, S>,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> Result<Update, MclError> {
        if scan.prepared().is_empty() {
            return Err(MclError::EmptyScan);
        }
        if let Some(u) = self.config.unexplained() {
            return self.update_unexplained(scan, u, free, rng);
        }
        self.update_prepared_over(scan, scan, 0, free, rng)
    }

    /// [`Mcl::update_prepared`] with the unexplained beams left out (out of line: the stack of
    /// the flags and of the reduced scan is taken only when the option is on).
    #[inline(never)]
    fn update_unexplained<R: Rng + ?Sized, const S: usize>(
        &mut self,
        scan: &TemperedScan<'_, S>,
        u: Unexplained,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> Result<Update, MclError> {
        let mut flags = [false; S];
        let at = self.estimate.pose;
        let removed = classify(scan.prepared(), &at, &u, &mut flags);
        let reduced = (removed > 0)
            .then(|| scan.retain(|j| !flags.get(j).copied().unwrap_or(false)))
            .filter(|r| !r.prepared().is_empty());
        // One call site, so that the scoring loop is inlined once here.
        let (weigh, removed) = match &reduced {
            Some(r) => (r, u16::try_from(removed).unwrap_or(u16::MAX)),
            None => (scan, 0),
        };
        self.update_prepared_over(weigh, scan, removed, free, rng)
    }

    /// The prepared update: weights from `weigh`, the quality signal's explained share from
    /// `whole` (both non-empty).
    #[inline(always)]
    fn update_prepared_over<R: Rng + ?Sized, const S: usize>(
        &mut self,
        weigh: &TemperedScan<'_, S>,
        whole: &TemperedScan<'_, S>,
        removed: u16,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> Result<Update, MclError> {
        let per_beam = 1.0 / weigh.prepared().len() as f32;
        // The quality signal's explained share: one pass over the beams at the estimate.
        let prepared = whole.prepared();
        let near_m = self.config.quality.explained_sigmas * prepared.field().params().sigma_hit_m();
        // Casting separates readings in front of mapped walls from readings through them (a
        // field too coarse to cast counts every unexplained beam as through).
        let caster = RayCaster::new(*prepared.field().view()).ok();
        let explain = |p: &Pose| Some(scan_fit(prepared, p, near_m, caster.as_ref()));
        // The prepared scan scores a NaN or infinite pose NaN itself: no check per particle.
        let mut up = self.update_scaled::<false, _, _, _>(
            |p| weigh.score(p).log_likelihood,
            per_beam,
            explain,
            free,
            rng,
        )?;
        up.unexplained = removed;
        Ok(up)
    }

    /// Reweights by any [`SensorModel`] (e.g. a [`crate::Tempered`] beam model) and finishes the
    /// update (see [`Mcl::update_with`]).
    ///
    /// # Errors
    /// [`MclError::EmptyScan`] when the model scores no beam of `scan` at the first particle
    /// (skipped, nothing changed), and as [`Mcl::update_with`].
    pub fn update_model<M: SensorModel<S>, R: Rng + ?Sized, const S: usize>(
        &mut self,
        model: &M,
        layout: &BeamLayout<S>,
        scan: &Scan<S>,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> Result<Update, MclError> {
        let first = self
            .poses()
            .first()
            .copied()
            .ok_or(MclError::NotInitialized)?;
        if model.score(layout, scan, &first).scored == 0 {
            return Err(MclError::EmptyScan);
        }
        self.update_with(|p| model.score(layout, scan, p).log_likelihood, free, rng)
    }

    /// Reweights each particle by `ln p(z | xᵢ)` = `log_likelihood(xᵢ)` (nats), computes the
    /// estimate, and resamples when due, drawing recovery particles from `free`.
    ///
    /// A NaN log-likelihood counts as `−∞` (an impossible pose) and `+∞` as `f32::MAX`, so no
    /// input puts a NaN in the weights.
    ///
    /// # Random numbers
    /// One `next_u32` for the number of random particles; when resampling, one more for
    /// Table 4.4's offset and four per random particle ([`FreeSpace::sample_pose`]).
    ///
    /// # Errors
    /// [`MclError::NotInitialized`]; [`MclError::AllImpossible`] when every particle scores
    /// `−∞` (the weights are reset to uniform, the particles and averages kept).
    pub fn update_with<F: FnMut(&Pose) -> f32, R: Rng + ?Sized>(
        &mut self,
        log_likelihood: F,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> Result<Update, MclError> {
        self.update_scaled::<true, _, _, _>(log_likelihood, 1.0, |_| None, free, rng)
    }

    #[allow(clippy::too_many_lines)]
    /// The update; `CHECK`: a particle with a NaN or infinite coordinate is made impossible
    /// here, without asking `log_likelihood` (which may not know it is nowhere); without it,
    /// the scorer must score such a pose NaN itself (every scorer of the crate does).
    fn update_scaled<
        const CHECK: bool,
        F: FnMut(&Pose) -> f32,
        E: FnMut(&Pose) -> Option<ScanFit>,
        R: Rng + ?Sized,
    >(
        &mut self,
        mut log_likelihood: F,
        recovery_scale: f32,
        mut explain: E,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> Result<Update, MclError> {
        let n = self.len;
        if n == 0 {
            return Err(MclError::NotInitialized);
        }
        // The adaptive motion noise's prior: the predicted set, before the scan.
        let prior = match (self.config.adaptive_noise, self.moved) {
            (Some(_), true) => Prior::of(self.poses(), self.weights(), self.uniform),
            _ => None,
        };
        self.moved = false;
        // At most two weighings (the second after a retry or an expansion), from one call site
        // so that the score is inlined once.
        let mut first: Option<(f32, QualityReport)> = None;
        let mut retried = false;
        let mut expanded = false;
        let rw = loop {
            let Some(rw) = self.reweight::<CHECK, F>(&mut log_likelihood) else {
                self.reset_weights_only();
                return Err(MclError::AllImpossible);
            };
            if first.is_none() {
                // Σ wᵢ p(z|xᵢ) with Σ wᵢ = 1: the prior weights' logs were added, so the
                // normalizer's total is the average likelihood itself.
                let ln_beam = rw.ln_total * recovery_scale;
                let explained = explain(&rw.estimate.pose);
                let report = self.quality_state.observe(
                    &self.config.quality,
                    ln_beam,
                    explained,
                    &rw.estimate.covariance,
                    rw.concentration,
                );
                first = Some((rw.ln_total, report));
                if let (Some(a), Some(prior)) = (self.config.adaptive_noise, prior) {
                    self.noise_scale = a.next_scale(self.noise_scale, prior.nis(&rw.best));
                }
                if self.config.retry() && self.collapsed(ln_beam) {
                    self.resample(0, rw.sum, None, rng);
                    self.spread(rng);
                    retried = true;
                    continue;
                }
                if let Some(r) = self.config.resetting {
                    let lost = match explained {
                        Some(fit) => self.config.quality.explained_share(&fit) < r.expand_below,
                        None => {
                            report.ln_beam_slow - report.ln_beam_fast
                                > self.config.quality.lost_drop_nats
                        }
                    };
                    if lost {
                        let k = self.expansions.min(u16::from(r.max_doublings));
                        let grow = f32::from(1u16 << k.min(15));
                        self.expansions = self.expansions.saturating_add(1);
                        self.resample(0, rw.sum, None, rng);
                        self.spread_by(grow * r.sigma_m, grow * r.sigma_rad, rng);
                        expanded = true;
                        continue;
                    }
                    self.expansions = 0;
                }
            }
            break rw;
        };
        let (ln_avg, report) = first.unwrap_or((rw.ln_total, QualityReport::default()));
        self.quality = report;
        self.reported =
            self.config
                .covariance
                .reported(&rw.estimate.covariance, &self.reported, report.state);
        let covariance = self.reported;
        let mut random_fraction = self.track_likelihood(ln_avg * recovery_scale);
        let mut reset = false;
        if let Some(r) = self.config.resetting {
            if report.state == Quality::Tracking {
                self.tracking_streak = self.tracking_streak.saturating_add(1);
            } else {
                self.tracking_streak = 0;
            }
            if r.settled_after > 0 && self.tracking_streak >= r.settled_after {
                // The settle guard: no random particles while settled.
                random_fraction = 0.0;
            }
            if report.state == Quality::Lost {
                self.lost_streak = self.lost_streak.saturating_add(1);
            } else {
                self.lost_streak = 0;
            }
            if r.reset_after > 0 && self.lost_streak >= r.reset_after && free.is_some() {
                random_fraction = random_fraction.max(r.reset_fraction);
                self.lost_streak = 0;
                // The next expansion starts from the first σ: the fresh particles are not to
                // be blurred by the widest step.
                self.expansions = 0;
                reset = true;
            }
        }
        self.estimate = rw.estimate;
        if report.state == Quality::Tracking {
            // Found (or never lost): a reset in progress stops.
            self.reset_pending = 0;
        }
        if let (Some(r), Some(free)) = (self.config.resetting, free) {
            let m = ((n as f32 * r.reset_fraction) as usize).clamp(1, n);
            let batch = |left: u32| match r.candidates_per_update {
                0 => left,
                b => left.min(b),
            };
            let started = reset && r.reset_candidates > 1;
            let continued = !reset && self.reset_pending > 0 && r.reset_candidates > 1;
            if started || continued {
                let left = if started {
                    u32::try_from(m.saturating_mul(usize::from(r.reset_candidates)))
                        .unwrap_or(u32::MAX)
                } else {
                    self.reset_pending
                };
                let now = batch(left);
                self.reset_pending = left - now;
                let scored = continued && rw.from_uniform && !rw.impossible;
                if scored {
                    // The kept poses' scores are this weighing's log-likelihoods.
                    let max = rw.max;
                    self.store
                        .weights
                        .iter_mut()
                        .take(n)
                        .for_each(|w| *w = max + math::ln(*w));
                } else {
                    // The survivors first (all of the set's places are then equal), then the m
                    // places compete with the candidates.
                    self.resample(0, rw.sum, None, rng);
                }
                let replaced = self.fill_by_selection(
                    m,
                    now as usize,
                    !scored,
                    free,
                    &mut log_likelihood,
                    rng,
                );
                return Ok(Update {
                    estimate: rw.estimate,
                    covariance,
                    ln_avg_likelihood: ln_avg,
                    random_fraction,
                    resampled: true,
                    injected: replaced,
                    retried,
                    quality: report,
                    expanded,
                    reset: started && replaced > 0,
                    unexplained: 0,
                });
            }
        }
        let u = uniform_f32(rng);
        let m = if free.is_some() {
            ((n as f32 * random_fraction + u) as usize).min(n)
        } else {
            0
        };
        let due = self.resampling_due(rw.estimate.ess, rw.impossible) || m > 0;
        let mut injected = 0u16;
        if due && self.config.kld.is_some() {
            injected = self.resample_kld(m, rw.sum, free, rng);
        } else if due {
            injected = self.resample(m, rw.sum, free, rng);
        } else {
            let inv = 1.0 / rw.sum;
            self.store
                .weights
                .iter_mut()
                .take(n)
                .for_each(|w| *w *= inv);
        }
        Ok(Update {
            estimate: rw.estimate,
            covariance,
            ln_avg_likelihood: ln_avg,
            random_fraction,
            resampled: due,
            injected,
            retried,
            quality: report,
            expanded,
            reset: reset && injected > 0,
            unexplained: 0,
        })
    }

    /// `wᵢ ← wᵢ·p(z | xᵢ)` in log space, and the estimate, in two passes. Pass 1: the
    /// log-weights `ln wᵢ + ln p(z | xᵢ)` (the first term skipped while the weights are uniform,
    /// and added to the total instead) and their maximum, whose particle is the estimate's
    /// centre. Pass 2: the weights `eᵢ = e^{vᵢ − max}` ([`exp_nonpositive`], within 2.6e-7
    /// relative of `e^x`), their sum `S` (plain f32: `S ≥ 1`, so its relative rounding error is
    /// below `n·2⁻²⁴`, 0.03 % at 5,000 particles, and it scales all weights alike, the resampling
    /// included, which uses `S` itself), `Σ eᵢ²`, and the estimate's
    /// sums over the centre's neighbourhood ([`Estimate::around`], which renormalizes, so the
    /// weights need not be). The weights are left unnormalized (`eᵢ`, summing to `S`): the
    /// caller resamples from them or divides them by `S`. None when every particle is
    /// impossible (the weights are then garbage: the caller resets them).
    fn reweight<const CHECK: bool, F: FnMut(&Pose) -> f32>(
        &mut self,
        log_likelihood: &mut F,
    ) -> Option<Reweighted> {
        let n = self.len;
        let uniform = self.uniform;
        let (poses, weights) = (&self.store.poses, &mut self.store.weights);
        // Two loops rather than a test per particle: with uniform weights the prior's log is
        // the same for all and goes into the total below.
        let (max, best, impossible) = if uniform {
            log_weights::<false, CHECK, F>(poses, weights, n, log_likelihood)
        } else {
            log_weights::<true, CHECK, F>(poses, weights, n, log_likelihood)
        };
        if max == f32::NEG_INFINITY {
            return None;
        }
        let center = poses.get(best).copied().unwrap_or_default();
        let mut near = Moments::new(&center, ESTIMATE_RADIUS_M, ESTIMATE_HALF_ANGLE_RAD);
        // S = Σ e^{v − max} ∈ [1, n]: the best particle contributes exactly 1.
        let (mut sum, mut sum_sq) = (0.0f32, 0.0f32);
        for (p, w) in poses.iter().zip(weights.iter_mut()).take(n) {
            let e = exp_nonpositive(*w - max);
            *w = e;
            sum += e;
            sum_sq += e * e;
            near.add_if_near(p, e);
        }
        self.uniform = false;
        let ln_uniform = if uniform { -math::ln(n as f32) } else { 0.0 };
        // The centre is near itself with weight 1, so there is always an estimate.
        let mut estimate = near.estimate().unwrap_or_default();
        estimate.ess = sum * sum / sum_sq;
        Some(Reweighted {
            ln_total: max + math::ln(sum) + ln_uniform,
            sum,
            estimate,
            impossible,
            concentration: (near.weight() / sum).clamp(0.0, 1.0),
            max,
            from_uniform: uniform,
            best: center,
        })
    }

    /// Whether the set is resampled at this update (recovery aside): when the effective sample
    /// size `ess` falls below the configured fraction of the way from a degenerate set (ESS 1)
    /// to an even one (ESS `n`), `ess − 1 < f·(n − 1)`, or when some particle scored NaN (a NaN
    /// or infinite particle, which must not stay in the set). The ESS of a set is never below 1, so the plain
    /// `ess < f·n` could never fire for `f·n ≤ 1` (2 particles at `f` = 0.5); for hundreds
    /// of particles the two differ by half a particle.
    fn resampling_due(&self, ess: f32, impossible: bool) -> bool {
        let n = self.len as f32;
        let f = self.config.resample_ess_fraction;
        impossible || (f > 0.0 && ess - 1.0 < f * (n - 1.0))
    }

    fn reset_weights_only(&mut self) {
        let w = 1.0 / self.len as f32;
        self.store
            .weights
            .iter_mut()
            .take(self.len)
            .for_each(|x| *x = w);
        self.uniform = true;
    }

    /// The retry's test ([`MclConfig::with_retry`]): is `ln_avg` more than the threshold below
    /// the level? Then moves the level towards `ln_avg`. Never after a zero step.
    fn collapsed(&mut self, ln_avg: f32) -> bool {
        let level = self.ln_level;
        if level == f32::NEG_INFINITY {
            self.ln_level = ln_avg;
            return false;
        }
        let collapsed = ln_avg < level - self.config.retry_drop_nats;
        if ln_avg.is_finite() {
            self.ln_level = level + RETRY_LEVEL_RATE * (ln_avg - level);
        }
        let moved = self.retry_sigma_xy_m > 0.0 || self.retry_sigma_theta_rad > 0.0;
        collapsed && moved
    }

    /// Moves every particle by a normal step, σ the last odometry step's spread (σ_xy the
    /// larger of σ_trans and δtrans·σ_rot1, σ_θ = √(σ_rot1² + σ_rot2²)) times the retry scale:
    /// the retry's second proposal. Two [`standard_normal_pair`]s per particle.
    fn spread<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        let k = self.config.retry_scale;
        self.spread_by(
            k * self.retry_sigma_xy_m,
            k * self.retry_sigma_theta_rad,
            rng,
        );
    }

    /// Moves every particle by a normal step of σ `s_xy` (metres, x and y) and `s_theta`
    /// (radians). Two [`standard_normal_pair`]s per particle.
    fn spread_by<R: Rng + ?Sized>(&mut self, s_xy: f32, s_theta: f32, rng: &mut R) {
        for p in self.store.poses.iter_mut().take(self.len) {
            let (a, b) = standard_normal_pair(rng);
            let (c, _) = standard_normal_pair(rng);
            *p = Pose {
                x_m: p.x_m + s_xy * a,
                y_m: p.y_m + s_xy * b,
                theta_rad: wrap_angle(p.theta_rad + s_theta * c),
            };
        }
    }

    /// Table 8.3's averages, in log space; returns `max(0, 1 − w_fast/w_slow)`.
    fn track_likelihood(&mut self, ln_avg: f32) -> f32 {
        if !self.config.recovery() {
            return 0.0;
        }
        let follow = |ln_w: f32, alpha: f32| {
            if ln_w == f32::NEG_INFINITY {
                ln_avg
            } else {
                // ln((1 − α)·w + α·w_avg).
                math::log_add_exp(math::ln(1.0 - alpha) + ln_w, math::ln(alpha) + ln_avg)
            }
        };
        self.ln_w_slow = follow(self.ln_w_slow, self.config.recovery_alpha_slow);
        self.ln_w_fast = follow(self.ln_w_fast, self.config.recovery_alpha_fast);
        let ratio = math::exp(self.ln_w_fast - self.ln_w_slow);
        if ratio.is_nan() {
            0.0
        } else {
            (1.0 - ratio).max(0.0)
        }
    }

    /// Sensor resetting in fixed memory ([`Resetting::reset_candidates`]): the particles at
    /// the `m` places `⌊j·n/m⌋` (`j` < `m`, spread over the set) are scored by
    /// `log_likelihood` (when `rescore`; otherwise their weights hold their scores already)
    /// and compete with `candidates` poses drawn uniformly from `free` (four `next_u32` each,
    /// [`FreeSpace::sample_pose`]), scored one at a time: each candidate that scores better
    /// than the worst kept one takes its place (a NaN score never wins). So a cloud that was
    /// right after all (a false `Lost`) keeps its particles, and one that was wrong gives way.
    /// The weights are left uniform. Returns the places taken by candidates.
    fn fill_by_selection<F: FnMut(&Pose) -> f32, R: Rng + ?Sized>(
        &mut self,
        m: usize,
        candidates: usize,
        rescore: bool,
        free: &FreeSpace<'_>,
        log_likelihood: &mut F,
        rng: &mut R,
    ) -> u16 {
        let n = self.len;
        let m = m.min(n);
        if m == 0 {
            return 0;
        }
        let place = |j: usize| j * n / m;
        let poses = &mut self.store.poses;
        // The kept poses' scores sit in the weights of their places until the end.
        let scores = &mut self.store.weights;
        let finite = |l: f32| if l.is_nan() { f32::NEG_INFINITY } else { l };
        for j in 0..m {
            if let (Some(p), Some(w)) = (poses.get(place(j)), scores.get_mut(place(j))) {
                *w = if rescore {
                    finite(log_likelihood(p))
                } else {
                    finite(*w)
                };
            }
        }
        let worst_of = |scores: &[f32]| {
            let (mut worst, mut at) = (f32::INFINITY, 0usize);
            for j in 0..m {
                let w = scores.get(place(j)).copied().unwrap_or(f32::NEG_INFINITY);
                if w < worst {
                    worst = w;
                    at = j;
                }
            }
            (worst, at)
        };
        let (mut worst, mut worst_at) = worst_of(scores);
        let mut taken = 0u16;
        for _ in 0..candidates {
            let pose = free.sample_pose(rng);
            let l = finite(log_likelihood(&pose));
            if l > worst {
                if let (Some(p), Some(w)) = (
                    poses.get_mut(place(worst_at)),
                    scores.get_mut(place(worst_at)),
                ) {
                    *p = pose;
                    *w = l;
                }
                taken = taken.saturating_add(1);
                // Found again after each change (they get rarer as the kept ones improve).
                (worst, worst_at) = worst_of(scores);
            }
        }
        self.reset_weights_only();
        taken
    }

    /// KLD sampling ([`MclConfig::with_kld`]): the new count `n'` from the bins of the
    /// particles the resampling would draw at the largest count (weight at least half of
    /// `total/max`), then low-variance resampling of `n' − m` particles and `m` random ones
    /// from `free` (`m` at most `n'`), in place; `self.len` becomes `n'` (`n' − m` without a
    /// free space).
    fn resample_kld<R: Rng + ?Sized>(
        &mut self,
        m: usize,
        total: f32,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> u16 {
        let Some(k) = self.config.kld else {
            return self.resample(m, total, free, rng);
        };
        let n = self.len;
        let hi = usize::from(k.max).min(N);
        let mut bins = BinCount::new(&k);
        let at_least = 0.5 * total / hi as f32;
        for (p, &w) in self.store.poses.iter().zip(&self.store.weights).take(n) {
            if w >= at_least {
                bins.add(p);
            }
        }
        let target = k.count(bins.bins(), N);
        let m = if free.is_some() { m.min(target) } else { 0 };
        let draws = u16::try_from(target - m).unwrap_or(u16::MAX);
        let slots = n.max(target);
        let store = &mut *self.store;
        let (weights, counts, poses) = (
            store.weights.get(..n).unwrap_or(&[]),
            store.counts.get_mut(..slots).unwrap_or(&mut []),
            store.poses.get_mut(..slots).unwrap_or(&mut []),
        );
        counts.iter_mut().skip(n).for_each(|c| *c = 0);
        low_variance_counts_of_total(
            weights,
            total,
            counts.get_mut(..n).unwrap_or(&mut []),
            draws,
            rng,
        );
        apply_counts(poses, counts);
        let mut injected = 0u16;
        if let Some(free) = free {
            for (p, c) in poses.iter_mut().zip(counts.iter_mut()) {
                if usize::from(injected) >= m {
                    break;
                }
                if *c == 0 {
                    *p = free.sample_pose(rng);
                    *c = 1;
                    injected = injected.saturating_add(1);
                }
            }
        }
        // The filled slots to the front, in order.
        let mut kept = 0usize;
        for i in 0..slots {
            if counts.get(i).copied().unwrap_or(0) != 0 {
                if let Some(p) = poses.get(i).copied() {
                    if let Some(q) = poses.get_mut(kept) {
                        *q = p;
                    }
                }
                kept += 1;
            }
        }
        self.len = kept.max(1);
        self.reset_weights_only();
        injected
    }

    /// Low-variance resampling of `n − m` particles and `m` random ones from `free`, in place.
    fn resample<R: Rng + ?Sized>(
        &mut self,
        m: usize,
        total: f32,
        free: Option<&FreeSpace<'_>>,
        rng: &mut R,
    ) -> u16 {
        let n = self.len;
        let draws = u16::try_from(n - m).unwrap_or(u16::MAX);
        let store = &mut *self.store;
        let (weights, counts, poses) = (
            store.weights.get(..n).unwrap_or(&[]),
            store.counts.get_mut(..n).unwrap_or(&mut []),
            store.poses.get_mut(..n).unwrap_or(&mut []),
        );
        low_variance_counts_of_total(weights, total, counts, draws, rng);
        apply_counts(poses, counts);
        let mut injected = 0u16;
        if let Some(free) = free {
            for (p, &c) in poses.iter_mut().zip(counts.iter()) {
                if c == 0 {
                    *p = free.sample_pose(rng);
                    injected = injected.saturating_add(1);
                }
            }
        }
        self.reset_weights_only();
        injected
    }
}

/// Pass 1 of [`Mcl::reweight`]: `wᵢ ← ln p(z | xᵢ)` (plus `ln wᵢ` when `PRIOR`) for the first
/// `n` particles, a NaN log-likelihood (and, with `CHECK`, a particle with a NaN or infinite
/// coordinate) counting as `−∞` and `+∞` clamped to `f32::MAX`; returns the largest, its
/// index (the first on ties), and whether some score was NaN.
#[inline]
fn log_weights<const PRIOR: bool, const CHECK: bool, F: FnMut(&Pose) -> f32>(
    poses: &[Pose],
    weights: &mut [f32],
    n: usize,
    log_likelihood: &mut F,
) -> (f32, usize, bool) {
    let mut max = f32::NEG_INFINITY;
    let mut best = 0usize;
    let mut nan = false;
    for (i, (p, w)) in poses.iter().zip(weights.iter_mut()).take(n).enumerate() {
        // A particle with a NaN or infinite coordinate is nowhere: impossible, whatever the
        // scorer would say (it is not asked).
        let l = if !CHECK || p.is_finite() {
            log_likelihood(p)
        } else {
            f32::NAN
        };
        let l = if l <= f32::MAX {
            l
        } else if l.is_nan() {
            // Off the hot path: only NaN scores (a NaN or infinite particle) come here.
            nan = true;
            f32::NEG_INFINITY
        } else {
            f32::MAX
        };
        let v = if PRIOR { math::ln(*w) + l } else { l };
        *w = v;
        if v > max {
            max = v;
            best = i;
        }
    }
    (max, best, nan)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcl::{OdometryNoise, SplitMix64};

    fn config() -> MclConfig {
        MclConfig::new(OdometryNoise::uniform(0.005).unwrap(), 0.5, 0.001, 0.1).unwrap()
    }

    #[test]
    fn eighteen_bytes_per_particle() {
        assert_eq!(core::mem::size_of::<Particles<1000>>(), 18 * 1000);
        let fixed = core::mem::size_of::<Mcl<'_, 1000>>();
        // 416 on a 64-bit host: the quality signal's thresholds and averages (the slow
        // average of the explained share and the share through walls included) and its last
        // scan fit, the recovery's counters, the last
        // reported covariance and how it is made, the adaptive motion noise's and KLD
        // sampling's parameters, the noise scale, the reset in progress; nothing per particle.
        assert!(fixed <= 416, "{fixed}");
        println!("Mcl: {fixed} bytes besides the particles");
    }

    #[test]
    fn capacity_and_count_errors() {
        let mut empty = Particles::<0>::new();
        assert_eq!(
            Mcl::new(&mut empty, config()).err(),
            Some(MclError::ZeroParticles)
        );
        let mut store = Particles::<8>::new();
        let mut f = Mcl::new(&mut store, config()).unwrap();
        let mut rng = SplitMix64::new(1);
        assert_eq!(
            f.update_with(|_| 0.0, None, &mut rng).err(),
            Some(MclError::NotInitialized)
        );
        let origin = Pose::default();
        assert_eq!(
            f.init_gaussian(0, &origin, 0.1, 0.1, &mut rng),
            Err(MclError::ZeroParticles)
        );
        assert_eq!(
            f.init_gaussian(9, &origin, 0.1, 0.1, &mut rng),
            Err(MclError::TooManyParticles)
        );
        assert_eq!(
            f.init_gaussian(8, &Pose::new(f32::NAN, 0.0, 0.0), 0.1, 0.1, &mut rng),
            Err(MclError::BadInitialPose)
        );
        assert!(f.is_empty());
        assert_eq!(
            MclConfig::new(OdometryNoise::uniform(0.0).unwrap(), 0.5, 0.2, 0.1).err(),
            Some(MclError::BadConfig)
        );
        assert_eq!(
            MclConfig::new(OdometryNoise::uniform(0.0).unwrap(), f32::NAN, 0.0, 0.0).err(),
            Some(MclError::BadConfig)
        );
    }

    #[test]
    fn all_impossible_and_nan_scores() {
        let mut store = Particles::<16>::new();
        let mut f = Mcl::new(&mut store, config()).unwrap();
        let mut rng = SplitMix64::new(2);
        f.init_gaussian(16, &Pose::new(1.0, 2.0, 0.5), 0.2, 0.1, &mut rng)
            .unwrap();
        let before: Vec<Pose> = f.poses().to_vec();
        assert_eq!(
            f.update_with(|_| f32::NEG_INFINITY, None, &mut rng).err(),
            Some(MclError::AllImpossible)
        );
        assert_eq!(f.poses(), &before[..]);
        assert!(f.weights().iter().all(|&w| w == 1.0 / 16.0));
        // NaN scores are impossible poses; the one finite particle takes all the weight.
        let keep = before[3];
        let up = f
            .update_with(|p| if *p == keep { -5.0 } else { f32::NAN }, None, &mut rng)
            .unwrap();
        assert!(up.resampled);
        assert!(f.poses().iter().all(|p| *p == keep));
        assert_eq!(up.estimate.pose.x_m, keep.x_m);
    }

    #[test]
    fn converges_on_a_synthetic_likelihood() {
        // ln p = −|x − x*|²/(2·0.05²) − … : the cloud (σ 0.5 m, 0.3 rad) must close on the peak
        // while the robot drives 0.3 m per step along +x with exact odometry.
        let mut store = Particles::<500>::new();
        let mut f = Mcl::new(&mut store, config()).unwrap();
        let mut rng = SplitMix64::new(3);
        let mut truth = Pose::new(0.0, 0.0, 0.0);
        f.init_gaussian(500, &Pose::new(0.3, -0.2, 0.2), 0.5, 0.3, &mut rng)
            .unwrap();
        let step = OdometryStep::new(0.0, 0.3, 0.0).unwrap();
        for _ in 0..30 {
            truth = step.apply(&truth);
            f.predict(&step, &mut rng);
            let t = truth;
            f.update_with(
                |p| {
                    let (dx, dy, dt) = (
                        p.x_m - t.x_m,
                        p.y_m - t.y_m,
                        wrap_angle(p.theta_rad - t.theta_rad),
                    );
                    -(dx * dx + dy * dy) / (2.0 * 0.05 * 0.05) - dt * dt / (2.0 * 0.02 * 0.02)
                },
                None,
                &mut rng,
            )
            .unwrap();
            assert!(f.poses().iter().all(Pose::is_finite));
        }
        let e = f.estimate().pose;
        assert!(
            (e.x_m - truth.x_m).abs() < 0.05 && e.y_m.abs() < 0.05,
            "{e:?} vs {truth:?}"
        );
        assert!(e.theta_rad.abs() < 0.03, "{e:?}");
    }

    #[test]
    fn retry_config_is_validated() {
        let c = config();
        assert!(!c.retry());
        assert!(c.with_retry(0.1, 0.5).unwrap().retry());
        assert!(c.with_retry(f32::NEG_INFINITY, 2.0).unwrap().retry());
        assert!(c.with_retry(0.1, crate::mcl::MAX_RETRY_SCALE).is_ok());
        assert!(!c.with_retry(f32::INFINITY, 1.0).unwrap().retry());
        for (d, k) in [
            (f32::NAN, 1.0),
            (0.1, 0.0),
            (0.1, -1.0),
            (0.1, f32::INFINITY),
            (f32::NEG_INFINITY, 1e30),
            (0.1, 1_000.5),
        ] {
            assert_eq!(
                c.with_retry(d, k).err(),
                Some(MclError::BadConfig),
                "{d} {k}"
            );
        }
    }

    /// Runs 12 updates of a cloud driven 0.5 m per step along +x, scored by a narrow
    /// Gaussian around `truth`; at update 8 the truth is 0.3 m off the odometry (the prediction
    /// misses it). Returns the updates' `retried` flags and the final estimate's x error.
    fn drive(config: MclConfig) -> (Vec<bool>, f32) {
        let mut store = Particles::<300>::new();
        let mut f = Mcl::new(&mut store, config).unwrap();
        let mut rng = SplitMix64::new(7);
        f.init_gaussian(300, &Pose::default(), 0.02, 0.01, &mut rng)
            .unwrap();
        let step = OdometryStep::new(0.0, 0.5, 0.0).unwrap();
        let mut truth = Pose::default();
        let mut retried = Vec::new();
        for k in 0..12 {
            truth = step.apply(&truth);
            if k == 8 {
                truth.y_m += 0.3;
            }
            f.predict(&step, &mut rng);
            let t = truth;
            let up = f
                .update_with(
                    |p| -((p.x_m - t.x_m).powi(2) + (p.y_m - t.y_m).powi(2)) / (2.0 * 0.03 * 0.03),
                    None,
                    &mut rng,
                )
                .unwrap();
            assert!(f.poses().iter().all(Pose::is_finite));
            retried.push(up.retried);
        }
        (retried, (f.estimate().pose.y_m - truth.y_m).abs())
    }

    /// Drives a 300-particle cloud 0.5 m per step along +x for 60 updates with the odometry
    /// saying exactly that, while the truth also wanders by a normal step of σ `extra_m` in x
    /// and y (drawn from its own generator); the scan is a narrow Gaussian (3 cm) around the
    /// truth. Returns the noise scale after each update and the last x–y error.
    fn wander(config: MclConfig, extra_m: f32) -> (Vec<f32>, f32) {
        let mut store = Particles::<300>::new();
        let mut f = Mcl::new(&mut store, config).unwrap();
        let mut rng = SplitMix64::new(11);
        let mut world = SplitMix64::new(12);
        f.init_gaussian(300, &Pose::default(), 0.02, 0.01, &mut rng)
            .unwrap();
        let step = OdometryStep::new(0.0, 0.5, 0.0).unwrap();
        let mut truth = Pose::default();
        let mut scales = Vec::new();
        for _ in 0..60 {
            let (a, b) = standard_normal_pair(&mut world);
            truth = step.apply(&truth);
            truth.x_m += extra_m * a;
            truth.y_m += extra_m * b;
            f.predict(&step, &mut rng);
            let t = truth;
            f.update_with(
                |p| -((p.x_m - t.x_m).powi(2) + (p.y_m - t.y_m).powi(2)) / (2.0 * 0.03 * 0.03),
                None,
                &mut rng,
            )
            .unwrap();
            assert!(f.poses().iter().all(Pose::is_finite));
            scales.push(f.noise_scale());
        }
        let e = f.estimate().pose;
        (scales, (e.x_m - truth.x_m).hypot(e.y_m - truth.y_m))
    }

    #[test]
    fn adaptive_noise_widens_for_bad_odometry_and_narrows_for_good() {
        use crate::mcl::AdaptiveNoise;
        // The model: α 0.001, σ_trans = √(0.001·0.25) ≈ 1.6 cm per 0.5 m step.
        let base = MclConfig::new(OdometryNoise::uniform(0.001).unwrap(), 0.5, 0.0, 0.0).unwrap();
        let a = AdaptiveNoise::DEFAULT;
        let on = base.with_adaptive_noise(Some(a)).unwrap();
        // Off: the scale never moves.
        let (off, _) = wander(base, 0.08);
        assert!(off.iter().all(|&q| q == 1.0));
        // Odometry 8 cm off per step, five times the model's σ: the scale grows to its bound
        // (the variance would need about 25×; the default bound is 4) and the filter keeps up.
        let (bad, err) = wander(on, 0.08);
        assert!(bad
            .iter()
            .all(|&q| (a.min_scale..=a.max_scale).contains(&q)));
        let late = bad[40..].iter().sum::<f32>() / 20.0;
        assert!(late > 0.9 * a.max_scale, "{bad:?}");
        assert!(err < 0.1, "{err}");
        // Exact odometry with a model 20× too wide (α 0.02): the scale shrinks (on average
        // well below 1; the floor is 0.25).
        let wide = MclConfig::new(OdometryNoise::uniform(0.02).unwrap(), 0.5, 0.0, 0.0)
            .unwrap()
            .with_adaptive_noise(Some(a))
            .unwrap();
        let (good, err) = wander(wide, 0.0);
        let late = good[20..].iter().sum::<f32>() / 40.0;
        assert!(late < 0.75, "{good:?}");
        assert!(err < 0.05, "{err}");
        // Refused values.
        assert_eq!(
            base.with_adaptive_noise(Some(AdaptiveNoise { rate: 0.0, ..a }))
                .err(),
            Some(MclError::BadConfig)
        );
    }

    #[test]
    fn kld_count_grows_with_the_spread_and_shrinks_back() {
        use crate::mcl::Kld;
        let kld = Kld {
            min: 100,
            max: 2000,
            ..Kld::NAV2
        };
        // Wide motion noise: σ_trans ≈ 0.7 m per 1 m step.
        let config = MclConfig::new(OdometryNoise::uniform(0.5).unwrap(), 1.0, 0.0, 0.0)
            .unwrap()
            .with_kld(Some(kld))
            .unwrap();
        let mut store = Particles::<3000>::new();
        let mut f = Mcl::new(&mut store, config).unwrap();
        let mut rng = SplitMix64::new(9);
        f.init_gaussian(100, &Pose::default(), 0.02, 0.01, &mut rng)
            .unwrap();
        let step = OdometryStep::new(0.0, 1.0, 0.0).unwrap();
        let mut counts = Vec::new();
        // Ten steps scored by an almost flat likelihood: the cloud spreads over many bins.
        for _ in 0..10 {
            f.predict(&step, &mut rng);
            let up = f
                .update_with(|p| 0.01 * (37.0 * p.x_m).sin(), None, &mut rng)
                .unwrap();
            assert!(up.resampled);
            counts.push(f.len());
        }
        // Then a sharp one (5 cm) around a pose in the cloud: it collapses.
        let at = f.estimate().pose;
        for _ in 0..5 {
            f.update_with(
                |p| -((p.x_m - at.x_m).powi(2) + (p.y_m - at.y_m).powi(2)) / (2.0 * 0.05 * 0.05),
                None,
                &mut rng,
            )
            .unwrap();
            counts.push(f.len());
        }
        assert!(
            counts.iter().all(|&n| (100..=2000).contains(&n)),
            "{counts:?}"
        );
        assert_eq!(counts[..10].iter().max(), Some(&2000), "{counts:?}");
        assert_eq!(*counts.last().unwrap(), 100, "{counts:?}");
        assert_eq!(f.weights().len(), f.len());
        assert!(f.poses().iter().all(Pose::is_finite));
        // A capacity below max: never more than the capacity.
        let mut small = Particles::<500>::new();
        let mut g = Mcl::new(&mut small, config).unwrap();
        g.init_gaussian(100, &Pose::default(), 0.02, 0.01, &mut rng)
            .unwrap();
        for _ in 0..10 {
            g.predict(&step, &mut rng);
            g.update_with(|p| 0.01 * (37.0 * p.x_m).sin(), None, &mut rng)
                .unwrap();
            assert!(g.len() <= 500);
        }
        assert_eq!(g.len(), 500);
    }

    #[test]
    fn a_reset_is_spread_over_updates() {
        use crate::field::{emit_free_space, free_space_len, FreeSpaceGrid};
        use crate::mcl::Resetting;
        use core::cell::Cell;
        // 10 m × 10 m, every 0.25 m cell free.
        let grid = FreeSpaceGrid {
            width: 40,
            height: 40,
            cell_size_m: 0.25,
            origin_x_m: 0.0,
            origin_y_m: 0.0,
        };
        let flags = vec![true; 1600];
        let mut bytes = vec![0u8; free_space_len(&grid, &flags).unwrap()];
        emit_free_space(&grid, &flags, &mut bytes).unwrap();
        let free = FreeSpace::parse(&bytes).unwrap();
        const N: usize = 200;
        let batch = 300u32;
        let r = Resetting {
            reset_candidates: 10,
            candidates_per_update: batch,
            settled_after: 0,
            ..Resetting::DEFAULT
        };
        let config = MclConfig::new(OdometryNoise::uniform(0.01).unwrap(), 0.5, 0.0, 0.0)
            .unwrap()
            .with_resetting(Some(r))
            .unwrap();
        let mut store = Particles::<N>::new();
        let mut f = Mcl::new(&mut store, config).unwrap();
        let mut rng = SplitMix64::new(5);
        let mut truth = Pose::new(2.0, 2.0, 0.0);
        f.init_gaussian(N, &truth, 0.05, 0.02, &mut rng).unwrap();
        let step = OdometryStep::new(0.0, 0.1, 0.0).unwrap();
        let calls = Cell::new(0usize);
        let (mut started, mut pending) = (None, Vec::new());
        for k in 0..40 {
            truth = step.apply(&truth);
            if k == 10 {
                // Kidnapped: 5 m away.
                truth.y_m += 5.0;
            }
            f.predict(&step, &mut rng);
            let t = truth;
            calls.set(0);
            let up = f
                .update_with(
                    |p| {
                        calls.set(calls.get() + 1);
                        -((p.x_m - t.x_m).powi(2) + (p.y_m - t.y_m).powi(2)) / (2.0 * 0.1 * 0.1)
                    },
                    Some(&free),
                    &mut rng,
                )
                .unwrap();
            // An ordinary weighing, an expansion's second one, the reset's rescoring of the
            // set at its start, and at most `batch` candidates.
            assert!(
                calls.get() <= 3 * N + batch as usize,
                "{k}: {}",
                calls.get()
            );
            if up.reset {
                // Started (or, still lost 2 updates later, started again).
                started.get_or_insert(k);
                assert_eq!(f.reset_pending(), 10 * N as u32 - batch);
            }
            if started.is_some() {
                pending.push(f.reset_pending());
            }
        }
        assert!(started.is_some(), "never reset");
        // Counted down by the batch at each update until done or tracking again (or started
        // again).
        for w in pending.windows(2) {
            assert!(
                w[1] == 0 || w[1] + batch == w[0] || w[1] == 10 * N as u32 - batch,
                "{pending:?}"
            );
        }
        assert!(
            pending.windows(2).any(|w| w[1] + batch == w[0]),
            "{pending:?}"
        );
        assert_eq!(*pending.last().unwrap(), 0, "{pending:?}");
        let e = f.estimate().pose;
        assert!(
            (e.x_m - truth.x_m).hypot(e.y_m - truth.y_m) < 0.3,
            "{e:?} {truth:?}"
        );
    }

    #[test]
    fn retry_fires_when_the_likelihood_collapses() {
        // σ of the step: α = 0.02 gives σ_trans = √(0.02·0.25) ≈ 7 cm, so the 0.3 m jump
        // drops the average log-likelihood by tens of nats at update 8 and nowhere else.
        let noise = OdometryNoise::uniform(0.02).unwrap();
        let base = MclConfig::new(noise, 0.5, 0.0, 0.0).unwrap();
        let (off, _) = drive(base);
        assert!(off.iter().all(|&r| !r));
        let (on, err) = drive(base.with_retry(5.0, 3.0).unwrap());
        assert!(on[8], "{on:?}");
        assert_eq!(on.iter().filter(|&&r| r).count(), 1, "{on:?}");
        assert!(err < 0.1, "{err}");
        // −∞: every update but the first.
        let (every, _) = drive(base.with_retry(f32::NEG_INFINITY, 0.5).unwrap());
        assert!(!every[0] && every[1..].iter().all(|&r| r), "{every:?}");
    }
}
