//! Mirror of `wgsl/splat_shade.wgsl`: per splat, the radiance it sends towards the eye from its
//! centre by its indirect and baked direct light; 0 for splats turned away or outside the view.

use glam::Vec3;
use rayon::prelude::*;

use super::splat_shading::Shading;
use crate::shared::splat::{faces_camera, in_view};
use crate::types::{Camera, Material, Splat};

pub const WG: u32 = 64;

pub fn splat_shade(
    cam: &Camera,
    splats: &[Splat],
    materials: &[Material],
    shading: &Shading,
) -> Vec<[f32; 4]> {
    let eye = Vec3::from(cam.eye);
    let shade = |(i, s): (usize, &Splat)| {
        if !(faces_camera(s, eye) && in_view(cam, s)) {
            return [0.0; 4];
        }
        let centre = Vec3::from(s.center);
        let wo = (eye - centre).normalize();
        let m = &materials[s.material as usize];
        let i = i as u32;
        let l = shading.indirect(i, s, m, wo) + shading.baked_direct(i, s, m, centre, wo);
        l.extend(0.0).to_array()
    };
    splats.par_iter().enumerate().map(shade).collect()
}
