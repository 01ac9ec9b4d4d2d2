// Splat grid build, pass 4 of 4: put each cell's list in splat-index order. One invocation per
// scratch entry (cell c, splat i): it counts the smaller indices in c's scratch list (indices in
// a cell are distinct, so the count is i's rank) and writes i at cell_start[c] + rank. No
// in-place swaps and no atomics: the result does not depend on how the scatter was scheduled.
// Work per invocation is one list's length, which the host keeps under MAX_CELL_LEN because
// llvmpipe silently ends loops past ~65k iterations per invocation.
// CPU mirror: src/cpu/grid_rank.rs.

// #import types
// #import dispatch

@group(0) @binding(0) var<uniform> grid: GridParams;
@group(0) @binding(1) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(2) var<storage, read> scratch_splats: array<u32>;
// #paged
@group(0) @binding(3) var<storage, read> scratch_cells: array<u32>;
// #paged
@group(0) @binding(4) var<storage, read_write> cell_splats: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let e = linear_workgroup(wg, num_wg) * WG + lid;
    if e >= grid.entry_count {
        return;
    }
    let i = scratch_splats_at(e);
    let c = scratch_cells_at(e);
    let begin = cell_start[c];
    let end = cell_start[c + 1u];
    var rank = 0u;
    for (var k = begin; k < end; k++) {
        rank += u32(scratch_splats_at(k) < i);
    }
    cell_splats_put(begin + rank, i);
}
