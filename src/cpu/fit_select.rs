//! Mirror of `wgsl/fit_select.wgsl`. Sequential, so the list and the lobe slots are in splat
//! order.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;

use crate::shared::bins::{bin_box, bin_row, bin_row_count};
use crate::shared::lobes::{EM_FIT_ALL, EM_GROUPS, EM_SHARE, FOLLOWER_BIT, GATHER_MAX};
use crate::types::{BinParams, EmParams, Material, Splat};

pub const WG: u32 = 64;
/// The fit-list entry's flag: fit this splat's lobes (see `wgsl/fit_select.wgsl`).
pub const FIT_BIT: u32 = 0x8000_0000;

#[allow(clippy::too_many_arguments)]
pub fn fit_select(
    em: &EmParams,
    bins: &BinParams,
    splats: &[Splat],
    materials: &[Material],
    cell_start: &[u32],
    active: &mut [[u32; 2]],
    counters: &mut [u32; 4],
    gather_list: &mut [u32],
    fit_groups: &[u32],
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let i = wg * WG + lid;
            if i >= em.splat_count {
                continue;
            }
            let s = &splats[i as usize];
            let glossy = materials[s.material as usize]
                .specular
                .iter()
                .any(|&x| x > 0.0);
            // A splat another's fit serves (EM_GROUPS) is lit as a diffuse splat is, not
            // fitted.
            let served = em.flags & EM_GROUPS != 0 && fit_groups[i as usize] & FOLLOWER_BIT != 0;
            let fit = (glossy || em.flags & EM_FIT_ALL != 0) && !served;
            if em.flags & EM_SHARE != 0 && !fit {
                continue;
            }
            let bx = bin_box(Vec3::from(s.center), em.radius, bins);
            let mut candidates = 0;
            for r in 0..bin_row_count(&bx) {
                let row = bin_row(&bx, r, bins);
                candidates += cell_start[row.y as usize] - cell_start[row.x as usize];
            }
            if candidates == 0 {
                continue;
            }
            if !fit && candidates <= GATHER_MAX {
                gather_list[counters[3] as usize] = i;
                counters[3] += 1;
                continue;
            }
            let mut lobe_slot = 0;
            if fit {
                lobe_slot = counters[2];
                counters[2] += 1;
            }
            let slot = counters[0] as usize;
            counters[0] += 1;
            active[slot] = [i | if fit { FIT_BIT } else { 0 }, lobe_slot];
            counters[1] = counters[1].max(candidates);
        }
    }
}

/// The executor's entry: `fit_select`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let bins = b.param(1)?;
    let splats = b.get(2)?;
    let materials = b.get(3)?;
    let cell_start = b.get(4)?;
    let mut active = b.get_mut(5)?;
    let mut counters = b.get_mut(6)?;
    let mut gather_list = b.get_mut(7)?;
    let fit_groups = b.get(8)?;
    let counters = b.counters::<4>(&mut counters)?;
    let (splats, materials) = (view(&splats), view(&materials));
    fit_select(
        &em,
        &bins,
        splats,
        materials,
        &cell_start,
        view_mut(&mut active),
        counters,
        &mut gather_list,
        &fit_groups,
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::FitSelect,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
