//! The pose estimate of a weighted particle set: weighted mean, circular mean heading,
//! covariance, and the effective sample size.

use crate::math;
use crate::math::fast::wrap_once;
use crate::pose::{wrap_angle, Pose};

/// What the filter believes after an update.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// Weighted mean position (metres) and circular mean heading
    /// `atan2(Σ wᵢ sin θᵢ, Σ wᵢ cos θᵢ)` (radians, in `[−π, π)`).
    pub pose: Pose,
    /// Weighted covariance of `(x, y, θ)` (m², m², rad² and mixed), row-major. Heading
    /// deviations are wrapped differences from the circular mean.
    pub covariance: [[f32; 3]; 3],
    /// Effective sample size `1 / Σ wᵢ²` of the weights the estimate was computed from.
    pub ess: f32,
}

impl Estimate {
    /// The estimate of `poses` weighted by `weights` (summing to 1; extra entries of the longer
    /// slice are ignored). An empty set gives the default (all zeros).
    ///
    /// Two passes: means, then second moments about the means (no cancellation).
    pub fn of(poses: &[Pose], weights: &[f32]) -> Self {
        Self::of_selected(poses, weights, |_| true)
    }

    /// The estimate of the particles within `radius_m` (metres) and `half_angle_rad` (radians)
    /// of `center` only, their weights renormalized: the mode's neighbourhood, so that a few
    /// far particles (recovery's random ones, a second hypothesis) do not drag the mean into a
    /// wall. The ESS is still that of the whole set. If no particle with positive weight is
    /// within, it is [`Estimate::of`] the whole set.
    ///
    /// One pass, on the deviations `(dx, dy, dθ)` of each particle from `center` (`dθ`
    /// wrapped): the mean is `center` plus their weighted mean, the heading `center.θ + atan2(Σ
    /// w sin dθ, Σ w cos dθ)` (the circular mean; for `|dθ| ≤ 0.5` the sine and cosine are
    /// their Taylor polynomials to degree 5 and 6, within 1.6e-6 of them, so the heading is
    /// within 1.6e-6 rad of the exact circular mean), and the covariance comes
    /// from the deviations' second moments (`E[d dᵀ] − E[d] E[d]ᵀ`, with the heading deviations
    /// taken from the circular mean). The deviations are at most `radius_m` and
    /// `half_angle_rad`, so the second moments lose no precision to cancellation at the filter's
    /// 1 m / 0.5 rad ([`ESTIMATE_RADIUS_M`](super::ESTIMATE_RADIUS_M)).
    pub fn around(
        poses: &[Pose],
        weights: &[f32],
        center: &Pose,
        radius_m: f32,
        half_angle_rad: f32,
    ) -> Self {
        let mut all = 0.0f32;
        let mut m = Moments::new(center, radius_m, half_angle_rad);
        for (p, &w) in poses.iter().zip(weights) {
            all += w * w;
            m.add_if_near(p, w);
        }
        let mut e = m.estimate().unwrap_or_else(|| Self::of(poses, weights));
        e.ess = if all > 0.0 { 1.0 / all } else { 0.0 };
        e
    }

    fn of_selected<F: Fn(&Pose) -> bool>(poses: &[Pose], weights: &[f32], keep: F) -> Self {
        let mut total = 0.0f32;
        for (p, &w) in poses.iter().zip(weights) {
            if keep(p) {
                total += w;
            }
        }
        if total <= 0.0 {
            return Self::default();
        }
        let inv = 1.0 / total;
        let (mut sx, mut sy, mut ss, mut sc, mut sw2) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
        for (p, &w) in poses.iter().zip(weights) {
            let w = if keep(p) { w * inv } else { 0.0 };
            sx += w * p.x_m;
            sy += w * p.y_m;
            let (s, c) = math::sin_cos(p.theta_rad);
            ss += w * s;
            sc += w * c;
            sw2 += w * w;
        }
        let theta = wrap_angle(math::atan2(ss, sc));
        let mut cov = [[0.0f32; 3]; 3];
        for (p, &w) in poses.iter().zip(weights) {
            let w = if keep(p) { w * inv } else { 0.0 };
            let d = [p.x_m - sx, p.y_m - sy, wrap_angle(p.theta_rad - theta)];
            for (row, di) in cov.iter_mut().zip(d) {
                for (cell, dj) in row.iter_mut().zip(d) {
                    *cell += w * di * dj;
                }
            }
        }
        Self {
            pose: Pose::new(sx, sy, theta),
            covariance: cov,
            ess: if sw2 > 0.0 { 1.0 / sw2 } else { 0.0 },
        }
    }
}

