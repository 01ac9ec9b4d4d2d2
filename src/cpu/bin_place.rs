//! Mirror of `wgsl/bin_place.wgsl`.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
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

/// The executor's entry: `bin_place`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let slots = b.get(1)?;
    let keys = b.get(2)?;
    let geom = b.get(3)?;
    let power = b.get(4)?;
    let mut out_keys = b.get_mut(5)?;
    let mut out_geom = b.get_mut(6)?;
    let mut out_power = b.get_mut(7)?;
    bin_place(
        &p,
        &slots,
        view(&keys),
        view(&geom),
        view(&power),
        view_mut(&mut out_keys),
        view_mut(&mut out_geom),
        view_mut(&mut out_power),
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::BinPlace,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
