// Lobe fit, after the photon pass, on every path (docs/design.md section 6): where a
// splat's gather disk leaves its surface (an edge, a corner), its photons land on part of the
// disk but the estimate divides their power by all of it, pi R^2: the faces' light darkens
// towards their edges. The share of the gather disk that the surface covers is measured at the
// points of a COVERAGE_GRID^2 grid over the disk in the splat's plane that lie within R: a
// point is covered where a disk of the same surface (its normal within SURFACE_COS_MIN of the
// splat's, as the photons' test) lies within the photons' slab of it and reaches over it where
// its surface keeps it (SurfaceClip: photons pass a box's disks past its edges). The splat's
// irradiance is divided by that share (at least COVERAGE_MIN).
// The points are searched in the splat grid's cell that holds them. Eight of them, near the
// rim (COVERAGE_PROBES), are tested first: a splat whose probes are all covered lies inside its
// face and keeps its estimate (8 point tests, not 69).
// The share changes little over a small part of R (at most about 0.64 per R the centre moves),
// so splats share it in groups (src/fit_groups.rs, CoverGroups: cells of R/16, facing within
// 11 degrees): a dense scan, whose every R holds thousands of splats, measures it once a group,
// not once a splat. Two passes of this stage: the first (EM_COVER_APPLY unset), one invocation
// per group, measures the share at the group's leader; the second, one per splat with photons,
// divides its irradiance by its group's share. CPU mirror: src/cpu/em_coverage.rs.

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
// Points a side of the grid over the gather disk (69 of its 81 lie within R).
const COVERAGE_GRID: u32 = 9u;
// The least share divided by: a splat's disk on a thin feature keeps a bounded estimate.
const COVERAGE_MIN: f32 = 0.2;
// Disk tests a splat may spend (lavapipe ends an invocation's loops near 65 k iterations).
const COVERAGE_BUDGET: u32 = 16384u;
// Grid points (a, b) tested first, near the rim: the four at the ends of the axes and the four
// on the diagonals.
const PROBE_COUNT: u32 = 8u;
const COVERAGE_PROBES = array<vec2<u32>, PROBE_COUNT>(
    vec2<u32>(0u, 4u), vec2<u32>(8u, 4u), vec2<u32>(4u, 0u), vec2<u32>(4u, 8u),
    vec2<u32>(1u, 1u), vec2<u32>(7u, 1u), vec2<u32>(1u, 7u), vec2<u32>(7u, 7u),
);

// Grid point (a, b) in the splat's frame, in units of R (inside the disk where |u| <= 1).
fn grid_point(a: u32, b: u32) -> vec2<f32> {
    return (vec2<f32>(f32(a), f32(b)) + 0.5) * (2.0 / f32(COVERAGE_GRID)) - 1.0;
}

// Point u (in units of R) of splat s's gather disk, in frame f of its plane.
fn disk_point(s: Splat, f: Frame, u: vec2<f32>) -> vec3<f32> {
    return s.center + em.radius * (u.x * f.t + u.y * f.b);
}

// Whether a disk of the surface with normal n reaches over point q, within `slab` of its plane.
fn covered(q: vec3<f32>, n: vec3<f32>, slab: f32, budget: ptr<function, u32>) -> bool {
    let c = point_cell(q, grid);
    if any(c < vec3<i32>(0)) || any(c >= vec3<i32>(grid.dims)) {
        return false;
    }
    let ci = cell_index(vec3<u32>(c), grid);
    // An empty cell (the distance field's nonzero) lists no disk.
    if cell_dist[ci] != 0u {
        return false;
    }
    var e = cell_start[ci];
    let end = cell_start[ci + 1u];
    // Where a disk's surface ends (a box's edge), it covers nothing, as photons see it. The
    // clip is read out of the disk loop, for the next disk that reaches over q (as trace_ray).
    loop {
        var found = NO_SPLAT;
        var at = q;
        for (; e < end && *budget > 0u; e++) {
            *budget -= 1u;
            let j = cell_splats_at(e);
            let s = splats_at(j);
            if dot(s.normal, n) < SURFACE_COS_MIN {
                continue;
            }
            let off = dot(q - s.center, s.normal);
            let p = q - off * s.normal - s.center;
            if abs(off) <= slab && dot(p, p) <= s.radius * s.radius {
                found = j;
                at = q - off * s.normal;
                e++;
                break;
            }
        }
        if found == NO_SPLAT {
            return false;
        }
        if surface_keeps(splats_at(found), at) {
            return true;
        }
    }
    // Not reached (naga asks every path to return).
    return false;
}

// The share of splat i's gather disk its surface covers, 1 where the search was cut short.
fn share_of(i: u32) -> f32 {
    let s = splats_at(i);
    let f = frame_of(s.normal);
    let slab = em.slab * s.radius;
    var budget = COVERAGE_BUDGET;
    var probes = 0u;
    for (var k = 0u; k < PROBE_COUNT; k++) {
        let u = grid_point(COVERAGE_PROBES[k].x, COVERAGE_PROBES[k].y);
        if covered(disk_point(s, f, u), s.normal, slab, &budget) {
            probes += 1u;
        }
    }
    if probes == PROBE_COUNT {
        return 1.0;
    }
    var inside = 0u;
    var hits = 0u;
    for (var a = 0u; a < COVERAGE_GRID; a++) {
        for (var b = 0u; b < COVERAGE_GRID; b++) {
            let u = grid_point(a, b);
            if dot(u, u) > 1.0 {
                continue;
            }
            inside += 1u;
            if covered(disk_point(s, f, u), s.normal, slab, &budget) {
                hits += 1u;
            }
        }
    }
    // A search cut short corrects nothing.
    if budget == 0u {
        return 1.0;
    }
    return max(f32(hits) / f32(inside), COVERAGE_MIN);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    // First pass: group i's share, at its leader (em.active_count groups).
    if (em.flags & EM_COVER_APPLY) == 0u {
        if i < em.active_count {
            shares_put(i, share_of(cover_at(em.splat_count + i)));
        }
        return;
    }
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
