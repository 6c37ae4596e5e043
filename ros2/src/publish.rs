//! A recording published onto its own topics over DDS, at its own pace (or faster), with
//! `/clock`: what `haunts replay REC --dds` runs, and how the node is tested without a robot.
//!
//! Scans, odometry and transforms are read from the topics [`Bag::recording_topics`] chooses
//! (as `haunts replay` reads them), streamed one chunk at a time, decoded and published on
//! the same topic names in log-time order; `/tf_static` topics transient local, as `tf2`
//! publishes them. Before each message whose log time is later than the last, `/clock`
//! carries its log time, so that a node with `use_sim_time` sees the arrival times the
//! recording logged.

use std::time::{Duration, Instant};

use haunts::bag::msg::Message as _;
use haunts::bag::msg::{LaserScan, Odometry, TfMessage};
use haunts::bag::{Bag, Messages, RawMessage, RecordingOptions, RecordingTopics};
use ros2_client::dds::{Context, Node, Publisher};

use crate::node::{advertise, ros_node};
use crate::wire::{self, Clock};
use crate::{Error, Result};

/// How a recording is published.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ReplayParams {
    /// Log seconds per wall-clock second (default 1; infinite: as fast as it can).
    pub rate: f64,
    /// Publish `/clock` (default true).
    pub clock: bool,
    /// How long to wait for a subscriber on every topic before the first message (default
    /// 10 s); the replay starts when the wait ends either way ([`Published::matched`] says).
    pub wait_for_subscribers: Duration,
    /// A pause after the subscribers matched, for their side of discovery to finish too
    /// (default 0.5 s).
    pub settle: Duration,
}

impl Default for ReplayParams {
    fn default() -> Self {
        Self {
            rate: 1.0,
            clock: true,
            wait_for_subscribers: Duration::from_secs(10),
            settle: Duration::from_millis(500),
        }
    }
}

impl ReplayParams {
    /// Sets [`ReplayParams::rate`].
    pub fn with_rate(mut self, rate: f64) -> Self {
        self.rate = rate;
        self
    }

    /// Sets [`ReplayParams::wait_for_subscribers`].
    pub fn with_wait(mut self, wait: Duration) -> Self {
        self.wait_for_subscribers = wait;
        self
    }
}

/// What a replay published.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Published {
    /// Messages published (scans, odometry, transforms; `/clock` not counted).
    pub messages: usize,
    /// `/clock` messages.
    pub clock_messages: usize,
    /// Messages that did not decode (skipped).
    pub undecodable: usize,
    /// Messages the middleware refused.
    pub publish_failures: usize,
    /// Whether every topic had a subscriber before the first message.
    pub matched: bool,
    /// Wall-clock seconds the replay took.
    pub seconds: f64,
    /// Log seconds from the first message to the last.
    pub span: f64,
}

/// A recording ready to be published (see the [module docs](self)).
pub struct DdsReplay {
    bag: Bag,
    topics: RecordingTopics,
    scan: Publisher<LaserScan>,
    odom: Option<Publisher<Odometry>>,
    tf: Vec<(String, Publisher<TfMessage>)>,
    clock: Publisher<Clock>,
    node: Node,
}

impl std::fmt::Debug for DdsReplay {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DdsReplay")
            .field("bag", &self.bag.path())
            .field("topics", &self.topics)
            .finish_non_exhaustive()
    }
}

impl DdsReplay {
    /// The recording `bag`, its topics chosen by `options`, advertised on `context` by a node
    /// named `haunts_replay`.
    ///
    /// # Errors
    /// The choice of topics; the middleware's errors.
    pub fn new(context: &Context, bag: Bag, options: &RecordingOptions) -> Result<Self> {
        let (topics, _) = bag
            .recording_topics(options)
            .map_err(haunts::pipeline::PipelineError::from)?;
        let mut node = ros_node(context, "/", "haunts_replay")?;
        let stream = wire::stream_qos(100);
        let scan = advertise(
            &mut node,
            &topics.scan,
            LaserScan::ROS2_TYPE,
            stream.clone(),
        )?;
        let odom = match &topics.odom {
            Some(t) => Some(advertise(
                &mut node,
                t,
                Odometry::ROS2_TYPE,
                stream.clone(),
            )?),
            None => None,
        };
        let mut tf = Vec::new();
        for t in &topics.tf {
            let qos = if t.ends_with("tf_static") {
                wire::latched_qos().history(ros2_client::qos::History::KeepLast { depth: 100 })
            } else {
                stream.clone()
            };
            tf.push((
                t.clone(),
                advertise(&mut node, t, TfMessage::ROS2_TYPE, qos)?,
            ));
        }
        let clock = advertise(&mut node, "/clock", Clock::ROS2_TYPE, stream)?;
        Ok(Self {
            bag,
            topics,
            scan,
            odom,
            tf,
            clock,
            node,
        })
    }

