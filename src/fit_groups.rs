//! Shared lobe fits (docs/design.md §6, "Shared fits"): neighbouring splats of a smooth surface
//! see nearly the same incident light, so the fitted splats are grouped — within one cell of
//! a grid of `EmConfig::share` search radii, facing within `GROUP_COS_MIN` of the group's
//! first splat — and each group is fitted once. Final gathering casts the group's rays from
//! all its members in turn (ray j from member j mod n), so the one fit sees the group's mean
//! incident light, and every member shades with its lobes. The fit's cost then follows the
//! glossy surface's area in cells, not its splat count.
//!
//! The groups are made once per bake on the host, from the splats alone, in splat order, so
//! that both executors read the same groups and the result does not depend on scheduling.
//! They travel as one array of words (`FitGroups::words`), which `em_select` and
//! `final_gather` read: one word a splat (`FOLLOWER_BIT | leader` for a splat that uses
//! another's fit, its group's index for a leader, all ones for a splat not fitted), then each group's first member, then the members.

use std::collections::HashMap;

use glam::Vec3;

use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::types::{Material, Splat};

/// A splat's word when another splat's fit serves it (`wgsl/shared/lobes.wgsl`).
pub use crate::shared::lobes::FOLLOWER_BIT;

/// The word of a splat that is not fitted: with `FOLLOWER_BIT` set, `em_select` lists it as
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
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::Invalid(format!(
                "a shared fit's cell must be a positive length, got {cell}"
            )));
        }
        let n = u32::try_from(splats.len())
            .map_err(|_| Error::DeviceLimit("more than 2³² splats in one scene".into()))?;
        let fitted = |s: &Splat| {
            fit_all
                || materials
                    .get(s.material as usize)
                    .is_some_and(|m| m.specular.iter().any(|&x| x > 0.0))
        };
        // Each cell's leaders, in splat order.
        let mut cells: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
        let mut words = vec![UNGROUPED; splats.len()];
        let (mut groups, mut followers) = (0u32, 0u32);
        for (i, s) in (0u32..).zip(splats) {
            if !fitted(s) {
                continue;
            }
            let key = (Vec3::from(s.center) / cell).floor().as_ivec3().to_array();
            let normal = Vec3::from(s.normal);
            let list = cells.entry(key).or_default();
            let joined = list
                .iter()
                .copied()
                .find(|&l| Vec3::from(splats[l as usize].normal).dot(normal) >= GROUP_COS_MIN);
            match joined {
                Some(l) => {
                    words[i as usize] = FOLLOWER_BIT | l;
                    followers += 1;
                }
                None => {
                    words[i as usize] = groups;
                    groups += 1;
                    list.push(i);
                }
            }
        }
        // Members by group: counts, starts, then each group's leader and its followers.
        let g = groups as usize;
        let mut starts = vec![0u32; g + 1];
        for &w in &words {
            if let Some(group) = group_of(&words, w) {
                starts[group as usize + 1] += 1;
            }
        }
        for k in 0..g {
            starts[k + 1] += starts[k];
        }
        let mut members = vec![0u32; starts[g] as usize];
        let mut next = starts.clone();
        for (i, &w) in words.iter().enumerate() {
            if let Some(group) = group_of(&words, w) {
                members[next[group as usize] as usize] = i as u32;
                next[group as usize] += 1;
            }
        }
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

/// The group of a splat with word `w`: its own for a leader, its leader's for a follower,
/// `None` for a splat that is not fitted.
fn group_of(words: &[u32], w: u32) -> Option<u32> {
    match w {
        UNGROUPED => None,
        w if w & FOLLOWER_BIT != 0 => Some(words[(w & !FOLLOWER_BIT) as usize]),
        w => Some(w),
    }
}
