//! The localizer under bad input (property tests with random inputs): NaN or infinite
//! odometry, steps beyond the motion model, empty and all-invalid scans, zero capacity, scores
//! of NaN / ±∞ / huge magnitude, particles and poses with NaN or infinite coordinates, sets too
//! small for the resampling threshold.
//! Every case ends in a typed error or a documented skip, never a panic, never a NaN in the
//! particles or weights.

use beamfield::field::{
    emit_blob, FieldHeader, FieldView, FreeSpace, LikelihoodField, LikelihoodParams,
};
use beamfield::mcl::{
    Mcl, MclConfig, MclError, OdometryNoise, OdometryStep, Particles, SplitMix64,
};
use beamfield::{BeamLayout, Pose, Scan, SensorMount, Tempered};
use proptest::prelude::*;

const N: usize = 64;

fn config() -> MclConfig {
    MclConfig::new(OdometryNoise::uniform(0.01).unwrap(), 0.5, 0.001, 0.1).unwrap()
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        -1e3f32..1e3,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(f32::MAX),
        Just(-f32::MAX),
        any::<f32>(),
    ]
}

fn healthy<const C: usize>(f: &Mcl<'_, C>) {
    assert!(f.poses().iter().all(Pose::is_finite), "non-finite particle");
    let sum: f32 = f.weights().iter().sum();
    assert!(f.weights().iter().all(|w| w.is_finite() && *w >= 0.0));
    assert!((sum - 1.0).abs() < 1e-3, "weights sum to {sum}");
    let e = f.estimate();
    assert!(e.pose.is_finite() && e.ess.is_finite());
}

