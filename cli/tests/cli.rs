//! The `haunts` command end to end on simulated bags: sim → day → merge → maps, merging twice,
//! days on other cells, and corrupt, truncated and newer-version day artifacts.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Runs `haunts ARGS`; its success and its last stdout line as JSON (or stderr on failure).
fn haunts(args: &[&str]) -> (bool, Value, String) {
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
    (out.status.success(), json, stderr)
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
    let bags = dir.join("bags");
    let sim = ok(&["sim", "--days", "2", "--patrols", "1", "-o", s(&bags)]);
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

    // A day on other cells (the default grid of its own odometry) is refused, reported, and
    // the library is unchanged.
    let other = dir.path().join("other.haunts");
    let bag = dir.path().join("bags/day_001.mcap");
    ok(&["day", s(&bag), "-o", s(&other), "--label", "elsewhere"]);
    let refused = ok(&["merge", s(&other), "-o", s(&library)]);
    assert_eq!(refused["refused"].as_array().unwrap().len(), 1, "{refused}");
    assert!(
        refused["refused"][0]["reason"]
            .as_str()
            .unwrap()
            .contains("lies on"),
        "{refused}"
    );
    assert_eq!(std::fs::read(&library).unwrap(), before);

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
    }
    let bag = haunts::bag::Bag::open(maps.join("maps.mcap")).unwrap();
    let grids = bag.topics_of::<haunts::bag::msg::OccupancyGrid>().len();
    assert_eq!(grids, 3 * layouts);
    let page = std::fs::read_to_string(maps.join("index.html")).unwrap();
    assert_eq!(page.matches("<img src=\"layout_").count(), layouts);
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
