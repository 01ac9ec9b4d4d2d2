//! Mirror of `wgsl/splat_shade.wgsl`: per splat `splat_select` listed, the radiance it sends
//! towards the eye from its centre by its indirect and baked direct light; 0 for the others
//! (the device leaves their slots as they were; nothing draws them). A glossy splat drawn as a
//! merged disk is shaded with the mean of the normals it stands for, its lobe widened by their
//! spread.

use super::MirrorRow;
use crate::shaders::Stage;
use glam::Vec3;
use rayon::prelude::*;

use super::splat_shading::{Shading, glossy_lobe};
use crate::shared::splat::{lod_normal, lod_roughness};
use crate::types::{Camera, Material, Splat};

pub const WG: u32 = 64;

pub fn splat_shade(
    cam: &Camera,
    splats: &[Splat],
    materials: &[Material],
    shading: &Shading,
    (selected, normals): (&[u32], &[u32]),
) -> Vec<[f32; 4]> {
    let eye = Vec3::from(cam.eye);
    let shade = |&i: &u32| {
        let s = &splats[i as usize];
        let centre = Vec3::from(s.center);
        let wo = (eye - centre).normalize();
        let mut m = materials[s.material as usize];
        let mut shaded = *s;
        // Only where drawn with the level of detail, and only glossy splats (see WGSL).
        if cam.lod > 0.0 && glossy_lobe(&m) {
            let word = normals[i as usize];
            if word != 0 {
                m.roughness = lod_roughness(m.roughness, word);
                shaded.normal = lod_normal(word, Vec3::from(s.normal)).to_array();
            }
        }
        let s = &shaded;
        let l = shading.indirect(i, s, &m, wo) + shading.baked_direct(i, s, &m, centre, wo);
        (i, l.extend(0.0).to_array())
    };
    let mut out = vec![[0.0; 4]; splats.len()];
    for (i, l) in selected.par_iter().map(shade).collect::<Vec<_>>() {
        out[i as usize] = l;
    }
    out
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatShade,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
];
