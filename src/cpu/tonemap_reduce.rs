//! Mirror of `wgsl/tonemap_reduce.wgsl`: per-block (Σ log(ε + Y), count) in the same order.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec2;

use crate::shared::tone::log_luminance;
use crate::types::ToneParams;

pub const WG: u32 = 256;
pub const ITEMS: u32 = 8;
pub const BLOCK: u32 = WG * ITEMS;

pub fn tonemap_reduce(
    tone: &ToneParams,
    hdr: &[[f32; 4]],
    sums_in: &[[f32; 2]],
    sums_out: &mut [[f32; 2]],
    groups: u32,
) {
    let value = |i: u32| -> Vec2 {
        if tone.level == 0 {
            let c = hdr[i as usize];
            return log_luminance(glam::Vec3::new(c[0], c[1], c[2]), tone.epsilon);
        }
        Vec2::from(sums_in[i as usize])
    };
    let mut partial = [Vec2::ZERO; WG as usize];
    for block in 0..groups {
        if block * BLOCK >= tone.count {
            continue;
        }
        for lid in 0..WG {
            let base = block * BLOCK + lid * ITEMS;
            let mut sum = Vec2::ZERO;
            for k in 0..ITEMS {
                if base + k < tone.count {
                    sum += value(base + k);
                }
            }
            partial[lid as usize] = sum;
        }
        let mut stride = WG / 2;
        while stride > 0 {
            for lid in 0..stride as usize {
                partial[lid] += partial[lid + stride as usize];
            }
            stride >>= 1;
        }
        sums_out[block as usize] = partial[0].into();
    }
}

/// The executor's entry: `tonemap_reduce`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let hdr = b.get(1)?;
    let sums_in = b.get(2)?;
    let mut sums_out = b.get_mut(3)?;
    let out = view_mut(&mut sums_out);
    tonemap_reduce(&p, view(&hdr), view(&sums_in), out, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::TonemapReduce,
        entry: "main",
        workgroup_size: Some(WG),
        items: ITEMS,
        run: Some(Mirror::Plain(dispatch)),
    },
];
