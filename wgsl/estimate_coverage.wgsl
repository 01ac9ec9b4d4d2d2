// Lobe fit, after the photon pass, on every path (docs/design.md section 6): where a
// splat's gather disk leaves its surface (an edge, a corner), its photons land on part of the
// disk but the estimate divides their power by all of it, pi R^2: the faces' light darkens
// towards their edges. The share of the gather disk that the surface covers is measured at the
// 64 points of a spiral over the disk in the splat's plane (COVERAGE_POINTS): a point is
// covered where a disk of the same surface (its normal within SURFACE_COS_MIN of the
// splat's, as the photons' test) reaches over it where its surface keeps it (SurfaceClip:
// photons pass a box's disks past its edges), at a point the photons' test keeps (within the
// slab, within R). A covered point counts the photons the surface over it sends the splat
// (surface_weight: more surface than its shadow in the plane where a curved model turns away,
// of which the photons from the splat's front count). The splat's irradiance is divided by
// that share (at least COVERAGE_MIN, at most 1).
// The surface over a point is searched in the splat grid's cells along the splat's normal.
// Eight of the points, nearest the rim, are tested first: a splat whose probes are all covered
// lies inside its face and keeps its estimate (8 point tests, not 64).
// The share changes little over a small part of R (at most about 0.64 per R the centre moves),
// so splats share it in groups (src/fit_groups.rs, CoverGroups: cells of R/16, facing within
// 11 degrees): a dense scan, whose every R holds thousands of splats, measures it once a group,
// not once a splat. Two entry points: main, one invocation per group, measures the share at
// the group's leader; apply, one per splat with photons, divides its irradiance by its group's
// share. CPU mirror: src/cpu/estimate_coverage.rs.

// #import types
// #import dispatch
// #import bins
// #import sampling
// #import trace
// #import lobes

@group(0) @binding(0) var<uniform> em: EmParams;
// #paged
@group(0) @binding(1) var<storage, read_write> light: array<SplatLight>;
// Each splat's group, then each group's leader (CoverGroups::words).
// #paged
@group(0) @binding(2) var<storage, read> cover: array<u32>;
// Each group's share of its gather disk covered (the first pass writes it).
// #paged
@group(0) @binding(3) var<storage, read_write> shares: array<f32>;

