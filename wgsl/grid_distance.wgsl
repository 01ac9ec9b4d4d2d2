// Splat grid, distance field for empty-space skipping: the Chebyshev distance (in cells,
// capped at DIST_CAP) from each cell to the nearest cell that lists a splat. Three passes, one
// per axis (the L-infinity distance is separable): pass x reads occupancy from the cell
// lists, passes y and z read the previous pass. One invocation per cell, 2 * DIST_CAP + 1
// loop iterations each.
// CPU mirror: src/cpu/grid_distance.rs.

// #import types
// #import dispatch
// #import grid

@group(0) @binding(0) var<uniform> params: DistanceParams;
@group(0) @binding(1) var<uniform> grid: GridParams;
@group(0) @binding(2) var<storage, read> cell_start: array<u32>;
@group(0) @binding(3) var<storage, read> src: array<u32>;
@group(0) @binding(4) var<storage, read_write> dst: array<u32>;

const WG: u32 = 64u;

fn value_at(c: u32) -> u32 {
    if params.axis == 0u {
        return select(DIST_CAP, 0u, cell_start[c + 1u] > cell_start[c]);
    }
    return src[c];
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let c = linear_workgroup(wg, num_wg) * WG + lid;
    if c >= grid.cell_count {
        return;
    }
    let coord = vec3<u32>(c % grid.dims.x, (c / grid.dims.x) % grid.dims.y,
                          c / (grid.dims.x * grid.dims.y));
    let strides = vec3<u32>(1u, grid.dims.x, grid.dims.x * grid.dims.y);
    let pos = i32(coord[params.axis]);
    let len = i32(grid.dims[params.axis]);
    let stride = strides[params.axis];
    var best = DIST_CAP;
    for (var o = -i32(DIST_CAP); o <= i32(DIST_CAP); o++) {
        let q = pos + o;
        if q >= 0 && q < len {
            let v = value_at(u32(i32(c) + o * i32(stride)));
            best = min(best, max(u32(abs(o)), v));
        }
    }
    dst[c] = best;
}
