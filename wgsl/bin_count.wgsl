// Photon binning, pass 1 of 4: count the photons of one store page per bin cell. The counts
// are then scanned into cell starts. A photon that opens a new chunk of its cell's list raises
// `chunks`, the number of bin_rank dispatches the longest list needs.
// CPU mirror: src/cpu/bin_count.rs.

// #import types
// #import dispatch
// #import bins

@group(0) @binding(0) var<uniform> bins: BinParams;
@group(0) @binding(1) var<storage, read> photons: array<Photon>;
@group(0) @binding(2) var<storage, read_write> cell_count: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> chunks: atomic<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= bins.photon_count {
        return;
    }
    let c = bin_of(photons[i].position, bins);
    let before = atomicAdd(&cell_count[c], 1u);
    if before % RANK_CHUNK == 0u {
        atomicMax(&chunks, before / RANK_CHUNK + 1u);
    }
}
