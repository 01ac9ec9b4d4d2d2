//! Twin of `wgsl/shared/octahedral.wgsl`: unit directions in 32 bits (octahedral map, two
//! snorm16), with WGSL's `pack2x16snorm` rounding (to nearest, ties to even).

use glam::{Vec2, Vec3};

fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(
        if v.x >= 0.0 { 1.0 } else { -1.0 },
        if v.y >= 0.0 { 1.0 } else { -1.0 },
    )
}

fn snorm16(x: f32) -> u32 {
    ((x.clamp(-1.0, 1.0) * 32767.0).round_ties_even() as i16) as u16 as u32
}

fn unsnorm16(bits: u32) -> f32 {
    ((bits as u16 as i16) as f32 / 32767.0).max(-1.0)
}

pub fn oct_encode(d: Vec3) -> u32 {
    let p = Vec2::new(d.x, d.y) / (d.x.abs() + d.y.abs() + d.z.abs());
    let q = if d.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * sign_not_zero(p)
    } else {
        p
    };
    snorm16(q.x) | (snorm16(q.y) << 16)
}

pub fn oct_decode(code: u32) -> Vec3 {
    let p = Vec2::new(unsnorm16(code & 0xffff), unsnorm16(code >> 16));
    let z = 1.0 - p.x.abs() - p.y.abs();
    let fold = (-z).max(0.0);
    let xy = p - fold * sign_not_zero(p);
    Vec3::new(xy.x, xy.y, z).normalize()
}

/// `SURFACE_STEPS` in WGSL: 12 bits per axis of a surface code.
const SURFACE_STEPS: f32 = 4095.0;

/// A binned photon's surface (its splat's normal) as a whole number below 2²⁴ in an f32.
pub fn surface_encode(n: Vec3) -> f32 {
    let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
    let q = if n.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * sign_not_zero(p)
    } else {
        p
    };
    let u =
        ((q.clamp(Vec2::NEG_ONE, Vec2::ONE) * 0.5 + 0.5) * SURFACE_STEPS).map(f32::round_ties_even);
    u.x + 4096.0 * u.y
}

pub fn surface_decode(code: f32) -> Vec3 {
    let c = code as u32;
    let p = Vec2::new((c % 4096) as f32, (c / 4096) as f32) * (2.0 / SURFACE_STEPS) - 1.0;
    let z = 1.0 - p.x.abs() - p.y.abs();
    let fold = (-z).max(0.0);
    let xy = p - fold * sign_not_zero(p);
    Vec3::new(xy.x, xy.y, z).normalize()
}
