//! The size programs' body ([`size_program!`]).

/// The whole program of `bin/size_core.rs`, `bin/size_lf.rs` and `bin/size_skeleton.rs`: each
/// is one call of this macro, which says whether it scores (`score`) and links the beam model
/// (`beam_model`). The body is expanded into each program, so it is compiled as the program's
/// own code. `size_lf` is the likelihood-field core alone
/// (what a user who localizes with the likelihood field flashes); `size_core` adds the beam model
/// with ray casting. The programs are the same text: they link the same blob, read the same opaque
/// inputs, end the same way and have the same (non-formatting) panic handler. Only `size_core`
/// calls the scoring core (`score` below), so the difference of their sections, as
/// `cargo xtask budgets` computes it with `llvm-size -A`, is what the scoring core costs in
/// flash and static RAM. No `core::fmt` is linked in either: there is no printing at all.
///
/// `size_core` built with the firmware feature `nopanic` is also the link-time proof of no
/// panics (`cargo xtask nopanic`): its panic handler then calls a function that is defined
/// nowhere, so it links only if no panic path survives optimization. The feature
/// `deliberate-panic` adds an indexing that can panic, to show that the proof can fail.
#[macro_export]
macro_rules! size_program {
    (score: $score:expr, beam_model: $beam_model:expr) => {
        /// Whether this program calls the scoring core.
        const SCORE: bool = $score;
        /// Whether this program links the beam model.
        const BEAM_MODEL: bool = $beam_model;

        use beamfield::{
            normalize_log_weights, BeamFieldModel, BeamIntrinsics, BeamLayout, BeamModel,
            FieldView, LikelihoodField, LikelihoodParams, Pose, RayCaster, Scan, SensorModel,
            SensorMount, Tempered,
        };
        use core::hint::black_box;
        use cortex_m_rt::entry;
        use $crate::exit;

        /// The Intel-lab distance field (the demo's blob), linked into both programs.
        static BLOB: &[u8] =
            include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/intel.bin"));
        /// Beams per scan: the size the budgets are stated for.
        const BEAMS: usize = 360;
        /// Pose hypotheses scored and normalized.
        const POSES: usize = 16;
        /// Readings, metres: their values do not matter, they reach the code through `black_box`.
        static RANGES_M: [f32; BEAMS] = [2.5; BEAMS];
        /// Model parameters, read through `black_box` so that no validation is folded away:
        /// `[max_range_m, z_hit, z_rand, sigma_hit_m, kappa, x_m, y_m, theta_rad]`.
        static PARAMS: [f32; 8] = [30.0, 0.95, 0.05, 0.0588, 8.25, 9.9, -18.96, 3.13];

        /// The scoring core: parses the blob, builds the tempered likelihood field, the beam layout
        /// and the scan, scores `POSES` hypotheses (through `score` and through a `PreparedScan`),
        /// normalizes their weights, and, with `BEAM_MODEL`, scores the best one with the beam model
        /// (ray casting through the same blob). Returns a checksum of every result, or NaN when an
        /// input is rejected.
        #[inline(never)]
        fn score(blob: &[u8], ranges_m: &[f32], p: &[f32; 8]) -> f32 {
            let [max_range_m, z_hit, z_rand, sigma_hit_m, kappa, x_m, y_m, theta_rad] = *p;
            let Ok(view) = FieldView::parse(blob) else {
                return f32::NAN;
            };
            let Ok(params) = LikelihoodParams::new(z_hit, z_rand, sigma_hit_m, max_range_m) else {
                return f32::NAN;
            };
            let field = LikelihoodField::new(view, params);
            let Ok(tempered) = Tempered::new(field.clone(), kappa, 1) else {
                return f32::NAN;
            };
            let tau = 2.0 * core::f32::consts::PI;
            let Ok(layout) = BeamLayout::<BEAMS>::uniform(
                -core::f32::consts::PI,
                tau / BEAMS as f32,
                BEAMS,
                max_range_m,
                SensorMount::CENTERED,
            ) else {
                return f32::NAN;
            };
            let Ok(scan) = Scan::<BEAMS>::from_ranges(ranges_m) else {
                return f32::NAN;
            };
            let mut weights = [0.0f32; POSES];
            for (i, w) in weights.iter_mut().enumerate() {
                let d = 0.01 * i as f32;
                let pose = Pose::new(x_m + d, y_m - d, theta_rad + d);
                *w = tempered.score(&layout, &scan, &pose).log_likelihood;
            }
            let prepared = field.prepare(&layout, &scan);
            let mut sum = 0.0f32;
            for (i, w) in weights.iter_mut().enumerate() {
                let d = 0.005 * i as f32;
                let pose = Pose::new(x_m - d, y_m + d, theta_rad - d);
                sum += prepared.score(&pose).log_likelihood;
                *w += sum;
            }
            let Ok(norm) = normalize_log_weights(&mut weights) else {
                return f32::NAN;
            };
            sum += norm.ess + norm.log_total;
            if BEAM_MODEL {
                let Ok(intrinsics) = BeamIntrinsics::amcl_defaults(max_range_m) else {
                    return f32::NAN;
                };
                let Ok(caster) = RayCaster::new(view) else {
                    return f32::NAN;
                };
                let beam = BeamFieldModel::new(BeamModel::new(intrinsics), caster);
                let d = 0.01 * norm.best as f32;
                let best = Pose::new(x_m + d, y_m - d, theta_rad + d);
                sum += beam.score(&layout, &scan, &best).log_likelihood;
            }
            #[cfg(feature = "deliberate-panic")]
            {
                // An index the compiler cannot prove in bounds: a panic path the no-panic link must
                // reject (`cargo xtask nopanic --show-failure`).
                #[allow(clippy::indexing_slicing)]
                let extra = ranges_m[black_box(BEAMS)];
                sum += extra;
            }
            for w in weights {
                sum += w;
            }
            sum
        }

        #[entry]
        fn main() -> ! {
            let blob: &[u8] = black_box(BLOB);
            let ranges_m: &[f32] = black_box(&RANGES_M[..]);
            let params: &[f32; 8] = black_box(&PARAMS);
            let checksum = if SCORE {
                score(blob, ranges_m, params)
            } else {
                // The skeleton: the same inputs kept alive, no scoring.
                black_box((blob.len(), ranges_m.len(), params));
                black_box(0.0f32)
            };
            exit(!black_box(checksum).is_nan())
        }

        /// Without `nopanic`: stop with exit status 1, printing nothing (no `core::fmt`).
        #[cfg(not(feature = "nopanic"))]
        #[panic_handler]
        fn on_panic(_: &core::panic::PanicInfo) -> ! {
            exit(false)
        }

        /// With `nopanic`: a call to a function that no object defines. The program links only if
        /// the optimizer removed every call of this handler, i.e. no panic path is left.
        #[cfg(feature = "nopanic")]
        #[panic_handler]
        fn on_panic(_: &core::panic::PanicInfo) -> ! {
            extern "C" {
                fn beamfield_scoring_path_can_panic() -> !;
            }
            // SAFETY: never executed in a program that links (the symbol exists nowhere).
            unsafe { beamfield_scoring_path_can_panic() }
        }
    };
}
