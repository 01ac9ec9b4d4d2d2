// Splat pass 3, shading (docs/design.md section 8): per pixel, normalise the blended sums of the
// attribute pass, add direct light from every light by shadow rays through the splat grid
// (area lights on a jittered area_samples^2 grid, or this refinement frame's strata of it)
// unless it was baked, and show area lights the view ray meets before the surface. Writes
// linear HDR radiance for tone mapping, or adds a refinement frame to the running mean.
//
// Glossy rays (params.glossy_rays > 0, still images): the glossy surfaces' indirect light is
// traced here instead of read from their lobes, which blur it over their width: each ray
// samples the Ward lobe at the pixel and brings back the baked light of the surface it meets,
// albedo / pi times its direct (the direct bake) and photon irradiance, as final gathering
// does (hit_albedo: a glossy disk counts its specular albedo too, as if it spread that light
// evenly; its lobes are not read here). A ray that meets a light first brings none: direct
// light is the shadow rays' part.
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
// #paged
@group(0) @binding(8) var<storage, read> splat_light: array<SplatLight>;
// #paged
@group(0) @binding(9) var<storage, read> direct_light: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> materials: array<Material>;
// Per pixel the surface shown (normal, reversed where a light shows; distance along the view
// ray, FAR where none): what the moving frames' temporal pass reprojects.
@group(0) @binding(11) var<storage, read_write> surface: array<vec4<f32>>;

const WG: u32 = 64u;
// Keeps the glossy rays' random numbers apart from the shadow rays'.
const GLOSSY_SALT: u32 = 0x9e3779b9u;

// Whether this pipeline casts shadow rays: frames of baked direct light take one without, so
// that no shadow-ray code is compiled into it (llvmpipe paid for that code even where
// params.direct skipped it: 15.6 ms against 4.9 ms per 512^2 frame of the bunny).
override SHADOW_RAYS: bool = true;

// A surface point as the shade pass sees it.
struct Surface {
    p: vec3<f32>,
    n: vec3<f32>,
    wo: vec3<f32>,
    rho_d: vec3<f32>,
    rho_s: vec3<f32>,
    alpha: f32,
}

