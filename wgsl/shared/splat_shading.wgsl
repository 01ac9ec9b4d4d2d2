// What a splat is shaded with (docs/design.md sections 7-8), for the attribute pass, the
// compute splatter and splat_shade alike: the indirect light from the splat's lobes and
// irradiance, and the baked direct light. The bindings 2-9 of group 0 are declared here, so
// that all three stages bind them at the same numbers; bindings 0 (the camera) and 1 (the
// splats) are the stage's, and so is `sky`, the environment light's map that lights.wgsl
// reads, after the stage's own bindings: only splat_shade reads it (baked_direct, where the
// scene has a sky). Twin: src/cpu/splat_shading.rs.

// #import splat
// #import lobe_brdf
// #import lights

@group(0) @binding(2) var<uniform> params: ShadeParams;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
// #paged
@group(0) @binding(4) var<storage, read> splat_light: array<SplatLight>;
// #paged
@group(0) @binding(5) var<storage, read> lobes: array<Lobe>;
@group(0) @binding(6) var<storage, read> lobe_norms: array<f32>;
@group(0) @binding(7) var<storage, read> lights: array<Light>;
// The direct bake's (direct_bake.wgsl): per splat (shadowed irradiance, 0), and per splat and
// light the light's visibility. Read only when params.direct is DIRECT_BAKED.
// #paged
@group(0) @binding(8) var<storage, read> direct: array<vec4<f32>>;
// #paged
@group(0) @binding(9) var<storage, read> visibility: array<f32>;

// The hemispherical integral of a lobe of width beta2 about axis (lobe_norms).
fn lobe_norm(n: vec3<f32>, axis: vec3<f32>, beta2: f32) -> f32 {
    let l = norm_lookup(dot(n, axis), beta2);
    let i = l.index;
    let row = NORM_COS_NODES;
    let lo = lobe_norms[i] + l.fx * (lobe_norms[i + 1u] - lobe_norms[i]);
    let hi = lobe_norms[i + row] + l.fx * (lobe_norms[i + row + 1u] - lobe_norms[i + row]);
    return lo + l.fy * (hi - lo);
}

// Radiance leaving splat `i` towards wo by the light its photons brought (thesis 3.6.1).
fn indirect(i: u32, s: Splat, m: Material, wo: vec3<f32>) -> vec3<f32> {
    let light = splat_light_at(i);
    var spec = vec3<f32>(0.0);
    let first = light.first_lobe;
    // With glossy rays the shade pass traces this part instead, where the BRDF can be sampled.
    let traced = params.glossy_rays > 0u && params.direct == DIRECT_RAYS && m.roughness >= MIN_ALPHA;
    let lobes_shown = (params.show & SHOW_INDIRECT_SPECULAR) != 0u && !traced;
    let shown = select(0u, light.lobes, lobes_shown);
    for (var k = 0u; k < shown; k++) {
        let lobe = lobes_at(first + k);
        let beta2 = lobe_beta2(params.family, lobe.sharpness);
        let norm = lobe_norm(s.normal, lobe.axis, beta2);
        spec += lobe.irradiance * lobe_specular(s.normal, wo, lobe.axis, m.roughness, beta2, norm);
    }
    let diffuse = select(vec3<f32>(0.0), s.diffuse * (light.irradiance / PI),
                         (params.show & SHOW_INDIRECT_DIFFUSE) != 0u);
    return diffuse + m.specular * spec;
}

// The specular light one light sample reflects towards wo, unshadowed.
fn specular_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, ls: LightSample) -> vec3<f32> {
    let cos_i = dot(n, ls.wi);
    if !(cos_i > 0.0) {
        return vec3<f32>(0.0);
    }
    return ward_specular(n, ls.wi, wo, alpha) * ls.e * cos_i;
}

// The specular light environment light l reflects towards wo at a surface of normal n and
// roughness alpha, unshadowed (but for rho_s): the sky seen along params.area_samples^2 fixed
// directions of the Ward lobe, the strata centres of its sampling. Points of the sky sampled
// by its own distribution would show on a glossy surface as that many highlights.
fn sky_specular(l: Light, n: vec3<f32>, wo: vec3<f32>, alpha: f32) -> vec3<f32> {
    let f = frame_of(n);
    let count = params.area_samples * params.area_samples;
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < count; j++) {
        let uv = area_point(j, params.area_samples, 0u, false);
        let s = ward_sample(f, wo, uv.x, uv.y, alpha);
        if s.weight > 0.0 {
            sum += s.weight * sky_radiance(l, s.wo);
        }
    }
    return sum * (1.0 / f32(count));
}

// Whether material m reflects by a glossy lobe: a specular part, rough enough for Ward's BRDF
// (the baked direct light's glossy part, and merged disks' normals in splat_shade).
fn glossy_lobe(m: Material) -> bool {
    return m.roughness >= MIN_ALPHA && any(m.specular > vec3<f32>(0.0));
}

// Radiance leaving splat i at p towards wo by the baked direct light: the diffuse part from
// the shadowed irradiance, the glossy part from the BRDF towards each light (an area light's
// n x n strata centres; the sky along the lobe's, sky_specular) times the light's visibility.
fn baked_direct(i: u32, s: Splat, m: Material, p: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    var out = vec3<f32>(0.0);
    if (params.show & SHOW_DIRECT_DIFFUSE) != 0u {
        out = s.diffuse * (direct_at(i).xyz / PI);
    }
    if (params.show & SHOW_DIRECT_SPECULAR) == 0u || !glossy_lobe(m) {
        return out;
    }
    var spec = vec3<f32>(0.0);
    for (var li = 0u; li < params.light_count; li++) {
        let vis = visibility_at(i * params.light_count + li);
        let l = lights[li];
        if !(vis > 0.0) {
            continue;
        }
        if l.kind == LIGHT_ENVIRONMENT {
            // Only where the scene has a sky does the pass bind its map (the define `sky`):
            // one binding more took a paged frame past a device's storage buffers.
            // #ifdef sky
            spec += vis * sky_specular(l, s.normal, wo, m.roughness);
            // #endif
            continue;
        }
        if !stratified(l.kind) {
            let ls = sample_emitter(l, p, 0.0, 0.0);
            spec += vis * specular_sample(s.normal, wo, m.roughness, ls);
            continue;
        }
        let n = params.area_samples;
        var area_sum = vec3<f32>(0.0);
        for (var j = 0u; j < n * n; j++) {
            let uv = area_point(j, n, 0u, false);
            let ls = sample_emitter(l, p, uv.x, uv.y);
            area_sum += specular_sample(s.normal, wo, m.roughness, ls);
        }
        spec += vis * area_sum * (1.0 / f32(n * n));
    }
    return out + m.specular * spec;
}
