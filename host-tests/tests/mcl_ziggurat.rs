//! The localizer's Gaussian sampler (`beamfield::mcl::normal`, a 128-layer ziggurat):
//!
//! - its tables are recomputed here from their definition in f64 and must match bit for bit
//!   (run with `BEAMFIELD_PRINT_ZIGGURAT=1 cargo test -p host-tests --test mcl_ziggurat -- --nocapture`
//!   to print them as Rust source: that is how `src/mcl/normal.rs` got them);
//! - its draws must pass a Kolmogorov–Smirnov test against the normal CDF and match the normal's
//!   moments, over a million draws, and its tail beyond the base strip must have the right mass.

use beamfield::math;
use beamfield::mcl::normal::{
    standard_normal, LAYERS, ZIGGURAT_F, ZIGGURAT_K, ZIGGURAT_R, ZIGGURAT_W,
};
use beamfield::mcl::SplitMix64;

/// The unnormalized density `e^{−x²/2}`.
fn f(x: f64) -> f64 {
    math::exp_f64(-0.5 * x * x)
}

/// The area of every layer for a base strip starting at `r`: the rectangle `r·f(r)` plus the
/// tail `∫_r^∞ f = √(π/2)·erfc(r/√2)`.
fn layer_area(r: f64) -> f64 {
    r * f(r) + (core::f64::consts::PI / 2.0).sqrt() * math::erfc_f64(r / core::f64::consts::SQRT_2)
}

/// The layers' right edges `x[1] = r > x[2] > … > x[n−1]` for a given `r` (and `x[0] = v/f(r)`,
/// `x[n] = 0`), or None when the stack overshoots the top before layer `n − 1`.
fn edges(r: f64, n: usize) -> Option<Vec<f64>> {
    let v = layer_area(r);
    let mut x = vec![v / f(r), r];
    for _ in 1..n - 1 {
        let last = *x.last()?;
        let a = f(last) + v / last;
        if a >= 1.0 {
            return None;
        }
        x.push((-2.0 * a.ln()).sqrt());
    }
    x.push(0.0);
    Some(x)
}

/// How far the top layer misses the peak `f(0) = 1` (positive: `r` too small).
fn top_miss(r: f64, n: usize) -> f64 {
    match edges(r, n) {
        None => 1.0,
        Some(x) => {
            let last = x[n - 1];
            f(last) + layer_area(r) / last - 1.0
        }
    }
}

