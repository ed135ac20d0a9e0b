//! Firing schedules for an ultrasonic ring (docs/models.md#sonar, docs/sonar.md): candidate
//! schedules compared by expected crosstalk and achievable scan rate, and one recommended. The
//! CLI is [`crate::cmd::sonar`]; ring files are read by [`crate::input::ring`].

use crate::input::ring::{LoadedRing, MAX_TRANSDUCERS};
use beamfield::sonar::{crosstalk_probability, Schedule};
use serde::Serialize;

/// One evaluated candidate schedule.
#[derive(Serialize, Debug, Clone)]
pub struct Candidate {
    /// Name of the pattern.
    pub name: String,
    /// Transducers fired together.
    pub group_size: usize,
    /// Number of groups per cycle.
    pub groups: usize,
    /// Interval between groups, ms.
    pub interval_ms: f64,
    /// Full-ring scans per second at this interval.
    pub scan_rate_hz: f64,
    /// True when the interval is the full echo lifetime (no lingering echoes, full range).
    pub full_range: bool,
    /// Range a transducer can still hear before the next group fires, metres.
    pub usable_range_m: f64,
    /// Mean crosstalk probability c_i over the ring.
    pub mean_crosstalk: f64,
    /// Largest c_i.
    pub max_crosstalk: f64,
    /// Mean z_rand,i = z_rand0 + (1 − z_rand0)·c_i.
    pub mean_z_rand: f64,
    /// Meets the requested rate.
    pub meets_rate: bool,
}

