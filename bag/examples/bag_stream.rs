//! Peak memory of streaming (issue 16): `make` writes an MCAP file COPIES times the `/scan`,
//! `/odom` and `/tf` messages of IN (one pass per copy, each copy's log times shifted past the
//! previous one's; header stamps are left as recorded), through `McapWriter`; `stream` reads
//! every scan of FILE through `Bag::read` and prints how many, so that `/usr/bin/time -v` can
//! report the peak resident memory against the file's size.
//!
//! ```sh
//! cargo run --release -p haunts-bag --example bag_stream -- make \
//!     ../shared/data/leg_tracker/general_tracking_moving_1.mcap /tmp/big.mcap 12
//! /usr/bin/time -v target/release/examples/bag_stream stream /tmp/big.mcap
//! ```

use haunts_bag::msg::{LaserScan, Odometry, TfMessage};
use haunts_bag::{Bag, McapWriter, codec};

type Error = Box<dyn std::error::Error>;

fn make(input: &str, output: &str, copies: u32) -> Result<(), Error> {
    let bag = Bag::open(input)?;
    let topics = ["/scan", "/odom", "/tf"];
    let enc = |t: &str| bag.topic(t).map(|i| i.encoding);
    let (scan_enc, odom_enc, tf_enc) = (enc("/scan")?, enc("/odom")?, enc("/tf")?);
    let (mut first, mut last) = (f64::INFINITY, f64::NEG_INFINITY);
    for m in bag.messages(&topics)? {
        let t = m?.log_seconds();
        first = first.min(t);
        last = last.max(t);
    }
    let span = last - first + 1.0;
    let mut out = McapWriter::create(output)?;
    let mut written = 0u64;
    for k in 0..copies {
        let shift = f64::from(k) * span;
        for m in bag.messages(&topics)? {
            let m = m?;
            let t = m.log_seconds() + shift;
            match &*m.topic {
                "/scan" => {
                    out.write("/scan", t, &codec::decode::<LaserScan>(scan_enc, &m.data)?)?
                }
                "/odom" => out.write("/odom", t, &codec::decode::<Odometry>(odom_enc, &m.data)?)?,
                _ => out.write("/tf", t, &codec::decode::<TfMessage>(tf_enc, &m.data)?)?,
            }
            written += 1;
        }
    }
    out.finish()?;
    let size = std::fs::metadata(output)?.len();
    println!("wrote {written} messages ({copies} copies of {input}) to {output}: {size} bytes");
    Ok(())
}

fn stream(path: &str, topic: &str) -> Result<(), Error> {
    let bag = Bag::open(path)?;
    let (mut scans, mut beams) = (0u64, 0u64);
    for scan in bag.read::<LaserScan>(topic)? {
        let (_, scan) = scan?;
        scans += 1;
        beams += scan.ranges.len() as u64;
    }
    let size = std::fs::metadata(path)?.len();
    println!("streamed {scans} scans ({beams} beams) of {path}: {size} bytes");
    // On Linux, split the resident memory at the end into the heap (anonymous) and the pages of
    // files mapped (the program's own code; no reader maps the bag, both read it a chunk at a
    // time).
    if let Ok(status) = std::fs::read_to_string("/proc/self/status") {
        let keep = ["VmHWM", "RssAnon", "RssFile"];
        let lines: Vec<String> = status
            .lines()
            .filter(|l| keep.iter().any(|k| l.starts_with(k)))
            .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
            .collect();
        println!("memory at the end: {}", lines.join(", "));
    }
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["make", input, output, copies] => match copies.parse() {
            Ok(n) => make(input, output, n),
            Err(e) => Err(format!("COPIES {copies}: {e}").into()),
        },
        ["stream", path] => stream(path, "/scan"),
        ["stream", path, topic] => stream(path, topic),
        _ => Err("usage: bag_stream make IN OUT COPIES | bag_stream stream FILE [TOPIC]".into()),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
