// Lobe fit, pass 2 of 3: the irradiance of each splat on the gather list (not fitted, at most
// GATHER_MAX candidates; see fit_select), one invocation per splat. It sums what em_fit's final
// pass sums for a splat without lobes: the count, power and weight of the photons within R of
// the centre, on its front side, inside the slab around its plane and on its surface, in the
// candidates' order. Diffuse scans of millions of splats are mostly such splats; a workgroup
// each cost them the bake's time.
// CPU mirror: src/cpu/estimate_gather.rs.

// #import types
// #import dispatch
// #import bins
// #import octahedral
// #import lobes

@group(0) @binding(0) var<uniform> em: EmParams;
@group(0) @binding(1) var<uniform> bins: BinParams;
// #paged
@group(0) @binding(2) var<storage, read> splats: array<Splat>;
@group(0) @binding(3) var<storage, read> gather_list: array<u32>;
@group(0) @binding(4) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(5) var<storage, read> bin_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(6) var<storage, read> bin_power: array<vec4<f32>>;
// #paged
@group(0) @binding(7) var<storage, read_write> light: array<SplatLight>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let index = linear_workgroup(wg, num_wg) * WG + lid;
    if index >= em.active_count {
        return;
    }
    let splat_index = gather_list[index];
    let s = splats_at(splat_index);
    let slab = em.slab * s.radius;
    let box = bin_box(s.center, em.radius, bins);
    var rgb = vec3<f32>(0.0);
    var count = 0u;
    var weight = 0.0;
    for (var r = 0u; r < bin_row_count(box); r++) {
        let row = bin_row(box, r, bins);
        for (var j = cell_start[row.x]; j < cell_start[row.y]; j++) {
            let g = bin_geom_at(j);
            let d = g.position - s.center;
            if dot(d, d) > em.radius2 || abs(dot(d, s.normal)) > slab {
                continue;
            }
            let power = bin_power_at(j);
            let dir = oct_decode(g.direction);
            if dot(dir, s.normal) > 0.0
                && dot(surface_decode(power.w), s.normal) >= SURFACE_COS_MIN {
                rgb += power.xyz;
                count += 1u;
                weight += photon_weight(power.xyz);
            }
        }
    }
    var out: SplatLight;
    out.irradiance = rgb * em.inv_area;
    out.photons = count;
    out.log_likelihood = 0.0;
    out.weight = weight;
    out.lobes = 0u;
    out.first_lobe = 0u;
    light_put(splat_index, out);
}
