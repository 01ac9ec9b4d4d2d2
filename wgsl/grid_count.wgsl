// Splat grid build, pass 1 of 4: count how many splats list each cell, and track the longest
// list (the host checks it against the loop budget of grid_rank).
// One invocation per splat; integer atomics only, so the counts are exact and order-free.
// CPU mirror: src/cpu/grid_count.rs.

// #import types
// #import dispatch
// #import grid

@group(0) @binding(0) var<uniform> grid: GridParams;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(2) var<storage, read_write> cell_counts: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> max_cell_len: atomic<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= grid.splat_count {
        return;
    }
    let r = disk_cell_range(splats_at(i), grid);
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            for (var x = r.lo.x; x <= r.hi.x; x++) {
                let before = atomicAdd(&cell_counts[cell_index(vec3<u32>(x, y, z), grid)], 1u);
                atomicMax(&max_cell_len, before + 1u);
            }
        }
    }
}
