// Deposits, pass 1 of 3 (docs/design.md section 6, "Deposits"): each stored photon of one
// store page adds itself to the deposit of the splat it landed on: its count, its RGB power
// in fixed point (deposit.power_scale units a unit of power), and its offset from the splat's
// centre and that offset's square, as 64-bit sums of u32 atomics. Integer sums do not depend
// on the order the photons arrive in, so the deposits are the same on every run. The
// deposit buffer holds the splats [first_splat, first_splat + splat_count): where the
// deposits outgrow one storage binding, each range has its own and its own dispatches.
// One invocation per photon. CPU mirror: src/cpu/deposit_add.rs.

// #import types
// #import dispatch
// #import deposits

@group(0) @binding(0) var<uniform> deposit: DepositParams;
@group(0) @binding(1) var<storage, read> photons: array<Photon>;
// #paged
@group(0) @binding(2) var<storage, read> splats: array<Splat>;
@group(0) @binding(3) var<storage, read_write> deposits: array<atomic<u32>>;

const WG: u32 = 64u;

// Adds v to the 64-bit sum at word `at`: the low word's carry goes to the high word.
fn add_wide(at: u32, v: u32) {
    let old = atomicAdd(&deposits[at], v);
    if old > 0xffffffffu - v {
        atomicAdd(&deposits[at + 1u], 1u);
    }
}

// x >= 0 in fixed point of `units`, rounded to nearest, at most u32's largest.
fn fixed(x: f32, units: f32) -> u32 {
    return u32(min(x * units + 0.5, 4294967040.0));
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= deposit.photon_count {
        return;
    }
    let p = photons[i];
    // Only the splats of this dispatch's deposit buffer (u32 wraps below first_splat).
    let local = p.splat - deposit.first_splat;
    if local >= deposit.splat_count {
        return;
    }
    let s = splats_at(p.splat);
    let o = clamp((p.position - s.center) / s.radius, vec3<f32>(-DEPOSIT_OFFSET),
                  vec3<f32>(DEPOSIT_OFFSET));
    let base = local * DEPOSIT_WORDS;
    atomicAdd(&deposits[base + DEPOSIT_COUNT], 1u);
    for (var c = 0u; c < 3u; c++) {
        add_wide(base + DEPOSIT_POWER + 2u * c, fixed(max(p.power[c], 0.0), deposit.power_scale));
        add_wide(base + DEPOSIT_OFFSET_SUM + 2u * c, fixed(o[c] + DEPOSIT_OFFSET,
                                                            DEPOSIT_POSITION_UNITS));
    }
    add_wide(base + DEPOSIT_SQUARE_SUM, fixed(dot(o, o), DEPOSIT_POSITION_UNITS));
}
