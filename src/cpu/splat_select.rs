//! Mirror of `wgsl/splat_select.wgsl`: the splats a frame of baked direct light draws (facing
//! the eye, inside the view, kept by the level of detail), in index order (the device's order
//! is its atomic counter's; what is listed is the same).

use glam::Vec3;
use rayon::prelude::*;

use crate::shared::splat::{drawn_radius, faces_camera, in_view};
use crate::types::{Camera, Splat};

pub const WG: u32 = 64;

pub fn splat_select(cam: &Camera, splats: &[Splat]) -> Vec<u32> {
    let eye = Vec3::from(cam.eye);
    (0..splats.len() as u32)
        .into_par_iter()
        .filter(|&i| {
            let s = Splat {
                radius: drawn_radius(cam, &splats[i as usize], i),
                ..splats[i as usize]
            };
            faces_camera(&s, eye) && s.radius > 0.0 && in_view(cam, &s)
        })
        .collect()
}

/// The splats as the raster passes draw them this frame: each at its drawn radius, 0 for
/// those the level of detail leaves out (`splat_bounds` gives them no pixels).
pub fn drawn_splats(cam: &Camera, splats: &[Splat]) -> Vec<Splat> {
    splats
        .par_iter()
        .enumerate()
        .map(|(i, s)| Splat {
            radius: drawn_radius(cam, s, i as u32),
            ..*s
        })
        .collect()
}
