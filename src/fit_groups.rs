//! Shared lobe fits (docs/design.md §6, "Shared fits"): neighbouring splats of a smooth surface
//! see nearly the same incident light, so the fitted splats are grouped — within one cell of
//! a grid of `EmConfig::share` search radii, facing within `GROUP_COS_MIN` of the group's
//! leader — and each group is fitted once. Final gathering casts the group's rays from
//! all its members in turn (ray j from member j mod n), so the one fit sees the group's mean
//! incident light, and every member shades with its lobes. The fit's cost then follows the
//! glossy surface's area in cells, not its splat count.
//!
//! The groups are made once per bake on the host, from the splats alone, so
//! that both executors read the same groups and the result does not depend on scheduling.
//! They travel as one array of words (`FitGroups::words`), which `fit_select` and
//! `final_gather` read: one word a splat (`FOLLOWER_BIT | leader` for a splat that uses
//! another's fit, its group's index for a leader, all ones for a splat not fitted), then where
//! each group's members start, then the members, each group's leader first.
//!
//! The covered share of a splat's gather disk (`estimate_coverage`) is shared the same way, in
//! smaller cells (`CoverGroups`): a dense scan's every search radius holds thousands of splats,
//! whose shares differ by little. A follower joins its fit leader's coverage group: only the
//! rays that meet it read its own estimate before `serve` replaces it.

use glam::Vec3;
use rayon::prelude::*;

use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::types::{Material, Splat};

/// A splat's word when another splat's fit serves it (`wgsl/shared/lobes.wgsl`).
pub use crate::shared::lobes::FOLLOWER_BIT;

/// The word of a splat that is not fitted: with `FOLLOWER_BIT` set, `fit_select` lists it as
/// the diffuse splat it is.
const UNGROUPED: u32 = u32::MAX;

/// Splats share a fit only where their normals lie within about 26° of the group's first
/// splat: across an edge or a thin part the hemispheres differ, and so does the light.
pub const GROUP_COS_MIN: f32 = 0.9;

/// The fitted splats in groups that share one fit (see the module's doc).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FitGroups {
    /// `splats` words, then `groups + 1` group starts, then the members (leader first).
    pub words: Vec<u32>,
    pub splats: u32,
    pub groups: u32,
    /// Fitted splats served by another's fit.
    pub followers: u32,
}

impl FitGroups {
    /// Groups in cells of `cell` scene units over the fitted splats: those of a glossy
    /// material, or every splat with `fit_all`.
    pub fn new(
        splats: &[Splat],
        materials: &[Material],
        fit_all: bool,
        cell: f32,
    ) -> Result<FitGroups> {
        let fitted = |i: usize| {
            fit_all
                || materials
                    .get(splats[i].material as usize)
                    .is_some_and(Material::is_glossy)
        };
        let cells = CellGroups::new(splats, fitted, cell, GROUP_COS_MIN)?;
        let n = cells.group.len() as u32;
        let groups = cells.leaders.len() as u32;
        // One word a splat: its group for a leader, its leader for a follower.
        let mut words: Vec<u32> = (0..n)
            .map(|i| match cells.group[i as usize] {
                UNGROUPED => UNGROUPED,
                g if cells.leaders[g as usize] == i => g,
                g => FOLLOWER_BIT | cells.leaders[g as usize],
            })
            .collect();
        // Members by group: counts, starts, then each group's leader and its followers.
        let g = groups as usize;
        let mut starts = vec![0u32; g + 1];
        for &group in cells.group.iter().filter(|&&k| k != UNGROUPED) {
            starts[group as usize + 1] += 1;
        }
        for k in 0..g {
            starts[k + 1] += starts[k];
        }
        let mut members = vec![0u32; starts[g] as usize];
        let mut next = starts.clone();
        // Each group's leader first (it need not be its first splat), then its followers.
        for (k, &l) in cells.leaders.iter().enumerate() {
            members[next[k] as usize] = l;
            next[k] += 1;
        }
        for (i, &group) in (0u32..).zip(&cells.group) {
            if group != UNGROUPED && cells.leaders[group as usize] != i {
                members[next[group as usize] as usize] = i;
                next[group as usize] += 1;
            }
        }
        let followers = starts[g] - groups;
        words.extend_from_slice(&starts);
        words.extend_from_slice(&members);
        Ok(FitGroups {
            words,
            splats: n,
            groups,
            followers,
        })
    }

