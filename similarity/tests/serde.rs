//! With the `serde` feature, parameters and results round-trip through JSON, and
//! deserialising a type whose constructor checks invariants checks them too.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used)]

use haunts_occupancy::{Cell, GridGeometry, OCCUPIED, OccupancyGrid, Pose2};
use haunts_similarity::{
    Agreement, ChangeParams, ClusterParams, Clustering, DifferenceParams, GlobalMatch,
    GlobalParams, IcpParams, IcpResult, IcpTarget, LayoutThreshold, Length, LocaliserParams,
    PairDifference, PreparedMap, RegionChange, RegionChanges, RobustLoss, SimilarityMatrix,
    Symmetrisation, UmeyamaFit, agreement, compare, complete_linkage_layouts, greedy_layouts,
    icp_map_to_map, local_changes, similarity_matrix, umeyama_similarity,
};
use nalgebra::{Point2, Vector2};

use haunts_test_support::json;
use json::{corrupt, rejection, round_trip};

/// A 3 m × 2.5 m room at 0.05 m with a wall across it at column `wall`.
fn day(wall: usize) -> OccupancyGrid {
    let g = GridGeometry::new(0.05, Point2::new(-1.0, 0.5), 60, 50).unwrap();
    let mut m = OccupancyGrid::unknown(g);
    for i in 0..60 {
        m.set(Cell::new(i, 0), OCCUPIED);
        m.set(Cell::new(i, 49), OCCUPIED);
    }
    for row in 0..50 {
        m.set(Cell::new(0, row), OCCUPIED);
        m.set(Cell::new(59, row), OCCUPIED);
        if row < 35 {
            m.set(Cell::new(wall, row), OCCUPIED);
        }
    }
    m
}

#[test]
fn parameters_round_trip_through_json() {
    for length in [Length::Cells(7.5), Length::Metres(0.25)] {
        round_trip(&length);
    }
    for how in [
        Symmetrisation::Max,
        Symmetrisation::Mean,
        Symmetrisation::Min,
        Symmetrisation::Sum,
    ] {
        round_trip(&how);
    }
    for threshold in [
        LayoutThreshold::Cells(900.0),
        LayoutThreshold::SquareMetres(1.5),
        LayoutThreshold::PerOccupiedCell(0.75),
    ] {
        round_trip(&threshold);
    }
    for loss in [
        RobustLoss::Squared,
        RobustLoss::Huber { delta: 0.125 },
        RobustLoss::Tukey { c: 0.375 },
    ] {
        round_trip(&loss);
    }
    let difference = DifferenceParams::default().with_cutoff(Length::Cells(4.0));
    assert_ne!(difference, DifferenceParams::default());
    round_trip(&difference);
    let cluster = ClusterParams::default()
        .with_threshold(LayoutThreshold::PerOccupiedCell(2.5))
        .with_symmetrisation(Symmetrisation::Mean);
    assert_ne!(cluster, ClusterParams::default());
    round_trip(&cluster);
    let change = {
        let mut p = ChangeParams::default();
        p.region = Length::Cells(12.0);
        p.difference = difference;
        p.threshold = LayoutThreshold::Cells(40.0);
        p.symmetrisation = Symmetrisation::Sum;
        p
    };
    assert_ne!(change, ChangeParams::default());
    round_trip(&change);
    let icp = {
        let mut p = IcpParams::default();
        p.max_iterations = 17;
        p.max_correspondence_distance = 0.75;
        p.loss = RobustLoss::Tukey { c: 0.25 };
        p.translation_tolerance = 1e-4;
        p.rotation_tolerance = 2e-5;
        p.min_correspondences = 25;
        p
    };
    assert_ne!(icp, IcpParams::default());
    round_trip(&icp);
    let global = {
        let mut p = GlobalParams::default();
        p.keypoint_spacing = Length::Cells(6.0);
        p.max_keypoints = 123;
        p.descriptor_radius = Length::Metres(2.5);
        p.rings = 9;
        p.candidates = 5;
        p.ransac_iterations = 777;
        p.seed = 42;
        p.inlier_distance = Length::Cells(3.5);
        p.min_inliers = 8;
        p.min_overlap = 0.625;
        p
    };
    assert_ne!(global, GlobalParams::default());
    round_trip(&global);
    let localiser = LocaliserParams::default()
        .with_revisit_distance(1.25)
        .with_refresh_every(7);
    round_trip(&localiser);
}

