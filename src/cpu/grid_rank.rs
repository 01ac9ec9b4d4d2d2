//! Mirror of `wgsl/grid_rank.wgsl`: each entry's rank within its cell.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::Bindings;
use crate::error::Result;
use crate::types::GridParams;

pub const WG: u32 = 64;

pub fn grid_rank(
    grid: &GridParams,
    cell_start: &[u32],
    scratch_splats: &[u32],
    scratch_cells: &[u32],
    cell_splats: &mut [u32],
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let e = wg * WG + lid;
            if e >= grid.entry_count {
                continue;
            }
            let i = scratch_splats[e as usize];
            let c = scratch_cells[e as usize] as usize;
            let (begin, end) = (cell_start[c] as usize, cell_start[c + 1] as usize);
            let rank = scratch_splats[begin..end]
                .iter()
                .filter(|&&s| s < i)
                .count();
            cell_splats[begin + rank] = i;
        }
    }
}

/// The executor's entry: `grid_rank`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let cell_start = b.get(1)?;
    let scratch_splats = b.get(2)?;
    let scratch_cells = b.get(3)?;
    let mut cell_splats = b.get_mut(4)?;
    grid_rank(
        &p,
        &cell_start,
        &scratch_splats,
        &scratch_cells,
        &mut cell_splats,
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::GridRank,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
