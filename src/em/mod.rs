//! EM for the beam model's intrinsics: Thrun's `learn_intrinsic_parameters`, Table 6.2, with a
//! monotone M-step that accounts for the truncation normalizers (docs/models.md#em).
//!
//! # What it does
//! Given readings `z_i` with their ray-cast ranges `z*_i` (metres), it iterates
//!
//! - **E-step**: `e_{i,c} = w_c·p_c(z_i) / Σ_c' w_c'·p_c'(z_i)` for the four causes `c`
//!   (hit, short, max, rand), computed from the component logarithms (log-sum-exp), so nothing
//!   underflows. A reading no cause with non-zero weight explains is skipped and counted
//!   ([`EmCounts::unexplained`]); NaN and negative readings too ([`EmCounts::invalid`]).
//!   Max-range readings follow the crate's reading policy (see [`crate::scan`]).
//! - **M-step, weights**: `w_c = (1/n)·Σ_i e_{i,c}`, rounded to f32 (see Precision for how the
//!   rounded weights are compared and evaluated).
//! - **M-step, σ and λ**: either [`ShapeUpdate::Textbook`] (Table 6.2's closed forms
//!   `σ² = Σe_hit·(z−z*)²/Σe_hit`, `λ = Σe_short/Σe_short·z`, which ignore the normalizers
//!   `η_hit`, `η_short`), or [`ShapeUpdate::Truncated`] (the default): a 1-D maximization of the
//!   expected complete log-likelihood *with* the normalizers, by safeguarded Newton (bracketing,
//!   bounded steps, and only an evaluated improvement is accepted). In λ this solves the weighted
//!   score equation `Σ e_i·(1/λ − z_i − z*_i/(e^{λz*_i} − 1)) = 0`, which removes the truncation
//!   bias (true λ = 1 truncated at 2 m: the textbook update converges near 1.46). In σ it works on
//!   the precision `τ = 1/σ²`, in which the hit term is concave.
//!
//! Because every part of the exact M-step never decreases its part of the expected complete
//! log-likelihood, [`ShapeUpdate::TruncatedExact`] is a generalized EM and the data
//! log-likelihood never decreases (up to f64 rounding, see below); [`ShapeUpdate::Truncated`]
//! accepts a cheaper step only when the data log-likelihood shows it did not decrease, and falls
//! back to the exact one otherwise, so it is monotone too. The textbook variant reproduces the chapter's
//! worked example, but on some data sets it decreases the log-likelihood.
//!
//! # Data and passes
//! The data are never stored: the caller supplies a re-iterable source, a closure returning a
//! fresh iterator of `(range_m, z_star_m)` pairs (so `z*` may be cached by the caller or cast on
//! the fly). Everything kept between readings is a fixed set of sums. Passes per iteration:
//!
//! - [`ShapeUpdate::Textbook`] makes one.
//! - [`ShapeUpdate::Truncated`] (default) makes about one. The E-step pass also evaluates the
//!   derivatives of the normalized expected complete log-likelihood at the current σ and λ; one
//!   safeguarded Newton step gives the next σ and λ (Lange's EM-gradient step, locally equivalent
//!   to EM). The next pass, which is the next E-step anyway, checks the data log-likelihood; if it
//!   went down, that pass is discarded and the [`ShapeUpdate::TruncatedExact`] step is taken from
//!   the previous parameters (guaranteed by the generalized-EM argument below), after one more
//!   pass there for the values of the shape terms (the one-step pass computes only their
//!   derivatives, which saves an `ln` per short-range reading).
//! - [`ShapeUpdate::TruncatedExact`] makes one E-step pass plus one per Newton evaluation (each re-runs
//!   the E-step at the same θ and evaluates the shape terms at the candidate), typically 1–3, at
//!   most [`EmConfig::max_newton_passes`].
//!
//! # Cost per reading
//! The E-step works on the component densities, not their logarithms: an inline f64 `e^x`
//! (within 1 ulp of libm's; no call, no division) for the hit density, and for a reading below
//! its `z*` two more, for the short density and its normalizer, evaluated side by side as the
//! two lanes of one SIMD-friendly `e^x` (bit for bit the scalar results); the max and rand
//! densities are constants of the pass. The data log-likelihood is kept as a running product
//! (mantissa and binary exponent, exact bookkeeping), so there is one `ln` per pass, not per
//! reading. A reading whose density total is outside `[1e-270, 1e270]` goes through a
//! log-sum-exp E-step instead, which cannot underflow; the two agree to f64 rounding. The
//! truncated-Gaussian normalizer skips its `erf` pair where it is exactly 1 in f64 (both ends
//! more than 8.5 σ away, tested as a `z*` interval fixed per pass with a proved margin), and
//! so do the probe's hit terms, which there are linear in `1` and `(z − z*)²` and are summed as
//! two numbers per pass. The one-step pass probes at the E-step's own σ and λ, so it shares the
//! E-step's truncation mass and short normalizer, and it skips the terms' values (an `ln` each)
//! because the one-step update uses only their derivatives. The pass after the last M-step has
//! no probe.
//!
//! # Precision
//! All accumulation and all densities here are f64 (the scoring path of [`crate::BeamModel`] is
//! f32). EM is not a hot path, and f64 buys two things: the sums over tens of thousands of
//! readings keep ~1e-12 relative accuracy, and the monotonicity guarantee holds to f64 rounding
//! instead of f32 rounding (an f32 E-step perturbs the per-beam log-likelihood by ~1e-7, more
//! than the late EM steps gain). On an MCU without a double-precision FPU f64 is emulated in
//! software: it works, but is ~10× slower than f32. The parameters themselves are kept as f32
//! (what [`BeamIntrinsics`] stores), and every candidate is rounded to f32 *before* it is
//! evaluated and compared, so the returned intrinsics are exactly the ones whose log-likelihood
//! the trace reports.
//!
//! Weights in f32. Four f32 weights rounded from `Σ_i e_{i,c}/n` sum to 1 only to within
//! `2⁻²⁴ ≈ 6·10⁻⁸` (each is off by at most half an ulp, `≤ 2⁻²⁵·w_c`). The mixture is linear in
//! the weights, so evaluated with them as stored every reading's log-likelihood would move by
//! `ln Σw`, a different amount after every M-step, and the weight part of Q,
//! `Q_w = Σ_c E_c·ln w_c`, by about `n·(Σw − 1)`: late in a fit that exceeds what a genuine
//! update gains, and comparing `Q_w` on the stored weights refused real updates and froze the
//! fit early. So the E-step, the log-likelihood and the weight step's acceptance all use the
//! stored weights divided by their f64 sum. Renormalized, the rounded candidate is within
//! `2⁻²⁴` relative of the exact maximizer `ŵ = E/n` in every weight, which costs `Q_w` only a
//! second-order `n·Σ_c ŵ_c·(2⁻²⁴)²/2 < n·10⁻¹⁵` nats, below the f64 rounding of `Q_w` itself, so
//! a candidate is refused only when it is the old weights to within rounding, and Jensen's
//! inequality (which the generalized-EM argument rests on) holds for the renormalized weights
//! exactly. The trace is therefore the log-likelihood of the returned intrinsics with their
//! weights divided by their sum; with the stored weights as they are (as
//! [`crate::BeamModel`] evaluates them) it differs by `ln Σw`, at most `6·10⁻⁸` nats per beam.
//! The responsibilities, and so every update, do not depend on the scaling.
//!
//! Rounding bound of the monotonicity: a step is accepted on an f64 comparison of sums of `n`
//! terms of size `|ℓ|`, each accurate to a few ulp; the computed mean log-likelihood per beam is
//! accurate to about `n·|ℓ|·2⁻⁵³/n ≈ 1e-15·|ℓ|` (naive summation bound `n·ε` relative, divided by
//! `n`), so a "decrease" of more than ~1e-12 nats per beam is a real one.
//!
//! # Bounds
//! σ is kept in `[1e-6·z_max, z_max]` and λ in `[1e-3/z_max, 1e6/z_max]`. A start outside is
//! clamped into them. σ reaching its lower bound (every hit reading equals its `z*`: the
//! likelihood is unbounded) or λ its upper bound (short readings at 0 m) stops the fit with
//! [`StopReason::Degenerate`].
//!
//! # Grouped fits
//! [`fit_grouped`] fits one set of weights per group (for example per co-fired count of an
//! ultrasonic ring, docs/models.md#sonar) with σ and λ shared by all groups: the source yields
//! `(group, range_m, z_star_m)`. [`fit`] is the one-group case.
//!
//! # Example
//! ```
//! use beamfield::em::{fit, EmConfig, StopReason};
//! use beamfield::BeamIntrinsics;
//!
//! // Readings and their ray-cast ranges, metres (cached by the caller).
//! let z = [4.5f32, 5.0, 3.0, 7.0, 10.0];
//! let z_star = [5.0f32; 5];
//! let start = BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0)?;
//! let mut trace = [0.0f64; 64]; // mean log-likelihood per beam, one entry per iteration
//! let out = fit(
//!     &EmConfig::default(),
//!     start,
//!     || z.iter().copied().zip(z_star.iter().copied()),
//!     &mut trace,
//! )?;
//! let fitted: BeamIntrinsics = out.intrinsics;
//! assert!(matches!(out.stop, StopReason::Converged | StopReason::IterationLimit));
//! let t = &trace[..out.trace_len];
//! assert!(t.windows(2).all(|w| w[1] >= w[0] - 1e-12));
//! assert!(fitted.sigma_hit_m() > 0.0);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

