// Light sampling (docs/design.md section 8): the irradiance one point of a light brings to a
// surface point, and the stratified points of an area light. Shared by the shade pass (shadow
// rays per pixel), the direct bake (shadow rays per splat) and the attribute pass (baked
// visibility times the BRDF towards each light). Twin: src/shared/lights.rs.

// #import types
// #import sampling
// #import rng

// Roughness below this gives no direct highlight (a mirror needs the lobes, not a sample).
const MIN_ALPHA: f32 = 1e-3;

// Light arriving at p from one light sample: its direction, distance (for the shadow ray)
// and irradiance on a surface facing it.
struct LightSample {
    wi: vec3<f32>,
    dist: f32,
    e: vec3<f32>,
}

// The environment light's map, as scene::sky::SkyTable packs it: [0] the header (width,
// height, the sum of the texels' sampling weights); [1 + y W + x] texel (x, y): radiance, and
// its row's cumulative share up to it; [1 + W H + y] the rows' cumulative share up to row y.
// A stage that imports this module declares `sky`: the tracing stages in the geometry group
// (trace.wgsl), the splat stages in their group 0 (splat_shade.wgsl and its siblings).

// Rec. 709 luminance, the sky's sampling weight.
fn sky_luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

fn sky_size() -> vec2<u32> {
    return vec2<u32>(u32(sky[0].x), u32(sky[0].y));
}

