//! Twin of `wgsl/shared/deposits.wgsl`: the layout of a splat's photon deposit and the shares
//! `deposit_share` weighs a deposit by (design §6, "Deposits").

use glam::Vec3;

/// Words a splat's deposit takes: its photon count, then the 64-bit sums (low word first) of
/// the RGB power, of the photons' offsets from the splat's centre (in splat radii, plus
/// `DEPOSIT_OFFSET`) and of their squared distance from it.
pub const DEPOSIT_WORDS: u32 = 15;
pub const DEPOSIT_COUNT: u32 = 0;
pub const DEPOSIT_POWER: u32 = 1;
pub const DEPOSIT_OFFSET_SUM: u32 = 7;
pub const DEPOSIT_SQUARE_SUM: u32 = 13;
/// Fixed-point units of one splat radius (offsets) and of one squared radius.
pub const DEPOSIT_POSITION_UNITS: f32 = 16384.0;
/// What an offset is shifted by to be non-negative; offsets are clamped to ±`DEPOSIT_OFFSET`.
pub const DEPOSIT_OFFSET: f32 = 2.0;
/// 2³², a 64-bit sum's high word's weight.
pub const DEPOSIT_HIGH: f32 = 4294967296.0;

/// A 64-bit sum (low, high) as f32.
pub fn deposit_value(low: u32, high: u32) -> f32 {
    high as f32 * DEPOSIT_HIGH + low as f32
}

/// acos within 2e-8 (Abramowitz and Stegun 4.4.46), by the device's operations: its acos may
/// be thousands of ulps off. The coefficients as published, as the WGSL twin writes them.
#[allow(clippy::excessive_precision)]
pub fn arccos(x: f32) -> f32 {
    let a = x.abs();
    let p = ((((((-0.0012624911 * a + 0.0066700901) * a - 0.0170881256) * a + 0.0308918810) * a
        - 0.0501743046)
        * a
        + 0.0889789874)
        * a
        - 0.2145988016)
        * a
        + 1.5707963050;
    let y = (1.0 - a).sqrt() * p;
    if x < 0.0 {
        crate::shared::sampling::PI - y
    } else {
        y
    }
}

/// The share of a uniform disk of radius `rho`, its centre at distance `l` from a splat's
/// centre, inside the splat's gather disk of radius `r`: the circles' lens over the disk.
pub fn disk_share(l: f32, r: f32, rho: f32) -> f32 {
    if rho <= 0.0 || l + rho <= r {
        return if l <= r { 1.0 } else { 0.0 };
    }
    if l >= r + rho {
        return 0.0;
    }
    if l + r <= rho {
        return (r * r) / (rho * rho);
    }
    let a = ((l * l + r * r - rho * rho) / (2.0 * l * r)).clamp(-1.0, 1.0);
    let b = ((l * l + rho * rho - r * r) / (2.0 * l * rho)).clamp(-1.0, 1.0);
    let k = ((-l + r + rho) * (l + r - rho) * (l - r + rho) * (l + r + rho)).max(0.0);
    let lens = r * r * arccos(a) + rho * rho * arccos(b) - 0.5 * k.sqrt();
    (lens / (crate::shared::sampling::PI * rho * rho)).clamp(0.0, 1.0)
}

/// The share of photons spread as cosine about normal `m` that arrive at the front of a
/// surface with normal `n`: (1 + n · m) / 2.
pub fn front_share(n: Vec3, m: Vec3) -> f32 {
    0.5 * (1.0 + n.dot(m))
}

/// The fixed-point value of `x` ≥ 0 in `units`, rounded to nearest, at most u32's largest
/// (`fixed` in `deposit_add.wgsl`).
pub fn fixed(x: f32, units: f32) -> u32 {
    (x * units + 0.5).min(4294967040.0) as u32
}
