//! Mirror of `wgsl/scan_apply.wgsl`: in-block exclusive scan plus the block's offset.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::Bindings;
use crate::error::Result;
use crate::types::ScanParams;

pub use super::scan_reduce::{BLOCK, ITEMS, WG};

pub fn scan_apply(params: &ScanParams, values: &mut [u32], block_offsets: &[u32], groups: u32) {
    let mut sums = [0u32; WG as usize];
    let mut local = [[0u32; ITEMS as usize]; WG as usize];
    for block in 0..groups {
        if block * BLOCK >= params.len {
            continue;
        }
        for lid in 0..WG {
            let base = (block * WG + lid) * ITEMS;
            let mut total = 0u32;
            for k in 0..ITEMS {
                local[lid as usize][k as usize] = total;
                if base + k < params.len {
                    total = total.wrapping_add(values[(base + k) as usize]);
                }
            }
            sums[lid as usize] = total;
        }
        // Hillis-Steele: every step reads the previous step's values (the GPU's barrier).
        let mut offset = 1;
        while offset < WG as usize {
            let prev = sums;
            for lid in offset..WG as usize {
                sums[lid] = prev[lid].wrapping_add(prev[lid - offset]);
            }
            offset <<= 1;
        }
        for lid in 0..WG {
            let base = (block * WG + lid) * ITEMS;
            let mut prefix = block_offsets[block as usize];
            if lid > 0 {
                prefix = prefix.wrapping_add(sums[lid as usize - 1]);
            }
            for k in 0..ITEMS {
                if base + k < params.len {
                    values[(base + k) as usize] =
                        prefix.wrapping_add(local[lid as usize][k as usize]);
                }
            }
        }
    }
}

/// The executor's entry: `scan_apply`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let mut values = b.get_mut(1)?;
    let offsets = b.get(2)?;
    scan_apply(&p, &mut values, &offsets, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::ScanApply,
        entry: "main",
        workgroup_size: Some(WG),
        items: ITEMS,
        run: Some(Mirror::Plain(dispatch)),
    },
];
