//! The level of detail's merge tree (docs/design.md §8), built once per scene on the host.
//!
//! Level 0 is every splat. Level L keeps a subset of level L − 1's splats, spread evenly (a
//! greedy packing in a fixed random order), and merges each splat it drops into the nearest
//! kept one; a kept splat's disk at level L grows until it covers every splat merged into it,
//! at every level below. `shared::splat::lod_radius` then draws each splat at the coarsest of
//! its levels that projects within the frame's level of detail, or not at all where its
//! parent's disk may do so. Each splat's chain of ancestors is then cut once at least, so the
//! merged surface has no hole from any view (the random thinning this replaced left about 1 %
//! of the dragon's pixels open).

use std::num::NonZeroUsize;

use glam::{Vec3, Vec4};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use crate::shared::octahedral::oct_encode;
use crate::shared::rng::pcg_hash;
use crate::shared::splat::{LOD_MAX_LEVEL, LOD_SPREAD_SCALE};
use crate::types::{LOD_LEVELS, LodSpread, Splat, SplatChunk, SplatLod};

/// Splats merge only where their normals lie within about 37° of each other: a disk stands in
/// for its neighbours only along their surface. Across a thin part or a sharp edge it would
/// face away from a view that sees the other side.
const MERGE_COS_MIN: f32 = 0.8;
/// A level's merge reach around a splat is `MERGE_FACTOR` times the distance to its `MERGE_K`-th
/// nearest splat of the level below. A random sequential packing at distance ρ keeps about
/// 0.7 / ρ² splats per unit area, and the k-th neighbour of n splats per unit area lies at
/// √(k / πn), so 0.86 times the 6th neighbour's distance keeps about half of them.
const MERGE_K: usize = 6;
const MERGE_FACTOR: f32 = 0.86;
/// The packing's order: a hash of the splat index, so that the kept splats do not follow the
/// order in which a file listed its points.
const PRIORITY_SALT: u32 = 0x2545_f491;

/// The merge tree of `splats` (see the module's doc), one record per splat in their order; and
/// with `normals`, at each level the normals each disk stands for (their mean direction and
/// spread), one of each per splat, else a single stand-in of zeros: only glossy disks are
/// shaded by them, and a diffuse scan would carry 20 bytes a splat for nothing.
pub fn merge_tree(splats: &[Splat], normals: bool) -> (Vec<SplatLod>, Vec<LodSpread>) {
    let n = splats.len();
    let centre = |i: u32| Vec3::from(splats[i as usize].center);
    // extent[i][L]: splat i's disk at level L, for L up to top[i].
    let mut extent: Vec<[f32; LOD_LEVELS]> =
        splats.iter().map(|s| [s.radius; LOD_LEVELS]).collect();
    let mut top = vec![0u32; n];
    let mut parent = vec![NONE; n];
    // Filled level by level.
    let mut spread: Vec<LodSpread> = vec![[0; LOD_MAX_LEVEL as usize]; if normals { n } else { 1 }];
    // Each splat's ancestor at the level last built.
    let mut ancestor: Vec<u32> = (0..n as u32).collect();
    // The splats of the level last built, in priority order.
    let mut members: Vec<u32> = (0..n as u32).collect();
    members.sort_by_key(|&i| (pcg_hash(i ^ PRIORITY_SALT), i));
    let mut position = vec![NONE; n];
    for level in 1..=LOD_MAX_LEVEL {
        let Some(into) = merge(splats, &members) else {
            break;
        };
        for (m, &i) in members.iter().enumerate() {
            position[i as usize] = m as u32;
        }
        let rep = |i: u32| members[into[position[i as usize] as usize] as usize];
        for (m, &i) in members.iter().enumerate() {
            let r = members[into[m] as usize];
            if r == i {
                top[i as usize] = level;
                extent[i as usize][level as usize] = 0.0;
            } else {
                parent[i as usize] = r;
            }
        }
        // A kept disk's reach at this level: every splat whose ancestor merged into it; and
        // their normals' sum weighted by their areas (by the kept splat's position).
        let mut sums = vec![Vec4::ZERO; if normals { members.len() } else { 0 }];
        for j in 0..n {
            let r = rep(ancestor[j]);
            ancestor[j] = r;
            let s = &splats[j];
            let reach = (Vec3::from(s.center) - centre(r)).length() + s.radius;
            let e = &mut extent[r as usize][level as usize];
            *e = e.max(reach);
            if let Some(sum) = sums.get_mut(position[r as usize] as usize) {
                let area = s.radius * s.radius;
                *sum += (Vec3::from(s.normal) * area).extend(area);
            }
        }
        for (&i, sum) in members.iter().zip(&sums) {
            if top[i as usize] == level {
                spread[i as usize][level as usize - 1] = spread_word(sum.truncate(), sum.w);
            }
        }
        members.retain(|&i| top[i as usize] == level);
    }
    let lods = (0..n)
        .map(|i| {
            let t = top[i] as usize;
            let mut lod = SplatLod {
                extent: [1, 2, 3, 4, 5].map(|k| extent[i][k.min(t)]),
                top: t as u32,
                ..SplatLod::default()
            };
            if let Some(&p) = parent.get(i).filter(|&&p| p != NONE) {
                lod.parent_extent = extent[p as usize][t + 1];
                lod.parent_gap = (Vec3::from(splats[i].center) - centre(p)).length();
            }
            lod
        })
        .collect();
    (lods, spread)
}