    /// Where the group starts lie in `words` (`GatherParams::group_starts`).
    pub fn starts_at(&self) -> u32 {
        self.splats
    }

    /// Where the members lie in `words` (`GatherParams::group_members`).
    pub fn members_at(&self) -> u32 {
        self.splats + self.groups + 1
    }

    /// The splat whose fit serves splat `i`, where another's does.
    pub fn leader(&self, i: usize) -> Option<usize> {
        let w = self.words[i];
        (w != UNGROUPED && w & FOLLOWER_BIT != 0).then_some((w & !FOLLOWER_BIT) as usize)
    }

    /// Gives every follower its leader's light whole: its lobes (aliased: stored once per
    /// group), its fit figures and its irradiance, the group's ray estimate, which on a curved
    /// surface reads closer to the path tracer than the follower's own photon estimate
    /// (design §6, "Shared fits"); returns how many were served lobes.
    pub fn serve(&self, map: &mut LobeMap) -> u32 {
        let mut served = 0;
        for i in 0..map.light.len().min(self.splats as usize) {
            let Some(l) = self.leader(i) else { continue };
            map.light[i] = map.light[l];
            served += u32::from(map.light[l].lobes > 0);
        }
        served
    }
}

/// Splats share the covered share of their gather disk (`estimate_coverage`) within cells of this
/// many search radii: the share moves by at most about 0.64 per radius the centre moves (the
/// disk's widest chord over its area), so by a few hundredths within a cell, where a dense
/// scan's cell of R/16 holds tens of splats.
pub const COVER_CELL: f32 = 1.0 / 16.0;

/// Splats share a coverage only where their normals lie within about 11°: the share is
/// measured in the tangent plane, which on a curved surface turns with the normal.
pub const COVER_COS_MIN: f32 = 0.98;

/// Every splat in a group that shares one measure of its gather disk's coverage
/// (`wgsl/estimate_coverage.wgsl`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoverGroups {
    /// `splats` words, each splat's group, then `groups` words, each group's leader.
    pub words: Vec<u32>,
    pub splats: u32,
    pub groups: u32,
}

impl CoverGroups {
    /// Groups in cells of `COVER_CELL` × `radius`, the photons' search radius. With shared
    /// fits (`fits`), a follower joins the group of its fit's leader instead: its own estimate
    /// would be measured only for final gathering's rays that meet it (`serve` then gives it
    /// its leader's light whole), and its leader's, read at its place, serves them as well as
    /// the leader's fit serves its shading. On a glossy scan that is half the splats or more,
    /// and the curved ones whose coverage costs the most to measure.
    pub fn new(splats: &[Splat], radius: f32, fits: Option<&FitGroups>) -> Result<CoverGroups> {
        let leader = |i: usize| fits.and_then(|f| f.leader(i));
        let include = |i: usize| leader(i).is_none();
        let cells = CellGroups::new(splats, include, COVER_CELL * radius, COVER_COS_MIN)?;
        let (splats, groups) = (cells.group.len() as u32, cells.leaders.len() as u32);
        let mut words = cells.group;
        // A fit's leader is never a follower, so its group is one of the cells'.
        for i in 0..words.len() {
            if let Some(l) = leader(i) {
                words[i] = words[l];
            }
        }
        words.extend_from_slice(&cells.leaders);
        Ok(CoverGroups {
            words,
            splats,
            groups,
        })
    }
}

