"""SplitMix64, the one random generator of the peer scripts: the state starts at the seed and
each draw is the Rust benches' (`gp/benches/common`, `affordance/benches/gk.rs`,
`similarity/benches/matrix.rs`), so both sides see the same data bit for bit."""

MASK64 = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed):
        self.state = seed & MASK64

    def next_u64(self):
        self.state = (self.state + 0x9E3779B97F4A7C15) & MASK64
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
        return z ^ (z >> 31)

    def uniform(self):
        """A uniform in [0, 1) from the top 53 bits."""
        return (self.next_u64() >> 11) * 2.0 ** -53

    def range(self, lo, hi):
        """An integer in [lo, hi) by the remainder (as the Rust benches draw it)."""
        return lo + self.next_u64() % (hi - lo)
