// The direct bake (docs/design.md section 8): what static lights give every splat, once, so
// that a moving camera casts no shadow ray. Per splat and light, shadow rays from the splat's
// centre to a samples^2 jittered grid on an area light or of an environment light's directions
// (one ray to any other light) give
// - the shadowed irradiance, summed over the lights: what the diffuse part needs;
// - the light's visibility, the shadowed share of its unshadowed irradiance: what the glossy
//   part needs, times the BRDF towards the light, which follows the view.
// One invocation per splat, in `order`. CPU mirror: src/cpu/direct_bake.rs.

// #import types
// #import dispatch
// #import rng
// #import splat
// #import trace
// #import lights

@group(0) @binding(0) var<uniform> params: DirectParams;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
// Per splat: (shadowed irradiance from every light, 0).
// #paged
@group(0) @binding(2) var<storage, read_write> direct: array<vec4<f32>>;
// Per splat and light, at splat * light_count + light: visibility in [0, 1].
// #paged
@group(0) @binding(3) var<storage, read_write> visibility: array<f32>;
// The splats in the order the invocations take them: neighbours in space side by side, so
// that a SIMD group's shadow rays walk the same cells (grid::splat_order). Each splat's
// result depends on its index alone.
// #paged
@group(0) @binding(4) var<storage, read> order: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let k = linear_workgroup(wg, num_wg) * WG + lid;
    if k >= params.splat_count {
        return;
    }
    let i = order_at(k);
    let s = splats_at(i);
    let o = s.center + params.shadow_bias * s.normal;
    let key = pcg_hash(pcg_hash(params.seed) + i);
    var total = vec3<f32>(0.0);
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        let n = strata_side(l.kind, params.samples);
        var open = vec3<f32>(0.0);
        var unshadowed = vec3<f32>(0.0);
        for (var j = 0u; j < n * n; j++) {
            let uv = area_point(j, n, key + (li * n * n + j) * 2u, true);
            let ls = sample_light(l, s.center, s.normal, uv.x, uv.y);
            let cos_i = dot(s.normal, ls.wi);
            if !(cos_i > 0.0) || all(ls.e <= vec3<f32>(0.0)) {
                continue;
            }
            let e = ls.e * cos_i;
            unshadowed += e;
            var budget = SHADOW_RAY_BUDGET;
            let reach = shadow_reach(l, o, ls.wi, ls.dist, params.shadow_bias);
            let hit = trace_ray(o, ls.wi, i, reach, &budget);
            if hit.splat == NO_SPLAT {
                open += e;
            }
        }
        total += open * (1.0 / f32(n * n));
        // A light the centre does not see at all may still light the disk's rim: unshadowed.
        let seen = unshadowed.x + unshadowed.y + unshadowed.z;
        let seen_open = select(1.0, (open.x + open.y + open.z) / seen, seen > 0.0);
        visibility_put(i * params.light_count + li, seen_open);
    }
    direct_put(i, vec4<f32>(total, 0.0));
}
