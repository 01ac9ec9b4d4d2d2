//! Mirror of `wgsl/direct_bake.wgsl`: every splat's shadowed irradiance from the lights, and
//! each light's visibility, by shadow rays from the splat's centre; an environment light's
//! blocked share averaged over the neighbours (`share`).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::grid::point_cell;
use crate::shared::lights::{
    SKY_STRATA, area_point, sample_light, shadow_reach, sky_irradiance, strata_side,
};
use crate::shared::rng::pcg_hash;
use crate::shared::splat::SHADOW_RAY_BUDGET;
use crate::shared::trace::{Geometry, trace_ray};
use crate::types::{DirectParams, Light, NO_SPLAT, Splat, light_kind};

pub const WG: u32 = 64;

/// An environment light's strata per side in the bake (`SKY_SIDE` in WGSL): 4 rays a splat.
pub const SKY_SIDE: u32 = SKY_STRATA;

/// The neighbours that share a sky's blocked share (WGSL's constants say which).
pub const SHARE_REACH: f32 = 3.0;
pub const SHARE_CELLS: f32 = 1.5;
pub const SHARE_COS: f32 = 0.95;

/// Stratum `j` of light `l`'s `n`² seen from splat `i`: its irradiance `e cos θ` (zero where
/// the light lies behind the splat or gives nothing, and then no ray is traced) and whether the
/// shadow ray from `o` reaches the light (`stratum_ray` in WGSL).
fn stratum_ray(
    (params, geo): (&DirectParams, &Geometry),
    (l, li): (&Light, u32),
    (i, s, o): (u32, &Splat, Vec3),
    key: u32,
    (j, n): (u32, u32),
) -> (Vec3, bool) {
    let (centre, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
    let r = key.wrapping_add((li * n * n + j).wrapping_mul(2));
    let uv = area_point(j, n, r, true);
    let ls = sample_light(geo.sky, l, centre, normal, uv.x, uv.y);
    let cos_i = normal.dot(ls.wi);
    if !(cos_i > 0.0) || ls.e.cmple(Vec3::ZERO).all() {
        return (Vec3::ZERO, false);
    }
    let mut budget = SHADOW_RAY_BUDGET;
    let t_max = shadow_reach(l, o, ls.wi, ls.dist, params.shadow_bias);
    let open = trace_ray(geo, o, ls.wi, i, t_max, &mut budget).splat == NO_SPLAT;
    (ls.e * cos_i, open)
}

/// Light `l`'s irradiance on splat `i` and the open share of its unshadowed irradiance, by
/// shadow rays from `o`; the sun's disk first through two of its strata.
fn seen_by_rays(
    (params, geo): (&DirectParams, &Geometry),
    light: (&Light, u32),
    splat: (u32, &Splat, Vec3),
    key: u32,
) -> (Vec3, f32) {
    let l = light.0;
    let n = strata_side(l.kind, params.samples);
    let first_look = l.kind == light_kind::SUN && n >= 2;
    let (mut open, mut unshadowed) = (Vec3::ZERO, Vec3::ZERO);
    let (mut rays_open, mut rays, mut taken) = (0u32, 0u32, 0u32);
    for look in 0..2 {
        if look == 1 && (!first_look || rays_open == 0 || rays_open == rays) {
            break;
        }
        for j in 0..n * n {
            let (x, y) = (j % n, j / n);
            let coarse = x % 2 == 0 && y % 2 == 0 && (x / 2 + y / 2) % 2 == 0;
            if first_look && coarse != (look == 0) {
                continue;
            }
            taken += 1;
            let (e, reached) = stratum_ray((params, geo), light, splat, key, (j, n));
            if e.cmple(Vec3::ZERO).all() {
                continue;
            }
            unshadowed += e;
            rays += 1;
            if reached {
                open += e;
                rays_open += 1;
            }
        }
    }
    let seen = unshadowed.x + unshadowed.y + unshadowed.z;
    let seen_open = if seen > 0.0 {
        (open.x + open.y + open.z) / seen
    } else {
        1.0
    };
    (open / taken.max(1) as f32, seen_open)
}

/// The share of environment light `l`'s unshadowed irradiance `e0` on splat `i` that its
/// `SKY_SIDE`² shadow rays find blocked.
fn sky_blocked(
    at: (&DirectParams, &Geometry),
    light: (&Light, u32),
    splat: (u32, &Splat, Vec3),
    key: u32,
    e0: Vec3,
) -> f32 {
    let n = SKY_SIDE;
    let mut lost = Vec3::ZERO;
    for j in 0..n * n {
        let (e, reached) = stratum_ray(at, light, splat, key, (j, n));
        if !reached {
            lost += e;
        }
    }
    let all_e = e0.x + e0.y + e0.z;
    if all_e > 0.0 {
        (lost.x + lost.y + lost.z) / ((n * n) as f32 * all_e)
    } else {
        0.0
    }
}

/// Fills `direct` (one `[E, 0]` per splat) with every light but an environment light, the
/// lights' `visibility` (splat × light) and the environment light's `blocked` share,
/// invocation k taking splat `order[k]`.
pub fn direct_bake(
    params: &DirectParams,
    lights: &[Light],
    order: &[u32],
    (direct, visibility, blocked): (&mut [[f32; 4]], &mut [f32], &mut [f32]),
    geo: &Geometry,
) {
    let lc = params.light_count as usize;
    let count = params.splat_count as usize;
    if lc == 0 {
        direct[..count].fill([0.0; 4]);
        return;
    }
    // Invocation k writes its rows at k of three arrays, then each row goes to its splat's
    // place: a row collected an invocation (and a vector of its lights') cost two allocations
    // a splat, 10 M of them on a 10 M-splat scan.
    let order = &order[..count];
    let mut rows = vec![([0.0f32; 4], 0.0f32); count];
    let mut seen_rows = vec![0.0f32; count * lc];
    rows.par_iter_mut()
        .zip(seen_rows.par_chunks_mut(lc))
        .zip(order.par_iter())
        .for_each(|((out, seen_by), &i)| {
            let s = &geo.splats[i as usize];
            let o = Vec3::from(s.center) + params.shadow_bias * Vec3::from(s.normal);
            let key = pcg_hash(pcg_hash(params.seed).wrapping_add(i));
            let mut total = Vec3::ZERO;
            for ((li, l), seen) in lights.iter().enumerate().zip(seen_by.iter_mut()) {
                let li = li as u32;
                if l.kind == light_kind::ENVIRONMENT {
                    let e0 = sky_irradiance(geo.sky, l, Vec3::from(s.normal));
                    out.1 = sky_blocked((params, geo), (l, li), (i, s, o), key, e0);
                    continue;
                }
                let (e, open) = seen_by_rays((params, geo), (l, li), (i, s, o), key);
                total += e;
                *seen = open;
            }
            out.0 = total.extend(0.0).to_array();
        });
    let sky = lights
        .iter()
        .position(|l| l.kind == light_kind::ENVIRONMENT);
    for ((&i, (row, lost)), seen) in order.iter().zip(rows).zip(seen_rows.chunks(lc)) {
        let i = i as usize;
        direct[i] = row;
        blocked[i] = lost;
        // The environment light's visibility is `share`'s to write.
        for (li, &v) in seen.iter().enumerate() {
            if Some(li) != sky {
                visibility[i * lc + li] = v;
            }
        }
    }
}

/// The mean blocked share over splat `i`'s neighbours, itself among them (`shared_blocked` in
/// WGSL).
fn shared_blocked(geo: &Geometry, blocked: &[f32], i: usize) -> f32 {
    let g = &geo.grid.params;
    let s = &geo.splats[i];
    let centre = Vec3::from(s.center);
    let normal = Vec3::from(s.normal);
    let reach = (SHARE_REACH * s.radius).min(SHARE_CELLS * g.cell_size);
    let top = IVec3::new(g.dims[0] as i32, g.dims[1] as i32, g.dims[2] as i32) - 1;
    let lo = point_cell(centre - Vec3::splat(reach), g).clamp(IVec3::ZERO, top);
    let hi = point_cell(centre + Vec3::splat(reach), g).clamp(IVec3::ZERO, top);
    let (mut sum, mut count) = (0.0f32, 0u32);
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                let c = IVec3::new(x, y, z);
                let ci = (c.x + (g.dims[0] as i32) * (c.y + (g.dims[1] as i32) * c.z)) as usize;
                for e in geo.grid.cell_start[ci]..geo.grid.cell_start[ci + 1] {
                    let j = geo.grid.cell_splats[e as usize] as usize;
                    let t = &geo.splats[j];
                    let d = Vec3::from(t.center) - centre;
                    if d.dot(d) <= reach * reach
                        && Vec3::from(t.normal).dot(normal) >= SHARE_COS
                        && point_cell(Vec3::from(t.center), g) == c
                    {
                        sum += blocked[j];
                        count += 1;
                    }
                }
            }
        }
    }
    if count > 0 {
        sum / count as f32
    } else {
        blocked[i]
    }
}

