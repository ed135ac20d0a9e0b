//! Map variants (`field build --variant`): the field of the union of the maps' occupied cells
//! is, cell by cell, the minimum of the fields built from each map alone (each by its own
//! transform), and a variant of another geometry is a typed error.

use beamfield::field::FieldView;
use beamfield_tools::blob::{build_blob, union_map, FieldError};
use beamfield_tools::input::map::{load_map, Occupancy};
use std::path::PathBuf;

#[test]
fn union_field_is_the_per_cell_minimum() {
    let map = load_map(&host_tests::data_dir().join("map_turtlebot3_world/map.yaml")).unwrap();
    // A "door": a 1 m wall of free cells closed, in a variant of the map.
    let mut door = map.clone();
    let w = map.width as usize;
    let mut closed = 0;
    for iy in 180..200 {
        let i = iy * w + 200;
        if door.cells[i] != Occupancy::Occupied {
            door.cells[i] = Occupancy::Occupied;
            closed += 1;
        }
    }
    assert!(closed > 10, "the door must close free cells ({closed})");
    let union = union_map(&map, &[(PathBuf::from("door.yaml"), door.clone())]).unwrap();
    let blobs: Vec<Vec<u8>> = [&map, &door, &union]
        .iter()
        .map(|m| build_blob(m, 2.0).unwrap())
        .collect();
    let views: Vec<FieldView<'_>> = blobs.iter().map(|b| FieldView::parse(b).unwrap()).collect();
    let mut lower = 0;
    for (i, &u) in views[2].codes().iter().enumerate() {
        let (a, b) = (views[0].codes()[i], views[1].codes()[i]);
        assert_eq!(u, a.min(b), "cell {i}");
        lower += usize::from(b < a);
    }
    // The door changes the field around it.
    assert!(
        lower > 100,
        "{lower} cells nearer a wall with the door closed"
    );

    let mut other = map.clone();
    other.width += 1;
    assert!(matches!(
        union_map(&map, &[(PathBuf::from("other.yaml"), other)]),
        Err(FieldError::VariantMismatch(p)) if p.as_path() == std::path::Path::new("other.yaml")
    ));
}

/// `field score-variants` on the Intel map built from the log, with two doors marked by hand
/// in scan 50's view: the wall where beams 80–95 of scan 50 end is opened (its occupied cells
/// within 0.5 m of those endpoints made free, 357 cells) in one variant, and a stretch of wall farther than 4 m from
/// every endpoint of the scan is opened in another. The scan saw the first wall, so the map
/// with it closed must be preferred; the second door changes no code within `d_max` (2 m) of
/// any endpoint, so its variant scores exactly as the original and no variant is preferred.
#[test]
fn score_variants_names_the_closed_door_on_the_intel_map() {
    use beamfield::field::LikelihoodParams;
    use beamfield::{BeamLayout, Scan, SensorMount};
    use beamfield_tools::beam_fit::map_from_log;
    use beamfield_tools::blob::variants::{score_variants, ScoreVariantsError};
    use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};

    let log = CarmenLog::read_path(
        &host_tests::data_dir().join("laser_intel_lab/intel-corrected.log"),
        ReadOptions::default(),
    )
    .unwrap();
    let max_range = log.max_range.value_m().unwrap();
    let map = map_from_log(&log, max_range).unwrap();
    let layout: BeamLayout<180> = log.layout_with_mount(SensorMount::CENTERED).unwrap();
    let s = &log.scans[50];
    let scan: Scan<180> = s.to_scan().unwrap();
    let pose = s.pose;
    let (w, res) = (map.width as usize, map.resolution_m);
    let endpoints: Vec<(f64, f64)> = layout
        .beams()
        .iter()
        .zip(&s.ranges_m)
        .filter(|(_, &r)| r > 0.0 && r < max_range)
        .map(|(b, &r)| {
            let a = f64::from(pose.theta_rad + b.bearing_rad);
            (
                f64::from(pose.x_m) + f64::from(r) * a.cos(),
                f64::from(pose.y_m) + f64::from(r) * a.sin(),
            )
        })
        .collect();
    // Door 1: occupied cells within 0.5 m of the endpoints of beams 80–95.
    let seen: Vec<(f64, f64)> = (80..96)
        .filter(|&i| s.ranges_m[i] > 0.0 && s.ranges_m[i] < max_range)
        .map(|i| {
            let a = f64::from(pose.theta_rad + layout.beams()[i].bearing_rad);
            let r = f64::from(s.ranges_m[i]);
            (
                f64::from(pose.x_m) + r * a.cos(),
                f64::from(pose.y_m) + r * a.sin(),
            )
        })
        .collect();
    assert!(seen.len() >= 12, "beams 80–95 mostly hit something");
    let centre = |ix: usize, iy: usize| {
        (
            map.origin_x_m + (ix as f64 + 0.5) * res,
            map.origin_y_m + (iy as f64 + 0.5) * res,
        )
    };
    let near = |p: (f64, f64), q: &(f64, f64), d: f64| (p.0 - q.0).hypot(p.1 - q.1) <= d;
    let mut open_seen = map.clone();
    let mut opened = 0;
    for (i, c) in open_seen.cells.iter_mut().enumerate() {
        let p = centre(i % w, i / w);
        if *c == Occupancy::Occupied && seen.iter().any(|q| near(p, q, 0.5)) {
            *c = Occupancy::Free;
            opened += 1;
        }
    }
    assert!(opened >= 10, "door 1 opens {opened} cells");
    // Door 2: up to 20 occupied cells farther than 4 m from every endpoint and from the pose.
    let mut open_far = map.clone();
    let mut far = 0;
    for i in 0..open_far.cells.len() {
        let p = centre(i % w, i / w);
        let away = !endpoints.iter().any(|q| near(p, q, 4.0))
            && !near(p, &(f64::from(pose.x_m), f64::from(pose.y_m)), 4.0);
        if far < 20 && open_far.cells[i] == Occupancy::Occupied && away {
            open_far.cells[i] = Occupancy::Free;
            far += 1;
        }
    }
    assert_eq!(far, 20);

    let params = LikelihoodParams::new(0.95, 0.05, 0.0588, max_range).unwrap();
    let named = |v: Vec<(&str, &beamfield_tools::input::map::OccupancyMap)>| {
        v.into_iter()
            .map(|(n, m)| (n.to_string(), m.clone()))
            .collect::<Vec<_>>()
    };
    let v = score_variants(
        &named(vec![("open", &open_seen), ("closed", &map)]),
        2.0,
        params,
        &layout,
        &scan,
        &pose,
        1.0,
    )
    .unwrap();
    assert_eq!(v.preferred, Some(1), "{v:?}");
    assert!(v.scores[1].log_likelihood > v.scores[0].log_likelihood + 1.0);
    eprintln!("door seen by the scan: {v:?} ({opened} cells opened)");

    let v = score_variants(
        &named(vec![("far door open", &open_far), ("closed", &map)]),
        2.0,
        params,
        &layout,
        &scan,
        &pose,
        1.0,
    )
    .unwrap();
    assert_eq!(v.preferred, None, "{v:?}");
    assert_eq!(
        v.scores[0].log_likelihood.to_bits(),
        v.scores[1].log_likelihood.to_bits()
    );

    assert!(matches!(
        score_variants(
            &named(vec![("closed", &map)]),
            2.0,
            params,
            &layout,
            &scan,
            &pose,
            1.0
        ),
        Err(ScoreVariantsError::TooFewVariants(1))
    ));
}
