//! The interleaved batch cast (`RayCaster::cast_dirs`) against the one-ray cast
//! (`RayCaster::cast_dir`): bit-identical ranges for every ray, at every lane count, on the
//! Intel race blob (every beam of many poses) and on random blobs (random rays, including
//! starts off the map, axis-aligned and exact-diagonal directions, and non-finite input). And
//! `BeamFieldModel::score` / `cast_layout`, which cast through the batch, against the same sums
//! and ranges computed one ray at a time in bearing order.

use host_workloads::intel_race;

use beamfield::field::{emit_blob, FieldHeader, FieldView};
use beamfield::{BeamFieldModel, Pose, RayCaster, SensorModel, Stride};
use host_tests::splitmix::{Draws, SplitMix64 as Rng};
use intel_race::N;

/// Casts `dirs` from `(x, y)` through the batch with 1, 2, 3, 4, 8 and 16 lanes and the default,
/// and one by one; asserts every range equal bit for bit. Returns how many rays it checked.
fn check_batch(
    rc: &RayCaster<'_>,
    x: f32,
    y: f32,
    dirs: &[[f32; 2]],
    max: f32,
    what: &str,
) -> usize {
    let want: Vec<f32> = dirs
        .iter()
        .map(|&[ux, uy]| rc.cast_dir(x, y, ux, uy, max))
        .collect();
    let mut got = vec![f32::NAN; dirs.len()];
    let compare = |lanes: &str, got: &[f32]| {
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(
                g.to_bits(),
                w.to_bits(),
                "{what}, {lanes} lanes, ray {i} {:?} from ({x}, {y}), max {max}: batch {g} vs one by one {w}",
                dirs[i]
            );
        }
    };
    rc.cast_dirs(x, y, dirs, max, &mut got);
    compare("default", &got);
    macro_rules! lanes {
        ($($k:literal),*) => {$(
            got.fill(f32::NAN);
            rc.cast_dirs_lanes::<$k>(x, y, dirs, max, &mut got);
            compare(stringify!($k), &got);
        )*};
    }
    lanes!(0, 1, 2, 3, 4, 8, 16);
    dirs.len()
}

#[test]
fn intel_every_beam_of_many_poses() {
    let data = intel_race::load();
    let view = FieldView::parse(&data.blob).unwrap();
    let max = data.max_range_m;
    let mut rng = Rng::new(41);
    let mut rays = 0;
    let mut hits = 0;
    for min_jump in [beamfield::raycast::JUMP_MIN_CELLS, 0.0, 8.0] {
        let rc = RayCaster::new(view).unwrap().with_min_jump_cells(min_jump);
        for (_, _, logged) in &data.scans {
            // The logged pose and perturbed ones around it (up to ±0.5 m, any heading).
            for j in 0..6 {
                let pose = if j == 0 {
                    *logged
                } else {
                    Pose {
                        x_m: logged.x_m + (rng.uniform() as f32 - 0.5),
                        y_m: logged.y_m + (rng.uniform() as f32 - 0.5),
                        theta_rad: ((rng.uniform() * 2.0 - 1.0) * std::f64::consts::PI) as f32,
                    }
                };
                let (s, c) = pose.theta_rad.sin_cos();
                let dirs: Vec<[f32; 2]> = data
                    .layout
                    .beams()
                    .iter()
                    .map(|b| [c * b.cos - s * b.sin, s * b.cos + c * b.sin])
                    .collect();
                rays += check_batch(&rc, pose.x_m, pose.y_m, &dirs, max, "intel");
                hits += dirs
                    .iter()
                    .filter(|&&[ux, uy]| rc.cast_dir(pose.x_m, pose.y_m, ux, uy, max) < max)
                    .count();
            }
        }
    }
    println!("intel: {rays} rays bit-identical through the batch, {hits} of them hit a wall");
    // The casts did hit walls (not all max range): the comparison is not a trivial one.
    assert!(hits > rays / 2, "{hits} of {rays}");
}

/// A random `w × h` blob: about `occupied` of the cells code 0, the rest random codes 1–255
/// (many of which jump).
fn random_blob(rng: &mut Rng, w: u32, h: u32, occupied: f64) -> Vec<u8> {
    let codes: Vec<u8> = (0..w * h)
        .map(|_| {
            if rng.uniform() < occupied {
                0
            } else {
                1 + (rng.uniform() * 254.99) as u8
            }
        })
        .collect();
    let header = FieldHeader::new(w, h, 0.05, -1.3, 0.7);
    let mut blob = vec![0u8; header.required_len().unwrap()];
    emit_blob(&header, &codes, &mut blob).unwrap();
    blob
}

