//! The work budget of drawing a `map.xml` (its own test process: the budget is
//! process-wide): the cells of the poles' boxes, refused one unit over, drawn at it.
#![allow(clippy::unwrap_used, clippy::panic)]

use haunts_occupancy::{FREE, GridGeometry, OccupancyError, OccupancyGrid, budget};
use haunts_tracking::{TrackingError, parse_scene_map};

#[test]
fn poles_are_refused_just_over_the_work_budget_and_drawn_at_it() {
    let g = GridGeometry::new(0.5, nalgebra::Point2::origin(), 10, 10).unwrap();
    let mut map = OccupancyGrid::from_values(g, vec![FREE; g.len()]).unwrap();
    // Two poles of radius 1e300 (each box clipped to the 100 cells) and one off the grid.
    let scene = parse_scene_map(
        r#"<Circle x="0" y="0" radius="1e300"/><Circle x="3" y="3" radius="1e300"/>
           <Circle x="-50" y="0" radius="1"/>"#,
    )
    .unwrap();
    budget::set_max_work(199).unwrap();
    match scene.draw(&mut map) {
        Err(TrackingError::Occupancy {
            source: OccupancyError::WorkTooLarge { what, work, .. },
        }) => assert_eq!((what, work), ("map.xml poles", 200.0)),
        other => panic!("{other:?}"),
    }
    // Refused before drawing: nothing marked.
    assert!(map.occupied_mask().data().iter().all(|o| !o));
    budget::set_max_work(200).unwrap();
    assert_eq!(scene.draw(&mut map).unwrap(), 100);
    budget::set_max_work(budget::DEFAULT_MAX_WORK).unwrap();
}
