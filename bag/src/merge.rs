//! Messages of a chunked file in log-time order: a k-way merge of its chunks, which holds in
//! memory only the chunks whose time ranges overlap the messages being yielded.
//!
//! A recorder writes messages in the order they arrive, and chunks of a file may overlap in
//! log time (two recorders merged, a late sensor, a reordered ROS 1 bag). The index of each
//! format gives every chunk's earliest log time (ROS 1 chunk infos, MCAP chunk indexes):
//! chunks are opened in that order, and the next chunk is opened before a message is yielded
//! whenever it may hold an earlier one. With chunks that do not overlap, one chunk is held at
//! a time.
//!
//! The order is as good as the index: a chunk whose indexed start time is later than its
//! earliest message (a corrupt index) yields that message late, never a panic.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};
use std::sync::Arc;

use crate::Result;

/// A stored message: topic, log time (ns), bytes.
pub(crate) type Stored = (Arc<str>, u64, Vec<u8>);

/// A chunk as the file's index has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct ChunkRef {
    /// The log time of its earliest message, ns.
    pub start: u64,
    /// The byte offset of its record.
    pub at: u64,
    /// The length of its record in bytes (where the index says; 0 otherwise).
    pub length: u64,
}

/// Reads the wanted messages of one chunk, in file order.
pub(crate) trait ChunkLoader: Send {
    /// The messages of `chunk`; an error names the chunk.
    fn load(&mut self, chunk: &ChunkRef) -> Result<Vec<Stored>>;
}

/// The k-way merge: the chunks not yet opened, and the messages left of the open ones.
#[derive(Debug)]
pub(crate) struct Merge {
    /// All chunks, by earliest log time (then offset).
    chunks: Vec<ChunkRef>,
    /// The next chunk to open.
    next: usize,
    /// Messages left in each open chunk, sorted by log time (file order among equal times).
    open: Vec<VecDeque<Stored>>,
    /// Slots of `open` that are free.
    free: Vec<usize>,
    /// (log time of the first message left, chunk rank, slot) of every open chunk.
    heads: BinaryHeap<Reverse<(u64, usize, usize)>>,
    /// The most chunks held at once.
    most_held: usize,
}

impl Merge {
    /// A merge of `chunks` (in any order; a chunk listed twice is read once).
    pub fn new(mut chunks: Vec<ChunkRef>) -> Self {
        chunks.sort_unstable();
        let mut seen = std::collections::BTreeSet::new();
        chunks.retain(|c| seen.insert(c.at));
        Self {
            chunks,
            next: 0,
            open: Vec::new(),
            free: Vec::new(),
            heads: BinaryHeap::new(),
            most_held: 0,
        }
    }

    /// The most chunks held in memory at once so far.
    pub fn most_held(&self) -> usize {
        self.most_held
    }

