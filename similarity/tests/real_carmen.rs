//! Maps built from the real CARMEN logs of two buildings (Intel lab, MIT CSAIL): the
//! similarity matrix and both clusterings group the maps by building.

mod common;

use haunts_occupancy::carmen::{CarmenLog, CarmenOptions, read_carmen};
use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_occupancy::{GridGeometry, OccupancyGrid, Pose2};
use haunts_similarity::{
    ClusterParams, DifferenceParams, LayoutThreshold, agreement, common_geometry,
    complete_linkage_layouts, greedy_layouts, resample, similarity_matrix,
};

/// `days` maps of one log, map `k` from scans `k, k + days, k + 2·days, …`: each "day" sees
/// the whole building, as the seed's robot did on its daily tour.
fn daily_maps(log: &CarmenLog, days: usize) -> Vec<OccupancyGrid> {
    let points = log.scans.iter().flat_map(|s| {
        let pose = s.laser_pose;
        s.scan.endpoints().map(move |p| pose * p)
    });
    let geometry = GridGeometry::bounding(points, 0.05, 1.0).unwrap();
    (0..days)
        .map(|k| {
            let mut mapper = OccupancyMapper::new(geometry, MapperParams::default()).unwrap();
            for s in log.scans.iter().skip(k).step_by(days) {
                mapper.insert(&s.scan, &s.laser_pose).unwrap();
            }
            mapper.occupancy_grid()
        })
        .collect()
}

/// The map of the log's odd scans in a frame moved by `truth`⁻¹: another day's SLAM frame,
/// which `truth` maps back onto the even scans' map.
fn odd_scans_in_moved_frame(log: &CarmenLog, truth: &Pose2) -> OccupancyGrid {
    let moved: Vec<Pose2> = log
        .scans
        .iter()
        .map(|s| truth.inverse() * s.laser_pose)
        .collect();
    let ends = log.scans.iter().zip(&moved).flat_map(|(s, p)| {
        let p = *p;
        s.scan.endpoints().map(move |e| p * e)
    });
    let geometry = GridGeometry::bounding(ends, 0.05, 1.0).unwrap();
    let mut mapper = OccupancyMapper::new(geometry, MapperParams::default()).unwrap();
    for (s, p) in log.scans.iter().zip(&moved).skip(1).step_by(2) {
        mapper.insert(&s.scan, p).unwrap();
    }
    mapper.occupancy_grid()
}

#[test]
fn days_of_two_buildings_cluster_by_building() {
    let (Some(intel), Some(csail)) = (
        common::shared_data("carmen/intel-corrected.log.gz"),
        common::shared_data("carmen/csail-corrected.log.gz"),
    ) else {
        return;
    };
    let days = 4;
    let mut maps = daily_maps(
        &read_carmen(intel, &CarmenOptions::default()).unwrap(),
        days,
    );
    maps.extend(daily_maps(
        &read_carmen(csail, &CarmenOptions::default()).unwrap(),
        days,
    ));
    let truth: Vec<usize> = (0..2 * days).map(|i| i / days).collect();
    // The buildings' maps have different geometries: compare them on their union.
    let union = common_geometry(&maps.iter().map(|m| *m.geometry()).collect::<Vec<_>>()).unwrap();
    let maps: Vec<OccupancyGrid> = maps.iter().map(|m| resample(m, &union).unwrap()).collect();
    let matrix = similarity_matrix(&maps, &DifferenceParams::default()).unwrap();
    let n = maps.len();
    for x in 0..n {
        let row: Vec<String> = (0..n)
            .map(|y| format!("{:9.0}", matrix.get(x, y).unwrap()))
            .collect();
        eprintln!("{}", row.join(" "));
    }
    eprintln!("occupied: {:?}", matrix.occupied_counts());
    // Every same-building difference is smaller than every cross-building one.
    let (mut within, mut across) = (0.0f64, f64::INFINITY);
    for x in 0..n {
        for y in 0..n {
            if x == y {
                continue;
            }
            let v = matrix.get(x, y).unwrap();
            if truth[x] == truth[y] {
                within = within.max(v);
            } else {
                across = across.min(v);
            }
        }
    }
    eprintln!("largest within a building {within:.0}, smallest across {across:.0}");
    assert!(within < across);
    // Same-building entries are a few thousand cells² (≈ 1 cell per occupied cell: sparse
    // scans see slightly different clutter), above the seed's absolute 1300, which was set for
    // one room; per occupied cell the two groups are ≈ 1 vs ≈ 55 cells apart.
    let params = ClusterParams::default().with_threshold(LayoutThreshold::PerOccupiedCell(5.0));
    for clustering in [
        greedy_layouts(&matrix, &params).unwrap(),
        complete_linkage_layouts(&matrix, &params).unwrap(),
    ] {
        let a = agreement(&clustering.labels, &truth).unwrap();
        assert_eq!(clustering.labels, truth, "{a:?}");
        assert_eq!(a.adjusted_rand_index, 1.0);
    }
}

