// Lobe fit, after estimate_coverage on the deposits' path (docs/design.md section 6, "Smoothing"):
// the photons' estimate widened where the light is smooth. A splat's irradiance counts the
// photons within R, a few hundred on the default scene, and neighbours within R share most of
// them: the estimate's noise is low-frequency blotches of the size of R. Where the light does
// not change, an estimate from the neighbours further out has less noise for the same light;
// where it changes (a shadow, a corner), it is off. So each splat takes the least noisy of three
// estimates that agree with the narrower ones within their noise (the intersection of
// confidence intervals, Katkovnik's rule for a kernel's width): its own (scale 0), and at two
// scales h, smooth/2 and smooth search radii, a plane fitted by weighted least squares to its
// surface's estimates over the tangent plane (weight 1 - d^2 / h^2, Epanechnikov), read at
// the splat. A plane, not a mean: near a face's edge the neighbours lie on one side, and a
// mean there takes the light of the face's inside (the default box's objects read up to
// +0.95 % with means). A mean of gather disks of radius R under that kernel has the own
// estimate's variance over 1 + 0.75 (h/R)^2 (a numeric convolution: 1.82, 2.69, 3.99 at
// h/R = 1, 1.5, 2); the plane's is the mean's times the ratio of its equivalent kernel's
// squared weights to the mean's (as for independent estimates). The own estimate's relative
// noise is one over the square root of its photons. A neighbour counts where it belongs to the
// splat's object, faces within SMOOTH_COS_MIN of it and its centre lies within the slab: the
// same surface (a reflecting light's disks, just below the ceiling, are another). The
// neighbours are the deposits' records (splats a photon landed on), in the deposit_share bins. The
// choice is made once a coverage group (splats within R/16 of each other facing within
// SMOOTH_COS_MIN: a dense scan's R holds thousands, whose choices differ by little), at its
// leader. Two entry points: main (one invocation a group) writes each group's choice to
// `smoothed`, with its plane's slopes; apply (one invocation a splat) reads its group's plane at the splat's place into the light (a splat must not read a
// neighbour the pass has already changed). CPU mirror: src/cpu/estimate_smooth.rs.

// #import types
// #import dispatch
// #import bins
// #import lobes
// #import sampling

@group(0) @binding(0) var<uniform> em: EmParams;
@group(0) @binding(1) var<uniform> deposit: DepositParams;
@group(0) @binding(2) var<uniform> bins: BinParams;
// #paged
@group(0) @binding(3) var<storage, read> splats: array<Splat>;
@group(0) @binding(4) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(5) var<storage, read> bin_keys: array<vec2<u32>>;
// #paged
@group(0) @binding(6) var<storage, read_write> light: array<SplatLight>;
// Each group's choice, three a group, from the first pass to the second: the plane's light at
// the leader (xyz) and its scale (w: 0 keeps each member's own); its slopes along the leader's
// tangent and bitangent per widest kernel (xyz; w of the first: 1 where the leader's box held
// more records than the budget and an even subset of them was fitted).
// #paged
@group(0) @binding(7) var<storage, read_write> smoothed: array<vec4<f32>>;
// The smoothed splats by the scale they took (0, 1, 2), and those whose group's choice came
// from a subset of its records.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;
// estimate_coverage's groups: each splat's group, then each group's leader.
// #paged
@group(0) @binding(9) var<storage, read> cover: array<u32>;

const WG: u32 = 64u;

// One scale's weighted sums for a plane fitted to the neighbours' light over the tangent plane
// (offsets u, v in units of the widest kernel): the moments of [1, u, v] under the weights w
// (m: 00 01 02 11 12 22) and w^2 (m2), and the light's moments under w.
struct Moments {
    m: array<f32, 6>,
    m2: array<f32, 6>,
    r: array<vec3<f32>, 3>,
}

fn moments_add(a: ptr<function, Moments>, w: f32, u: f32, v: f32, e: vec3<f32>) {
    (*a).m[0] += w;
    (*a).m[1] += w * u;
    (*a).m[2] += w * v;
    (*a).m[3] += w * u * u;
    (*a).m[4] += w * u * v;
    (*a).m[5] += w * v * v;
    let w2 = w * w;
    (*a).m2[0] += w2;
    (*a).m2[1] += w2 * u;
    (*a).m2[2] += w2 * v;
    (*a).m2[3] += w2 * u * u;
    (*a).m2[4] += w2 * u * v;
    (*a).m2[5] += w2 * v * v;
    (*a).r[0] += w * e;
    (*a).r[1] += w * u * e;
    (*a).r[2] += w * v * e;
}

