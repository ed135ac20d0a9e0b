//! The grouped EM and the fit of `q` against the physical ring simulator
//! (`host_tests::sonar_sim`): crosstalk there is a neighbour's echo arriving first, not a draw
//! from the crosstalk model being fitted.

use beamfield::sonar::{fit_constant_q, fit_gaussian_q, GroupRate, GroupedWeightEm, NeighbourRate};
use beamfield::{BeamIntrinsics, BeamModel, Components};
use host_tests::sonar_sim::{
    simulate_cycle, spread_groups, PairStats, QTrue, Rng, Room, SimParams, SimRing,
};

const N: usize = 24;
const KS: [usize; 8] = [1, 2, 3, 4, 6, 8, 12, 24];

struct Run {
    /// (group size, z_rand learnt, readings, effective pairwise q of the simulator for that
    /// size, fraction of readings the simulator replaced by a neighbour's echo lying more than
    /// 3σ from the true range, the same fraction without the 3σ condition)
    per_k: Vec<(usize, f32, u64, f64, f64, f64)>,
    stats: PairStats,
}

fn params(q_true: QTrue) -> SimParams {
    SimParams {
        sigma_hit_m: 0.08,
        lambda_short_per_m: 4.0,
        p_short: 0.05,
        p_max: 0.08,
        p_rand: 0.03,
        q_true,
    }
}

fn ring() -> SimRing {
    SimRing {
        bearings_rad: (0..N).map(|i| -(i as f64) * 15f64.to_radians()).collect(),
        radius_m: 0.25,
        max_range_m: 5.0,
    }
}

fn run(q_true: QTrue, poses_per_k: usize, seed: u64) -> Run {
    let room = Room::test_room();
    let ring = ring();
    let p = params(q_true);
    let mut rng = Rng::new(seed);
    let mut stats = PairStats::default();
    // σ and λ fixed at the simulator's values; the weights start from a neutral guess.
    let base = BeamIntrinsics::new(0.7, 0.1, 0.1, 0.1, 0.08, 4.0, 5.0).unwrap();
    let model = BeamModel::new(base);
    let mut data: Vec<(usize, Components)> = Vec::new();
    let mut eff = Vec::new();
    for &k in &KS {
        let groups = spread_groups(N, k);
        let mut sk = PairStats::default();
        let (mut crossed, mut any, mut total) = (0u64, 0u64, 0u64);
        for _ in 0..poses_per_k {
            let pose = room.random_pose(&mut rng, 0.5);
            for b in simulate_cycle(&room, &ring, &groups, pose, &p, &mut rng, &mut sk) {
                total += 1;
                crossed += u64::from(b.distinct_crosstalk);
                any += u64::from(b.crosstalk);
                let c = model
                    .components(b.range_m as f32, b.z_star_m as f32)
                    .unwrap();
                data.push((b.cofired, c));
            }
        }
        let e = if k > 1 { sk.rate() } else { 0.0 };
        eff.push((e, crossed as f64 / total as f64, any as f64 / total as f64));
        stats.merge(&sk);
    }
    let mut em = GroupedWeightEm::<N>::new(base.weights());
    let mut last = f64::NEG_INFINITY;
    for pass in 0..500 {
        for (k, c) in &data {
            assert!(em.add(*k, c));
        }
        let r = em.finish_pass();
        // EM never decreases the likelihood (up to f32 rounding of the weights).
        assert!(r.log_likelihood >= last - 1e-6 * last.abs(), "pass {pass}");
        last = r.log_likelihood;
        if r.max_change < 1e-6 {
            break;
        }
    }
    let per_k = KS
        .iter()
        .zip(eff)
        .map(|(&k, (e, c, a))| (k, em.z_rand(k - 1).unwrap(), em.count(k - 1), e, c, a))
        .collect();
    Run { per_k, stats }
}

/// `c_k` as the EM sees it: the part of `z_rand(k)` above the lone transducer's, rescaled
/// (docs/models.md#sonar: `z_rand(k) = z_rand,0 + (1 − z_rand,0)·c_k`).
fn learnt_c(per_k: &[(usize, f32, u64, f64, f64, f64)]) -> Vec<f64> {
    let z0 = f64::from(per_k[0].1);
    per_k
        .iter()
        .map(|p| (f64::from(p.1) - z0) / (1.0 - z0))
        .collect()
}

