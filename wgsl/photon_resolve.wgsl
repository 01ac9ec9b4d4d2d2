// The photon view's fixed-point sums (photon_view) as HDR pixels, for the tone map.
// One invocation per pixel. CPU mirror: src/cpu/photon_resolve.rs.

// #import types
// #import dispatch

@group(0) @binding(0) var<uniform> params: PhotonViewParams;
@group(0) @binding(1) var<storage, read> sums: array<u32>;
@group(0) @binding(2) var<storage, read_write> hdr: array<vec4<f32>>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= params.count {
        return;
    }
    let rgb = vec3<f32>(f32(sums[3u * i]), f32(sums[3u * i + 1u]), f32(sums[3u * i + 2u]));
    hdr[i] = vec4<f32>(rgb / params.scale, 1.0);
}