mod exp;
mod pass;
mod solve;

use crate::intrinsics::{BeamIntrinsics, IntrinsicsError, Param};
use pass::{PassStats, Probe, Theta};
use solve::Solver;

/// How σ_hit and λ_short are re-estimated in the M-step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ShapeUpdate {
    /// Table 6.2's closed forms. Reproduces the chapter's worked example; biased for truncated
    /// short readings, and not monotone on every data set.
    Textbook,
    /// The default. One safeguarded Newton step per iteration on the expected complete
    /// log-likelihood with the truncation normalizers (Lange's EM-gradient step), accepted only
    /// if the next pass shows the data log-likelihood did not decrease; otherwise the
    /// [`ShapeUpdate::TruncatedExact`] step is taken from the previous parameters instead.
    /// Monotone; unbiased λ; about one pass per iteration.
    #[default]
    Truncated,
    /// Maximize the expected complete log-likelihood with the truncation normalizers in every
    /// iteration (safeguarded Newton to convergence, accept only evaluated improvements): an
    /// exact (generalized) EM step. Monotone; unbiased λ; 2–4 passes per iteration.
    TruncatedExact,
}

/// EM settings. [`EmConfig::default`] is the monotone EM with 100 iterations.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EmConfig {
    /// Largest number of M-steps.
    pub max_iterations: u32,
    /// Stop when the mean log-likelihood per beam changes by at most this much between two
    /// iterations, nats (≥ 0; 0 stops only when the parameters stop changing).
    pub tolerance_nats: f64,
    /// The σ and λ update.
    pub shape_update: ShapeUpdate,
    /// Largest number of extra passes per iteration for the truncated M-step (≥ 1).
    pub max_newton_passes: u8,
}