/// The learnt `c_k` must lie between the simulator's rate of crosstalk readings that no model can
/// take for a hit (more than 3σ from the true range) and its rate of all crosstalk readings,
/// each widened by 0.02 (four standard errors of a rate near 0.5 over 9,600 readings is 0.02).
fn check_bracket(per_k: &[(usize, f32, u64, f64, f64, f64)]) {
    for (p, cl) in per_k.iter().zip(learnt_c(per_k)) {
        assert!(
            cl > p.4 - 0.02 && cl < p.5 + 0.02,
            "group size {}: c learnt {cl} outside [{}, {}]",
            p.0,
            p.4,
            p.5
        );
    }
}

fn print(r: &Run) {
    let c = learnt_c(&r.per_k);
    for ((k, z, n, e, cs, ca), cl) in r.per_k.iter().zip(&c) {
        println!(
            "group size {k:2}: z_rand {z:.4} ({n} readings), c learnt {cl:.4}, \
             c simulated {cs:.4} (any crosstalk {ca:.4}), sim pairwise q {e:.4}"
        );
    }
}

fn rates(per_k: &[(usize, f32, u64, f64, f64, f64)]) -> Vec<GroupRate> {
    per_k
        .iter()
        .map(|&(k, z, n, _, _, _)| GroupRate {
            k: (k - 1) as f32,
            z_rand: z,
            weight: n as f32,
        })
        .collect()
}

/// Constant detection probability 0.3 for every neighbour. The grouped EM must find `z_rand(k)`
/// strictly increasing, its `c_k` must match the fraction of readings the simulator actually
/// replaced by a neighbour's echo (see `check_bracket`), and the constant-q fit over small groups must match the
/// simulator's pairwise event rate.
#[test]
fn em_recovers_rising_z_rand_and_constant_q() {
    let r = run(QTrue::Constant(0.3), 400, 1);
    print(&r);
    let q_eff = r.stats.rate();
    for w in r.per_k.windows(2) {
        assert!(
            w[1].1 > w[0].1,
            "z_rand must increase with k: {:?}",
            r.per_k
        );
    }
    // The lone transducer's z_rand is the simulator's base rate 0.03 (± 4 standard errors).
    let z0 = f64::from(r.per_k[0].1);
    assert!(
        (z0 - 0.03).abs() < 4.0 * (0.03f64 * 0.97 / 9600.0).sqrt(),
        "{z0}"
    );
    check_bracket(&r.per_k);
    let all = fit_constant_q(&rates(&r.per_k)).unwrap();
    let small = fit_constant_q(&rates(&r.per_k[..4])).unwrap();
    println!("simulator pairwise q (pooled over all co-fired pairs) {q_eff:.4}");
    println!("constant fit, groups of 1-4: {small:?}");
    println!("constant fit, all groups:    {all:?}");
    assert!(
        (f64::from(small.q) - q_eff).abs() < 0.15 * q_eff,
        "q {} vs {q_eff}",
        small.q
    );
    assert!((f64::from(small.z_rand0) - 0.03).abs() < 0.01, "{small:?}");
}

/// Detection falling with separation, `q_true(Δβ) = 0.6·exp(−Δβ²/(2·(40°)²))`. Spread groups
/// add ever closer neighbours, so `z_rand(k)` rises (within noise where the added neighbours are
/// too far apart to be heard), `c_k` matches the simulator's, and the separation-dependent form
/// explains the per-group rates better than a constant.
#[test]
fn gaussian_q_from_separation() {
    let r = run(
        QTrue::Gaussian {
            q0: 0.6,
            width_rad: 40f64.to_radians(),
        },
        400,
        2,
    );
    print(&r);
    for d in (15..=180).step_by(15) {
        if let Some(q) = r.stats.rate_at(d) {
            println!("separation {d:3}°: sim pairwise q {q:.4}");
        }
    }
    let se = (0.03f64 * 0.97 / 9600.0).sqrt();
    for w in r.per_k.windows(2) {
        assert!(
            f64::from(w[1].1) > f64::from(w[0].1) - 4.0 * se,
            "z_rand must not fall with k: {:?}",
            r.per_k
        );
    }
    assert!(r.per_k[7].1 > r.per_k[0].1 + 0.3);
    check_bracket(&r.per_k);
    // One observation per group size: every transducer of a spread group has the same
    // neighbour separations.
    let neigh: Vec<Vec<(f32, f32)>> = KS
        .iter()
        .map(|&k| {
            (1..k)
                .map(|m| {
                    let d = (m * 360 / k) as f32;
                    let d = if d > 180.0 { 360.0 - d } else { d };
                    (d.to_radians(), 1.0)
                })
                .collect()
        })
        .collect();
    let obs: Vec<NeighbourRate<'_>> = r
        .per_k
        .iter()
        .zip(&neigh)
        .map(|(&(_, z, n, _, _, _), nb)| NeighbourRate {
            z_rand: z,
            weight: n as f32,
            neighbours: nb,
        })
        .collect();
    let fit = fit_gaussian_q(&obs).unwrap();
    let cfit = fit_constant_q(&rates(&r.per_k)).unwrap();
    println!(
        "gaussian fit: {fit:?}, width {:.1}°",
        fit.width_rad.to_degrees()
    );
    println!("constant fit on the same data: {cfit:?}");
    assert!(fit.mean_sq_residual < cfit.mean_sq_residual);
}

