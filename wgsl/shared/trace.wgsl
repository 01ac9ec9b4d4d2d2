// Nearest front-facing disk along a ray, through the splat grid (docs/design.md section 4).
// Twin: src/shared/trace.rs. The geometry is bind group 1, the same for every stage that
// traces (photon tracing, test rays; later shadow rays and the reference renderer).
//
// Policy, the same on the CPU:
// - Disks are one-sided: a ray hits a disk only against its normal (dot(n, d) < -PARALLEL_COS).
//   Back faces are transparent, so a ray leaving a surface never hits the overlapping
//   coplanar neighbours it starts behind, and light never leaks *into* a closed model through
//   the back of its own splats.
// - Rays within PARALLEL_COS of a disk's plane miss it (a disk has no thickness).
// - A hit counts only where the disk's surface keeps it (`surface_clips`, SurfaceClip in
//   src/types.rs): a box's disks end at its edges, so that light meets the same box going
//   either way past a convex edge.
// - The disk a ray leaves (`skip`) is ignored; any other front-facing hit with 0 < t counts.
// - Overlapping disks hit at exactly the same t: the first in the cell's list wins, i.e. the
//   lowest splat index, since lists are sorted.
// - A disk listed in several cells is accepted only if its hit lies before the current cell's
//   exit (plus a 1e-4 cell tolerance), so a farther disk met early never hides a nearer one.
// Traversal: 3D DDA (Amanatides & Woo) with empty-space skipping: `cell_dist` holds the
// Chebyshev distance (in cells, capped) to the nearest listed cell, so a ray in an empty cell
// at distance d jumps out of the empty (2d - 1)^3 box around it in one step; a listed cell's
// word also holds its facing cone (grid_cone.wgsl), with which a ray passes a cell whose disks
// all face away from it without reading them. Each step moves
// at least one cell forward and never back, so a ray ends within the sum of the grid's dims.
// Every cell step and disk test spends one unit of `budget`; at zero the ray stops with
// `aborted` set (llvmpipe silently ends an invocation's loops after ~65k iterations).

// #import types
// #import grid

@group(1) @binding(0) var<uniform> grid: GridParams;
// #paged
@group(1) @binding(1) var<storage, read> splats: array<Splat>;
@group(1) @binding(2) var<storage, read> cell_start: array<u32>;
// #paged
@group(1) @binding(3) var<storage, read> cell_splats: array<u32>;
@group(1) @binding(4) var<storage, read> cell_dist: array<u32>;
// Per surface (Splat.object); a surface past the end clips nothing.
@group(1) @binding(5) var<storage, read> surface_clips: array<SurfaceClip>;
// The environment light's map (lights.wgsl reads it; scene::sky::SkyTable).
@group(1) @binding(6) var<storage, read> sky: array<vec4<f32>>;

const PARALLEL_COS: f32 = 1e-6;

// Ray parameter of the hit with a disk's front face, or -1.
fn intersect_disk(s: Splat, o: vec3<f32>, d: vec3<f32>) -> f32 {
    let denom = dot(s.normal, d);
    if !(denom < -PARALLEL_COS) {
        return -1.0;
    }
    let t = dot(s.normal, s.center - o) / denom;
    let q = o + t * d - s.center;
    if !(dot(q, q) <= s.radius * s.radius) {
        return -1.0;
    }
    return t;
}

// Whether splat s's surface keeps the point p of its disk.
fn surface_keeps(s: Splat, p: vec3<f32>) -> bool {
    return s.object >= arrayLength(&surface_clips) || clip_keeps(surface_clips[s.object], p);
}

// Ray parameter of the hit with splat s's disk where its surface keeps it, or -1.
fn intersect_splat(s: Splat, o: vec3<f32>, d: vec3<f32>) -> f32 {
    let t = intersect_disk(s, o, d);
    if t < 0.0 || surface_keeps(s, o + t * d) {
        return t;
    }
    return -1.0;
}

fn miss(t_max: f32) -> Hit {
    var h: Hit;
    h.t = t_max;
    h.splat = NO_SPLAT;
    h.aborted = 0u;
    h._pad = 0u;
    return h;
}

