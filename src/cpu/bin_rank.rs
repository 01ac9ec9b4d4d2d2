//! Mirror of `wgsl/bin_rank.wgsl`; workgroups run in parallel (each entry writes only its own
//! slot).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use rayon::prelude::*;

use crate::shared::bins::RANK_CHUNK;
use crate::types::BinParams;

pub const WG: u32 = 64;

fn key_less(a: [u32; 2], b: [u32; 2]) -> bool {
    a[0] < b[0] || (a[0] == b[0] && a[1] < b[1])
}

pub fn bin_rank(
    bins: &BinParams,
    cell_start: &[u32],
    scratch_keys: &[[u32; 2]],
    scratch_cells: &[u32],
    slots: &mut [u32],
    groups: u32,
) {
    slots
        .par_chunks_mut(WG as usize)
        .take(groups as usize)
        .enumerate()
        .for_each(|(wg, group)| {
            for (lid, slot) in group.iter_mut().enumerate() {
                let e = wg as u32 * WG + lid as u32;
                if e >= bins.photon_count {
                    continue;
                }
                let key = scratch_keys[e as usize];
                let c = scratch_cells[e as usize] as usize;
                let begin = cell_start[c] + bins.rank_chunk * RANK_CHUNK;
                let end = cell_start[c + 1].min(begin + RANK_CHUNK);
                let mut rank = 0;
                for k in begin..end {
                    rank += key_less(scratch_keys[k as usize], key) as u32;
                }
                if bins.rank_chunk == 0 {
                    *slot = cell_start[c] + rank;
                } else {
                    *slot += rank;
                }
            }
        });
}

/// The executor's entry: `bin_rank`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let cell_start = b.get(1)?;
    let keys = b.get(2)?;
    let cells = b.get(3)?;
    let mut slots = b.get_mut(4)?;
    bin_rank(&p, &cell_start, view(&keys), &cells, &mut slots, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::BinRank,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
