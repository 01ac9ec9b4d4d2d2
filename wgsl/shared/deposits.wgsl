// #import types
// #import sampling

// Per-splat photon deposits (docs/design.md section 6, "Deposits"): what deposit_add sums of
// the photons that landed on a splat, as 64-bit integers (two u32 words, low first) so that
// the sums are exact and do not depend on the order the photons arrive in. Twin:
// src/shared/deposits.rs.

// Words a splat's deposit takes: its photon count, then the 64-bit sums of the RGB power, of
// the photons' offsets from the splat's centre (x, y, z, in splat radii, plus DEPOSIT_OFFSET),
// and of their squared distance from it (in squared radii).
const DEPOSIT_WORDS: u32 = 15u;
const DEPOSIT_COUNT: u32 = 0u;
const DEPOSIT_POWER: u32 = 1u;
const DEPOSIT_OFFSET_SUM: u32 = 7u;
const DEPOSIT_SQUARE_SUM: u32 = 13u;
// Fixed-point units of one splat radius (offsets) and of one squared radius.
const DEPOSIT_POSITION_UNITS: f32 = 16384.0;
// What an offset is shifted by to be non-negative; offsets are clamped to +-DEPOSIT_OFFSET
// (photons land on the disk, within one radius).
const DEPOSIT_OFFSET: f32 = 2.0;
// 2^32, a 64-bit sum's high word's weight.
const DEPOSIT_HIGH: f32 = 4294967296.0;

// A 64-bit sum (low, high) as f32.
fn deposit_value(low: u32, high: u32) -> f32 {
    return f32(high) * DEPOSIT_HIGH + f32(low);
}

// acos within 2e-8 (Abramowitz and Stegun 4.4.46) by the same operations as the mirror's: the
// device's acos may be thousands of ulps off, and the shares would differ between the two.
fn arccos(x: f32) -> f32 {
    let a = abs(x);
    let p = ((((((-0.0012624911 * a + 0.0066700901) * a - 0.0170881256) * a + 0.0308918810) * a
        - 0.0501743046) * a + 0.0889789874) * a - 0.2145988016) * a + 1.5707963050;
    let y = sqrt(1.0 - a) * p;
    return select(y, PI - y, x < 0.0);
}

// The share of a uniform disk of radius rho, its centre at distance l from a splat's centre,
// that lies within the splat's gather disk of radius r: the two circles' lens over the disk's
// area. A deposit of one photon (rho 0) is in or out.
fn disk_share(l: f32, r: f32, rho: f32) -> f32 {
    if rho <= 0.0 || l + rho <= r {
        return select(0.0, 1.0, l <= r);
    }
    if l >= r + rho {
        return 0.0;
    }
    if l + r <= rho {
        return (r * r) / (rho * rho);
    }
    let a = clamp((l * l + r * r - rho * rho) / (2.0 * l * r), -1.0, 1.0);
    let b = clamp((l * l + rho * rho - r * r) / (2.0 * l * rho), -1.0, 1.0);
    let k = max((-l + r + rho) * (l + r - rho) * (l - r + rho) * (l + r + rho), 0.0);
    let lens = r * r * arccos(a) + rho * rho * arccos(b) - 0.5 * sqrt(k);
    return clamp(lens / (PI * rho * rho), 0.0, 1.0);
}

// The share of photons arriving at a surface whose normal is m, spread as cosine around it,
// that arrive at the front of a surface with normal n (the photons' test, direction . n > 0):
// (1 + n . m) / 2.
fn front_share(n: vec3<f32>, m: vec3<f32>) -> f32 {
    return 0.5 * (1.0 + dot(n, m));
}
