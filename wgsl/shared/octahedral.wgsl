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