const WG: u32 = 64u;
// The least share divided by: a splat's disk on a thin feature keeps a bounded estimate.
const COVERAGE_MIN: f32 = 0.2;
// A point outside the splat grid.
const NO_CELL: u32 = 0xffffffffu;
// Disk tests a splat may spend (lavapipe ends an invocation's loops near 65 k iterations).
const COVERAGE_BUDGET: u32 = 16384u;
// Points of the gather disk where its coverage is measured, in units of R: a Vogel spiral,
// point k at radius sqrt((k + 1/2) / N), turned by the golden angle from the one before: each
// stands for an equal area, ring by ring. The last PROBE_COUNT, nearest the rim and spread
// around it, are tested first. The mirror writes out the same f32 literals.
const POINT_COUNT: u32 = 64u;
const PROBE_COUNT: u32 = 8u;
const COVERAGE_POINTS = array<vec2<f32>, POINT_COUNT>(
    vec2<f32>(0.088388346, 0.0),
    vec2<f32>(-0.11288609, 0.10341291),
    vec2<f32>(0.017279025, -0.19688559),
    vec2<f32>(0.14228562, 0.18558638),
    vec2<f32>(-0.2611116, -0.046186965),
    vec2<f32>(0.2473477, -0.15734236),
    vec2<f32>(-0.08273296, 0.3077625),
    vec2<f32>(-0.15778074, -0.30379722),
    vec2<f32>(0.34232107, 0.12501511),
    vec2<f32>(-0.35612804, 0.14700449),
    vec2<f32>(0.17167725, -0.36686432),
    vec2<f32>(0.12686512, 0.404466),
    vec2<f32>(-0.38237295, -0.22159293),
    vec2<f32>(0.448567, -0.0986162),
    vec2<f32>(-0.27375346, 0.38938612),
    vec2<f32>(-0.06324339, -0.48804486),
    vec2<f32>(0.38825238, 0.32721952),
    vec2<f32>(-0.522466, 0.021605609),
    vec2<f32>(0.38109884, -0.37924424),
    vec2<f32>(-0.025496988, 0.5513959),
    vec2<f32>(-0.36261675, -0.43453607),
    vec2<f32>(0.574425, 0.07728807),
    vec2<f32>(-0.48670912, 0.33863953),
    vec2<f32>(0.13299693, -0.5911847),
    vec2<f32>(0.30761498, 0.5368291),
    vec2<f32>(-0.6013578, -0.19184956),
    vec2<f32>(0.5841426, -0.2698887),
    vec2<f32>(-0.25306517, 0.6046863),
    vec2<f32>(-0.2258551, -0.6279347),
    vec2<f32>(0.60097617, 0.31585622),
    vec2<f32>(-0.6675333, 0.17595963),
    vec2<f32>(0.37943053, -0.59010166),
    vec2<f32>(0.12069909, 0.7023135),
    vec2<f32>(-0.57200783, -0.442995),
    vec2<f32>(0.7317019, -0.06062001),
    vec2<f32>(-0.50576025, 0.54671204),
    vec2<f32>(0.003684028, -0.7551814),
    vec2<f32>(0.51430494, 0.56694615),
    vec2<f32>(-0.7722949, -0.07157611),
    vec2<f32>(0.6257873, -0.47495025),
    vec2<f32>(-0.14238057, 0.7826495),
    vec2<f32>(-0.42888394, -0.6815395),
    vec2<f32>(0.78592014, 0.21538812),
    vec2<f32>(-0.7334855, 0.37641266),
    vec2<f32>(0.28986168, -0.7818521),
    vec2<f32>(0.31791148, 0.7809416),
    vec2<f32>(-0.7702639, -0.36504245),
    vec2<f32>(0.8232633, -0.25382087),
    vec2<f32>(-0.44015652, 0.7510491),
    vec2<f32>(-0.18464324, -0.85985136),
    vec2<f32>(0.72417736, 0.5144217),
    vec2<f32>(-0.89015734, 0.1109386),
    vec2<f32>(0.58705425, -0.6896954),
    vec2<f32>(0.033319898, 0.91368884),
    vec2<f32>(-0.64772695, -0.6572764),
    vec2<f32>(0.93001413, 0.047552247),
    vec2<f32>(-0.7243231, 0.5984718),
    vec2<f32>(0.13097532, -0.9387667),
    vec2<f32>(0.5422049, 0.7874493),
    vec2<f32>(-0.93964905, -0.21621105),
    vec2<f32>(0.8459368, -0.47927395),
    vec2<f32>(-0.3024919, 0.93243563),
    vec2<f32>(-0.4100971, -0.89910114),
    vec2<f32>(0.91697586, 0.38902795),
);

// The photons a covered point stands for, against a point of the plane: a disk whose
// normal turns from the plane's by an angle of cosine `cos` holds 1/cos as much surface over
// the point (photons land on the surface, not on its shadow in the plane), of which the
// photons that arrive at the plane's front count, (1 + cos)/2 of light spread as cosine about
// the disk's normal (front_share). 1 on a flat face.
fn surface_weight(cos: f32) -> f32 {
    return (1.0 + cos) / (2.0 * cos);
}

// Point u (in units of R) of splat s's gather disk, in frame f of its plane.
fn disk_point(s: Splat, f: Frame, u: vec2<f32>) -> vec3<f32> {
    return s.center + em.radius * (u.x * f.t + u.y * f.b);
}

// What point q of the gather disk of centre c and normal n counts towards its covered
// share: surface_weight of the first disk that reaches over q at a point the photons' test
// keeps (within `slab` of the plane, within R of c, facing within SURFACE_COS_MIN), where its
// surface keeps it; else 0. Where the surface curves away from the plane, the surface over q
// lies up to the slab away from it along n, in another cell: the cells along n through q are
// searched, q's own first, then from one end of the slab to the other in steps of half a cell.
fn covered(q: vec3<f32>, c: vec3<f32>, n: vec3<f32>, slab: f32, budget: ptr<function, u32>) -> f32 {
    let own = cell_at(q);
    if own != NO_CELL {
        let w = covered_in_cell(own, q, c, n, slab, budget);
        if w >= 0.0 {
            return w;
        }
    }
    let step = 0.5 * grid.cell_size;
    let steps = i32(ceil(slab / step));
    var last = own;
    for (var k = -steps; k <= steps; k++) {
        let ci = cell_at(q + (f32(k) * step) * n);
        if ci == NO_CELL || ci == own || ci == last {
            continue;
        }
        last = ci;
        let w = covered_in_cell(ci, q, c, n, slab, budget);
        if w >= 0.0 {
            return w;
        }
    }
    return 0.0;
}

