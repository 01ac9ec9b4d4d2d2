//! Mirror of `wgsl/deposit_share.wgsl`: each coverage group's photon irradiance from the binned
//! deposits around its leader, in the candidates' order (`main`), then each splat's, its
//! leader's, and the count of splats lit (`copy`).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;

use crate::shared::bins::{SURFACE_COS_MIN, bin_box, bin_row, bin_row_count, photon_weight};
use crate::shared::deposits::{disk_share, front_share};
use crate::shared::lobes::EM_FIT_ALL;
use crate::shared::octahedral::surface_decode;
use crate::types::{BinParams, BinnedPhoton, DepositParams, EmParams, Material, Splat, SplatLight};

pub const WG: u32 = 64;

/// The binned deposits `deposit_share` reads: list starts, keys, geometry, power, and each splat's
/// spread and count.
pub struct BinnedDeposits<'a> {
    pub cell_start: &'a [u32],
    pub keys: &'a [[u32; 2]],
    pub geom: &'a [BinnedPhoton],
    pub power: &'a [[f32; 4]],
    pub spread: &'a [[f32; 2]],
}

/// Splat `s`'s light: the deposits within reach of its centre, each by the share of its
/// photons in the gather disk and at the splat's front.
fn share(
    em: &EmParams,
    deposit: &DepositParams,
    bins: &BinParams,
    splats: &[Splat],
    d: &BinnedDeposits,
    s: &Splat,
) -> SplatLight {
    let reach2 = deposit.reach * deposit.reach;
    let (center, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
    let slab = em.slab * s.radius;
    let bx = bin_box(center, deposit.reach, bins);
    let mut rgb = Vec3::ZERO;
    let mut photons = 0.0f32;
    let mut weight = 0.0f32;
    for r in 0..bin_row_count(&bx) {
        let row = bin_row(&bx, r, bins);
        for k in d.cell_start[row.x as usize]..d.cell_start[row.y as usize] {
            let k = k as usize;
            let dv = Vec3::from(d.geom[k].position) - center;
            let l2 = dv.dot(dv);
            if l2 > reach2 || dv.dot(normal).abs() > slab {
                continue;
            }
            let power = d.power[k];
            if surface_decode(power[3]).dot(normal) < SURFACE_COS_MIN {
                continue;
            }
            let j = d.keys[k][0] as usize;
            let form = d.spread[j];
            let share = disk_share(l2.sqrt(), em.radius, form[0])
                * front_share(normal, Vec3::from(splats[j].normal));
            rgb += Vec3::new(power[0], power[1], power[2]) * share;
            photons += form[1] * share;
            weight += photon_weight(power) * share;
        }
    }
    SplatLight {
        irradiance: (rgb * em.inv_area).into(),
        photons: photons.ceil() as u32,
        log_likelihood: 0.0,
        weight,
        lobes: 0,
        first_lobe: 0,
    }
}

/// The first pass (`main`): each of `em.active_count` groups' light, at its leader
/// (`cover`'s words after the splats').
#[allow(clippy::too_many_arguments)]
pub fn deposit_share(
    em: &EmParams,
    deposit: &DepositParams,
    bins: &BinParams,
    splats: &[Splat],
    d: &BinnedDeposits,
    (light, cover): (&mut [SplatLight], &[u32]),
    groups: u32,
) {
    let invocations = (groups * WG) as usize;
    let leaders = &cover[em.splat_count as usize..];
    let count = invocations.min(em.active_count as usize);
    let sums: Vec<SplatLight> = leaders[..count]
        .par_iter()
        .map(|&leader| share(em, deposit, bins, splats, d, &splats[leader as usize]))
        .collect();
    for (&leader, l) in leaders.iter().zip(sums) {
        light[leader as usize] = l;
    }
}

/// The second pass (`copy`): each splat's light its leader's, and the splats lit that are
/// not fitted counted.
pub fn copy(
    em: &EmParams,
    (splats, materials): (&[Splat], &[Material]),
    (light, cover): (&mut [SplatLight], &[u32]),
    counters: &mut [u32; 4],
    groups: u32,
) {
    let invocations = (groups * WG) as usize;
    let leaders = &cover[em.splat_count as usize..];
    let count = invocations.min(em.splat_count as usize);
    // The leaders' light apart, a group's a word (the pass writes members, never leaders).
    let led: Vec<SplatLight> = leaders.iter().map(|&l| light[l as usize]).collect();
    light[..count]
        .par_iter_mut()
        .zip(&cover[..count])
        .for_each(|(l, &g)| *l = led[g as usize]);
    let fitted = |s: &Splat| {
        let glossy = materials[s.material as usize]
            .specular
            .iter()
            .any(|&x| x > 0.0);
        glossy || em.flags & EM_FIT_ALL != 0
    };
    let lit = light[..count]
        .iter()
        .zip(splats)
        .filter(|(l, s)| l.photons > 0 && !fitted(s));
    counters[3] += lit.count() as u32;
}

/// The executor's entry of `main`: `deposit_share`'s bindings, unpacked in the order its WGSL
/// declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let deposit = b.param(1)?;
    let bins = b.param(2)?;
    let splats = b.get(3)?;
    let cell_start = b.get(6)?;
    let keys = b.get(7)?;
    let geom = b.get(8)?;
    let power = b.get(9)?;
    let spread = b.get(10)?;
    let mut light = b.get_mut(11)?;
    let cover = b.get(12)?;
    let binned = BinnedDeposits {
        cell_start: &cell_start,
        keys: view(&keys),
        geom: view(&geom),
        power: view(&power),
        spread: view(&spread),
    };
    let on = (view_mut(&mut light), view(&cover));
    deposit_share(&em, &deposit, &bins, view(&splats), &binned, on, groups);
    Ok(())
}

/// The executor's entry of `copy`.
pub fn dispatch_copy(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let splats = b.get(3)?;
    let materials = b.get(4)?;
    let mut counters = b.get_mut(5)?;
    let mut light = b.get_mut(11)?;
    let cover = b.get(12)?;
    let counters = b.counters::<4>(&mut counters)?;
    let of = (view(&splats), view(&materials));
    copy(&em, of, (view_mut(&mut light), view(&cover)), counters, groups);
    Ok(())
}

/// This file's rows of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::DepositShare,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
    MirrorRow {
        stage: Stage::DepositShare,
        entry: "copy",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch_copy)),
    },
];
