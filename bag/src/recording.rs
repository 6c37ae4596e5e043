//! A [`Recording`] from a bag: which topics, chosen automatically (and said) or named.

use std::collections::BTreeMap;

use haunts_occupancy::recording::{RecordedScan, Recording, ScanSource, Scans};
use haunts_occupancy::{OccupancyError, Pose2};
use haunts_occupancy::{PoseHistory, TransformTree};

use crate::convert::{laser_scan, occupancy_grid, pose2};
use crate::map_frame::{self, MapFrame};
use crate::msg::{self, Message};
use crate::{Bag, BagError, Result, TopicInfo};

/// Which topics of a bag make its [`Recording`]. Every topic left `None` is chosen
/// automatically, and the recording's notes say what was chosen.
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct RecordingOptions {
    /// The `LaserScan` topic (default: the only one, or `/scan` among several).
    pub scan_topic: Option<String>,
    /// The `Odometry` topic (default: the only one, or `/odom` among several; none is fine).
    pub odom_topic: Option<String>,
    /// The transform topics (default: `/tf` and `/tf_static`, those that exist).
    pub tf_topics: Option<Vec<String>>,
    /// The `OccupancyGrid` topic whose first message is the map (default: the only one, or
    /// `/map`; none is fine).
    pub map_topic: Option<String>,
    /// The robot's base frame (default: the odometry's child frame, else `base_link`).
    pub base_frame: Option<String>,
    /// The frame of the robot's poses (default [`MapFrame::Auto`]: `map` when the transforms
    /// link it to the odometry frame, else the odometry frame).
    pub map_frame: MapFrame,
}

/// The topics of a bag that make its [`Recording`] ([`Bag::recording_topics`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct RecordingTopics {
    /// The `LaserScan` topic.
    pub scan: String,
    /// The `Odometry` topic, when there is one.
    pub odom: Option<String>,
    /// The `OccupancyGrid` topic of the map, when there is one.
    pub map: Option<String>,
    /// The transform topics (those ending in `tf_static` hold static transforms).
    pub tf: Vec<String>,
}

impl RecordingOptions {
    /// Automatic choices throughout.
    pub fn new() -> Self {
        Self::default()
    }

    /// Reads scans from `topic`.
    pub fn with_scan_topic(mut self, topic: impl Into<String>) -> Self {
        self.scan_topic = Some(topic.into());
        self
    }

    /// Reads odometry from `topic`.
    pub fn with_odom_topic(mut self, topic: impl Into<String>) -> Self {
        self.odom_topic = Some(topic.into());
        self
    }

    /// Reads transforms from `topics`.
    pub fn with_tf_topics(mut self, topics: Vec<String>) -> Self {
        self.tf_topics = Some(topics);
        self
    }

    /// Reads the map from `topic`.
    pub fn with_map_topic(mut self, topic: impl Into<String>) -> Self {
        self.map_topic = Some(topic.into());
        self
    }

    /// Names the robot's base frame.
    pub fn with_base_frame(mut self, frame: impl Into<String>) -> Self {
        self.base_frame = Some(frame.into());
        self
    }

    /// Puts the robot's poses in `map_frame` (or keeps raw odometry with [`MapFrame::Off`]).
    pub fn with_map_frame(mut self, map_frame: MapFrame) -> Self {
        self.map_frame = map_frame;
        self
    }
}

/// The topic of type `T` to read: the one named, the only one, or `preferred` among several.
/// `required` makes "none" an error.
fn choose<'a, T: Message>(
    bag: &'a Bag,
    named: Option<&str>,
    preferred: &str,
    required: bool,
    notes: &mut Vec<String>,
) -> Result<Option<&'a TopicInfo>> {
    if let Some(name) = named {
        let info = bag.topic(name)?;
        crate::read::check_type::<T>(info)?;
        return Ok(Some(info));
    }
    let candidates = bag.topics_of::<T>();
    let kind = T::ROS2_TYPE;
    let chosen = match candidates.as_slice() {
        [] if required => {
            return Err(BagError::TopicChoice {
                path: bag.path().to_path_buf(),
                what: format!("no topic of type {kind}"),
            });
        }
        [] => {
            notes.push(format!("no {kind} topic"));
            return Ok(None);
        }
        [only] => *only,
        several => match several.iter().find(|t| t.name == preferred) {
            Some(t) => *t,
            None => {
                let names: Vec<&str> = several.iter().map(|t| t.name.as_str()).collect();
                return Err(BagError::TopicChoice {
                    path: bag.path().to_path_buf(),
                    what: format!(
                        "{} topics of type {kind}: {}; name one",
                        names.len(),
                        names.join(", ")
                    ),
                });
            }
        },
    };
    crate::read::check_type::<T>(chosen)?;
    notes.push(format!(
        "{kind} from {} (chosen automatically)",
        chosen.name
    ));
    Ok(Some(chosen))
}

/// The scans of one `LaserScan` topic of a bag, read from the file on each iteration.
#[derive(Debug, Clone)]
pub(crate) struct BagScans {
    bag: Bag,
    topic: String,
    count: Option<u64>,
}

