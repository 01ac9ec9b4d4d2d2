//! Mirror of `wgsl/splat_list.wgsl`: the drawn splats (drawn radius above 0) chunk by chunk,
//! each chunk's from its offset in the scanned counts, in the order of its visited entries.

use super::MirrorRow;
use crate::shaders::Stage;
use crate::lod::{LodTree, visited};

pub const WG: u32 = 64;

pub fn splat_list(offsets: &[u32], drawn: &[f32], tree: &LodTree, visits: &[u32]) -> Vec<u32> {
    let mut selected = Vec::new();
    for ((ch, &v), &offset) in tree.chunks.iter().zip(visits).zip(offsets) {
        debug_assert_eq!(offset as usize, selected.len());
        let listed = visited(ch, v)
            .map(|e| tree.order[e as usize])
            .filter(|&i| drawn[i as usize] > 0.0);
        selected.extend(listed);
    }
    selected
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatList,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
];