impl Default for EmConfig {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            tolerance_nats: 1e-9,
            shape_update: ShapeUpdate::Truncated,
            max_newton_passes: 8,
        }
    }
}

impl EmConfig {
    /// The chapter's EM (Table 6.2 updates), otherwise the defaults.
    pub fn textbook() -> Self {
        Self {
            shape_update: ShapeUpdate::Textbook,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), EmError> {
        if !(self.tolerance_nats >= 0.0 && self.tolerance_nats.is_finite()) {
            return Err(EmError::BadTolerance);
        }
        if self.max_newton_passes == 0 {
            return Err(EmError::NoNewtonPasses);
        }
        Ok(())
    }
}

/// Why EM could not run or could not return intrinsics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EmError {
    /// [`EmConfig::tolerance_nats`] is negative or not finite.
    BadTolerance,
    /// [`EmConfig::max_newton_passes`] is 0.
    NoNewtonPasses,
    /// The fitted parameters failed validation (not expected; reported rather than hidden).
    Intrinsics(IntrinsicsError),
}

impl core::fmt::Display for EmError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadTolerance => f.write_str("em tolerance must be finite and >= 0"),
            Self::NoNewtonPasses => f.write_str("em needs at least one newton pass"),
            Self::Intrinsics(e) => write!(f, "fitted intrinsics invalid: {e}"),
        }
    }
}

impl core::error::Error for EmError {}

impl From<IntrinsicsError> for EmError {
    fn from(e: IntrinsicsError) -> Self {
        Self::Intrinsics(e)
    }
}