/// The result of `sonar schedule`.
#[derive(Serialize, Debug)]
pub struct ScheduleReport {
    /// Requested rate, Hz.
    pub requested_rate_hz: f64,
    /// Echo lifetime 2·max_range/c, ms.
    pub echo_lifetime_ms: f64,
    /// Every candidate evaluated.
    pub candidates: Vec<Candidate>,
    /// Index into `candidates` of the recommendation, if any meets the rate.
    pub recommended: Option<usize>,
    /// Why.
    pub reason: String,
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn pattern_name(n: usize, k: usize) -> String {
    if k == n {
        "all at once".into()
    } else if k == 1 {
        "one at a time".into()
    } else if k == 2 && n % 2 == 0 {
        "opposite pairs".into()
    } else if 2 * k == n {
        "alternating halves".into()
    } else {
        format!("groups of {k} spread ({:.0}° apart)", 360.0 / k as f64)
    }
}

fn evaluate(
    lr: &LoadedRing,
    groups: &[Vec<usize>],
    name: String,
    interval_s: f32,
    full_range: bool,
    rate: f64,
) -> Result<Candidate, String> {
    let ring = &lr.ring;
    let slices: Vec<&[usize]> = groups.iter().map(Vec::as_slice).collect();
    let s = Schedule::<MAX_TRANSDUCERS, MAX_TRANSDUCERS>::new(
        ring,
        &slices,
        interval_s,
        lr.speed_of_sound_m_per_s,
    )
    .map_err(|e| format!("schedule `{name}`: {e}"))?;
    let cs: Vec<f64> = (0..ring.len())
        .map(|i| f64::from(crosstalk_probability(ring, &s, &lr.model, i)))
        .collect();
    let mean = cs.iter().sum::<f64>() / cs.len() as f64;
    let max = cs.iter().copied().fold(0.0, f64::max);
    let z0 = f64::from(lr.z_rand0);
    let scan_rate = 1.0 / (groups.len() as f64 * f64::from(interval_s));
    Ok(Candidate {
        name,
        group_size: groups.first().map_or(0, Vec::len),
        groups: groups.len(),
        interval_ms: 1e3 * f64::from(interval_s),
        scan_rate_hz: scan_rate,
        full_range,
        usable_range_m: (0.5 * f64::from(lr.speed_of_sound_m_per_s) * f64::from(interval_s))
            .min(f64::from(ring.max_range_m())),
        mean_crosstalk: mean,
        max_crosstalk: max,
        mean_z_rand: z0 + (1.0 - z0) * mean,
        // The interval is an f32: allow its rounding (relative 1e-6).
        meets_rate: scan_rate >= rate * (1.0 - 1e-6),
    })
}

/// Evaluates every candidate and picks one. See `beamfield sonar schedule --help`.
///
/// # Errors
/// A message for a rate that is not finite and positive.
pub fn compare_schedules(lr: &LoadedRing, rate: f64) -> Result<ScheduleReport, String> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err("--rate must be finite and > 0".into());
    }
    let n = lr.ring.len();
    let lifetime = 2.0 * lr.ring.max_range_m() / lr.speed_of_sound_m_per_s;
    let mut candidates = Vec::new();
    let mut ks: Vec<usize> = (1..=n).filter(|k| n % k == 0).collect();
    ks.reverse();
    for k in ks {
        let step = n / k;
        let groups: Vec<Vec<usize>> = (0..step)
            .map(|g| (0..k).map(|m| g + m * step).collect())
            .collect();
        let name = pattern_name(n, k);
        let full = evaluate(lr, &groups, name.clone(), lifetime, true, rate)?;
        let slow = !full.meets_rate;
        candidates.push(full);
        if slow {
            // Squeezed to the rate, earlier groups' echoes linger; the firing order then matters.
            // Try every stride s coprime with T (group order g·s mod T) and keep the best.
            let t = groups.len();
            let squeezed = (1.0 / (rate * t as f64)) as f32;
            let mut best: Option<Candidate> = None;
            for stride in (1..t.max(2)).filter(|&s| gcd(s, t) == 1) {
                let order: Vec<Vec<usize>> =
                    (0..t).map(|g| groups[(g * stride) % t].clone()).collect();
                let label = if stride == 1 {
                    format!("{name}, squeezed")
                } else {
                    format!("{name}, squeezed, stride {stride}")
                };
                let c = evaluate(lr, &order, label, squeezed, false, rate)?;
                if best
                    .as_ref()
                    .is_none_or(|b| c.mean_crosstalk < b.mean_crosstalk - 1e-12)
                {
                    best = Some(c);
                }
            }
            candidates.extend(best);
        }
    }
    let best = |full: bool| {
        candidates
            .iter()
            .enumerate()
            .filter(|(_, c)| c.meets_rate && c.full_range == full)
            .min_by(|a, b| {
                a.1.mean_crosstalk
                    .total_cmp(&b.1.mean_crosstalk)
                    .then(b.1.scan_rate_hz.total_cmp(&a.1.scan_rate_hz))
            })
            .map(|(i, _)| i)
    };
    let (recommended, reason) = match (best(true), best(false)) {
        (Some(i), alt) => {
            let c = &candidates[i];
            let note = match alt.map(|j| &candidates[j]) {
                Some(a) if a.mean_crosstalk < c.mean_crosstalk => format!(
                    " If {:.2} m of range is enough, `{}` would cut the mean crosstalk to {:.3}.",
                    a.usable_range_m, a.name, a.mean_crosstalk
                ),
                _ => String::new(),
            };
            (
                Some(i),
                format!(
                    "`{}` has the least expected crosstalk (mean c = {:.3}, z_rand ≈ {:.3}) among \
                     the schedules that reach {rate} Hz with every group waiting the full echo \
                     lifetime ({:.1} ms), so no echo lingers and the full {} m range is usable; it \
                     scans at {:.1} Hz.",
                    c.name,
                    c.mean_crosstalk,
                    c.mean_z_rand,
                    1e3 * lifetime,
                    lr.ring.max_range_m(),
                    c.scan_rate_hz
                ) + &note,
            )
        }
        (None, Some(i)) => {
            let c = &candidates[i];
            (
                Some(i),
                format!(
                    "no schedule reaches {rate} Hz while waiting the full echo lifetime; `{}` \
                     has the least crosstalk when squeezed to the rate (mean c = {:.3}), but each \
                     group hears only {:.2} m before the next fires.",
                    c.name, c.mean_crosstalk, c.usable_range_m
                ),
            )
        }
        (None, None) => (None, "no candidate reaches the requested rate".into()),
    };
    Ok(ScheduleReport {
        requested_rate_hz: rate,
        echo_lifetime_ms: 1e3 * f64::from(lifetime),
        candidates,
        recommended,
        reason,
    })
}

/// Renders a report as text.
pub fn render_text(r: &ScheduleReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "echo lifetime {:.1} ms; requested {} Hz\n",
        r.echo_lifetime_ms, r.requested_rate_hz
    );
    let _ = writeln!(
        s,
        "{:<52} {:>6} {:>9} {:>9} {:>8} {:>7} {:>7} {:>8}  rate?",
        "schedule", "groups", "interval", "scan Hz", "range m", "mean c", "max c", "z_rand"
    );
    for (i, c) in r.candidates.iter().enumerate() {
        let mark = if Some(i) == r.recommended { "*" } else { " " };
        let _ = writeln!(
            s,
            "{mark}{:<51} {:>6} {:>6.1} ms {:>9.2} {:>8.2} {:>7.3} {:>7.3} {:>8.3}  {}",
            c.name,
            c.groups,
            c.interval_ms,
            c.scan_rate_hz,
            c.usable_range_m,
            c.mean_crosstalk,
            c.max_crosstalk,
            c.mean_z_rand,
            if c.meets_rate { "yes" } else { "no" }
        );
    }
    let _ = writeln!(
        s,
        "\nc is the probability that a reading is a neighbour's echo (docs/models.md#sonar): \
         1 − Π(1 − w·q(Δβ)) over co-fired and still-lingering transducers."
    );
    match r.recommended {
        Some(i) => {
            let _ = writeln!(s, "recommended: {} — {}", r.candidates[i].name, r.reason);
        }
        None => {
            let _ = writeln!(s, "no recommendation: {}", r.reason);
        }
    }
    s
}

