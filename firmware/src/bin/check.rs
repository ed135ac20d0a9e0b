//! On-target check: the chapter's worked example and the host-generated reference cases, run
//! with the crate's f32 code on the emulated Cortex-M4F. Prints every case and exits 1 when any
//! is off by more than its tolerance (or cannot be built), 0 otherwise.
//!
//! `cargo xtask qemu` builds and runs it.
#![no_std]
#![no_main]

use beamfield::{BeamIntrinsics, BeamModel, Scan};
use beamfield_firmware::reference_cases::CASES;
use beamfield_firmware::{exit, println, Fixed};
use cortex_m_rt::entry;
use panic_semihosting as _;

/// The worked example of docs/models.md#mixture (numbers checked by hand, pinned by the chapter's unit
/// test), with its allowed error: the printed values are rounded to 6 decimals (±5e-7) and the
/// f32 evaluation adds well under 5e-7.
const WORKED_TOL: f64 = 1e-6;

fn check_value(label: &str, got: f64, want: f64, tol: f64) -> bool {
    let err = if got > want { got - want } else { want - got };
    let ok = err <= tol;
    println!(
        "{} {}: got {} want {} |err| {} tol {}",
        if ok { "ok  " } else { "FAIL" },
        label,
        Fixed::new(got, 6),
        Fixed::new(want, 6),
        Fixed::new(err, 9),
        Fixed::new(tol, 9)
    );
    ok
}

fn worked_example() -> bool {
    println!("worked example (Thrun Table 6.1): Z=[4.5,5,3,7,10], z*=5, z_max=10, weights 0.25, sigma=1, lambda=0.5");
    let Ok(intr) = BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0) else {
        println!("FAIL worked-example intrinsics rejected");
        return false;
    };
    let model = BeamModel::new(intr);
    let mut ok = true;
    match model.components(4.5, 5.0) {
        Some(c) => {
            ok &= check_value("p_hit(4.5)", f64::from(c.hit), 0.352_066, WORKED_TOL);
            ok &= check_value("p_short(4.5)", f64::from(c.short), 0.057_412, WORKED_TOL);
            ok &= check_value("p_max(4.5)", f64::from(c.max), 0.0, 0.0);
            ok &= check_value("p_rand(4.5)", f64::from(c.rand), 0.1, WORKED_TOL);
        }
        None => {
            println!("FAIL z=4.5 classified invalid");
            ok = false;
        }
    }
    ok &= check_value(
        "mixture(4.5)",
        f64::from(model.beam_likelihood(4.5, 5.0)),
        0.127_369,
        WORKED_TOL,
    );
    match Scan::<5>::from_ranges(&[4.5, 5.0, 3.0, 7.0, 10.0]) {
        Ok(scan) => {
            let s = model.scan_log_likelihood(&scan, &[5.0; 5]);
            ok &= check_value(
                "mean log-likelihood of the 5 beams",
                f64::from(s.log_likelihood) / 5.0,
                -2.275_038,
                WORKED_TOL,
            );
            if s.scored != 5 || s.invalid != 0 || s.unpaired != 0 {
                println!(
                    "FAIL scan counts {} scored {} invalid {} unpaired",
                    s.scored, s.invalid, s.unpaired
                );
                ok = false;
            }
        }
        Err(_) => {
            println!("FAIL scan rejected");
            ok = false;
        }
    }
    ok
}

fn reference_cases() -> (usize, usize) {
    println!(
        "reference cases (host f64 reference, firmware/src/reference_cases.rs): {}",
        CASES.len()
    );
    let mut failed = 0;
    for (i, c) in CASES.iter().enumerate() {
        let [zh, zs, zm, zr, s, l, r] = c.intrinsics;
        let Ok(intr) = BeamIntrinsics::new(zh, zs, zm, zr, s, l, r) else {
            println!("FAIL case {:02} {}: intrinsics rejected", i, c.name);
            failed += 1;
            continue;
        };
        let got = BeamModel::new(intr).beam_log_likelihood(c.range_m, c.z_star_m);
        let z = Fixed::new(f64::from(c.range_m), 4);
        let zs = Fixed::new(f64::from(c.z_star_m), 4);
        match (got, c.expected) {
            (None, None) => println!(
                "ok   case {:02} {}: z={} z*={}: invalid, skipped",
                i, c.name, z, zs
            ),
            (Some(g), Some(e)) => {
                let g = f64::from(g);
                let err = if g > e { g - e } else { e - g };
                let ok = err <= c.tolerance;
                if !ok {
                    failed += 1;
                }
                println!(
                    "{} case {:02} {}: z={} z*={}: ln p got {} want {} |err| {} tol {}",
                    if ok { "ok  " } else { "FAIL" },
                    i,
                    c.name,
                    z,
                    zs,
                    Fixed::new(g, 6),
                    Fixed::new(e, 6),
                    Fixed::new(err, 9),
                    Fixed::new(c.tolerance, 9)
                );
            }
            (g, e) => {
                failed += 1;
                println!(
                    "FAIL case {:02} {}: z={} z*={}: got {}, want {}",
                    i,
                    c.name,
                    z,
                    zs,
                    if g.is_some() { "a value" } else { "invalid" },
                    if e.is_some() { "a value" } else { "invalid" }
                );
            }
        }
    }
    (CASES.len(), failed)
}

#[entry]
fn main() -> ! {
    let worked_ok = worked_example();
    let (n, failed) = reference_cases();
    let ok = worked_ok && failed == 0;
    println!(
        "check: worked example {}, reference cases {}/{} within tolerance: {}",
        if worked_ok { "ok" } else { "FAILED" },
        n - failed,
        n,
        if ok { "PASS" } else { "FAIL" }
    );
    exit(ok)
}
