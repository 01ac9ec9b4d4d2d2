// Tone mapping's shared pieces (docs/design.md section 9): luminance, the finite test that keeps
// NaN/Inf pixels out of the log-average, the operator, and sRGB encoding.
// Twin: src/shared/tone.rs.

// #import types

// ToneParams.mode
const TONE_REINHARD: u32 = 0u;
const TONE_LINEAR: u32 = 1u;

// Rec. 709 luminance of linear RGB.
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// WGSL has no isnan/isinf: a float is finite when its exponent bits are not all ones.
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn all_finite(c: vec3<f32>) -> bool {
    return is_finite(c.x) && is_finite(c.y) && is_finite(c.z);
}

// What a pixel adds to the log-average: (log(eps + Y), 1), or nothing when it is not finite.
// Negative components (none should exist) count as zero.
fn log_luminance(c: vec3<f32>, epsilon: f32) -> vec2<f32> {
    if !all_finite(c) {
        return vec2<f32>(0.0);
    }
    return vec2<f32>(log(epsilon + luminance(max(c, vec3<f32>(0.0)))), 1.0);
}

// The scotopic tint of docs/design.md section 9: night vision sees blue.
const SCOTOPIC_TINT: vec3<f32> = vec3<f32>(1.05, 0.97, 1.27);

// Display RGB in [0, 1] of a linear HDR pixel; `log_sum` is (sum of log(eps + Y), count).
// Reinhard: Yr = a Y / Yavg, Ld = Yr / (1 + Yr), blended towards a grey-blue by
// s = 0.04 / (0.04 + Y in cd/m2); then the exposure. Linear: the pixel times the exposure.
fn tone_map(c_in: vec3<f32>, log_sum: vec2<f32>, p: ToneParams) -> vec3<f32> {
    if !all_finite(c_in) {
        return vec3<f32>(0.0);
    }
    let c = max(c_in, vec3<f32>(0.0));
    if p.mode == TONE_LINEAR {
        return c * p.exposure;
    }
    let y = luminance(c);
    if y <= 0.0 {
        return vec3<f32>(0.0);
    }
    let average = exp(log_sum.x / max(log_sum.y, 1.0));
    let yr = p.key * y / average;
    let ld = yr / (1.0 + yr);
    let s = 0.04 / (0.04 + y * p.luminance_scale);
    return ((ld / y) * c * (1.0 - s) + SCOTOPIC_TINT * ld * s) * p.exposure;
}

// Linear [0, 1] to 8-bit sRGB.
fn srgb_byte(v_in: f32) -> u32 {
    let v = clamp(select(0.0, v_in, is_finite(v_in)), 0.0, 1.0);
    let s = select(1.055 * pow(v, 1.0 / 2.4) - 0.055, 12.92 * v, v <= 0.0031308);
    return u32(s * 255.0 + 0.5);
}

// RGBA8 (alpha 255) in one u32, red in the low byte: the byte order of an RGBA image.
fn pack_srgb(c: vec3<f32>) -> u32 {
    return srgb_byte(c.x) | (srgb_byte(c.y) << 8u) | (srgb_byte(c.z) << 16u) | (255u << 24u);
}