    /// The next message by log time (ties: the chunk that starts earlier, then file order),
    /// opening chunks through `loader` as needed. A chunk that fails to load is an error item,
    /// and the merge goes on with the other chunks.
    pub fn next(&mut self, loader: &mut dyn ChunkLoader) -> Option<Result<Stored>> {
        loop {
            let earliest = self.heads.peek().map(|Reverse(h)| h.0);
            if let Some(&chunk) = self.chunks.get(self.next)
                && earliest.is_none_or(|t| chunk.start < t)
            {
                let rank = self.next;
                self.next += 1;
                let mut messages = match loader.load(&chunk) {
                    Ok(messages) => messages,
                    Err(e) => return Some(Err(e)),
                };
                if messages.is_empty() {
                    continue;
                }
                // Stable: messages of equal log times keep their file order.
                messages.sort_by_key(|m| m.1);
                let first = messages[0].1;
                let slot = match self.free.pop() {
                    Some(slot) => {
                        self.open[slot] = messages.into();
                        slot
                    }
                    None => {
                        self.open.push(messages.into());
                        self.open.len() - 1
                    }
                };
                self.heads.push(Reverse((first, rank, slot)));
                self.most_held = self.most_held.max(self.heads.len());
                continue;
            }
            let Reverse((_, rank, slot)) = self.heads.pop()?;
            let queue = self.open.get_mut(slot)?;
            let message = queue.pop_front()?;
            match queue.front() {
                Some(next) => self.heads.push(Reverse((next.1, rank, slot))),
                None => {
                    // Give the chunk's memory back now, not when the slot is reused.
                    *queue = VecDeque::new();
                    self.free.push(slot);
                }
            }
            return Some(Ok(message));
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Chunks held in a map by offset; loading one of them can be made to fail.
    struct Memory(Vec<(u64, Vec<u64>)>, Option<u64>);

    impl ChunkLoader for Memory {
        fn load(&mut self, chunk: &ChunkRef) -> Result<Vec<Stored>> {
            if self.1 == Some(chunk.at) {
                return Err(crate::BagError::Ros1 {
                    path: "memory".into(),
                    what: format!("chunk at byte {}", chunk.at),
                });
            }
            let topic: Arc<str> = Arc::from("/t");
            Ok(self
                .0
                .iter()
                .find(|c| c.0 == chunk.at)
                .map(|c| {
                    c.1.iter()
                        .enumerate()
                        .map(|(i, &t)| (topic.clone(), t, vec![chunk.at as u8, i as u8]))
                        .collect()
                })
                .unwrap_or_default())
        }
    }

    fn refs(chunks: &[(u64, Vec<u64>)]) -> Vec<ChunkRef> {
        chunks
            .iter()
            .map(|(at, times)| ChunkRef {
                start: times.iter().copied().min().unwrap_or(0),
                at: *at,
                length: 0,
            })
            .collect()
    }

    /// The merge against the plain way: every message of every chunk, sorted (stably) by log
    /// time then chunk start.
    fn check(chunks: Vec<(u64, Vec<u64>)>, most_held: usize) {
        let mut merge = Merge::new(refs(&chunks));
        let mut memory = Memory(chunks.clone(), None);
        let mut got = Vec::new();
        while let Some(m) = merge.next(&mut memory) {
            let m = m.unwrap();
            got.push((m.1, m.2));
        }
        let mut order = refs(&chunks);
        order.sort();
        let mut expected: Vec<(u64, Vec<u8>)> = Vec::new();
        for c in &order {
            let times = &chunks.iter().find(|x| x.0 == c.at).unwrap().1;
            expected.extend(
                times
                    .iter()
                    .enumerate()
                    .map(|(i, &t)| (t, vec![c.at as u8, i as u8])),
            );
        }
        expected.sort_by_key(|m| m.0);
        assert_eq!(got, expected);
        assert_eq!(merge.most_held(), most_held, "{chunks:?}");
    }

    #[test]
    fn chunks_in_order_are_held_one_at_a_time() {
        // A chunk that starts when the last one ends is opened after that one's messages
        // of that time (they come first).
        check(
            vec![(10, vec![1, 2, 3]), (20, vec![3, 4, 5]), (30, vec![9])],
            1,
        );
        check(vec![(10, vec![1, 2]), (20, vec![4, 5]), (30, vec![6])], 1);
    }

    #[test]
    fn overlapping_chunks_are_merged_by_log_time() {
        // Two recorders written alternately: their chunks overlap, and two are held.
        check(
            vec![
                (10, vec![1, 3, 5, 7]),
                (20, vec![2, 4, 6, 8]),
                (30, vec![9, 11, 13]),
                (40, vec![10, 12, 14]),
            ],
            2,
        );
        // Out of order inside a chunk, and a chunk written after a later one.
        check(
            vec![(10, vec![50, 40, 45]), (20, vec![1, 60, 2]), (30, vec![41])],
            3,
        );
        // Equal times: the chunk that starts first, then file order.
        check(vec![(10, vec![5, 5, 6]), (20, vec![5, 6])], 2);
        // Empty chunks and no chunks.
        check(vec![(10, vec![]), (20, vec![3])], 1);
        check(vec![], 0);
    }

    #[test]
    fn a_chunk_that_fails_is_one_error_and_the_rest_is_read() {
        let chunks = vec![(10, vec![1, 4]), (20, vec![2, 3]), (30, vec![5])];
        let mut merge = Merge::new(refs(&chunks));
        let mut memory = Memory(chunks, Some(20));
        let mut times = Vec::new();
        let mut errors = 0;
        while let Some(m) = merge.next(&mut memory) {
            match m {
                Ok(m) => times.push(m.1),
                Err(e) => {
                    errors += 1;
                    assert!(e.to_string().contains("byte 20"), "{e}");
                }
            }
        }
        assert_eq!((times, errors), (vec![1, 4, 5], 1));
    }
}
