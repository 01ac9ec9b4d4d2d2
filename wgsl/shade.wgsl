// Splat pass 3, shading (docs/design.md section 8): per pixel, normalise the blended sums of the
// attribute pass, add direct light from every light by shadow rays through the splat grid
// (area lights on a jittered area_samples^2 grid, or this refinement frame's strata of it)
// unless it was baked, and show area lights the view ray meets before the surface. Writes
// linear HDR radiance for tone mapping, or adds a refinement frame to the running mean.
// Twin: src/cpu/shade.rs.

// #import types
// #import dispatch
// #import rng
// #import splat
// #import trace
// #import lights

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> params: ShadeParams;
@group(0) @binding(2) var radiance_sum: texture_2d<f32>;
@group(0) @binding(3) var geometry_sum: texture_2d<f32>;
@group(0) @binding(4) var diffuse_sum: texture_2d<f32>;
@group(0) @binding(5) var specular_sum: texture_2d<f32>;
@group(0) @binding(6) var<storage, read> lights: array<Light>;
@group(0) @binding(7) var<storage, read_write> hdr: array<vec4<f32>>;

const WG: u32 = 64u;

// A surface point as the shade pass sees it.
struct Surface {
    p: vec3<f32>,
    n: vec3<f32>,
    wo: vec3<f32>,
    rho_d: vec3<f32>,
    rho_s: vec3<f32>,
    alpha: f32,
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
        // This frame's strata of the n x n grid: all of them, or a refinement frame's share.
        let n = params.area_samples;
        var area_sum = vec3<f32>(0.0);
        for (var k = 0u; k < params.area_count; k++) {
            let j = (params.area_first + k) % (n * n);
            let uv = area_point(j, n, key + (li * n * n + j) * 2u, true);
            area_sum += shade_sample(sf, sample_light(l, sf.p, uv.x, uv.y));
        }
        sum += area_sum * (1.0 / f32(params.area_count));
    }
    return sum;
}

// The radiance of the nearest area light the view ray meets before t_surface, or -1.
fn emitted(d: vec3<f32>, t_surface: f32) -> vec3<f32> {
    var out = vec3<f32>(-1.0);
    var t_near = t_surface;
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        let t = area_light_hit(l, cam.eye, d);
        if t > 0.0 && t < t_near {
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
        // Baked direct light came with the attribute pass's sums.
        let rays = params.direct == DIRECT_RAYS;
        if rays && (params.show & (SHOW_DIRECT_DIFFUSE | SHOW_DIRECT_SPECULAR)) != 0u {
            color += direct(sf, i);
        }
    }
    // A light seen directly hides what lies behind it; its radiance counts with the direct
    // diffuse term, so that the parts a frame can show add up to the whole.
    let seen = emitted(d, t_surface);
    let light = select(vec3<f32>(0.0), seen, (params.show & SHOW_DIRECT_DIFFUSE) != 0u);
    let out = vec4<f32>(select(color, light, seen.x >= 0.0), 1.0);
    // Refinement: the running mean of this frame and the `sample` frames before it.
    if params.sample == 0u {
        hdr[i] = out;
    } else {
        hdr[i] += (out - hdr[i]) * (1.0 / f32(params.sample + 1u));
    }
}