// `d` must be a unit vector; t is then a distance.
fn trace_ray(o: vec3<f32>, d: vec3<f32>, skip: u32, t_max: f32, budget: ptr<function, u32>) -> Hit {
    var hit = miss(t_max);
    let lo = grid.origin;
    let cs = grid.cell_size;
    let dims = vec3<i32>(grid.dims);
    let hi = lo + vec3<f32>(grid.dims) * cs;
    // Axes the ray does not move along take no part in slab tests or steps.
    let moving = abs(d) > vec3<f32>(1e-30);
    let inv = 1.0 / select(vec3<f32>(1.0), d, moving);
    if any(!moving & ((o < lo) | (o > hi))) {
        return hit;
    }
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let near = select(vec3<f32>(-FAR), min(ta, tb), moving);
    let far = select(vec3<f32>(FAR), max(ta, tb), moving);
    let t_enter = max(0.0, max(near.x, max(near.y, near.z)));
    let t_leave = min(t_max, min(far.x, min(far.y, far.z)));
    if !(t_enter <= t_leave) {
        return hit;
    }
    let step = select(vec3<i32>(0), select(vec3<i32>(-1), vec3<i32>(1), d > vec3<f32>(0.0)), moving);
    let p0 = o + t_enter * d;
    var c = clamp(vec3<i32>(floor((p0 - lo) * grid.inv_cell_size)), vec3<i32>(0), dims - 1);
    var t = t_enter;
    loop {
        if *budget == 0u {
            hit.aborted = 1u;
            return hit;
        }
        *budget -= 1u;
        let ci = u32(c.x + dims.x * (c.y + dims.y * c.z));
        let word = cell_dist[ci];
        let dist = word & DIST_MASK;
        let k = i32(max(dist, 1u) - 1u);
        // Exit of the empty box [c - k, c + k + 1) (just the cell when it lists splats).
        let face = select(c - k, c + k + 1, step > vec3<i32>(0));
        let tf = select(vec3<f32>(FAR), (lo + vec3<f32>(face) * cs - o) * inv, moving);
        let t_exit = min(tf.x, min(tf.y, tf.z));
        // Where every disk of a listed cell faces away from the ray (its facing cone: the
        // cells of the surface a ray leaves), none is read, and the budget is spent as if each
        // had been, so that a ray ends where it would have.
        var search = dist == 0u;
        if search && cone_faces_away(word, d) {
            let listed = cell_start[ci + 1u] - cell_start[ci];
            if *budget < listed {
                *budget = 0u;
                hit.aborted = 1u;
                return hit;
            }
            *budget -= listed;
            search = false;
        }
        if search {
            let limit = t_exit + 1e-4 * cs;
            let start = cell_start[ci];
            let end = cell_start[ci + 1u];
            // The cell's nearest disk in (t, list position) order; one its surface's clip
            // passes over is skipped and the cell searched again past it. The clip is then
            // read once a cell, not once a disk: in the disk loop, llvmpipe paid it for every
            // disk (photon tracing 25 % slower).
            var floor_t = 0.0;
            var floor_e = NO_SPLAT;
            loop {
                var best_t = hit.t;
                var best = NO_SPLAT;
                var best_e = 0u;
                for (var e = start; e < end; e++) {
                    if *budget == 0u {
                        hit.aborted = 1u;
                        return hit;
                    }
                    *budget -= 1u;
                    let s = cell_splats_at(e);
                    if s == skip {
                        continue;
                    }
                    let th = intersect_disk(splats_at(s), o, d);
                    let past = th > floor_t || (th == floor_t && floor_e != NO_SPLAT && e > floor_e);
                    if past && th < best_t && th <= limit {
                        best_t = th;
                        best = s;
                        best_e = e;
                    }
                }
                if best == NO_SPLAT || surface_keeps(splats_at(best), o + best_t * d) {
                    hit.t = select(hit.t, best_t, best != NO_SPLAT);
                    hit.splat = best;
                    break;
                }
                floor_t = best_t;
                floor_e = best_e;
            }
            if hit.splat != NO_SPLAT {
                return hit;
            }
        }
        if t_exit >= t_leave {
            return hit;
        }
        t = max(t, t_exit);
        // Next cell: past the exit face on the exit axis; on the others where the ray is now,
        // kept inside the box and never behind the current cell.
        let at = vec3<i32>(floor((o + t * d - lo) * grid.inv_cell_size));
        var n = select(clamp(at, c, c + k), clamp(at, c - k, c), step < vec3<i32>(0));
        n = select(n, c, step == vec3<i32>(0));
        let exit_x = tf.x <= tf.y && tf.x <= tf.z;
        let exit_y = !exit_x && tf.y <= tf.z;
        let exit_axis = vec3<bool>(exit_x, exit_y, !exit_x && !exit_y);
        n = select(n, select(face - 1, face, step > vec3<i32>(0)), exit_axis);
        if any(n < vec3<i32>(0)) || any(n >= dims) {
            return hit;
        }
        c = n;
    }
    return hit;  // not reached: naga wants a return after the loop
}
