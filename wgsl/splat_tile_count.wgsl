// Compute splatter, pass 1 (docs/design.md section 8): every splat counts itself into each
// screen tile its triangle may cover (`tile_rect`). One invocation per splat. The counts are
// then scanned into each tile's list start. CPU mirror: src/cpu/splat_tiles.rs.

// #import types
// #import dispatch
// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> tiles: TileParams;
// #paged
@group(0) @binding(2) var<storage, read> splats: array<Splat>;
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;

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
            atomicAdd(&counts[ty * tiles.tiles_x + tx], 1u);
        }
    }
}
