//! Mirror of `wgsl/final_gather.wgsl`: rays over each fitted splat's cosine-weighted
//! hemisphere (with shared fits, over its group's members' in turn), and the radiance of the
//! surface each meets, as the bake knows it (`hit_albedo`).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::fit_select::FIT_BIT;
use crate::shared::lights::{area_point, light_first};
use crate::shared::octahedral::oct_encode;
use crate::shared::rng::pcg_hash;
use crate::shared::sampling::{frame_of, sample_cosine, to_world};
use crate::shared::splat::{SHADOW_RAY_BUDGET, hit_albedo};
use crate::shared::trace::{FAR, Geometry, trace_ray};
use crate::types::{GatherParams, Light, Material, NO_SPLAT, SplatLight};

pub const WG: u32 = 64;

/// Fills `samples` (`samples²` for each fitted splat of the fit list's entries `first..first
/// + splat_count`, entry `first + k` at `k · samples²`, each `[radiance, direction bits]`).
#[allow(clippy::too_many_arguments)]
pub fn final_gather(
    params: &GatherParams,
    list: &[[u32; 2]],
    light: &[SplatLight],
    direct: &[[f32; 4]],
    samples: &mut [[f32; 4]],
    materials: &[Material],
    lights: &[Light],
    groups: &[u32],
    geo: &Geometry,
) {
    let lights = &lights[..params.light_count as usize];
    let rays = (params.samples * params.samples) as usize;
    let first = params.first as usize;
    let entries = &list[first..first + params.splat_count as usize];
    samples[..entries.len() * rays]
        .par_chunks_mut(rays)
        .zip(entries)
        .filter(|(_, [entry, _])| entry & FIT_BIT != 0)
        .for_each(|(out, [entry, _])| {
            let i = entry & !FIT_BIT;
            for (j, sample) in (0u32..).zip(out) {
                let from = ray_origin(params, groups, i, j);
                *sample = ray(params, (i, from), j, light, direct, materials, lights, geo);
            }
        });
}

/// The splat ray `j` of fitted splat `i` starts from: with shared fits, member j mod n of the n
/// in `i`'s group (the leader first); else `i` itself.
fn ray_origin(params: &GatherParams, groups: &[u32], i: u32, j: u32) -> u32 {
    if params.group_members == 0 {
        return i;
    }
    let group = groups[i as usize];
    let first = groups[(params.group_starts + group) as usize];
    let count = groups[(params.group_starts + group + 1) as usize] - first;
    groups[(params.group_members + first + j % count) as usize]
}

/// Ray `j` of fitted splat `i`, cast from splat `from`: the radiance it brings back, and its
/// direction's bits.
#[allow(clippy::too_many_arguments)]
fn ray(
    params: &GatherParams,
    (i, from): (u32, u32),
    j: u32,
    light: &[SplatLight],
    direct: &[[f32; 4]],
    materials: &[Material],
    lights: &[Light],
    geo: &Geometry,
) -> [f32; 4] {
    let s = &geo.splats[from as usize];
    let (centre, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
    let key = pcg_hash(pcg_hash(params.seed).wrapping_add(i)).wrapping_add(2 * j);
    let uv = area_point(j, params.samples, key, true);
    let d = to_world(&frame_of(normal), sample_cosine(uv.x, uv.y));
    let o = centre + params.shadow_bias * normal;
    let mut budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(geo, o, d, from, FAR, &mut budget);
    let mut radiance = Vec3::ZERO;
    let lit = lights.iter().any(|l| light_first(l, o, d, hit.t));
    if hit.splat != NO_SPLAT && !lit {
        let h = &geo.splats[hit.splat as usize];
        if Vec3::from(h.normal).dot(d) < 0.0 {
            let e = Vec4::from(direct[hit.splat as usize]).truncate()
                + Vec3::from(light[hit.splat as usize].irradiance);
            let m = &materials[h.material as usize];
            radiance = hit_albedo(h, m) * e * std::f32::consts::FRAC_1_PI;
        }
    }
    radiance.extend(f32::from_bits(oct_encode(d))).to_array()
}

/// The executor's entry: `final_gather`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let list = b.get(1)?;
    let light = b.get(2)?;
    let direct = b.get(3)?;
    let mut samples = b.get_mut(4)?;
    let materials = b.get(5)?;
    let lights = b.get(6)?;
    let groups = b.get(7)?;
    let (list, light, direct) = (view(&list), view(&light), view(&direct));
    let (samples, materials) = (view_mut(&mut samples), view(&materials));
    let lights = view(&lights);
    final_gather(
        &p, list, light, direct, samples, materials, lights, &groups, geo,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::FinalGather,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
];
