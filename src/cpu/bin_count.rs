//! Mirror of `wgsl/bin_count.wgsl`.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
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

/// The executor's entry: `bin_count`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let photons = b.get(1)?;
    let mut cell_start = b.get_mut(2)?;
    let mut chunks = b.get_mut(3)?;
    let photons = view(&photons);
    bin_count(&p, photons, &mut cell_start, &mut chunks[0], groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::BinCount,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
