//! Mirror of `wgsl/bin_scatter.wgsl`. Sequential, so each cell's scratch list is in input
//! order; the GPU's depends on scheduling until `bin_rank` and `bin_place`.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use crate::shared::bins::bin_of;
use crate::shared::octahedral::{oct_encode, surface_encode};
use crate::types::{BinParams, BinnedPhoton, Photon, Splat};
use glam::Vec3;

pub const WG: u32 = 64;

#[allow(clippy::too_many_arguments)]
pub fn bin_scatter(
    bins: &BinParams,
    photons: &[Photon],
    cell_start: &[u32],
    cell_cursor: &mut [u32],
    scratch_keys: &mut [[u32; 2]],
    scratch_cells: &mut [u32],
    scratch_geom: &mut [BinnedPhoton],
    scratch_power: &mut [[f32; 4]],
    splats: &[Splat],
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let i = wg * WG + lid;
            if i >= bins.photon_count {
                continue;
            }
            let p = &photons[i as usize];
            let c = bin_of(Vec3::from(p.position), bins) as usize;
            let slot = (cell_start[c] + cell_cursor[c]) as usize;
            cell_cursor[c] += 1;
            scratch_keys[slot] = [p.path, p.bounce];
            scratch_cells[slot] = c as u32;
            scratch_geom[slot] = BinnedPhoton {
                position: p.position,
                direction: oct_encode(Vec3::from(p.direction)),
            };
            let n = splats
                .get(p.splat as usize)
                .map_or(Vec3::Z, |s| Vec3::from(s.normal));
            scratch_power[slot] = [p.power[0], p.power[1], p.power[2], surface_encode(n)];
        }
    }
}

/// The executor's entry: `bin_scatter`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let photons = b.get(1)?;
    let cell_start = b.get(2)?;
    let mut cursor = b.get_mut(3)?;
    let mut keys = b.get_mut(4)?;
    let mut cells = b.get_mut(5)?;
    let mut geom = b.get_mut(6)?;
    let mut power = b.get_mut(7)?;
    let splats = b.get(8)?;
    bin_scatter(
        &p,
        view(&photons),
        &cell_start,
        &mut cursor,
        view_mut(&mut keys),
        &mut cells,
        view_mut(&mut geom),
        view_mut(&mut power),
        view(&splats),
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::BinScatter,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
