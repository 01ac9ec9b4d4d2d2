//! Mirror of `wgsl/direct_bake.wgsl`: every splat's shadowed irradiance from the lights, and
//! each light's visibility, by shadow rays from the splat's centre.
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;

use crate::shared::lights::{area_point, sample_light, shadow_reach, strata_side};
use crate::shared::rng::pcg_hash;
use crate::shared::splat::SHADOW_RAY_BUDGET;
use crate::shared::trace::{Geometry, trace_ray};
use crate::types::{DirectParams, Light, NO_SPLAT};

pub const WG: u32 = 64;

/// Fills `direct` (one `[E, 0]` per splat) and `visibility` (splat × light), invocation k
/// taking splat `order[k]`.
pub fn direct_bake(
    params: &DirectParams,
    lights: &[Light],
    order: &[u32],
    direct: &mut [[f32; 4]],
    visibility: &mut [f32],
    geo: &Geometry,
) {
    let lc = params.light_count as usize;
    let count = params.splat_count as usize;
    if lc == 0 {
        direct[..count].fill([0.0; 4]);
        return;
    }
    // Invocation k writes its rows at k of two arrays, then each row goes to its splat's
    // place: a row collected an invocation (and a vector of its lights') cost two allocations
    // a splat, 10 M of them on a 10 M-splat scan.
    let order = &order[..count];
    let mut rows = vec![[0.0f32; 4]; count];
    let mut seen_rows = vec![0.0f32; count * lc];
    rows.par_iter_mut()
        .zip(seen_rows.par_chunks_mut(lc))
        .zip(order.par_iter())
        .for_each(|((out, seen_by), &i)| {
            let s = &geo.splats[i as usize];
            let (centre, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
            let o = centre + params.shadow_bias * normal;
            let key = pcg_hash(pcg_hash(params.seed).wrapping_add(i));
            let mut total = Vec3::ZERO;
            for ((li, l), seen) in lights.iter().enumerate().zip(seen_by.iter_mut()) {
                let li = li as u32;
                let n = strata_side(l.kind, params.samples);
                let (mut open, mut unshadowed) = (Vec3::ZERO, Vec3::ZERO);
                for j in 0..n * n {
                    let r = key.wrapping_add((li * n * n + j).wrapping_mul(2));
                    let uv = area_point(j, n, r, true);
                    let ls = sample_light(geo.sky, l, centre, normal, uv.x, uv.y);
                    let cos_i = normal.dot(ls.wi);
                    if !(cos_i > 0.0) || ls.e.cmple(Vec3::ZERO).all() {
                        continue;
                    }
                    let e = ls.e * cos_i;
                    unshadowed += e;
                    let mut budget = SHADOW_RAY_BUDGET;
                    let t_max = shadow_reach(l, o, ls.wi, ls.dist, params.shadow_bias);
                    let hit = trace_ray(geo, o, ls.wi, i, t_max, &mut budget);
                    if hit.splat == NO_SPLAT {
                        open += e;
                    }
                }
                total += open * (1.0 / (n * n) as f32);
                let seen_e = unshadowed.x + unshadowed.y + unshadowed.z;
                *seen = if seen_e > 0.0 {
                    (open.x + open.y + open.z) / seen_e
                } else {
                    1.0
                };
            }
            *out = total.extend(0.0).to_array();
        });
    for ((&i, row), seen) in order.iter().zip(rows).zip(seen_rows.chunks(lc)) {
        let i = i as usize;
        direct[i] = row;
        visibility[i * lc..(i + 1) * lc].copy_from_slice(seen);
    }
}

/// The executor's entry: `direct_bake`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let lights = b.get(1)?;
    let mut direct = b.get_mut(2)?;
    let mut visibility = b.get_mut(3)?;
    let order = b.get(4)?;
    let (direct, visibility) = (view_mut(&mut direct), view_mut(&mut visibility));
    direct_bake(&p, view(&lights), view(&order), direct, visibility, geo);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::DirectBake,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
];
