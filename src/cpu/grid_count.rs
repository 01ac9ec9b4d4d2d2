//! Mirror of `wgsl/grid_count.wgsl`.

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
