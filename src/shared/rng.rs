//! Twin of `wgsl/shared/rng.wgsl`: PCG hash random numbers keyed by (path, bounce, purpose).

pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// u32 → [0, 1) with 24 bits, exact in f32.
pub fn unit_float(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The random stream of one emitted photon.
pub fn path_key(seed: u32, path: u32) -> u32 {
    pcg_hash(pcg_hash(seed).wrapping_add(path))
}

pub const RNG_EMIT_POS_U: u32 = 0;
pub const RNG_EMIT_POS_V: u32 = 1;
pub const RNG_EMIT_DIR_U: u32 = 2;
pub const RNG_EMIT_DIR_V: u32 = 3;
pub const RNG_ROULETTE: u32 = 4;
pub const RNG_BOUNCE_U: u32 = 5;
pub const RNG_BOUNCE_V: u32 = 6;
pub const RNG_PURPOSES: u32 = 16;

pub fn rand(key: u32, bounce: u32, purpose: u32) -> f32 {
    unit_float(pcg_hash(
        key.wrapping_add(bounce.wrapping_mul(RNG_PURPOSES))
            .wrapping_add(purpose),
    ))
}