/// The most splats of a cell weighed as its next leader: a dense scan's cell of a search
/// radius holds thousands, and each candidate's count visits them all.
const LEADER_CANDIDATES: usize = 16;

/// Splats grouped by cell and facing: the splats that `include` takes, by cell (a grid of
/// `cell` scene units), each in the group of a leader of its cell that faces within `cos_min`
/// of it. A cell's leaders are chosen in turn to take the most of its splats still open (see
/// `CellGroups::new`). Groups are numbered in their leaders' splat order, so the grouping
/// depends on the splats alone.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellGroups {
    /// Each splat's group (`UNGROUPED` where `include` left it out).
    pub group: Vec<u32>,
    /// Each group's leader.
    pub leaders: Vec<u32>,
}

impl CellGroups {
    pub fn new(
        splats: &[Splat],
        include: impl Fn(usize) -> bool + Sync,
        cell: f32,
        cos_min: f32,
    ) -> Result<CellGroups> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::Invalid(format!(
                "a group's cell must be a positive length, got {cell}"
            )));
        }
        let n = u32::try_from(splats.len())
            .map_err(|_| Error::DeviceLimit("more than 2³² splats in one scene".into()))?;
        // The included splats by cell, each cell's in splat order (a sort, not a map of
        // lists: ten million splats are ten million cells where the cells are small).
        let mut keyed: Vec<([i32; 3], u32)> = (0..n)
            .into_par_iter()
            .filter(|&i| include(i as usize))
            .map(|i| {
                let c = Vec3::from(splats[i as usize].center) / cell;
                (c.floor().as_ivec3().to_array(), i)
            })
            .collect();
        keyed.par_sort_unstable();
        // Each splat's leader, cell by cell.
        let mut leader_of = vec![UNGROUPED; splats.len()];
        let normal = |i: u32| Vec3::from(splats[i as usize].normal);
        let mut open: Vec<u32> = Vec::new();
        for run in keyed.chunk_by(|a, b| a.0 == b.0) {
            open.clear();
            open.extend(run.iter().map(|&(_, i)| i));
            // Leaders chosen to cover the most: of up to LEADER_CANDIDATES of the cell's open
            // splats (evenly strided, in splat order), the one whose cone holds the most open
            // splats, the first of them on a tie; it takes them all, and again until none is
            // open. On a curved surface a cell's first splat may face one edge of the cell's
            // normals, and then the ones facing the other edge lead groups of their own.
            while !open.is_empty() {
                let stride = open.len().div_ceil(LEADER_CANDIDATES);
                let held = |l: u32| {
                    let n = normal(l);
                    open.iter()
                        .filter(|&&j| normal(j).dot(n) >= cos_min)
                        .count()
                };
                let mut best = (open[0], held(open[0]));
                for &c in open.iter().step_by(stride).skip(1) {
                    // A leader that holds every open splat cannot be bettered (a flat cell's
                    // first): the other candidates' counts are not needed.
                    if best.1 == open.len() {
                        break;
                    }
                    let h = held(c);
                    if h > best.1 {
                        best = (c, h);
                    }
                }
                let (l, n) = (best.0, normal(best.0));
                open.retain(|&j| {
                    let joins = j == l || normal(j).dot(n) >= cos_min;
                    if joins {
                        leader_of[j as usize] = l;
                    }
                    !joins
                });
            }
        }
        // Groups numbered in their leaders' splat order.
        let mut group = vec![UNGROUPED; splats.len()];
        let mut leaders = Vec::new();
        for i in 0..splats.len() {
            if leader_of[i] == i as u32 {
                group[i] = leaders.len() as u32;
                leaders.push(i as u32);
            }
        }
        for i in 0..splats.len() {
            let l = leader_of[i];
            if l != UNGROUPED && l != i as u32 {
                group[i] = group[l as usize];
            }
        }
        Ok(CellGroups { group, leaders })
    }
}