/// How the covariance the filter reports ([`Update::covariance`](super::Update::covariance)) is
/// made from the particles' ([`Estimate::covariance`]), so that a consumer that weighs the
/// pose by it (nav2, robot_localization) is not told more than the filter knows.
///
/// - **Tracking**: the particles' covariance plus `floor_m²` on x and y and `floor_rad²` on the
///   heading: the error the particle set cannot see — the map's and the scan's own resolution
///   and the disagreement between the map and the world, which every particle shares.
/// - **Uncertain or Lost**: at least the previous update's reported covariance times `growth`
///   (`lost_growth` when Lost), whichever of the two has the larger position variance: it grows
///   while the filter doubts, and never shrinks towards zero until the filter tracks again.
/// - Never above `max_var_m2` in x or y (the matrix scaled down to it) or `max_var_rad2` in
///   heading: the reported value stays finite.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReportedCovariance {
    /// Standard deviation added in quadrature to x and y, metres (≥ 0).
    pub floor_m: f32,
    /// Standard deviation added in quadrature to the heading, radians (≥ 0).
    pub floor_rad: f32,
    /// Factor (≥ 1) by which the reported covariance at least grows per `Uncertain` update.
    pub growth: f32,
    /// Factor (≥ `growth`) by which it at least grows per `Lost` update.
    pub lost_growth: f32,
    /// Largest reported variance of x and of y, m² (> 0).
    pub max_var_m2: f32,
    /// Largest reported variance of the heading, rad² (> 0).
    pub max_var_rad2: f32,
}

impl ReportedCovariance {
    /// The defaults: `floor_m` 0.025 m (chosen on the tuning buildings with the filter at the
    /// crate's defaults, κ 64 and α 0.02: docs/localization.md "Honest covariance"; a sharper
    /// likelihood gives a tighter particle set and needs a larger floor) and `floor_rad`
    /// 0.02 rad, growth 1.2 per `Uncertain` update and 1.5 per `Lost` one, at most (100 m)² and
    /// π² rad².
    pub const DEFAULT: Self = Self {
        floor_m: 0.025,
        floor_rad: 0.02,
        growth: 1.2,
        lost_growth: 1.5,
        max_var_m2: 1.0e4,
        max_var_rad2: core::f32::consts::PI * core::f32::consts::PI,
    };

    /// The particles' covariance as reported (the particles' own, without inflation).
    pub const PARTICLES: Self = Self {
        floor_m: 0.0,
        floor_rad: 0.0,
        growth: 1.0,
        lost_growth: 1.0,
        max_var_m2: f32::MAX,
        max_var_rad2: f32::MAX,
    };

    /// True when every value is finite (the maxima may be `f32::MAX`) and in range.
    pub fn validate(&self) -> bool {
        let ok = |v: f32| v.is_finite() && v >= 0.0;
        ok(self.floor_m)
            && ok(self.floor_rad)
            && self.growth.is_finite()
            && self.growth >= 1.0
            && self.lost_growth.is_finite()
            && self.lost_growth >= self.growth
            && self.max_var_m2.is_finite()
            && self.max_var_m2 > 0.0
            && self.max_var_rad2.is_finite()
            && self.max_var_rad2 > 0.0
    }

