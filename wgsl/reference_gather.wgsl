// The reference renderer's first pass (thesis section 4.2, docs/design.md section 7): per pixel,
// the visible point by casting the view ray through the splat grid, and the radiance the
// photon map reflects there directly: every binned photon within R of the point (in the
// splat's slab, on a surface facing its way, arriving from above it) with the exact Ward BRDF of its own direction,
// weighted by the Epanechnikov kernel 2 / (pi R^2) (1 - d^2 / R^2). No lobes: the image the
// lobes approximate. It writes what splat_attributes writes, with weight 1, so the same shade
// pass adds the same direct light. A full-screen triangle, so the targets and their formats
// are the attribute pass's. Twin: src/cpu/reference_gather.rs.

// #import splat
// #import trace
// #import bins
// #import octahedral
// #import fullscreen

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> em: EmParams;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<uniform> bins: BinParams;
@group(0) @binding(4) var<storage, read> bin_start: array<u32>;
// #paged
@group(0) @binding(5) var<storage, read> bin_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(6) var<storage, read> bin_power: array<vec4<f32>>;

// Radiance the photons within R of p reflect towards wo, on a splat of normal n.
fn gather(p: vec3<f32>, n: vec3<f32>, wo: vec3<f32>, rho_d: vec3<f32>, m: Material,
          slab: f32) -> vec3<f32> {
    let box = bin_box(p, em.radius, bins);
    let kernel = 2.0 * em.inv_area;
    let inv_r2 = 1.0 / em.radius2;
    var sum = vec3<f32>(0.0);
    for (var r = 0u; r < bin_row_count(box); r++) {
        let row = bin_row(box, r, bins);
        for (var j = bin_start[row.x]; j < bin_start[row.y]; j++) {
            let g = bin_geom_at(j);
            let d = g.position - p;
            let d2 = dot(d, d);
            if d2 > em.radius2 || abs(dot(d, n)) > slab {
                continue;
            }
            let power = bin_power_at(j);
            let wi = oct_decode(g.direction);
            if dot(wi, n) <= 0.0 || dot(surface_decode(power.w), n) < SURFACE_COS_MIN {
                continue;
            }
            let f = rho_d / PI + m.specular * ward_specular(n, wi, wo, m.roughness);
            sum += (kernel * (1.0 - d2 * inv_r2)) * f * power.xyz;
        }
    }
    return sum;
}

@vertex
fn vs_main(@builtin(vertex_index) corner: u32) -> @builtin(position) vec4<f32> {
    return fullscreen_corner(corner);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> Attributes {
    let d = pixel_ray(cam, pixel.xy);
    var budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(cam.eye, d, NO_SPLAT, FAR, &budget);
    if hit.splat == NO_SPLAT {
        discard;
    }
    let s = splats_at(hit.splat);
    let m = materials[s.material];
    let gloss = (m.specular.x + m.specular.y + m.specular.z) * (1.0 / 3.0);
    let p = cam.eye + hit.t * d;
    var out: Attributes;
    out.radiance = vec4<f32>(gather(p, s.normal, -d, s.diffuse, m, em.slab * s.radius), 1.0);
    out.geometry = vec4<f32>(s.normal, hit.t);
    out.diffuse = vec4<f32>(s.diffuse, gloss * m.roughness);
    out.specular = vec4<f32>(m.specular, gloss);
    return out;
}