#[test]
fn localiser_parameters_saved_before_revisits_read_as_drawing_every_keyframe() {
    // Saved before `revisit_distance` existed: those parameters drew every keyframe.
    let mut saved: serde_json::Value = serde_json::to_value(LocaliserParams::default()).unwrap();
    let removed = saved.as_object_mut().unwrap().remove("revisit_distance");
    assert_eq!(removed, Some(serde_json::json!(0.75)));
    let read: LocaliserParams = serde_json::from_value(saved).unwrap();
    assert_eq!(read, LocaliserParams::default().with_revisit_distance(0.0));
}

#[test]
fn computed_results_round_trip_through_json() {
    let days = [day(20), day(21), day(45), day(20)];
    let params = DifferenceParams::default().with_cutoff(Length::Cells(3.0));

    let matrix = similarity_matrix(&days, &params).unwrap();
    assert!(matrix.values().iter().any(|v| *v > 0.0));
    let json = serde_json::to_string(&matrix).unwrap();
    assert!(
        !json.contains("\"n\""),
        "the size is derived, not stored: {json}"
    );
    let back = round_trip(&matrix);
    assert_eq!(back.len(), 4);

    let pair: PairDifference = compare(&days[0], &days[2], &params).unwrap();
    assert!(pair.x_to_y > 0.0 && pair.y_to_x > 0.0);
    round_trip(&pair);

    let cluster = ClusterParams::default().with_threshold(LayoutThreshold::Cells(50.0));
    let clustering: Clustering = complete_linkage_layouts(&matrix, &cluster).unwrap();
    assert_eq!(clustering.labels, vec![0, 0, 1, 0]);
    round_trip(&clustering);

    let score: Agreement = agreement(&clustering.labels, &[0, 1, 1, 0]).unwrap();
    assert!(score.rand_index < 1.0);
    round_trip(&score);

    let x = PreparedMap::new(&days[0]).unwrap();
    let y = PreparedMap::new(&days[2]).unwrap();
    let changes: RegionChanges = local_changes(
        &x,
        &y,
        &ChangeParams::default().with_region(Length::Cells(20.0)),
    )
    .unwrap();
    assert!(changes.changed().count() > 0);
    let json = serde_json::to_string(&changes).unwrap();
    assert!(!json.contains("\"cols\""), "cols are derived: {json}");
    let back = round_trip(&changes);
    assert_eq!(back.cols(), changes.cols());
    assert_eq!(back.bounds(1, 1), changes.bounds(1, 1));
    round_trip(&changes.regions()[1]);

    let target = IcpTarget::new(&days[0]).unwrap();
    let fit: IcpResult = icp_map_to_map(
        &target,
        &days[0],
        &Pose2::new(Vector2::new(0.03, -0.02), 0.01),
        &IcpParams::default(),
    )
    .unwrap();
    assert!(fit.iterations > 0 && fit.fitness > 0.9);
    round_trip(&fit);

    let src = [
        Point2::new(0.0, 0.0),
        Point2::new(1.0, 0.0),
        Point2::new(0.3, 2.0),
    ];
    let truth = Pose2::new(Vector2::new(0.7, -1.3), 0.4);
    let dst: Vec<_> = src.iter().map(|p| truth * (p * 1.5)).collect();
    let umeyama: UmeyamaFit = umeyama_similarity(&src, &dst).unwrap();
    assert!((umeyama.scale - 1.5).abs() < 1e-9);
    round_trip(&umeyama);
}