    /// The covariance to report, from the particles' (`particles`), the last reported one
    /// (`previous`; all zeros before the first) and the quality state of this update.
    /// Non-finite entries of `particles` are taken as the maxima.
    pub fn reported(
        &self,
        particles: &[[f32; 3]; 3],
        previous: &[[f32; 3]; 3],
        state: super::Quality,
    ) -> [[f32; 3]; 3] {
        let mut base = *particles;
        if !base.iter().flatten().all(|v| v.is_finite()) {
            base = [[0.0; 3]; 3];
            base[0][0] = self.max_var_m2;
            base[1][1] = self.max_var_m2;
            base[2][2] = self.max_var_rad2;
        }
        base[0][0] += self.floor_m * self.floor_m;
        base[1][1] += self.floor_m * self.floor_m;
        base[2][2] += self.floor_rad * self.floor_rad;
        let g = match state {
            super::Quality::Tracking => 0.0,
            super::Quality::Uncertain => self.growth,
            super::Quality::Lost => self.lost_growth,
        };
        let grown = previous.map(|row| row.map(|v| v * g));
        let pos = |c: &[[f32; 3]; 3]| c[0][0].max(c[1][1]);
        let mut out = if g > 0.0 && pos(&grown) > pos(&base) {
            // Heading at least as grown too.
            let mut o = grown;
            o[2][2] = o[2][2].max(base[2][2]);
            o
        } else {
            base
        };
        // Within the maxima: position block scaled down as a whole (stays positive semi-
        // definite), heading clamped with its cross terms scaled alike.
        let p = pos(&out);
        if p > self.max_var_m2 {
            let k = self.max_var_m2 / p;
            for (i, row) in out.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    let f = match (i < 2, j < 2) {
                        (true, true) => k,
                        (false, false) => 1.0,
                        _ => math::sqrt(k),
                    };
                    *v *= f;
                }
            }
        }
        if out[2][2] > self.max_var_rad2 {
            let k = self.max_var_rad2 / out[2][2];
            let r = math::sqrt(k);
            let [r0, r1, r2] = &mut out;
            r0[2] *= r;
            r1[2] *= r;
            r2[0] *= r;
            r2[1] *= r;
            r2[2] = self.max_var_rad2;
        }
        out
    }
}

impl Default for ReportedCovariance {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// `(sin x, cos x)`: Taylor polynomials to degree 5 and 6 for `|x| ≤ 0.5` (truncation below
/// 1.6e-6 and 5e-8, and far less for the small deviations of a converged cloud: `x⁷/5040`),
/// [`math::sin_cos`] beyond.
#[inline]
fn small_sin_cos(x: f32) -> (f32, f32) {
    if x.abs() <= 0.5 {
        let z = x * x;
        let s = x + x * z * (-1.0 / 6.0 + z * (1.0 / 120.0));
        let c = 1.0 - 0.5 * z + z * z * (1.0 / 24.0 + z * (-1.0 / 720.0));
        (s, c)
    } else {
        math::sin_cos(x)
    }
}

/// Weighted sums of the deviations from a centre of the particles near it.
pub(super) struct Moments {
    center: Pose,
    radius2_m2: f32,
    half_angle_rad: f32,
    w: f32,
    x: f32,
    y: f32,
    t: f32,
    sin: f32,
    cos: f32,
    xx: f32,
    xy: f32,
    xt: f32,
    yy: f32,
    yt: f32,
    tt: f32,
}

impl Moments {
    /// Nothing summed yet, about `center`, keeping particles within `radius_m` and
    /// `half_angle_rad`.
    pub(super) fn new(center: &Pose, radius_m: f32, half_angle_rad: f32) -> Self {
        Self {
            center: *center,
            radius2_m2: radius_m * radius_m,
            half_angle_rad,
            w: 0.0,
            x: 0.0,
            y: 0.0,
            t: 0.0,
            sin: 0.0,
            cos: 0.0,
            xx: 0.0,
            xy: 0.0,
            xt: 0.0,
            yy: 0.0,
            yt: 0.0,
            tt: 0.0,
        }
    }

    /// The total weight added.
    pub(super) fn weight(&self) -> f32 {
        self.w
    }

    /// Adds `p` with weight `w` if it is near the centre.
    #[inline]
    pub(super) fn add_if_near(&mut self, p: &Pose, w: f32) {
        let (dx, dy) = (p.x_m - self.center.x_m, p.y_m - self.center.y_m);
        let dt = wrap_once(p.theta_rad - self.center.theta_rad);
        if dx * dx + dy * dy <= self.radius2_m2 && dt.abs() <= self.half_angle_rad {
            self.add(w, dx, dy, dt);
        }
    }

    #[inline]
    fn add(&mut self, w: f32, dx: f32, dy: f32, dt: f32) {
        let (wx, wy, wt) = (w * dx, w * dy, w * dt);
        self.w += w;
        self.x += wx;
        self.y += wy;
        self.t += wt;
        let (s, c) = small_sin_cos(dt);
        self.sin += w * s;
        self.cos += w * c;
        self.xx += wx * dx;
        self.xy += wx * dy;
        self.xt += wx * dt;
        self.yy += wy * dy;
        self.yt += wy * dt;
        self.tt += wt * dt;
    }

