// Exclusive scan, up-sweep of one level: the sum of each block of BLOCK = WG * ITEMS values.
// The host scans the block sums recursively (any length), then scan_apply finishes each block.
// Integer sums, fixed tree order. CPU mirror: src/cpu/scan_reduce.rs.

// #import types
// #import dispatch

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read> values: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

const WG: u32 = 256u;
const ITEMS: u32 = 4u;

var<workgroup> partial: array<u32, WG>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let block = linear_workgroup(wg, num_wg);
    // Uniform per workgroup, so returning before the barriers is allowed.
    if block * WG * ITEMS >= params.len {
        return;
    }
    let base = (block * WG + lid) * ITEMS;
    var sum = 0u;
    for (var k = 0u; k < ITEMS; k++) {
        if base + k < params.len {
            sum += values[base + k];
        }
    }
    partial[lid] = sum;
    workgroupBarrier();
    for (var stride = WG / 2u; stride > 0u; stride >>= 1u) {
        if lid < stride {
            partial[lid] += partial[lid + stride];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        block_sums[block] = partial[0];
    }
}
