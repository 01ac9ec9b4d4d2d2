// Photon binning, pass 4 of 4: move every scratch entry to the slot bin_rank gave it. Each
// cell's list is then in key order, so every later sum over it runs in a fixed order.
// CPU mirror: src/cpu/bin_place.rs.

// #import types
// #import dispatch

@group(0) @binding(0) var<uniform> bins: BinParams;
@group(0) @binding(1) var<storage, read> slots: array<u32>;
// #paged
@group(0) @binding(2) var<storage, read> scratch_keys: array<vec2<u32>>;
// #paged
@group(0) @binding(3) var<storage, read> scratch_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(4) var<storage, read> scratch_power: array<vec4<f32>>;
// #paged
@group(0) @binding(5) var<storage, read_write> bin_keys: array<vec2<u32>>;
// #paged
@group(0) @binding(6) var<storage, read_write> bin_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(7) var<storage, read_write> bin_power: array<vec4<f32>>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let e = linear_workgroup(wg, num_wg) * WG + lid;
    if e >= bins.photon_count {
        return;
    }
    let slot = slots[e];
    bin_keys_put(slot, scratch_keys_at(e));
    bin_geom_put(slot, scratch_geom_at(e));
    bin_power_put(slot, scratch_power_at(e));
}
