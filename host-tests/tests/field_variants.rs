//! Map variants (`field build --variant`): the field of the union of the maps' occupied cells
//! is, cell by cell, the minimum of the fields built from each map alone (each by its own
//! transform), and a variant of another geometry is a typed error.

use beamfield::field::FieldView;
use beamfield_tools::field_cmd::{build_blob, union_map, FieldCmdError};
use beamfield_tools::map::{load_map, Occupancy};
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
        Err(FieldCmdError::VariantMismatch(p)) if p.as_path() == std::path::Path::new("other.yaml")
    ));
}
