//! Mirror of `wgsl/grid_cone.wgsl`: each listed cell's facing cone, in the upper bits of its
//! distance word.
// `!(x > y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use crate::grid::{CONE_MARGIN, CONE_STEPS, DIST_MASK, cone_axis, cone_axis_encode};
use crate::types::{GridParams, Splat};
use glam::Vec3;
use rayon::prelude::*;

pub const WG: u32 = 64;

pub fn grid_cone(
    grid: &GridParams,
    splats: &[Splat],
    cell_start: &[u32],
    cell_splats: &[u32],
    cell_dist: &mut [u32],
    groups: u32,
) {
    let invocations = (groups * WG).min(grid.cell_count) as usize;
    // Each cell's invocation writes its own word alone.
    cell_dist[..invocations]
        .par_iter_mut()
        .enumerate()
        .for_each(|(c, word)| {
            let list = &cell_splats[cell_start[c] as usize..cell_start[c + 1] as usize];
            let normal = |&i: &u32| Vec3::from(splats[i as usize].normal);
            let mut sum = Vec3::ZERO;
            for n in list.iter().map(normal) {
                sum += n;
            }
            if !(sum.abs().element_sum() > 0.0) {
                return;
            }
            let code = cone_axis_encode(sum);
            let axis = cone_axis(code);
            let mut cos_min = 1.0f32;
            for n in list.iter().map(normal) {
                cos_min = cos_min.min(axis.dot(n));
            }
            let cos_t = cos_min - CONE_MARGIN;
            if !(cos_t > 0.0) {
                return;
            }
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let open = ((1.0 - sin_t) * CONE_STEPS).floor().clamp(0.0, CONE_STEPS) as u32;
            *word = (*word & DIST_MASK) | code | (open << 24);
        });
}

/// The executor's entry: `grid_cone`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let grid = b.param(0)?;
    let splats = b.get(1)?;
    let cell_start = b.get(2)?;
    let cell_splats = b.get(3)?;
    let mut cell_dist = b.get_mut(4)?;
    grid_cone(
        &grid,
        view(&splats),
        &cell_start,
        &cell_splats,
        &mut cell_dist,
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::GridCone,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
