// The direct bake (docs/design.md section 8): what static lights give every splat, once, so
// that a moving camera casts no shadow ray. Per splat and light, shadow rays from the splat's
// centre to a samples^2 jittered grid on an area light or the sun's disk (one ray to a point
// or directional light) give
// - the shadowed irradiance, summed over the lights: what the diffuse part needs;
// - the light's visibility, the shadowed share of its unshadowed irradiance: what the glossy
//   part needs, times the BRDF towards the light, which follows the view.
// The sun's disk is first seen through two of its strata on a diagonal; where those agree
// (all of it in view, or none: everywhere but in a penumbra a few millimetres wide) the rest
// are not traced.
// An environment light is the unshadowed irradiance of its table less what the splat's
// SKY_RAYS shadow rays find blocked, the blocked share averaged over the neighbours within
// reach that face alike (`share`): the sky's shadows are soft, and the neighbours' rays make
// the average of many at the cost of a few. One invocation per splat, in `order`, for each
// entry. CPU mirror: src/cpu/direct_bake.rs.

// #import types
// #import dispatch
// #import rng
// #import splat
// #import grid
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
// Per splat: the share of the environment light's unshadowed irradiance its own rays found
// blocked (`main` writes it, `share` averages it).
// #paged
@group(0) @binding(5) var<storage, read_write> blocked: array<f32>;

const WG: u32 = 64u;

// An environment light's strata per side in the bake: SKY_STRATA (half by the map, half by
// the cosine), 4 rays a splat.
const SKY_SIDE: u32 = 2u;

// The neighbours that share a sky's blocked share: centres within SHARE_REACH times the
// splat's radius (at most SHARE_CELLS of the grid's cells, which bounds the cells read),
// normals within about 18 degrees.
const SHARE_REACH: f32 = 3.0;
const SHARE_CELLS: f32 = 1.5;
const SHARE_COS: f32 = 0.95;

// The irradiance and the open share of its unshadowed irradiance that light l gives splat i
// by shadow rays from o.
struct Seen {
    e: vec3<f32>,
    open: f32,
}

// Stratum j of light l's n x n seen from splat i: its irradiance e cos(theta) (zero where the
// light lies behind the splat or gives nothing, and then no ray is traced) and, in w, 1 where
// the shadow ray from o reaches the light.
fn stratum_ray(l: Light, li: u32, i: u32, s: Splat, o: vec3<f32>, key: u32, j: u32,
               n: u32) -> vec4<f32> {
    let uv = area_point(j, n, key + (li * n * n + j) * 2u, true);
    let ls = sample_light(l, s.center, s.normal, uv.x, uv.y);
    let cos_i = dot(s.normal, ls.wi);
    if !(cos_i > 0.0) || all(ls.e <= vec3<f32>(0.0)) {
        return vec4<f32>(0.0);
    }
    var budget = SHADOW_RAY_BUDGET;
    let reach = shadow_reach(l, o, ls.wi, ls.dist, params.shadow_bias);
    let open = trace_ray(o, ls.wi, i, reach, &budget).splat == NO_SPLAT;
    return vec4<f32>(ls.e * cos_i, select(0.0, 1.0, open));
}

// Light l's Seen on splat i, the sun's disk first through two of its strata.
fn seen_by_rays(l: Light, li: u32, i: u32, s: Splat, o: vec3<f32>, key: u32) -> Seen {
    let n = strata_side(l.kind, params.samples);
    let first_look = l.kind == LIGHT_SUN && n >= 2u;
    var open = vec3<f32>(0.0);
    var unshadowed = vec3<f32>(0.0);
    var rays_open = 0u;
    var rays = 0u;
    var taken = 0u;
    // Look 0 takes every other stratum of those at even (x, y), a diagonal of the disk (2 of
    // the sun's 16), where the first look applies; look 1 the rest unless those agreed.
    // Without it look 0 takes them all.
    for (var look = 0u; look < 2u; look++) {
        if look == 1u && (!first_look || rays_open == 0u || rays_open == rays) {
            break;
        }
        for (var j = 0u; j < n * n; j++) {
            let x = j % n;
            let y = j / n;
            let coarse = x % 2u == 0u && y % 2u == 0u && (x / 2u + y / 2u) % 2u == 0u;
            if first_look && coarse != (look == 0u) {
                continue;
            }
            taken += 1u;
            let ray = stratum_ray(l, li, i, s, o, key, j, n);
            if all(ray.xyz <= vec3<f32>(0.0)) {
                continue;
            }
            unshadowed += ray.xyz;
            rays += 1u;
            if ray.w > 0.0 {
                open += ray.xyz;
                rays_open += 1u;
            }
        }
    }
    // A light the centre does not see at all may still light the disk's rim: unshadowed.
    let seen = unshadowed.x + unshadowed.y + unshadowed.z;
    let seen_open = select(1.0, (open.x + open.y + open.z) / seen, seen > 0.0);
    return Seen(open / f32(max(taken, 1u)), seen_open);
}