/// A 20 × 20 room of 10 cm cells, walls on the border, every inner cell free.
fn room() -> (Vec<u8>, Vec<u8>) {
    let (w, h) = (20u32, 20u32);
    let header = FieldHeader::new(w, h, 0.1, 0.0, 0.0);
    let codes: Vec<u8> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let d = x.min(y).min(w - 1 - x).min(h - 1 - y);
            header.encode_distance_m(f64::from(d) * 0.1)
        })
        .collect();
    let mut blob = vec![0u8; header.required_len().unwrap()];
    emit_blob(&header, &codes, &mut blob).unwrap();
    let grid = beamfield::field::FreeSpaceGrid::of_view(&FieldView::parse(&blob).unwrap());
    let free: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            x > 0 && y > 0 && x < w - 1 && y < h - 1
        })
        .collect();
    let mut fs = vec![0u8; beamfield::field::free_space_len(&grid, &free).unwrap()];
    beamfield::field::emit_free_space(&grid, &free, &mut fs).unwrap();
    (blob, fs)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn odometry_is_finite_or_a_typed_error(a in prop::array::uniform6(any_f32()), seed in any::<u64>()) {
        let prev = Pose::new(a[0], a[1], a[2]);
        let cur = Pose::new(a[3], a[4], a[5]);
        let mut store = Particles::<N>::new();
        let mut f = Mcl::new(&mut store, config()).unwrap();
        let mut rng = SplitMix64::new(seed);
        f.init_gaussian(N, &Pose::new(1.0, 1.0, 0.0), 0.1, 0.1, &mut rng).unwrap();
        match OdometryStep::between(&prev, &cur) {
            Ok(step) => {
                prop_assert!(step.rot1_rad().is_finite() && step.trans_m().is_finite());
                prop_assert!(step.trans_m().abs() <= beamfield::mcl::MAX_STEP_M);
                f.predict(&step, &mut rng);
                healthy(&f);
            }
            Err(e) => prop_assert!(matches!(
                e,
                beamfield::mcl::MotionError::NonFiniteOdometry
                    | beamfield::mcl::MotionError::StepTooLarge
            )),
        }
    }

    #[test]
    fn any_scores_keep_the_set_finite(
        scores in prop::collection::vec(any_f32(), N),
        seed in any::<u64>(),
        rounds in 1usize..4,
    ) {
        let (_, fs) = room();
        let free = FreeSpace::parse(&fs).unwrap();
        let mut store = Particles::<N>::new();
        let mut f = Mcl::new(&mut store, config()).unwrap();
        let mut rng = SplitMix64::new(seed);
        f.init_uniform(N, &free, &mut rng).unwrap();
        let all_impossible = scores.iter().all(|s| s.is_nan() || *s == f32::NEG_INFINITY);
        for _ in 0..rounds {
            let mut i = 0;
            let r = f.update_with(
                |_| {
                    let s = scores[i % N];
                    i += 1;
                    s
                },
                Some(&free),
                &mut rng,
            );
            if all_impossible {
                prop_assert_eq!(r.err(), Some(MclError::AllImpossible));
            } else {
                prop_assert!(r.is_ok());
            }
            healthy(&f);
        }
    }

    #[test]
    fn any_scores_keep_the_set_finite_with_the_retry(
        scores in prop::collection::vec(any_f32(), N),
        seed in any::<u64>(),
        rounds in 1usize..4,
        scale in prop_oneof![Just(0.3f32), Just(1.0f32), Just(1e3f32)],
    ) {
        // The retry at every update (after the first): every score is used twice per update.
        let (_, fs) = room();
        let free = FreeSpace::parse(&fs).unwrap();
        let mut store = Particles::<N>::new();
        let c = config().with_retry(f32::NEG_INFINITY, scale).unwrap();
        let mut f = Mcl::new(&mut store, c).unwrap();
        let mut rng = SplitMix64::new(seed);
        f.init_uniform(N, &free, &mut rng).unwrap();
        let step = OdometryStep::new(0.1, 0.5, -0.1).unwrap();
        let all_impossible = scores.iter().all(|s| s.is_nan() || *s == f32::NEG_INFINITY);
        for _ in 0..rounds {
            f.predict(&step, &mut rng);
            let mut i = 0;
            let r = f.update_with(
                |_| {
                    let s = scores[i % N];
                    i += 1;
                    s
                },
                Some(&free),
                &mut rng,
            );
            if all_impossible {
                prop_assert_eq!(r.err(), Some(MclError::AllImpossible));
            } else {
                prop_assert!(r.is_ok());
            }
            healthy(&f);
        }
    }

    #[test]
    fn empty_and_invalid_scans_are_skipped(ranges in prop::collection::vec(prop_oneof![Just(f32::NAN), -10f32..-0.001], 0..30), seed in any::<u64>()) {
        let (blob, fs) = room();
        let free = FreeSpace::parse(&fs).unwrap();
        let view = FieldView::parse(&blob).unwrap();
        let lf = LikelihoodField::new(view, LikelihoodParams::new(0.9, 0.1, 0.05, 5.0).unwrap());
        let model = Tempered::new(lf, 4.0, 1).unwrap();
        let layout: BeamLayout<30> =
            BeamLayout::uniform(-1.5, 0.1, 30, 5.0, SensorMount::CENTERED).unwrap();
        let scan: Scan<30> = Scan::from_ranges(&ranges).unwrap();
        let mut store = Particles::<N>::new();
        let mut f = Mcl::new(&mut store, config()).unwrap();
        let mut rng = SplitMix64::new(seed);
        f.init_uniform(N, &free, &mut rng).unwrap();
        let before: Vec<Pose> = f.poses().to_vec();
        let w_before: Vec<f32> = f.weights().to_vec();
        let prepared = model.prepare(&layout, &scan);
        prop_assert_eq!(f.update_prepared(&prepared, Some(&free), &mut rng).err(), Some(MclError::EmptyScan));
        prop_assert_eq!(f.update_model(&model, &layout, &scan, Some(&free), &mut rng).err(), Some(MclError::EmptyScan));
        prop_assert_eq!(f.poses(), &before[..]);
        prop_assert_eq!(f.weights(), &w_before[..]);
    }

    #[test]
    fn free_space_parser_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..200)) {
        let _ = FreeSpace::parse(&bytes);
        let _ = FreeSpace::parse_prefix(&bytes);
    }
}

#[test]
fn zero_capacity_is_a_typed_error() {
    let mut store = Particles::<0>::new();
    assert_eq!(
        Mcl::new(&mut store, config()).err(),
        Some(MclError::ZeroParticles)
    );
}

