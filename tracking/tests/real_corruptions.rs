//! Skips stay skips: one malformed line in any file of the real `leg_tracker` recording
//! (`general_tracking_moving_1`) is one counted skip, and the evaluation still runs and scores
//! about what the clean files score. Skipped with a notice when `../shared/data` is absent.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use haunts_tracking::detect::{LegDetector, LegDetectorParams};
use haunts_tracking::eval::mot::truth_frames_for_scans;
use haunts_tracking::eval::sequence::{EvalParams, EvalReport, Sequence, evaluate_sequence};
use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};

use data::shared_data;
use haunts_test_support::data;

const FILES: [&str; 4] = [
    "scans.txt",
    "ground_truth_people.txt",
    "odom.txt",
    "static_tf.txt",
];

fn evaluate(sequence: &Sequence) -> EvalReport {
    let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    let mut tracker = KalmanTracker::new(KalmanParams::default()).unwrap();
    evaluate_sequence(
        sequence,
        &detector,
        &mut tracker,
        &EvalParams::leg_tracker_benchmarks(),
    )
    .unwrap_or_else(|e| panic!("one bad line made the evaluation fail: {e}"))
}

/// A copy of the recording in a fresh folder, with `field` of line `line` (1-based) of
/// `file` replaced by `nan`.
fn corrupted(source: &Path, file: &str, line: usize, field: usize) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "haunts-corrupt-{}-{file}-{line}-{field}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for name in FILES {
        let text = std::fs::read_to_string(source.join(name)).unwrap();
        let text = if name == file {
            let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
            let mut fields: Vec<&str> = lines[line - 1].split_whitespace().collect();
            fields[field] = "nan";
            lines[line - 1] = fields.join(" ");
            lines.join("\n") + "\n"
        } else {
            text
        };
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

#[test]
fn one_nan_field_in_any_file_is_one_counted_skip_and_the_evaluation_runs() {
    let Some(scans) = shared_data("leg_tracker/general_tracking_moving_1/scans.txt") else {
        return;
    };
    let source = scans.parent().unwrap();
    let clean = Sequence::read(source).unwrap();
    assert_eq!(clean.skipped_lines, 0);
    let reference = evaluate(&clean);
    assert_eq!((reference.scans, reference.unassigned_truth), (873, 0));

    // Scans whose annotations share an id with the scan before: skipping one of them used
    // to move its annotations there and fail ("id appears more than once in the frame").
    let times: Vec<f64> = clean.scans.iter().map(|s| s.bag_time).collect();
    let frames = truth_frames_for_scans(&times, &clean.ground_truth)
        .unwrap()
        .frames;
    let shared: Vec<usize> = (1..frames.len())
        .filter(|&k| {
            frames[k]
                .objects
                .iter()
                .any(|o| frames[k - 1].objects.iter().any(|p| p.0 == o.0))
        })
        .take(4)
        .collect();
    assert_eq!(shared.len(), 4);
    // File line of scan k: one comment line first. The header stamp (field 1) or the bag time
    // (field 0) made NaN; the first and last scans and one nobody annotated besides.
    let mut cases: Vec<(&str, usize, usize)> =
        shared.iter().map(|&k| ("scans.txt", k + 2, 1)).collect();
    cases.extend([
        ("scans.txt", 2, 0),
        ("scans.txt", 874, 1),
        ("scans.txt", 12, 0),
        ("ground_truth_people.txt", 2, 2),
        ("ground_truth_people.txt", 77, 0),
        ("ground_truth_people.txt", 154, 3),
        ("odom.txt", 2, 2),
        ("odom.txt", 5000, 4),
        ("odom.txt", 11_562, 1),
    ]);
    for (file, line, field) in cases {
        let dir = corrupted(source, file, line, field);
        let sequence = Sequence::read(&dir).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(sequence.skipped_lines, 1, "{file}:{line}");
        let report = evaluate(&sequence);
        let what = format!("{file}:{line} field {field}: {:?}", report.scores);
        let scans_lost = usize::from(file == "scans.txt");
        assert_eq!(report.scans, 873 - scans_lost, "{what}");
        let truth_lost = usize::from(file == "ground_truth_people.txt");
        // Every annotation is scored, or counted as scored nowhere.
        let counted = report.scores.ground_truth + report.unassigned_truth + truth_lost;
        assert!(counted >= reference.scores.ground_truth, "{what}");
        assert!(report.unassigned_truth <= 3, "{what}");
        assert!(
            (report.scores.mota - reference.scores.mota).abs() <= 0.05,
            "{what} vs {:?}",
            reference.scores
        );
    }

    assert!(reference.mounts_assumed.is_empty());

    // The laser's mount is the one line of static_tf.txt: skipped and counted, the run goes
    // on with the laser at the robot's origin, and the report says so.
    let dir = corrupted(source, "static_tf.txt", 2, 2);
    let sequence = Sequence::read(&dir).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(
        (sequence.skipped_lines, sequence.static_transforms.len()),
        (1, 0)
    );
    let report = evaluate(&sequence);
    assert_eq!(report.scans, 873);
    assert_eq!(report.mounts_assumed, vec!["left_laser".to_owned()]);
}
