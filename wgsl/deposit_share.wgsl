// Deposits, pass 3 of 3 (docs/design.md section 6, "Deposits"): each splat's photon
// irradiance from its neighbours' deposits, in a time bounded by splats, not photons. A
// deposit counts where the photons' own tests would count its photons (on a surface facing
// the same way, its mean within the slab around the splat's plane), with the share of them
// inside the gather disk of radius R (disk_share: its photons spread as a uniform disk of
// radius rho about their mean) and the share that arrives at the splat's front (front_share:
// photons spread as cosine about the deposit's normal). In flat surroundings that is the
// photons' estimate with each photon's position smoothed over its deposit's disk.
// The deposits are deposit_list's records, binned (cells of deposit.reach, which bounds
// how far a deposit's photons lie from its mean, plus R). The sum is made once a coverage
// group (splats within R/16 of each other facing within 11 degrees: a dense scan's R holds
// thousands, whose sums differ by little), at its leader, in the leaders' order (a list of the
// splats with deposits near them saves nothing: the reach holds hundreds of splats, and the
// list's scheduling order cost a 3 M-splat terrain 0.8 s). Two entry points: main (one
// invocation a group) writes each leader's light; copy (one a splat) copies it to the members, and counters[3] counts the splats lit that are not fitted
// (fit_select lists and counts those). CPU mirror: src/cpu/deposit_share.rs.

// #import types
// #import dispatch
// #import bins
// #import octahedral
// #import deposits
// #import lobes

@group(0) @binding(0) var<uniform> em: EmParams;
@group(0) @binding(1) var<uniform> deposit: DepositParams;
@group(0) @binding(2) var<uniform> bins: BinParams;
// #paged
@group(0) @binding(3) var<storage, read> splats: array<Splat>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(6) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(7) var<storage, read> bin_keys: array<vec2<u32>>;
// #paged
@group(0) @binding(8) var<storage, read> bin_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(9) var<storage, read> bin_power: array<vec4<f32>>;
// #paged
@group(0) @binding(10) var<storage, read> spread: array<vec2<f32>>;
// #paged
@group(0) @binding(11) var<storage, read_write> light: array<SplatLight>;
// estimate_coverage's groups: each splat's group, then each group's leader.
// #paged
@group(0) @binding(12) var<storage, read> cover: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let invocation = linear_workgroup(wg, num_wg) * WG + lid;
    if invocation >= em.active_count {
        return;
    }
    let i = cover_at(em.splat_count + invocation);
    let s = splats_at(i);
    let slab = em.slab * s.radius;
    let reach2 = deposit.reach * deposit.reach;
    let box = bin_box(s.center, deposit.reach, bins);
    var rgb = vec3<f32>(0.0);
    var count = 0.0;
    var weight = 0.0;
    for (var r = 0u; r < bin_row_count(box); r++) {
        let row = bin_row(box, r, bins);
        for (var k = cell_start[row.x]; k < cell_start[row.y]; k++) {
            let d = bin_geom_at(k).position - s.center;
            let l2 = dot(d, d);
            if l2 > reach2 || abs(dot(d, s.normal)) > slab {
                continue;
            }
            let power = bin_power_at(k);
            if dot(surface_decode(power.w), s.normal) < SURFACE_COS_MIN {
                continue;
            }
            let j = bin_keys_at(k).x;
            let form = spread_at(j);
            let share = disk_share(sqrt(l2), em.radius, form.x)
                * front_share(s.normal, splats_at(j).normal);
            rgb += power.xyz * share;
            count += form.y * share;
            weight += photon_weight(power.xyz) * share;
        }
    }
    var out: SplatLight;
    out.irradiance = rgb * em.inv_area;
    out.photons = u32(ceil(count));
    out.log_likelihood = 0.0;
    out.weight = weight;
    out.lobes = 0u;
    out.first_lobe = 0u;
    light_put(i, out);
}

// The second pass, one invocation a splat: splat i's light, its group's leader's, and whether
// it counts as lit and not fitted (fit_select listed the fitted ones, counters[2]).
@compute @workgroup_size(64)
fn copy(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= em.splat_count {
        return;
    }
    let leader = cover_at(em.splat_count + cover_at(i));
    let l = light_at(leader);
    if leader != i {
        light_put(i, l);
    }
    let glossy = any(materials[splats_at(i).material].specular > vec3<f32>(0.0));
    if l.photons > 0u && !glossy && (em.flags & EM_FIT_ALL) == 0u {
        atomicAdd(&counters[3], 1u);
    }
}
