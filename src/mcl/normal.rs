//! Standard normal variates by the ziggurat method (Marsaglia & Tsang, "The Ziggurat Method for
//! Generating Random Variables", *Journal of Statistical Software* 5(8), 2000), table-driven:
//! about a dozen instructions and one 32-bit word per draw on the common path, where the
//! Box–Muller transform ([`crate::gaussian::standard_normal_pair`]) needs a logarithm, a square
//! root and a sine and cosine.
//!
//! # The method
//! The area under the half density `f(x) = e^{−x²/2}`, `x ≥ 0`, is covered by [`LAYERS`] = 128
//! horizontal layers of equal area `v`: layer 0 is the base strip (the rectangle `[0, r] × [0,
//! f(r)]` plus the tail `x > r`, drawn as a rectangle of width `x₀ = v/f(r)`), layer `i ≥ 1` is
//! the rectangle `[0, xᵢ] × [f(xᵢ), f(xᵢ₊₁)]` with `x₁ = r` and `x₁₂₈ = 0`. `r` is the value for
//! which the stack ends exactly at the peak: `r = 3.442619855899…`, `v = 9.912563035262…e-3`.
//! A draw picks a layer `i` and a point `x = u·xᵢ`, `u` uniform on `[0, 1)`:
//!
//! - `x < xᵢ₊₁`: the point lies under the curve whatever its height: accept (98.8 % of draws);
//! - layer 0 and `x ≥ r`: draw from the tail `x > r` instead, by Marsaglia's (1964) method
//!   (`a = −ln(u₁)/r`, `b = −ln(u₂)` until `2b > a²`; return `r + a`);
//! - otherwise (a wedge): draw the height `y` uniformly in `[f(xᵢ), f(xᵢ₊₁))` and accept if
//!   `y < f(x)`, else start again with a new word.
//!
//! The accepted points are uniform under the curve, so `x` is exactly half-normal, and a sign
//! bit makes it normal.
//!
//! # Bits and rounding
//! One `u32` word `b` per attempt: layer `i = b & 127`, sign bit 7, and the 24-bit integer
//! `m = b >> 8`, so `u = m·2⁻²⁴` and `x = m · ZIGGURAT_W[i]` with `ZIGGURAT_W[i] = xᵢ·2⁻²⁴`
//! (rounded to f32). The fast test `x < xᵢ₊₁` is done in integers, exactly: `m < ZIGGURAT_K[i]
//! = ⌈2²⁴·xᵢ₊₁/xᵢ⌉`. The wedge test uses the filter's own `e^x` for `x ≤ 0` (within 2.6e-7
//! relative, `src/math/fast.rs`), the tail [`crate::math`]'s `ln`; they take one more word
//! each (two for a tail try). The tables were computed in f64 from the definition
//! above (`r` by bisection on "the top layer ends at the peak") and rounded once;
//! `host-tests/tests/mcl_ziggurat.rs` recomputes them and requires every entry to match bit for
//! bit, and tests the draws against the normal CDF (Kolmogorov–Smirnov) and its moments.
//!
//! Limits: `x` takes values on a 24-bit grid per layer (steps below `xᵢ·6e-8`), the f32 tables
//! and products round at 6e-8 relative, and after 16 rejected attempts in a row (probability
//! below 1e-30 with a sound generator; a broken one that returns a constant word could otherwise
//! loop for ever) the last candidate is returned as it is.

use crate::gaussian::{uniform_f32, uniform_open_closed_f32};
use crate::math;
use crate::math::fast::exp_nonpositive;
use rand_core::Rng;

/// Number of layers of the ziggurat.
pub const LAYERS: usize = 128;

/// Attempts before a draw gives up and returns its last candidate.
const MAX_ATTEMPTS: u32 = 16;

/// A standard normal variate (mean 0, variance 1): one `next_u32`, and more in the rare slow
/// path (about 1.2 % of draws; see the module docs).
#[inline]
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    let word = rng.next_u32();
    standard_normal_from(word, rng)
}

/// A standard normal variate whose first attempt uses `word` (already drawn by the caller, e.g.
/// one half of a `next_u64`); further attempts draw from `rng`.
#[inline]
pub fn standard_normal_from<R: Rng + ?Sized>(word: u32, rng: &mut R) -> f32 {
    let i = (word & 0x7F) as usize;
    let m = word >> 8;
    let x = m as f32 * ZIGGURAT_W.get(i).copied().unwrap_or(0.0);
    if m < ZIGGURAT_K.get(i).copied().unwrap_or(0) {
        return if word & 0x80 != 0 { -x } else { x };
    }
    slow(word, rng)
}

