//! Twin of `wgsl/shared/tone.wgsl`: luminance, the finite test, the operator, sRGB bytes.

use glam::{Vec2, Vec3};

use crate::types::ToneParams;

pub const TONE_REINHARD: u32 = 0;
pub const TONE_LINEAR: u32 = 1;

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

pub fn all_finite(c: Vec3) -> bool {
    c.is_finite()
}

/// (log(ε + Y), 1) of a pixel, or nothing when it is not finite.
pub fn log_luminance(c: Vec3, epsilon: f32) -> Vec2 {
    if !all_finite(c) {
        return Vec2::ZERO;
    }
    Vec2::new((epsilon + luminance(c.max(Vec3::ZERO))).ln(), 1.0)
}

pub const SCOTOPIC_TINT: Vec3 = Vec3::new(1.05, 0.97, 1.27);

/// Display RGB in [0, 1] of a linear HDR pixel; `log_sum` is (Σ log(ε + Y), count).
pub fn tone_map(c_in: Vec3, log_sum: Vec2, p: &ToneParams) -> Vec3 {
    if !all_finite(c_in) {
        return Vec3::ZERO;
    }
    let c = c_in.max(Vec3::ZERO);
    if p.mode == TONE_LINEAR {
        return c * p.exposure;
    }
    let y = luminance(c);
    if y <= 0.0 {
        return Vec3::ZERO;
    }
    let average = (log_sum.x / log_sum.y.max(1.0)).exp();
    let yr = p.key * y / average;
    let ld = yr / (1.0 + yr);
    let s = 0.04 / (0.04 + y * p.luminance_scale);
    ((ld / y) * c * (1.0 - s) + SCOTOPIC_TINT * ld * s) * p.exposure
}

/// Linear [0, 1] → 8-bit sRGB.
pub fn srgb_byte(v_in: f32) -> u32 {
    let v = if v_in.is_finite() { v_in } else { 0.0 }.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u32
}

/// RGBA8 in one u32, red in the low byte.
pub fn pack_srgb(c: Vec3) -> u32 {
    srgb_byte(c.x) | (srgb_byte(c.y) << 8) | (srgb_byte(c.z) << 16) | (255 << 24)
}
