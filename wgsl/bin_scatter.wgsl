// Photon binning, pass 2 of 4: copy the photons of one store page into a scratch list grouped
// by cell, in the compact binned form (position + octahedral direction, RGB power + the
// surface it landed on, surface_encode of its splat's normal), each with its sort key (path, bounce) and cell. Slots come from an atomic cursor
// per cell, so the order inside a cell depends on scheduling until bin_rank and bin_place.
// CPU mirror: src/cpu/bin_scatter.rs.

// #import types
// #import dispatch
// #import bins
// #import octahedral

@group(0) @binding(0) var<uniform> bins: BinParams;
@group(0) @binding(1) var<storage, read> photons: array<Photon>;
@group(0) @binding(2) var<storage, read> cell_start: array<u32>;
@group(0) @binding(3) var<storage, read_write> cell_cursor: array<atomic<u32>>;
// #paged
@group(0) @binding(4) var<storage, read_write> scratch_keys: array<vec2<u32>>;
// #paged
@group(0) @binding(5) var<storage, read_write> scratch_cells: array<u32>;
// #paged
@group(0) @binding(6) var<storage, read_write> scratch_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(7) var<storage, read_write> scratch_power: array<vec4<f32>>;
// #paged
@group(0) @binding(8) var<storage, read> splats: array<Splat>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= bins.photon_count {
        return;
    }
    let p = photons[i];
    let c = bin_of(p.position, bins);
    let slot = cell_start[c] + atomicAdd(&cell_cursor[c], 1u);
    scratch_keys_put(slot, vec2<u32>(p.path, p.bounce));
    scratch_cells_put(slot, c);
    scratch_geom_put(slot, BinnedPhoton(p.position, oct_encode(p.direction)));
    // A photon's splat is always one of the scene's; were it not, it faces nowhere in particular.
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if p.splat < splats_len() {
        n = splats_at(p.splat).normal;
    }
    scratch_power_put(slot, vec4<f32>(p.power, surface_encode(n)));
}
