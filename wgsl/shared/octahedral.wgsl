// Unit directions in 32 bits: the octahedral map (Meyer et al. 2010) with two snorm16
// components, about 5e-5 rad apart at worst. Binned photons carry their direction this way.
// Twin: src/shared/octahedral.rs.

fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

fn oct_encode(d: vec3<f32>) -> u32 {
    let p = d.xy / (abs(d.x) + abs(d.y) + abs(d.z));
    var q = p;
    if d.z < 0.0 {
        q = (vec2<f32>(1.0) - abs(p.yx)) * sign_not_zero(p);
    }
    return pack2x16snorm(q);
}

fn oct_decode(code: u32) -> vec3<f32> {
    let p = unpack2x16snorm(code);
    let z = 1.0 - abs(p.x) - abs(p.y);
    let fold = max(-z, 0.0);
    let xy = p - fold * sign_not_zero(p);
    return normalize(vec3<f32>(xy, z));
}

// A binned photon's surface (its splat's normal) in an f32 that holds a whole number below 2^24:
// the octahedral map at 12 bits per axis, ux + 4096 uy. A number, not bits, so that no device
// can alter it in a copy (bin_power's w).
const SURFACE_STEPS: f32 = 4095.0;

fn surface_encode(n: vec3<f32>) -> f32 {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    var q = p;
    if n.z < 0.0 {
        q = (vec2<f32>(1.0) - abs(p.yx)) * sign_not_zero(p);
    }
    let u = round((clamp(q, vec2<f32>(-1.0), vec2<f32>(1.0)) * 0.5 + 0.5) * SURFACE_STEPS);
    return u.x + 4096.0 * u.y;
}

fn surface_decode(code: f32) -> vec3<f32> {
    let c = u32(code);
    let p = vec2<f32>(f32(c % 4096u), f32(c / 4096u)) * (2.0 / SURFACE_STEPS) - 1.0;
    let z = 1.0 - abs(p.x) - abs(p.y);
    let fold = max(-z, 0.0);
    let xy = p - fold * sign_not_zero(p);
    return normalize(vec3<f32>(xy, z));
}