/// Adds the environment light's part to `direct` and writes its `visibility` (`share`).
pub fn direct_share(
    params: &DirectParams,
    lights: &[Light],
    (direct, visibility, blocked): (&mut [[f32; 4]], &mut [f32], &[f32]),
    geo: &Geometry,
) {
    let lc = params.light_count as usize;
    let count = params.splat_count as usize;
    let Some((li, l)) = (lights.iter().enumerate()).find(|(_, l)| l.kind == light_kind::ENVIRONMENT)
    else {
        return;
    };
    let opens: Vec<f32> = (0..count)
        .into_par_iter()
        .map(|i| (1.0 - shared_blocked(geo, blocked, i)).clamp(0.0, 1.0))
        .collect();
    for (i, open) in opens.into_iter().enumerate() {
        let e = sky_irradiance(geo.sky, l, Vec3::from(geo.splats[i].normal)) * open;
        direct[i] = (Vec3::from_slice(&direct[i][..3]) + e).extend(0.0).to_array();
        visibility[i * lc + li] = open;
    }
}

/// The executor's entry: `direct_bake`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let lights = b.get(1)?;
    let mut direct = b.get_mut(2)?;
    let mut visibility = b.get_mut(3)?;
    let order = b.get(4)?;
    let mut blocked = b.get_mut(5)?;
    let out = (
        view_mut(&mut direct),
        view_mut(&mut visibility),
        view_mut(&mut blocked),
    );
    direct_bake(&p, view(&lights), view(&order), out, geo);
    Ok(())
}

/// `share`'s entry.
pub fn dispatch_share(b: &Bindings, geo: &Geometry, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let lights = b.get(1)?;
    let mut direct = b.get_mut(2)?;
    let mut visibility = b.get_mut(3)?;
    let blocked = b.get(5)?;
    let out = (view_mut(&mut direct), view_mut(&mut visibility), view(&blocked));
    direct_share(&p, view(&lights), out, geo);
    Ok(())
}

/// This file's rows of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::DirectBake,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
    MirrorRow {
        stage: Stage::DirectBake,
        entry: "share",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch_share)),
    },
];
