//! What the `bag_ros1` and `bag_mcap` fuzz targets do with a file, shared with
//! `bag/tests/fuzz_regressions.rs` so that saved inputs replay exactly as fuzzed: open it,
//! list its topics, read every message of every topic raw, decode the topics whose type is a
//! built-in message, build its recording and iterate its scans. Everything must end in values
//! or typed errors; the invariants that hold for any file are asserted here.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::Path;

use haunts_bag::msg::{
    LaserScan, MarkerArray, Message, OccupancyGrid, Odometry, Path as PathMsg, PoseArray,
    PoseStamped, TfMessage,
};
use haunts_bag::{Bag, BagError, Format, RecordingOptions};

/// What was read from a file that opened.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Outcome {
    /// Its format.
    pub format: Option<Format>,
    /// Its topics.
    pub topics: usize,
    /// Raw messages read (of all topics).
    pub raw: u64,
    /// Errors met while reading raw messages.
    pub raw_errors: u64,
    /// Messages of built-in types decoded.
    pub decoded: u64,
    /// Items that were errors while decoding.
    pub decode_errors: u64,
    /// Whether `recording` built a recording (`None`: it returned an error).
    pub recording: Option<bool>,
    /// Scans the recording yielded.
    pub scans: u64,
    /// Scans that were errors.
    pub scan_errors: u64,
}

/// Decodes every message of the topics of type `T`, counting values and errors.
fn decode_all<T: Message>(bag: &Bag, out: &mut Outcome) {
    let names: Vec<String> = bag
        .topics_of::<T>()
        .iter()
        .map(|t| t.name.clone())
        .collect();
    for name in names {
        // Type or MD5 mismatch: a typed error, nothing to iterate.
        let Ok(items) = bag.read::<T>(&name) else {
            continue;
        };
        for item in items {
            match item {
                Ok(_) => out.decoded += 1,
                Err(_) => out.decode_errors += 1,
            }
        }
    }
}

/// Runs every reader of `haunts-bag` over the file at `path`.
///
/// # Errors
/// The error of `Bag::open` (the only step whose error ends the run).
pub fn exercise(path: &Path) -> Result<Outcome, BagError> {
    let bag = Bag::open(path)?;
    let mut out = Outcome {
        format: Some(bag.format()),
        topics: bag.topics().len(),
        ..Outcome::default()
    };
    let names: Vec<&str> = bag.topics().iter().map(|t| t.name.as_str()).collect();
    assert!(
        names.windows(2).all(|w| w[0] < w[1]),
        "topics not sorted and distinct"
    );
    for t in bag.topics() {
        assert!(bag.topic(&t.name).is_ok());
    }
    assert!(bag.topic("\u{0}not a topic").is_err());
    // Every message of every topic, raw: topics are the ones asked for, indices count up.
    let mut next_index: BTreeMap<String, u64> = BTreeMap::new();
    match bag.messages(&names) {
        Ok(messages) => {
            for m in messages {
                match m {
                    Ok(m) => {
                        assert!(names.contains(&&*m.topic), "unasked topic {}", m.topic);
                        let next = next_index.entry(m.topic.to_string()).or_insert(0);
                        assert_eq!(m.index, *next, "index of a message of {}", m.topic);
                        *next += 1;
                        out.raw += 1;
                    }
                    Err(_) => out.raw_errors += 1,
                }
            }
        }
        // The file changed under us (it cannot here) or a topic vanished: both wrong.
        Err(e) => panic!("messages() of listed topics failed: {e}"),
    }
    decode_all::<LaserScan>(&bag, &mut out);
    decode_all::<Odometry>(&bag, &mut out);
    decode_all::<TfMessage>(&bag, &mut out);
    decode_all::<OccupancyGrid>(&bag, &mut out);
    decode_all::<PoseArray>(&bag, &mut out);
    decode_all::<PathMsg>(&bag, &mut out);
    decode_all::<PoseStamped>(&bag, &mut out);
    decode_all::<MarkerArray>(&bag, &mut out);
    match bag.recording(&RecordingOptions::default()) {
        Ok(recording) => {
            out.recording = Some(true);
            if let Ok(scans) = recording.scans() {
                for s in scans {
                    match s {
                        Ok(_) => out.scans += 1,
                        Err(_) => out.scan_errors += 1,
                    }
                }
            }
        }
        Err(_) => out.recording = Some(false),
    }
    Ok(out)
}

/// Writes `data` to a file in `/dev/shm` (or the temporary folder) unique to this process and
/// runs [`exercise`] on it.
pub fn exercise_bytes(data: &[u8]) -> Result<Outcome, BagError> {
    let dir = if Path::new("/dev/shm").is_dir() {
        std::path::PathBuf::from("/dev/shm")
    } else {
        std::env::temp_dir()
    };
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = dir.join(format!("haunts-bag-fuzz-{}-{n}", std::process::id()));
    std::fs::write(&path, data).expect("writing the input file");
    let out = exercise(&path);
    std::fs::remove_file(&path).ok();
    out
}
