//! Twin of `wgsl/shared/splat_shading.wgsl`: what a splat is shaded with, for the attribute
//! pass, the compute splatter and the per-splat shading of baked frames alike: the indirect
//! light from its lobes and irradiance, and its baked direct light.
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec3, Vec4};

use crate::shared::lights::{LightSample, MIN_ALPHA, area_point, sample_emitter, sky_radiance};
use crate::shared::lobe_brdf::{lobe_specular, norm_at, norm_lookup};
use crate::shared::sampling::{PI, frame_of};
use crate::shared::splat::{
    SHOW_DIRECT_DIFFUSE, SHOW_DIRECT_SPECULAR, SHOW_INDIRECT_DIFFUSE, SHOW_INDIRECT_SPECULAR,
    lobe_beta2,
};
use crate::shared::ward::{ward_sample, ward_specular};
use crate::types::{
    DIRECT_RAYS, Light, Lobe, Material, ShadeParams, Splat, SplatLight, light_kind, stratified,
};

/// The direct bake's results (`DIRECT_BAKED`): bindings 7–9 of the WGSL.
#[derive(Clone, Copy)]
pub struct BakedDirect<'a> {
    pub lights: &'a [Light],
    pub direct: &'a [[f32; 4]],
    pub visibility: &'a [f32],
    /// The environment light's map (`scene::sky::SkyTable`).
    pub sky: &'a [[f32; 4]],
}

/// Bindings 2–9 of the WGSL but the materials, which the callers index themselves.
#[derive(Clone, Copy)]
pub struct Shading<'a> {
    pub params: &'a ShadeParams,
    pub splat_light: &'a [SplatLight],
    pub lobes: &'a [Lobe],
    /// `lobe_norms::lobe_norms()`.
    pub lobe_norms: &'a [f32],
    pub baked: BakedDirect<'a>,
}

impl Shading<'_> {
    /// The hemispherical integral of a lobe of width `beta2` about `axis`.
    fn lobe_norm(&self, n: Vec3, axis: Vec3, beta2: f32) -> f32 {
        norm_at(self.lobe_norms, norm_lookup(n.dot(axis), beta2))
    }

    /// Radiance leaving splat `i` towards `wo` by the light its photons brought.
    pub fn indirect(&self, i: u32, s: &Splat, m: &Material, wo: Vec3) -> Vec3 {
        let params = self.params;
        let light = &self.splat_light[i as usize];
        let mut spec = Vec3::ZERO;
        let first = light.first_lobe;
        // With glossy rays the shade pass traces this part instead, where the BRDF can be sampled.
        let traced =
            params.glossy_rays > 0 && params.direct == DIRECT_RAYS && m.roughness >= MIN_ALPHA;
        let shown = if params.show & SHOW_INDIRECT_SPECULAR != 0 && !traced {
            light.lobes
        } else {
            0
        };
        for k in 0..shown {
            let lobe = &self.lobes[(first + k) as usize];
            let beta2 = lobe_beta2(params.family, lobe.sharpness);
            let (n, axis) = (Vec3::from(s.normal), Vec3::from(lobe.axis));
            let norm = self.lobe_norm(n, axis, beta2);
            spec +=
                Vec3::from(lobe.irradiance) * lobe_specular(n, wo, axis, m.roughness, beta2, norm);
        }
        let diffuse = if params.show & SHOW_INDIRECT_DIFFUSE != 0 {
            Vec3::from(s.diffuse) * (Vec3::from(light.irradiance) / PI)
        } else {
            Vec3::ZERO
        };
        diffuse + Vec3::from(m.specular) * spec
    }

    /// Radiance leaving splat `i` at `p` towards `wo` by the baked direct light.
    pub fn baked_direct(&self, i: u32, s: &Splat, m: &Material, p: Vec3, wo: Vec3) -> Vec3 {
        let (params, baked) = (self.params, &self.baked);
        let mut out = Vec3::ZERO;
        if params.show & SHOW_DIRECT_DIFFUSE != 0 {
            out = Vec3::from(s.diffuse) * (Vec4::from(baked.direct[i as usize]).truncate() / PI);
        }
        let specular = Vec3::from(m.specular);
        if params.show & SHOW_DIRECT_SPECULAR == 0 || !glossy_lobe(m) {
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
            if l.kind == light_kind::ENVIRONMENT {
                spec += vis * sky_specular(params, baked.sky, l, (normal, wo), m.roughness);
                continue;
            }
            if !stratified(l.kind) {
                let ls = sample_emitter(l, p, 0.0, 0.0);
                spec += vis * specular_sample(normal, wo, m.roughness, &ls);
                continue;
            }
            let n = params.area_samples;
            let mut area_sum = Vec3::ZERO;
            for j in 0..n * n {
                let uv = area_point(j, n, 0, false);
                let ls = sample_emitter(l, p, uv.x, uv.y);
                area_sum += specular_sample(normal, wo, m.roughness, &ls);
            }
            spec += vis * area_sum * (1.0 / (n * n) as f32);
        }
        out + specular * spec
    }
}

/// The specular light environment light `l` reflects towards `wo` at a surface of normal `n`
/// and roughness `alpha`, unshadowed (but for ρs): the sky along the Ward lobe's
/// `area_samples²` strata centres (`sky_specular` in WGSL says why).
fn sky_specular(
    params: &ShadeParams,
    sky: &[[f32; 4]],
    l: &Light,
    (n, wo): (Vec3, Vec3),
    alpha: f32,
) -> Vec3 {
    let f = frame_of(n);
    let k = params.area_samples;
    let mut sum = Vec3::ZERO;
    for j in 0..k * k {
        let uv = area_point(j, k, 0, false);
        let s = ward_sample(&f, wo, uv.x, uv.y, alpha);
        if s.weight > 0.0 {
            sum += s.weight * sky_radiance(sky, l, s.wo);
        }
    }
    sum * (1.0 / (k * k) as f32)
}

/// Whether material `m` reflects by a glossy lobe: a specular part, rough enough for Ward's
/// BRDF (the baked direct light's glossy part, and merged disks' normals in `splat_shade`).
pub fn glossy_lobe(m: &Material) -> bool {
    m.roughness >= MIN_ALPHA && Vec3::from(m.specular).cmpgt(Vec3::ZERO).any()
}

/// The specular light one light sample reflects towards `wo`, unshadowed.
fn specular_sample(n: Vec3, wo: Vec3, alpha: f32, ls: &LightSample) -> Vec3 {
    let cos_i = n.dot(ls.wi);
    if !(cos_i > 0.0) {
        return Vec3::ZERO;
    }
    ward_specular(n, ls.wi, wo, alpha) * ls.e * cos_i
}
