//! The real 24-sonar ring (UCI wall-following data, SCITOS G5): parsing, layout and range
//! statistics. Expected figures are the data README's, counted independently of this code.

use beamfield::Reading;
use host_tests::sonar_uci::{parse_uci, uci_layout, uci_ring, UciError, UCI_MAX_RANGE_M};

fn rows() -> Vec<host_tests::sonar_uci::UciRow> {
    let path = host_tests::data_dir().join("sonar_uci_wall_following/sensor_readings_24.data");
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    parse_uci(&bytes).unwrap()
}

#[test]
fn counts_and_extremes_match_the_readme() {
    let rows = rows();
    assert_eq!(rows.len(), 5_456);
    let all: Vec<f32> = rows
        .iter()
        .flat_map(|r| r.scan.ranges_m().to_vec())
        .collect();
    assert_eq!(all.len(), 130_944);
    assert_eq!(all.iter().filter(|&&z| z == 5.0).count(), 18_081);
    let above: Vec<f32> = all.iter().copied().filter(|&z| z > 5.0).collect();
    assert_eq!(above.len(), 48);
    assert!(above.iter().all(|&z| z <= 5.087 + 1e-6));
    let min = all.iter().copied().fold(f32::INFINITY, f32::min);
    assert!((min - 0.340).abs() < 1e-6, "{min}");
    // The reading policy classifies every value ≥ 5.0 as max-range, the rest as ranges.
    let max_range = all
        .iter()
        .filter(|&&z| Reading::classify(z, UCI_MAX_RANGE_M) == Reading::MaxRange)
        .count();
    assert_eq!(max_range, 18_081 + 48);
    let labels = [
        "Move-Forward",
        "Sharp-Right-Turn",
        "Slight-Right-Turn",
        "Slight-Left-Turn",
    ];
    let counts: Vec<usize> = labels
        .iter()
        .map(|l| rows.iter().filter(|r| r.label == *l).count())
        .collect();
    assert_eq!(counts, [2_205, 2_097, 826, 328]);
}

#[test]
fn layout_is_clockwise_and_the_wall_is_on_the_left() {
    let layout = uci_layout();
    let ring = uci_ring();
    let deg = std::f32::consts::PI / 180.0;
    // US7 right (−90°), US13 back, US19 left (+90° after wrapping).
    assert!((layout.beams()[6].bearing_rad + 90.0 * deg).abs() < 1e-5);
    assert!((layout.beams()[6].sin + 1.0).abs() < 1e-6);
    assert!((layout.beams()[18].sin - 1.0).abs() < 1e-6);
    assert!((layout.beams()[12].cos + 1.0).abs() < 1e-6);
    assert!((ring.separation_rad(0, 23) - 15.0 * deg).abs() < 1e-5);
    let rows = rows();
    // Per-sensor statistics over readings below max range.
    let mut stats = Vec::new();
    for k in 0..24 {
        let v: Vec<f32> = rows
            .iter()
            .map(|r| r.scan.ranges_m()[k])
            .filter(|&z| matches!(Reading::classify(z, UCI_MAX_RANGE_M), Reading::Range(_)))
            .collect();
        let min = v.iter().copied().fold(f32::INFINITY, f32::min);
        let mean = v.iter().map(|&z| f64::from(z)).sum::<f64>() / v.len() as f64;
        let max_frac = 1.0 - v.len() as f64 / rows.len() as f64;
        println!(
            "US{:<2} bearing {:7.1}°: min {min:.3} m, mean {mean:.3} m, max-range {:.1} %",
            k + 1,
            beamfield::wrap_angle(layout.beams()[k].bearing_rad) / deg,
            100.0 * max_frac
        );
        stats.push((layout.beams()[k].sin, min, mean));
    }
    let side = |left: bool| -> (f32, f64) {
        let s: Vec<_> = stats
            .iter()
            .filter(|(sin, _, _)| if left { *sin > 0.1 } else { *sin < -0.1 })
            .collect();
        let min = s.iter().map(|x| x.1).fold(f32::INFINITY, f32::min);
        let mean = s.iter().map(|x| x.2).sum::<f64>() / s.len() as f64;
        (min, mean)
    };
    let (lmin, lmean) = side(true);
    let (rmin, rmean) = side(false);
    println!("left: min {lmin:.3} m, mean {lmean:.3} m; right: min {rmin:.3} m, mean {rmean:.3} m");
    assert!(lmean < rmean);
    // README: US16–US24 reach 0.34–0.42 m (two decimals: below 0.425); US5–US7 never read below
    // 1.1 m.
    for (k, st) in stats.iter().enumerate().take(24).skip(15) {
        assert!(st.1 < 0.425, "US{} min {}", k + 1, st.1);
    }
    for (k, st) in stats.iter().enumerate().take(7).skip(4) {
        assert!(st.1 >= 1.1, "US{} min {}", k + 1, st.1);
    }
}

#[test]
fn malformed_lines_are_rejected_with_their_line_number() {
    let good = "1,".repeat(24) + "Move-Forward\r\n";
    assert_eq!(parse_uci(good.as_bytes()).unwrap().len(), 1);
    let lf = good.replace("\r\n", "\n");
    assert_eq!(
        parse_uci((good.clone() + &lf).as_bytes()).err(),
        Some(UciError::NotCrlf(2))
    );
    let short = "1,".repeat(23) + "x\r\n";
    assert_eq!(
        parse_uci(short.as_bytes()).err(),
        Some(UciError::FieldCount(1, 24))
    );
    let nan = "a,".to_string() + &"1,".repeat(23) + "x\r\n";
    assert_eq!(
        parse_uci(nan.as_bytes()).err(),
        Some(UciError::BadNumber(1))
    );
}
