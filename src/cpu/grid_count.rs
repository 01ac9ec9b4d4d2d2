//! Mirror of `wgsl/grid_count.wgsl`.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use crate::grid::{cell_index, disk_cell_range};
use crate::types::{GridParams, Splat};
use glam::UVec3;

pub const WG: u32 = 64;

pub fn grid_count(
    grid: &GridParams,
    splats: &[Splat],
    cell_counts: &mut [u32],
    max_cell_len: &mut u32,
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
                        let before = cell_counts[c];
                        cell_counts[c] += 1;
                        *max_cell_len = (*max_cell_len).max(before + 1);
                    }
                }
            }
        }
    }
}

/// The executor's entry: `grid_count`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let splats = b.get(1)?;
    let mut counts = b.get_mut(2)?;
    let mut max_len = b.get_mut(3)?;
    grid_count(&p, view(&splats), &mut counts, &mut max_len[0], groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::GridCount,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
