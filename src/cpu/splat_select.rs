//! Mirror of `wgsl/splat_select.wgsl`: the radius each splat is drawn with in a frame of baked
//! direct light (facing the eye, inside the view, at its level of detail; 0: not drawn), and
//! each workgroup's count of drawn splats. `selection` adds `splat_list` for the list.

use glam::Vec3;
use rayon::prelude::*;

use crate::shared::splat::{faces_camera, in_view, lod_radius};
use crate::types::{Camera, Splat, SplatLod};

pub const WG: u32 = 64;

/// The drawn radii, and the count of each workgroup of `WG` splats.
pub fn splat_select(cam: &Camera, splats: &[Splat], lods: &[SplatLod]) -> (Vec<f32>, Vec<u32>) {
    let eye = Vec3::from(cam.eye);
    let drawn: Vec<f32> = splats
        .par_iter()
        .zip(lods)
        .map(|(s, lod)| {
            let mut s = *s;
            if cam.lod > 0.0 {
                s.radius = lod_radius(cam, &s, lod);
            }
            match faces_camera(&s, eye) && s.radius > 0.0 && in_view(cam, &s) {
                true => s.radius,
                false => 0.0,
            }
        })
        .collect();
    let counts = drawn
        .chunks(WG as usize)
        .map(|c| c.iter().filter(|&&r| r > 0.0).count() as u32)
        .collect();
    (drawn, counts)
}

/// What a frame of baked direct light draws: the splats in index order (`splat_list`), and
/// each splat's drawn radius.
pub struct Selection {
    pub selected: Vec<u32>,
    pub drawn: Vec<f32>,
}

/// `splat_select`, the scan of its counts and `splat_list`, as the device runs them.
pub fn selection(cam: &Camera, splats: &[Splat], lods: &[SplatLod]) -> Selection {
    let (drawn, counts) = splat_select(cam, splats, lods);
    let offsets: Vec<u32> = counts
        .iter()
        .scan(0, |sum, &c| {
            let first = *sum;
            *sum += c;
            Some(first)
        })
        .collect();
    let selected = super::splat_list::splat_list(&offsets, &drawn);
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
