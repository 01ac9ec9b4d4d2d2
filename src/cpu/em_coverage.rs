//! Mirror of `wgsl/em_coverage.wgsl`: the share of its gather disk a group's leader's surface
//! covers (first pass, one invocation a group), and each splat's photon irradiance divided by
//! its group's share (second pass, `EM_COVER_APPLY`).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{IVec3, UVec3, Vec2, Vec3};
use rayon::prelude::*;

use crate::grid::{cell_index, point_cell};
use crate::shared::bins::SURFACE_COS_MIN;
use crate::shared::lobes::EM_COVER_APPLY;
use crate::shared::sampling::frame_of;
use crate::shared::trace::Geometry;
use crate::types::{EmParams, SplatLight};

pub const WG: u32 = 64;
/// Points a side of the grid over the gather disk (69 of its 81 lie within R).
pub const COVERAGE_GRID: u32 = 9;
/// The least share divided by: a splat's disk on a thin feature keeps a bounded estimate.
pub const COVERAGE_MIN: f32 = 0.2;
/// Disk tests a splat may spend.
pub const COVERAGE_BUDGET: u32 = 16384;
/// Grid points `(a, b)` tested first, near the rim: a splat whose probes are all covered lies
/// inside its face and keeps its estimate.
pub const COVERAGE_PROBES: [(u32, u32); 8] = [
    (0, 4),
    (8, 4),
    (4, 0),
    (4, 8),
    (1, 1),
    (7, 1),
    (1, 7),
    (7, 7),
];

/// Grid point `(a, b)` in the splat's frame, in units of R (inside the disk where |u| <= 1).
fn grid_point(a: u32, b: u32) -> Vec2 {
    (Vec2::new(a as f32, b as f32) + 0.5) * (2.0 / COVERAGE_GRID as f32) - 1.0
}

/// Whether a disk of the surface with normal `n` reaches over `q`, within `slab` of its plane.
fn covered(geo: &Geometry, q: Vec3, n: Vec3, slab: f32, budget: &mut u32) -> bool {
    let g = &geo.grid.params;
    let c = point_cell(q, g);
    if c.cmplt(IVec3::ZERO).any() || c.cmpge(UVec3::from(g.dims).as_ivec3()).any() {
        return false;
    }
    let ci = cell_index(c.as_uvec3(), g);
    // An empty cell (the distance field's nonzero) lists no disk.
    if geo.grid.cell_dist[ci as usize] != 0 {
        return false;
    }
    // The next disk that reaches over q, then its clip (as the WGSL twin reads it).
    let mut disks = geo.grid.cell(ci).iter();
    loop {
        let mut found = None;
        for &j in disks.by_ref() {
            if *budget == 0 {
                break;
            }
            *budget -= 1;
            let s = &geo.splats[j as usize];
            let sn = Vec3::from(s.normal);
            if sn.dot(n) < SURFACE_COS_MIN {
                continue;
            }
            let off = (q - Vec3::from(s.center)).dot(sn);
            let p = q - off * sn - Vec3::from(s.center);
            if off.abs() <= slab && p.dot(p) <= s.radius * s.radius {
                found = Some((s, q - off * sn));
                break;
            }
        }
        match found {
            None => return false,
            Some((s, at)) if geo.keeps(s, at) => return true,
            Some(_) => {}
        }
    }
}

/// The share of splat `i`'s gather disk its surface covers, 1 where the search was cut short.
fn share(em: &EmParams, geo: &Geometry, i: usize) -> f32 {
    let s = &geo.splats[i];
    let (centre, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
    let f = frame_of(normal);
    let slab = em.slab * s.radius;
    let mut budget = COVERAGE_BUDGET;
    let point = |u: Vec2| centre + em.radius * (u.x * f.t + u.y * f.b);
    let probes = COVERAGE_PROBES
        .iter()
        .filter(|&&(a, b)| covered(geo, point(grid_point(a, b)), normal, slab, &mut budget))
        .count();
    if probes == COVERAGE_PROBES.len() {
        return 1.0;
    }
    let (mut inside, mut hits) = (0u32, 0u32);
    for a in 0..COVERAGE_GRID {
        for b in 0..COVERAGE_GRID {
            let u = grid_point(a, b);
            if u.dot(u) > 1.0 {
                continue;
            }
            inside += 1;
            if covered(geo, point(u), normal, slab, &mut budget) {
                hits += 1;
            }
        }
    }
    // A search cut short corrects nothing.
    if budget == 0 {
        return 1.0;
    }
    (hits as f32 / inside as f32).max(COVERAGE_MIN)
}

/// The first pass: each of `em.active_count` groups' share, at its leader (`cover`'s words
/// after the splats'); the second (`EM_COVER_APPLY`): each splat's irradiance divided by its
/// group's share.
pub fn em_coverage(
    em: &EmParams,
    light: &mut [SplatLight],
    (cover, shares): (&[u32], &mut [f32]),
    geo: &Geometry,
    groups: u32,
) {
    let invocations = (groups * WG) as usize;
    if em.flags & EM_COVER_APPLY == 0 {
        let count = invocations.min(em.active_count as usize);
        let leaders = &cover[em.splat_count as usize..];
        shares[..count]
            .par_iter_mut()
            .zip(&leaders[..count])
            .for_each(|(share_out, &leader)| *share_out = share(em, geo, leader as usize));
        return;
    }
    let count = invocations.min(em.splat_count as usize);
    light[..count]
        .par_iter_mut()
        .zip(&cover[..count])
        .for_each(|(l, &group)| {
            if l.photons == 0 || l.lobes > 0 {
                return;
            }
            l.irradiance = (Vec3::from(l.irradiance) / shares[group as usize]).into();
        });
}

/// The executor's entry: `em_coverage`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let mut light = b.get_mut(1)?;
    let cover = b.get(2)?;
    let mut shares = b.get_mut(3)?;
    em_coverage(
        &em,
        view_mut(&mut light),
        (view(&cover), view_mut(&mut shares)),
        geo,
        groups,
    );
    Ok(())
}
