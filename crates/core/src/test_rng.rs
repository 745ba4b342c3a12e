//! Random test data for the unit tests: a fixed xorshift64 sequence, so a test sees the same values
//! on every run.

/// Floats uniform in [0, 1) (24 bits each) from the xorshift64 state `seed` (not 0).
pub fn unit_floats(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}
