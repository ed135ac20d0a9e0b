//! The device's ray cast through the blob ([`beamfield::RayCaster`]) against the host's exact
//! f64 grid traversal (`ray_cast_grid`) on the same occupancy grid: TurtleBot3, Willow Garage
//! and the Intel lab map built from its log. Prints the error distribution.

use beamfield::field::{FieldView, DEFAULT_MAX_DIST_M};
use beamfield::RayCaster;
use beamfield_tools::beam_fit::map_from_log;
use beamfield_tools::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::field_cmd::build_blob;
use beamfield_tools::map::{load_map, OccupancyMap};
use beamfield_tools::mapping::ray_cast_grid;

/// A small deterministic generator (splitmix64), independent of the code under test.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Casts `rays` random rays (start uniform over the map's rectangle, angle uniform, range
/// limit 12 m) both ways; returns the absolute errors in cells, sorted.
fn errors_in_cells(map: &OccupancyMap, rays: usize, seed: u64) -> Vec<f64> {
    let blob = build_blob(map, DEFAULT_MAX_DIST_M).unwrap();
    let caster = RayCaster::new(FieldView::parse(&blob).unwrap()).unwrap();
    let mut rng = Rng(seed);
    let res = map.resolution_m;
    let (w, h) = (f64::from(map.width) * res, f64::from(map.height) * res);
    let max_range = 12.0;
    let mut errs = Vec::with_capacity(rays);
    for _ in 0..rays {
        // The start on the f32 lattice, so both casts start at the same point.
        let x = (map.origin_x_m + rng.next() * w) as f32;
        let y = (map.origin_y_m + rng.next() * h) as f32;
        let a = ((rng.next() * 2.0 - 1.0) * std::f64::consts::PI) as f32;
        let want = ray_cast_grid(map, f64::from(x), f64::from(y), f64::from(a), max_range);
        let got = caster.cast(x, y, a, max_range as f32);
        errs.push(f64::from((got - want).abs()) / res);
    }
    errs.sort_by(f64::total_cmp);
    errs
}

fn check(name: &str, map: &OccupancyMap, rays: usize, seed: u64) {
    let e = errors_in_cells(map, rays, seed);
    let q = |p: f64| e[((e.len() - 1) as f64 * p) as usize];
    let over = e.iter().filter(|&&x| x > 1.0).count();
    let exact = e.iter().filter(|&&x| x < 1e-3).count();
    println!(
        "{name}: {rays} rays, errors in cells: median {:.2e}, p99 {:.2e}, p99.9 {:.2e}, max {:.3}; \
         {exact} within 1e-3 cell, {over} over one cell",
        q(0.5),
        q(0.99),
        q(0.999),
        e[e.len() - 1]
    );
    assert_eq!(over, 0, "{name}: {over} rays off by more than one cell");
}

#[test]
fn turtlebot3_within_one_cell() {
    let m = load_map(&host_tests::data_dir().join("map_turtlebot3_world/map.yaml")).unwrap();
    check("turtlebot3", &m, 20_000, 1);
}

#[test]
fn willow_within_one_cell() {
    let m =
        load_map(&host_tests::data_dir().join("map_willow_garage/willow-full-0.05.yaml")).unwrap();
    check("willow", &m, 20_000, 2);
}

#[test]
fn intel_within_one_cell() {
    let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&path, ReadOptions::default()).unwrap();
    let m = map_from_log(&log, log.max_range.value_m().unwrap()).unwrap();
    check("intel", &m, 20_000, 3);
}
