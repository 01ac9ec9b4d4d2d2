//! Mirror of `wgsl/tonemap_apply.wgsl`: every pixel through the operator, as sRGB bytes.

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
