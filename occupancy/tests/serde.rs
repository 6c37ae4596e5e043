//! With the `serde` feature, grids, scans and parameters round-trip through JSON, and
//! deserialising checks the same rules as the constructors.
#![cfg(feature = "serde")]

use haunts_occupancy::mapping::MapperParams;
use haunts_occupancy::{Grid, GridGeometry, LaserScan, MapLoadOptions, OccupancyGrid};
use nalgebra::Point2;

#[test]
fn values_round_trip_through_json() {
    let g = GridGeometry::new(0.05, Point2::new(-1.5, 2.0), 3, 2).unwrap();
    let map = OccupancyGrid::from_values(g, vec![-1, 0, 100, 50, 0, 0]).unwrap();
    let back: OccupancyGrid = serde_json::from_str(&serde_json::to_string(&map).unwrap()).unwrap();
    assert_eq!(back, map);
    let scan = LaserScan::new(1.5, -1.0, 0.5, 0.1, 8.0, vec![1.0, 2.0], vec![]).unwrap();
    let back: LaserScan = serde_json::from_str(&serde_json::to_string(&scan).unwrap()).unwrap();
    assert_eq!(back, scan);
    let params = MapperParams::default();
    let back: MapperParams =
        serde_json::from_str(&serde_json::to_string(&params).unwrap()).unwrap();
    assert_eq!(back, params);
    let options = MapLoadOptions::default();
    let back: MapLoadOptions =
        serde_json::from_str(&serde_json::to_string(&options).unwrap()).unwrap();
    assert_eq!(back, options);
}

#[test]
fn deserialising_checks_the_rules() {
    let bad_geometry = r#"{"resolution":-0.1,"origin":[0.0,0.0],"width":2,"height":2}"#;
    let e = serde_json::from_str::<GridGeometry>(bad_geometry).unwrap_err();
    assert!(e.to_string().contains("resolution"), "{e}");
    let short =
        r#"{"geometry":{"resolution":0.1,"origin":[0.0,0.0],"width":2,"height":2},"data":[1,2,3]}"#;
    let e = serde_json::from_str::<Grid<u8>>(short).unwrap_err();
    assert!(e.to_string().contains("4"), "{e}");
    let bad_value = r#"{"values":{"geometry":{"resolution":0.1,"origin":[0.0,0.0],"width":1,"height":1},"data":[101]},"thresholds":{"occupied_min":65,"free_max":25}}"#;
    assert!(serde_json::from_str::<OccupancyGrid>(bad_value).is_err());
    let bad_scan = r#"{"stamp":0.0,"angle_min":0.0,"angle_increment":0.0,"range_min":0.0,"range_max":1.0,"ranges":[]}"#;
    let e = serde_json::from_str::<LaserScan>(bad_scan).unwrap_err();
    assert!(e.to_string().contains("angle_increment"), "{e}");
}
