// Splat pass 2, attributes (docs/design.md sections 7-8): the splats within the depth
// tolerance of the visible surface (depth test against pass 1, no depth writes) add
// weight x (what the shade pass needs) into four float targets by additive blending, in
// draw order. Each fragment is shaded from its own splat's lobes with its own view ray:
// the indirect light, diffuse from the total irradiance and specular from every lobe.
// Twin: src/cpu/splat_attributes.rs.

// #import splat
// #import lobe_brdf

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(2) var<uniform> params: ShadeParams;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var<storage, read> splat_light: array<SplatLight>;
@group(0) @binding(5) var<storage, read> lobes: array<Lobe>;
@group(0) @binding(6) var<storage, read> lobe_norms: array<f32>;

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
    let light = splat_light[i];
    var spec = vec3<f32>(0.0);
    let first = light.first_lobe;
    let shown = select(0u, light.lobes, (params.show & SHOW_INDIRECT_SPECULAR) != 0u);
    for (var k = 0u; k < shown; k++) {
        let lobe = lobes[first + k];
        let beta2 = lobe_beta2(params.family, lobe.sharpness);
        let norm = lobe_norm(s.normal, lobe.axis, beta2);
        spec += lobe.irradiance * lobe_specular(s.normal, wo, lobe.axis, m.roughness, beta2, norm);
    }
    let diffuse = select(vec3<f32>(0.0), s.diffuse * (light.irradiance / PI),
                         (params.show & SHOW_INDIRECT_DIFFUSE) != 0u);
    return diffuse + m.specular * spec;
}

@vertex
fn vs_main(@builtin(vertex_index) corner: u32, @builtin(instance_index) i: u32) -> SplatVertex {
    return splat_vertex(cam, splats[i], i, corner);
}

@fragment
fn fs_main(v: SplatVertex) -> Attributes {
    let s = splats[v.splat];
    let d = pixel_ray(cam, v.position.xy);
    let h = splat_hit(s, cam.eye, d);
    if !covers(cam, h, d) {
        discard;
    }
    let w = splat_weight(h.q);
    let m = materials[s.material];
    let gloss = (m.specular.x + m.specular.y + m.specular.z) * (1.0 / 3.0);
    var out: Attributes;
    out.radiance = w * vec4<f32>(indirect(v.splat, s, m, -d), 1.0);
    out.geometry = w * vec4<f32>(s.normal, h.t);
    out.diffuse = w * vec4<f32>(s.diffuse, gloss * m.roughness);
    out.specular = w * vec4<f32>(m.specular, gloss);
    return out;
}