// The grid cell of p, NO_CELL outside the grid.
fn cell_at(p: vec3<f32>) -> u32 {
    let cell = point_cell(p, grid);
    if any(cell < vec3<i32>(0)) || any(cell >= vec3<i32>(grid.dims)) {
        return NO_CELL;
    }
    return cell_index(vec3<u32>(cell), grid);
}

// `covered` within cell ci: the weight of the first of its disks that reaches over q where its
// surface keeps it, −1 where none does.
fn covered_in_cell(ci: u32, q: vec3<f32>, c: vec3<f32>, n: vec3<f32>, slab: f32,
                   budget: ptr<function, u32>) -> f32 {
    // An empty cell (the distance field's nonzero) lists no disk.
    if (cell_dist[ci] & DIST_MASK) != 0u {
        return -1.0;
    }
    var e = cell_start[ci];
    let end = cell_start[ci + 1u];
    // Where a disk's surface ends (a box's edge), it covers nothing, as photons see it. The
    // clip is read out of the disk loop, for the next disk that reaches over q (as trace_ray).
    loop {
        var found = NO_SPLAT;
        var at = q;
        var cos = 1.0;
        for (; e < end && *budget > 0u; e++) {
            *budget -= 1u;
            let j = cell_splats_at(e);
            let s = splats_at(j);
            let cj = dot(s.normal, n);
            if cj < SURFACE_COS_MIN {
                continue;
            }
            // The line through q along n meets this disk's plane at height t over the gather
            // disk's plane: the point whose shadow in the plane q is, tested as photons are.
            let t = -dot(q - s.center, s.normal) / cj;
            let on = q + t * n;
            let p = on - s.center;
            let d = on - c;
            if abs(t) <= slab && dot(p, p) <= s.radius * s.radius
                && dot(d, d) <= em.radius2 {
                found = j;
                at = on;
                cos = cj;
                e++;
                break;
            }
        }
        if found == NO_SPLAT {
            return -1.0;
        }
        if surface_keeps(splats_at(found), at) {
            return surface_weight(cos);
        }
    }
    // Not reached (naga asks every path to return).
    return -1.0;
}

// The share of splat i's gather disk its surface covers, 1 where the search was cut short.
fn share_of(i: u32) -> f32 {
    let s = splats_at(i);
    let f = frame_of(s.normal);
    let slab = em.slab * s.radius;
    var budget = COVERAGE_BUDGET;
    var probes = 0u;
    var area = 0.0;
    for (var k = POINT_COUNT - PROBE_COUNT; k < POINT_COUNT; k++) {
        let w = covered(disk_point(s, f, COVERAGE_POINTS[k]), s.center, s.normal, slab, &budget);
        probes += select(0u, 1u, w > 0.0);
        area += w;
    }
    if probes == PROBE_COUNT {
        return 1.0;
    }
    for (var k = 0u; k < POINT_COUNT - PROBE_COUNT; k++) {
        area += covered(disk_point(s, f, COVERAGE_POINTS[k]), s.center, s.normal, slab, &budget);
    }
    // A search cut short corrects nothing.
    if budget == 0u {
        return 1.0;
    }
    return clamp(area / f32(POINT_COUNT), COVERAGE_MIN, 1.0);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    // Group i's share, at its leader (em.active_count groups).
    if i < em.active_count {
        shares_put(i, share_of(cover_at(em.splat_count + i)));
    }
}

// The second pass: splat i's irradiance divided by its group's share.
@compute @workgroup_size(64)
fn apply(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= em.splat_count {
        return;
    }
    var l = light_at(i);
    // Lobes the photon fit wrote carry their own irradiance: correcting the total alone would
    // split the splat's diffuse light from its glossy light.
    if l.photons == 0u || l.lobes > 0u {
        return;
    }
    l.irradiance = l.irradiance / shares_at(cover_at(i));
    light_put(i, l);
}