#[test]
fn random_blobs_random_rays() {
    let mut rng = Rng::new(7);
    let mut rays = 0;
    for trial in 0..60 {
        let (w, h) = (
            1 + (rng.uniform() * 90.0) as u32,
            1 + (rng.uniform() * 90.0) as u32,
        );
        let occupied = [0.0, 0.002, 0.02, 0.2][trial % 4];
        let blob = random_blob(&mut rng, w, h, occupied);
        let view = FieldView::parse(&blob).unwrap();
        let rc = RayCaster::new(view)
            .unwrap()
            .with_min_jump_cells([2.0, 0.0, 5.0][trial % 3]);
        let (x0, y0) = (-1.3f32, 0.7f32);
        let (wm, hm) = (w as f32 * 0.05, h as f32 * 0.05);
        for _ in 0..40 {
            // Starts over the map and a margin around it; cell centres and corners too.
            let mut x = x0 - 0.5 + rng.uniform() as f32 * (wm + 1.0);
            let mut y = y0 - 0.5 + rng.uniform() as f32 * (hm + 1.0);
            match rng.next_u64() % 4 {
                0 => {
                    x = x0 + ((rng.uniform() * f64::from(w)) as u32 as f32 + 0.5) * 0.05;
                    y = y0 + ((rng.uniform() * f64::from(h)) as u32 as f32 + 0.5) * 0.05;
                }
                1 => {
                    x = x0 + (rng.uniform() * f64::from(w)) as u32 as f32 * 0.05;
                    y = y0 + (rng.uniform() * f64::from(h)) as u32 as f32 * 0.05;
                }
                _ => {}
            }
            let max = [0.0f32, 0.03, 1.0, 8.0, 81.83][(rng.next_u64() % 5) as usize];
            let n = (rng.next_u64() % 40) as usize;
            let dirs: Vec<[f32; 2]> = (0..n)
                .map(|_| match rng.next_u64() % 8 {
                    0 => [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]
                        [(rng.next_u64() % 4) as usize],
                    1 => {
                        let d = std::f32::consts::FRAC_1_SQRT_2;
                        [[d, d], [-d, d], [d, -d], [-d, -d]][(rng.next_u64() % 4) as usize]
                    }
                    2 => [
                        [f32::NAN, 0.0],
                        [1.0, f32::INFINITY],
                        [0.0, 0.0],
                        [1e-40, 1.0],
                    ][(rng.next_u64() % 4) as usize],
                    _ => {
                        let a = (rng.uniform() * 2.0 - 1.0) * std::f64::consts::PI;
                        [a.cos() as f32, a.sin() as f32]
                    }
                })
                .collect();
            rays += check_batch(&rc, x, y, &dirs, max, &format!("random blob {w}x{h}"));
        }
        // Non-finite starts: every ray gives the range limit, in the batch as well.
        let dirs = [[1.0f32, 0.0], [0.6, 0.8], [0.0, -1.0]];
        rays += check_batch(&rc, f32::NAN, 1.0, &dirs, 3.0, "NaN start");
        rays += check_batch(&rc, 0.0, f32::INFINITY, &dirs, 3.0, "infinite start");
    }
    println!("random blobs: {rays} rays bit-identical through the batch");
}

#[test]
fn batch_writes_what_fits_and_nothing_else() {
    let mut rng = Rng::new(3);
    let blob = random_blob(&mut rng, 40, 30, 0.05);
    let rc = RayCaster::new(FieldView::parse(&blob).unwrap()).unwrap();
    let dirs: Vec<[f32; 2]> = (0..20)
        .map(|i| {
            let a = i as f32 * 0.3;
            [a.cos(), a.sin()]
        })
        .collect();
    let (x, y) = (-0.3f32, 1.4f32);
    let want: Vec<f32> = dirs
        .iter()
        .map(|&[ux, uy]| rc.cast_dir(x, y, ux, uy, 5.0))
        .collect();
    // A shorter output receives the first rays.
    let mut short = [-1.0f32; 7];
    rc.cast_dirs(x, y, &dirs, 5.0, &mut short);
    assert_eq!(short.as_slice(), &want[..7]);
    // A longer one keeps its entries past the directions.
    let mut long = [-1.0f32; 25];
    rc.cast_dirs(x, y, &dirs, 5.0, &mut long);
    assert_eq!(&long[..20], want.as_slice());
    assert!(long[20..].iter().all(|&v| v == -1.0));
}

