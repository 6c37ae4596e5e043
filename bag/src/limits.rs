//! How much a compressed chunk may inflate: the decompression-bomb rule both formats' readers
//! can share (a leaf: it imports nothing of the crate).
//!
//! A chunk announces how many bytes its records take decompressed (ROS 1's `size`, MCAP's
//! `uncompressed_size`); decompression never produces more than announced plus one byte (the
//! byte that proves a chunk longer than its header says). That alone bounds memory but not
//! time: a bz2 stream of 785 bytes can announce and honestly hold 1 GiB of zeros, seconds of
//! bz2 on one core, and a file of such chunks runs for minutes. So a chunk may also inflate at most
//! [`MAX_RATIO`] times its compressed length, beyond the [`FREE_BYTES`] any chunk may hold:
//! recorded robot data (laser ranges, poses, images) compress 2–20 times, and a
//! thousand-fold chunk is made of repeated bytes, not of messages. The check is made on the
//! header, before anything is decompressed.

/// The largest ratio of decompressed to compressed bytes of a chunk beyond [`FREE_BYTES`].
pub(crate) const MAX_RATIO: u64 = 1000;

/// Decompressed bytes any chunk may hold whatever its ratio: 1 MiB (ROS 1's default chunk
/// is 768 KB).
pub(crate) const FREE_BYTES: u64 = 1 << 20;

/// Bytes the chunks of one pass over a file (an open, or a read of its messages) may hold, in
/// all, beyond [`MAX_RATIO`] times their compressed length: 1 GiB. [`FREE_BYTES`] lets any
/// one chunk inflate freely, so without a total a file of thousands of tiny chunks, each a
/// megabyte of zeros in a few hundred bytes, would run for minutes (each chunk within its own
/// rule); with it, such a file is refused once a gigabyte has been spent on such chunks, a
/// few seconds. Recorded data never comes near it (they compress 2–20 times).
pub(crate) const FREE_TOTAL: u64 = 1 << 30;

/// The running total of one pass's chunks against [`FREE_TOTAL`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Inflation {
    beyond: u64,
    allowance: u64,
}

impl Default for Inflation {
    fn default() -> Self {
        Self::with_allowance(FREE_TOTAL)
    }
}

impl Inflation {
    /// A total with `allowance` bytes beyond the ratio (tests use a small one).
    pub(crate) fn with_allowance(allowance: u64) -> Self {
        Self {
            beyond: 0,
            allowance,
        }
    }

    /// Counts a chunk of `compressed` bytes that announces `decompressed`, before it is
    /// inflated.
    ///
    /// # Errors
    /// A text naming the total and the allowance when the pass's chunks would hold more than
    /// the allowance beyond [`MAX_RATIO`] times their compressed length.
    pub(crate) fn charge(&mut self, compressed: u64, decompressed: u64) -> Result<(), String> {
        let beyond = decompressed.saturating_sub(compressed.saturating_mul(MAX_RATIO));
        self.beyond = self.beyond.saturating_add(beyond);
        if self.beyond > self.allowance {
            return Err(format!(
                "with this chunk the file's chunks hold {} bytes beyond {MAX_RATIO} times their \
                 compressed length, over the allowance of {} for a whole file: a \
                 decompression bomb spread over many small chunks",
                self.beyond, self.allowance
            ));
        }
        Ok(())
    }
}

/// The most bytes a chunk of `compressed` bytes may decompress to: its announced size when it
/// announces one (`announced`), within `cap`, within [`MAX_RATIO`] · `compressed` (or
/// [`FREE_BYTES`], the larger).
///
/// # Errors
/// A text naming the announced size and the limit it breaks.
pub(crate) fn decompressed_limit(
    announced: Option<u64>,
    compressed: u64,
    cap: u64,
) -> Result<u64, String> {
    let ratio_limit = compressed.saturating_mul(MAX_RATIO).max(FREE_BYTES);
    match announced {
        Some(size) if size > cap => Err(format!(
            "announces {size} decompressed bytes, over the limit of {cap}"
        )),
        Some(size) if size > ratio_limit => Err(format!(
            "announces {size} decompressed bytes from {compressed} compressed: over \
             {MAX_RATIO} times as many (and over {FREE_BYTES}), a decompression bomb"
        )),
        Some(size) => Ok(size),
        None => Ok(cap.min(ratio_limit)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_limit_is_the_announced_size_within_the_cap_and_the_ratio() {
        let cap = 1 << 30;
        assert_eq!(decompressed_limit(Some(768_000), 200_000, cap), Ok(768_000));
        // Small chunks may inflate freely.
        assert_eq!(decompressed_limit(Some(FREE_BYTES), 1, cap), Ok(FREE_BYTES));
        assert_eq!(
            decompressed_limit(Some(4000 * 1000), 4000, cap),
            Ok(4_000_000)
        );
        let bomb = decompressed_limit(Some(cap), 40, cap).unwrap_err();
        assert!(bomb.contains("decompression bomb"), "{bomb}");
        assert!(decompressed_limit(Some(4_000_001), 4000, cap).is_err());
        assert!(
            decompressed_limit(Some(cap + 1), u64::MAX, cap)
                .unwrap_err()
                .contains("over the limit")
        );
        // Nothing announced: the cap and the ratio bound what is decompressed.
        assert_eq!(decompressed_limit(None, 40, cap), Ok(FREE_BYTES));
        assert_eq!(decompressed_limit(None, u64::MAX, cap), Ok(cap));
    }

    #[test]
    fn the_free_bytes_of_many_chunks_add_up_to_a_refusal() {
        let mut total = Inflation::with_allowance(3 * FREE_BYTES);
        // Chunks within the ratio cost nothing, however many.
        for _ in 0..10_000 {
            total.charge(300_000, 768_000).unwrap();
        }
        // Each a megabyte from 100 bytes: 900 000 beyond the ratio, under the per-chunk rule.
        for _ in 0..3 {
            total.charge(100, FREE_BYTES).unwrap();
        }
        let e = total.charge(100, FREE_BYTES).unwrap_err();
        assert!(e.contains("decompression bomb spread over many"), "{e}");
        assert_eq!(Inflation::default().allowance, FREE_TOTAL);
    }
}
