// PCG hash random numbers (Jarzynski & Olano 2020), keyed by (path, bounce, purpose) so that
// every number a photon draws is a pure function of its indices: the CPU mirror
// (src/shared/rng.rs) draws the same bits, whatever the scheduling.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// u32 -> [0, 1) with 24 bits, exact in f32.
fn unit_float(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// The random stream of one emitted photon.
fn path_key(seed: u32, path: u32) -> u32 {
    return pcg_hash(pcg_hash(seed) + path);
}

// What a number is for, so that no two uses share one.
const RNG_EMIT_POS_U: u32 = 0u;
const RNG_EMIT_POS_V: u32 = 1u;
const RNG_EMIT_DIR_U: u32 = 2u;
const RNG_EMIT_DIR_V: u32 = 3u;
const RNG_ROULETTE: u32 = 4u;
const RNG_BOUNCE_U: u32 = 5u;
const RNG_BOUNCE_V: u32 = 6u;
const RNG_PURPOSES: u32 = 16u;

fn rand(key: u32, bounce: u32, purpose: u32) -> f32 {
    return unit_float(pcg_hash(key + bounce * RNG_PURPOSES + purpose));
}

// Point j of the R2 sequence (Roberts 2018) shifted modulo 1 by `shift` (a Cranley-Patterson
// rotation), in 32-bit fixed point so that the mirror draws the same bits. Every prefix of the
// sequence spreads evenly over the unit square: a pixel's samples numbered across refinement
// frames stratify what they sample, where independent ones would clump. A uniformly random
// shift keeps each point uniform, so an estimate from them stays unbiased.
const R2_STEP: vec2<u32> = vec2<u32>(3242174889u, 2447445414u);

fn r2_point(j: u32, shift: vec2<u32>) -> vec2<f32> {
    let x = j * R2_STEP + shift;
    return vec2<f32>(unit_float(x.x), unit_float(x.y));
}

// A random shift for r2_point from key.
fn r2_shift(key: u32) -> vec2<u32> {
    return vec2<u32>(pcg_hash(key), pcg_hash(key + 1u));
}
