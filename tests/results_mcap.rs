//! The results MCAP: what is written reads back, with the values a viewer shows.

use haunts::bag::Bag;
use haunts::bag::msg::{OccupancyGrid as GridMsg, Path as PathMsg};
use haunts::occupancy::{Grid, GridGeometry};
use haunts::pipeline::results::ResultsMcap;
use haunts::tracking::io::trajectory::Trajectory;
use nalgebra::Point2;

#[test]
fn grids_paths_tracks_and_hours_read_back() {
    let dir = std::env::temp_dir().join(format!("haunts-results-mcap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("run.mcap");
    let g = GridGeometry::new(0.5, Point2::new(-1.0, 2.0), 4, 2).unwrap();
    // 0, a quarter, a half, the top, twice the top (clamped), NaN, −inf, a negative value.
    let values = vec![0.0, 0.25, 0.5, 1.0, 2.0, f64::NAN, f64::NEG_INFINITY, -1.0];
    let density = Grid::from_vec(g, values).unwrap();
    let mut mcap = ResultsMcap::create(&file).unwrap();
    for hour in 8..11 {
        let scaled = density.map(|v| v * f64::from(hour - 7));
        mcap.scalar("/hypertime", f64::from(hour) * 3600.0, &scaled, 3.0)
            .unwrap();
    }
    mcap.path(
        "/plan",
        5.0,
        &[
            Point2::new(0.0, 0.0),
            Point2::new(0.0, 1.0),
            Point2::new(-1.0, 1.0),
        ],
    )
    .unwrap();
    let tracks = vec![
        Trajectory {
            id: 1,
            samples: vec![(10.0, Point2::new(1.0, 1.0)), (10.1, Point2::new(1.1, 1.0))],
        },
        Trajectory {
            id: 2,
            samples: vec![],
        },
        Trajectory {
            id: 3,
            samples: vec![(12.0, Point2::new(0.0, 0.0))],
        },
    ];
    mcap.tracks("/tracks", &tracks).unwrap();
    mcap.finish().unwrap();

    let bag = Bag::open(&file).unwrap();
    let hours: Vec<(f64, GridMsg)> = bag
        .read::<GridMsg>("/hypertime")
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(
        hours
            .iter()
            .map(|h| (h.0 * 1e3).round() / 1e3)
            .collect::<Vec<_>>(),
        vec![28_800.0, 32_400.0, 36_000.0]
    );
    let first = &hours[0].1;
    assert_eq!(
        (first.info.width, first.info.height, first.info.resolution),
        (4, 2, 0.5)
    );
    assert_eq!(
        (first.info.origin.position.x, first.info.origin.position.y),
        (-1.0, 2.0)
    );
    assert_eq!(first.header.frame_id, "map");
    // With top = 3: v · 100 / 3, rounded, clamped to 0–100; non-finite values are unknown.
    assert_eq!(first.data, vec![0, 8, 17, 33, 67, -1, -1, 0]);
    assert_eq!(hours[2].1.data, vec![0, 25, 50, 100, 100, -1, -1, 0]);

    let plans: Vec<(f64, PathMsg)> = bag
        .read::<PathMsg>("/plan")
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(plans.len(), 1);
    let yaw = |q: &haunts::bag::msg::Quaternion| 2.0 * q.z.atan2(q.w);
    let headings: Vec<f64> = plans[0]
        .1
        .poses
        .iter()
        .map(|p| yaw(&p.pose.orientation))
        .collect();
    let expected = [
        std::f64::consts::FRAC_PI_2,
        std::f64::consts::PI,
        std::f64::consts::PI,
    ];
    for (h, e) in headings.iter().zip(expected) {
        assert!(
            (h.rem_euclid(std::f64::consts::TAU) - e).abs() < 1e-9,
            "{headings:?}"
        );
    }

    let read: Vec<(f64, PathMsg)> = bag
        .read::<PathMsg>("/tracks")
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(read.len(), 2, "the empty track is skipped");
    assert_eq!(read[0].0, 10.0);
    assert_eq!(read[0].1.poses.len(), 2);
    assert!((read[0].1.poses[1].pose.position.x - 1.1).abs() < 1e-12);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_negative_time_is_refused_by_name() {
    let file = std::env::temp_dir().join(format!("haunts-results-neg-{}.mcap", std::process::id()));
    let mut mcap = ResultsMcap::create(&file).unwrap();
    let err = mcap
        .path("/plan", -1.0, &[Point2::new(0.0, 0.0)])
        .unwrap_err();
    assert!(err.to_string().contains("-1"), "{err}");
    std::fs::remove_file(&file).ok();
}