#[test]
fn free_space_corruptions_are_typed_errors() {
    let (_, fs) = room();
    for n in 0..fs.len() {
        assert!(FreeSpace::parse(&fs[..n]).is_err());
    }
    for bit in 0..fs.len() * 8 {
        let mut b = fs.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        assert!(FreeSpace::parse(&b).is_err(), "bit {bit}");
    }
}

/// Poses with a NaN or infinite coordinate, each in one place.
fn nowhere() -> [Pose; 6] {
    [
        Pose::new(f32::NAN, 1.0, 0.0),
        Pose::new(1.0, f32::NAN, 0.0),
        Pose::new(1.0, 1.0, f32::NAN),
        Pose::new(f32::INFINITY, 1.0, 0.0),
        Pose::new(1.0, f32::NEG_INFINITY, 0.0),
        Pose::new(1.0, 1.0, f32::INFINITY),
    ]
}

#[test]
fn no_scorer_gives_a_nan_pose_a_finite_score() {
    use beamfield::SensorModel;
    use beamfield::{BeamFieldModel, BeamIntrinsics, BeamModel, MapCorrelation, RayCaster};
    let (blob, _) = room();
    let view = FieldView::parse(&blob).unwrap();
    let lf = LikelihoodField::new(view, LikelihoodParams::new(0.9, 0.1, 0.05, 5.0).unwrap());
    let layout: BeamLayout<30> =
        BeamLayout::uniform(-1.5, 0.1, 30, 5.0, SensorMount::CENTERED).unwrap();
    let scan: Scan<30> = Scan::from_ranges(&[0.7; 30]).unwrap();
    let prepared = lf.prepare(&layout, &scan);
    let tempered = Tempered::new(
        LikelihoodField::new(view, LikelihoodParams::new(0.9, 0.1, 0.05, 5.0).unwrap()),
        4.0,
        1,
    )
    .unwrap();
    let tempered_scan = tempered.prepare(&layout, &scan);
    let beam = BeamFieldModel::new(
        BeamModel::new(BeamIntrinsics::amcl_defaults(5.0).unwrap()),
        RayCaster::new(view).unwrap(),
    );
    let mut buf = vec![0u8; 16 * 16];
    let corr = MapCorrelation::new(view, 16, 16, &mut buf).unwrap();
    let inside = Pose::new(1.0, 1.0, 0.3);
    assert!(prepared.score(&inside).log_likelihood.is_finite());
    for p in nowhere() {
        // Before: the prepared scan scored (NaN, 1, 0) as a finite −161.5 (its f32 path read
        // the cells at a saturated index), and the other models did the same.
        assert!(prepared.score(&p).log_likelihood.is_nan(), "prepared {p:?}");
        assert!(
            tempered_scan.score(&p).log_likelihood.is_nan(),
            "tempered {p:?}"
        );
        assert!(
            lf.score(&layout, &scan, &p).log_likelihood.is_nan(),
            "field {p:?}"
        );
        assert!(
            tempered.score(&layout, &scan, &p).log_likelihood.is_nan(),
            "tempered model {p:?}"
        );
        assert!(
            beam.score(&layout, &scan, &p).log_likelihood.is_nan(),
            "beam {p:?}"
        );
        assert!(
            corr.score(&layout, &scan, &p).log_likelihood.is_nan(),
            "correlation {p:?}"
        );
    }
}

/// The case: a step of 1e20 m was accepted and one prediction made every particle NaN;
/// the next updates returned `Ok` with the estimate (0, 0, 0) and ESS 500.
#[test]
fn a_step_beyond_the_motion_model_is_refused() {
    assert_eq!(
        OdometryStep::new(0.0, 1e20, 0.0).err(),
        Some(beamfield::mcl::MotionError::StepTooLarge)
    );
    assert!(OdometryNoise::uniform(1e30).is_err());
}

