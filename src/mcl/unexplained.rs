//! Readings the map cannot explain: beams that hit something not in the map (a crowd, a new
//! shelf, a moved table), found once per update and left out of that update's weighing
//! ([`MclConfig::with_unexplained`](super::MclConfig::with_unexplained), off by default).
//!
//! # The classification (once per update, at the predicted estimate)
//! The pose is the last update's estimate moved by the odometry steps given since
//! ([`Mcl::predict`](super::Mcl::predict) moves [`Mcl::estimate`](super::Mcl::estimate)'s pose
//! while the option is on, without noise; no memory is added to the filter). With the robot there, a kept beam of
//! the prepared scan is **unmapped** when
//! 1. its endpoint lies farther than [`Unexplained::distance_m`] from any obstacle of the map
//!    (the distance the likelihood field reads for it), and
//! 2. it is **short**: the ray from the sensor to the endpoint crosses no occupied cell
//!    ([`RayCaster`], cast up to the measured range), so the map's wall along that bearing lies
//!    beyond the reading and something unmapped stood in front of it.
//!
//! A far endpoint that lies *behind* a mapped wall (a long reading: an opened door, or the
//! estimate being wrong) is kept: it is evidence against the pose, not an obstacle. Max-range
//! and invalid readings were already dropped by the likelihood field's preparation.
//!
//! If more than [`Unexplained::max_share`] of the kept beams would be removed, none is (as
//! AMCL's `beam_skip_error_threshold`): the estimate is then more likely wrong than the map.
//!
//! # Cost
//! Per update, not per particle: one pass of the prepared scan's scoring at one pose (the
//! distances), one ray cast per candidate (far) beam, and one copy of the scan's kept endpoints
//! (8 bytes per beam); the particles are then scored over the beams left, so each particle
//! costs less, not more. Stack: the flags (one byte per beam of the scan's capacity) and the
//! copy of the prepared scan.
//!
//! # Compared with AMCL's beam skipping
//! nav2 AMCL (`do_beamskip`) skips a beam when fewer than `beam_skip_threshold` of the particles
//! see its endpoint within `beam_skip_distance` of an obstacle, which needs every particle's
//! distances before any weight (a pass over all particles and beams, kept per particle). Here
//! one pose decides, the ray test separates short readings from long ones, and the
//! per-particle loop is the unchanged scoring.

use crate::field::PreparedScan;
use crate::pose::Pose;
use crate::raycast::RayCaster;

/// The parameters of the classification (module docs). Validated by
/// [`Unexplained::validate`] when given to
/// [`MclConfig::with_unexplained`](super::MclConfig::with_unexplained).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Unexplained {
    /// A beam is a candidate when its endpoint, at the predicted estimate, lies farther than
    /// this from any obstacle of the map (metres, > 0; AMCL's `beam_skip_distance` is 0.5).
    pub distance_m: f32,
    /// Largest share of the kept beams (0 to 1) removed at one update; above it none is.
    pub max_share: f32,
}

impl Unexplained {
    /// 0.25 m (5 σ_hit of the Intel log's field) and at most half the beams: the values
    /// measured in docs/localization.md ("Readings the map cannot explain").
    pub const DEFAULT: Self = Self {
        distance_m: 0.25,
        max_share: 0.5,
    };

    /// True when `distance_m` is finite and positive and `max_share` within `[0, 1]`.
    pub fn validate(&self) -> bool {
        self.distance_m.is_finite()
            && self.distance_m > 0.0
            && (0.0..=1.0).contains(&self.max_share)
    }
}