#[test]
fn hand_made_results_round_trip_through_json() {
    round_trip(&GlobalMatch {
        pose: Pose2::new(Vector2::new(2.5, -0.75), 2.2),
        inliers: 14,
        matches: 230,
        overlap: 0.875,
        residual: 0.031,
    });
    round_trip(&RegionChange {
        col: 3,
        row: 2,
        x_to_y: 12.5,
        y_to_x: 0.0,
        changed: true,
    });
    round_trip(
        &SimilarityMatrix::from_values(vec![0.0, 3.5, 7.25, 0.0], vec![40, 55], 0.1).unwrap(),
    );
    round_trip(&SimilarityMatrix::from_values(Vec::new(), Vec::new(), 0.05).unwrap());
}

#[test]
fn an_invalid_similarity_matrix_is_rejected() {
    let ok = r#"{"values":[0.0,1.0,2.0,0.0],"occupied":[3,4],"resolution":0.05}"#;
    assert_eq!(
        serde_json::from_str::<SimilarityMatrix>(ok).unwrap(),
        SimilarityMatrix::from_values(vec![0.0, 1.0, 2.0, 0.0], vec![3, 4], 0.05).unwrap()
    );
    let e = rejection::<SimilarityMatrix>(
        r#"{"values":[0.0,-1.0,2.0,0.0],"occupied":[3,4],"resolution":0.05}"#,
    );
    assert!(e.contains("`values`"), "{e}");
    let e = rejection::<SimilarityMatrix>(
        r#"{"values":[0.0,1.0,2.0],"occupied":[3,4],"resolution":0.05}"#,
    );
    assert!(e.contains("values"), "{e}");
    let e = rejection::<SimilarityMatrix>(
        r#"{"values":[0.0,1.0,2.0,0.0],"occupied":[3,4],"resolution":0.0}"#,
    );
    assert!(e.contains("`resolution`"), "{e}");
    let e = rejection::<SimilarityMatrix>(r#"{"values":[],"occupied":[]}"#);
    assert!(e.contains("resolution"), "{e}");
}

#[test]
fn invalid_region_changes_are_rejected() {
    let g = GridGeometry::new(0.1, Point2::origin(), 5, 3).unwrap();
    // Regions of 2 cells: 3 columns × 2 rows of regions.
    let region = |k: usize| RegionChange {
        col: k % 3,
        row: k / 3,
        x_to_y: k as f64,
        y_to_x: 0.5,
        changed: k == 4,
    };
    let json = |side: usize, regions: &[RegionChange]| {
        format!(
            r#"{{"geometry":{},"side":{side},"regions":{}}}"#,
            serde_json::to_string(&g).unwrap(),
            serde_json::to_string(regions).unwrap()
        )
    };
    let regions: Vec<RegionChange> = (0..6).map(region).collect();
    let ok: RegionChanges = serde_json::from_str(&json(2, &regions)).unwrap();
    assert_eq!((ok.region_cells(), ok.cols()), (2, 3));
    assert_eq!(ok.regions(), &regions[..]);
    round_trip(&ok);

    let e = rejection::<RegionChanges>(&json(0, &[]));
    assert!(e.contains("`side`"), "{e}");
    let e = rejection::<RegionChanges>(&json(2, &regions[..5]));
    assert!(e.contains("regions"), "{e}");
    let mut swapped = regions.clone();
    swapped.swap(1, 2);
    let e = rejection::<RegionChanges>(&json(2, &swapped));
    assert!(e.contains("`regions.col`"), "{e}");
    let mut wrong_row = regions.clone();
    wrong_row[3].row = 0;
    wrong_row[3].col = 0;
    let e = rejection::<RegionChanges>(&json(2, &wrong_row));
    assert!(e.contains("`regions.row`"), "{e}");
    let mut negative = regions.clone();
    negative[2].y_to_x = -1.0;
    let e = rejection::<RegionChanges>(&json(2, &negative));
    assert!(e.contains("`regions.y_to_x`"), "{e}");
    let bad_geometry = json(2, &regions).replace("\"resolution\":0.1", "\"resolution\":-0.1");
    let e = rejection::<RegionChanges>(&bad_geometry);
    assert!(e.contains("resolution"), "{e}");
}

/// Accessors of a loaded matrix, and both clusterings with every threshold kind and
/// symmetrisation; their labels scored against the truth.
fn use_matrix(matrix: &SimilarityMatrix, truth: &[usize]) {
    let n = matrix.len();
    assert_eq!(matrix.values().len(), n * n);
    assert_eq!(matrix.occupied_counts().len(), n);
    assert_eq!(matrix.is_empty(), n == 0);
    for x in 0..=n {
        for y in 0..=n {
            assert_eq!(matrix.get(x, y).is_some(), x < n && y < n);
        }
    }
    assert!(matrix.resolution() > 0.0);
    for threshold in [
        LayoutThreshold::Cells(50.0),
        LayoutThreshold::SquareMetres(3.25),
        LayoutThreshold::PerOccupiedCell(0.5),
    ] {
        for how in [
            Symmetrisation::Max,
            Symmetrisation::Mean,
            Symmetrisation::Min,
            Symmetrisation::Sum,
        ] {
            assert_eq!(matrix.symmetrised(how).len(), n * n);
            let params = ClusterParams::default()
                .with_threshold(threshold)
                .with_symmetrisation(how);
            assert_eq!(params.layout_distances(matrix).len(), n * n);
            for clustering in [
                greedy_layouts(matrix, &params).unwrap(),
                complete_linkage_layouts(matrix, &params).unwrap(),
            ] {
                assert_eq!(clustering.labels.len(), n);
                assert!(clustering.labels.iter().all(|&l| l < clustering.clusters));
                let _ = agreement(&clustering.labels, truth);
            }
        }
    }
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    let days = [day(20), day(21), day(45), day(20), day(46)];
    let truth = [0, 0, 1, 0, 1];
    let params = DifferenceParams::default().with_cutoff(Length::Cells(3.0));
    let matrix = similarity_matrix(&days, &params).unwrap();
    let matrices = corrupt(&matrix, 1000, |m: &SimilarityMatrix| use_matrix(m, &truth));

    let x = PreparedMap::new(&days[0]).unwrap();
    let y = PreparedMap::new(&days[2]).unwrap();
    let changes = local_changes(
        &x,
        &y,
        &ChangeParams::default().with_region(Length::Cells(20.0)),
    )
    .unwrap();
    let regions = corrupt(&changes, 1000, |c: &RegionChanges| {
        let cols = c.cols();
        assert!(cols >= 1 && c.region_cells() >= 1);
        for r in c.regions() {
            let (lo, hi) = c.bounds(r.col, r.row);
            assert!(lo.x <= hi.x && lo.y <= hi.y, "{lo} {hi}");
        }
        let _ = c.bounds(usize::MAX, usize::MAX);
        let _ = c.changed().count();
    });

    let cluster = ClusterParams::default().with_threshold(LayoutThreshold::Cells(50.0));
    let clustering = complete_linkage_layouts(&matrix, &cluster).unwrap();
    let clusterings = corrupt(&clustering, 1000, |c: &Clustering| {
        // Plain data (public fields): scored against the truth, the only library use.
        let _ = agreement(&c.labels, &truth);
        let _ = agreement(&c.labels, &c.labels);
    });
    for (name, tally) in [
        ("SimilarityMatrix", matrices),
        ("RegionChanges", regions),
        ("Clustering", clusterings),
    ] {
        eprintln!("{name}: {tally:?}");
        assert!(tally.refused > 0 && tally.accepted > 0, "{name}: {tally:?}");
    }
}
