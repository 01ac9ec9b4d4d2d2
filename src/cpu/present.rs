//! Mirror of `wgsl/present.wgsl`: the colour the window's pixel (x, y) is written with, from
//! the tone-mapped image's packed sRGB bytes, decoded to linear for an sRGB surface.

use glam::Vec3;

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

/// The window's pixels (rows from the top) for an image of `width × height` packed pixels.
pub fn present(params: [u32; 4], rgba: &[u32]) -> Vec<[f32; 4]> {
    let [width, height, decode, _] = params;
    (0..width * height)
        .map(|i| {
            let p = rgba[i as usize];
            let c = Vec3::new(
                (p & 0xff) as f32,
                ((p >> 8) & 0xff) as f32,
                ((p >> 16) & 0xff) as f32,
            ) / 255.0;
            let c = if decode != 0 { srgb_to_linear(c) } else { c };
            c.extend(1.0).to_array()
        })
        .collect()
}
