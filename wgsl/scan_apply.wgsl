// Exclusive scan, down-sweep of one level: scans each block of BLOCK = WG * ITEMS values in place
// and adds the block's offset (the exclusive scan of the block sums; a single zero when the
// whole input fits one block). CPU mirror: src/cpu/scan_apply.rs.

// #import types
// #import dispatch

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> values: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

const WG: u32 = 256u;
const ITEMS: u32 = 4u;

var<workgroup> sums: array<u32, WG>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let block = linear_workgroup(wg, num_wg);
    if block * WG * ITEMS >= params.len {
        return;
    }
    let base = (block * WG + lid) * ITEMS;
    // Each invocation scans its ITEMS values serially...
    var local: array<u32, ITEMS>;
    var total = 0u;
    for (var k = 0u; k < ITEMS; k++) {
        local[k] = total;
        if base + k < params.len {
            total += values[base + k];
        }
    }
    sums[lid] = total;
    workgroupBarrier();
    // ...then the workgroup scans the invocation totals (Hillis-Steele, inclusive).
    for (var offset = 1u; offset < WG; offset <<= 1u) {
        var left = 0u;
        if lid >= offset {
            left = sums[lid - offset];
        }
        workgroupBarrier();
        sums[lid] += left;
        workgroupBarrier();
    }
    var prefix = block_offsets[block];
    if lid > 0u {
        prefix += sums[lid - 1u];
    }
    for (var k = 0u; k < ITEMS; k++) {
        if base + k < params.len {
            values[base + k] = prefix + local[k];
        }
    }
}
