//! Mirror of `wgsl/grid_distance.wgsl`: one axis pass of the capped Chebyshev distance field.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::Bindings;
use crate::error::Result;
use crate::grid::DIST_CAP;
use crate::types::{DistanceParams, GridParams};
use rayon::prelude::*;

pub const WG: u32 = 64;

fn value_at(params: &DistanceParams, cell_start: &[u32], src: &[u32], c: usize) -> u32 {
    if params.axis == 0 {
        return if cell_start[c + 1] > cell_start[c] {
            0
        } else {
            DIST_CAP
        };
    }
    src[c]
}

pub fn grid_distance(
    params: &DistanceParams,
    grid: &GridParams,
    cell_start: &[u32],
    src: &[u32],
    dst: &mut [u32],
    groups: u32,
) {
    let [dx, dy, _] = grid.dims;
    let invocations = (groups * WG).min(grid.cell_count) as usize;
    // Each cell's invocation writes its own cell alone: the cells run a z-plane a task, each
    // plane in the invocations' order (one cell at a time, the three passes took 5.8 s on a
    // 10 M-splat terrain's 2^24 cells; 3.1–3.3 s so).
    let plane = (dx * dy) as usize;
    dst[..invocations]
        .par_chunks_mut(plane)
        .enumerate()
        .for_each(|(z, out)| {
            for (k, slot) in out.iter_mut().enumerate() {
                let c = (z * plane + k) as u32;
                let coord = [c % dx, (c / dx) % dy, c / (dx * dy)];
                let strides = [1, dx, dx * dy];
                let axis = params.axis as usize;
                let pos = coord[axis] as i32;
                let len = grid.dims[axis] as i32;
                let stride = strides[axis] as i32;
                let mut best = DIST_CAP;
                for o in -(DIST_CAP as i32)..=DIST_CAP as i32 {
                    let q = pos + o;
                    if q >= 0 && q < len {
                        let v = value_at(params, cell_start, src, (c as i32 + o * stride) as usize);
                        best = best.min((o.unsigned_abs()).max(v));
                    }
                }
                *slot = best;
            }
        });
}

/// The executor's entry: `grid_distance`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let pass = b.param(0)?;
    let grid = b.param(1)?;
    let cell_start = b.get(2)?;
    let src = b.get(3)?;
    let mut dst = b.get_mut(4)?;
    grid_distance(&pass, &grid, &cell_start, &src, &mut dst, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::GridDistance,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
