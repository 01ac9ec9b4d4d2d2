//! Mirror of `wgsl/splat_select.wgsl`: chunk by chunk of the level of detail's tree, under the
//! levels its node visits (`splat_nodes`), the radius each splat of the levels the chunk
//! visits is drawn with in a frame of baked direct light
//! (`drawn_radius`; 0: not drawn) and the word of its merged normals there, each chunk's count
//! of drawn splats and the levels it visited. `selection` adds `splat_list` for the list.

use super::MirrorRow;
use crate::shaders::Stage;
use rayon::prelude::*;

use crate::lod::{LodTree, NODE_FANOUT, visited};
use crate::shared::splat::{chunk_visits, drawn_radius, lod_level, lod_word};
use crate::types::{Camera, Splat};

pub const WG: u32 = 64;

/// What `splat_select` writes: per splat the drawn radius (0 where it is not drawn or its
/// chunk did not visit it), and per chunk its count of drawn splats and the levels it visited.
pub struct Selected {
    pub drawn: Vec<f32>,
    /// Per splat, the word of its merged normals at the level it is drawn at (`LodSpread`; 0
    /// at its own level, where not visited or where the tree holds none).
    pub normals: Vec<u32>,
    pub counts: Vec<u32>,
    pub visits: Vec<u32>,
}

/// A visited splat: its index, drawn radius and word of merged normals.
type Visited = (u32, f32, u32);

/// `parent_visits`: the levels each node of the level above the chunks visits
/// (`splat_nodes::walk`'s first).
pub fn splat_select(
    cam: &Camera,
    splats: &[Splat],
    tree: &LodTree,
    parent_visits: &[u32],
) -> Selected {
    let per_chunk: Vec<(u32, Vec<Visited>)> = tree
        .chunks
        .par_iter()
        .enumerate()
        .map(|(c, ch)| {
            // A chunk whose node visits nothing is not read.
            let visits = match parent_visits[c / NODE_FANOUT] {
                0 => 0,
                up => chunk_visits(cam, ch) & up,
            };
            let radii = visited(ch, visits)
                .map(|e| {
                    let i = tree.order[e as usize];
                    let (s, lod) = (&splats[i as usize], tree.lod(i));
                    let level = lod_level(cam, s, lod);
                    // Without merged normals the stand-in's words are 0 (the device, which
                    // cannot index the stand-in per splat, writes none; see WGSL).
                    let word = lod_word(tree.spread(i), level);
                    (i, drawn_radius(cam, s, lod, level), word)
                })
                .collect();
            (visits, radii)
        })
        .collect();
    let mut drawn = vec![0.0; splats.len()];
    let mut normals = vec![0; splats.len()];
    let mut counts = Vec::with_capacity(per_chunk.len());
    let mut visits = Vec::with_capacity(per_chunk.len());
    for (v, radii) in per_chunk {
        counts.push(radii.iter().filter(|(_, r, _)| *r > 0.0).count() as u32);
        visits.push(v);
        for (i, r, word) in radii {
            drawn[i as usize] = r;
            normals[i as usize] = word;
        }
    }
    Selected {
        drawn,
        normals,
        counts,
        visits,
    }
}

/// What a frame of baked direct light draws: the splats chunk by chunk (`splat_list`), and
/// each splat's drawn radius.
pub struct Selection {
    pub selected: Vec<u32>,
    pub drawn: Vec<f32>,
    /// `Selected::normals`.
    pub normals: Vec<u32>,
}

/// The walk down the chunks' nodes (`splat_nodes`), `splat_select`, the scan of its counts
/// and `splat_list`, as the device runs them.
pub fn selection(cam: &Camera, splats: &[Splat], tree: &LodTree) -> Selection {
    let nodes = super::splat_nodes::walk(cam, tree);
    let chosen = splat_select(cam, splats, tree, &nodes[0]);
    let offsets: Vec<u32> = chosen
        .counts
        .iter()
        .scan(0, |sum, &c| {
            let first = *sum;
            *sum += c;
            Some(first)
        })
        .collect();
    let selected = super::splat_list::splat_list(&offsets, &chosen.drawn, tree, &chosen.visits);
    Selection {
        selected,
        drawn: chosen.drawn,
        normals: chosen.normals,
    }
}

/// The splats as the raster passes draw them with the level of detail: each at the radius
/// `splat_select` chose, 0 for those it left out (`splat_bounds` gives them no pixels).
pub fn drawn_splats(splats: &[Splat], drawn: &[f32]) -> Vec<Splat> {
    splats
        .iter()
        .zip(drawn)
        .map(|(s, &radius)| Splat { radius, ..*s })
        .collect()
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatSelect,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
];
