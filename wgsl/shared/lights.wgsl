// Light sampling (docs/design.md section 8): the irradiance one point of a light brings to a
// surface point, and the stratified points of an area light. Shared by the shade pass (shadow
// rays per pixel), the direct bake (shadow rays per splat) and the attribute pass (baked
// visibility times the BRDF towards each light). Twin: src/shared/lights.rs.

// #import types
// #import sampling
// #import rng

// Roughness below this gives no direct highlight (a mirror needs the lobes, not a sample).
const MIN_ALPHA: f32 = 1e-3;

// Light arriving at p from one light sample: its direction, distance (for the shadow ray)
// and irradiance on a surface facing it.
struct LightSample {
    wi: vec3<f32>,
    dist: f32,
    e: vec3<f32>,
}

// The mean of a spot's smooth falloff over its cone, uniform in cos (see photons.rs).
fn spot_falloff_mean(l: Light) -> f32 {
    if l.cos_inner <= l.cos_outer {
        return 1.0;
    }
    return ((l.cos_inner - l.cos_outer) * 0.5 + (1.0 - l.cos_inner)) / (1.0 - l.cos_outer);
}

// A point on a light towards p: (u, v) picks the point of an area light.
fn sample_light(l: Light, p: vec3<f32>, u: f32, v: f32) -> LightSample {
    var s: LightSample;
    if l.kind == LIGHT_DIRECTIONAL {
        s.wi = -l.direction;
        s.dist = FAR;
        s.e = l.power / l.area;
        return s;
    }
    var q = l.position;
    if l.kind == LIGHT_AREA {
        q += u * l.edge_u + v * l.edge_v;
    }
    let to = q - p;
    let d2 = dot(to, to);
    s.dist = sqrt(d2);
    s.wi = to / s.dist;
    let cos_l = -dot(s.wi, l.direction);
    if l.kind == LIGHT_AREA {
        // Radiance power / (pi A) over the whole rectangle: pdf 1 / A per point.
        s.e = l.power * (max(cos_l, 0.0) / (PI * d2));
    } else if l.kind == LIGHT_SPOT {
        let ramp = select(1.0, smoothstep(l.cos_outer, l.cos_inner, cos_l), l.cos_inner > l.cos_outer);
        let inside = select(0.0, ramp, cos_l >= l.cos_outer);
        let solid_angle = 2.0 * PI * (1.0 - l.cos_outer);
        s.e = l.power * (inside / (spot_falloff_mean(l) * solid_angle * d2));
    } else {
        s.e = l.power / (4.0 * PI * d2);
    }
    return s;
}

// Stratum j of an area light's n x n grid, jittered by the two hashes at r and r + 1
// (jitter false: the stratum's centre).
fn area_point(j: u32, n: u32, r: u32, jitter: bool) -> vec2<f32> {
    let inv_n = 1.0 / f32(n);
    var o = vec2<f32>(0.5);
    if jitter {
        o = vec2<f32>(unit_float(pcg_hash(r)), unit_float(pcg_hash(r + 1u)));
    }
    return (vec2<f32>(f32(j % n), f32(j / n)) + o) * inv_n;
}

// Whether the ray (o, d) meets area light l before distance t (a surface's hit) and ends
// there. A light that reflects (LIGHT_REFLECTS) ends nothing: the ray goes on to its surface's
// splats just behind its face, which reflect as any surface does.
fn light_first(l: Light, o: vec3<f32>, d: vec3<f32>, t: f32) -> bool {
    if (l.flags & LIGHT_REFLECTS) != 0u {
        return false;
    }
    let tl = area_light_hit(l, o, d);
    return tl > 0.0 && tl < t;
}

// How far a shadow ray from o (its surface point lifted by bias) towards a sample of light l
// at dist from that point looks for what shadows it: dist - bias, and for a light that
// reflects no farther than its face, so that its own surface just behind that face never
// shadows it (the lifted ray can cross the face before dist - bias).
fn shadow_reach(l: Light, o: vec3<f32>, wi: vec3<f32>, dist: f32, bias: f32) -> f32 {
    let reach = dist - bias;
    if (l.flags & LIGHT_REFLECTS) == 0u {
        return reach;
    }
    let t = area_light_hit(l, o, wi);
    return select(reach, min(reach, t), t > 0.0);
}

// Where ray (o, d) meets area light l's emitting face: t > 0, or -1 when it misses it (or
// meets its back, which emits nothing).
fn area_light_hit(l: Light, o: vec3<f32>, d: vec3<f32>) -> f32 {
    let denom = dot(d, l.direction);
    if l.kind != LIGHT_AREA || !(denom < 0.0) {
        return -1.0;
    }
    let t = dot(l.position - o, l.direction) / denom;
    let q = o + t * d - l.position;
    let u = dot(q, l.edge_u) / dot(l.edge_u, l.edge_u);
    let v = dot(q, l.edge_v) / dot(l.edge_v, l.edge_v);
    return select(-1.0, t, t > 0.0 && u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0);
}