// Reflected radiance of one light sample, if nothing shadows it, its specular part weighted by
// `spec_weight` (multiple importance sampling against the BRDF's samples).
fn shade_sample(sf: Surface, l: Light, ls: LightSample, spec_weight: f32) -> vec3<f32> {
    let cos_i = dot(sf.n, ls.wi);
    if !(cos_i > 0.0) || all(ls.e <= vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let o = sf.p + params.shadow_bias * sf.n;
    var budget = SHADOW_RAY_BUDGET;
    let reach = shadow_reach(l, o, ls.wi, ls.dist, params.shadow_bias);
    let hit = trace_ray(o, ls.wi, NO_SPLAT, reach, &budget);
    if hit.splat != NO_SPLAT {
        return vec3<f32>(0.0);
    }
    var f = sf.rho_d / PI;
    if sf.alpha >= MIN_ALPHA {
        f += spec_weight * sf.rho_s * ward_specular(sf.n, ls.wi, sf.wo, sf.alpha);
    }
    return f * ls.e * cos_i;
}

// The solid-angle pdf of a stratified light's sample along `wi` (light_pdf: an area light's
// point at distance `dist`, a direction of a sky or the sun's disk towards a surface of
// normal n), times `count` samples.
fn area_pdf(l: Light, n: vec3<f32>, wi: vec3<f32>, dist: f32, count: f32) -> f32 {
    return count * light_pdf(l, n, wi, dist);
}

// Whether the Ward lobe at sf is narrower than area light l seen from it (4 pi alpha^2, about
// the reflected lobe's solid angle, under the light's A cos / d^2): the light's points then
// seldom meet the lobe, which one sample of the lobe finds (the path tracer does the same).
// Wider lobes are lit by the light's strata alone, which vary less than a random lobe sample.
fn narrow_lobe(sf: Surface, l: Light) -> bool {
    if !(sf.alpha >= MIN_ALPHA) || all(sf.rho_s <= vec3<f32>(0.0)) {
        return false;
    }
    // A sky surrounds every lobe; the sun's disk is narrower than nearly all.
    if l.kind == LIGHT_ENVIRONMENT {
        return true;
    }
    if l.kind == LIGHT_SUN {
        return 4.0 * PI * sf.alpha * sf.alpha < sun_solid_angle(l);
    }
    let to = l.position + 0.5 * (l.edge_u + l.edge_v) - sf.p;
    let d2 = dot(to, to);
    let cos_l = -dot(to, l.direction) * inverseSqrt(d2);
    return 4.0 * PI * sf.alpha * sf.alpha * d2 < l.area * max(cos_l, 0.0);
}

// The glossy part of stratified light l's direct light by one sample of the Ward lobe (at the
// unit square's point u), weighted by the power heuristic against the frame's `count` light
// samples.
fn specular_by_brdf(sf: Surface, l: Light, u: vec2<f32>, count: f32) -> vec3<f32> {
    let s = ward_sample(frame_of(sf.n), sf.wo, u.x, u.y, sf.alpha);
    let wi = s.wo;
    let cos_i = dot(sf.n, wi);
    if !(s.weight > 0.0) || !(cos_i > 0.0) {
        return vec3<f32>(0.0);
    }
    let o = sf.p + params.shadow_bias * sf.n;
    // An area light where the ray meets its face; a sky or the sun past everything.
    let far = l.kind != LIGHT_AREA;
    let t = select(area_light_hit(l, o, wi), FAR, far);
    var radiance = l.power / (PI * l.area);
    if far {
        radiance = escaped_radiance(l, wi);
    }
    if !(t > 0.0) || all(radiance <= vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    var budget = SHADOW_RAY_BUDGET;
    if trace_ray(o, wi, NO_SPLAT, t - params.shadow_bias, &budget).splat != NO_SPLAT {
        return vec3<f32>(0.0);
    }
    let pdf_brdf = ward_pdf(sf.n, sf.wo, wi, sf.alpha);
    let pdf_light = area_pdf(l, sf.n, wi, t, count);
    // f L cos / pdf_brdf times the heuristic's pdf_brdf^2 / (pdf_brdf^2 + pdf_light^2).
    let scale = pdf_brdf / (pdf_brdf * pdf_brdf + pdf_light * pdf_light);
    return sf.rho_s * ward_specular(sf.n, wi, sf.wo, sf.alpha) * radiance * (cos_i * scale);
}

fn direct(sf: Surface, pixel: u32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let key = pcg_hash(pcg_hash(params.seed) + pixel);
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        if !stratified(l.kind) {
            sum += shade_sample(sf, l, sample_light(l, sf.p, sf.n, 0.0, 0.0), 1.0);
            continue;
        }
        // This frame's strata of the n x n grid: all of them, or a refinement frame's share;
        // a lobe narrower than the light adds one sample of its own, each strategy's glossy
        // part weighted by the power heuristic.
        // A sky's grid is finer than an area light's: each frame takes as many more strata.
        let n = strata_side(l.kind, params.area_samples);
        let finer = (n * n) / (params.area_samples * params.area_samples);
        let area_count = params.area_count * finer;
        let count = f32(area_count);
        let glossy = narrow_lobe(sf, l);
        var area_sum = vec3<f32>(0.0);
        // The strata turned by a per-pixel offset: refinement frame k samples the pixel at
        // jitter point k, and without the turn at stratum k too, which tied the point in the
        // pixel to the point on the light (the diffuse box's blocks read 2 % bright in direct
        // light at 16 frames).
        let turn = pcg_hash(key) % (n * n);
        for (var k = 0u; k < area_count; k++) {
            let j = (params.area_first * finer + k + turn) % (n * n);
            let uv = area_point(j, n, key + (li * n * n + j) * 2u, true);
            let ls = sample_light(l, sf.p, sf.n, uv.x, uv.y);
            var w = 1.0;
            if glossy {
                let pdf_brdf = ward_pdf(sf.n, sf.wo, ls.wi, sf.alpha);
                w = power_heuristic(area_pdf(l, sf.n, ls.wi, ls.dist, count), pdf_brdf);
            }
            area_sum += shade_sample(sf, l, ls, w);
        }
        sum += area_sum * (1.0 / count);
        if glossy {
            // One point a refinement frame of the pixel's R2 sequence, its shift from random
            // numbers past every stratum's.
            let shift = r2_shift(key + (params.light_count * n * n + li) * 2u);
            sum += specular_by_brdf(sf, l, r2_point(params.sample, shift), count);
        }
    }
    return sum;
}

// The glossy part of the indirect light at sf (its unshown terms zeroed) by the frame's glossy
// rays, each a sample of the Ward lobe at the next points of the pixel's R2 sequence (shifted
// by `shift`): numbered on across refinement frames, a still image's rays stratify the lobe.
fn glossy_indirect(sf: Surface, shift: vec2<u32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let o = sf.p + params.shadow_bias * sf.n;
    let f = frame_of(sf.n);
    for (var k = 0u; k < params.glossy_rays; k++) {
        let u = r2_point(params.sample * params.glossy_rays + k, shift);
        let s = ward_sample(f, sf.wo, u.x, u.y, sf.alpha);
        if !(s.weight > 0.0) || !(dot(sf.n, s.wo) > 0.0) {
            continue;
        }
        var budget = SHADOW_RAY_BUDGET;
        let hit = trace_ray(o, s.wo, NO_SPLAT, FAR, &budget);
        if hit.splat == NO_SPLAT {
            continue;
        }
        var lit = false;
        for (var li = 0u; li < params.light_count; li++) {
            lit = lit || light_first(lights[li], o, s.wo, hit.t);
        }
        let h = splats_at(hit.splat);
        if lit || dot(h.normal, s.wo) >= 0.0 {
            continue;
        }
        let e = direct_light_at(hit.splat).xyz + splat_light_at(hit.splat).irradiance;
        sum += s.weight * hit_albedo(h, materials[h.material]) * e * (1.0 / PI);
    }
    return sf.rho_s * sum * (1.0 / f32(params.glossy_rays));
}

// How far past the blended surface, relative to its distance, a reflecting light still counts
// as in front of it (src/cpu/shade.rs has the same).
const REFLECTING_LIGHT_SLACK: f32 = 0.01;

// The radiance of the nearest area light the view ray meets before t_surface, in xyz; w is 1
// where the light reflects (its own surface, just behind its face, shows too), 0 where it hides
// what lies behind it, and -1 where the ray meets no light. A ray that meets nothing (t_surface
// FAR) sees the sky and the sun's disk, if the scene has them, as a light that hides nothing.
fn emitted(d: vec3<f32>, t_surface: f32) -> vec4<f32> {
    var out = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    var t_near = t_surface;
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        let t = area_light_hit(l, cam.eye, d);
        let reflects = (l.flags & LIGHT_REFLECTS) != 0u;
        // A light that reflects lies in front of its own surface by less than the depth
        // targets round (f16 where the device cannot blend f32): within REFLECTING_LIGHT_SLACK
        // of the surface's distance, that surface counts as the light's own.
        let limit = select(t_near, t_near * (1.0 + REFLECTING_LIGHT_SLACK), reflects);
        if t > 0.0 && t < limit {
            t_near = t;
            out = vec4<f32>(l.power / (PI * l.area), select(0.0, 1.0, reflects));
        }
    }
    // Past every surface, the background: a colour, or the sky and the sun's disk.
    if t_surface >= FAR && out.w < 0.0 && params.background.w > 0.0 {
        return vec4<f32>(params.background.xyz, 0.0);
    }
    if t_surface >= FAR && out.w < 0.0 {
        var seen = vec3<f32>(0.0);
        var any_light = false;
        for (var li = 0u; li < params.light_count; li++) {
            let l = lights[li];
            seen += escaped_radiance(l, d);
            any_light = any_light || l.kind == LIGHT_ENVIRONMENT || l.kind == LIGHT_SUN;
        }
        if any_light {
            out = vec4<f32>(seen, 0.0);
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
    var normal = vec3<f32>(0.0);
    if acc.w > 0.0 {
        let inv_w = 1.0 / acc.w;
        let g = textureLoad(geometry_sum, px, 0);
        let dif = textureLoad(diffuse_sum, px, 0);
        let spec = textureLoad(specular_sum, px, 0);
        t_surface = g.w * inv_w;
        var sf: Surface;
        sf.p = cam.eye + t_surface * d;
        sf.n = select(-d, normalize(g.xyz), dot(g.xyz, g.xyz) > 0.0);
        normal = sf.n;
        sf.wo = -d;
        // Terms the frame does not show weigh nothing; with neither, no shadow ray is cast.
        sf.rho_d = select(vec3<f32>(0.0), dif.xyz * inv_w, (params.show & SHOW_DIRECT_DIFFUSE) != 0u);
        sf.rho_s = select(vec3<f32>(0.0), spec.xyz * inv_w, (params.show & SHOW_DIRECT_SPECULAR) != 0u);
        sf.alpha = select(0.0, dif.w / spec.w, spec.w > 0.0);
        color = acc.xyz * inv_w;
        // Baked direct light came with the attribute pass's sums.
        let rays = SHADOW_RAYS && params.direct == DIRECT_RAYS;
        if rays && (params.show & (SHOW_DIRECT_DIFFUSE | SHOW_DIRECT_SPECULAR)) != 0u {
            color += direct(sf, i);
        }
        let glossy = params.glossy_rays > 0u && sf.alpha >= MIN_ALPHA;
        if rays && glossy && (params.show & SHOW_INDIRECT_SPECULAR) != 0u {
            var g = sf;
            g.rho_s = spec.xyz * inv_w;
            // Random numbers apart from the shadow rays' (those use the key itself, plus).
            color += glossy_indirect(g, r2_shift(pcg_hash(pcg_hash(params.seed ^ GLOSSY_SALT) + i)));
        }
    }
    // A light seen directly hides what lies behind it, or adds to its own surface where it
    // reflects; its radiance counts with the direct diffuse term, so that the parts a frame
    // can show add up to the whole.
    let seen = emitted(d, t_surface);
    let light = select(vec3<f32>(0.0), seen.xyz, (params.show & SHOW_DIRECT_DIFFUSE) != 0u);
    var shown_color = color;
    if seen.w > 0.0 {
        shown_color = color + light;
    } else if seen.w == 0.0 {
        shown_color = light;
    }
    let out = vec4<f32>(shown_color, 1.0);
    // A light's pixels carry the normal reversed: to the temporal pass a light and the surface
    // it lies on are two surfaces, so that no history carries its brightness onto the ceiling.
    surface[i] = vec4<f32>(select(normal, -normal, seen.w >= 0.0), t_surface);
    // Refinement: the running mean of this frame and the `sample` frames before it.
    if params.sample == 0u {
        hdr[i] = out;
    } else {
        hdr[i] += (out - hdr[i]) * (1.0 / f32(params.sample + 1u));
    }
}
