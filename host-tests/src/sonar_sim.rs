//! A host-side simulator of an ultrasonic ring in a simple map, for the sonar tests.
//!
//! The map is a rectangular room with a few boxes (axis-aligned rectangles); ranges are exact ray
//! casts against the wall segments, in f64. Each transducer's own reading is generated from its
//! true range with the four causes of Thrun's Table 6.1 (hit noise, short readings from clutter,
//! specular misses at max range, and a base rate of random readings). **Crosstalk is generated
//! physically**, not by sampling the crosstalk model under test: a co-fired transducer `j`'s
//! pulse travels along `j`'s axis to the wall point `p_j`, scatters back to transducer `i` along
//! `p_j → o_i` (if that path is not blocked), and is timed by `i` as the range
//! `(|p_j − o_j| + |p_j − o_i|)/2` with probability `q_true(Δβ_ij)`; `i` reports whichever echo
//! arrives first. The simulator counts, per co-fired pair, how often `j`'s echo was detected and
//! arrived before `i`'s own: that rate is the simulator's *effective* pairwise `q`.

use crate::splitmix::Draws;
/// A small deterministic PRNG (SplitMix64), so the tests need no external randomness.
pub use crate::splitmix::SplitMix64 as Rng;

/// A room: wall segments `[x0, y0, x1, y1]` (metres) and the boxes they include.
#[derive(Clone, Debug)]
pub struct Room {
    /// Every wall segment, the boxes' sides included.
    pub segments: Vec<[f64; 4]>,
    /// Outer room `[xmin, ymin, xmax, ymax]`.
    pub outer: [f64; 4],
    /// Boxes `[xmin, ymin, xmax, ymax]`.
    pub boxes: Vec<[f64; 4]>,
}

fn rect_sides(r: [f64; 4]) -> [[f64; 4]; 4] {
    let [a, b, c, d] = r;
    [[a, b, c, b], [c, b, c, d], [c, d, a, d], [a, d, a, b]]
}

impl Room {
    /// A `width × height` room (metres, corner at the origin) with the given boxes.
    pub fn new(width_m: f64, height_m: f64, boxes: &[[f64; 4]]) -> Self {
        let outer = [0.0, 0.0, width_m, height_m];
        let mut segments = rect_sides(outer).to_vec();
        for b in boxes {
            segments.extend(rect_sides(*b));
        }
        Self {
            segments,
            outer,
            boxes: boxes.to_vec(),
        }
    }

    /// The test room: 7 m × 5 m with three boxes.
    pub fn test_room() -> Self {
        Self::new(
            7.0,
            5.0,
            &[
                [1.0, 1.0, 1.6, 1.5],
                [4.5, 3.2, 5.3, 3.8],
                [5.6, 0.8, 6.0, 1.6],
            ],
        )
    }

    /// Distance from `(ox, oy)` along the unit direction `(dx, dy)` to the nearest segment.
    pub fn raycast(&self, ox: f64, oy: f64, dx: f64, dy: f64) -> Option<f64> {
        let mut best: Option<f64> = None;
        for s in &self.segments {
            let (ex, ey) = (s[2] - s[0], s[3] - s[1]);
            let den = dx * ey - dy * ex;
            if den.abs() < 1e-15 {
                continue;
            }
            let (wx, wy) = (s[0] - ox, s[1] - oy);
            let t = (wx * ey - wy * ex) / den;
            let u = (wx * dy - wy * dx) / den;
            if t > 1e-9 && (-1e-12..=1.0 + 1e-12).contains(&u) && best.is_none_or(|b| t < b) {
                best = Some(t);
            }
        }
        best
    }

