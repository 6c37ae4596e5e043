//! What the `leg_tracker`, `trajectory` and `detections` fuzz targets do with an input, shared
//! with `tracking/tests/fuzz_regressions.rs` and `affordance/tests/fuzz_regressions.rs` so
//! that saved inputs replay exactly as fuzzed.
//!
//! **Byte 0 is the configuration**, the rest is the file's text (any bytes):
//! - `leg_tracker`: bits 0–1 pick the reader (0 `parse_scans`, 1 `parse_odometry`,
//!   2 `parse_static_transforms`, 3 `parse_ground_truth`).
//! - `trajectory`: bit 0 picks ETH `parse_eth` (1) or `parse_delimited` (0). ETH: bit 1 gives
//!   a frame rate of 25 Hz (else the rate is guessed). Delimited: bits 1–2 the delimiter
//!   (whitespace, `,`, `;`, tab), bit 3 one header line, bits 4–5 the columns
//!   (`0 1 2 3`, ETH's `0 1 2 4`, reversed `3 2 1 0`, `0 1 2 1000`).
//! - `detections` (`haunts_affordance`, see `affordance_check.rs`): the same bits 1–5.
//!
//! Every reader works from memory, so only values come back (an I/O error is a failure);
//! the invariants that hold for any input are asserted here.
#![allow(dead_code)]

use haunts_tracking::io::leg_tracker::{
    parse_ground_truth, parse_odometry, parse_scans, parse_static_transforms,
};
use haunts_tracking::io::trajectory::{
    DelimitedOptions, Delimiter, EthOptions, parse_delimited, parse_eth,
};
use haunts_tracking::{KEEP_SKIPPED, Parsed};

/// Splits an input into its configuration byte and the file (an empty input is an empty
/// file with configuration 0).
pub fn split(data: &[u8]) -> (u8, &[u8]) {
    match data.split_first() {
        Some((&config, rest)) => (config, rest),
        None => (0, &[]),
    }
}

/// The delimiter of configuration bits 1–2.
pub fn delimiter(config: u8) -> Delimiter {
    match (config >> 1) & 3 {
        0 => Delimiter::Whitespace,
        1 => Delimiter::Char(','),
        2 => Delimiter::Char(';'),
        _ => Delimiter::Char('\t'),
    }
}

/// The header lines of configuration bit 3.
pub fn header_lines(config: u8) -> usize {
    usize::from(config & 8 != 0)
}

/// Four columns of configuration bits 4–5.
pub fn columns(config: u8) -> [usize; 4] {
    match (config >> 4) & 3 {
        0 => [0, 1, 2, 3],
        1 => [0, 1, 2, 4],
        2 => [3, 2, 1, 0],
        _ => [0, 1, 2, 1000],
    }
}

/// Lines of a file as the readers count them.
pub fn line_count(file: &[u8]) -> usize {
    file.split(|&b| b == b'\n').count() - usize::from(file.ends_with(b"\n") || file.is_empty())
}

/// The invariants of any `Parsed`: line numbers within the file and increasing, skips
/// counted and the first ones kept; returns the number of records.
pub fn check_parsed<T>(parsed: &Parsed<T>, lines: usize, line_of: impl Fn(&T) -> Option<usize>) {
    assert_eq!(
        parsed.first_skipped.len(),
        parsed.skipped.min(KEEP_SKIPPED),
        "skips counted and kept"
    );
    assert!(parsed.skipped <= lines);
    assert!(
        parsed
            .first_skipped
            .windows(2)
            .all(|w| w[0].line < w[1].line)
    );
    assert!(
        parsed
            .first_skipped
            .iter()
            .all(|s| (1..=lines).contains(&s.line))
    );
    let numbered: Vec<usize> = parsed.records.iter().filter_map(&line_of).collect();
    assert!(
        numbered.windows(2).all(|w| w[0] < w[1]),
        "records in file order"
    );
    assert!(numbered.iter().all(|l| (1..=lines).contains(l)));
    if !numbered.is_empty() {
        assert!(numbered.len() + parsed.skipped <= lines);
    }
}

/// Runs the `leg_tracker` target on an input; returns (records, skipped).
pub fn leg_tracker(data: &[u8]) -> (usize, usize) {
    let (config, file) = split(data);
    let lines = line_count(file);
    let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
    match config & 3 {
        0 => {
            let p = parse_scans(file).expect("in-memory read");
            check_parsed(&p, lines, |r| Some(r.line));
            for r in &p.records {
                assert!(finite(&[r.bag_time, r.scan.stamp]));
                assert!(!r.frame.is_empty());
                assert!(r.scan.clone().check().is_ok(), "invalid scan kept: {r:?}");
            }
            (p.records.len(), p.skipped)
        }
        1 => {
            let p = parse_odometry(file).expect("in-memory read");
            check_parsed(&p, lines, |r| Some(r.line));
            for r in &p.records {
                let t = r.pose.translation.vector;
                assert!(finite(&[
                    r.bag_time,
                    r.stamp,
                    t.x,
                    t.y,
                    r.pose.rotation.angle()
                ]));
            }
            (p.records.len(), p.skipped)
        }
        2 => {
            let p = parse_static_transforms(file).expect("in-memory read");
            check_parsed(&p, lines, |r| Some(r.line));
            for r in &p.records {
                let t = r.transform.translation.vector;
                assert!(finite(&[t.x, t.y, r.transform.rotation.angle()]));
                assert!(!r.parent.is_empty() && !r.child.is_empty());
            }
            (p.records.len(), p.skipped)
        }
        _ => {
            let p = parse_ground_truth(file).expect("in-memory read");
            check_parsed(&p, lines, |r| Some(r.line));
            for r in &p.records {
                assert!(finite(&[r.bag_time, r.position.x, r.position.y]));
            }
            (p.records.len(), p.skipped)
        }
    }
}

/// Runs the `trajectory` target on an input; returns (trajectories, samples, skipped).
pub fn trajectory(data: &[u8]) -> (usize, usize, usize) {
    let (config, file) = split(data);
    let lines = line_count(file);
    let parsed = if config & 1 == 1 {
        let options = if config & 2 != 0 {
            EthOptions::default().with_frame_rate(25.0)
        } else {
            EthOptions::default()
        };
        parse_eth(file, &options).expect("valid options, in-memory read")
    } else {
        let [t, id, x, y] = columns(config);
        let options = DelimitedOptions::default()
            .with_columns(t, id, x, y)
            .with_delimiter(delimiter(config))
            .with_header_lines(header_lines(config));
        parse_delimited(file, &options).expect("valid options, in-memory read")
    };
    check_parsed(&parsed, lines, |_| None);
    let samples: usize = parsed.records.iter().map(|t| t.samples.len()).sum();
    assert!(samples + parsed.skipped <= lines);
    assert!(
        parsed.records.windows(2).all(|w| w[0].id < w[1].id),
        "ids sorted, distinct"
    );
    for t in &parsed.records {
        assert!(!t.samples.is_empty());
        assert!(
            t.samples.windows(2).all(|w| w[0].0 <= w[1].0),
            "sorted by time"
        );
        for (time, p) in &t.samples {
            assert!(time.is_finite() && p.x.is_finite() && p.y.is_finite());
        }
    }
    (parsed.records.len(), samples, parsed.skipped)
}
