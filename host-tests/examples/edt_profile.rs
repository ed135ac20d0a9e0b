//! Runs the exact transform of the `field` bench's grids a given number of times, for
//! instruction counting under `valgrind --tool=cachegrind` (no timing of its own).
//!
//! `cargo build --profile profiling -p host-tests --example edt_profile`, then
//! `valgrind --tool=cachegrind target/profiling/examples/edt_profile 400 20` (or `willow 5`);
//! the same with a third argument `skip` counts everything but the transform.

use beamfield::field::{edt_scratch_len, squared_edt, EdtScratch, EDT_INFINITY};
use beamfield_tools::blob::edt_seeds;
use beamfield_tools::input::map::load_map;
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map_or("400", String::as_str);
    let reps: usize = args.get(2).map_or(10, |s| s.parse().unwrap());
    // A third argument `skip` runs everything but the transform (the harness's own count).
    let skip = args.get(3).is_some_and(|a| a == "skip");
    let (seeds, w, h) = if which == "willow" {
        let m = load_map(&host_tests::data_dir().join("map_willow_garage/willow-full-0.05.yaml"))
            .unwrap();
        let seeds = edt_seeds(&m);
        (seeds, m.width as usize, m.height as usize)
    } else {
        // The bench's 400 × 400 grid: the same generator, seed and 3 % density.
        let mut s = 11u64;
        let seeds: Vec<u32> = (0..400 * 400)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                if ((s >> 11) as f64 / (1u64 << 53) as f64) < 0.03 {
                    0
                } else {
                    EDT_INFINITY
                }
            })
            .collect();
        (seeds, 400, 400)
    };
    let n = edt_scratch_len(w, h);
    let (mut a, mut b, mut c) = (vec![0u32; n], vec![0i64; n], vec![0u32; n]);
    let mut grid = seeds.clone();
    let mut acc = 0u64;
    for _ in 0..reps {
        grid.copy_from_slice(&seeds);
        if skip {
            acc = acc.wrapping_add(black_box(&grid).iter().map(|&v| u64::from(v)).sum::<u64>());
            continue;
        }
        squared_edt(
            black_box(&mut grid),
            w,
            h,
            EdtScratch {
                sites: &mut a,
                bounds: &mut b,
                heights: &mut c,
            },
        )
        .unwrap();
        acc = acc.wrapping_add(grid.iter().map(|&v| u64::from(v)).sum::<u64>());
    }
    println!("{which} {w}x{h} reps {reps} checksum {acc}");
}
