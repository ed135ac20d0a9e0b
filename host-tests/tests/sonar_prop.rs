//! Property tests: for every valid schedule, every beam's weights stay on the simplex, a beam
//! fired alone keeps the base weights exactly, and `c_i` matches an f64 brute force written from
//! the definitions in docs/models.md#sonar (firing times, echo lifetime, product over neighbours).

use beamfield::sonar::{CrosstalkModel, Ring, Schedule, SonarModel};
use beamfield::BeamIntrinsics;
use host_tests::sonar_sim::reference_c;
use proptest::prelude::*;

const M: usize = 24;
const G: usize = 24;

/// A random valid schedule: a permutation of the ring cut into groups, some transducers left out.
fn schedule_parts() -> impl Strategy<Value = (usize, Vec<Vec<usize>>, f32)> {
    (1usize..=M)
        .prop_flat_map(|n| {
            (
                Just(n),
                Just((0..n).collect::<Vec<_>>()).prop_shuffle(),
                proptest::collection::vec(any::<bool>(), n),
                proptest::collection::vec(any::<bool>(), n),
                0.0f32..0.08,
            )
        })
        .prop_map(|(n, perm, cut, keep, interval)| {
            let mut groups: Vec<Vec<usize>> = vec![];
            let mut cur = vec![];
            for (k, &i) in perm.iter().enumerate() {
                if keep[k] || k == 0 {
                    cur.push(i);
                }
                if cut[k] && !cur.is_empty() {
                    groups.push(std::mem::take(&mut cur));
                }
            }
            if !cur.is_empty() {
                groups.push(cur);
            }
            (n, groups, interval)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn weights_stay_on_the_simplex(
        (n, groups, interval) in schedule_parts(),
        raw in proptest::array::uniform4(0.001f32..1.0),
        q0 in 0.0f32..=1.0,
        width_deg in 1.0f32..180.0,
        gaussian in any::<bool>(),
    ) {
        let ring = Ring::<M>::uniform(n, 0.3, -15f32.to_radians(), 0.25, 0.2, 5.0).unwrap();
        let slices: Vec<&[usize]> = groups.iter().map(|g| g.as_slice()).collect();
        let sched = Schedule::<M, G>::new(&ring, &slices, interval, 343.0).unwrap();
        let s: f32 = raw.iter().sum();
        let w = raw.map(|x| x / s);
        let base = BeamIntrinsics::new(w[0], w[1], w[2], 1.0 - w[0] - w[1] - w[2], 0.1, 1.0, 5.0).unwrap();
        let model = if gaussian {
            CrosstalkModel::gaussian(q0, width_deg.to_radians()).unwrap()
        } else {
            CrosstalkModel::constant(q0).unwrap()
        };
        let sonar = SonarModel::new(&ring, &sched, &base, &model).unwrap();
        let bearings: Vec<f64> = ring.transducers().iter().map(|t| f64::from(t.bearing_rad)).collect();
        let q = |d: f64| if gaussian {
            f64::from(q0) * (-0.5 * (d / f64::from(width_deg).to_radians()).powi(2)).exp()
        } else {
            f64::from(q0)
        };
        for i in 0..n {
            let bw = sonar.beam_model(i).unwrap().intrinsics().weights();
            let sum: f32 = bw.iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-5, "beam {i}: {bw:?}");
            prop_assert!(bw.iter().all(|&x| (0.0..=1.0).contains(&x)), "beam {i}: {bw:?}");
            prop_assert!(bw[3] >= base.z_rand(), "beam {i}");
            let c = sonar.crosstalk()[i];
            let want = reference_c(&bearings, &groups, f64::from(interval),
                f64::from(sched.echo_lifetime_s()), &q, i);
            prop_assert!((f64::from(c) - want).abs() < 2e-5, "beam {i}: c {c} vs {want}");
            if sched.cofired_count(i) == 0 {
                prop_assert_eq!(bw, base.weights());
            }
        }
    }
}
