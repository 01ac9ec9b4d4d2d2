//! Mirror of `wgsl/grid_scatter.wgsl`. Sequential, so the scratch order is splat order; the
//! GPU's depends on scheduling until `grid_rank`.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use crate::grid::{cell_index, disk_cell_range};
use crate::types::{GridParams, Splat};
use glam::UVec3;

pub const WG: u32 = 64;

pub fn grid_scatter(
    grid: &GridParams,
    splats: &[Splat],
    cell_start: &[u32],
    cell_cursor: &mut [u32],
    scratch_splats: &mut [u32],
    scratch_cells: &mut [u32],
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let i = wg * WG + lid;
            if i >= grid.splat_count {
                continue;
            }
            let (lo, hi) = disk_cell_range(&splats[i as usize], grid);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let c = cell_index(UVec3::new(x, y, z), grid) as usize;
                        let slot = cell_start[c] + cell_cursor[c];
                        cell_cursor[c] += 1;
                        scratch_splats[slot as usize] = i;
                        scratch_cells[slot as usize] = c as u32;
                    }
                }
            }
        }
    }
}

/// The executor's entry: `grid_scatter`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let splats = b.get(1)?;
    let cell_start = b.get(2)?;
    let mut cursor = b.get_mut(3)?;
    let mut scratch_splats = b.get_mut(4)?;
    let mut scratch_cells = b.get_mut(5)?;
    grid_scatter(
        &p,
        view(&splats),
        &cell_start,
        &mut cursor,
        &mut scratch_splats,
        &mut scratch_cells,
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::GridScatter,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