    /// The estimate from the sums (the weights need not be normalized); the ESS is left 0 for
    /// the caller. None when no particle with positive weight was near.
    pub(super) fn estimate(&self) -> Option<Estimate> {
        let inv = (self.w > 0.0).then(|| 1.0 / self.w)?;
        let center = &self.center;
        let (mx, my, mt) = (self.x * inv, self.y * inv, self.t * inv);
        // The circular mean's offset from the centre; |offset| ≤ the largest |dθ|.
        let offset = math::atan2(self.sin, self.cos);
        let xx = (self.xx * inv - mx * mx).max(0.0);
        let yy = (self.yy * inv - my * my).max(0.0);
        let xy = self.xy * inv - mx * my;
        // E[(dx − mx)(dθ − offset)] = E[dx dθ] − mx E[dθ] (the offset drops out).
        let xt = self.xt * inv - mx * mt;
        let yt = self.yt * inv - my * mt;
        // E[(dθ − offset)²] = E[dθ²] − 2·offset·E[dθ] + offset².
        let tt = (self.tt * inv - 2.0 * offset * mt + offset * offset).max(0.0);
        Some(Estimate {
            pose: Pose::new(
                center.x_m + mx,
                center.y_m + my,
                wrap_angle(center.theta_rad + offset),
            ),
            covariance: [[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]],
            ess: 0.0,
        })
    }
}

/// The variances on the diagonal of a 3×3 covariance (x, y, heading: m², m², rad²), each
/// clamped at 0 (a rounding-negative variance reads 0).
#[inline]
pub fn diagonal_variances(covariance: &[[f32; 3]; 3]) -> [f32; 3] {
    let [[xx, _, _], [_, yy, _], [_, _, tt]] = *covariance;
    [xx.max(0.0), yy.max(0.0), tt.max(0.0)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    #[test]
    fn heading_mean_across_the_seam() {
        // Two headings at ±(π − 0.1): the circular mean is π (wrapped to −π), not 0.
        let poses = [
            Pose::new(1.0, 0.0, PI - 0.1),
            Pose::new(3.0, 2.0, -PI + 0.1),
        ];
        let e = Estimate::of(&poses, &[0.5, 0.5]);
        assert!(
            (e.pose.theta_rad.abs() - PI).abs() < 1e-5,
            "{}",
            e.pose.theta_rad
        );
        assert!((e.pose.x_m - 2.0).abs() < 1e-6 && (e.pose.y_m - 1.0).abs() < 1e-6);
        // Hand-derived: var x = var y = cov xy = 1; var θ = 0.01.
        assert!((e.covariance[0][0] - 1.0).abs() < 1e-6);
        assert!((e.covariance[0][1] - 1.0).abs() < 1e-6);
        assert!((e.covariance[2][2] - 0.01).abs() < 1e-5);
        assert!((e.ess - 2.0).abs() < 1e-6);
    }

    #[test]
    fn around_matches_a_two_pass_f64_reference() {
        // A cloud straddling the ±π seam plus far particles that must be left out; the
        // reference is the textbook two-pass computation in f64 over the kept particles.
        let center = Pose::new(2.0, -1.0, PI - 0.2);
        let mut state = 0x1234_5678u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            f64::from(state >> 8) / 16_777_216.0 - 0.5
        };
        let mut poses = Vec::new();
        let mut weights = Vec::new();
        for k in 0..400 {
            let far = k % 10 == 0;
            let spread = if far { 8.0 } else { 1.6 };
            let x = f64::from(center.x_m) + spread * next();
            let y = f64::from(center.y_m) + spread * next();
            let t = f64::from(center.theta_rad) + if far { 6.0 } else { 1.2 } * next();
            poses.push(Pose::new(x as f32, y as f32, wrap_angle(t as f32)));
            weights.push((1.0 + next()) as f32);
        }
        let total: f32 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= total);
        let e = Estimate::around(&poses, &weights, &center, 1.0, 0.5);
        let kept: Vec<(f64, f64, f64, f64)> = poses
            .iter()
            .zip(&weights)
            .filter_map(|(p, &w)| {
                let (dx, dy) = (p.x_m - center.x_m, p.y_m - center.y_m);
                let dt = wrap_angle(p.theta_rad - center.theta_rad);
                (dx * dx + dy * dy <= 1.0 && dt.abs() <= 0.5).then_some((
                    f64::from(w),
                    f64::from(p.x_m),
                    f64::from(p.y_m),
                    f64::from(p.theta_rad),
                ))
            })
            .collect();
        assert!(kept.len() > 50 && kept.len() < 360, "{}", kept.len());
        let wt: f64 = kept.iter().map(|k| k.0).sum();
        let mx = kept.iter().map(|k| k.0 * k.1).sum::<f64>() / wt;
        let my = kept.iter().map(|k| k.0 * k.2).sum::<f64>() / wt;
        let s: f64 = kept.iter().map(|k| k.0 * k.3.sin()).sum();
        let c: f64 = kept.iter().map(|k| k.0 * k.3.cos()).sum();
        let mt = s.atan2(c);
        let wrap = |a: f64| {
            (a + core::f64::consts::PI).rem_euclid(core::f64::consts::TAU) - core::f64::consts::PI
        };
        let dev = |k: &(f64, f64, f64, f64)| [k.1 - mx, k.2 - my, wrap(k.3 - mt)];
        assert!((f64::from(e.pose.x_m) - mx).abs() < 1e-5);
        assert!((f64::from(e.pose.y_m) - my).abs() < 1e-5);
        assert!(
            wrap(f64::from(e.pose.theta_rad) - mt).abs() < 2e-6,
            "{} vs {mt}",
            e.pose.theta_rad
        );
        for i in 0..3 {
            for j in 0..3 {
                let want = kept
                    .iter()
                    .map(|k| k.0 * dev(k)[i] * dev(k)[j])
                    .sum::<f64>()
                    / wt;
                let got = f64::from(e.covariance[i][j]);
                assert!(
                    (got - want).abs() < 2e-6 + 1e-4 * want.abs(),
                    "cov[{i}][{j}] {got} vs {want}"
                );
            }
        }
        let ess = 1.0
            / weights
                .iter()
                .map(|&w| f64::from(w) * f64::from(w))
                .sum::<f64>();
        assert!((f64::from(e.ess) / ess - 1.0).abs() < 1e-5);
    }

