//! Twin of `shaders-wgsl/common/rng.wgsl`.

pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

pub fn rng_seed(a: u32, b: u32, c: u32) -> u32 {
    pcg_hash(a ^ pcg_hash(b ^ pcg_hash(c)))
}

pub fn rng_next(state: &mut u32) -> f32 {
    *state = pcg_hash(*state);
    (*state >> 8) as f32 * (1.0 / 16777216.0)
}
