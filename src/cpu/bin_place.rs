//! Mirror of `wgsl/bin_place.wgsl`.

use crate::types::{BinParams, BinnedPhoton};

pub const WG: u32 = 64;

#[allow(clippy::too_many_arguments)]
pub fn bin_place(
    bins: &BinParams,
    slots: &[u32],
    scratch_keys: &[[u32; 2]],
    scratch_geom: &[BinnedPhoton],
    scratch_power: &[[f32; 4]],
    bin_keys: &mut [[u32; 2]],
    bin_geom: &mut [BinnedPhoton],
    bin_power: &mut [[f32; 4]],
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let e = wg * WG + lid;
            if e >= bins.photon_count {
                continue;
            }
            let (e, slot) = (e as usize, slots[e as usize] as usize);
            bin_keys[slot] = scratch_keys[e];
            bin_geom[slot] = scratch_geom[e];
            bin_power[slot] = scratch_power[e];
        }
    }
}
