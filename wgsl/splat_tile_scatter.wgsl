// Compute splatter, pass 2 (docs/design.md section 8): every splat writes (splat, tile) into
// each tile's list from its scanned start, in whatever order the atomics give; `grid_rank`
// then puts each list in splat-index order, the raster passes' draw order. One invocation
// per splat. CPU mirror: src/cpu/splat_tiles.rs.

// #import types
// #import dispatch
// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> tiles: TileParams;
// #paged
@group(0) @binding(2) var<storage, read> splats: array<Splat>;
@group(0) @binding(3) var<storage, read> tile_start: array<u32>;
@group(0) @binding(4) var<storage, read_write> cursor: array<atomic<u32>>;
// #paged
@group(0) @binding(5) var<storage, read_write> scratch_splats: array<u32>;
@group(0) @binding(6) var<storage, read_write> scratch_tiles: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= tiles.splat_count {
        return;
    }
    let r = tile_rect(cam, splats_at(i), tiles.tiles_x, tiles.tiles_y);
    for (var ty = r.y; ty <= r.w && r.x <= r.z; ty++) {
        for (var tx = r.x; tx <= r.z; tx++) {
            let t = ty * tiles.tiles_x + tx;
            let e = tile_start[t] + atomicAdd(&cursor[t], 1u);
            scratch_splats_put(e, i);
            scratch_tiles[e] = t;
        }
    }
}