/// The Ward roughness that stands for the spread of the normals a merged disk replaces, whose
/// area-weighted mean has length `mean_length` (1 where they agree): shaded with one normal, the
/// disk's highlight is as sharp as a single splat's where its surface's would be blurred by
/// the normals' spread (a mottle of bright and dark disks on a curved glossy model). For a small
/// spread, 1 − |n̄| ≈ ⟨θ²⟩ / 2 is the variance of the slopes along each axis (Toksvig's
/// filtering of normal maps), and a Ward lobe's α² is twice its slopes' variance along an
/// axis, so the disk's lobe is widened to α² + 2 (1 − |n̄|) / |n̄| (`lod_roughness`).
pub fn normal_spread(mean_length: f32) -> f32 {
    let m = mean_length.clamp(1e-3, 1.0);
    (2.0 * (1.0 - m) / m).sqrt()
}

/// A level's word of `LodSpread` for normals whose area-weighted sum is `sum` over the area
/// `area`: the spread's byte, and above it the sum's direction in 24 bits.
fn spread_word(sum: Vec3, area: f32) -> u32 {
    let byte = (normal_spread(sum.length() / area) * LOD_SPREAD_SCALE)
        .round()
        .min(255.0) as u32;
    let code = oct_encode(sum.normalize_or(Vec3::Z));
    let (x, y) = ((code & 0xffff) >> 4, code >> 20);
    byte | (x << 8) | (y << 20)
}

/// Splats a chunk holds: a frame's selection visits the chunks, and within a chunk it visits,
/// the levels its bounds cannot rule out (`shared::splat::chunk_visits`). 256 keeps the
/// chunks' records under 0.5 byte a splat, and one invocation's walk of a chunk short.
pub const CHUNK: usize = 256;

/// Children a node of the chunks' hierarchy holds (`LodTree::nodes`): a node stands for 16
/// consecutive records of the level below, so that its children are found by position.
pub const NODE_FANOUT: usize = 16;