/// Why EM stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StopReason {
    /// The mean log-likelihood changed by at most the tolerance, or the parameters stopped
    /// changing.
    Converged,
    /// [`EmConfig::max_iterations`] M-steps were made.
    IterationLimit,
    /// No reading was usable (all invalid, unexplained, or the source was empty): the start is
    /// returned unchanged.
    NoData,
    /// A shape parameter ran to its bound, where the likelihood is unbounded:
    /// [`Param::SigmaHit`] at its lower bound or [`Param::LambdaShort`] at its upper bound.
    Degenerate(Param),
}

/// Readings seen in the last pass, by fate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EmCounts {
    /// Readings used by the E-step.
    pub used: u64,
    /// NaN or negative readings, skipped.
    pub invalid: u64,
    /// Readings no cause with non-zero weight explains (e.g. `z > z*` below the range limit with
    /// `z_hit = z_rand = 0`), skipped.
    pub unexplained: u64,
    /// Readings whose group index was out of range ([`fit_grouped`] only), skipped.
    pub bad_group: u64,
}

/// The result of [`fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EmFit {
    /// The fitted, validated intrinsics (the range limit is the start's).
    pub intrinsics: BeamIntrinsics,
    /// Why it stopped.
    pub stop: StopReason,
    /// M-steps made.
    pub iterations: u32,
    /// Passes over the data made (E-step passes plus Newton passes).
    pub passes: u32,
    /// Entries written to the caller's trace buffer: `trace[t]` is the mean log-likelihood per
    /// used beam (nats) at the parameters after `t` M-steps; the last entry is that of
    /// [`EmFit::intrinsics`].
    pub trace_len: usize,
    /// Trace entries that did not fit in the caller's buffer (the latest ones are lost).
    pub trace_dropped: usize,
    /// What happened to the readings (last pass).
    pub counts: EmCounts,
}

/// The result of [`fit_grouped`]: one weight vector per group, shared σ and λ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupedFit<const G: usize> {
    /// `[z_hit, z_short, z_max, z_rand]` per group. A group without readings keeps its start.
    pub weights: [[f32; 4]; G],
    /// Readings used per group (last pass).
    pub used_per_group: [u64; G],
    /// σ_hit, metres.
    pub sigma_hit_m: f32,
    /// λ_short, 1/m.
    pub lambda_short_per_m: f32,
    /// The sensor's range limit, metres (the start's).
    pub max_range_m: f32,
    /// Why it stopped.
    pub stop: StopReason,
    /// M-steps made.
    pub iterations: u32,
    /// Passes over the data made.
    pub passes: u32,
    /// Entries written to the trace buffer (mean log-likelihood per beam over all groups).
    pub trace_len: usize,
    /// Trace entries that did not fit.
    pub trace_dropped: usize,
    /// What happened to the readings (last pass).
    pub counts: EmCounts,
}

impl<const G: usize> GroupedFit<G> {
    /// The intrinsics of group `g` (`None` when `g ≥ G`).
    ///
    /// # Errors
    /// Inside the option, an [`IntrinsicsError`] if the group's weights fail validation (not
    /// expected: they are on the simplex to f32 rounding).
    pub fn intrinsics(&self, g: usize) -> Option<Result<BeamIntrinsics, IntrinsicsError>> {
        let w = self.weights.get(g)?;
        Some(BeamIntrinsics::new(
            w[0],
            w[1],
            w[2],
            w[3],
            self.sigma_hit_m,
            self.lambda_short_per_m,
            self.max_range_m,
        ))
    }
}

/// Runs EM from `start` over the pairs `(range_m, z_star_m)` that `source` yields (a fresh
/// iterator on every call: it is called once per pass), writing the trace into `trace`.
///
/// # Errors
/// [`EmError::BadTolerance`] / [`EmError::NoNewtonPasses`] for a bad config, before any pass.
pub fn fit<F, I>(
    config: &EmConfig,
    start: BeamIntrinsics,
    source: F,
    trace: &mut [f64],
) -> Result<EmFit, EmError>
where
    F: Fn() -> I,
    I: IntoIterator<Item = (f32, f32)>,
{
    let g = fit_grouped::<1, _, _>(
        config,
        &start,
        [start.weights()],
        || source().into_iter().map(|(z, s)| (0usize, z, s)),
        trace,
    )?;
    Ok(EmFit {
        intrinsics: BeamIntrinsics::new(
            g.weights[0][0],
            g.weights[0][1],
            g.weights[0][2],
            g.weights[0][3],
            g.sigma_hit_m,
            g.lambda_short_per_m,
            g.max_range_m,
        )?,
        stop: g.stop,
        iterations: g.iterations,
        passes: g.passes,
        trace_len: g.trace_len,
        trace_dropped: g.trace_dropped,
        counts: g.counts,
    })
}