impl std::fmt::Display for ScheduleReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&render_text(self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::ring::{load_ring, ring_from_spec, RingSpec};
    use std::path::Path;

    fn ring24() -> LoadedRing {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/examples/ring24.toml");
        load_ring(&p).unwrap()
    }

    #[test]
    fn example_ring_loads_with_the_readme_geometry() {
        let r = ring24();
        assert_eq!(r.ring.len(), 24);
        let b = r.ring.transducers()[6].bearing_rad.to_degrees();
        assert!((b + 90.0).abs() < 1e-4, "{b}");
        assert_eq!(r.ring.max_range_m(), 5.0);
    }

    #[test]
    fn all_at_once_matches_the_closed_form() {
        let r = ring24();
        let rep = compare_schedules(&r, 1.0).unwrap();
        let all = rep
            .candidates
            .iter()
            .find(|c| c.name == "all at once")
            .unwrap();
        // f64 closed form: 23 neighbours at 15°·m, q = 0.3·exp(−Δβ²/(2·45²)).
        let clean: f64 = (1..24)
            .map(|m| {
                let d = (15.0 * m as f64).min(360.0 - 15.0 * m as f64);
                1.0 - 0.3 * (-0.5 * (d / 45.0f64).powi(2)).exp()
            })
            .product();
        assert!((all.mean_crosstalk - (1.0 - clean)).abs() < 1e-5);
        assert!((all.scan_rate_hz - 343.0 / 10.0).abs() < 1e-3);
        let one = rep
            .candidates
            .iter()
            .find(|c| c.name == "one at a time")
            .unwrap();
        assert_eq!(one.mean_crosstalk, 0.0);
    }

    #[test]
    fn recommendation_is_the_least_crosstalk_that_meets_the_rate() {
        let r = ring24();
        for rate in [1.0, 5.0, 10.0, 20.0, 30.0, 100.0] {
            let rep = compare_schedules(&r, rate).unwrap();
            let i = rep.recommended.unwrap();
            let pick = &rep.candidates[i];
            assert!(pick.meets_rate, "{rate} Hz");
            let any_full = rep.candidates.iter().any(|c| c.meets_rate && c.full_range);
            assert_eq!(pick.full_range, any_full, "{rate} Hz");
            for c in rep
                .candidates
                .iter()
                .filter(|c| c.meets_rate && c.full_range == any_full)
            {
                assert!(
                    pick.mean_crosstalk <= c.mean_crosstalk,
                    "{rate} Hz: {} beats {}",
                    c.name,
                    pick.name
                );
            }
        }
        // 1 Hz: one at a time (no crosstalk at all) is fast enough.
        let rep = compare_schedules(&r, 1.0).unwrap();
        assert_eq!(rep.candidates[rep.recommended.unwrap()].mean_crosstalk, 0.0);
        assert!(compare_schedules(&r, 0.0).is_err());
        assert!(compare_schedules(&r, f64::NAN).is_err());
    }

    #[test]
    fn bad_ring_files_are_explained() {
        let base = r#"
            cone_half_angle_deg = 12.5
            max_range_m = 5.0
            [crosstalk]
            model = "constant"
            q0 = 0.1
        "#;
        let parse = |extra: &str| -> Result<LoadedRing, String> {
            let spec: RingSpec =
                toml::from_str(&format!("{extra}\n{base}")).map_err(|e| e.to_string())?;
            ring_from_spec(&spec)
        };
        assert!(parse("count = 4\nstep_deg = 90.0").is_ok());
        assert!(parse("bearings_deg = [0.0, 90.0]").is_ok());
        assert!(parse("count = 4").unwrap_err().contains("step_deg"));
        assert!(parse("count = 2\nstep_deg = 1.0\nbearings_deg = [0.0]")
            .unwrap_err()
            .contains("not both"));
        assert!(parse("count = 0\nstep_deg = 1.0")
            .unwrap_err()
            .contains("no transducer"));
        let bad_model = base.replace("constant", "cosine");
        let spec: RingSpec =
            toml::from_str(&format!("count = 2\nstep_deg = 1.0\n{bad_model}")).unwrap();
        assert!(ring_from_spec(&spec)
            .err()
            .unwrap()
            .contains("unknown model"));
        assert!(toml::from_str::<RingSpec>(&format!("colour = 1\n{base}")).is_err());
    }
}
