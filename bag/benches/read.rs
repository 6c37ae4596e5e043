//! Reading and decoding every `LaserScan` (`/scan`), `Odometry` (`/odom`) and `TFMessage`
//! (`/tf`) message of the shared ROS 1 bag (unzipped into the temporary folder in the setup,
//! outside the timed loop) and of its MCAP twin. Throughput is the file's size, so criterion
//! reports MB/s. Two routes per file: one pass over the three topics (`Bag::messages` +
//! `codec::decode`, what `benches/peers/bag_rosbags.py` does with `rosbags`), and the plain API
//! (`Bag::read::<T>` once per topic, three passes over the file).
//!
//! The bench prints a `bag check:` line per file (message counts and sums of a few fields), so
//! that `benches/peers/compare_bag.sh` can check both sides decoded the same messages.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use haunts_bag::msg::{LaserScan, Odometry, TfMessage};
use haunts_bag::{Bag, codec};
use haunts_test_support::bag;

/// What one pass decoded: counts per topic and sums that both sides can compute.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
struct Tally {
    scans: u64,
    beams: u64,
    odoms: u64,
    odom_x: f64,
    tf_messages: u64,
    transforms: u64,
}

/// One pass over the file, the three topics decoded by their recorded encoding.
fn one_pass(bag: &Bag) -> Tally {
    let enc = |topic: &str| bag.topic(topic).unwrap().encoding;
    let (scan_enc, odom_enc, tf_enc) = (enc("/scan"), enc("/odom"), enc("/tf"));
    let mut t = Tally::default();
    for m in bag.messages(&["/scan", "/odom", "/tf"]).unwrap() {
        let m = m.unwrap();
        match &*m.topic {
            "/scan" => {
                let s: LaserScan = codec::decode(scan_enc, &m.data).unwrap();
                t.scans += 1;
                t.beams += s.ranges.len() as u64;
                black_box(s);
            }
            "/odom" => {
                let o: Odometry = codec::decode(odom_enc, &m.data).unwrap();
                t.odoms += 1;
                t.odom_x += o.pose.pose.position.x;
                black_box(o);
            }
            _ => {
                let f: TfMessage = codec::decode(tf_enc, &m.data).unwrap();
                t.tf_messages += 1;
                t.transforms += f.transforms.len() as u64;
                black_box(f);
            }
        }
    }
    t
}

/// The plain API: `Bag::read` once per topic.
fn per_topic(bag: &Bag) -> Tally {
    let mut t = Tally::default();
    for m in bag.read::<LaserScan>("/scan").unwrap() {
        let (_, s) = m.unwrap();
        t.scans += 1;
        t.beams += s.ranges.len() as u64;
        black_box(s);
    }
    for m in bag.read::<Odometry>("/odom").unwrap() {
        let (_, o) = m.unwrap();
        t.odoms += 1;
        t.odom_x += o.pose.pose.position.x;
        black_box(o);
    }
    for m in bag.read::<TfMessage>("/tf").unwrap() {
        let (_, f) = m.unwrap();
        t.tf_messages += 1;
        t.transforms += f.transforms.len() as u64;
        black_box(f);
    }
    t
}

fn bench_file(c: &mut Criterion, name: &str, path: &Path) {
    let bag = Bag::open(path).unwrap();
    let size = std::fs::metadata(path).unwrap().len();
    let a = one_pass(&bag);
    let b = per_topic(&bag);
    assert_eq!(a.scans, b.scans);
    assert_eq!(a.transforms, b.transforms);
    println!(
        "bag check: {{\"file\": \"{name}\", \"bytes\": {size}, \"scans\": {}, \"beams\": {}, \
         \"odoms\": {}, \"odom_x_sum\": {:?}, \"tf_messages\": {}, \"transforms\": {}}}",
        a.scans, a.beams, a.odoms, a.odom_x, a.tf_messages, a.transforms
    );
    let mut group = c.benchmark_group(format!("bag_read_{name}"));
    group.throughput(Throughput::Bytes(size));
    group.sample_size(20);
    group.bench_function("one_pass", |bch| bch.iter(|| black_box(one_pass(&bag))));
    group.bench_function("per_topic", |bch| bch.iter(|| black_box(per_topic(&bag))));
    group.finish();
}

fn read(c: &mut Criterion) {
    match bag::moving_bag() {
        Some(p) => bench_file(c, "ros1", &p),
        None => eprintln!("no shared data: the ROS 1 bag is not benched"),
    }
    match bag::moving_mcap() {
        Some(p) => bench_file(c, "mcap", &p),
        None => eprintln!("no shared data: the MCAP file is not benched"),
    }
}

criterion_group!(benches, read);
criterion_main!(benches);
