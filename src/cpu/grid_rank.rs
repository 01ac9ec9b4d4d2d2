//! Mirror of `wgsl/grid_rank.wgsl`: each entry's rank within its cell.

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
