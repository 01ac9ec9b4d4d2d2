//! Mirror of `wgsl/bin_count.wgsl`.

use crate::shared::bins::{RANK_CHUNK, bin_of};
use crate::types::{BinParams, Photon};
use glam::Vec3;

pub const WG: u32 = 64;

pub fn bin_count(
    bins: &BinParams,
    photons: &[Photon],
    cell_count: &mut [u32],
    chunks: &mut u32,
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let i = wg * WG + lid;
            if i >= bins.photon_count {
                continue;
            }
            let c = bin_of(Vec3::from(photons[i as usize].position), bins) as usize;
            let before = cell_count[c];
            cell_count[c] += 1;
            if before.is_multiple_of(RANK_CHUNK) {
                *chunks = (*chunks).max(before / RANK_CHUNK + 1);
            }
        }
    }
}