/// What a frame's selection walks: the merge tree, the splats in chunks near one another, and
/// a hierarchy of nodes over the chunks that a frame walks from the top.
pub struct LodTree {
    /// Whether it holds the merge tree (`build`) or the chunks alone (`flat`).
    pub merged: bool,
    /// Per splat, its place in the merge tree (in the splats' order); without one, a single
    /// stand-in record (level 0, no parent) for every splat, as the device binds it.
    pub lods: Vec<SplatLod>,
    /// Whether it holds the merged normals (`merge_tree`); without them, a stand-in.
    pub normals: bool,
    /// Per splat, its merged normals at each level: their mean and spread; without them, a
    /// single stand-in of zeros, as the device binds it.
    pub spreads: Vec<LodSpread>,
    /// The splats chunk by chunk, each chunk's sorted by top level.
    pub order: Vec<u32>,
    pub chunks: Vec<SplatChunk>,
    /// The hierarchy over the chunks, from the level just above them to the top, which holds
    /// one node: node j of a level stands for records `NODE_FANOUT·j ..` of the level below
    /// (`first`: the first of them), and bounds them all as a chunk bounds its splats
    /// (`node_of`), so that `chunk_visits` of a node rules out a level for its whole subtree.
    pub nodes: Vec<Vec<SplatChunk>>,
}

impl LodTree {
    /// The merge tree of `splats`, with its merged normals or not (`merge_tree`), and their
    /// chunks along a Morton curve of their centres.
    pub fn build(splats: &[Splat], normals: bool) -> LodTree {
        let (lods, spreads) = merge_tree(splats, normals);
        let mut order = morton_order(splats);
        for run in order.chunks_mut(CHUNK) {
            run.sort_by_key(|&i| lods[i as usize].top);
        }
        LodTree::chunked(splats, true, normals, (lods, spreads), order)
    }

    /// Without a merge tree (the level of detail off): the chunks alone, each splat at level
    /// 0 with no parent, so that chunks are culled by the view alone.
    pub fn flat(splats: &[Splat]) -> LodTree {
        LodTree::chunked(
            splats,
            false,
            false,
            (vec![SplatLod::default()], vec![[0; LOD_MAX_LEVEL as usize]]),
            morton_order(splats),
        )
    }

    /// Splat `i`'s place in the merge tree (the stand-in without one).
    pub fn lod(&self, i: u32) -> &SplatLod {
        &self.lods[if self.merged { i as usize } else { 0 }]
    }

    /// Splat `i`'s merged normals (the stand-in's without them).
    pub fn spread(&self, i: u32) -> &LodSpread {
        &self.spreads[if self.normals { i as usize } else { 0 }]
    }

    fn chunked(
        splats: &[Splat],
        merged: bool,
        normals: bool,
        (lods, spreads): (Vec<SplatLod>, Vec<LodSpread>),
        order: Vec<u32>,
    ) -> LodTree {
        let mut tree = LodTree {
            merged,
            normals,
            lods,
            spreads,
            order,
            chunks: Vec::new(),
            nodes: Vec::new(),
        };
        tree.chunks = chunks(splats, &tree);
        tree.nodes = nodes(&tree.chunks);
        tree
    }
}

/// The levels of nodes over `chunks` (`LodTree::nodes`), up to a level of one node.
fn nodes(chunks: &[SplatChunk]) -> Vec<Vec<SplatChunk>> {
    let mut levels: Vec<Vec<SplatChunk>> = Vec::new();
    loop {
        let below = levels.last().map_or(chunks, |l| l.as_slice());
        let level: Vec<SplatChunk> = below
            .chunks(NODE_FANOUT)
            .enumerate()
            .map(|(k, run)| node_of(run, (k * NODE_FANOUT) as u32))
            .collect();
        let top = level.len() <= 1;
        levels.push(level);
        if top {
            return levels;
        }
    }
}