impl BagScans {
    /// The scans of `topic` (its type is checked).
    ///
    /// # Errors
    /// [`BagError::NoSuchTopic`], [`BagError::TypeMismatch`], [`BagError::Md5Mismatch`].
    pub(crate) fn new(bag: Bag, topic: &str) -> Result<Self> {
        let info = bag.topic(topic)?;
        crate::read::check_type::<msg::LaserScan>(info)?;
        let count = info.count;
        Ok(Self {
            bag,
            topic: topic.to_owned(),
            count,
        })
    }
}

impl ScanSource for BagScans {
    fn scans(&self) -> haunts_occupancy::Result<Scans<'_>> {
        let wrap = |e: BagError| OccupancyError::ScanSource {
            what: format!("{} topic {}", self.bag.path().display(), self.topic),
            source: Box::new(e),
        };
        let messages = self.bag.read::<msg::LaserScan>(&self.topic).map_err(wrap)?;
        let topic = self.topic.clone();
        Ok(Box::new(messages.enumerate().map(move |(i, m)| {
            let (received, m) = m.map_err(wrap)?;
            let scan = laser_scan(&m).map_err(|what| {
                wrap(BagError::InvalidMessage {
                    topic: topic.clone(),
                    index: i as u64,
                    what,
                })
            })?;
            Ok(RecordedScan {
                scan,
                frame: m.header.frame_id,
                received,
            })
        })))
    }

    fn len_hint(&self) -> Option<usize> {
        self.count.and_then(|c| usize::try_from(c).ok())
    }
}

/// The samples of each link of a set of `TFMessage` topics: (parent, child) → (time, pose).
type LinkSamples = BTreeMap<(String, String), Vec<(f64, Pose2)>>;

impl Bag {
    /// The topics a [`Recording`] of this bag is read from with `options`: named ones checked,
    /// the others chosen as [`Bag::recording`] chooses them, with notes saying what was
    /// chosen: for a reader that streams the same topics (a live replay).
    ///
    /// # Errors
    /// As [`Bag::recording`]'s choice of topics.
    pub fn recording_topics(
        &self,
        options: &RecordingOptions,
    ) -> Result<(RecordingTopics, Vec<String>)> {
        let mut notes = Vec::new();
        let topics = self.choose_topics(options, &mut notes)?;
        Ok((topics, notes))
    }

    fn choose_topics(
        &self,
        options: &RecordingOptions,
        notes: &mut Vec<String>,
    ) -> Result<RecordingTopics> {
        let scan =
            choose::<msg::LaserScan>(self, options.scan_topic.as_deref(), "/scan", true, notes)?
                .map(|t| t.name.clone())
                .unwrap_or_default();
        let odom =
            choose::<msg::Odometry>(self, options.odom_topic.as_deref(), "/odom", false, notes)?
                .map(|t| t.name.clone());
        let map =
            choose::<msg::OccupancyGrid>(self, options.map_topic.as_deref(), "/map", false, notes)?
                .map(|t| t.name.clone());
        let tf = match &options.tf_topics {
            Some(named) => {
                for t in named {
                    crate::read::check_type::<msg::TfMessage>(self.topic(t)?)?;
                }
                named.clone()
            }
            None => ["/tf", "/tf_static"]
                .into_iter()
                .filter(|t| {
                    self.topic(t)
                        .is_ok_and(|i| crate::read::check_type::<msg::TfMessage>(i).is_ok())
                })
                .map(str::to_owned)
                .collect(),
        };
        Ok(RecordingTopics {
            scan,
            odom,
            map,
            tf,
        })
    }

