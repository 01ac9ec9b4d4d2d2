// Lobe fit, pass 1 of 3: list the splats that have binned photons near them, so em_fit and
// estimate_gather spend no work on the others (their outputs stay zero). A splat that is not fitted
// and has at most GATHER_MAX candidates goes to the gather list: estimate_gather sums its
// irradiance in one invocation, where a workgroup of em_fit would cost many times more. An entry is
// the splat index, with the top bit set when the splat's lobes are fitted (a glossy material, or
// EM_FIT_ALL), and the fitted splat's slot in the lobe buffer, so that it holds lobes for fitted
// splats alone; other listed splats only gather their total irradiance. The list's order and the
// slots depend on scheduling, but each em_fit workgroup writes only its own splat's light and slot,
// and the host packs the lobes in splat order (LobeMap::pack), so the results do not. counters =
// [fit-list splats, most candidate photons of a fit-list splat, splats fitted, gather-list splats].
// With shared fits (EM_GROUPS) only each group's leader is listed among the fitted splats. With
// deposits (EM_SHARE) deposit_share lights every splat, and only the fitted splats are listed (on
// the fit list), without a look at the others' candidates. CPU mirror: src/cpu/fit_select.rs.

// #import types
// #import dispatch
// #import bins
// #import lobes

@group(0) @binding(0) var<uniform> em: EmParams;
@group(0) @binding(1) var<uniform> bins: BinParams;
// #paged
@group(0) @binding(2) var<storage, read> splats: array<Splat>;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var<storage, read> cell_start: array<u32>;
@group(0) @binding(5) var<storage, read_write> fit_list: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(7) var<storage, read_write> gather_list: array<u32>;
// With EM_GROUPS, the shared fits' groups (src/fit_groups.rs): a splat's word is
// FOLLOWER_BIT | leader where another splat's fit serves it.
@group(0) @binding(8) var<storage, read> groups: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= em.splat_count {
        return;
    }
    let s = splats_at(i);
    let glossy = any(materials[s.material].specular > vec3<f32>(0.0));
    // A splat another's fit serves (EM_GROUPS) is lit as a diffuse splat is, not fitted.
    let served = (em.flags & EM_GROUPS) != 0u && (groups[i] & FOLLOWER_BIT) != 0u;
    let fit = (glossy || (em.flags & EM_FIT_ALL) != 0u) && !served;
    // With deposits deposit_share lights every splat; only the fitted ones are listed.
    if (em.flags & EM_SHARE) != 0u && !fit {
        return;
    }
    let box = bin_box(s.center, em.radius, bins);
    var candidates = 0u;
    for (var r = 0u; r < bin_row_count(box); r++) {
        let row = bin_row(box, r, bins);
        candidates += cell_start[row.y] - cell_start[row.x];
    }
    if candidates == 0u {
        return;
    }
    if !fit && candidates <= GATHER_MAX {
        gather_list[atomicAdd(&counters[3], 1u)] = i;
        return;
    }
    var lobe_slot = 0u;
    if fit {
        lobe_slot = atomicAdd(&counters[2], 1u);
    }
    let slot = atomicAdd(&counters[0], 1u);
    fit_list[slot] = vec2<u32>(i | select(0u, FIT_BIT, fit), lobe_slot);
    atomicMax(&counters[1], candidates);
}