/// The rare cases: the tail, the wedges, and the retries.
#[inline(never)]
fn slow<R: Rng + ?Sized>(mut word: u32, rng: &mut R) -> f32 {
    let mut x = 0.0f32;
    for attempt in 0..MAX_ATTEMPTS {
        if attempt > 0 {
            word = rng.next_u32();
        }
        let i = (word & 0x7F) as usize;
        let m = word >> 8;
        x = m as f32 * ZIGGURAT_W.get(i).copied().unwrap_or(0.0);
        let negative = word & 0x80 != 0;
        let accepted = if m < ZIGGURAT_K.get(i).copied().unwrap_or(0) {
            true
        } else if i == 0 {
            x = tail(rng);
            true
        } else {
            let lo = ZIGGURAT_F.get(i).copied().unwrap_or(0.0);
            let hi = ZIGGURAT_F.get(i + 1).copied().unwrap_or(1.0);
            let y = lo + uniform_f32(rng) * (hi - lo);
            y < exp_nonpositive(-0.5 * x * x)
        };
        x = if negative { -x } else { x };
        if accepted {
            break;
        }
    }
    x
}

/// A draw from the normal's tail beyond [`ZIGGURAT_R`] (Marsaglia 1964): two words per try.
fn tail<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    let mut x = ZIGGURAT_R;
    for _ in 0..MAX_ATTEMPTS {
        let a = -math::ln(uniform_open_closed_f32(rng)) / ZIGGURAT_R;
        let b = -math::ln(uniform_open_closed_f32(rng));
        x = ZIGGURAT_R + a;
        if 2.0 * b > a * a {
            break;
        }
    }
    x
}