/// [`fit`] over readings `z_m[i]` with ray-cast ranges `z_star_m[i]` (pairs past the shorter
/// slice are ignored).
///
/// # Errors
/// An [`EmError`], as [`fit`].
pub fn fit_slices(
    config: &EmConfig,
    start: BeamIntrinsics,
    z_m: &[f32],
    z_star_m: &[f32],
    trace: &mut [f64],
) -> Result<EmFit, EmError> {
    fit(
        config,
        start,
        || z_m.iter().copied().zip(z_star_m.iter().copied()),
        trace,
    )
}

/// Lower bound of σ relative to the range limit.
const SIGMA_MIN_REL: f64 = 1e-6;
/// Bounds of λ times the range limit.
const LAMBDA_MIN_REL: f64 = 1e-3;
const LAMBDA_MAX_REL: f64 = 1e6;

/// EM with one weight vector per group and shared σ, λ (see the module docs). `start` gives
/// σ, λ and the range limit; `start_weights[g]` the starting weights of group `g` (each must be
/// on the simplex, as [`BeamIntrinsics`] checks them; pass `start.weights()` for every group if
/// in doubt). `source` yields `(group, range_m, z_star_m)`; a group index `≥ G` is skipped and
/// counted.
///
/// # Errors
/// As [`fit`]; also [`EmError::Intrinsics`] if a start weight vector is not on the simplex.
pub fn fit_grouped<const G: usize, F, I>(
    config: &EmConfig,
    start: &BeamIntrinsics,
    start_weights: [[f32; 4]; G],
    source: F,
    trace: &mut [f64],
) -> Result<GroupedFit<G>, EmError>
where
    F: Fn() -> I,
    I: IntoIterator<Item = (usize, f32, f32)>,
{
    config.validate()?;
    for w in &start_weights {
        BeamIntrinsics::new(w[0], w[1], w[2], w[3], 1.0, 1.0, 1.0)?;
    }
    let zmax_f32 = start.max_range_m();
    let zmax = f64::from(zmax_f32);
    let sigma_lo = round_f32(SIGMA_MIN_REL * zmax);
    let sigma_hi = round_f32(zmax);
    let lambda_lo = round_f32(LAMBDA_MIN_REL / zmax);
    let lambda_hi = round_f32(LAMBDA_MAX_REL / zmax);
    let mut w = start_weights;
    let mut sigma = f64::from(start.sigma_hit_m()).clamp(sigma_lo, sigma_hi);
    let mut lambda = f64::from(start.lambda_short_per_m()).clamp(lambda_lo, lambda_hi);

    let run = |th: &Theta<G>, probe: &Probe| {
        let mut st = PassStats::<G>::default();
        for (g, z, s) in source() {
            st.visit(th, probe, g, z, s);
        }
        st.finish(probe);
        st
    };

    let mut trace_len = 0usize;
    let mut trace_dropped = 0usize;
    let mut passes = 0u32;
    let mut iterations = 0u32;
    let mut prev_ll: Option<f64> = None;
    let exact = config.shape_update == ShapeUpdate::TruncatedExact;
    let truncated = exact || config.shape_update == ShapeUpdate::Truncated;
    let bounds = (sigma_lo, sigma_hi, lambda_lo, lambda_hi);
    let mut proposal_from: Option<Saved<G>> = None;
    let (stop, last) = loop {
        let th = Theta::new(&w, sigma as f32, lambda as f32, zmax_f32);
        // After the last M-step the pass only evaluates the result (and checks the last
        // proposal): no M-step follows it, so it needs no probe.
        let probe = if truncated && iterations < config.max_iterations {
            // The one-step update needs only the derivatives; the fallback re-evaluates the
            // values if it is ever needed.
            Probe::at_theta(sigma, lambda, exact)
        } else {
            Probe::default()
        };
        let st = run(&th, &probe);
        passes = passes.saturating_add(1);
        let used = st.used();
        if used == 0 {
            break (StopReason::NoData, st);
        }
        let mean_ll = st.log_likelihood() / used as f64;
        if let Some(prev) = proposal_from.take() {
            if mean_ll < prev.mean_ll {
                // The one-step Newton proposal lowered the likelihood: take the generalized EM
                // step from the previous parameters instead (guaranteed not to lower it). Its
                // start needs the shape terms' values at the previous σ, λ, which the one-step
                // pass did not compute: one more pass at the previous θ (same E-step).
                let first = run(&prev.theta, &Probe::at_theta(prev.sigma, prev.lambda, true));
                let (s, l, extra) = newton_shapes(
                    config,
                    &run,
                    &prev.theta,
                    &first,
                    (prev.sigma, prev.lambda),
                    bounds,
                );
                passes = passes.saturating_add(extra.saturating_add(1));
                w = prev.new_weights;
                sigma = s;
                lambda = l;
                continue;
            }
        }
        match trace.get_mut(trace_len) {
            Some(slot) => {
                *slot = mean_ll;
                trace_len += 1;
            }
            None => trace_dropped += 1,
        }
        if st.total(0) > 0.0 && sigma <= sigma_lo {
            break (StopReason::Degenerate(Param::SigmaHit), st);
        }
        if st.total(1) > 0.0 && lambda >= lambda_hi {
            break (StopReason::Degenerate(Param::LambdaShort), st);
        }
        if let Some(p) = prev_ll {
            let change = mean_ll - p;
            let change = if change < 0.0 { -change } else { change };
            if change <= config.tolerance_nats {
                break (StopReason::Converged, st);
            }
        }
        prev_ll = Some(mean_ll);
        if iterations >= config.max_iterations {
            break (StopReason::IterationLimit, st);
        }

        // M-step: weights (exact), accepted only if the f32-rounded result does not lower Q_w,
        // both compared renormalized, as the E-step uses them (see the module docs, Precision).
        let mut new_w = w;
        for ((nw, e), n) in new_w.iter_mut().zip(&st.e).zip(&st.n) {
            if *n == 0 {
                continue;
            }
            let cand = weights_from(e, *n);
            if q_weights(e, &cand) >= q_weights(e, nw) {
                *nw = cand;
            }
        }

        // M-step: σ and λ.
        let e_hit = st.total(0);
        let e_short = st.total(1);
        let (new_sigma, new_lambda) = if exact {
            let (s, l, extra) = newton_shapes(config, &run, &th, &st, (sigma, lambda), bounds);
            passes = passes.saturating_add(extra);
            (s, l)
        } else if truncated {
            // One safeguarded Newton step on each (Lange's EM-gradient step), checked by the
            // next pass; the full generalized-EM step above is the fallback.
            let tau = 1.0 / (sigma * sigma);
            let s = if e_hit > 0.0 {
                let t = newton_step(tau, st.hit_curve, tau_of(sigma_hi), tau_of(sigma_lo));
                round_f32(1.0 / crate::math::sqrt_f64(t)).clamp(sigma_lo, sigma_hi)
            } else {
                sigma
            };
            let l = if e_short > 0.0 {
                round_f32(newton_step(lambda, st.short_curve, lambda_lo, lambda_hi))
                    .clamp(lambda_lo, lambda_hi)
            } else {
                lambda
            };
            proposal_from = Some(Saved {
                theta: th,
                sigma,
                lambda,
                new_weights: new_w,
                mean_ll,
            });
            (s, l)
        } else {
            let s = if e_hit > 0.0 {
                round_f32(crate::math::sqrt_f64(st.hit_sq / e_hit)).clamp(sigma_lo, sigma_hi)
            } else {
                sigma
            };
            let l = if e_short > 0.0 {
                round_f32(e_short / st.short_z).clamp(lambda_lo, lambda_hi)
            } else {
                lambda
            };
            (s, l)
        };
        iterations += 1;
        let unchanged = new_w == w && new_sigma == sigma && new_lambda == lambda;
        w = new_w;
        sigma = new_sigma;
        lambda = new_lambda;
        if unchanged {
            // The next pass would repeat this one exactly.
            break (StopReason::Converged, st);
        }
    };
    Ok(GroupedFit {
        weights: w,
        used_per_group: last.n,
        sigma_hit_m: sigma as f32,
        lambda_short_per_m: lambda as f32,
        max_range_m: zmax_f32,
        stop,
        iterations,
        passes,
        trace_len,
        trace_dropped,
        counts: EmCounts {
            used: last.used(),
            invalid: last.invalid,
            unexplained: last.unexplained,
            bad_group: last.bad_group,
        },
    })
}

