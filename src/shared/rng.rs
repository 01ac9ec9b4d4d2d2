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

/// The R2 sequence's step in 32-bit fixed point: 2³² times 1/φ₂ and 1/φ₂², φ₂ the plastic
/// number.
pub const R2_STEP: [u32; 2] = [3_242_174_889, 2_447_445_414];

/// Point `j` of the R2 sequence (Roberts 2018) shifted modulo 1 by `shift`: twin of
/// `r2_point` in `wgsl/shared/rng.wgsl`, which says why.
pub fn r2_point(j: u32, shift: [u32; 2]) -> (f32, f32) {
    (
        unit_float(j.wrapping_mul(R2_STEP[0]).wrapping_add(shift[0])),
        unit_float(j.wrapping_mul(R2_STEP[1]).wrapping_add(shift[1])),
    )
}

/// A random shift for `r2_point` from `key`.
pub fn r2_shift(key: u32) -> [u32; 2] {
    [pcg_hash(key), pcg_hash(key.wrapping_add(1))]
}
