//! Reading a recorded sequence for the examples: a `leg_tracker` text folder, a ROS 1 bag or a
//! ROS 2 MCAP file, with topics named by flags or chosen automatically.

use std::path::Path;

use haunts::bag::msg::{Message, Person};
use haunts::bag::{Bag, RecordingOptions};
use haunts::tracking::eval::sequence::Sequence;

/// Topics of a bag, as the examples' flags name them (`None`: chosen automatically).
#[derive(Debug, Clone, Default)]
pub struct Topics {
    /// `--scan-topic`.
    pub scan: Option<String>,
    /// `--odom-topic`.
    pub odom: Option<String>,
    /// `--ground-truth-topic`.
    pub ground_truth: Option<String>,
    /// `--base-frame`.
    pub base_frame: Option<String>,
}

impl Topics {
    /// Takes `flag`'s value from `args` if `flag` is one of the topic flags.
    pub fn take(&mut self, flag: &str, args: &mut impl Iterator<Item = String>) -> Option<bool> {
        let slot = match flag {
            "--scan-topic" => &mut self.scan,
            "--odom-topic" => &mut self.odom,
            "--ground-truth-topic" => &mut self.ground_truth,
            _ => return None,
        };
        *slot = args.next();
        Some(slot.is_some())
    }
}

/// The sequence at `path`: a folder of `leg_tracker` text files, or a `.bag` / `.mcap` file
/// (read through `haunts-bag`; its notes go to stderr).
pub fn read_sequence(path: &str, topics: &Topics) -> Result<Sequence, Box<dyn std::error::Error>> {
    if Path::new(path).is_dir() {
        return Ok(Sequence::read(path)?);
    }
    let bag = Bag::open(path)?;
    let mut options = RecordingOptions::new();
    if let Some(t) = &topics.scan {
        options = options.with_scan_topic(t);
    }
    if let Some(t) = &topics.odom {
        options = options.with_odom_topic(t);
    }
    if let Some(f) = &topics.base_frame {
        options = options.with_base_frame(f);
    }
    let recording = bag.recording(&options)?;
    for note in recording.notes() {
        eprintln!("note: {note}");
    }
    let truth_topic =
        haunts::live::replay::ground_truth_topic(&bag, topics.ground_truth.as_deref())?;
    let mut ground_truth = Vec::new();
    match &truth_topic {
        None => eprintln!(
            "note: no {} topic: nothing to score against",
            Person::ROS2_TYPE
        ),
        Some(topic) => {
            eprintln!("note: ground truth from {topic}");
            ground_truth = haunts::live::replay::ground_truth(&bag, topic)?;
        }
    }
    Ok(Sequence::from_recording(&recording, ground_truth)?)
}
