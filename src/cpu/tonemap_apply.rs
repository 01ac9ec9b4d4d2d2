//! Mirror of `wgsl/tonemap_apply.wgsl`: every pixel through the operator, as sRGB bytes.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::shared::tone::{pack_srgb, tone_map};
use crate::types::ToneParams;

pub const WG: u32 = 256;

pub fn tonemap_apply(tone: &ToneParams, hdr: &[[f32; 4]], log_sum: &[[f32; 2]], rgba: &mut [u32]) {
    let sum = Vec2::from(log_sum[0]);
    rgba.par_iter_mut()
        .enumerate()
        .take(tone.count as usize)
        .for_each(|(i, out)| {
            let c = hdr[i];
            *out = pack_srgb(tone_map(Vec3::new(c[0], c[1], c[2]), sum, tone));
        });
}

/// The executor's entry: `tonemap_apply`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let hdr = b.get(1)?;
    let log_sum = b.get(2)?;
    let mut rgba = b.get_mut(3)?;
    tonemap_apply(&p, view(&hdr), view(&log_sum), &mut rgba);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::TonemapApply,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