// The fitted plane: its light at the splat and its slopes along u and v (rows 0 to 2, xyz),
// and how much more noise its light at the splat has than the weighted mean of the same
// neighbours (row 0, w); w < 0 where the neighbours do not span the plane.
fn moments_solve(a: Moments) -> array<vec4<f32>, 3> {
    var plane: array<vec4<f32>, 3>;
    plane[0].w = -1.0;
    let m00 = a.m[0];
    let m01 = a.m[1];
    let m02 = a.m[2];
    let m11 = a.m[3];
    let m12 = a.m[4];
    let m22 = a.m[5];
    // The cofactors of the symmetric 3 x 3 moment matrix (its adjugate, symmetric too).
    let c = vec3<f32>(m11 * m22 - m12 * m12, m12 * m02 - m01 * m22, m01 * m12 - m11 * m02);
    let det = m00 * c.x + m01 * c.y + m02 * c.z;
    if !(det > SMOOTH_DET_MIN * m00 * m00 * m00) {
        return plane;
    }
    let c11 = m00 * m22 - m02 * m02;
    let c12 = m01 * m02 - m00 * m12;
    let c22 = m00 * m11 - m01 * m01;
    let fit = c.x * c.x * a.m2[0]
        + c.y * c.y * a.m2[3]
        + c.z * c.z * a.m2[5]
        + 2.0 * (c.x * c.y * a.m2[1] + c.x * c.z * a.m2[2] + c.y * c.z * a.m2[4]);
    let mean = a.m2[0] / (m00 * m00);
    plane[0] = vec4<f32>((c.x * a.r[0] + c.y * a.r[1] + c.z * a.r[2]) / det,
        fit / (det * det) / mean);
    plane[1] = vec4<f32>((c.y * a.r[0] + c11 * a.r[1] + c12 * a.r[2]) / det, 0.0);
    plane[2] = vec4<f32>((c.z * a.r[0] + c12 * a.r[1] + c22 * a.r[2]) / det, 0.0);
    return plane;
}

// Whether a splat's estimate is one to smooth: lit by photons (not by the photon fit's lobes,
// which carry their own irradiance), above zero and with fewer than SMOOTH_PHOTONS_ENOUGH.
fn smoothable(l: SplatLight) -> bool {
    let level = (l.irradiance.x + l.irradiance.y + l.irradiance.z) / 3.0;
    return l.photons > 0u && l.lobes == 0u && level > 0.0 && l.photons < SMOOTH_PHOTONS_ENOUGH;
}

// The second pass: splat i's irradiance read from its group's plane at its place in the
// leader's tangent plane, and counted.
@compute @workgroup_size(64)
fn apply(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= em.splat_count {
        return;
    }
    var l = light_at(i);
    if !smoothable(l) {
        return;
    }
    let g = cover_at(i);
    let choice = smoothed_at(3u * g);
    let s = splats_at(i);
    let leader = splats_at(cover_at(em.splat_count + g));
    // A member of another object than its leader's (a light's disk just below the ceiling)
    // keeps its own: the leader's plane is of its own surface.
    var scale = u32(choice.w);
    if s.object != leader.object {
        scale = 0u;
    }
    if scale != 0u {
        let d = s.center - leader.center;
        let f = frame_of(leader.normal);
        let widest = em.smooth_radii * em.radius;
        let u = dot(d, f.t) / widest;
        let v = dot(d, f.b) / widest;
        let slopes = smoothed_at(3u * g + 1u);
        l.irradiance = choice.xyz + u * slopes.xyz + v * smoothed_at(3u * g + 2u).xyz;
        light_put(i, l);
    }
    atomicAdd(&counters[scale], 1u);
    if slopes_subset(g) {
        atomicAdd(&counters[3], 1u);
    }
}

fn slopes_subset(g: u32) -> bool {
    return smoothed_at(3u * g + 1u).w != 0.0;
}