/// `score` and `cast_layout` (batched) equal the one-ray-at-a-time computation: the same z*
/// for every beam, and the same sum in the same order, bit for bit, at several strides.
#[test]
fn intel_scores_equal_one_by_one() {
    let data = intel_race::load();
    let (beam, _) = intel_race::models(&data);
    let layout = &data.layout;
    let max = data.max_range_m;
    let mut rng = Rng::new(99);
    let mut scored = 0u64;
    for (_, scan, logged) in &data.scans {
        for j in 0..3 {
            let pose = if j == 0 {
                *logged
            } else {
                Pose {
                    x_m: logged.x_m + 0.3 * (rng.uniform() as f32 - 0.5),
                    y_m: logged.y_m + 0.3 * (rng.uniform() as f32 - 0.5),
                    theta_rad: logged.theta_rad + (rng.uniform() as f32 - 0.5),
                }
            };
            for stride in [1usize, 2, 3, 7, 17, 200] {
                let st = Stride::new(stride).unwrap();
                // One by one, as `score_strided` did before the batch.
                let sensor = layout.mount().sensor_pose(&pose);
                let (s, c) = beamfield::math::sin_cos(sensor.theta_rad);
                let mut sum = 0.0f32;
                let (mut ok, mut invalid) = (0u16, 0u16);
                let mut want_z = [f32::NAN; N];
                for (k, (b, &z)) in layout
                    .beams()
                    .iter()
                    .zip(scan.ranges_m())
                    .enumerate()
                    .step_by(stride)
                {
                    let (ux, uy) = (c * b.cos - s * b.sin, s * b.cos + c * b.sin);
                    let z_star = beam.caster().cast_dir(sensor.x_m, sensor.y_m, ux, uy, max);
                    want_z[k] = z_star;
                    match beam.model().beam_log_likelihood(z, z_star) {
                        Some(l) => {
                            sum += l;
                            ok += 1;
                        }
                        None => invalid += 1,
                    }
                }
                let got = beam.score_strided(layout, scan, &pose, st);
                assert_eq!(
                    got.log_likelihood.to_bits(),
                    sum.to_bits(),
                    "pose {pose:?}, stride {stride}: {} vs {sum}",
                    got.log_likelihood
                );
                assert_eq!((got.scored, got.invalid), (ok, invalid));
                let mut got_z = [f32::NAN; N];
                beam.cast_layout(layout, &pose, st, &mut got_z);
                assert_eq!(got_z.map(f32::to_bits), want_z.map(f32::to_bits));
                // A shorter output slice: the strided beams that fit.
                let mut short = [f32::NAN; 50];
                beam.cast_layout(layout, &pose, st, &mut short);
                assert_eq!(short.map(f32::to_bits)[..], want_z.map(f32::to_bits)[..50]);
                scored += u64::from(ok);
            }
        }
    }
    assert!(scored > 0);
    println!("intel: {scored} beams scored bit-identically through the batch");
}

/// The same model type over a random blob, through `score`: whatever the blob, the batched
/// score is the one-ray-at-a-time one.
#[test]
fn random_blob_scores_equal_one_by_one() {
    let mut rng = Rng::new(5);
    let data = intel_race::load();
    let (beam, _) = intel_race::models(&data);
    let layout = &data.layout;
    for trial in 0..20 {
        let blob = random_blob(&mut rng, 60 + trial, 50, 0.01);
        let rc = RayCaster::new(FieldView::parse(&blob).unwrap()).unwrap();
        let model = BeamFieldModel::new(*beam.model(), rc);
        let (_, scan, _) = &data.scans[trial as usize];
        let pose = Pose {
            x_m: -1.3 + rng.uniform() as f32 * 3.0,
            y_m: 0.7 + rng.uniform() as f32 * 2.5,
            theta_rad: rng.uniform() as f32 * 6.0,
        };
        let sensor = layout.mount().sensor_pose(&pose);
        let (s, c) = beamfield::math::sin_cos(sensor.theta_rad);
        let mut sum = 0.0f32;
        for (b, &z) in layout.beams().iter().zip(scan.ranges_m()) {
            let (ux, uy) = (c * b.cos - s * b.sin, s * b.cos + c * b.sin);
            let z_star = rc.cast_dir(sensor.x_m, sensor.y_m, ux, uy, data.max_range_m);
            if let Some(l) = model.model().beam_log_likelihood(z, z_star) {
                sum += l;
            }
        }
        let got = model.score(layout, scan, &pose);
        assert_eq!(got.log_likelihood.to_bits(), sum.to_bits(), "trial {trial}");
    }
}