/// Particles at a NaN or infinite pose never survive an update: with the field's own scorer
/// they are impossible, and the set is resampled from the finite ones.
#[test]
fn nan_particles_never_survive_an_update() {
    let (blob, fs) = room();
    let free = FreeSpace::parse(&fs).unwrap();
    let view = FieldView::parse(&blob).unwrap();
    let lf = LikelihoodField::new(view, LikelihoodParams::new(0.9, 0.1, 0.05, 5.0).unwrap());
    let model = Tempered::new(lf, 4.0, 1).unwrap();
    let layout: BeamLayout<30> =
        BeamLayout::uniform(-1.5, 0.1, 30, 5.0, SensorMount::CENTERED).unwrap();
    let scan: Scan<30> = Scan::from_ranges(&[0.7; 30]).unwrap();
    let prepared = model.prepare(&layout, &scan);
    let mut store = Particles::<N>::new();
    let mut f = Mcl::new(&mut store, config()).unwrap();
    let mut rng = SplitMix64::new(3);
    f.init_uniform(N, &free, &mut rng).unwrap();
    let bad = nowhere();
    let mut k = 0;
    // Half the set made NaN or infinite (move_particles refuses them, so through a copy).
    let mut store2 = Particles::<N>::new();
    let mut g = Mcl::new(&mut store2, config()).unwrap();
    g.init_gaussian(N, &Pose::new(1.0, 1.0, 0.0), 3e38, 0.1, &mut rng)
        .unwrap();
    let overflowed = g.poses().iter().filter(|p| !p.is_finite()).count();
    assert!(overflowed > 0, "σ 3e38 should overflow some particles");
    for _ in 0..3 {
        let u = g.update_prepared(&prepared, Some(&free), &mut rng).unwrap();
        assert!(u.estimate.pose.is_finite());
        assert!(
            g.poses().iter().all(Pose::is_finite),
            "a non-finite particle survived"
        );
    }
    // And a scorer that would give them a finite score is not asked.
    f.move_particles(|p| {
        k += 1;
        if k % 2 == 0 {
            bad[k % bad.len()]
        } else {
            *p
        }
    });
    assert!(f.poses().iter().all(Pose::is_finite));
    let mut store3 = Particles::<N>::new();
    let mut h = Mcl::new(&mut store3, config()).unwrap();
    h.init_gaussian(N, &Pose::new(1.0, 1.0, 0.0), 3e38, 0.1, &mut rng)
        .unwrap();
    h.update_with(|_| 0.0, None, &mut rng).unwrap();
    assert!(
        h.poses().iter().all(Pose::is_finite),
        "a closure's finite score kept one"
    );
}

/// Two particles at the usual resampling fraction 0.5: the ESS of a set is never below 1, and
/// the test was `ess < 0.5·2`, so the set was never resampled.
#[test]
fn two_particles_resample() {
    let mut store = Particles::<2>::new();
    let mut f = Mcl::new(&mut store, config()).unwrap();
    let mut rng = SplitMix64::new(4);
    f.init_gaussian(2, &Pose::new(1.0, 1.0, 0.0), 0.5, 0.1, &mut rng)
        .unwrap();
    let keep = f.poses()[0];
    let u = f
        .update_with(|p| if *p == keep { 0.0 } else { -30.0 }, None, &mut rng)
        .unwrap();
    assert!(u.resampled, "{u:?}");
    assert!(f.poses().iter().all(|p| *p == keep));
}

/// A pose far off the map (finite) put the correlation window's origin at `i64::MAX`, and its
/// row loop overflowed (a panic in a debug build).
#[test]
fn correlation_far_off_the_map_does_not_panic() {
    use beamfield::{MapCorrelation, SensorModel};
    let (blob, _) = room();
    let view = FieldView::parse(&blob).unwrap();
    let layout: BeamLayout<30> =
        BeamLayout::uniform(-1.5, 0.1, 30, 5.0, SensorMount::CENTERED).unwrap();
    let scan: Scan<30> = Scan::from_ranges(&[0.7; 30]).unwrap();
    let mut buf = vec![0u8; 16 * 16];
    let corr = MapCorrelation::new(view, 16, 16, &mut buf).unwrap();
    for p in [Pose::new(1e30, -1e30, 0.0), Pose::new(-3e38, 3e38, 1.0)] {
        assert!(!corr.score(&layout, &scan, &p).log_likelihood.is_nan());
    }
}
