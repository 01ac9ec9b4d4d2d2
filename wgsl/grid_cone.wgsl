// Splat grid, facing cones: for each listed cell, an axis and the widest angle between it and
// the normals of the disks it lists, kept in the upper bits of its distance word (grid.wgsl,
// `cone_faces_away`). A ray leaving a surface crosses the cells of its own surface first, and
// disks are one-sided: where the cone shows that every disk of a cell faces away from the ray,
// trace_ray reads none of them. One invocation per cell; its list is read twice, in order (the
// axis from the normals' sum, then the widest angle from the axis as stored).
// CPU mirror: src/cpu/grid_cone.rs.

// #import types
// #import dispatch
// #import grid

@group(0) @binding(0) var<uniform> grid: GridParams;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(2) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(3) var<storage, read> cell_splats: array<u32>;
@group(0) @binding(4) var<storage, read_write> cell_dist: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let c = linear_workgroup(wg, num_wg) * WG + lid;
    if c >= grid.cell_count {
        return;
    }
    let start = cell_start[c];
    let end = cell_start[c + 1u];
    var sum = vec3<f32>(0.0);
    for (var e = start; e < end; e++) {
        sum += splats_at(cell_splats_at(e)).normal;
    }
    // An empty cell, or normals that cancel, keep no cone.
    if !(abs(sum.x) + abs(sum.y) + abs(sum.z) > 0.0) {
        return;
    }
    let code = cone_axis_encode(sum);
    let axis = cone_axis(code);
    var cos_min = 1.0;
    for (var e = start; e < end; e++) {
        cos_min = min(cos_min, dot(axis, splats_at(cell_splats_at(e)).normal));
    }
    // Lowered a little for rounding; a cone as wide as a right angle turns no ray away.
    let cos_t = cos_min - CONE_MARGIN;
    if !(cos_t > 0.0) {
        return;
    }
    let sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    let open = u32(clamp(floor((1.0 - sin_t) * CONE_STEPS), 0.0, CONE_STEPS));
    cell_dist[c] = (cell_dist[c] & DIST_MASK) | code | (open << 24u);
}
