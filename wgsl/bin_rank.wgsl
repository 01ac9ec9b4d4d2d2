// Photon binning, pass 3 of 4: the final slot of every scratch entry. Keys (path, bounce) are
// unique, so an entry's rank in its cell is the number of smaller keys in the cell's list; the
// slot is the cell's start plus that rank. Lists can be long, so each dispatch compares
// against one chunk of RANK_CHUNK entries of every list and adds its count (dispatch 0 starts
// from the cell start): each invocation's loop stays far below llvmpipe's silent limit.
// No atomics, so the result does not depend on scheduling. CPU mirror: src/cpu/bin_rank.rs.

// #import types
// #import dispatch
// #import bins

@group(0) @binding(0) var<uniform> bins: BinParams;
@group(0) @binding(1) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(2) var<storage, read> scratch_keys: array<vec2<u32>>;
// #paged
@group(0) @binding(3) var<storage, read> scratch_cells: array<u32>;
@group(0) @binding(4) var<storage, read_write> slots: array<u32>;

const WG: u32 = 64u;

fn key_less(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let e = linear_workgroup(wg, num_wg) * WG + lid;
    if e >= bins.photon_count {
        return;
    }
    let key = scratch_keys_at(e);
    let c = scratch_cells_at(e);
    let begin = cell_start[c] + bins.rank_chunk * RANK_CHUNK;
    let end = min(cell_start[c + 1u], begin + RANK_CHUNK);
    var rank = 0u;
    for (var k = begin; k < end; k++) {
        rank += u32(key_less(scratch_keys_at(k), key));
    }
    if bins.rank_chunk == 0u {
        slots[e] = cell_start[c] + rank;
    } else {
        slots[e] += rank;
    }
}
