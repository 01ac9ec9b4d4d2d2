// The path tracer (docs/design.md section 10): ground truth of the same splat scene, with the
// same Ward BRDF, lights and path length as the bake. One invocation per pixel adds one sample
// to the running mean of the image: a uniformly jittered view ray through the splat grid, at
// each surface vertex next-event estimation of every light (area lights sampled uniformly,
// weighted against BRDF sampling by the power heuristic), then a BRDF sample chosen as the
// photons choose theirs (diffuse with probability mean(rho_d), Ward with mean(rho_s), else
// the path ends: Russian roulette by albedo). A BRDF-sampled ray that meets an area light
// adds its radiance with the other MIS weight. CPU mirror: src/cpu/path_trace.rs.
//
// params.show picks terms as the splat frame's --show does, by the first surface the camera
// sees: direct light is what reaches it from a light (its next events, and a light its BRDF
// sample meets), indirect all the rest; diffuse or specular is the part of its BRDF (next
// events split the BRDF; a bounce counts for the part it sampled, which keeps each part
// unbiased). A light the camera sees directly counts as direct diffuse, as in shade.wgsl.

// #import types
// #import dispatch
// #import rng
// #import splat
// #import trace
// #import lights

@group(0) @binding(0) var<uniform> params: PathParams;
@group(0) @binding(1) var<uniform> cam: Camera;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read> lights: array<Light>;
@group(0) @binding(4) var<storage, read_write> hdr: array<vec4<f32>>;

const WG: u32 = 64u;

// Random numbers of a light's sample at a vertex: purposes after the photon tracer's.
const RNG_LIGHT_U: u32 = 7u;
const RNG_LIGHT_V: u32 = 8u;

// The pdf (solid angle) of choosing wi by the BRDF sampling below, from wo.
fn brdf_pdf(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, pd: f32, ps: f32, alpha: f32) -> f32 {
    let ci = dot(n, wi);
    if !(ci > 0.0) {
        return 0.0;
    }
    var pdf = pd * ci / PI;
    if ps > 0.0 && alpha >= MIN_ALPHA {
        pdf += ps * ward_pdf(n, wo, wi, alpha);
    }
    return pdf;
}

// The BRDF with its diffuse and specular parts weighed by wd and ws (1 or 0: shown or not).
fn brdf(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, rho_d: vec3<f32>, m: Material, wd: f32,
        ws: f32) -> vec3<f32> {
    var f = rho_d / PI * wd;
    if m.roughness >= MIN_ALPHA {
        f += m.specular * ward_specular(n, wi, wo, m.roughness) * ws;
    }
    return f;
}

// How far past a hit, in each disk's radii along the ray, the disks that blend into its normal
// may lie: the splat frame's depth tolerance (FrameConfig::depth_tolerance).
const BLEND_DEPTH: f32 = 1.0;
// The largest neighbour, in hit-disk radii, whose hit the search is sure to find.
const BLEND_REACH: f32 = 1.5;

// The normal of the surface the splat frame shows where the ray (o, d) meets disk hit.splat:
// the disks the ray meets from there to BLEND_DEPTH radii past it, of the hit's surface
// (same_surface: within 60 degrees of its normal), weighted by the splat kernel at their hits,
// as the attribute pass blends them in a pixel (design section 10). Their hits lie on the ray
// within BLEND_DEPTH of their radii past the hit: the search covers the cells of that segment
// for disks up to BLEND_REACH times the hit disk's radius, and a disk counts only in the cell
// that holds its hit, so none counts twice. The disk's own normal where the search finds none.
fn blended_normal(o: vec3<f32>, d: vec3<f32>, hit: Hit, skip: u32) -> vec3<f32> {
    let h = splats_at(hit.splat);
    let p = o + hit.t * d;
    let end = p + (BLEND_REACH * BLEND_DEPTH * h.radius) * d;
    let top = vec3<i32>(grid.dims) - 1;
    let a = clamp(point_cell(min(p, end), grid), vec3<i32>(0), top);
    let b = clamp(point_cell(max(p, end), grid), vec3<i32>(0), top);
    var budget = SHADOW_RAY_BUDGET;
    var sum = vec3<f32>(0.0);
    for (var z = a.z; z <= b.z; z++) {
        for (var y = a.y; y <= b.y; y++) {
            for (var x = a.x; x <= b.x; x++) {
                let c = vec3<i32>(x, y, z);
                let ci = cell_index(vec3<u32>(c), grid);
                for (var e = cell_start[ci]; e < cell_start[ci + 1u] && budget > 0u; e++) {
                    budget -= 1u;
                    let j = cell_splats_at(e);
                    let s = splats_at(j);
                    if j == skip || dot(s.normal, h.normal) < FRONT_COS_MIN {
                        continue;
                    }
                    let t = intersect_splat(s, o, d);
                    if !(t >= hit.t && t <= hit.t + BLEND_DEPTH * s.radius) {
                        continue;
                    }
                    let q = o + t * d;
                    if any(point_cell(q, grid) != c) {
                        continue;
                    }
                    let r = q - s.center;
                    sum += splat_weight(dot(r, r) / (s.radius * s.radius)) * s.normal;
                }
            }
        }
    }
    return select(h.normal, normalize(sum), dot(sum, sum) > 0.0);
}