fn choice_put(g: u32, choice: array<vec4<f32>, 3>) {
    smoothed_put(3u * g, choice[0]);
    smoothed_put(3u * g + 1u, choice[1]);
    smoothed_put(3u * g + 2u, choice[2]);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let invocation = linear_workgroup(wg, num_wg) * WG + lid;
    if invocation >= em.active_count {
        return;
    }
    let g = invocation;
    let i = cover_at(em.splat_count + g);
    let l = light_at(i);
    var chosen: array<vec4<f32>, 3>;
    if !smoothable(l) {
        choice_put(g, chosen);
        return;
    }
    let own = l.irradiance;
    let level = (own.x + own.y + own.z) / 3.0;
    let s = splats_at(i);
    let f = frame_of(s.normal);
    let slab = em.slab * s.radius;
    let widest = em.smooth_radii * em.radius;
    let inv_h2 = vec2<f32>(4.0, 1.0) / (widest * widest);
    // A record lies within its splat's radius of the splat's centre: the box reaches as far
    // past the widest kernel as a deposit's reach does past R.
    let box = bin_box_spanning(s.center, widest + deposit.reach - em.radius, bins, SMOOTH_SPAN);
    var half: Moments;
    var full: Moments;
    // Past the budget, every stride-th record of the box (bin order is the order of space, so
    // the subset is even and the same on every run). The untrimmed rows bound the count: the
    // trimmed count is needed only past the budget. Rows empty untrimmed (most of the box on a
    // flat scan) are skipped before trimming.
    let rows = bin_row_count(box);
    var records_in = 0u;
    for (var r = 0u; r < rows; r++) {
        let all = bin_row_untrimmed(box, r, bins);
        records_in += cell_start[all.y] - cell_start[all.x];
    }
    if records_in > SMOOTH_BUDGET {
        records_in = 0u;
        for (var r = 0u; r < rows; r++) {
            let all = bin_row_untrimmed(box, r, bins);
            if cell_start[all.y] == cell_start[all.x] {
                continue;
            }
            let row = bin_row(box, r, bins);
            records_in += cell_start[row.y] - cell_start[row.x];
        }
    }
    let stride = max(1u, (records_in + SMOOTH_BUDGET - 1u) / SMOOTH_BUDGET);
    var skip = 0u;
    for (var r = 0u; r < rows; r++) {
        let all = bin_row_untrimmed(box, r, bins);
        if cell_start[all.y] == cell_start[all.x] {
            continue;
        }
        let row = bin_row(box, r, bins);
        let end = cell_start[row.y];
        var k = cell_start[row.x] + skip;
        for (; k < end; k += stride) {
            let j = bin_keys_at(k).x;
            let n = splats_at(j);
            let d = n.center - s.center;
            let w = max(vec2<f32>(0.0), vec2<f32>(1.0) - dot(d, d) * inv_h2);
            if w.y == 0.0 || n.object != s.object || abs(dot(d, s.normal)) > slab
                || dot(n.normal, s.normal) < SMOOTH_COS_MIN {
                continue;
            }
            let u = dot(d, f.t) / widest;
            let v = dot(d, f.b) / widest;
            let e = light_at(j).irradiance;
            moments_add(&half, w.x, u, v, e);
            moments_add(&full, w.y, u, v, e);
        }
        // An empty trimmed row leaves k at its start plus skip: the skip carries over.
        skip = k - end;
    }
    // The chosen scale: of those whose intervals meet every narrower one's, the least noisy.
    let sigma = level / sqrt(f32(l.photons));
    var lo = level - SMOOTH_CONFIDENCE * sigma;
    var hi = level + SMOOTH_CONFIDENCE * sigma;
    var narrowest = SMOOTH_CONFIDENCE * sigma;
    for (var k = 0u; k < 2u; k++) {
        var fit: array<vec4<f32>, 3>;
        if k == 0u {
            fit = moments_solve(half);
        } else {
            fit = moments_solve(full);
        }
        if fit[0].w < 0.0 {
            break;
        }
        let ratio = em.smooth_radii * f32(k + 1u) * 0.5;
        let e = fit[0].xyz;
        let m = (e.x + e.y + e.z) / 3.0;
        let half_width = SMOOTH_CONFIDENCE * sigma * sqrt(fit[0].w / (1.0 + 0.75 * ratio * ratio));
        lo = max(lo, m - half_width);
        hi = min(hi, m + half_width);
        if lo > hi {
            break;
        }
        // A fit noisier than the choice so far (one-sided neighbours) is no better.
        if half_width < narrowest {
            chosen = fit;
            chosen[0].w = f32(k + 1u);
            narrowest = half_width;
        }
    }
    chosen[1].w = select(0.0, 1.0, stride > 1u);
    choice_put(g, chosen);
}
