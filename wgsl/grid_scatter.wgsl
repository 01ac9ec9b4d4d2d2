// Splat grid build, pass 3 of 4: write each (cell, splat) entry into a scratch list. Slots come
// from an atomic cursor per cell, so the order inside a cell depends on scheduling; grid_rank
// then moves every entry to its deterministic slot. CPU mirror: src/cpu/grid_scatter.rs.

// #import types
// #import dispatch
// #import grid

@group(0) @binding(0) var<uniform> grid: GridParams;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(2) var<storage, read> cell_start: array<u32>;
@group(0) @binding(3) var<storage, read_write> cell_cursor: array<atomic<u32>>;
// #paged
@group(0) @binding(4) var<storage, read_write> scratch_splats: array<u32>;
// #paged
@group(0) @binding(5) var<storage, read_write> scratch_cells: array<u32>;

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
                let c = cell_index(vec3<u32>(x, y, z), grid);
                let slot = cell_start[c] + atomicAdd(&cell_cursor[c], 1u);
                scratch_splats_put(slot, i);
                scratch_cells_put(slot, c);
            }
        }
    }
}