    /// The topics published.
    pub fn topics(&self) -> &RecordingTopics {
        &self.topics
    }

    /// Whether every topic published has a subscriber now.
    pub fn matched(&self) -> bool {
        let n = &self.node;
        self.scan.get_subscription_count(n) > 0
            && self
                .odom
                .as_ref()
                .is_none_or(|p| p.get_subscription_count(n) > 0)
            && self.tf.iter().all(|(_, p)| p.get_subscription_count(n) > 0)
    }

    /// Publishes the recording (see the [module docs](self)).
    ///
    /// # Errors
    /// A rate that is not positive; the file's errors that end a read.
    pub fn run(&self, params: &ReplayParams) -> Result<Published> {
        if params.rate.is_nan() || params.rate <= 0.0 {
            return Err(Error::Invalid(format!(
                "rate {} must be positive",
                params.rate
            )));
        }
        let mut out = Published::default();
        let waited = Instant::now();
        while !self.matched() && waited.elapsed() < params.wait_for_subscribers {
            std::thread::sleep(Duration::from_millis(20));
        }
        out.matched = self.matched();
        if out.matched {
            std::thread::sleep(params.settle);
        }
        let start = Instant::now();
        let (mut first, mut last) = (None::<f64>, f64::NEG_INFINITY);
        let mut last_clock = f64::NEG_INFINITY;
        for message in self.messages()? {
            let Ok(m) = message else {
                out.undecodable += 1;
                continue;
            };
            let t = m.log_seconds();
            let t0 = *first.get_or_insert(t);
            last = last.max(t);
            if params.rate.is_finite() {
                let due = Duration::from_secs_f64(((t - t0) / params.rate).max(0.0));
                if let Some(wait) = due.checked_sub(start.elapsed()) {
                    std::thread::sleep(wait);
                }
            }
            let clock = params.clock.then_some(&mut last_clock);
            self.publish(&m, clock, &mut out);
        }
        out.seconds = start.elapsed().as_secs_f64();
        out.span = first.map_or(0.0, |f| last - f);
        Ok(out)
    }

    /// The recording's messages on the topics published, in log-time order, as
    /// [`DdsReplay::run`] reads them: for a caller that publishes them at its own pace with
    /// [`DdsReplay::publish`] (a benchmark timing each one).
    ///
    /// # Errors
    /// The file's errors that end a read.
    pub fn messages(&self) -> Result<Messages> {
        let mut names: Vec<&str> = vec![self.topics.scan.as_str()];
        names.extend(self.topics.odom.as_deref());
        names.extend(self.topics.tf.iter().map(String::as_str));
        Ok(self
            .bag
            .messages(&names)
            .map_err(haunts::pipeline::PipelineError::from)?)
    }

    /// Publishes `m` (one of [`DdsReplay::messages`]) now, counted in `out`; with
    /// `last_clock` (the log time of the last `/clock` published, `-inf` at first), `/clock`
    /// at `m`'s log time first when that is later.
    pub fn publish(&self, m: &RawMessage, last_clock: Option<&mut f64>, out: &mut Published) {
        let t = m.log_seconds();
        if let Some(last_clock) = last_clock.filter(|last| t > **last) {
            *last_clock = t;
            let clock = Clock {
                clock: haunts::bag::msg::Time::from_seconds(t).unwrap_or_default(),
            };
            out.publish_failures += usize::from(self.clock.publish(clock).is_err());
            out.clock_messages += 1;
        }
        let published = if *m.topic == *self.topics.scan {
            self.bag
                .decode::<LaserScan>(m)
                .map(|s| self.scan.publish(s).is_ok())
        } else if let Some(odom) = self
            .odom
            .as_ref()
            .filter(|_| self.topics.odom.as_deref() == Some(&*m.topic))
        {
            self.bag
                .decode::<Odometry>(m)
                .map(|o| odom.publish(o).is_ok())
        } else if let Some((_, tf)) = self.tf.iter().find(|(name, _)| *name == *m.topic) {
            self.bag
                .decode::<TfMessage>(m)
                .map(|t| tf.publish(t).is_ok())
        } else {
            return;
        };
        match published {
            Ok(true) => out.messages += 1,
            Ok(false) => out.publish_failures += 1,
            Err(_) => out.undecodable += 1,
        }
    }
}