    /// Distance from a point to the nearest segment.
    pub fn clearance(&self, x: f64, y: f64) -> f64 {
        self.segments
            .iter()
            .map(|s| {
                let (ex, ey) = (s[2] - s[0], s[3] - s[1]);
                let l2 = ex * ex + ey * ey;
                let t = (((x - s[0]) * ex + (y - s[1]) * ey) / l2).clamp(0.0, 1.0);
                let (px, py) = (s[0] + t * ex - x, s[1] + t * ey - y);
                (px * px + py * py).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// True when `(x, y)` is inside the room, outside every box, and at least `margin_m` from
    /// every wall.
    pub fn is_free(&self, x: f64, y: f64, margin_m: f64) -> bool {
        let [a, b, c, d] = self.outer;
        let inside = x > a && x < c && y > b && y < d;
        let in_box = self
            .boxes
            .iter()
            .any(|r| x >= r[0] && x <= r[2] && y >= r[1] && y <= r[3]);
        inside && !in_box && self.clearance(x, y) >= margin_m
    }

    /// A uniformly random free pose `(x, y, θ)`.
    pub fn random_pose(&self, rng: &mut Rng, margin_m: f64) -> (f64, f64, f64) {
        let [a, b, c, d] = self.outer;
        loop {
            let x = a + (c - a) * rng.uniform();
            let y = b + (d - b) * rng.uniform();
            if self.is_free(x, y, margin_m) {
                return (x, y, std::f64::consts::TAU * rng.uniform());
            }
        }
    }
}

/// The simulated ring: bearings (radians, counter-clockwise), mounting radius, max range.
#[derive(Clone, Debug)]
pub struct SimRing {
    /// Bearing of each transducer, radians.
    pub bearings_rad: Vec<f64>,
    /// Mounting radius (each transducer sits on its own bearing), metres.
    pub radius_m: f64,
    /// Max range, metres.
    pub max_range_m: f64,
}

/// Pairwise detection probability of a neighbour's echo, by angular separation.
#[derive(Clone, Copy, Debug)]
pub enum QTrue {
    /// The same probability for every separation.
    Constant(f64),
    /// `q0·exp(−Δβ²/(2w²))`, `w` in radians.
    Gaussian {
        /// Peak probability.
        q0: f64,
        /// Lobe width, radians.
        width_rad: f64,
    },
}

impl QTrue {
    /// Detection probability at separation `d` (radians).
    pub fn at(&self, d: f64) -> f64 {
        match *self {
            Self::Constant(q) => q,
            Self::Gaussian { q0, width_rad } => q0 * (-0.5 * (d / width_rad).powi(2)).exp(),
        }
    }
}

/// The own-reading noise (Table 6.1 causes) and the crosstalk law.
#[derive(Clone, Copy, Debug)]
pub struct SimParams {
    /// Hit noise σ, metres.
    pub sigma_hit_m: f64,
    /// Clutter rate λ, per metre.
    pub lambda_short_per_m: f64,
    /// Probability of a short reading (clutter before the wall).
    pub p_short: f64,
    /// Probability of a specular miss (max-range reading).
    pub p_max: f64,
    /// Base probability of a random reading (without crosstalk).
    pub p_rand: f64,
    /// Neighbour-echo detection law.
    pub q_true: QTrue,
}

/// One simulated beam.
#[derive(Clone, Copy, Debug)]
pub struct SimBeam {
    /// Reported range, metres (`≥ max_range` = no echo).
    pub range_m: f64,
    /// True range (ray cast), metres, `max_range` when nothing within range.
    pub z_star_m: f64,
    /// Number of other transducers in its group.
    pub cofired: usize,
    /// Whether the reported reading came from a neighbour's echo.
    pub crosstalk: bool,
    /// Whether it came from a neighbour's echo *and* lies more than 3σ_hit from the true range
    /// (a crosstalk echo closer than that is, for any model, a correct reading).
    pub distinct_crosstalk: bool,
}

/// Per-separation pair counts: `pairs[s]` co-fired pairs at separation bin `s` (rounded to the
/// nearest degree), `events[s]` of them where the neighbour's echo was detected and came first.
#[derive(Clone, Debug)]
pub struct PairStats {
    /// Co-fired ordered pairs per separation degree `0..=180`.
    pub pairs: Vec<u64>,
    /// Crosstalk events per separation degree.
    pub events: Vec<u64>,
    /// Crosstalk events whose range differs from the true range by more than 3σ_hit (the ones
    /// no model can take for a hit), per separation degree.
    pub distinct: Vec<u64>,
}

impl Default for PairStats {
    fn default() -> Self {
        Self {
            pairs: vec![0; 181],
            events: vec![0; 181],
            distinct: vec![0; 181],
        }
    }
}

impl PairStats {
    /// Pooled event rate over all pairs.
    pub fn rate(&self) -> f64 {
        let p: u64 = self.pairs.iter().sum();
        let e: u64 = self.events.iter().sum();
        e as f64 / p as f64
    }
    /// Pooled rate of distinct events (see [`PairStats::distinct`]).
    pub fn distinct_rate(&self) -> f64 {
        let p: u64 = self.pairs.iter().sum();
        let e: u64 = self.distinct.iter().sum();
        e as f64 / p as f64
    }
    /// Adds another set of counts.
    pub fn merge(&mut self, o: &PairStats) {
        for (a, b) in [
            (&mut self.pairs, &o.pairs),
            (&mut self.events, &o.events),
            (&mut self.distinct, &o.distinct),
        ] {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }
    /// Event rate at one separation (degrees), if any pair was seen.
    pub fn rate_at(&self, deg: usize) -> Option<f64> {
        match (self.pairs.get(deg), self.events.get(deg)) {
            (Some(&p), Some(&e)) if p > 0 => Some(e as f64 / p as f64),
            _ => None,
        }
    }
}

fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut a = a % t;
    if a >= std::f64::consts::PI {
        a -= t;
    }
    if a < -std::f64::consts::PI {
        a += t;
    }
    a
}

/// Origin x, origin y (metres), true range (metres), wall point within range.
type Geometry = (f64, f64, f64, Option<(f64, f64)>);

/// Simulates one full cycle of `groups` (each fired alone in time: no lingering echoes) at
/// robot pose `(x, y, θ)`. Returns one beam per transducer in index order; transducers in no
/// group get `NaN`.
pub fn simulate_cycle(
    room: &Room,
    ring: &SimRing,
    groups: &[Vec<usize>],
    pose: (f64, f64, f64),
    p: &SimParams,
    rng: &mut Rng,
    stats: &mut PairStats,
) -> Vec<SimBeam> {
    let n = ring.bearings_rad.len();
    let zmax = ring.max_range_m;
    // Geometry of each transducer: origin x, origin y, true range, wall point.
    let geo: Vec<Geometry> = ring
        .bearings_rad
        .iter()
        .map(|&b| {
            let a = pose.2 + b;
            let (dx, dy) = (a.cos(), a.sin());
            let (ox, oy) = (pose.0 + ring.radius_m * dx, pose.1 + ring.radius_m * dy);
            let t = room.raycast(ox, oy, dx, dy);
            let zs = t.map_or(zmax, |t| t.min(zmax));
            let wall = t.filter(|&t| t < zmax).map(|t| (ox + t * dx, oy + t * dy));
            (ox, oy, zs, wall)
        })
        .collect();
    let mut out = vec![
        SimBeam {
            range_m: f64::NAN,
            z_star_m: zmax,
            cofired: 0,
            crosstalk: false,
            distinct_crosstalk: false,
        };
        n
    ];
    for group in groups {
        for &i in group {
            let (oxi, oyi, zs, _) = geo[i];
            // The own reading, by the four causes.
            let u = rng.uniform();
            let own = if u < p.p_max {
                zmax
            } else if u < p.p_max + p.p_rand {
                zmax * rng.uniform()
            } else if u < p.p_max + p.p_rand + p.p_short && zs > 0.0 {
                // Truncated exponential on [0, z*] by inversion.
                let m = 1.0 - (-p.lambda_short_per_m * zs).exp();
                -(1.0 - rng.uniform() * m).ln() / p.lambda_short_per_m
            } else {
                (zs + p.sigma_hit_m * rng.normal_clamped()).clamp(0.0, zmax)
            };
            let mut reading = own;
            let mut from_neighbour = false;
            for &j in group {
                if j == i {
                    continue;
                }
                let sep = wrap(ring.bearings_rad[i] - ring.bearings_rad[j]).abs();
                let bin = (sep.to_degrees().round() as usize).min(180);
                stats.pairs[bin] += 1;
                let (oxj, oyj, _, wall) = geo[j];
                let Some((px, py)) = wall else { continue };
                let (vx, vy) = (oxi - px, oyi - py);
                let back = (vx * vx + vy * vy).sqrt();
                // Line of sight from the wall point back to transducer i.
                let blocked = room
                    .raycast(px, py, vx / back, vy / back)
                    .is_some_and(|t| t < back - 1e-6);
                if blocked {
                    continue;
                }
                let out_len = ((px - oxj).powi(2) + (py - oyj).powi(2)).sqrt();
                let r = 0.5 * (out_len + back);
                if rng.uniform() < p.q_true.at(sep) && r < own && r < zmax {
                    stats.events[bin] += 1;
                    if (r - zs).abs() > 3.0 * p.sigma_hit_m {
                        stats.distinct[bin] += 1;
                    }
                    if r < reading {
                        reading = r;
                        from_neighbour = true;
                    }
                }
            }
            out[i] = SimBeam {
                range_m: reading,
                z_star_m: zs,
                cofired: group.len() - 1,
                crosstalk: from_neighbour,
                distinct_crosstalk: from_neighbour && (reading - zs).abs() > 3.0 * p.sigma_hit_m,
            };
        }
    }
    out
}

/// Groups of `k` transducers spread evenly around an `n`-ring (`k` divides `n`): group `g`
/// holds `g, g + n/k, g + 2n/k, …`.
pub fn spread_groups(n: usize, k: usize) -> Vec<Vec<usize>> {
    let step = n / k;
    (0..step)
        .map(|g| (0..k).map(|m| g + m * step).collect())
        .collect()
}

/// Reference `c_i` (docs/models.md#sonar) from the definitions, in f64, independent of the crate: group g fires at g·Δ; j's last pulse before i's is
/// ((g_i − g_j) mod T)·Δ earlier; weight = clamp(1 − age/L, 0, 1); same group = 1.
pub fn reference_c(
    bearings: &[f64],
    groups: &[Vec<usize>],
    interval: f64,
    lifetime: f64,
    q: &dyn Fn(f64) -> f64,
    i: usize,
) -> f64 {
    let t = groups.len();
    let gi = groups.iter().position(|g| g.contains(&i));
    let Some(gi) = gi else { return 0.0 };
    let mut clean = 1.0;
    for (gj, g) in groups.iter().enumerate() {
        for &j in g {
            if j == i {
                continue;
            }
            let w = if gj == gi {
                1.0
            } else {
                let age = ((gi + t - gj) % t) as f64 * interval;
                (1.0 - age / lifetime).clamp(0.0, 1.0)
            };
            let mut d = (bearings[i] - bearings[j]).rem_euclid(std::f64::consts::TAU);
            if d > std::f64::consts::PI {
                d = std::f64::consts::TAU - d;
            }
            clean *= 1.0 - w * q(d);
        }
    }
    1.0 - clean
}