/// Where the base strip's rectangle ends and the tail begins, `r` (rounded to f32).
pub const ZIGGURAT_R: f32 = 3.4426198;
/// `xᵢ·2⁻²⁴`: the scale from the 24-bit integer to `x` in layer `i`.
pub const ZIGGURAT_W: [f32; LAYERS] = [
    2.2131718e-7,
    2.0519613e-7,
    1.9211083e-7,
    1.8377476e-7,
    1.7754414e-7,
    1.7251635e-7,
    1.6827138e-7,
    1.6457852e-7,
    1.6129694e-7,
    1.5833416e-7,
    1.5562607e-7,
    1.5312634e-7,
    1.5080033e-7,
    1.4862147e-7,
    1.4656891e-7,
    1.4462594e-7,
    1.4277902e-7,
    1.4101693e-7,
    1.3933034e-7,
    1.3771138e-7,
    1.3615335e-7,
    1.3465045e-7,
    1.3319769e-7,
    1.3179073e-7,
    1.3042572e-7,
    1.2909929e-7,
    1.2780846e-7,
    1.2655053e-7,
    1.2532313e-7,
    1.2412407e-7,
    1.229514e-7,
    1.2180338e-7,
    1.2067837e-7,
    1.1957489e-7,
    1.1849163e-7,
    1.17427305e-7,
    1.163808e-7,
    1.15351035e-7,
    1.1433705e-7,
    1.1333791e-7,
    1.12352794e-7,
    1.11380885e-7,
    1.10421446e-7,
    1.09473795e-7,
    1.0853726e-7,
    1.0761123e-7,
    1.0669511e-7,
    1.05788374e-7,
    1.0489048e-7,
    1.0400093e-7,
    1.0311926e-7,
    1.0224502e-7,
    1.01377765e-7,
    1.00517084e-7,
    9.9662586e-8,
    9.8813885e-8,
    9.797061e-8,
    9.7132414e-8,
    9.629894e-8,
    9.546986e-8,
    9.464484e-8,
    9.3823566e-8,
    9.300573e-8,
    9.219103e-8,
    9.137916e-8,
    9.056983e-8,
    8.976275e-8,
    8.8957634e-8,
    8.8154195e-8,
    8.7352156e-8,
    8.6551225e-8,
    8.575113e-8,
    8.4951594e-8,
    8.4152326e-8,
    8.335304e-8,
    8.255345e-8,
    8.1753264e-8,
    8.09522e-8,
    8.014993e-8,
    7.934618e-8,
    7.854061e-8,
    7.773291e-8,
    7.692275e-8,
    7.6109785e-8,
    7.5293656e-8,
    7.447401e-8,
    7.365045e-8,
    7.282259e-8,
    7.199e-8,
    7.115225e-8,
    7.0308886e-8,
    6.945942e-8,
    6.860333e-8,
    6.7740075e-8,
    6.686908e-8,
    6.598971e-8,
    6.510132e-8,
    6.420318e-8,
    6.329453e-8,
    6.2374525e-8,
    6.144227e-8,
    6.0496774e-8,
    5.9536948e-8,
    5.856161e-8,
    5.7569448e-8,
    5.6559003e-8,
    5.5528652e-8,
    5.4476573e-8,
    5.3400715e-8,
    5.2298752e-8,
    5.1168016e-8,
    5.000545e-8,
    4.8807497e-8,
    4.7569994e-8,
    4.628801e-8,
    4.495565e-8,
    4.3565745e-8,
    4.2109466e-8,
    4.057574e-8,
    3.895036e-8,
    3.7214672e-8,
    3.5343344e-8,
    3.3300648e-8,
    3.103352e-8,
    2.8457512e-8,
    2.542424e-8,
    2.1628823e-8,
    1.6231589e-8,
];
/// `⌈2²⁴·xᵢ₊₁/xᵢ⌉`: 24-bit integers below this lie under the curve in layer `i`.
pub const ZIGGURAT_K: [u32; LAYERS] = [
    15555141, 15707338, 16049219, 16208408, 16302111, 16364394, 16409026, 16442690, 16469045,
    16490265, 16507733, 16522368, 16534809, 16545511, 16554812, 16562965, 16570163, 16576559,
    16582273, 16587402, 16592025, 16596206, 16599999, 16603449, 16606593, 16609465, 16612091,
    16614494, 16616696, 16618714, 16620563, 16622257, 16623808, 16625226, 16626520, 16627698,
    16628768, 16629737, 16630609, 16631390, 16632085, 16632698, 16633231, 16633689, 16634075,
    16634390, 16634637, 16634817, 16634934, 16634987, 16634979, 16634910, 16634781, 16634593,
    16634346, 16634041, 16633677, 16633254, 16632773, 16632233, 16631634, 16630974, 16630253,
    16629470, 16628624, 16627713, 16626735, 16625690, 16624575, 16623387, 16622125, 16620786,
    16619367, 16617865, 16616276, 16614597, 16612822, 16610949, 16608972, 16606885, 16604682,
    16602358, 16599905, 16597314, 16594579, 16591688, 16588633, 16585401, 16581980, 16578357,
    16574515, 16570437, 16566104, 16561496, 16556587, 16551351, 16545758, 16539772, 16533356,
    16526462, 16519042, 16511034, 16502372, 16492974, 16482747, 16471581, 16459346, 16445883,
    16431005, 16414482, 16396029, 16375294, 16351834, 16325081, 16294298, 16258511, 16216402,
    16166150, 16105158, 16029597, 15933580, 15807564, 15635012, 15384587, 14988942, 14272656,
    12590647, 0,
];
/// `f(xᵢ) = e^{−xᵢ²/2}`, `i = 0 … 128` (`f(x₁₂₈) = f(0) = 1`): the layers' heights.
pub const ZIGGURAT_F: [f32; LAYERS + 1] = [
    0.0010143525,
    0.0026696292,
    0.005548995,
    0.008624485,
    0.011839478,
    0.015167298,
    0.018592102,
    0.022103304,
    0.025693292,
    0.029356318,
    0.033087887,
    0.03688439,
    0.040742867,
    0.044660863,
    0.048636295,
    0.0526674,
    0.056752663,
    0.06089077,
    0.06508058,
    0.06932112,
    0.073611505,
    0.077950984,
    0.0823389,
    0.08677467,
    0.0912578,
    0.095787846,
    0.10036444,
    0.104987256,
    0.10965602,
    0.11437051,
    0.119130544,
    0.12393598,
    0.12878671,
    0.13368265,
    0.13862377,
    0.14361008,
    0.14864157,
    0.15371831,
    0.15884037,
    0.16400786,
    0.1692209,
    0.17447963,
    0.17978427,
    0.18513499,
    0.19053204,
    0.19597565,
    0.20146611,
    0.20700371,
    0.21258877,
    0.21822165,
    0.2239027,
    0.22963232,
    0.23541094,
    0.241239,
    0.24711695,
    0.2530453,
    0.25902456,
    0.2650553,
    0.27113807,
    0.2772735,
    0.2834622,
    0.28970486,
    0.29600215,
    0.30235484,
    0.30876362,
    0.3152294,
    0.3217529,
    0.3283351,
    0.33497685,
    0.34167916,
    0.34844297,
    0.35526937,
    0.3621595,
    0.36911446,
    0.37613547,
    0.3832238,
    0.3903808,
    0.39760786,
    0.40490642,
    0.41227803,
    0.41972435,
    0.427247,
    0.43484783,
    0.44252872,
    0.45029163,
    0.4581387,
    0.46607214,
    0.4740943,
    0.48220766,
    0.49041483,
    0.49871865,
    0.50712204,
    0.5156282,
    0.52424055,
    0.5329627,
    0.54179835,
    0.5507518,
    0.5598274,
    0.56903,
    0.5783647,
    0.58783704,
    0.5974532,
    0.6072195,
    0.6171434,
    0.6272325,
    0.63749546,
    0.6479418,
    0.658582,
    0.6694277,
    0.68049186,
    0.69178915,
    0.7033361,
    0.7151515,
    0.7272569,
    0.73967725,
    0.7524416,
    0.7655842,
    0.7791461,
    0.793177,
    0.8077383,
    0.8229072,
    0.8387836,
    0.8555006,
    0.87324303,
    0.89228165,
    0.9130436,
    0.9362827,
    0.9635997,
    1.0,
];
