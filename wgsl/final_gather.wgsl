// Final gathering (docs/design.md section 6): the light arriving at a splat, sampled by rays
// from its centre rather than estimated from the photons within the gather radius, so that it
// is resolved at the splat's own position. Per fitted splat of the fit list (fit_select's
// entries with FIT_BIT), samples^2 rays over its cosine-weighted hemisphere (one stratum each,
// jittered; with shared fits, from its group's members in turn); each brings back the
// radiance of the surface it meets, as the bake already knows it: hit_albedo / pi times its
// irradiance, direct (the direct bake) and indirect (the photons). Rays that miss, meet a
// disk's back, or meet an area light first (its light is the direct bake's part) bring none,
// as the shade pass's glossy rays. Sample j of fit-list entry params.first + k is at
// k * samples^2 + j: (radiance, direction as an octahedral u32's bits), where em_fit's
// gathered dispatch finds it; the host takes the list in batches that bound the samples'
// memory. One invocation per ray. CPU mirror: src/cpu/final_gather.rs.

// #import types
// #import dispatch
// #import rng
// #import sampling
// #import octahedral
// #import splat
// #import trace
// #import lights
// #import lobes

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> list: array<vec2<u32>>;
// #paged
@group(0) @binding(2) var<storage, read> light: array<SplatLight>;
// #paged
@group(0) @binding(3) var<storage, read> direct: array<vec4<f32>>;
// One binding: the host sizes its batches to fit (one page fewer keeps the stage within the
// bindings a device allows beside the paged geometry).
@group(0) @binding(4) var<storage, read_write> samples: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> materials: array<Material>;
@group(0) @binding(6) var<storage, read> lights: array<Light>;
// The shared fits' groups (src/fit_groups.rs), read where params.group_members is not 0.
@group(0) @binding(7) var<storage, read> groups: array<u32>;

const WG: u32 = 64u;

// The splat ray j of fitted splat i starts from: with shared fits, member j mod n of the n in
// i's group (the leader first), so that the one fit sees the group's light; else i itself.
fn ray_origin(i: u32, j: u32) -> u32 {
    if params.group_members == 0u {
        return i;
    }
    let group = groups[i];
    let first = groups[params.group_starts + group];
    let count = groups[params.group_starts + group + 1u] - first;
    return groups[params.group_members + first + j % count];
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let g = linear_workgroup(wg, num_wg) * WG + lid;
    let rays = params.samples * params.samples;
    if g >= params.splat_count * rays {
        return;
    }
    let entry = list[params.first + g / rays];
    if (entry.x & FIT_BIT) == 0u {
        return;
    }
    let i = entry.x & ~FIT_BIT;
    let j = g % rays;
    let origin = ray_origin(i, j);
    let s = splats_at(origin);
    let key = pcg_hash(pcg_hash(params.seed) + i) + 2u * j;
    let uv = area_point(j, params.samples, key, true);
    let d = to_world(frame_of(s.normal), sample_cosine(uv.x, uv.y));
    let o = s.center + params.shadow_bias * s.normal;
    var budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(o, d, origin, FAR, &budget);
    var radiance = vec3<f32>(0.0);
    var lit = false;
    for (var li = 0u; li < params.light_count; li++) {
        lit = lit || light_first(lights[li], o, d, hit.t);
    }
    if hit.splat != NO_SPLAT && !lit {
        let h = splats_at(hit.splat);
        if dot(h.normal, d) < 0.0 {
            let e = direct_at(hit.splat).xyz + light_at(hit.splat).irradiance;
            radiance = hit_albedo(h, materials[h.material]) * e * (1.0 / PI);
        }
    }
    samples[g] = vec4<f32>(radiance, bitcast<f32>(oct_encode(d)));
}