#[test]
fn icp_recovers_a_known_transform_of_a_real_map() {
    use haunts_similarity::{IcpParams, IcpTarget, RobustLoss, icp, icp_map_to_map};
    use nalgebra::{Point2, Vector2};
    let Some(path) = common::shared_data("carmen/intel-corrected.log.gz") else {
        return;
    };
    let log = read_carmen(path, &CarmenOptions::default()).unwrap();
    let target_map = &daily_maps(&log, 2)[0];
    let target = IcpTarget::new(target_map).unwrap();
    // The odd scans, mapped in a frame moved by `truth`⁻¹ (another day's SLAM frame).
    let truth = Pose2::new(Vector2::new(0.4, -0.3), 3f64.to_radians());
    let source = odd_scans_in_moved_frame(&log, &truth);
    let params = IcpParams::default()
        .with_loss(RobustLoss::Tukey { c: 0.3 })
        .with_max_correspondence_distance(1.0);
    // An initial guess off by 0.2 m and 1.5°, as odometry or a coarse registration gives.
    let guess = Pose2::new(Vector2::new(0.25, -0.15), 1.5f64.to_radians());
    let r = icp_map_to_map(&target, &source, &guess, &params).unwrap();
    eprintln!("map-to-map: {r:?}");
    let err_t = (r.pose.translation.vector - truth.translation.vector).norm();
    let err_r = r.pose.rotation.angle_to(&truth.rotation).abs();
    assert!(err_t < 2.0 * 0.05, "translation off by {err_t} m");
    assert!(err_r < 1f64.to_radians(), "rotation off by {err_r} rad");
    assert!(r.fitness > 0.8, "{r:?}");
    // Scan-to-map: a held-out (odd) scan in its sensor frame, from a guess 0.13 m and 2° off.
    let k = 301;
    let scan_pts: Vec<Point2<f64>> = log.scans[k].scan.endpoints().collect();
    let true_pose = log.scans[k].laser_pose;
    let guess = true_pose * Pose2::new(Vector2::new(0.1, -0.08), 2f64.to_radians());
    let r = icp(&target, &scan_pts, &guess, &params).unwrap();
    let err_t = (r.pose.translation.vector - true_pose.translation.vector).norm();
    let err_r = r.pose.rotation.angle_to(&true_pose.rotation).abs();
    eprintln!("scan-to-map: {r:?}, off by {err_t} m, {err_r} rad");
    assert!(err_t < 2.0 * 0.05 && err_r < 1f64.to_radians());
}

#[test]
fn global_registration_of_real_maps_and_no_match_across_buildings() {
    use haunts_similarity::{GlobalParams, SimilarityError, register_maps};
    use nalgebra::Vector2;
    let (Some(intel), Some(csail)) = (
        common::shared_data("carmen/intel-corrected.log.gz"),
        common::shared_data("carmen/csail-corrected.log.gz"),
    ) else {
        return;
    };
    let log = read_carmen(intel, &CarmenOptions::default()).unwrap();
    let target = &daily_maps(&log, 2)[0];
    // The odd scans mapped in a frame turned by 130° and moved: no initial guess is given.
    let truth = Pose2::new(Vector2::new(-4.0, 2.5), 130f64.to_radians());
    let source = odd_scans_in_moved_frame(&log, &truth);
    let m = register_maps(target, &source, &GlobalParams::default()).unwrap();
    let err_t = (m.pose.translation.vector - truth.translation.vector).norm();
    let err_r = m.pose.rotation.angle_to(&truth.rotation).abs();
    eprintln!(
        "intel vs rotated intel: {m:?}, off by {err_t:.3} m, {:.3}°",
        err_r.to_degrees()
    );
    assert!(err_t < 2.0 * 0.05, "translation off by {err_t} m");
    assert!(err_r < 1f64.to_radians(), "rotation off by {err_r} rad");
    // A map of another building: no reliable match, not a wrong transform.
    let csail_map = &daily_maps(&read_carmen(csail, &CarmenOptions::default()).unwrap(), 1)[0];
    let r = register_maps(target, csail_map, &GlobalParams::default());
    eprintln!("intel vs csail: {r:?}");
    assert!(
        matches!(r, Err(SimilarityError::NoReliableMatch { .. })),
        "{r:?}"
    );
    // Even when any two consistent matches are let through, the whole-map check refuses.
    let lax = GlobalParams::default().with_min_inliers(2);
    let r = register_maps(target, csail_map, &lax);
    eprintln!("intel vs csail, lax: {r:?}");
    assert!(
        matches!(r, Err(SimilarityError::NoReliableMatch { overlap, .. }) if overlap > 0.0 && overlap < 0.5),
        "{r:?}"
    );
}
