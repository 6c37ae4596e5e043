//! Independent random streams derived from (seed, day, purpose, index), so that each day and
//! each scan can be simulated alone, in any order, on any thread, with the same result.

/// What a random stream is used for; changing one part of the simulation (say the laser)
/// leaves the others' draws unchanged.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Stream {
    Schedule = 1,
    Furniture = 2,
    People = 3,
    Laser = 4,
    Odometry = 5,
    Start = 6,
}

/// SplitMix64's finaliser: a bijective mix of 64 bits.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of one stream.
pub(crate) fn stream_seed(seed: u64, day: u64, stream: Stream, index: u64) -> u64 {
    mix(mix(mix(mix(seed) ^ day) ^ stream as u64) ^ index)
}
