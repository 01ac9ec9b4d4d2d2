// Splat pass 3, shading (docs/design.md section 8): per pixel, normalise the blended sums of the
// attribute pass, add direct light from every light by shadow rays through the splat grid
// (area lights on a jittered area_samples^2 grid), and show area lights the view ray meets
// before the surface. Writes linear HDR radiance for tone mapping. Twin: src/cpu/shade.rs.

// #import types
// #import dispatch
// #import rng
// #import splat
// #import trace

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> params: ShadeParams;
@group(0) @binding(2) var radiance_sum: texture_2d<f32>;
@group(0) @binding(3) var geometry_sum: texture_2d<f32>;
@group(0) @binding(4) var diffuse_sum: texture_2d<f32>;
@group(0) @binding(5) var specular_sum: texture_2d<f32>;
@group(0) @binding(6) var<storage, read> lights: array<Light>;
@group(0) @binding(7) var<storage, read_write> hdr: array<vec4<f32>>;

const WG: u32 = 64u;

// Roughness below this gives no direct highlight (a mirror needs the lobes, not a sample).
const MIN_ALPHA: f32 = 1e-3;

// A surface point as the shade pass sees it.
struct Surface {
    p: vec3<f32>,
    n: vec3<f32>,
    wo: vec3<f32>,
    rho_d: vec3<f32>,
    rho_s: vec3<f32>,
    alpha: f32,
}

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

fn brdf(sf: Surface, wi: vec3<f32>) -> vec3<f32> {
    var f = sf.rho_d / PI;
    if sf.alpha >= MIN_ALPHA {
        f += sf.rho_s * ward_specular(sf.n, wi, sf.wo, sf.alpha);
    }
    return f;
}

// Reflected radiance of one light sample, if nothing shadows it.
fn shade_sample(sf: Surface, ls: LightSample) -> vec3<f32> {
    let cos_i = dot(sf.n, ls.wi);
    if !(cos_i > 0.0) || all(ls.e <= vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let o = sf.p + params.shadow_bias * sf.n;
    var budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(o, ls.wi, NO_SPLAT, ls.dist - params.shadow_bias, &budget);
    if hit.splat != NO_SPLAT {
        return vec3<f32>(0.0);
    }
    return brdf(sf, ls.wi) * ls.e * cos_i;
}

fn direct(sf: Surface, pixel: u32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let key = pcg_hash(pcg_hash(params.seed) + pixel);
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        if l.kind != LIGHT_AREA {
            sum += shade_sample(sf, sample_light(l, sf.p, 0.0, 0.0));
            continue;
        }
        let n = params.area_samples;
        let inv_n = 1.0 / f32(n);
        var area_sum = vec3<f32>(0.0);
        for (var j = 0u; j < n * n; j++) {
            let r = key + (li * n * n + j) * 2u;
            let u = (f32(j % n) + unit_float(pcg_hash(r))) * inv_n;
            let v = (f32(j / n) + unit_float(pcg_hash(r + 1u))) * inv_n;
            area_sum += shade_sample(sf, sample_light(l, sf.p, u, v));
        }
        sum += area_sum * (inv_n * inv_n);
    }
    return sum;
}

// The radiance of the nearest area light the view ray meets before t_surface, or -1.
fn emitted(d: vec3<f32>, t_surface: f32) -> vec3<f32> {
    var out = vec3<f32>(-1.0);
    var t_near = t_surface;
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        let denom = dot(d, l.direction);
        if l.kind != LIGHT_AREA || !(denom < 0.0) {
            continue;
        }
        let t = dot(l.position - cam.eye, l.direction) / denom;
        let q = cam.eye + t * d - l.position;
        let u = dot(q, l.edge_u) / dot(l.edge_u, l.edge_u);
        let v = dot(q, l.edge_v) / dot(l.edge_v, l.edge_v);
        if t > 0.0 && t < t_near && u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0 {
            t_near = t;
            out = l.power / (PI * l.area);
        }
    }
    return out;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    let size = vec2<u32>(cam.size);
    if i >= size.x * size.y {
        return;
    }
    let px = vec2<u32>(i % size.x, i / size.x);
    let d = pixel_ray(cam, vec2<f32>(px) + 0.5);
    let acc = textureLoad(radiance_sum, px, 0);
    var color = vec3<f32>(0.0);
    var t_surface = FAR;
    if acc.w > 0.0 {
        let inv_w = 1.0 / acc.w;
        let g = textureLoad(geometry_sum, px, 0);
        let dif = textureLoad(diffuse_sum, px, 0);
        let spec = textureLoad(specular_sum, px, 0);
        t_surface = g.w * inv_w;
        var sf: Surface;
        sf.p = cam.eye + t_surface * d;
        sf.n = select(-d, normalize(g.xyz), dot(g.xyz, g.xyz) > 0.0);
        sf.wo = -d;
        // Terms the frame does not show weigh nothing; with neither, no shadow ray is cast.
        sf.rho_d = select(vec3<f32>(0.0), dif.xyz * inv_w, (params.show & SHOW_DIRECT_DIFFUSE) != 0u);
        sf.rho_s = select(vec3<f32>(0.0), spec.xyz * inv_w, (params.show & SHOW_DIRECT_SPECULAR) != 0u);
        sf.alpha = select(0.0, dif.w / spec.w, spec.w > 0.0);
        color = acc.xyz * inv_w;
        if (params.show & (SHOW_DIRECT_DIFFUSE | SHOW_DIRECT_SPECULAR)) != 0u {
            color += direct(sf, i);
        }
    }
    // A light seen directly hides what lies behind it; its radiance counts with the direct
    // diffuse term, so that the parts a frame can show add up to the whole.
    let seen = emitted(d, t_surface);
    let light = select(vec3<f32>(0.0), seen, (params.show & SHOW_DIRECT_DIFFUSE) != 0u);
    hdr[i] = vec4<f32>(select(color, light, seen.x >= 0.0), 1.0);
}
