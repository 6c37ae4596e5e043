//! Fuzzes `carmen::parse_carmen` with the default options and checks the log it returns.
#![no_main]

use haunts_occupancy::carmen::{CarmenOptions, LaserKind, parse_carmen};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let options = CarmenOptions::default();
    // Reading from memory cannot fail: only I/O errors are errors.
    let log = match parse_carmen(data, &options) {
        Ok(log) => log,
        Err(e) => panic!("in-memory parse returned an I/O error: {e}"),
    };
    let lines = data.split(|&b| b == b'\n').count() - usize::from(data.ends_with(b"\n"));
    let others: usize = log.other_messages.values().sum();
    assert!(log.scans.len() + log.odometry.len() + log.skipped + others <= lines);
    assert_eq!(
        log.first_skipped.len(),
        log.skipped.min(options.keep_skipped)
    );
    assert!(log.first_skipped.windows(2).all(|w| w[0].line < w[1].line));
    assert!(log.scans.windows(2).all(|w| w[0].line < w[1].line));
    assert!(log.odometry.windows(2).all(|w| w[0].line < w[1].line));
    for s in &log.scans {
        assert!((1..=lines).contains(&s.line));
        assert!(s.scan.clone().check().is_ok(), "invalid scan kept: {s:?}");
        assert!(s.scan.stamp.is_finite());
        if s.kind != LaserKind::Robot {
            assert!(s.scan.intensities.is_empty());
            assert_eq!(s.scan.range_max, options.max_range);
        }
        for p in [&s.laser_pose, &s.robot_pose] {
            assert!(p.translation.vector.iter().all(|v| v.is_finite()));
            assert!(p.rotation.angle().is_finite());
        }
    }
    for o in &log.odometry {
        assert!((1..=lines).contains(&o.line));
        assert!(o.stamp.is_finite());
        assert!(o.pose.translation.vector.iter().all(|v| v.is_finite()));
    }
});
