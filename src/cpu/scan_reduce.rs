//! Mirror of `wgsl/scan_reduce.wgsl`: per-block sums with the same tree order.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::Bindings;
use crate::error::Result;
use crate::types::ScanParams;

pub const WG: u32 = 256;
pub const ITEMS: u32 = 4;
pub const BLOCK: u32 = WG * ITEMS;

pub fn scan_reduce(params: &ScanParams, values: &[u32], block_sums: &mut [u32], groups: u32) {
    let mut partial = [0u32; WG as usize];
    for block in 0..groups {
        if block * BLOCK >= params.len {
            continue;
        }
        for lid in 0..WG {
            let base = (block * WG + lid) * ITEMS;
            let mut sum = 0u32;
            for k in 0..ITEMS {
                if base + k < params.len {
                    sum = sum.wrapping_add(values[(base + k) as usize]);
                }
            }
            partial[lid as usize] = sum;
        }
        let mut stride = WG / 2;
        while stride > 0 {
            for lid in 0..stride as usize {
                partial[lid] = partial[lid].wrapping_add(partial[lid + stride as usize]);
            }
            stride >>= 1;
        }
        block_sums[block as usize] = partial[0];
    }
}

/// The executor's entry: `scan_reduce`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let values = b.get(1)?;
    let mut sums = b.get_mut(2)?;
    scan_reduce(&p, &values, &mut sums, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::ScanReduce,
        entry: "main",
        workgroup_size: Some(WG),
        items: ITEMS,
        run: Some(Mirror::Plain(dispatch)),
    },
];
