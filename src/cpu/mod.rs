//! CPU mirrors of the WGSL stages: one file per `wgsl/<stage>.wgsl`, with the same name, the
//! same bindings as arguments in binding order, and the same loop shape (workgroups, then
//! local invocations), so that a difference between the two points at one line.
//! They are the reference for the parity tests and a fallback when no GPU is wanted.

pub mod grid_count;
pub mod grid_rank;
pub mod grid_scatter;
pub mod scan_apply;
pub mod scan_reduce;

use crate::error::Result;
use crate::grid::{SplatGrid, check_cell_len};
use crate::types::{GridParams, ScanParams, Splat};

/// Number of workgroups that cover `n` items with `wg` invocations each.
pub fn groups_for(n: u32, wg: u32) -> u32 {
    n.div_ceil(wg)
}

/// Exclusive scan of `values` in place, level by level exactly as `gpu::scan` records it:
/// reduce blocks, scan the block sums recursively, apply.
pub fn exclusive_scan(values: &mut [u32]) {
    let len = values.len() as u32;
    let params = ScanParams {
        len,
        ..Default::default()
    };
    let blocks = groups_for(len, scan_reduce::BLOCK);
    if blocks <= 1 {
        scan_apply::scan_apply(&params, values, &[0], blocks);
        return;
    }
    let mut block_sums = vec![0u32; blocks as usize];
    scan_reduce::scan_reduce(&params, values, &mut block_sums, blocks);
    exclusive_scan(&mut block_sums);
    scan_apply::scan_apply(&params, values, &block_sums, blocks);
}

/// The whole grid build on the CPU: count → exclusive scan → scatter → rank.
pub fn build_grid(params: &GridParams, splats: &[Splat]) -> Result<SplatGrid> {
    let splat_groups = groups_for(params.splat_count, grid_count::WG);
    let mut cell_start = vec![0u32; params.cell_count as usize + 1];
    let mut max_cell_len = 0;
    grid_count::grid_count(
        params,
        splats,
        &mut cell_start,
        &mut max_cell_len,
        splat_groups,
    );
    check_cell_len(max_cell_len)?;
    exclusive_scan(&mut cell_start);
    let params = GridParams {
        entry_count: cell_start[params.cell_count as usize],
        ..*params
    };
    let entries = params.entry_count as usize;
    let mut cursor = vec![0u32; params.cell_count as usize];
    let (mut scratch_splats, mut scratch_cells) = (vec![0u32; entries], vec![0u32; entries]);
    grid_scatter::grid_scatter(
        &params,
        splats,
        &cell_start,
        &mut cursor,
        &mut scratch_splats,
        &mut scratch_cells,
        splat_groups,
    );
    let mut cell_splats = vec![0u32; entries];
    let entry_groups = groups_for(params.entry_count, grid_rank::WG);
    grid_rank::grid_rank(
        &params,
        &cell_start,
        &scratch_splats,
        &scratch_cells,
        &mut cell_splats,
        entry_groups,
    );
    Ok(SplatGrid {
        params,
        cell_start,
        cell_splats,
    })
}
