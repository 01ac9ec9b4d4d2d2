//! Mirror of `wgsl/splat_attributes.wgsl`: the splats within the depth tolerance add their
//! weighted attributes into four targets, in draw order per pixel (as the GPU blends).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec3, Vec4};

use super::splat_visibility::{TILE, Tiles, Visible, gather, raster};
use crate::shared::lights::{LightSample, MIN_ALPHA, area_point, sample_light};
use crate::shared::lobe_brdf::{lobe_specular, norm_at, norm_lookup};
use crate::shared::sampling::PI;
use crate::shared::splat::{
    SHOW_DIRECT_DIFFUSE, SHOW_DIRECT_SPECULAR, SHOW_INDIRECT_DIFFUSE, SHOW_INDIRECT_SPECULAR,
    covers, lobe_beta2, pixel_ray, same_surface, splat_hit, splat_weight, view_depth,
};
use crate::shared::ward::ward_specular;
use crate::types::{
    Camera, DIRECT_BAKED, Light, Lobe, Material, ShadeParams, Splat, SplatLight, light_kind,
};

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

fn specular_sample(n: Vec3, wo: Vec3, alpha: f32, ls: &LightSample) -> Vec3 {
    let cos_i = n.dot(ls.wi);
    if !(cos_i > 0.0) {
        return Vec3::ZERO;
    }
    ward_specular(n, ls.wi, wo, alpha) * ls.e * cos_i
}

/// The direct bake's results the attribute pass reads (`DIRECT_BAKED`).
#[derive(Clone, Copy)]
pub struct BakedDirect<'a> {
    pub lights: &'a [Light],
    pub direct: &'a [[f32; 4]],
    pub visibility: &'a [f32],
}

fn baked_direct(
    params: &ShadeParams,
    baked: &BakedDirect,
    i: u32,
    s: &Splat,
    m: &Material,
    p: Vec3,
    wo: Vec3,
) -> Vec3 {
    let mut out = Vec3::ZERO;
    if params.show & SHOW_DIRECT_DIFFUSE != 0 {
        out = Vec3::from(s.diffuse) * (Vec4::from(baked.direct[i as usize]).truncate() / PI);
    }
    let specular = Vec3::from(m.specular);
    let glossy = m.roughness >= MIN_ALPHA && specular.cmpgt(Vec3::ZERO).any();
    if params.show & SHOW_DIRECT_SPECULAR == 0 || !glossy {
        return out;
    }
    let normal = Vec3::from(s.normal);
    let mut spec = Vec3::ZERO;
    let lc = params.light_count;
    for (li, l) in baked.lights.iter().enumerate().take(lc as usize) {
        let vis = baked.visibility[(i * lc) as usize + li];
        if !(vis > 0.0) {
            continue;
        }
        if l.kind != light_kind::AREA {
            let ls = sample_light(l, p, 0.0, 0.0);
            spec += vis * specular_sample(normal, wo, m.roughness, &ls);
            continue;
        }
        let n = params.area_samples;
        let mut area_sum = Vec3::ZERO;
        for j in 0..n * n {
            let uv = area_point(j, n, 0, false);
            let ls = sample_light(l, p, uv.x, uv.y);
            area_sum += specular_sample(normal, wo, m.roughness, &ls);
        }
        spec += vis * area_sum * (1.0 / (n * n) as f32);
    }
    out + specular * spec
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
    baked: &BakedDirect,
    visible: &[Visible],
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
            let mut radiance = indirect(params, splat_light, lobes, lobe_norms, i, s, m, -d);
            // `fs_baked` blends the first two targets only; the shade pass reads no more.
            let mut out = [
                Vec4::ZERO,
                w * Vec3::from(s.normal).extend(h.t),
                w * Vec3::from(s.diffuse).extend(gloss * m.roughness),
                w * Vec3::from(m.specular).extend(gloss),
            ];
            if params.direct == DIRECT_BAKED {
                radiance += baked_direct(params, baked, i, s, m, eye + h.t * d, -d);
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