/// A node over `children` (records of the level below, the first at position `first`): a
/// sphere holding theirs, and per level the counts of splats below it (`ends`, as a chunk's)
/// and the largest of the children's disks, parents' disks and gaps among those that hold
/// splats of that level (a root among them keeps the level visited). A level `chunk_visits`
/// keeps for a child it keeps for the node: the sphere holds the child's, its bounds are the
/// children's largest, and its nearest depth is theirs or nearer.
fn node_of(children: &[SplatChunk], first: u32) -> SplatChunk {
    let (lo, hi) = children.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), ch| {
            let (c, r) = (Vec3::from(ch.center), Vec3::splat(ch.centre_reach));
            (lo.min(c - r), hi.max(c + r))
        },
    );
    let center = (lo + hi) * 0.5;
    let mut node = SplatChunk {
        center: center.to_array(),
        first,
        ..SplatChunk::default()
    };
    let mut below = [0u32; LOD_LEVELS];
    for ch in children {
        let reach = (Vec3::from(ch.center) - center).length() + ch.centre_reach;
        // A little wider than the arithmetic says, so that rounding (of the reach, and of the
        // centre's coordinates, some ulps of their size) never leaves a child's sphere outside.
        let slack = 1e-5 * reach + 1e-6 * center.abs().max_element();
        node.centre_reach = node.centre_reach.max(reach + slack);
        for (t, sum) in below.iter_mut().enumerate() {
            let held = ch.level(t).len() as u32;
            if held == 0 {
                continue;
            }
            *sum += held;
            node.level_fit[t] = node.level_fit[t].max(ch.level_fit[t]);
            node.parent_gap[t] = node.parent_gap[t].max(ch.parent_gap[t]);
            node.parent_fit[t] = match ch.parent_fit[t] > 0.0 && node.parent_fit[t] >= 0.0 {
                true => node.parent_fit[t].max(ch.parent_fit[t]),
                false => -1.0,
            };
        }
    }
    let mut sum = 0;
    for (end, held) in node.ends.iter_mut().zip(below) {
        sum += held;
        *end = sum;
    }
    node
}

/// The entries of `ch` (positions in the tree's order) that a frame visits, level by level
/// (`visits`: bit t for its splats whose top level is t, as `shared::splat::chunk_visits` says).
pub fn visited(ch: &SplatChunk, visits: u32) -> impl Iterator<Item = u32> + '_ {
    (0..LOD_LEVELS).flat_map(move |t| {
        let entries = match visits >> t & 1 {
            0 => 0..0,
            _ => ch.level(t),
        };
        entries.map(move |e| ch.first + e)
    })
}

/// The splats' indices along a Morton curve of their centres in the bounds' cube (21 bits an
/// axis; the index breaks ties), so that each run of `CHUNK`, and each node's runs, lie close
/// together: in a cube, not in a box of the bounds' shape, whose cells a long scan (a street,
/// a corridor) would stretch along its length.
fn morton_order(splats: &[Splat]) -> Vec<u32> {
    let (lo, hi) = splats.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), s| (lo.min(s.center.into()), hi.max(s.center.into())),
    );
    let scale = ((1u32 << 21) - 1) as f32 / (hi - lo).max_element().max(1e-30);
    let spread = |v: u32| {
        // The 21 bits of v, two zero bits between each.
        let mut x = v as u64 & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    let mut keyed: Vec<(u64, u32)> = splats
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            let q = ((Vec3::from(s.center) - lo) * scale).max(Vec3::ZERO);
            let key = spread(q.x as u32) | spread(q.y as u32) << 1 | spread(q.z as u32) << 2;
            (key, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Each run of `CHUNK` entries of `order` (sorted by top level within) as a chunk.
fn chunks(splats: &[Splat], tree: &LodTree) -> Vec<SplatChunk> {
    tree.order
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(k, run)| {
            let at = |i: u32| (&splats[i as usize], tree.lod(i));
            let (lo, hi) = run.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &i| (lo.min(at(i).0.center.into()), hi.max(at(i).0.center.into())),
            );
            let center = (lo + hi) * 0.5;
            let mut ch = SplatChunk {
                center: center.to_array(),
                first: (k * CHUNK) as u32,
                ..SplatChunk::default()
            };
            for (e, &i) in run.iter().enumerate() {
                let (s, lod) = at(i);
                let t = lod.top as usize;
                let reach = (Vec3::from(s.center) - center).length();
                ch.centre_reach = ch.centre_reach.max(reach);
                for end in &mut ch.ends[t..] {
                    *end = (e + 1) as u32;
                }
                let own = if t == 0 { s.radius } else { lod.extent[t - 1] };
                ch.level_fit[t] = ch.level_fit[t].max(own);
                ch.parent_gap[t] = ch.parent_gap[t].max(lod.parent_gap);
                // A root among them (no parent) keeps the level visited: -1 from then on.
                ch.parent_fit[t] = match lod.parent_extent > 0.0 && ch.parent_fit[t] >= 0.0 {
                    true => ch.parent_fit[t].max(lod.parent_extent),
                    false => -1.0,
                };
            }
            ch
        })
        .collect()
}

