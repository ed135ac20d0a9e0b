//! Tests of the map_server reader: pixel classification and the YAML keys.

use super::*;

#[test]
fn pixel_rule_table() {
    // (grey, negate, expected) with the usual 0.65 / 0.196 thresholds.
    let cases = [
        (0.0, false, Occupancy::Occupied),
        (89.0, false, Occupancy::Occupied),
        (90.0, false, Occupancy::Unknown),
        (205.0, false, Occupancy::Unknown),
        (206.0, false, Occupancy::Free),
        (254.0, false, Occupancy::Free),
        (255.0, true, Occupancy::Occupied),
        (0.0, true, Occupancy::Free),
    ];
    for (g, n, want) in cases {
        assert_eq!(
            classify_pixel(g, n, 0.65, 0.196),
            want,
            "grey {g} negate {n}"
        );
    }
}
