// Photon emission and tracing (docs/design.md section 4): one invocation per emitted photon.
// The photon leaves a light chosen by its index (each light owns a range of indices in
// proportion to its power), then bounces through the splat grid: at each hit it is stored
// when its bounce count is at least params.min_bounce, then Russian roulette picks a diffuse
// bounce (cosine, power * rho_d / P_d), a specular bounce (Ward sampling, power *
// rho_s * f cos / pdf / P_s) or absorption, with P_d = mean(rho_d), P_s = mean(rho_s).
// A photon that meets an area light's face before a surface ends there, absorbed: a light is
// an opaque emitter that reflects nothing, as the path tracer and final gathering see it
// (the surface behind it would otherwise reflect light the light hides).
// Random numbers are keyed by (path, bounce, purpose), so the CPU mirror retraces the same
// paths; the slot of a stored photon comes from an atomic counter and varies between runs,
// (path, bounce) does not.
// CPU mirror: src/cpu/photon_trace.rs.

// #import types
// #import dispatch
// #import rng
// #import sampling
// #import ward
// #import trace
// #import lights

@group(0) @binding(0) var<uniform> params: TraceParams;
@group(0) @binding(1) var<storage, read> emitters: array<Emitter>;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(4) var<storage, read_write> counters: TraceCounters;

const WG: u32 = 64u;

// The emitter owning a path: the last one whose first index is <= path (binary search).
fn find_emitter(path: u32) -> u32 {
    var lo = 0u;
    var hi = params.emitter_count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if emitters[mid].first <= path {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

struct Emission {
    origin: vec3<f32>,
    direction: vec3<f32>,
    power: vec3<f32>,
}

fn emit(path: u32, key: u32) -> Emission {
    let em = emitters[find_emitter(path)];
    let l = em.light;
    let p1 = rand(key, 0u, RNG_EMIT_POS_U);
    let p2 = rand(key, 0u, RNG_EMIT_POS_V);
    let d1 = rand(key, 0u, RNG_EMIT_DIR_U);
    let d2 = rand(key, 0u, RNG_EMIT_DIR_V);
    var e: Emission;
    e.power = em.photon_power;
    switch l.kind {
        case LIGHT_POINT: {
            e.origin = l.position;
            e.direction = sample_sphere(d1, d2);
        }
        case LIGHT_SPOT: {
            let v = sample_cone(d1, d2, l.cos_outer);
            e.origin = l.position;
            e.direction = to_world(frame_of(l.direction), v);
            let falloff = select(1.0, smoothstep(l.cos_outer, l.cos_inner, v.z),
                                 l.cos_inner > l.cos_outer);
            e.power = e.power * (falloff * em.falloff_norm);
        }
        case LIGHT_AREA: {
            e.origin = l.position + p1 * l.edge_u + p2 * l.edge_v;
            e.direction = to_world(frame_of(l.direction), sample_cosine(d1, d2));
        }
        case LIGHT_ENVIRONMENT: {
            // A direction by the map's distribution; the photon comes from a disk across the
            // scene's bounds, two of its radii out that way, and carries the disk's share of
            // the light arriving from there: L / pdf times the disk's area over the photons.
            let s = sample_sky_map(l, d1, d2);
            let f = frame_of(-s.wi);
            let r = sqrt(l.area / PI);
            let q = sample_disk(p1, p2) * r;
            e.origin = l.position + s.wi * (2.0 * r) + f.t * q.x + f.b * q.y;
            e.direction = -s.wi;
            e.power = s.e * (l.area / f32(em.count));
        }
        default: {  // LIGHT_DIRECTIONAL, LIGHT_SUN: from a disk of area l.area across the scene
            let f = frame_of(l.direction);
            let q = sample_disk(p1, p2) * sqrt(l.area / PI);
            e.origin = l.position + f.t * q.x + f.b * q.y;
            e.direction = l.direction;
            if l.kind == LIGHT_SUN {
                // Spread over the sun's cone (1 - cos exact in cos_inner).
                e.direction = to_world(f, polar(1.0 - d1 * l.cos_inner, d2));
            }
        }
    }
    return e;
}

// Whether the ray meets an area light's face before distance t.
fn meets_light(o: vec3<f32>, d: vec3<f32>, t: f32) -> bool {
    for (var k = 0u; k < params.emitter_count; k++) {
        if light_first(emitters[k].light, o, d, t) {
            return true;
        }
    }
    return false;
}

fn store(p: Photon) {
    let slot = atomicAdd(&counters.stored, 1u);
    if slot < counters.capacity {
        photons[slot] = p;
    } else {
        atomicStore(&counters.overflow, 1u);
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= params.path_count {
        return;
    }
    let path = params.path_offset + i;
    let key = path_key(params.seed, path);
    let e = emit(path, key);
    var o = e.origin;
    var d = e.direction;
    var power = e.power;
    var skip = NO_SPLAT;
    var budget = params.iteration_budget;
    for (var bounce = 0u; bounce < params.max_depth; bounce++) {
        let hit = trace_ray(o, d, skip, FAR, &budget);
        if hit.aborted != 0u {
            atomicAdd(&counters.aborted, 1u);
            return;
        }
        if meets_light(o, d, hit.t) {
            atomicAdd(&counters.absorbed, 1u);
            return;
        }
        if hit.splat == NO_SPLAT {
            atomicAdd(&counters.escaped, 1u);
            return;
        }
        let s = splats_at(hit.splat);
        let p = o + hit.t * d;
        let wi = -d;
        if bounce >= params.min_bounce {
            store(Photon(p, bounce, wi, hit.splat, power, path));
        }
        if bounce + 1u == params.max_depth {
            break;
        }
        let m = materials[s.material];
        let u = rand(key, bounce, RNG_ROULETTE);
        let u1 = rand(key, bounce, RNG_BOUNCE_U);
        let u2 = rand(key, bounce, RNG_BOUNCE_V);
        let f = frame_of(s.normal);
        let next = sample_bounce(f, wi, s.diffuse, m.specular, m.roughness, u, u1, u2);
        if !next.alive {
            atomicAdd(&counters.absorbed, 1u);
            return;
        }
        d = next.dir;
        power = power * next.weight;
        o = p;
        skip = hit.splat;
    }
    atomicAdd(&counters.depth_capped, 1u);
}