// The radiance of the lights a ray d that left the scene sees (a sky, the sun's disk), each
// weighted by the power heuristic against its next-event pdf where a BRDF sample of pdf
// `pdf_brdf` at a surface of normal n chose d (0: the camera's ray, which sees them whole).
fn escaped(d: vec3<f32>, n: vec3<f32>, pdf_brdf: f32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var li = 0u; li < params.light_count; li++) {
        let l = lights[li];
        let radiance = escaped_radiance(l, d);
        if all(radiance <= vec3<f32>(0.0)) {
            continue;
        }
        var w = 1.0;
        if pdf_brdf > 0.0 {
            w = power_heuristic(pdf_brdf, light_pdf(l, n, d, FAR));
        }
        sum += radiance * w;
    }
    return sum;
}

// 1 where params.show has any of `bits`, else 0.
fn shown(bits: u32) -> f32 {
    return select(0.0, 1.0, (params.show & bits) != 0u);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= params.width * params.height {
        return;
    }
    // The seed hashed before the sample is added: seeds s and s + 1 share no sample.
    let key = path_key(pcg_hash(pcg_hash(params.seed) + params.sample), i);
    let px = vec2<f32>(f32(i % params.width), f32(i / params.width));
    let jitter = vec2<f32>(rand(key, 0u, RNG_EMIT_POS_U), rand(key, 0u, RNG_EMIT_POS_V));
    var o = cam.eye;
    var d = pixel_ray(cam, px + jitter);
    var throughput = vec3<f32>(1.0);
    var radiance = vec3<f32>(0.0);
    var skip = NO_SPLAT;
    // The pdf of the BRDF sample that chose d (0: the camera's ray, which sees lights whole).
    var pdf_brdf = 0.0;
    // The normal of the surface the ray left (the sky's next-event pdf there).
    var from_normal = vec3<f32>(0.0);
    // Weights of the terms by params.show: a light the ray meets, and next events at vertices
    // past the first; both fixed by the first bounce's part.
    var hit_shown = shown(SHOW_DIRECT_DIFFUSE);
    var later_shown = 1.0;
    for (var depth = 0u; depth <= params.max_depth; depth++) {
        var budget = SHADOW_RAY_BUDGET;
        let hit = trace_ray(o, d, skip, FAR, &budget);
        let t_surface = select(hit.t, FAR, hit.splat == NO_SPLAT);
        // An area light in front of the surface adds its radiance and ends the path, unless it
        // reflects.
        var light_t = t_surface;
        var seen = NO_SPLAT;
        for (var li = 0u; li < params.light_count; li++) {
            let t = area_light_hit(lights[li], o, d);
            if t > 0.0 && t < light_t {
                light_t = t;
                seen = li;
            }
        }
        if seen != NO_SPLAT {
            let l = lights[seen];
            var w = 1.0;
            if pdf_brdf > 0.0 {
                let pdf_light = light_t * light_t / (l.area * -dot(d, l.direction));
                w = power_heuristic(pdf_brdf, pdf_light);
            }
            radiance += throughput * (l.power / (PI * l.area)) * (w * hit_shown);
            // A light that reflects goes on to its own surface, just behind its face.
            if (l.flags & LIGHT_REFLECTS) == 0u {
                break;
            }
        }
        // A ray that leaves the scene sees the sky and the sun.
        if hit.splat == NO_SPLAT && hit.aborted == 0u {
            var seen = escaped(d, from_normal, pdf_brdf);
            // The camera's own ray sees the background where it is a colour.
            if depth == 0u && params.background.w > 0.0 {
                seen = params.background.xyz;
            }
            radiance += throughput * seen * hit_shown;
        }
        if hit.splat == NO_SPLAT || hit.aborted != 0u || depth == params.max_depth {
            break;
        }
        let s = splats_at(hit.splat);
        let m = materials[s.material];
        let p = o + hit.t * d;
        // The camera sees the blended surface, as the splat frame shows it; past it, paths
        // bounce off the disks' own normals, as photons do.
        var n = s.normal;
        if depth == 0u {
            n = blended_normal(o, d, hit, skip);
        }
        let wo = -d;
        let pd = mean3(s.diffuse);
        let ps = mean3(m.specular);
        // Next-event estimation of every light.
        for (var li = 0u; li < params.light_count; li++) {
            let l = lights[li];
            let lkey = pcg_hash(key + li);
            let uv = vec2<f32>(rand(lkey, depth, RNG_LIGHT_U), rand(lkey, depth, RNG_LIGHT_V));
            let ls = sample_light(l, p, n, uv.x, uv.y);
            let cos_i = dot(n, ls.wi);
            if !(cos_i > 0.0) || all(ls.e <= vec3<f32>(0.0)) {
                continue;
            }
            var shadow_budget = SHADOW_RAY_BUDGET;
            // Off the surface as the renderer's shadow rays start (design section 10).
            let o_shadow = p + params.shadow_bias * n;
            let reach = shadow_reach(l, o_shadow, ls.wi, ls.dist, params.shadow_bias);
            let blocked = trace_ray(o_shadow, ls.wi, hit.splat, reach, &shadow_budget);
            if blocked.splat != NO_SPLAT {
                continue;
            }
            let pdf_light = light_pdf(l, n, ls.wi, ls.dist);
            var w = 1.0;
            if pdf_light > 0.0 {
                w = power_heuristic(pdf_light, brdf_pdf(n, wo, ls.wi, pd, ps, m.roughness));
            }
            var wd = later_shown;
            var ws = later_shown;
            if depth == 0u {
                wd = shown(SHOW_DIRECT_DIFFUSE);
                ws = shown(SHOW_DIRECT_SPECULAR);
            }
            radiance += throughput * brdf(n, wo, ls.wi, s.diffuse, m, wd, ws) * ls.e * (cos_i * w);
        }
        if depth + 1u == params.max_depth {
            break;
        }
        // The next direction, as a photon would bounce.
        let u = rand(key, depth + 1u, RNG_ROULETTE);
        let u1 = rand(key, depth + 1u, RNG_BOUNCE_U);
        let u2 = rand(key, depth + 1u, RNG_BOUNCE_V);
        let f = frame_of(n);
        let next = sample_bounce(f, wo, s.diffuse, m.specular, m.roughness, u, u1, u2);
        if !next.alive {
            break;
        }
        let wi = next.dir;
        throughput *= next.weight;
        if depth == 0u {
            hit_shown = shown(select(SHOW_DIRECT_DIFFUSE, SHOW_DIRECT_SPECULAR, next.specular));
            later_shown = shown(select(SHOW_INDIRECT_DIFFUSE, SHOW_INDIRECT_SPECULAR, next.specular));
        } else {
            hit_shown = later_shown;
        }
        // A mirror-like Ward sample (alpha below MIN_ALPHA) has no pdf to weigh against: next
        // events skip it, so a light it meets counts in full.
        let mirror = next.specular && m.roughness < MIN_ALPHA;
        pdf_brdf = select(brdf_pdf(n, wo, wi, pd, ps, m.roughness), 0.0, mirror);
        o = p;
        d = wi;
        skip = hit.splat;
        from_normal = n;
    }
    let out = vec4<f32>(radiance, 1.0);
    if params.sample == 0u {
        hdr[i] = out;
    } else {
        hdr[i] += (out - hdr[i]) * (1.0 / f32(params.sample + 1u));
    }
}
