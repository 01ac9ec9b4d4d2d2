// Deposits, pass 2 of 3 (docs/design.md section 6, "Deposits"): each splat with a deposit
// lists it once, as a record of the photons' form that the binning takes: at the mean
// position of its photons, with their total power, the splat's normal for a direction and
// the splat's index for its key, so that the binned list comes out in splat order whatever
// order this pass writes in. Beside it, in `spread` at the splat's index: the radius of the
// uniform disk with its photons' spread about their mean (rho^2 = 2 E|x - mean|^2, at most
// deposit.spread_max) and their count. One invocation per splat of one range
// (deposit.first_splat on; see deposit_add), whose records go to the range's own list.
// CPU mirror: src/cpu/deposit_list.rs.

// #import types
// #import dispatch
// #import deposits

@group(0) @binding(0) var<uniform> deposit: DepositParams;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(2) var<storage, read> deposits: array<u32>;
// #paged
@group(0) @binding(3) var<storage, read_write> deposit_list: array<Photon>;
// #paged
@group(0) @binding(4) var<storage, read_write> spread: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> listed: array<atomic<u32>, 1>;

const WG: u32 = 64u;

fn wide(at: u32) -> f32 {
    return deposit_value(deposits[at], deposits[at + 1u]);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let local = linear_workgroup(wg, num_wg) * WG + lid;
    if local >= deposit.splat_count {
        return;
    }
    let j = deposit.first_splat + local;
    let base = local * DEPOSIT_WORDS;
    let count = deposits[base + DEPOSIT_COUNT];
    if count == 0u {
        return;
    }
    let s = splats_at(j);
    let per_photon = 1.0 / f32(count);
    var power = vec3<f32>(0.0);
    var mean = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        power[c] = wide(base + DEPOSIT_POWER + 2u * c) / deposit.power_scale;
        mean[c] = wide(base + DEPOSIT_OFFSET_SUM + 2u * c) / DEPOSIT_POSITION_UNITS * per_photon
            - DEPOSIT_OFFSET;
    }
    let square = wide(base + DEPOSIT_SQUARE_SUM) / DEPOSIT_POSITION_UNITS * per_photon;
    // A large splat's photons are taken to spread no wider than the reach (spread_max).
    let rho = min(s.radius * sqrt(2.0 * max(square - dot(mean, mean), 0.0)), deposit.spread_max);
    let slot = atomicAdd(&listed[0], 1u);
    deposit_list_put(slot, Photon(s.center + mean * s.radius, 0u, s.normal, j, power, j));
    spread_put(j, vec2<f32>(rho, f32(count)));
}
