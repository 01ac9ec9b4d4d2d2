//! Mirror of `wgsl/estimate_gather.wgsl`: the irradiance of each splat on the gather list, one
//! invocation per splat, summed in the candidates' order.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;

use crate::shared::bins::{SURFACE_COS_MIN, bin_box, bin_row, bin_row_count, photon_weight};
use crate::shared::octahedral::{oct_decode, surface_decode};
use crate::types::{BinParams, BinnedPhoton, EmParams, Splat, SplatLight};

pub const WG: u32 = 64;

#[allow(clippy::too_many_arguments)]
pub fn estimate_gather(
    em: &EmParams,
    bins: &BinParams,
    splats: &[Splat],
    gather_list: &[u32],
    cell_start: &[u32],
    bin_geom: &[BinnedPhoton],
    bin_power: &[[f32; 4]],
    light: &mut [SplatLight],
    groups: u32,
) {
    let count = (groups * WG)
        .min(em.active_count)
        .min(gather_list.len() as u32);
    let results: Vec<(u32, SplatLight)> = gather_list[..count as usize]
        .par_iter()
        .map(|&i| {
            let s = &splats[i as usize];
            let (center, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
            let slab = em.slab * s.radius;
            let bx = bin_box(center, em.radius, bins);
            let mut rgb = Vec3::ZERO;
            let mut photons = 0u32;
            let mut weight = 0.0f32;
            for r in 0..bin_row_count(&bx) {
                let row = bin_row(&bx, r, bins);
                for j in cell_start[row.x as usize]..cell_start[row.y as usize] {
                    let g = bin_geom[j as usize];
                    let d = Vec3::from(g.position) - center;
                    if d.dot(d) > em.radius2 || d.dot(normal).abs() > slab {
                        continue;
                    }
                    let power = bin_power[j as usize];
                    let dir = oct_decode(g.direction);
                    if dir.dot(normal) > 0.0
                        && surface_decode(power[3]).dot(normal) >= SURFACE_COS_MIN
                    {
                        rgb += Vec3::new(power[0], power[1], power[2]);
                        photons += 1;
                        weight += photon_weight(power);
                    }
                }
            }
            let out = SplatLight {
                irradiance: (rgb * em.inv_area).into(),
                photons,
                log_likelihood: 0.0,
                weight,
                lobes: 0,
                first_lobe: 0,
            };
            (i, out)
        })
        .collect();
    for (i, out) in results {
        light[i as usize] = out;
    }
}

/// The executor's entry: `estimate_gather`'s bindings, unpacked in the order its WGSL declares
/// them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let bins = b.param(1)?;
    let splats = b.get(2)?;
    let gather_list = b.get(3)?;
    let cell_start = b.get(4)?;
    let geom = b.get(5)?;
    let power = b.get(6)?;
    let mut light = b.get_mut(7)?;
    estimate_gather(
        &em,
        &bins,
        view(&splats),
        &gather_list,
        &cell_start,
        view(&geom),
        view(&power),
        view_mut(&mut light),
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::EstimateGather,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