impl Default for Unexplained {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Marks in `flags` (indexed by kept beam) the unmapped beams of `scan` with the robot at
/// `pose` and returns how many; 0 (and no flag set) when more than `u.max_share` of the beams
/// would be, when the pose is not finite, or when the blob cannot be ray cast.
pub(crate) fn classify<const S: usize>(
    scan: &PreparedScan<'_, S>,
    pose: &Pose,
    u: &Unexplained,
    flags: &mut [bool; S],
) -> usize {
    if !pose.is_finite() {
        return 0;
    }
    let Ok(caster) = RayCaster::new(*scan.field().view()) else {
        return 0;
    };
    let far = u.distance_m;
    let mut candidates = 0usize;
    scan.score_with(pose, |j, d| {
        if d > far {
            if let Some(f) = flags.get_mut(j) {
                *f = true;
                candidates += 1;
            }
        }
    });
    if candidates == 0 {
        return 0;
    }
    let trig = crate::math::sin_cos(pose.theta_rad);
    let (sx, sy) = scan.sensor_at(pose);
    let mut removed = 0usize;
    for (j, f) in flags.iter_mut().enumerate().take(scan.len()) {
        if !*f {
            continue;
        }
        let short = scan.endpoint_at(pose, trig, j).is_some_and(|(ex, ey)| {
            let (dx, dy) = (ex - sx, ey - sy);
            let r = crate::math::sqrt(dx * dx + dy * dy);
            if r > 0.0 {
                // A wall crossed before the endpoint lies at least `far` before it (the endpoint
                // is farther than that from every obstacle): half of it is the margin.
                caster.cast_dir(sx, sy, dx / r, dy / r, r) > r - 0.5 * far
            } else {
                false
            }
        });
        *f = short;
        removed += usize::from(short);
    }
    if removed as f32 > u.max_share * scan.len() as f32 {
        flags.iter_mut().for_each(|f| *f = false);
        return 0;
    }
    removed
}

/// How one scan fits the map with the robot at one pose, as shares of the kept beams (each 0
/// to 1, summing to 1 over the three): the quality signal's input
/// ([`QualityThresholds::clutter_share`](super::QualityThresholds::clutter_share)).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanFit {
    /// Beams whose endpoint lies within the explained distance of an obstacle.
    pub explained: f32,
    /// Beams not explained whose ray reaches the endpoint without crossing a mapped wall:
    /// something unmapped in front of the map's wall (clutter, people), or a pose that is off.
    pub short: f32,
    /// Beams not explained whose ray crosses a mapped wall before its endpoint (a reading
    /// through a wall: an opened door, a map error, or a pose that is off). Without a ray
    /// caster for the field, every beam not explained counts here.
    pub through: f32,
}

