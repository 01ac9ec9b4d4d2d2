//! Mirror of `wgsl/present.wgsl`: the colour the window's pixel (x, y) is written with, from
//! the tone-mapped image's packed sRGB bytes (filtered bilinearly where the image is smaller
//! than the target), decoded to linear for an sRGB surface.

use super::MirrorRow;
use crate::shaders::Stage;
use glam::{Vec2, Vec3, Vec4};

use crate::types::PresentParams;

pub fn srgb_to_linear(c: Vec3) -> Vec3 {
    let f = |v: f32| {
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

/// The image's pixel (x, y), clamped to its edges, as display values in [0, 1].
fn texel(params: &PresentParams, rgba: &[u32], x: i32, y: i32) -> Vec4 {
    let p = rgba[clamped(params, x, y)];
    Vec4::new(
        (p & 0xff) as f32,
        ((p >> 8) & 0xff) as f32,
        ((p >> 16) & 0xff) as f32,
        255.0,
    ) / 255.0
}

/// The index of the image's pixel (x, y), clamped to its edges.
fn clamped(params: &PresentParams, x: i32, y: i32) -> usize {
    let last = (
        params.image_width as i32 - 1,
        params.image_height as i32 - 1,
    );
    let (x, y) = (x.clamp(0, last.0) as u32, y.clamp(0, last.1) as u32);
    (y * params.image_width + x) as usize
}

/// The image filtered bilinearly at the target's pixel whose centre is `pixel` (x + 0.5,
/// y + 0.5): at equal sizes exactly the image's pixel (x, y).
fn bilinear(params: &PresentParams, pixel: Vec2, texel: impl Fn(i32, i32) -> Vec4) -> Vec4 {
    let image = Vec2::new(params.image_width as f32, params.image_height as f32);
    let target = Vec2::new(params.target_width as f32, params.target_height as f32);
    let s = pixel * (image / target) - Vec2::splat(0.5);
    let f = s.floor();
    let t = s - f;
    let (x, y) = (f.x as i32, f.y as i32);
    let top = texel(x, y).lerp(texel(x + 1, y), t.x);
    let bottom = texel(x, y + 1).lerp(texel(x + 1, y + 1), t.x);
    top.lerp(bottom, t.y)
}

/// The centre of the target's pixel `i` (rows from the top).
fn centre(params: &PresentParams, i: u32) -> Vec2 {
    let width = params.target_width;
    Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5)
}

/// The colour of the target's pixel whose centre is `pixel`.
fn fs_main(params: &PresentParams, rgba: &[u32], pixel: Vec2) -> [f32; 4] {
    let c = bilinear(params, pixel, |x, y| texel(params, rgba, x, y)).truncate();
    let c = if params.decode != 0 {
        srgb_to_linear(c)
    } else {
        c
    };
    c.extend(1.0).to_array()
}

/// The target's pixels (rows from the top) for an image of packed pixels.
pub fn present(params: &PresentParams, rgba: &[u32]) -> Vec<[f32; 4]> {
    (0..params.target_width * params.target_height)
        .map(|i| fs_main(params, rgba, centre(params, i)))
        .collect()
}

/// An HDR image (linear radiance) of `params`' image size upsampled to its target size with
/// the present pass's bilinear weights: what a moving frame drawn at a lower internal
/// resolution shows, for measuring it against a still image of the window's size.
pub fn upsample(params: &PresentParams, hdr: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let texel = |x, y| Vec4::from(hdr[clamped(params, x, y)]);
    (0..params.target_width * params.target_height)
        .map(|i| bilinear(params, centre(params, i), texel).to_array())
        .collect()
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::Present,
        entry: "main",
        workgroup_size: None,
        items: 1,
        run: None,
    },
];