// The first of `count` entries from `first` whose component c exceeds x (a cumulative
// distribution's pick), the last where none does.
fn sky_pick(first: u32, count: u32, c: u32, x: f32) -> u32 {
    var lo = 0u;
    var hi = count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if sky[first + mid][c] > x {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

// Where x lies between the cumulative shares before and at entry k (of the run from first),
// in [0, 1).
fn sky_remap(first: u32, k: u32, c: u32, x: f32) -> f32 {
    var before = 0.0;
    if k > 0u {
        before = sky[first + k - 1u][c];
    }
    let span = sky[first + k][c] - before;
    return select(0.5, clamp((x - before) / span, 0.0, 0.999999), span > 0.0);
}

// The solid-angle pdf of sampling texel row y at sin theta, by the texel's radiance c.
fn sky_texel_pdf(c: vec3<f32>, y: u32, sin_theta: f32) -> f32 {
    let size = sky_size();
    let sin_row = sin(PI * (f32(y) + 0.5) / f32(size.y));
    let pdf_uv = sky_luminance(c) * sin_row * f32(size.x * size.y) / sky[0].z;
    return select(0.0, pdf_uv / (2.0 * PI * PI * sin_theta), sin_theta > 0.0);
}

// The texel a direction looks at: its entry in sky, its row, and the sine of the direction's
// angle to the map's up axis.
struct SkyTexel {
    entry: u32,
    y: u32,
    sin_theta: f32,
}

// The texel direction d (world) looks at through environment light l's frame.
fn sky_texel(l: Light, d: vec3<f32>) -> SkyTexel {
    let size = sky_size();
    let local = vec3<f32>(dot(d, l.edge_u), dot(d, l.direction), dot(d, l.edge_v));
    var u = atan2(local.x, -local.z) / (2.0 * PI);
    if u < 0.0 {
        u += 1.0;
    }
    // sin theta from the two other components, theta by atan2: exact near the poles, where
    // sqrt(1 - cos^2) and acos lose their digits.
    let sin_theta = length(local.xz);
    let v = atan2(sin_theta, local.y) / PI;
    let x = min(u32(u * f32(size.x)), size.x - 1u);
    let y = min(u32(v * f32(size.y)), size.y - 1u);
    return SkyTexel(1u + y * size.x + x, y, sin_theta);
}

// The side of the sky's grid of irradiance normals (scene::sky::IRRADIANCE_SIZE).
const IRRADIANCE_W: u32 = 128u;
const IRRADIANCE_H: u32 = 65u;

// The unshadowed irradiance environment light l gives a surface of normal n: its table (after
// the map's rows; its first and last rows the poles) read bilinearly, across the seam at
// phi = 0.
fn sky_irradiance(l: Light, n: vec3<f32>) -> vec3<f32> {
    let size = sky_size();
    let first = 1u + size.x * size.y + size.y;
    let local = vec3<f32>(dot(n, l.edge_u), dot(n, l.direction), dot(n, l.edge_v));
    let u = atan2(local.x, -local.z) / (2.0 * PI);
    let v = atan2(length(local.xz), local.y) / PI;
    let ew = f32(IRRADIANCE_W);
    let eh = f32(IRRADIANCE_H);
    let fx = u * ew;
    let fy = clamp(v * (eh - 1.0), 0.0, eh - 1.0);
    let x0 = floor(fx);
    let y0 = floor(fy);
    let t = vec2<f32>(fx - x0, fy - y0);
    let xa = min(u32(x0 - floor(x0 / ew) * ew), IRRADIANCE_W - 1u);
    let xb = min(u32((x0 + 1.0) - floor((x0 + 1.0) / ew) * ew), IRRADIANCE_W - 1u);
    let ya = u32(y0);
    let yb = min(ya + 1u, IRRADIANCE_H - 1u);
    let top = mix(sky[first + ya * IRRADIANCE_W + xa].xyz,
                  sky[first + ya * IRRADIANCE_W + xb].xyz, t.x);
    let bottom = mix(sky[first + yb * IRRADIANCE_W + xa].xyz,
                     sky[first + yb * IRRADIANCE_W + xb].xyz, t.x);
    return mix(top, bottom, t.y);
}

// The radiance environment light l sends along -d (arriving from direction d).
fn sky_radiance(l: Light, d: vec3<f32>) -> vec3<f32> {
    return sky[sky_texel(l, d).entry].xyz;
}

// The solid-angle pdf with which sample_sky_map picks direction d of environment light l.
fn sky_map_pdf(l: Light, d: vec3<f32>) -> f32 {
    let t = sky_texel(l, d);
    return sky_texel_pdf(sky[t.entry].xyz, t.y, t.sin_theta);
}

// The solid-angle pdf with which sample_light picks direction d of environment light l for a
// surface of normal n: half by the map, half by the cosine about n.
fn sky_pdf(l: Light, n: vec3<f32>, d: vec3<f32>) -> f32 {
    return 0.5 * (sky_map_pdf(l, d) + max(dot(n, d), 0.0) / PI);
}

// A direction of environment light l picked by the unit square's point (u, v) in proportion
// to its radiance's luminance times its solid angle: the row by the rows' shares, the texel by
// its row's, the point within the texel uniformly. e is its radiance over its pdf. Photons
// leave the sky so; surfaces take sample_sky.
fn sample_sky_map(l: Light, u: f32, v: f32) -> LightSample {
    let size = sky_size();
    let rows = 1u + size.x * size.y;
    let y = sky_pick(rows, size.y, 0u, v);
    let fy = sky_remap(rows, y, 0u, v);
    let x = sky_pick(1u + y * size.x, size.x, 3u, u);
    let fx = sky_remap(1u + y * size.x, x, 3u, u);
    let phi = 2.0 * PI * (f32(x) + fx) / f32(size.x);
    let theta = PI * (f32(y) + fy) / f32(size.y);
    let sin_t = sin(theta);
    var s: LightSample;
    s.wi = (sin_t * sin(phi)) * l.edge_u + cos(theta) * l.direction + (-sin_t * cos(phi)) * l.edge_v;
    s.dist = FAR;
    let c = sky[1u + y * size.x + x].xyz;
    let pdf = sky_texel_pdf(c, y, sin_t);
    s.e = select(vec3<f32>(0.0), c / pdf, pdf > 0.0);
    return s;
}

// A direction of environment light l towards a surface of normal n: the unit square's left
// half picks it by the map (sample_sky_map), its right half by the cosine about n, and e
// weighs the radiance by the power heuristic of the two, each taking half the samples
// (e = 2 w L / p of its own strategy). The map alone varies as the cosine does where the sky
// is smooth (a constant sky's irradiance from 16 samples was 10-20 % off a splat), the cosine
// alone misses a small bright sun; together neither.
fn sample_sky(l: Light, n: vec3<f32>, u: f32, v: f32) -> LightSample {
    var s: LightSample;
    let by_map = u < 0.5;
    if by_map {
        s = sample_sky_map(l, 2.0 * u, v);
    } else {
        s.wi = to_world(frame_of(n), sample_cosine(2.0 * u - 1.0, v));
        s.dist = FAR;
    }
    let p_map = sky_map_pdf(l, s.wi);
    let p_cos = max(dot(n, s.wi), 0.0) / PI;
    let own = select(p_cos, p_map, by_map);
    let both = p_map * p_map + p_cos * p_cos;
    s.e = select(vec3<f32>(0.0), sky_radiance(l, s.wi) * (2.0 * own / both), own > 0.0);
    return s;
}

// Whether a light of this kind is sampled on a grid of strata (an area light's points, an
// environment light's directions) rather than at one point.
fn stratified(kind: u32) -> bool {
    return kind == LIGHT_AREA || kind == LIGHT_ENVIRONMENT || kind == LIGHT_SUN;
}

// An environment light's strata per side, in an area light's: a sky fills the hemisphere, and
// at 4 x 4 samples a splat its irradiance over an open plane varied by 5.6 % (sd) from splat
// to splat.
const SKY_STRATA: u32 = 2u;

// The side of the grid of strata a light of this kind is sampled on, where an area light's
// has n: 1 for a light sampled at one point.
fn strata_side(kind: u32, n: u32) -> u32 {
    if kind == LIGHT_ENVIRONMENT {
        return SKY_STRATA * n;
    }
    return select(1u, n, stratified(kind));
}

// The solid angle of the sun's disk: 2 pi (1 - cos), cos_inner holding 1 - cos.
fn sun_solid_angle(l: Light) -> f32 {
    return 2.0 * PI * l.cos_inner;
}

// The solid-angle pdf of light l's sample along wi towards a surface of normal n (an area
// light's point at distance dist): 0 for a light sampled at one point, which no ray meets.
fn light_pdf(l: Light, n: vec3<f32>, wi: vec3<f32>, dist: f32) -> f32 {
    if l.kind == LIGHT_AREA {
        let cos_l = -dot(wi, l.direction);
        return select(0.0, dist * dist / (l.area * cos_l), cos_l > 0.0);
    }
    if l.kind == LIGHT_ENVIRONMENT {
        return sky_pdf(l, n, wi);
    }
    if l.kind == LIGHT_SUN {
        return 1.0 / sun_solid_angle(l);
    }
    return 0.0;
}

// The radiance light l sends along -d to a ray d that leaves the scene: a sky's, or the
// sun's where d lies in its disk.
fn escaped_radiance(l: Light, d: vec3<f32>) -> vec3<f32> {
    if l.kind == LIGHT_ENVIRONMENT {
        return sky_radiance(l, d);
    }
    if l.kind == LIGHT_SUN && -dot(d, l.direction) >= l.cos_outer {
        return l.power / (l.area * sun_solid_angle(l));
    }
    return vec3<f32>(0.0);
}

// The mean of a spot's smooth falloff over its cone, uniform in cos (see photons.rs).
fn spot_falloff_mean(l: Light) -> f32 {
    if l.cos_inner <= l.cos_outer {
        return 1.0;
    }
    return ((l.cos_inner - l.cos_outer) * 0.5 + (1.0 - l.cos_inner)) / (1.0 - l.cos_outer);
}

// A point on a light towards p, a surface of normal n: (u, v) picks the point of an area light
// or the direction of an environment light or the sun's disk.
fn sample_light(l: Light, p: vec3<f32>, n: vec3<f32>, u: f32, v: f32) -> LightSample {
    if l.kind == LIGHT_ENVIRONMENT {
        return sample_sky(l, n, u, v);
    }
    return sample_emitter(l, p, u, v);
}

// sample_light of any light but the sky, which reads no map: what a pass that binds none calls.
fn sample_emitter(l: Light, p: vec3<f32>, u: f32, v: f32) -> LightSample {
    var s: LightSample;
    if l.kind == LIGHT_DIRECTIONAL || l.kind == LIGHT_SUN {
        s.wi = -l.direction;
        if l.kind == LIGHT_SUN {
            // Uniform over the disk's cone (sample_cone, with 1 - cos exact).
            s.wi = to_world(frame_of(-l.direction), polar(1.0 - u * l.cos_inner, v));
        }
        s.dist = FAR;
        s.e = l.power / l.area;
        return s;
    }
    var q = l.position;
    if l.kind == LIGHT_AREA {
        q += u * l.edge_u + v * l.edge_v;
    }
    let to = q - p;
    let d2 = dot(to, to);
    s.dist = sqrt(d2);
    s.wi = to / s.dist;
    let cos_l = -dot(s.wi, l.direction);
    if l.kind == LIGHT_AREA {
        // Radiance power / (pi A) over the whole rectangle: pdf 1 / A per point.
        s.e = l.power * (max(cos_l, 0.0) / (PI * d2));
    } else if l.kind == LIGHT_SPOT {
        let ramp = select(1.0, smoothstep(l.cos_outer, l.cos_inner, cos_l), l.cos_inner > l.cos_outer);
        let inside = select(0.0, ramp, cos_l >= l.cos_outer);
        let solid_angle = 2.0 * PI * (1.0 - l.cos_outer);
        s.e = l.power * (inside / (spot_falloff_mean(l) * solid_angle * d2));
    } else {
        s.e = l.power / (4.0 * PI * d2);
    }
    return s;
}

// Stratum j of an area light's n x n grid, jittered by the two hashes at r and r + 1
// (jitter false: the stratum's centre).
fn area_point(j: u32, n: u32, r: u32, jitter: bool) -> vec2<f32> {
    let inv_n = 1.0 / f32(n);
    var o = vec2<f32>(0.5);
    if jitter {
        o = vec2<f32>(unit_float(pcg_hash(r)), unit_float(pcg_hash(r + 1u)));
    }
    return (vec2<f32>(f32(j % n), f32(j / n)) + o) * inv_n;
}

// Whether the ray (o, d) meets area light l before distance t (a surface's hit) and ends
// there. A light that reflects (LIGHT_REFLECTS) ends nothing: the ray goes on to its surface's
// splats just behind its face, which reflect as any surface does.
fn light_first(l: Light, o: vec3<f32>, d: vec3<f32>, t: f32) -> bool {
    if (l.flags & LIGHT_REFLECTS) != 0u {
        return false;
    }
    let tl = area_light_hit(l, o, d);
    return tl > 0.0 && tl < t;
}

// How far a shadow ray from o (its surface point lifted by bias) towards a sample of light l
// at dist from that point looks for what shadows it: dist - bias, and for a light that
// reflects no farther than its face, so that its own surface just behind that face never
// shadows it (the lifted ray can cross the face before dist - bias).
fn shadow_reach(l: Light, o: vec3<f32>, wi: vec3<f32>, dist: f32, bias: f32) -> f32 {
    let reach = dist - bias;
    if (l.flags & LIGHT_REFLECTS) == 0u {
        return reach;
    }
    let t = area_light_hit(l, o, wi);
    return select(reach, min(reach, t), t > 0.0);
}

// Where ray (o, d) meets area light l's emitting face: t > 0, or -1 when it misses it (or
// meets its back, which emits nothing).
fn area_light_hit(l: Light, o: vec3<f32>, d: vec3<f32>) -> f32 {
    let denom = dot(d, l.direction);
    if l.kind != LIGHT_AREA || !(denom < 0.0) {
        return -1.0;
    }
    let t = dot(l.position - o, l.direction) / denom;
    let q = o + t * d - l.position;
    let u = dot(q, l.edge_u) / dot(l.edge_u, l.edge_u);
    let v = dot(q, l.edge_v) / dot(l.edge_v, l.edge_v);
    return select(-1.0, t, t > 0.0 && u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0);
}
