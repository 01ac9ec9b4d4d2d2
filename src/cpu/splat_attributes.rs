//! Mirror of `wgsl/splat_attributes.wgsl`: the splats within the depth tolerance add their
//! weighted attributes into four targets, in draw order per pixel (as the GPU blends).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec3, Vec4};

use super::splat_visibility::{TILE, Tiles, gather, raster};
use crate::shared::lobe_brdf::{lobe_specular, norm_at, norm_lookup};
use crate::shared::sampling::PI;
use crate::shared::splat::{
    SHOW_INDIRECT_DIFFUSE, SHOW_INDIRECT_SPECULAR, covers, lobe_beta2, pixel_ray, splat_hit,
    splat_weight, view_depth,
};
use crate::types::{Camera, Lobe, Material, ShadeParams, Splat, SplatLight};

/// The four blended targets of the attribute pass (see the WGSL file for what each holds).
#[derive(Clone, Debug, Default)]
pub struct Attributes {
    pub radiance: Vec<[f32; 4]>,
    pub geometry: Vec<[f32; 4]>,
    pub diffuse: Vec<[f32; 4]>,
    pub specular: Vec<[f32; 4]>,
}

#[allow(clippy::too_many_arguments)]
/// The hemispherical integral of a lobe of width `beta2` about `axis` (`lobe_norms`).
fn lobe_norm(lobe_norms: &[f32], n: Vec3, axis: Vec3, beta2: f32) -> f32 {
    norm_at(lobe_norms, norm_lookup(n.dot(axis), beta2))
}

#[allow(clippy::too_many_arguments)]
fn indirect(
    params: &ShadeParams,
    splat_light: &[SplatLight],
    lobes: &[Lobe],
    lobe_norms: &[f32],
    i: u32,
    s: &Splat,
    m: &Material,
    wo: Vec3,
) -> Vec3 {
    let light = &splat_light[i as usize];
    let mut spec = Vec3::ZERO;
    let first = light.first_lobe;
    let shown = if params.show & SHOW_INDIRECT_SPECULAR != 0 {
        light.lobes
    } else {
        0
    };
    for k in 0..shown {
        let lobe = &lobes[(first + k) as usize];
        let beta2 = lobe_beta2(params.family, lobe.sharpness);
        let (n, axis) = (Vec3::from(s.normal), Vec3::from(lobe.axis));
        let norm = lobe_norm(lobe_norms, n, axis, beta2);
        spec += Vec3::from(lobe.irradiance) * lobe_specular(n, wo, axis, m.roughness, beta2, norm);
    }
    let diffuse = if params.show & SHOW_INDIRECT_DIFFUSE != 0 {
        Vec3::from(s.diffuse) * (Vec3::from(light.irradiance) / PI)
    } else {
        Vec3::ZERO
    };
    diffuse + Vec3::from(m.specular) * spec
}

#[allow(clippy::too_many_arguments)]
pub fn splat_attributes(
    cam: &Camera,
    splats: &[Splat],
    params: &ShadeParams,
    materials: &[Material],
    splat_light: &[SplatLight],
    lobes: &[Lobe],
    lobe_norms: &[f32],
    depth: &[f32],
    tiles: &Tiles,
) -> Attributes {
    let eye = Vec3::from(cam.eye);
    let forward = Vec3::from(cam.forward);
    let width = tiles.width as usize;
    let blocks = raster(
        tiles,
        || vec![[Vec4::ZERO; 4]; (TILE * TILE) as usize],
        |sums, tile, i, local, centre| {
            let s = &splats[i as usize];
            let d = pixel_ray(cam, centre);
            let h = splat_hit(s, eye, d);
            if !covers(cam, h, d) {
                return;
            }
            // Depth test `GreaterEqual` against the visibility pass, no write.
            let (x, y) = (
                tile.x0 as usize + local % TILE as usize,
                tile.y0 as usize + local / TILE as usize,
            );
            if !(view_depth(cam, h.t * d.dot(forward)) >= depth[y * width + x]) {
                return;
            }
            let w = splat_weight(h.q);
            let m = &materials[s.material as usize];
            let gloss = (m.specular[0] + m.specular[1] + m.specular[2]) * (1.0 / 3.0);
            let out = [
                w * indirect(params, splat_light, lobes, lobe_norms, i, s, m, -d).extend(1.0),
                w * Vec3::from(s.normal).extend(h.t),
                w * Vec3::from(s.diffuse).extend(gloss * m.roughness),
                w * Vec3::from(m.specular).extend(gloss),
            ];
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
