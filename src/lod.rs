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

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use crate::shared::rng::pcg_hash;
use crate::shared::splat::LOD_MAX_LEVEL;
use crate::types::{Splat, SplatLod};

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

/// The merge tree of `splats` (see the module's doc); one record per splat, in their order.
pub fn splat_lods(splats: &[Splat]) -> Vec<SplatLod> {
    let n = splats.len();
    let centre = |i: u32| Vec3::from(splats[i as usize].center);
    // extent[i][L]: splat i's disk at level L, for L up to top[i].
    let mut extent: Vec<[f32; 4]> = splats.iter().map(|s| [s.radius; 4]).collect();
    let mut top = vec![0u32; n];
    let mut parent = vec![NONE; n];
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
        // A kept disk's reach at this level: every splat whose ancestor merged into it.
        for j in 0..n {
            let r = rep(ancestor[j]);
            ancestor[j] = r;
            let reach = (Vec3::from(splats[j].center) - centre(r)).length() + splats[j].radius;
            let e = &mut extent[r as usize][level as usize];
            *e = e.max(reach);
        }
        members.retain(|&i| top[i as usize] == level);
    }
    (0..n)
        .map(|i| {
            let t = top[i] as usize;
            let mut lod = SplatLod {
                extent: [1, 2, 3].map(|k| extent[i][k.min(t)]),
                top: t as u32,
                ..SplatLod::default()
            };
            if let Some(&p) = parent.get(i).filter(|&&p| p != NONE) {
                lod.parent_extent = extent[p as usize][t + 1];
                lod.parent_gap = (Vec3::from(splats[i].center) - centre(p)).length();
            }
            lod
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
