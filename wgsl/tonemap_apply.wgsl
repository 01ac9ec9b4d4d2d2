// Tone mapping, pass 2 (docs/design.md section 9): each pixel through the operator with the
// log-average of pass 1, encoded as 8-bit sRGB. CPU mirror: src/cpu/tonemap_apply.rs.

// #import types
// #import dispatch
// #import tone

@group(0) @binding(0) var<uniform> tone: ToneParams;
@group(0) @binding(1) var<storage, read> hdr: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> log_sum: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> rgba: array<u32>;

const WG: u32 = 256u;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= tone.count {
        return;
    }
    rgba[i] = pack_srgb(tone_map(hdr[i].xyz, log_sum[0], tone));
}