/// The fit of `scan` with the robot at `pose`: a beam is explained when its endpoint lies
/// within `near_m` (metres) of an obstacle; the others are cast (one ray each, up to the
/// measured range) and counted short or through ([`ScanFit`]). Without a caster (`None`: the
/// field's steps are too coarse to cast) every unexplained beam counts as through. An empty
/// scan or a pose that is not finite gives all zeros.
pub(crate) fn scan_fit<const S: usize>(
    scan: &PreparedScan<'_, S>,
    pose: &Pose,
    near_m: f32,
    caster: Option<&RayCaster<'_>>,
) -> ScanFit {
    let n = scan.len();
    if n == 0 || !pose.is_finite() {
        return ScanFit::default();
    }
    let trig = crate::math::sin_cos(pose.theta_rad);
    let (sx, sy) = scan.sensor_at(pose);
    let (mut explained, mut short) = (0u32, 0u32);
    scan.score_with(pose, |j, d| {
        if d <= near_m {
            explained += 1;
        } else if let Some(c) = caster {
            let reaches = scan.endpoint_at(pose, trig, j).is_some_and(|(ex, ey)| {
                let (dx, dy) = (ex - sx, ey - sy);
                let r = crate::math::sqrt(dx * dx + dy * dy);
                // A wall crossed before the endpoint lies at least `near_m` before it (the
                // endpoint is farther than that from every obstacle): half is the margin.
                r > 0.0 && c.cast_dir(sx, sy, dx / r, dy / r, r) > r - 0.5 * near_m
            });
            short += u32::from(reaches);
        }
    });
    let share = 1.0 / n as f32;
    let explained = explained as f32 * share;
    let short = short as f32 * share;
    ScanFit {
        explained,
        short,
        through: (1.0 - explained - short).max(0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{emit_blob, FieldHeader, FieldView, LikelihoodField, LikelihoodParams};
    use crate::scan::{BeamLayout, Scan};
    use crate::SensorMount;

    /// A 4 m × 4 m room of 0.1 m cells at (0, 0), walls on its border; codes from a brute-force
    /// distance.
    fn room() -> Vec<u8> {
        let n = 40i32;
        let h = FieldHeader::new(n as u32, n as u32, 0.1, 0.0, 0.0);
        let mut codes = vec![0u8; (n * n) as usize];
        for r in 0..n {
            for c in 0..n {
                let d = [c, r, n - 1 - c, n - 1 - r].into_iter().min().unwrap_or(0);
                codes[(r * n + c) as usize] = h.encode_distance_m(f64::from(d) * 0.1);
            }
        }
        let mut out = vec![0; h.required_len().unwrap()];
        emit_blob(&h, &codes, &mut out).unwrap();
        out
    }

    /// The robot at the room's centre facing +x, 36 beams every 10°, ranges to the walls
    /// (from the cell centres of the border, 0.05 m inside it) except those given.
    fn classify_scan(change: impl Fn(usize, f32) -> f32, u: &Unexplained) -> (usize, [bool; 36]) {
        let blob = room();
        let view = FieldView::parse(&blob).unwrap();
        let params = LikelihoodParams::new(0.95, 0.05, 0.05, 10.0).unwrap();
        let field = LikelihoodField::new(view, params);
        let step = core::f32::consts::PI / 18.0;
        let layout = BeamLayout::<36>::uniform(0.0, step, 36, 10.0, SensorMount::CENTERED).unwrap();
        let ranges: Vec<f32> = (0..36)
            .map(|i| {
                let a = i as f32 * step;
                // Distance from (2, 2) to the square of half-side 1.95 m along a.
                let t = 1.95 / a.cos().abs().max(a.sin().abs());
                change(i, t)
            })
            .collect();
        let scan = Scan::<36>::from_ranges(&ranges).unwrap();
        let prepared = field.prepare(&layout, &scan);
        let mut flags = [false; 36];
        let k = classify(&prepared, &Pose::new(2.0, 2.0, 0.0), u, &mut flags);
        (k, flags)
    }

    #[test]
    fn short_readings_far_from_walls_are_unmapped() {
        let u = Unexplained::DEFAULT;
        // Clean: nothing.
        let (k, flags) = classify_scan(|_, t| t, &u);
        assert_eq!(k, 0);
        assert!(flags.iter().all(|&f| !f));
        // Beams 3–6 stopped 1 m from the robot by something in the room: unmapped. Beam 9
        // stopped 0.1 m before the wall: explained (near an obstacle), kept.
        let (k, flags) = classify_scan(
            |i, t| match i {
                3..=6 => 1.0,
                9 => t - 0.1,
                _ => t,
            },
            &u,
        );
        assert_eq!(k, 4, "{flags:?}");
        assert!((3..=6).all(|i| flags[i]) && !flags[9]);
        // Long readings (through the wall, 1 m beyond it): far from every obstacle but not
        // short, so kept.
        let (k, _) = classify_scan(|i, t| if (20..=23).contains(&i) { t + 1.0 } else { t }, &u);
        assert_eq!(k, 0);
        // More than the share: none.
        let (k, flags) = classify_scan(|i, t| if i < 20 { 1.0 } else { t }, &u);
        assert_eq!(k, 0);
        assert!(flags.iter().all(|&f| !f));
        let all = Unexplained {
            max_share: 1.0,
            ..u
        };
        assert_eq!(
            classify_scan(|i, t| if i < 20 { 1.0 } else { t }, &all).0,
            20
        );
    }

    /// [`scan_fit`] of the room scan, changed by `change`, at the centre.
    fn fit_of(change: impl Fn(usize, f32) -> f32) -> ScanFit {
        let blob = room();
        let view = FieldView::parse(&blob).unwrap();
        let params = LikelihoodParams::new(0.95, 0.05, 0.05, 10.0).unwrap();
        let field = LikelihoodField::new(view, params);
        let step = core::f32::consts::PI / 18.0;
        let layout = BeamLayout::<36>::uniform(0.0, step, 36, 10.0, SensorMount::CENTERED).unwrap();
        let ranges: Vec<f32> = (0..36)
            .map(|i| {
                let a = i as f32 * step;
                change(i, 1.95 / a.cos().abs().max(a.sin().abs()))
            })
            .collect();
        let scan = Scan::<36>::from_ranges(&ranges).unwrap();
        let prepared = field.prepare(&layout, &scan);
        let caster = RayCaster::new(view).unwrap();
        scan_fit(&prepared, &Pose::new(2.0, 2.0, 0.0), 0.15, Some(&caster))
    }

    #[test]
    fn scan_fit_tells_clutter_in_front_from_readings_through_walls() {
        let share = |k: usize| k as f32 / 36.0;
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        let f = fit_of(|_, t| t);
        assert!(
            close(f.explained, 1.0) && close(f.short, 0.0) && close(f.through, 0.0),
            "{f:?}"
        );
        // 9 beams stopped 1 m out by something unmapped: short; 4 beams 1 m beyond the wall:
        // through.
        let f = fit_of(|i, t| match i {
            0..=8 => 1.0,
            20..=23 => t + 1.0,
            _ => t,
        });
        assert!(close(f.explained, share(23)), "{f:?}");
        assert!(close(f.short, share(9)), "{f:?}");
        assert!(close(f.through, share(4)), "{f:?}");
    }

    #[test]
    fn parameters_are_validated() {
        assert!(Unexplained::DEFAULT.validate());
        for (d, s) in [
            (0.0, 0.5),
            (-1.0, 0.5),
            (f32::NAN, 0.5),
            (f32::INFINITY, 0.5),
            (0.3, 1.5),
            (0.3, f32::NAN),
        ] {
            assert!(
                !Unexplained {
                    distance_m: d,
                    max_share: s
                }
                .validate(),
                "{d} {s}"
            );
        }
    }
}