/// A splat's neighbours in the packing (positions among the level's splats), `NONE` after the
/// last.
type Near = [u32; MERGE_K];
const NONE: u32 = u32::MAX;

/// One level of the tree: for each of `members` (in priority order), the position among them
/// of the kept splat it merges into (its own where kept); None where too few are left.
fn merge(splats: &[Splat], members: &[u32]) -> Option<Vec<u32>> {
    if members.len() <= MERGE_K {
        return None;
    }
    let points: Vec<[f32; 3]> = members.iter().map(|&i| splats[i as usize].center).collect();
    let normal = |m: usize| Vec3::from(splats[members[m] as usize].normal);
    let mergeable = |a: usize, b: usize| normal(a).dot(normal(b)) >= MERGE_COS_MIN;
    let tree = ImmutableKdTree::<f32, 3>::new_from_slice(&points).ok()?;
    let k = NonZeroUsize::new(MERGE_K + 1)?;
    // Each splat's neighbours within its reach that may stand in for it, nearest first (the
    // lower position where two are as near), `NONE` after the last; a fixed array, so that ten
    // million splats take 240 MB here, not twice that and an allocation each. The reach lies
    // inside the k-th neighbour's distance, so the k nearest hold them all.
    let near: Vec<Near> = (0..members.len())
        .into_par_iter()
        .map(|m| {
            let found = tree.query(&points[m]).nearest_n::<SquaredEuclidean<f32>>(k);
            let mut found = found.execute();
            let reach = found.last().map_or(0.0, |r| r.distance.sqrt()) * MERGE_FACTOR;
            found.retain(|r| r.distance <= reach * reach);
            found.retain(|r| r.item as usize != m && mergeable(m, r.item as usize));
            found.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.item.cmp(&b.item)));
            let mut out = [NONE; MERGE_K];
            for (slot, r) in out.iter_mut().zip(&found) {
                *slot = r.item;
            }
            out
        })
        .collect();
    let kept = greedy_packing(&near);
    // The rest merge into the nearest kept splat within their reach (the lower position where
    // two are as near).
    let into = (0..members.len())
        .into_par_iter()
        .map(|m| {
            if kept[m] {
                return m as u32;
            }
            let mut candidates = near[m].iter().take_while(|&&k| k != NONE);
            candidates
                .find(|&&k| kept[k as usize])
                .map_or(m as u32, |&k| k)
        })
        .collect();
    Some(into)
}

/// Which splats the greedy packing keeps: in priority order (their positions), a splat is kept
/// unless one kept before it is among its `near` ones. Computed in rounds, in parallel, with
/// the sequential result: a splat is settled once one of its earlier neighbours is kept (then
/// it is not) or all are settled and not kept (then it is). The first open splat settles in
/// every round, and with priorities in random order the chains of waiting splats are short.
fn greedy_packing(near: &[Near]) -> Vec<bool> {
    const OPEN: u8 = 0;
    const KEPT: u8 = 1;
    const MERGED: u8 = 2;
    let mut state = vec![OPEN; near.len()];
    loop {
        let next: Vec<u8> = (0..near.len())
            .into_par_iter()
            .map(|m| {
                if state[m] != OPEN {
                    return state[m];
                }
                let earlier = near[m].iter().filter(|&&k| k != NONE && (k as usize) < m);
                if earlier.clone().any(|&k| state[k as usize] == KEPT) {
                    MERGED
                } else if earlier.clone().all(|&k| state[k as usize] == MERGED) {
                    KEPT
                } else {
                    OPEN
                }
            })
            .collect();
        let settled = !next.contains(&OPEN);
        state = next;
        if settled {
            break;
        }
    }
    state.into_iter().map(|s| s == KEPT).collect()
}