/// The parameters and E-step statistics an EM-gradient proposal was made from.
#[derive(Clone, Copy)]
struct Saved<const G: usize> {
    theta: Theta<G>,
    sigma: f64,
    lambda: f64,
    new_weights: [[f32; 4]; G],
    mean_ll: f64,
}

/// `1/σ²`.
fn tau_of(sigma: f64) -> f64 {
    1.0 / (sigma * sigma)
}

/// One safeguarded Newton step for the maximum of a concave function from `x` with
/// `[Q, Q', Q'']` there: at most a factor 4 either way, inside `[lo, hi]`.
fn newton_step(x: f64, [_, g, h]: [f64; 3], lo: f64, hi: f64) -> f64 {
    let cand = if h < 0.0 {
        x - g / h
    } else if g > 0.0 {
        x * 4.0
    } else {
        x / 4.0
    };
    let cand = if cand.is_finite() { cand } else { x };
    cand.clamp(x / 4.0, x * 4.0).clamp(lo, hi)
}

/// `x` rounded to the nearest f32, back in f64.
fn round_f32(x: f64) -> f64 {
    f64::from(x as f32)
}

/// `e_c / n` rounded to f32, renormalized so the f32 weights sum to 1 as closely as possible.
fn weights_from(e: &[f64; 4], n: u64) -> [f32; 4] {
    let total: f64 = e.iter().sum();
    let denom = if total > 0.0 { total } else { n as f64 };
    let mut out = [0.0f32; 4];
    for (o, &x) in out.iter_mut().zip(e) {
        *o = (x / denom) as f32;
    }
    out
}