/// `r` by bisection: the base strip's start for which `n` equal layers end exactly at the peak.
fn solve_r(n: usize) -> f64 {
    let (mut lo, mut hi) = (2.0f64, 5.0f64);
    assert!(top_miss(lo, n) > 0.0 && top_miss(hi, n) < 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if top_miss(mid, n) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

struct Tables {
    r: f64,
    w: Vec<f32>,
    k: Vec<u32>,
    f: Vec<f32>,
}

fn tables(n: usize) -> Tables {
    let r = solve_r(n);
    let x = edges(r, n).expect("a solved r stacks all layers");
    let two24 = 16_777_216.0f64;
    let w = (0..n).map(|i| (x[i] / two24) as f32).collect();
    let k = (0..n)
        .map(|i| (two24 * x[i + 1] / x[i]).ceil() as u32)
        .collect();
    let mut fs: Vec<f32> = (0..n).map(|i| f(x[i]) as f32).collect();
    fs.push(1.0);
    Tables { r, w, k, f: fs }
}

#[test]
fn tables_match_their_definition() {
    let t = tables(LAYERS);
    // Marsaglia & Tsang (2000), "The ziggurat method for generating random variables", J. Stat.
    // Software 5(8), give r = 3.442619855899 and v = 9.91256303526217e-3 for 128 layers.
    assert!((t.r - 3.442_619_855_899).abs() < 1e-9, "{}", t.r);
    assert!((layer_area(t.r) - 9.912_563_035_262_17e-3).abs() < 1e-12);
    if std::env::var_os("BEAMFIELD_PRINT_ZIGGURAT").is_some() {
        println!("pub const ZIGGURAT_R: f32 = {:?};", t.r as f32);
        println!("pub const ZIGGURAT_W: [f32; LAYERS] = {:?};", t.w);
        println!("pub const ZIGGURAT_K: [u32; LAYERS] = {:?};", t.k);
        println!("pub const ZIGGURAT_F: [f32; LAYERS + 1] = {:?};", t.f);
    }
    assert_eq!(ZIGGURAT_R.to_bits(), (t.r as f32).to_bits());
    for i in 0..LAYERS {
        assert_eq!(ZIGGURAT_W[i].to_bits(), t.w[i].to_bits(), "w[{i}]");
        assert_eq!(ZIGGURAT_K[i], t.k[i], "k[{i}]");
    }
    for (i, (got, want)) in ZIGGURAT_F.iter().zip(&t.f).enumerate() {
        assert_eq!(got.to_bits(), want.to_bits(), "f[{i}]");
    }
    assert_eq!(t.f.len(), LAYERS + 1);
}

/// A million draws from a fixed seed, sorted.
fn draws(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    let mut v: Vec<f64> = (0..n)
        .map(|_| f64::from(standard_normal(&mut rng)))
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

#[test]
fn kolmogorov_smirnov_against_the_normal_cdf() {
    let n = 1_000_000;
    let v = draws(n, 11);
    let mut d = 0.0f64;
    for (i, &x) in v.iter().enumerate() {
        let cdf = math::normal_cdf_f64(x);
        let lo = i as f64 / n as f64;
        let hi = (i + 1) as f64 / n as f64;
        d = d.max((cdf - lo).abs()).max((hi - cdf).abs());
    }
    // The KS statistic's critical value at the 0.1 % level is 1.95/√n (asymptotic).
    let critical = 1.95 / (n as f64).sqrt();
    assert!(d < critical, "D = {d} >= {critical}");
}

#[test]
fn chi_square_over_equiprobable_bins() {
    // 256 bins of equal normal probability; a layer's wedge or table entry off by a little
    // shifts mass between neighbouring bins, which the KS statistic may average away.
    let (n, bins) = (2_000_000usize, 256usize);
    let mut rng = SplitMix64::new(12);
    let mut counts = vec![0u64; bins];
    for _ in 0..n {
        let p = math::normal_cdf_f64(f64::from(standard_normal(&mut rng)));
        counts[((p * bins as f64) as usize).min(bins - 1)] += 1;
    }
    let expected = n as f64 / bins as f64;
    let chi2: f64 = counts
        .iter()
        .map(|&c| (c as f64 - expected).powi(2) / expected)
        .sum();
    // χ² with 255 degrees of freedom: the 0.1 % upper point is 330.5 (Wilson–Hilferty).
    assert!(chi2 < 330.5, "chi2 = {chi2}");
}

#[test]
fn moments_and_tail_mass() {
    let n = 1_000_000usize;
    let v = draws(n, 13);
    let nf = n as f64;
    let mean = v.iter().sum::<f64>() / nf;
    let m2 = v.iter().map(|x| x * x).sum::<f64>() / nf;
    let m4 = v.iter().map(|x| x.powi(4)).sum::<f64>() / nf;
    // Four standard errors: σ(mean) = 1/√n, σ(m2) = √(2/n), σ(m4) = √(96/n) for a normal.
    assert!(mean.abs() < 4.0 / nf.sqrt(), "mean {mean}");
    assert!((m2 - 1.0).abs() < 4.0 * (2.0 / nf).sqrt(), "variance {m2}");
    assert!(
        (m4 - 3.0).abs() < 4.0 * (96.0 / nf).sqrt(),
        "fourth moment {m4}"
    );
    // The tail beyond r comes from its own sampler: its mass must be 2·Φ(−r).
    let r = f64::from(ZIGGURAT_R);
    let tail = v.iter().filter(|x| x.abs() > r).count() as f64;
    let p = 2.0 * math::normal_cdf_f64(-r);
    let sd = (nf * p * (1.0 - p)).sqrt();
    assert!(
        (tail - nf * p).abs() < 4.0 * sd,
        "tail {tail} vs {}",
        nf * p
    );
    assert!(
        v.iter().any(|x| x.abs() > r + 0.5),
        "no draw deep in the tail"
    );
}

/// Returns the same word for ever.
struct Stuck(u32);

impl rand_core::TryRng for Stuck {
    type Error = core::convert::Infallible;
    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        Ok(self.0)
    }
    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        Ok(u64::from(self.0) << 32 | u64::from(self.0))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        dst.fill(self.0 as u8);
        Ok(())
    }
}

#[test]
fn a_stuck_generator_does_not_hang_the_draw() {
    // Layer 127 with the largest 24-bit value: a wedge that a constant word rejects every time.
    for word in [u32::MAX, 0x7F, 0, 0x80, 0xFFFF_FF00] {
        let x = standard_normal(&mut Stuck(word));
        assert!(x.is_finite() && x.abs() < 10.0, "{word:#x}: {x}");
    }
}
