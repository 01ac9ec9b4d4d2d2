//! Mirror of `wgsl/splat_attributes.wgsl`: the splats within the depth tolerance add their
//! weighted attributes into four targets, in draw order per pixel (as the GPU blends).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::MirrorRow;
use crate::shaders::Stage;
use glam::{Vec3, Vec4};

use super::splat_shading::Shading;
use super::splat_visibility::{TILE, Tiles, Visible, gather, raster};
use crate::shared::splat::{
    covers, drawn_keeps, pixel_ray, same_surface, splat_hit, splat_weight, view_depth,
};
use crate::types::{Camera, DIRECT_BAKED, Material, Splat, SurfaceClip};

/// The four blended targets of the attribute pass (see the WGSL file for what each holds).
#[derive(Clone, Debug, Default)]
pub struct Attributes {
    pub radiance: Vec<[f32; 4]>,
    pub geometry: Vec<[f32; 4]>,
    pub diffuse: Vec<[f32; 4]>,
    pub specular: Vec<[f32; 4]>,
}

#[allow(clippy::too_many_arguments)]
pub fn splat_attributes(
    cam: &Camera,
    splats: &[Splat],
    clips: &[SurfaceClip],
    materials: &[Material],
    shading: &Shading,
    shaded: &[[f32; 4]],
    visible: &[Visible],
    tiles: &Tiles,
) -> Attributes {
    let eye = Vec3::from(cam.eye);
    let forward = Vec3::from(cam.forward);
    let width = tiles.width as usize;
    // `fs_baked` blends the first two targets only (the shade pass reads no more), and the
    // radiance `splat_shade` gave the splat.
    let baked = shading.params.direct == DIRECT_BAKED;
    let blocks = raster(
        tiles,
        || vec![[Vec4::ZERO; 4]; (TILE * TILE) as usize],
        |sums, tile, i, local, centre| {
            let s = &splats[i as usize];
            let d = pixel_ray(cam, centre);
            let h = splat_hit(s, eye, d);
            if !covers(cam, h, d) || !drawn_keeps(clips, s, eye + h.t * d) {
                return;
            }
            // Depth test `GreaterEqual` against the visibility pass, no write.
            let (x, y) = (
                tile.x0 as usize + local % TILE as usize,
                tile.y0 as usize + local / TILE as usize,
            );
            // ... and a splat of the surface the pixel sees (the front target).
            let seen = visible[y * width + x];
            if !(view_depth(cam, h.t * d.dot(forward)) >= seen.depth)
                || !same_surface(seen.front, Vec3::from(s.normal))
            {
                return;
            }
            let w = splat_weight(h.q);
            let m = &materials[s.material as usize];
            let gloss = (m.specular[0] + m.specular[1] + m.specular[2]) * (1.0 / 3.0);
            let radiance = match baked {
                true => Vec4::from(shaded[i as usize]).truncate(),
                false => shading.indirect(i, s, m, -d),
            };
            let mut out = [
                Vec4::ZERO,
                w * Vec3::from(s.normal).extend(h.t),
                w * Vec3::from(s.diffuse).extend(gloss * m.roughness),
                w * Vec3::from(m.specular).extend(gloss),
            ];
            if baked {
                out[2] = Vec4::ZERO;
                out[3] = Vec4::ZERO;
            }
            out[0] = w * radiance.extend(1.0);
            for (sum, v) in sums[local].iter_mut().zip(out) {
                *sum += v;
            }
        },
    );
    let target = |k: usize| {
        let blocks: Vec<_> = blocks
            .iter()
            .map(|(r, b)| (*r, b.iter().map(|px| px[k].to_array()).collect()))
            .collect();
        gather(tiles, &blocks)
    };
    Attributes {
        radiance: target(0),
        geometry: target(1),
        diffuse: target(2),
        specular: target(3),
    }
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatAttributes,
        entry: "main",
        workgroup_size: None,
        items: 1,
        run: None,
    },
];