/// The weight part of Q for one group at the weights the E-step uses, `w` renormalized
/// ([`pass::normalized`]): `Σ_c e_c·ln(w_c/Σw)` (a term with `e_c = 0` is 0).
fn q_weights(e: &[f64; 4], w: &[f32; 4]) -> f64 {
    e.iter()
        .zip(pass::normalized(w))
        .map(|(&ec, wc)| {
            if ec > 0.0 {
                ec * crate::math::ln_f64(wc)
            } else {
                0.0
            }
        })
        .sum()
}

/// The truncation-aware σ and λ M-step: safeguarded Newton on both at once, one pass per joint
/// evaluation. Returns the accepted `(σ, λ)` and the number of passes made.
fn newton_shapes<const G: usize, R>(
    config: &EmConfig,
    run: &R,
    th: &Theta<G>,
    first: &PassStats<G>,
    (sigma, lambda): (f64, f64),
    (sigma_lo, sigma_hi, lambda_lo, lambda_hi): (f64, f64, f64, f64),
) -> (f64, f64, u32)
where
    R: Fn(&Theta<G>, &Probe) -> PassStats<G>,
{
    // τ is rounded through σ's f32 representation.
    let round_tau = |t: f64| tau_of(round_f32(1.0 / crate::math::sqrt_f64(t)));
    let (tau_lo, tau_hi) = (tau_of(sigma_hi), tau_of(sigma_lo));
    let has_hit = first.total(0) > 0.0;
    let has_short = first.total(1) > 0.0;
    let tau0 = tau_of(sigma);
    let mut hs = Solver::new(tau0, first.hit_curve, tau_lo, tau_hi);
    let mut ls = Solver::new(lambda, first.short_curve, lambda_lo, lambda_hi);
    let mut passes = 0u32;
    for _ in 0..config.max_newton_passes {
        let t = if has_hit {
            hs.propose(round_tau, tau_lo, tau_hi)
        } else {
            None
        };
        let l = if has_short {
            ls.propose(round_f32, lambda_lo, lambda_hi)
        } else {
            None
        };
        if t.is_none() && l.is_none() {
            break;
        }
        let st = run(th, &Probe::new(t, l));
        passes += 1;
        if let Some(t) = t {
            hs.observe(t, st.hit_curve);
        }
        if let Some(l) = l {
            ls.observe(l, st.short_curve);
        }
    }
    let best_tau = hs.best();
    let new_sigma = if best_tau == tau0 {
        sigma
    } else {
        round_f32(1.0 / crate::math::sqrt_f64(best_tau))
    };
    (new_sigma, ls.best(), passes)
}
