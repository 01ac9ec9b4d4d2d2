//! Mirror of `wgsl/splat_shade.wgsl`: per splat `splat_select` listed, the radiance it sends
//! towards the eye from its centre by its indirect and baked direct light; 0 for the others
//! (the device leaves their slots as they were; nothing draws them).

use glam::Vec3;
use rayon::prelude::*;

use super::splat_shading::Shading;
use crate::types::{Camera, Material, Splat};

pub const WG: u32 = 64;

pub fn splat_shade(
    cam: &Camera,
    splats: &[Splat],
    materials: &[Material],
    shading: &Shading,
    selected: &[u32],
) -> Vec<[f32; 4]> {
    let eye = Vec3::from(cam.eye);
    let shade = |&i: &u32| {
        let s = &splats[i as usize];
        let centre = Vec3::from(s.center);
        let wo = (eye - centre).normalize();
        let m = &materials[s.material as usize];
        let l = shading.indirect(i, s, m, wo) + shading.baked_direct(i, s, m, centre, wo);
        (i, l.extend(0.0).to_array())
    };
    let mut out = vec![[0.0; 4]; splats.len()];
    for (i, l) in selected.par_iter().map(shade).collect::<Vec<_>>() {
        out[i as usize] = l;
    }
    out
}