/// Pairs at a fixed separation `s·15°` (`s` ∈ {1, 2, 3, 4, 6, 12}): the co-fired count is 1
/// for every schedule, so EM is grouped by schedule, and each schedule's `c` measures `q` at one
/// separation. This is the design that can learn the lobe; the Gaussian fit must match the
/// simulator's pairwise rates at every separation.
#[test]
fn gaussian_lobe_from_pairs_at_fixed_separation() {
    let q_true = QTrue::Gaussian {
        q0: 0.6,
        width_rad: 40f64.to_radians(),
    };
    let room = Room::test_room();
    let ring = ring();
    let p = params(q_true);
    let mut rng = Rng::new(3);
    let base = BeamIntrinsics::new(0.7, 0.1, 0.1, 0.1, 0.08, 4.0, 5.0).unwrap();
    let model = BeamModel::new(base);
    let steps = [1usize, 2, 3, 4, 6, 12];
    // Group 0: fired alone (the base); group 1 + m: pairs at steps[m].
    let mut data: Vec<(usize, Components)> = Vec::new();
    let mut sim_q = Vec::new();
    let alone: Vec<Vec<usize>> = (0..N).map(|i| vec![i]).collect();
    let mut schedules = vec![(0usize, alone)];
    for (m, &s) in steps.iter().enumerate() {
        let pairs: Vec<Vec<usize>> = (0..N)
            .filter(|i| (i / s) % 2 == 0)
            .map(|i| vec![i, i + s])
            .collect();
        assert_eq!(pairs.len(), N / 2);
        schedules.push((m + 1, pairs));
    }
    for (g, groups) in &schedules {
        let mut st = PairStats::default();
        for _ in 0..300 {
            let pose = room.random_pose(&mut rng, 0.5);
            for b in simulate_cycle(&room, &ring, groups, pose, &p, &mut rng, &mut st) {
                data.push((
                    *g,
                    model
                        .components(b.range_m as f32, b.z_star_m as f32)
                        .unwrap(),
                ));
            }
        }
        if *g > 0 {
            sim_q.push((st.distinct_rate(), st.rate()));
        }
    }
    let mut em = GroupedWeightEm::<7>::new(base.weights());
    for _ in 0..500 {
        for (g, c) in &data {
            em.add(*g, c);
        }
        if em.finish_pass().max_change < 1e-6 {
            break;
        }
    }
    let neigh: Vec<[(f32, f32); 1]> = steps
        .iter()
        .map(|&s| [((s as f32) * 15f32.to_radians(), 1.0)])
        .collect();
    let mut obs = vec![NeighbourRate {
        z_rand: em.z_rand(0).unwrap(),
        weight: em.count(0) as f32,
        neighbours: &[],
    }];
    for (m, nb) in neigh.iter().enumerate() {
        obs.push(NeighbourRate {
            z_rand: em.z_rand(m + 1).unwrap(),
            weight: em.count(m + 1) as f32,
            neighbours: nb,
        });
    }
    let fit = fit_gaussian_q(&obs).unwrap();
    println!(
        "gaussian fit from pairs: {fit:?}, width {:.1}°",
        fit.width_rad.to_degrees()
    );
    let z0 = f64::from(em.z_rand(0).unwrap());
    for (m, &s) in steps.iter().enumerate() {
        let d = s as f64 * 15f64.to_radians();
        let fitted = f64::from(fit.q) * (-0.5 * (d / f64::from(fit.width_rad)).powi(2)).exp();
        let c = (f64::from(em.z_rand(m + 1).unwrap()) - z0) / (1.0 - z0);
        let (lo, hi) = sim_q[m];
        println!(
            "separation {:3}°: sim pairwise q {lo:.4} (> 3σ from truth) … {hi:.4} (all), \
             EM c {c:.4}, fitted q {fitted:.4}",
            s * 15,
        );
        // As in `check_bracket`: between the two simulated rates, widened by four standard
        // errors of a rate near 0.3 over 7,200 readings (0.02).
        assert!(
            fitted > lo - 0.02 && fitted < hi + 0.02,
            "{}°: fitted {fitted} outside [{lo}, {hi}]",
            s * 15
        );
    }
}
