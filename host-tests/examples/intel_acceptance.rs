//! The localization acceptance over the whole Intel log against one map built from the whole
//! log (the demo's blob): for every scan, the best pose of a ±20 cm, ±5° grid (1 cm, 0.25°)
//! around its logged pose, and whether it lies within 5 cm and 1° of it.
//!
//! Run: `cargo run --release -p host-tests --example intel_acceptance [-- STEP]` (every STEP-th
//! scan; default 1 = all 910). Prints a line per scan that misses, then the counts overall, over
//! the 50 evenly spread scans the acceptance test picks, and per tenth of the log. Progress
//! goes to stderr.
//!
//! Model: the demo's (likelihood field, z_hit 0.95, z_rand 0.05, σ_hit 5.88 cm), scored through
//! a `PreparedScan`; the FLASER pose is the laser's pose (no mount offset).

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::{BeamLayout, SensorMount};
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::pose_grid::GridSpec;
use std::path::PathBuf;

const N: usize = 180;

fn main() {
    let step: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("STEP must be a positive integer"))
        .unwrap_or(1)
        .max(1);
    let blob_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../firmware/assets/intel.bin");
    let blob = std::fs::read(&blob_path).expect("firmware/assets/intel.bin");
    let log_path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&log_path, ReadOptions::default()).expect("the Intel log");
    let max_range = log.max_range.value_m().expect("max range");
    let lf = LikelihoodField::new(
        FieldView::parse(&blob).expect("blob"),
        LikelihoodParams::new(0.95, 0.05, 0.0588, max_range).expect("params"),
    );
    let layout: BeamLayout<N> = log
        .layout_with_mount(SensorMount::CENTERED)
        .expect("layout");
    let spec = GridSpec {
        half_xy_m: 0.20,
        step_xy_m: 0.01,
        half_theta_rad: 5f64.to_radians(),
        step_theta_rad: 0.25f64.to_radians(),
    };
    let total = log.scans.len();
    let picks: Vec<usize> = (0..50).map(|i| i * total / 50).collect();
    let (mut n, mut within) = (0usize, 0usize);
    let (mut n50, mut within50) = (0usize, 0usize);
    let mut tenth = [(0usize, 0usize); 10];
    let mut misses = Vec::new();
    for i in (0..total).step_by(step) {
        let s = &log.scans[i];
        let Ok(scan) = s.to_scan::<N>() else {
            eprintln!("scan {i}: not a {N}-beam scan, skipped");
            continue;
        };
        let prep = lf.prepare(&layout, &scan);
        let mut best = (f32::NEG_INFINITY, 0usize);
        for k in 0..spec.len() {
            let ll = prep.score(&spec.pose(&s.pose, k)).log_likelihood;
            if ll > best.0 {
                best = (ll, k);
            }
        }
        let (dx, dy, dt) = spec.offset(best.1);
        let d = (dx * dx + dy * dy).sqrt();
        let ok = d <= 0.05 + 1e-9 && dt.abs().to_degrees() <= 1.0 + 1e-9;
        n += 1;
        within += usize::from(ok);
        let t = &mut tenth[(i * 10 / total).min(9)];
        *t = (t.0 + 1, t.1 + usize::from(ok));
        if picks.contains(&i) {
            n50 += 1;
            within50 += usize::from(ok);
        }
        if !ok {
            misses.push(format!(
                "scan {i}: best {:.1} cm ({:+.1}, {:+.1}) {:+.2}°",
                d * 100.0,
                dx * 100.0,
                dy * 100.0,
                dt.to_degrees()
            ));
        }
        eprint!("\rintel_acceptance: scan {}/{total}", i + 1);
    }
    eprintln!();
    for m in &misses {
        println!("{m}");
    }
    println!(
        "grid ±20 cm / 1 cm, ±5° / 0.25° ({} poses); map of the whole log (firmware/assets/intel.bin)",
        spec.len()
    );
    println!("all scored scans: {within} of {n} within 5 cm and 1°");
    println!("the acceptance test's 50 evenly spread scans: {within50} of {n50} within");
    let per: Vec<String> = tenth.iter().map(|(a, b)| format!("{b}/{a}")).collect();
    println!("per tenth of the log: {}", per.join(" "));
}
