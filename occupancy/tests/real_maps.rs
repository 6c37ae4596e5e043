//! The real ROS maps of `../shared/data/maps/` load as Pillow + the map servers' rules say
//! (fixtures from `benches/peers/map_fixtures.py`), and their distance transforms equal
//! SciPy's `distance_transform_edt` exactly (fixtures from `benches/peers/edt_fixtures.py`).

mod common;

use haunts_occupancy::distance_transform_with_nearest;
use haunts_occupancy::{Interpretation, LoadNote, MapLoadOptions, MapMode, load_map};
use sha2::{Digest, Sha256};

fn maps() -> Vec<serde_json::Value> {
    common::fixture("maps.json")["maps"]
        .as_array()
        .unwrap()
        .clone()
}

#[test]
fn real_maps_have_the_expected_geometry_and_counts_under_both_readings() {
    for expected in maps() {
        let name = expected["name"].as_str().unwrap();
        let Some(yaml) =
            common::shared_data(&format!("maps/{}", expected["yaml"].as_str().unwrap()))
        else {
            return;
        };
        for (key, interpretation) in [
            ("ros1", Interpretation::Ros1),
            ("nav2", Interpretation::Nav2),
        ] {
            for (mode_key, mode) in [
                ("trinary", MapMode::Trinary),
                ("scale", MapMode::Scale),
                ("raw", MapMode::Raw),
            ] {
                let options = {
                    let mut p = MapLoadOptions::default();
                    p.interpretation = interpretation;
                    p
                };
                let mut map = load_map(&yaml, &options).unwrap();
                // The files are trinary; other modes are the same pixels read another way.
                map.metadata.mode = mode;
                let grid = haunts_occupancy::load_map_image(&map.metadata, interpretation).unwrap();
                let g = grid.geometry();
                assert_eq!(
                    g.width() as u64,
                    expected["width"].as_u64().unwrap(),
                    "{name}"
                );
                assert_eq!(
                    g.height() as u64,
                    expected["height"].as_u64().unwrap(),
                    "{name}"
                );
                assert_eq!(
                    g.resolution(),
                    expected["resolution"].as_f64().unwrap(),
                    "{name}"
                );
                assert_eq!(
                    g.origin().x,
                    expected["origin"][0].as_f64().unwrap(),
                    "{name}"
                );
                assert_eq!(
                    g.origin().y,
                    expected["origin"][1].as_f64().unwrap(),
                    "{name}"
                );

                let want = &expected[key][mode_key];
                let count = |pred: &dyn Fn(i8) -> bool| {
                    grid.values().data().iter().filter(|&&v| pred(v)).count() as u64
                };
                let n = |k: &str| want[k].as_u64().unwrap();
                // ROS 1 raw stores shades above 127 wrapped; we read any raw value outside
                // 0..=100 as unknown (see `Interpretation`'s docs), so those join the unknown count.
                assert_eq!(
                    count(&|v| v == -1),
                    n("unknown") + n("out_of_range"),
                    "{name} {key} {mode_key}"
                );
                assert_eq!(count(&|v| v == 0), n("free"), "{name} {key} {mode_key}");
                assert_eq!(
                    count(&|v| v == 100),
                    n("occupied"),
                    "{name} {key} {mode_key}"
                );
                assert_eq!(
                    count(&|v| (1..=99).contains(&v)),
                    n("other"),
                    "{name} {key} {mode_key}"
                );
                if n("out_of_range") == 0 {
                    let sum: i64 = grid.values().data().iter().map(|&v| i64::from(v)).sum();
                    assert_eq!(
                        sum,
                        want["sum"].as_i64().unwrap(),
                        "{name} {key} {mode_key}"
                    );
                }
            }
        }
        // What the loader noticed: neither file has a `mode` (trinary is the default).
        let map = load_map(&yaml, &MapLoadOptions::default()).unwrap();
        let defaulted = |field| {
            map.notes
                .iter()
                .any(|n| matches!(n, LoadNote::Defaulted { field: f, .. } if *f == field))
        };
        assert_eq!(
            defaulted("free_thresh"),
            expected["free_thresh_defaulted"].as_bool().unwrap(),
            "{name}"
        );
        assert!(defaulted("mode"), "{name}: {:?}", map.notes);
    }
}

#[test]
fn distance_transform_of_real_maps_equals_scipy_exactly() {
    for name in ["willow", "y4"] {
        let expected = common::fixture(&format!("edt_{name}.json"));
        let map_fixture = maps()
            .into_iter()
            .find(|m| m["name"].as_str().unwrap().starts_with(name))
            .unwrap();
        let Some(yaml) =
            common::shared_data(&format!("maps/{}", map_fixture["yaml"].as_str().unwrap()))
        else {
            return;
        };
        let map = load_map(&yaml, &MapLoadOptions::default()).unwrap();
        let mask = map.grid.occupied_mask();
        let obstacles = mask.data().iter().filter(|&&m| m).count() as u64;
        assert_eq!(obstacles, expected["obstacles"].as_u64().unwrap(), "{name}");

        let field = distance_transform_with_nearest(&mask).unwrap();
        let d2 = field.squared_cells();
        for s in expected["samples"].as_array().unwrap() {
            let (col, row, want) = (
                s[0].as_u64().unwrap() as usize,
                s[1].as_u64().unwrap() as usize,
                s[2].as_u64().unwrap(),
            );
            assert_eq!(
                u64::from(d2[row * mask.width() + col]),
                want,
                "{name} cell ({col}, {row})"
            );
        }
        assert_eq!(
            d2.iter().map(|&v| u64::from(v)).max().unwrap(),
            expected["max_d2"].as_u64().unwrap()
        );
        assert_eq!(
            d2.iter().map(|&v| u64::from(v)).sum::<u64>(),
            expected["sum_d2"].as_u64().unwrap()
        );
        let mut hasher = Sha256::new();
        for v in d2 {
            hasher.update(v.to_le_bytes());
        }
        let digest: String = hasher
            .finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(
            digest,
            expected["sha256"].as_str().unwrap(),
            "{name}: every cell equals SciPy's"
        );

        // Nearest obstacles are obstacles at exactly that distance.
        let g = *mask.geometry();
        for i in (0..g.len()).step_by(97) {
            let cell = g.cell_at(i).unwrap();
            let n = field.nearest(cell).unwrap();
            assert!(mask[n]);
            let dd = (cell.col.abs_diff(n.col).pow(2) + cell.row.abs_diff(n.row).pow(2)) as u32;
            assert_eq!(dd, d2[i]);
        }
    }
}