    /// The recording in this bag: scans streamed from the scan topic, odometry, transforms
    /// and map read now (they are small next to the scans).
    ///
    /// Transforms: links of `/tf_static` are static; a link of `/tf` whose every sample is the
    /// same pose is taken as static too (ROS 1 bags carry fixed mounts on `/tf`), the others
    /// move, interpolated in time by their header stamps. Messages that do not decode or
    /// convert are skipped, and the notes count them.
    ///
    /// Poses: with a map frame ([`RecordingOptions::map_frame`]; by default `map` when the
    /// transforms hold map → odom, as AMCL and slam_toolbox publish it) the odometry becomes
    /// the base's pose in the map frame, `(map ← odom)(t) · (odom ← base)(t)` at each
    /// odometry stamp `t`, map → odom interpolated between its samples and held at its first
    /// or last one outside their span; [`Recording::odom_frame`] is then the map frame, and
    /// the notes say so and count the held stamps.
    ///
    /// # Errors
    /// [`BagError::TopicChoice`] when there is no scan topic, or several and none named;
    /// the errors of the topics named; [`BagError::Occupancy`] for conflicting transforms;
    /// [`BagError::NoMapFrame`] when a map frame named is not linked to the odometry frame.
    pub fn recording(&self, options: &RecordingOptions) -> Result<Recording> {
        let mut notes = Vec::new();
        let RecordingTopics {
            scan,
            odom,
            map,
            tf: tf_topics,
        } = self.choose_topics(options, &mut notes)?;

        let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
        let mut skip = |topic: &str| *skipped.entry(topic.to_owned()).or_insert(0) += 1;

        // Odometry: the pose of the child frame in the header's frame, by header stamp.
        let mut odometry = None;
        let mut frames = (String::from("odom"), String::from("base_link"));
        if let Some(topic) = &odom {
            let (mut samples, mut named) = (Vec::new(), false);
            for m in self.read::<msg::Odometry>(topic)? {
                let Ok((_, m)) = m else {
                    skip(topic);
                    continue;
                };
                match pose2(&m.pose.pose.position, &m.pose.pose.orientation) {
                    Ok(p) => {
                        if !named {
                            frames = (m.header.frame_id.clone(), m.child_frame_id.clone());
                            named = true;
                        }
                        samples.push((m.header.stamp.seconds(), p));
                    }
                    // A NaN or infinite position goes into the history as it is, which
                    // counts it (`PoseHistory::skipped_non_finite`: the `non_finite` of the
                    // day's `skipped_rows`); an orientation without a heading is skipped here.
                    Err(_)
                        if !(m.pose.pose.position.x.is_finite()
                            && m.pose.pose.position.y.is_finite()) =>
                    {
                        let p = m.pose.pose.position;
                        let pose = Pose2::from_parts(
                            nalgebra::Translation2::new(p.x, p.y),
                            nalgebra::UnitComplex::identity(),
                        );
                        samples.push((m.header.stamp.seconds(), pose));
                    }
                    Err(_) => skip(topic),
                }
            }
            match PoseHistory::new(samples) {
                Ok(h) => odometry = Some(h),
                Err(_) => notes.push(format!("{topic}: no usable odometry message")),
            }
        }
        let base = options
            .base_frame
            .clone()
            .unwrap_or_else(|| frames.1.clone());

        // Transforms.
        let mut statics: LinkSamples = BTreeMap::new();
        let mut moving: LinkSamples = BTreeMap::new();
        for topic in &tf_topics {
            let is_static = topic.ends_with("tf_static");
            for m in self.read::<msg::TfMessage>(topic)? {
                let Ok((_, m)) = m else {
                    skip(topic);
                    continue;
                };
                for t in m.transforms {
                    let Ok(p) = pose2(&t.transform.translation, &t.transform.rotation) else {
                        skip(topic);
                        continue;
                    };
                    let key = (t.header.frame_id, t.child_frame_id);
                    let target = if is_static { &mut statics } else { &mut moving };
                    target
                        .entry(key)
                        .or_default()
                        .push((t.header.stamp.seconds(), p));
                }
            }
        }
        let mut tree = TransformTree::new();
        for ((parent, child), samples) in &statics {
            if let Some((_, last)) = samples.last() {
                tree.add_static(parent, child, *last)?;
            }
        }
        for ((parent, child), samples) in moving {
            let fixed = samples.windows(2).all(|w| w[0].1 == w[1].1);
            if fixed && let Some((_, pose)) = samples.first() {
                notes.push(format!(
                    "{parent} → {child}: {} identical /tf samples, taken as static",
                    samples.len()
                ));
                tree.add_static(&parent, &child, *pose)?;
            } else if statics.contains_key(&(parent.clone(), child.clone())) {
                notes.push(format!(
                    "{parent} → {child}: on /tf and /tf_static; /tf_static kept"
                ));
            } else if let Ok(history) = PoseHistory::new(samples) {
                tree.add_moving(&parent, &child, history)?;
            }
        }

        // The frame of the poses: a map frame above the odometry's, when there is one.
        let (odometry, pose_frame) = map_frame::apply(
            &options.map_frame,
            &tree,
            &frames.0,
            odometry,
            self.path(),
            &mut notes,
        )?;

        // The map: the first message that converts.
        let mut grid = None;
        if let Some(topic) = &map {
            for m in self.read::<msg::OccupancyGrid>(topic)? {
                match m.ok().map(|(_, m)| occupancy_grid(&m)) {
                    Some(Ok(g)) => {
                        grid = Some(g);
                        break;
                    }
                    _ => skip(topic),
                }
            }
        }

        let scans = BagScans::new(self.clone(), &scan)?;
        let mut recording = Recording::new(scans).with_transforms(tree);
        recording = match odometry {
            Some(h) => recording.with_odometry(h, &pose_frame, &base),
            None => recording
                .with_base_frame(&base)
                .with_note("no odometry: scans stay in their own frame"),
        };
        if let Some(g) = grid {
            recording = recording.with_map(g);
        }
        if tf_topics.is_empty() {
            notes.push(
                "no transform topic: sensors are taken as mounted at the base frame's origin"
                    .to_owned(),
            );
        }
        for (topic, n) in skipped {
            notes.push(format!(
                "{topic}: {n} messages skipped (did not decode or convert)"
            ));
        }
        for note in self.notes().iter().chain(&notes) {
            recording = recording.with_note(note.clone());
        }
        Ok(recording)
    }
}