// The share of environment light l's unshadowed irradiance `e0` on splat i that its SKY_SIDE^2
// shadow rays find blocked: unbiased, and exactly 0 where every ray is open.
fn sky_blocked(l: Light, li: u32, i: u32, s: Splat, o: vec3<f32>, key: u32, e0: vec3<f32>) -> f32 {
    let n = SKY_SIDE;
    var lost = vec3<f32>(0.0);
    for (var j = 0u; j < n * n; j++) {
        let ray = stratum_ray(l, li, i, s, o, key, j, n);
        lost += ray.xyz * (1.0 - ray.w);
    }
    let all_e = e0.x + e0.y + e0.z;
    return select(0.0, (lost.x + lost.y + lost.z) / (f32(n * n) * all_e), all_e > 0.0);
}

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
        if l.kind == LIGHT_ENVIRONMENT {
            blocked_put(i, sky_blocked(l, li, i, s, o, key, sky_irradiance(l, s.normal)));
            continue;
        }
        let seen = seen_by_rays(l, li, i, s, o, key);
        total += seen.e;
        visibility_put(i * params.light_count + li, seen.open);
    }
    direct_put(i, vec4<f32>(total, 0.0));
}

// The mean blocked share over splat i's neighbours (itself among them): each read once, in
// the cell that holds its centre.
fn shared_blocked(i: u32, s: Splat) -> f32 {
    let reach = min(SHARE_REACH * s.radius, SHARE_CELLS * grid.cell_size);
    let top = vec3<i32>(grid.dims) - vec3<i32>(1);
    let lo = clamp(point_cell(s.center - vec3<f32>(reach), grid), vec3<i32>(0), top);
    let hi = clamp(point_cell(s.center + vec3<f32>(reach), grid), vec3<i32>(0), top);
    var sum = 0.0;
    var count = 0u;
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                let c = vec3<i32>(x, y, z);
                let ci = cell_index(vec3<u32>(c), grid);
                for (var e = cell_start[ci]; e < cell_start[ci + 1u]; e++) {
                    let j = cell_splats_at(e);
                    let t = splats_at(j);
                    let d = t.center - s.center;
                    if dot(d, d) <= reach * reach && dot(t.normal, s.normal) >= SHARE_COS
                        && all(point_cell(t.center, grid) == c) {
                        sum += blocked_at(j);
                        count += 1u;
                    }
                }
            }
        }
    }
    return select(blocked_at(i), sum / f32(count), count > 0u);
}

// The environment light's part: its unshadowed irradiance times the open share the
// neighbours' rays give, added to what `main` summed.
@compute @workgroup_size(64)
fn share(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    let k = linear_workgroup(wg, num_wg) * WG + lid;
    if k >= params.splat_count {
        return;
    }
    let i = order_at(k);
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        if l.kind != LIGHT_ENVIRONMENT {
            continue;
        }
        let s = splats_at(i);
        let open = clamp(1.0 - shared_blocked(i, s), 0.0, 1.0);
        let e = sky_irradiance(l, s.normal) * open;
        direct_put(i, direct_at(i) + vec4<f32>(e, 0.0));
        visibility_put(i * params.light_count + li, open);
    }
}
