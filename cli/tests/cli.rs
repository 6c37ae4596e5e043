//! The `haunts` command end to end on simulated bags: sim → day → merge → maps, merging twice,
//! days on other cells, and corrupt, truncated and newer-version day artifacts.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Runs `haunts ARGS`; its success and its last stdout line as JSON (or stderr on failure).
fn haunts(args: &[&str]) -> (bool, Value, String) {
    let (status, json, stderr) = haunts_status(args);
    (status == Some(0), json, stderr)
}

/// Runs `haunts ARGS`; its exit status, its last stdout line as JSON, and its stderr.
fn haunts_status(args: &[&str]) -> (Option<i32>, Value, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_haunts"))
        .args(args)
        .output()
        .expect("haunts runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let json = stdout
        .lines()
        .last()
        .and_then(|l| serde_json::from_str(l).ok())
        .unwrap_or(Value::Null);
    (out.status.code(), json, stderr)
}

fn ok(args: &[&str]) -> Value {
    let (success, json, stderr) = haunts(args);
    assert!(success, "haunts {args:?} failed: {stderr}");
    json
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Two simulated one-patrol days as bags, each made a day artifact on the office's grid.
fn days(dir: &Path) -> (Vec<PathBuf>, String) {
    n_days(dir, 2)
}

/// `n` simulated one-patrol days as bags, each made a day artifact on the office's grid.
fn n_days(dir: &Path, n: usize) -> (Vec<PathBuf>, String) {
    let bags = dir.join("bags");
    let n = n.to_string();
    let sim = ok(&["sim", "--days", &n, "--patrols", "1", "-o", s(&bags)]);
    let grid = sim["grid"].as_str().unwrap().to_owned();
    let mut days = Vec::new();
    for (i, bag) in sim["bags"].as_array().unwrap().iter().enumerate() {
        let out = dir.join(format!("day{i}.haunts"));
        let day = ok(&[
            "day",
            bag.as_str().unwrap(),
            "-o",
            s(&out),
            "--grid",
            &grid,
            "--tuning",
            "sim",
        ]);
        assert_eq!(day["skipped"], 0, "{day}");
        assert!(day["trajectories"].as_u64().unwrap() > 0, "{day}");
        assert!(day["density_cells_known"].as_u64().unwrap() > 1000, "{day}");
        days.push(out);
    }
    (days, grid)
}

#[test]
fn bags_become_days_a_library_and_maps_and_merging_twice_counts_once() {
    let dir = tempfile::tempdir().unwrap();
    let (days, _) = days(dir.path());
    let library = dir.path().join("library.haunts");
    // What saves killed half-way leave (process 4 000 000 000 never runs): the merge's load of
    // a day and its save of the library remove them (on Linux, where a process id can be
    // asked about).
    let orphans = [
        dir.path().join(".library.haunts.tmp-4000000000-0"),
        dir.path().join(".day0.haunts.tmp-4000000000-3"),
    ];
    for orphan in &orphans {
        std::fs::write(orphan, b"half a file").unwrap();
    }
    let merged = ok(&["merge", s(&days[1]), s(&days[0]), "-o", s(&library)]);
    for orphan in &orphans {
        assert_eq!(orphan.exists(), !cfg!(target_os = "linux"), "{orphan:?}");
    }
    assert_eq!(merged["ingested"].as_array().unwrap().len(), 2, "{merged}");
    // In recording order, whatever the order on the command line.
    assert_eq!(merged["ingested"][0]["day"], "day_000.mcap");
    assert_eq!(merged["days"], 2);
    let before = std::fs::read(&library).unwrap();

    // The same days again: skipped, the library not even rewritten.
    let again = ok(&["merge", s(&days[0]), s(&days[1]), "-o", s(&library)]);
    assert_eq!(again["duplicates"].as_array().unwrap().len(), 2, "{again}");
    assert_eq!(again["saved"], false);
    assert_eq!(again["days"], 2);
    assert_eq!(std::fs::read(&library).unwrap(), before);

    // The same recording as a day on other cells (the default grid of its own odometry)
    // under a new label: registered onto the library (its frame is the library's, so the
    // transform is the identity) and merged into the same layout, not as a new one.
    let other = dir.path().join("other.haunts");
    let bag = dir.path().join("bags/day_001.mcap");
    ok(&[
        "day",
        s(&bag),
        "-o",
        s(&other),
        "--label",
        "again",
        "--tuning",
        "sim",
    ]);
    let again = ok(&["merge", s(&other), "-o", s(&library)]);
    assert_eq!(again["ingested"].as_array().unwrap().len(), 1, "{again}");
    let joined = &again["ingested"][0];
    assert_eq!(joined["new_layout"], false, "{again}");
    let a = &joined["alignment"];
    let (x, y, yaw) = (
        a["x"].as_f64().unwrap(),
        a["y"].as_f64().unwrap(),
        a["yaw"].as_f64().unwrap(),
    );
    assert!(x.hypot(y) < 0.2 && yaw.abs() < 1f64.to_radians(), "{a}");
    assert!(a["inliers"].as_f64().unwrap() > 0.9, "{a}");
    assert_ne!(std::fs::read(&library).unwrap(), before);

    // Maps: ROS map files that load back, a picture, an MCAP of every layout's grids.
    let maps = dir.path().join("maps");
    let report = ok(&["maps", s(&library), "-o", s(&maps)]);
    let layouts = report["layouts"].as_array().unwrap().len();
    assert!(layouts >= 1);
    for id in 0..layouts {
        let load = |what: &str| {
            let path = maps.join(format!("layout_{id}_{what}.yaml"));
            haunts::occupancy::load_map(path, &Default::default())
                .unwrap()
                .grid
        };
        assert!(load("composite").values().data().contains(&100));
        // Raw mode: values between free and lethal where the affordance layer raised them.
        let costmap = load("costmap");
        assert!(costmap.values().data().iter().any(|v| (1..99).contains(v)));
        assert!(maps.join(format!("layout_{id}_affordance.png")).exists());
        // A replay with the library publishes the same costmap, cell for cell.
        if id == 0 {
            let live = dir.path().join("live.mcap");
            let replay = ok(&["replay", s(&bag), "-o", s(&live), "--library", s(&library)]);
            assert_eq!(replay["costmaps"], layouts, "{replay}");
            assert!(
                replay["left_out"]["mota_every_scan"].is_string(),
                "{replay}"
            );
            let published = haunts::bag::Bag::open(&live).unwrap();
            let (_, grid) = published
                .read::<haunts::bag::msg::OccupancyGrid>("/haunts/costmap/layout_0")
                .unwrap()
                .next()
                .unwrap()
                .unwrap();
            let grid = haunts::bag::convert::occupancy_grid(&grid).unwrap();
            // The message's resolution is an f32.
            let (g, c) = (grid.geometry(), costmap.geometry());
            assert!((g.resolution() - c.resolution()).abs() < 1e-6);
            assert_eq!(
                (g.origin(), g.width(), g.height()),
                (c.origin(), c.width(), c.height())
            );
            assert_eq!(grid.values().data(), costmap.values().data());
        }
    }
    let bag = haunts::bag::Bag::open(maps.join("maps.mcap")).unwrap();
    let grids = bag.topics_of::<haunts::bag::msg::OccupancyGrid>().len();
    assert_eq!(grids, 3 * layouts);
    let page = std::fs::read_to_string(maps.join("index.html")).unwrap();
    assert_eq!(page.matches("<img src=\"layout_").count(), layouts);
}

#[test]
fn maps_with_the_days_draw_each_layouts_flow() {
    use haunts::affordance::flow::{FlowMap, FlowParams, observations};
    let dir = tempfile::tempdir().unwrap();
    let (days, _) = days(dir.path());
    let library = dir.path().join("library.haunts");
    ok(&["merge", s(&days[0]), s(&days[1]), "-o", s(&library)]);
    // A third artifact under a label the library does not hold: skipped and counted.
    let stranger = dir.path().join("stranger.haunts");
    std::fs::copy(&days[0], &stranger).unwrap();
    let mut other = haunts::artifact::DayArtifact::load(&stranger).unwrap();
    other.label = "not merged".into();
    other.save(&stranger).unwrap();
    let maps = dir.path().join("maps");
    let report = ok(&[
        "maps",
        s(&library),
        "-o",
        s(&maps),
        "--days",
        s(&days[0]),
        s(&days[1]),
        s(&stranger),
    ]);
    assert_eq!(report["flow_days_not_in_library"], 1, "{report}");
    let layouts = report["layouts"].as_array().unwrap();
    // The reference: the layout's days' tracks through the library's code, here.
    let lib = haunts::affordance::LayoutLibrary::load(&library).unwrap();
    let bag = haunts::bag::Bag::open(maps.join("maps.mcap")).unwrap();
    for (layout, entry) in lib.layouts().iter().zip(layouts) {
        let id = layout.id().0;
        let tracks: Vec<_> = days
            .iter()
            .map(|d| haunts::artifact::DayArtifact::load(d).unwrap())
            .filter(|d| layout.days().iter().any(|r| r.label == d.label))
            .flat_map(|d| d.trajectories)
            .collect();
        let (seen, _) = observations(&tracks, 0.1);
        let grid = lib.geometry().with_resolution(1.0).unwrap();
        let flow = FlowMap::fit(&seen, grid, &FlowParams::default().with_mixture(false)).unwrap();
        let arrows = haunts::pipeline::flow::flow_arrows(&flow, 0.1);
        assert!(!arrows.is_empty());
        assert_eq!(entry["flow"]["arrows"], arrows.len(), "{entry}");
        assert_eq!(entry["flow"]["observations"], flow.used(), "{entry}");
        assert!(maps.join(format!("layout_{id}_flow.png")).exists());
        let (_, markers) = bag
            .read::<haunts::bag::msg::MarkerArray>(&format!("/layout_{id}/flow"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap();
        assert_eq!(markers.markers.len(), 1 + arrows.len());
        for (m, (tail, head)) in markers.markers[1..].iter().zip(&arrows) {
            assert_eq!(m.type_, haunts::bag::msg::Marker::ARROW);
            assert_eq!((m.points[0].x, m.points[0].y), (tail.x, tail.y));
            assert_eq!((m.points[1].x, m.points[1].y), (head.x, head.y));
        }
    }
    let page = std::fs::read_to_string(maps.join("index.html")).unwrap();
    assert_eq!(page.matches("_flow.png").count(), layouts.len());
}

#[test]
fn corrupt_truncated_and_newer_day_artifacts_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let (days, _) = days(dir.path());
    let bytes = std::fs::read(&days[0]).unwrap();
    let library = dir.path().join("library.haunts");
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "flipped",
            {
                let mut b = bytes.clone();
                let mid = b.len() / 2;
                b[mid] ^= 0x10;
                b
            },
            "checksum",
        ),
        (
            "truncated",
            bytes[..bytes.len() - 100].to_vec(),
            "announces",
        ),
        (
            "newer",
            {
                let mut b = bytes.clone();
                b[8..12].copy_from_slice(&2u32.to_le_bytes());
                b
            },
            "format 2",
        ),
        ("not a day", b"HAUNTLIB and more".to_vec(), "layout library"),
    ];
    for (name, content, expected) in cases {
        let path = dir.path().join(format!("{name}.haunts"));
        std::fs::write(&path, content).unwrap();
        let (success, _, stderr) = haunts(&["merge", s(&days[1]), s(&path), "-o", s(&library)]);
        assert!(!success, "{name} was accepted");
        assert!(stderr.contains(expected), "{name}: {stderr}");
        // Nothing was merged: the good day was not written alone.
        assert!(!library.exists(), "{name}: a library was written");
    }
}

/// Days stored in the library at `path`.
fn stored_days(path: &Path) -> usize {
    haunts::affordance::LayoutLibrary::load(path)
        .unwrap()
        .layouts()
        .iter()
        .map(|l| l.days().len())
        .sum()
}

#[test]
fn a_merge_killed_at_any_moment_leaves_the_library_as_it_was_or_merged() {
    let dir = tempfile::tempdir().unwrap();
    let (days, _) = days(dir.path());
    let library = dir.path().join("library.haunts");
    ok(&["merge", s(&days[0]), "-o", s(&library)]);
    let before = std::fs::read(&library).unwrap();
    let merge = || {
        Command::new(env!("CARGO_BIN_EXE_haunts"))
            .args(["merge", s(&days[1]), "-o", s(&library)])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap()
    };
    // How long an uninterrupted merge takes, then kills spread over that time.
    let start = std::time::Instant::now();
    assert!(merge().wait().unwrap().success());
    let took = start.elapsed();
    assert_eq!(stored_days(&library), 2);
    let (mut unchanged, mut merged) = (0, 0);
    for k in 0..24u32 {
        std::fs::write(&library, &before).unwrap();
        let mut child = merge();
        std::thread::sleep(took * k / 20);
        // SIGKILL: no destructor, no flush, no clean-up of the child.
        let _ = child.kill();
        let _ = child.wait();
        let now = std::fs::read(&library).unwrap();
        if now == before {
            unchanged += 1;
        } else {
            // Anything else must be the whole merge: both days, each once.
            assert_eq!(stored_days(&library), 2, "kill {k}: a partial library");
            merged += 1;
        }
    }
    eprintln!("24 kills: {unchanged} left the library as it was, {merged} after the merge");
    // The interrupted merge is simply run again: the day is stored once.
    std::fs::write(&library, &before).unwrap();
    ok(&["merge", s(&days[1]), "-o", s(&library)]);
    let again = ok(&["merge", s(&days[0]), s(&days[1]), "-o", s(&library)]);
    assert_eq!(again["duplicates"].as_array().unwrap().len(), 2, "{again}");
    assert_eq!(stored_days(&library), 2);
}

/// Issue 49, item 4: merges into one library run one at a time (an advisory lock on its
/// sidecar `.NAME.lock`, held from the load to the save), so four merges started together
/// keep every day; a merge that finds the lock held waits `--wait` seconds, then refuses
/// with the library untouched.
#[test]
fn concurrent_merges_keep_every_day_and_a_held_lock_refuses_after_the_wait() {
    let dir = tempfile::tempdir().unwrap();
    let (days, _) = n_days(dir.path(), 4);
    for round in 0..3 {
        let library = dir.path().join(format!("library{round}.haunts"));
        let children: Vec<_> = days
            .iter()
            .map(|day| {
                Command::new(env!("CARGO_BIN_EXE_haunts"))
                    .args(["merge", s(day), "-o", s(&library)])
                    .stdout(std::process::Stdio::null())
                    .stderr(std::process::Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for child in children {
            let out = child.wait_with_output().unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        assert_eq!(stored_days(&library), 4, "round {round}: a day was lost");
    }
    // Another writer holds the lock: the merge waits, then refuses and leaves the library.
    let library = dir.path().join("library0.haunts");
    let before = std::fs::read(&library).unwrap();
    let holder =
        haunts::occupancy::atomic::lock(&library, std::time::Duration::ZERO, |_, _, e| e).unwrap();
    assert_eq!(holder.path(), dir.path().join(".library0.haunts.lock"));
    let start = std::time::Instant::now();
    let (status, _, stderr) =
        haunts_status(&["merge", s(&days[0]), "-o", s(&library), "--wait", "0.5"]);
    let waited = start.elapsed();
    assert_eq!(status, Some(1), "{stderr}");
    assert!(
        stderr.contains("another merge into this library is running"),
        "{stderr}"
    );
    assert!(
        waited >= std::time::Duration::from_millis(500),
        "{waited:?}"
    );
    assert_eq!(std::fs::read(&library).unwrap(), before);
    // Released, the same merge runs (the day is a duplicate: nothing is lost or doubled).
    drop(holder);
    let again = ok(&["merge", s(&days[0]), "-o", s(&library), "--wait", "0"]);
    assert_eq!(again["duplicates"].as_array().unwrap().len(), 1, "{again}");
    for bad in ["-1", "nan", "inf"] {
        let (status, _, stderr) =
            haunts_status(&["merge", s(&days[0]), "-o", s(&library), "--wait", bad]);
        assert_ne!(status, Some(0), "--wait {bad}: {stderr}");
    }
}

/// `sim --days` outside 1 to 10 000 is refused before anything is simulated or written
/// (`usize::MAX` simulated until killed, 0 wrote nothing with exit 0).
#[test]
fn sim_refuses_absurd_day_counts() {
    let dir = tempfile::tempdir().unwrap();
    for days in ["0", "18446744073709551615", "10001"] {
        let out = dir.path().join(format!("bags-{days}"));
        let (success, _, stderr) = haunts(&["sim", "--days", days, "-o", s(&out)]);
        assert!(!success, "--days {days} accepted");
        assert!(stderr.contains("must be from 1 to 10000"), "{stderr}");
        assert!(!out.exists(), "--days {days} created {}", out.display());
    }
}

/// `(x, y, yaw)` of `a⁻¹ · b` for poses given as JSON `{"x", "y", "yaw"}`: the true transform
/// of day `b`'s odometry frame into day `a`'s.
fn relative(a: &Value, b: &Value) -> (f64, f64, f64) {
    let pose = |v: &Value| {
        haunts::occupancy::Pose2::new(
            nalgebra::Vector2::new(v["x"].as_f64().unwrap(), v["y"].as_f64().unwrap()),
            v["yaw"].as_f64().unwrap(),
        )
    };
    let r = pose(a).inverse() * pose(b);
    (r.translation.x, r.translation.y, r.rotation.angle())
}

/// Three days from three random start poses, each processed on its own grid: merged in any
/// order they give one library, byte for byte, of one layout, each day's transform within
/// 2 cells and 1° of the truth; `day --like` aligns a day the same way and `--pose` forces
/// one; another building is refused and the library is unchanged.
#[test]
fn days_from_random_start_poses_are_aligned_and_another_building_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bags = dir.path().join("bags");
    let sim = ok(&[
        "sim",
        "--days",
        "3",
        "--patrols",
        "1",
        "--random-start",
        "-o",
        s(&bags),
    ]);
    let starts = sim["starts"].as_array().unwrap().clone();
    let (mut days, mut grids) = (Vec::new(), Vec::new());
    for (i, bag) in sim["bags"].as_array().unwrap().iter().enumerate() {
        let out = dir.path().join(format!("day{i}.haunts"));
        let day = ok(&[
            "day",
            bag.as_str().unwrap(),
            "-o",
            s(&out),
            "--tuning",
            "sim",
        ]);
        grids.push(day["grid"].clone());
        days.push(out);
    }
    let (one, two) = (dir.path().join("one.haunts"), dir.path().join("two.haunts"));
    let merged = ok(&[
        "merge",
        s(&days[2]),
        s(&days[0]),
        s(&days[1]),
        "-o",
        s(&one),
    ]);
    ok(&[
        "merge",
        s(&days[1]),
        s(&days[2]),
        s(&days[0]),
        "-o",
        s(&two),
    ]);
    assert_eq!(std::fs::read(&one).unwrap(), std::fs::read(&two).unwrap());
    assert_eq!(merged["layouts"], 1, "{merged}");
    let ingested = merged["ingested"].as_array().unwrap();
    assert_eq!(ingested.len(), 3, "{merged}");
    assert!(
        ingested[0]["alignment"].is_null(),
        "the first day is the library's frame"
    );
    let close = |a: &Value, truth: (f64, f64, f64)| {
        let dx = a["x"].as_f64().unwrap() - truth.0;
        let dy = a["y"].as_f64().unwrap() - truth.1;
        let dyaw = (a["yaw"].as_f64().unwrap() - truth.2 + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        dx.hypot(dy) <= 0.2 && dyaw.abs() <= 1f64.to_radians()
    };
    for (k, d) in ingested.iter().enumerate().skip(1) {
        let truth = relative(&starts[0], &starts[k]);
        assert!(close(&d["alignment"], truth), "day {k}: {d} vs {truth:?}");
    }

    // `day --like`: the day is aligned when it is made.
    let liked = dir.path().join("liked.haunts");
    let bag = bags.join("day_002.mcap");
    let day = ok(&[
        "day",
        s(&bag),
        "-o",
        s(&liked),
        "--like",
        s(&one),
        "--label",
        "again",
        "--tuning",
        "sim",
    ]);
    assert!(
        close(&day["alignment"], relative(&starts[0], &starts[2])),
        "{day}"
    );
    assert!(day["refused"].is_null());
    // Drawn on the library's cells (day 0's, the earliest day's), where day 2 had its own.
    assert_eq!(day["grid"], grids[0], "{day}");
    assert_ne!(grids[2], grids[0]);
    let again = ok(&["merge", s(&liked), "-o", s(&one)]);
    assert_eq!(again["ingested"][0]["new_layout"], false, "{again}");
    // A forced transform is measured, not judged: a wrong one puts little on the library.
    let forced = ok(&[
        "day",
        s(&bag),
        "-o",
        s(&liked),
        "--like",
        s(&two),
        "--pose",
        "1,-2,0.5",
        "--tuning",
        "sim",
    ]);
    assert_eq!(forced["alignment"]["forced"], true, "{forced}");
    assert_eq!(forced["alignment"]["yaw"], 0.5, "{forced}");
    assert!(
        forced["alignment"]["inliers"].as_f64().unwrap() < 0.5,
        "{forced}"
    );
    let (success, _, stderr) = haunts(&["day", s(&bag), "-o", s(&liked), "--pose", "1,2,0"]);
    assert!(!success && stderr.contains("--like"), "{stderr}");

    // Another building (leg_tracker's recording) is refused by `day --like` and by `merge`.
    let Some(moving) = haunts_test_support::bag::moving_mcap() else {
        eprintln!("skipped the other building: ../shared/data is absent");
        return;
    };
    let before = std::fs::read(&two).unwrap();
    let elsewhere = dir.path().join("elsewhere.haunts");
    let (status, day, stderr) =
        haunts_status(&["day", s(&moving), "-o", s(&elsewhere), "--like", s(&two)]);
    assert_eq!(
        status,
        Some(3),
        "a refused day exits with status 3: {stderr}"
    );
    assert!(
        elsewhere.exists(),
        "the refused day is written in its own frame"
    );
    assert!(day["alignment"].is_null(), "{day}");
    assert!(
        day["refused"].as_str().unwrap().contains("another place"),
        "{day}"
    );
    let refused = ok(&["merge", s(&elsewhere), "-o", s(&two)]);
    assert_eq!(refused["refused"].as_array().unwrap().len(), 1, "{refused}");
    assert_eq!(refused["saved"], false, "{refused}");
    assert_eq!(std::fs::read(&two).unwrap(), before);
}

/// `bag` copied to `out` (scans, odometry, the laser's mount) with a localiser's constant
/// `map → odom` transform (`x`, `y` metres, no turn) on `/tf` at the first and last scan.
fn with_map_frame(bag: &Path, out: &Path, x: f64, y: f64) {
    use haunts::bag::{Bag, McapWriter, convert, msg};
    let bag = Bag::open(bag).unwrap();
    let mut w = McapWriter::create(out).unwrap();
    let mut stamps = Vec::new();
    for m in bag.read::<msg::LaserScan>("/scan").unwrap() {
        let (t, m) = m.unwrap();
        stamps.push(t);
        w.write("/scan", t, &m).unwrap();
    }
    for m in bag.read::<msg::Odometry>("/odom").unwrap() {
        let (t, m) = m.unwrap();
        w.write("/odom", t, &m).unwrap();
    }
    for m in bag.read::<msg::TfMessage>("/tf_static").unwrap() {
        let (t, m) = m.unwrap();
        w.write("/tf_static", t, &m).unwrap();
    }
    for t in [stamps[0], stamps[stamps.len() - 1]] {
        let link = msg::TransformStamped {
            header: convert::header(t, "map"),
            child_frame_id: "odom".into(),
            transform: msg::Transform {
                translation: msg::Vector3 { x, y, z: 0.0 },
                rotation: convert::quaternion(0.0),
            },
        };
        w.write(
            "/tf",
            t,
            &msg::TfMessage {
                transforms: vec![link],
            },
        )
        .unwrap();
    }
    w.finish().unwrap();
}

/// `X0,Y0,WIDTH,HEIGHT` of a day's JSON `grid`.
fn grid_of(day: &Value) -> Vec<f64> {
    day["grid"]
        .as_str()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect()
}

/// A recording whose `/tf` holds `map → odom` is placed in the map frame (its JSON says
/// `"frame": "map"`, its grid moved by the transform); `--fixed-frame odom` keeps the raw
/// odometry, and a frame the recording does not have is an error naming the frames it has.
#[test]
fn a_recording_with_a_map_frame_is_placed_in_it() {
    let dir = tempfile::tempdir().unwrap();
    let bags = dir.path().join("bags");
    let sim = ok(&["sim", "--days", "1", "--patrols", "1", "-o", s(&bags)]);
    let plain = PathBuf::from(sim["bags"][0].as_str().unwrap());
    let mapped = dir.path().join("mapped.mcap");
    with_map_frame(&plain, &mapped, 5.0, -3.0);
    let day = |bag: &Path, extra: &[&str]| {
        let out = dir.path().join("day.haunts");
        let mut args = vec!["day", s(bag), "-o", s(&out), "--tuning", "sim"];
        args.extend_from_slice(extra);
        ok(&args)
    };
    let odom = day(&plain, &[]);
    assert_eq!(odom["frame"], "odom", "{odom}");
    let map = day(&mapped, &[]);
    assert_eq!(map["frame"], "map", "{map}");
    let (a, b) = (grid_of(&odom), grid_of(&map));
    assert!(
        (b[0] - a[0] - 5.0).abs() < 1e-6 && (b[1] - a[1] + 3.0).abs() < 1e-6,
        "{a:?} {b:?}"
    );
    assert_eq!((a[2], a[3]), (b[2], b[3]));
    // Raw odometry when the odometry frame is named; the same day as the plain bag's.
    let raw = day(&mapped, &["--fixed-frame", "odom"]);
    assert_eq!(raw["frame"], "odom", "{raw}");
    assert_eq!(raw["grid"], odom["grid"]);
    let (success, _, stderr) = haunts(&[
        "day",
        s(&mapped),
        "-o",
        s(&dir.path().join("x.haunts")),
        "--fixed-frame",
        "world",
    ]);
    assert!(!success, "{stderr}");
    assert!(
        stderr.contains("`world`") && stderr.contains("map"),
        "{stderr}"
    );
}

/// `--resolution` is the day's cell size (the daily loop draws at it), and a day made
/// `--like` a library takes the library's.
#[test]
fn the_resolution_asked_for_is_the_days() {
    let dir = tempfile::tempdir().unwrap();
    let bags = dir.path().join("bags");
    let sim = ok(&["sim", "--days", "1", "--patrols", "1", "-o", s(&bags)]);
    let bag = sim["bags"][0].as_str().unwrap();
    let (coarse, liked, library) = (
        dir.path().join("coarse.haunts"),
        dir.path().join("liked.haunts"),
        dir.path().join("library.haunts"),
    );
    let args = ["--tuning", "sim", "--resolution", "0.2"];
    ok(&[&["day", bag, "-o", s(&coarse)][..], &args].concat());
    let day = haunts::artifact::DayArtifact::load(&coarse).unwrap();
    assert!((day.map.geometry().resolution() - 0.2).abs() < 1e-12);
    assert!((day.density.hits().geometry().resolution() - 0.2).abs() < 1e-12);
    ok(&["merge", s(&coarse), "-o", s(&library)]);
    ok(&[
        "day",
        bag,
        "-o",
        s(&liked),
        "--like",
        s(&library),
        "--label",
        "again",
        "--tuning",
        "sim",
    ]);
    let again = haunts::artifact::DayArtifact::load(&liked).unwrap();
    assert_eq!(again.map.geometry(), day.map.geometry());
}

/// `bag` copied to `out` with two bad odometry messages among the real ones, each stamped
/// half-way between two real ones: one at `x = 10⁵ m` (far from the rest) and one with a NaN
/// position.
fn with_bad_odometry(bag: &Path, out: &Path) {
    use haunts::bag::{Bag, McapWriter, convert, msg};
    let bag = Bag::open(bag).unwrap();
    let mut w = McapWriter::create(out).unwrap();
    for m in bag.read::<msg::LaserScan>("/scan").unwrap() {
        let (t, m) = m.unwrap();
        w.write("/scan", t, &m).unwrap();
    }
    let odometry: Vec<_> = bag
        .read::<msg::Odometry>("/odom")
        .unwrap()
        .map(Result::unwrap)
        .collect();
    let third = odometry.len() / 3;
    for (i, (t, m)) in odometry.iter().enumerate() {
        w.write("/odom", *t, m).unwrap();
        for (at, x) in [(third, 1.0e5), (2 * third, f64::NAN)] {
            if i == at {
                let mid = 0.5 * (t + odometry[i + 1].0);
                let mut bad = m.clone();
                bad.header = convert::header(mid, &m.header.frame_id);
                bad.pose.pose.position.x = x;
                w.write("/odom", mid, &bad).unwrap();
            }
        }
    }
    for m in bag.read::<msg::TfMessage>("/tf_static").unwrap() {
        let (t, m) = m.unwrap();
        w.write("/tf_static", t, &m).unwrap();
    }
    w.finish().unwrap();
}

/// One odometry message at 10⁵ m and one at NaN among a day's real ones are skipped and
/// counted (`skipped_rows`), and the day is the day of the real messages alone, bit for bit
/// (the far pose named on standard error).
#[test]
fn a_far_and_a_non_finite_odometry_pose_are_skipped_and_the_day_is_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let bags = dir.path().join("bags");
    let sim = ok(&["sim", "--days", "1", "--patrols", "1", "-o", s(&bags)]);
    let plain = PathBuf::from(sim["bags"][0].as_str().unwrap());
    let bad = dir.path().join("bad.mcap");
    with_bad_odometry(&plain, &bad);
    let day = |bag: &Path, name: &str| {
        let out = dir.path().join(name);
        let args = [
            "day",
            s(bag),
            "-o",
            s(&out),
            "--tuning",
            "sim",
            "--label",
            "d",
        ];
        let (success, json, stderr) = haunts(&args);
        assert!(success, "{stderr}");
        (
            json,
            stderr,
            haunts::artifact::DayArtifact::load(&out).unwrap(),
        )
    };
    let (good_json, _, good) = day(&plain, "good.haunts");
    let (bad_json, stderr, bad) = day(&bad, "bad.haunts");
    assert_eq!(good_json["skipped_rows"]["far"], 0, "{good_json}");
    assert_eq!(bad_json["skipped_rows"]["far"], 1, "{bad_json}");
    assert_eq!(bad_json["skipped_rows"]["non_finite"], 1, "{bad_json}");
    assert!(stderr.contains("(1e5, "), "{stderr}");
    assert_eq!(bad_json["grid"], good_json["grid"]);
    assert_eq!(bad.map, good.map);
    assert_eq!(bad.density, good.density);
    assert_eq!(bad.trajectories, good.trajectories);
    assert_eq!(bad.tracked, good.tracked);
    assert_eq!(bad.robot, good.robot);
    assert_eq!(bad.span, good.span);
}

/// `v` as `eval_tracking` prints it (`{:.4}`).
fn four(v: f64) -> f64 {
    format!("{v:.4}").parse().unwrap()
}

#[test]
fn a_replay_scores_the_shared_recording_as_the_live_session_and_publishes_its_people() {
    use haunts::bag::msg::{MarkerArray, PoseArray};
    use haunts::live::replay::Replay;
    use haunts::live::{LiveParams, LiveSession};
    use haunts::tracking::detect::static_map::StaticMapParams;
    use haunts::tracking::eval::sequence::EvalParams;

    let Some(mcap) = haunts_test_support::bag::moving_mcap() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("live.mcap");
    let json = ok(&["replay", s(&mcap), "-o", s(&out)]);

    // The library's replay of the same file (whose scores equal `evaluate_sequence`'s with
    // `eval_tracking`'s defaults, tests/live.rs), printed as `eval_tracking` prints them.
    let bag = haunts::bag::Bag::open(&mcap).unwrap();
    let replay = Replay::new(bag, &Default::default(), None).unwrap();
    let mut session = LiveSession::with_defaults(replay.params(LiveParams::default())).unwrap();
    let replayed = replay.run(&mut session, |_| Ok(())).unwrap();
    let protocol =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    let (every, annotated) = replayed.scores(&protocol).unwrap().unwrap();
    for (key, c) in [
        ("mota_every_scan", &every.scores),
        ("mota_annotated", &annotated.scores),
    ] {
        let j = &json[key];
        assert_eq!(j["mota"].as_f64().unwrap(), four(c.mota), "{json}");
        assert_eq!(j["motp"].as_f64().unwrap(), four(c.motp), "{json}");
        for (k, v) in [
            ("misses", c.misses),
            ("false_positives", c.false_positives),
            ("id_switches", c.id_switches),
            ("objects", c.ground_truth),
        ] {
            assert_eq!(j[k].as_u64().unwrap(), v as u64, "{key}.{k}: {json}");
        }
    }
    assert_eq!(json["scans"].as_u64().unwrap(), session.scans() as u64);
    assert_eq!(json["dropped"]["no_odometry"], 0, "{json}");
    let latency = &json["latency_ms"];
    let (p50, p99, max) = (
        latency["p50"].as_f64().unwrap(),
        latency["p99"].as_f64().unwrap(),
        latency["max"].as_f64().unwrap(),
    );
    assert!(0.0 < p50 && p50 <= p99 && p99 <= max, "{latency}");
    if cfg!(target_os = "linux") {
        assert!(json["peak_rss_mb"].as_f64().unwrap() > 1.0, "{json}");
    }

    // What a node would publish: one PoseArray and one MarkerArray per tracked scan, in the
    // odometry frame, the people as the session reported them.
    let published = haunts::bag::Bag::open(&out).unwrap();
    let people: Vec<PoseArray> = published
        .read::<PoseArray>("/haunts/people")
        .unwrap()
        .map(|m| m.unwrap().1)
        .collect();
    let markers = published
        .read::<MarkerArray>("/haunts/people_markers")
        .unwrap()
        .count();
    let tracked = json["tracked_scans"].as_u64().unwrap() as usize;
    assert_eq!((people.len(), markers), (tracked, tracked));
    assert_eq!(json["people_messages"].as_u64().unwrap() as usize, tracked);
    assert!(people.iter().all(|p| p.header.frame_id == "/odom"));
    let seen: usize = people.iter().map(|p| p.poses.len()).sum();
    let reported: usize = replayed.hypotheses.iter().map(|f| f.objects.len()).sum();
    assert_eq!(seen, reported);
    assert!(seen > 0);
}

/// Issue 47: a replay that closes its day folds it into the library as `haunts day` and
/// `haunts merge` would (the same maps, byte for byte), and a replay killed at any moment
/// of its close leaves the library as it was or with the day merged.
#[test]
fn a_replay_closes_its_day_as_day_and_merge_would_and_a_kill_leaves_the_old_or_new_library() {
    let dir = tempfile::tempdir().unwrap();
    let bags = dir.path().join("bags");
    ok(&["sim", "--days", "2", "--patrols", "1", "-o", s(&bags)]);
    let (bag0, bag1) = (bags.join("day_000.mcap"), bags.join("day_001.mcap"));
    let day = |bag: &Path, name: &str| {
        let out = dir.path().join(name);
        ok(&["day", s(bag), "-o", s(&out)]);
        out
    };
    let (day0, day1) = (day(&bag0, "d0.haunts"), day(&bag1, "d1.haunts"));
    let old = dir.path().join("old.haunts");
    ok(&["merge", s(&day0), "-o", s(&old)]);
    let before = std::fs::read(&old).unwrap();
    let reference = dir.path().join("reference.haunts");
    std::fs::write(&reference, &before).unwrap();
    ok(&["merge", s(&day1), "-o", s(&reference)]);

    let library = dir.path().join("live.haunts");
    std::fs::write(&library, &before).unwrap();
    let out = dir.path().join("live.mcap");
    let replay_args = [
        "replay",
        s(&bag1),
        "-o",
        s(&out),
        "--library",
        s(&library),
        "--close-day",
    ];
    let start = std::time::Instant::now();
    let json = ok(&replay_args);
    let took = start.elapsed();
    let closed = &json["closed_day"];
    assert_eq!(
        (closed["days"].as_u64(), closed["saved"].as_bool()),
        (Some(2), Some(true)),
        "{json}"
    );
    assert_eq!(closed["new_layout"], false, "{json}");
    assert!(
        !out.with_extension("day.mcap").exists(),
        "the spool was left behind"
    );
    // The costmaps published after the close are the library's new ones.
    let published = haunts::bag::Bag::open(&out).unwrap();
    let costmaps = published
        .read::<haunts::bag::msg::OccupancyGrid>("/haunts/costmap/layout_0")
        .unwrap()
        .count();
    assert_eq!(costmaps, 2, "the old costmap, then the new");
    // The same maps as `haunts day` + `haunts merge` of the same recording.
    let maps = |lib: &Path, name: &str| {
        let dir = dir.path().join(name);
        ok(&["maps", s(lib), "-o", s(&dir)]);
        ["composite", "costmap"]
            .map(|w| std::fs::read(dir.join(format!("layout_0_{w}.pgm"))).unwrap())
    };
    assert_eq!(
        maps(&library, "live_maps"),
        maps(&reference, "reference_maps")
    );

    // Killed anywhere in the second half of the run (the close and its save among it).
    let (mut unchanged, mut merged) = (0, 0);
    for k in 0..16u32 {
        std::fs::write(&library, &before).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_haunts"))
            .args(replay_args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(took / 2 + took * k / 28);
        let _ = child.kill();
        let _ = child.wait();
        if std::fs::read(&library).unwrap() == before {
            unchanged += 1;
        } else {
            assert_eq!(stored_days(&library), 2, "kill {k}: a partial library");
            merged += 1;
        }
    }
    eprintln!("16 kills: {unchanged} left the library as it was, {merged} with the day");
}
