//! A live session keeps nothing per scan: after the shared recording played ten times in a
//! row through one session, the session holds hardly more memory than after one pass
//! (the bytes alive counted by `dhat`'s allocator).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use haunts::bag::{Bag, RecordingOptions};
use haunts::live::replay::Replay;
use haunts::live::{LiveParams, LiveSession};
use haunts_test_support::bag;

#[global_allocator]
static ALLOC: dhat::Alloc = dhat::Alloc;

/// The bytes alive now.
fn alive() -> isize {
    dhat::HeapStats::get().curr_bytes as isize
}

/// Bytes the session holds after the recording played `loops` times through it (the
/// replay's own records dropped first).
fn held_after(path: &std::path::Path, loops: usize) -> (isize, usize, usize) {
    let replay = Replay::new(Bag::open(path).unwrap(), &RecordingOptions::new(), None).unwrap();
    let before = alive();
    let mut session = LiveSession::with_defaults(replay.params(LiveParams::default())).unwrap();
    let replayed = replay.run_looped(&mut session, loops, |_| Ok(())).unwrap();
    drop(replayed);
    let held = alive() - before;
    let scans = session.scans();
    let finished = session.tracker().finished().len();
    drop(session);
    (held, scans, finished)
}

#[test]
fn a_session_holds_as_much_after_ten_passes_as_after_one() {
    let Some(mcap) = bag::moving_mcap() else {
        return;
    };
    let _profiler = dhat::Profiler::builder().testing().build();
    let (one, scans_one, ended_one) = held_after(&mcap, 1);
    let (ten, scans_ten, ended_ten) = held_after(&mcap, 10);
    assert_eq!(scans_ten, 10 * scans_one);
    eprintln!(
        "session holds {one} B after 1 pass ({ended_one} tracks ended), {ten} B after 10 \
         ({scans_ten} scans, {ended_ten} tracks ended)"
    );
    // What it keeps beyond the first pass is the ended tracks, one latest position each
    // (the tracker's finished list, which `trajectories` reads): under 400 bytes per track,
    // nothing per scan (a session that kept one position per scan would hold 16 B more per
    // scan, 126 kB over these passes).
    let per_track = (ten - one) as f64 / (ended_ten - ended_one).max(1) as f64;
    assert!(per_track < 400.0, "{per_track:.0} B more per ended track");
    assert!(ten - one < 126_000, "{} B more", ten - one);
}
