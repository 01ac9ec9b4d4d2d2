// Tone mapping, pass 1 (docs/design.md section 9): one level of the log-average luminance. Each
// workgroup sums (log(eps + Y), count) over a block of BLOCK values in a fixed order (each
// invocation its ITEMS consecutive values, then a tree over the invocations) into one partial
// sum; the host runs levels until one sum is left. Level 0 reads HDR pixels (NaN and Inf
// pixels count for nothing), later levels the partial sums. No float atomics.
// CPU mirror: src/cpu/tonemap_reduce.rs.

// #import types
// #import dispatch
// #import tone

@group(0) @binding(0) var<uniform> tone: ToneParams;
@group(0) @binding(1) var<storage, read> hdr: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> sums_in: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> sums_out: array<vec2<f32>>;

const WG: u32 = 256u;
const ITEMS: u32 = 8u;
const BLOCK: u32 = WG * ITEMS;

var<workgroup> partial: array<vec2<f32>, WG>;

fn value(i: u32) -> vec2<f32> {
    if tone.level == 0u {
        return log_luminance(hdr[i].xyz, tone.epsilon);
    }
    return sums_in[i];
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let block = linear_workgroup(wg, num_wg);
    // Uniform per workgroup, so returning before the barriers is allowed.
    if block * BLOCK >= tone.count {
        return;
    }
    let base = block * BLOCK + lid * ITEMS;
    var sum = vec2<f32>(0.0);
    for (var k = 0u; k < ITEMS; k++) {
        if base + k < tone.count {
            sum += value(base + k);
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
        sums_out[block] = partial[0];
    }
}
