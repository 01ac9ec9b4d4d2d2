//! Mirror of `wgsl/splat_nodes.wgsl`: one level of the walk down the hierarchy of nodes over
//! the level of detail's chunks, each node's levels its subtree may visit (none where its
//! parent's visits none). `walk` runs every level from the top, as the device does.

use super::MirrorRow;
use crate::shaders::Stage;
use rayon::prelude::*;

use crate::lod::{LodTree, NODE_FANOUT};
use crate::shared::splat::chunk_visits;
use crate::types::{Camera, SplatChunk};

pub const WG: u32 = 64;

/// The visits of one level of `nodes`, under its parents' `parent_visits` (node j's parent is
/// j / `NODE_FANOUT`).
pub fn splat_nodes(cam: &Camera, nodes: &[SplatChunk], parent_visits: &[u32]) -> Vec<u32> {
    nodes
        .par_iter()
        .enumerate()
        .map(|(j, node)| {
            let up = parent_visits[j / NODE_FANOUT];
            match up {
                0 => 0,
                _ => chunk_visits(cam, node) & up,
            }
        })
        .collect()
}

/// Every level's visits (`LodTree::nodes`'s order: the level above the chunks first), walked
/// from the top under a parent that visits all.
pub fn walk(cam: &Camera, tree: &LodTree) -> Vec<Vec<u32>> {
    let mut visits: Vec<Vec<u32>> = vec![Vec::new(); tree.nodes.len()];
    let mut up = vec![u32::MAX];
    for (level, nodes) in tree.nodes.iter().enumerate().rev() {
        let found = splat_nodes(cam, nodes, &up);
        up.clone_from(&found);
        visits[level] = found;
    }
    visits
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatNodes,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
];
