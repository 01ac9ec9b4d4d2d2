//! Mirror of `wgsl/splat_select.wgsl`: the splats a frame of baked direct light draws (facing
//! the eye, inside the view, drawn at their level of detail), in index order (the device's
//! order is its atomic counter's; what is listed is the same), and the radius each is drawn
//! with (0: not drawn).

use glam::Vec3;
use rayon::prelude::*;

use crate::shared::splat::{faces_camera, in_view, lod_radius};
use crate::types::{Camera, Splat, SplatLod};

pub const WG: u32 = 64;

pub struct Selection {
    pub selected: Vec<u32>,
    pub drawn: Vec<f32>,
}

pub fn splat_select(cam: &Camera, splats: &[Splat], lods: &[SplatLod]) -> Selection {
    let eye = Vec3::from(cam.eye);
    let drawn: Vec<f32> = splats
        .par_iter()
        .zip(lods)
        .map(|(s, lod)| {
            let s = Splat {
                radius: lod_radius(cam, s, lod),
                ..*s
            };
            match faces_camera(&s, eye) && s.radius > 0.0 && in_view(cam, &s) {
                true => s.radius,
                false => 0.0,
            }
        })
        .collect();
    let selected = (0..splats.len() as u32)
        .filter(|&i| drawn[i as usize] > 0.0)
        .collect();
    Selection { selected, drawn }
}

/// The splats as the raster passes draw them with the level of detail: each at the radius
/// `splat_select` chose, 0 for those it left out (`splat_bounds` gives them no pixels).
pub fn drawn_splats(splats: &[Splat], drawn: &[f32]) -> Vec<Splat> {
    splats
        .iter()
        .zip(drawn)
        .map(|(s, &radius)| Splat { radius, ..*s })
        .collect()
}