    #[test]
    fn reported_covariance_adds_its_floor_and_grows_while_not_tracking() {
        use super::super::Quality;
        let r = ReportedCovariance::DEFAULT;
        assert!(r.validate() && ReportedCovariance::PARTICLES.validate());
        let p = [[1e-4, 0.0, 0.0], [0.0, 4e-4, 0.0], [0.0, 0.0, 1e-4]];
        let zero = [[0.0f32; 3]; 3];
        let f2 = r.floor_m * r.floor_m;
        let t = r.reported(&p, &zero, Quality::Tracking);
        assert!((t[0][0] - (1e-4 + f2)).abs() < 1e-9 && (t[1][1] - (4e-4 + f2)).abs() < 1e-9);
        // Doubting: never smaller than the last one grown, whatever the particles say.
        let tight = [[1e-8, 0.0, 0.0], [0.0, 1e-8, 0.0], [0.0, 0.0, 1e-8]];
        let mut last = t;
        for _ in 0..10 {
            let u = r.reported(&tight, &last, Quality::Uncertain);
            assert!(
                u[0][0] >= last[0][0] * r.growth * 0.999_99,
                "{u:?} after {last:?}"
            );
            last = u;
        }
        let l = r.reported(&tight, &last, Quality::Lost);
        assert!(l[1][1] >= last[1][1] * r.lost_growth * 0.999_99);
        // Tracking again: back to the particles plus the floor.
        assert_eq!(r.reported(&p, &l, Quality::Tracking), t);
        // Bounded, and finite for a NaN input.
        let mut big = l;
        for _ in 0..200 {
            big = r.reported(&tight, &big, Quality::Lost);
        }
        assert!(big[0][0] <= r.max_var_m2 && big[1][1] <= r.max_var_m2 && big[0][0] > 0.0);
        let nan = [[f32::NAN; 3]; 3];
        let n = r.reported(&nan, &zero, Quality::Lost);
        assert!(n.iter().flatten().all(|v| v.is_finite()));
        // The particles' own when asked.
        assert_eq!(
            ReportedCovariance::PARTICLES.reported(&p, &l, Quality::Tracking),
            p
        );
        assert!(!ReportedCovariance { growth: 0.5, ..r }.validate());
    }
}
