//! Mirror of `wgsl/shade.wgsl`: normalise the blended sums, add direct light by shadow rays
//! (unless it was baked), show area lights seen directly; linear HDR out, or a refinement
//! frame added to the running mean.
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::MirrorRow;
use crate::shaders::Stage;
use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::shared::lights::{
    LightSample, MIN_ALPHA, area_light_hit, area_point, escaped_radiance, light_first, light_pdf,
    sample_light, shadow_reach, strata_side, sun_solid_angle,
};
use crate::shared::rng::{pcg_hash, r2_point, r2_shift};
use crate::shared::sampling::{PI, frame_of, power_heuristic};
use crate::shared::splat::{
    SHADOW_RAY_BUDGET, SHOW_DIRECT_DIFFUSE, SHOW_DIRECT_SPECULAR, SHOW_INDIRECT_SPECULAR,
    hit_albedo, pixel_ray,
};
use crate::shared::trace::{FAR, Geometry, trace_ray};
use crate::shared::ward::{ward_pdf, ward_sample, ward_specular};
use crate::types::{
    Camera, DIRECT_RAYS, Light, Material, NO_SPLAT, ShadeParams, SplatLight, light_flags,
    light_kind, stratified,
};

use super::splat_attributes::Attributes;

pub const WG: u32 = 64;
struct Surface {
    p: Vec3,
    n: Vec3,
    wo: Vec3,
    rho_d: Vec3,
    rho_s: Vec3,
    alpha: f32,
}

fn shade_sample(
    params: &ShadeParams,
    geo: &Geometry,
    sf: &Surface,
    l: &Light,
    ls: &LightSample,
    spec_weight: f32,
) -> Vec3 {
    let cos_i = sf.n.dot(ls.wi);
    if !(cos_i > 0.0) || ls.e.cmple(Vec3::ZERO).all() {
        return Vec3::ZERO;
    }
    let o = sf.p + params.shadow_bias * sf.n;
    let mut budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(
        geo,
        o,
        ls.wi,
        NO_SPLAT,
        shadow_reach(l, o, ls.wi, ls.dist, params.shadow_bias),
        &mut budget,
    );
    if hit.splat != NO_SPLAT {
        return Vec3::ZERO;
    }
    let mut f = sf.rho_d / PI;
    if sf.alpha >= MIN_ALPHA {
        f += spec_weight * sf.rho_s * ward_specular(sf.n, ls.wi, sf.wo, sf.alpha);
    }
    f * ls.e * cos_i
}

fn area_pdf(sky: &[[f32; 4]], l: &Light, (n, wi): (Vec3, Vec3), dist: f32, count: f32) -> f32 {
    count * light_pdf(sky, l, (n, wi), dist)
}

fn narrow_lobe(sf: &Surface, l: &Light) -> bool {
    if !(sf.alpha >= MIN_ALPHA) || sf.rho_s.cmple(Vec3::ZERO).all() {
        return false;
    }
    // A sky surrounds every lobe; the sun's disk is narrower than nearly all.
    if l.kind == light_kind::ENVIRONMENT {
        return true;
    }
    if l.kind == light_kind::SUN {
        return 4.0 * PI * sf.alpha * sf.alpha < sun_solid_angle(l);
    }
    let centre = Vec3::from(l.position) + 0.5 * (Vec3::from(l.edge_u) + Vec3::from(l.edge_v));
    let to = centre - sf.p;
    let d2 = to.dot(to);
    let cos_l = -to.dot(Vec3::from(l.direction)) / d2.sqrt();
    4.0 * PI * sf.alpha * sf.alpha * d2 < l.area * cos_l.max(0.0)
}

fn specular_by_brdf(
    params: &ShadeParams,
    geo: &Geometry,
    sf: &Surface,
    l: &Light,
    (u1, u2): (f32, f32),
    count: f32,
) -> Vec3 {
    let s = ward_sample(&frame_of(sf.n), sf.wo, u1, u2, sf.alpha);
    let wi = s.wo;
    let cos_i = sf.n.dot(wi);
    if !(s.weight > 0.0) || !(cos_i > 0.0) {
        return Vec3::ZERO;
    }
    let o = sf.p + params.shadow_bias * sf.n;
    // An area light where the ray meets its face; a sky or the sun past everything.
    let (t, radiance) = if l.kind == light_kind::AREA {
        let area_radiance = Vec3::from(l.power) / (PI * l.area);
        (area_light_hit(l, o, wi), area_radiance)
    } else {
        (FAR, escaped_radiance(geo.sky, l, wi))
    };
    if !(t > 0.0) || radiance.cmple(Vec3::ZERO).all() {
        return Vec3::ZERO;
    }
    let mut budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(geo, o, wi, NO_SPLAT, t - params.shadow_bias, &mut budget);
    if hit.splat != NO_SPLAT {
        return Vec3::ZERO;
    }
    let pdf_brdf = ward_pdf(sf.n, sf.wo, wi, sf.alpha);
    let pdf_light = area_pdf(geo.sky, l, (sf.n, wi), t, count);
    let scale = pdf_brdf / (pdf_brdf * pdf_brdf + pdf_light * pdf_light);
    sf.rho_s * ward_specular(sf.n, wi, sf.wo, sf.alpha) * radiance * (cos_i * scale)
}

fn direct(
    params: &ShadeParams,
    geo: &Geometry,
    lights: &[Light],
    sf: &Surface,
    pixel: u32,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let key = pcg_hash(pcg_hash(params.seed).wrapping_add(pixel));
    for (li, l) in lights.iter().enumerate().take(params.light_count as usize) {
        if !stratified(l.kind) {
            let ls = sample_light(geo.sky, l, sf.p, sf.n, 0.0, 0.0);
            sum += shade_sample(params, geo, sf, l, &ls, 1.0);
            continue;
        }
        // This frame's strata of the n × n grid: all of them, or a refinement frame's share;
        // a lobe narrower than the light adds one sample of its own (multiple importance
        // sampling; see `wgsl/shade.wgsl`).
        // A sky's grid is finer than an area light's: each frame takes as many more strata.
        let n = strata_side(l.kind, params.area_samples);
        let finer = (n * n) / (params.area_samples * params.area_samples);
        let area_count = params.area_count * finer;
        let count = area_count as f32;
        let glossy = narrow_lobe(sf, l);
        let mut area_sum = Vec3::ZERO;
        // The strata turned by a per-pixel offset, so that the point in the pixel and the
        // point on the light are not tied (`wgsl/shade.wgsl`).
        let turn = pcg_hash(key) % (n * n);
        for k in 0..area_count {
            let j = (params.area_first * finer + k + turn) % (n * n);
            let r = key.wrapping_add((li as u32 * n * n + j).wrapping_mul(2));
            let uv = area_point(j, n, r, true);
            let ls = sample_light(geo.sky, l, sf.p, sf.n, uv.x, uv.y);
            let mut w = 1.0;
            if glossy {
                let pdf_brdf = ward_pdf(sf.n, sf.wo, ls.wi, sf.alpha);
                w = power_heuristic(area_pdf(geo.sky, l, (sf.n, ls.wi), ls.dist, count), pdf_brdf);
            }
            area_sum += shade_sample(params, geo, sf, l, &ls, w);
        }
        sum += area_sum * (1.0 / count);
        if glossy {
            // One point a refinement frame of the pixel's R2 sequence.
            let shift = r2_shift(
                key.wrapping_add((params.light_count * n * n + li as u32).wrapping_mul(2)),
            );
            let u = r2_point(params.sample, shift);
            sum += specular_by_brdf(params, geo, sf, l, u, count);
        }
    }
    sum
}

/// Keeps the glossy rays' random numbers apart from the shadow rays'.
const GLOSSY_SALT: u32 = 0x9e37_79b9;

/// The baked light the glossy rays read at their hits: each splat's photon irradiance and its
/// direct bake (`direct_light`, xyz).
pub struct HitLight<'a> {
    pub splat_light: &'a [SplatLight],
    pub direct_light: &'a [[f32; 4]],
    pub materials: &'a [Material],
}

/// `glossy_indirect` in WGSL: the glossy part of the indirect light at `sf` by the frame's
/// glossy rays, at the next points of the pixel's R2 sequence (shifted by `shift`).
fn glossy_indirect(
    params: &ShadeParams,
    geo: &Geometry,
    lights: &[Light],
    baked: &HitLight,
    sf: &Surface,
    shift: [u32; 2],
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let o = sf.p + params.shadow_bias * sf.n;
    let f = frame_of(sf.n);
    for k in 0..params.glossy_rays {
        let (u1, u2) = r2_point(params.sample * params.glossy_rays + k, shift);
        let s = ward_sample(&f, sf.wo, u1, u2, sf.alpha);
        if !(s.weight > 0.0) || !(sf.n.dot(s.wo) > 0.0) {
            continue;
        }
        let mut budget = SHADOW_RAY_BUDGET;
        let hit = trace_ray(geo, o, s.wo, NO_SPLAT, FAR, &mut budget);
        if hit.splat == NO_SPLAT {
            continue;
        }
        let lit = lights
            .iter()
            .take(params.light_count as usize)
            .any(|l| light_first(l, o, s.wo, hit.t));
        let h = &geo.splats[hit.splat as usize];
        if lit || Vec3::from(h.normal).dot(s.wo) >= 0.0 {
            continue;
        }
        let e = Vec4::from(baked.direct_light[hit.splat as usize]).truncate()
            + Vec3::from(baked.splat_light[hit.splat as usize].irradiance);
        let m = &baked.materials[h.material as usize];
        sum += s.weight * hit_albedo(h, m) * e * (1.0 / PI);
    }
    sf.rho_s * sum * (1.0 / params.glossy_rays as f32)
}

/// How far past the blended surface, relative to its distance, a reflecting light still counts
/// as in front of it (the WGSL's `REFLECTING_LIGHT_SLACK`).
pub const REFLECTING_LIGHT_SLACK: f32 = 0.01;

/// The radiance of the nearest area light the view ray meets before `t_surface`, and whether
/// it reflects (its own surface, just behind its face, then shows too). A ray that meets
/// nothing (`t_surface` FAR) sees the sky and the sun's disk, if the scene has them, as a
/// light that hides nothing.
fn emitted(
    cam: &Camera,
    params: &ShadeParams,
    (lights, sky): (&[Light], &[[f32; 4]]),
    d: Vec3,
    t_surface: f32,
) -> Option<(Vec3, bool)> {
    let eye = Vec3::from(cam.eye);
    let mut out = None;
    let mut t_near = t_surface;
    for l in lights.iter().take(params.light_count as usize) {
        let t = area_light_hit(l, eye, d);
        let reflects = l.flags & light_flags::REFLECTS != 0;
        // A light that reflects lies in front of its own surface by less than the depth
        // targets round: within `REFLECTING_LIGHT_SLACK` of the surface's distance, that
        // surface counts as the light's own.
        let limit = if reflects {
            t_near * (1.0 + REFLECTING_LIGHT_SLACK)
        } else {
            t_near
        };
        if t > 0.0 && t < limit {
            t_near = t;
            out = Some((Vec3::from(l.power) / (PI * l.area), reflects));
        }
    }
    // Past every surface, the background: a colour, or the sky and the sun's disk.
    let background = Vec4::from(params.background);
    if t_surface >= FAR && out.is_none() && background.w > 0.0 {
        return Some((background.truncate(), false));
    }
    let lights = &lights[..params.light_count as usize];
    let open_sky = (lights.iter()).any(|l| matches!(l.kind, light_kind::ENVIRONMENT | light_kind::SUN));
    if t_surface >= FAR && out.is_none() && open_sky {
        let seen = lights.iter().map(|l| escaped_radiance(sky, l, d)).sum();
        out = Some((seen, false));
    }
    out
}

/// Shades every pixel into `hdr` (`width × height` values): written for refinement sample 0,
/// added to the running mean after it. `surface` gets each pixel's surface (normal, reversed
/// where a light shows; distance along the view ray, `FAR` where none), what the temporal pass
/// reprojects.
#[allow(clippy::too_many_arguments)]
pub fn shade(
    cam: &Camera,
    params: &ShadeParams,
    sums: &Attributes,
    lights: &[Light],
    baked: &HitLight,
    geo: &Geometry,
    hdr: &mut [[f32; 4]],
    surface: &mut [[f32; 4]],
) {
    let eye = Vec3::from(cam.eye);
    let width = cam.size[0] as u32;
    let pixels = hdr.par_iter_mut().zip(surface.par_iter_mut());
    pixels.enumerate().for_each(|(i, (out, out_surface))| {
        let i = i as u32;
        let px = Vec2::new((i % width) as f32, (i / width) as f32);
        let d = pixel_ray(cam, px + 0.5);
        let acc = Vec4::from(sums.radiance[i as usize]);
        let mut color = Vec3::ZERO;
        let mut t_surface = FAR;
        let mut normal = Vec3::ZERO;
        let shown = |bit: u32, v: Vec3| {
            if params.show & bit != 0 {
                v
            } else {
                Vec3::ZERO
            }
        };
        if acc.w > 0.0 {
            let inv_w = 1.0 / acc.w;
            let g = Vec4::from(sums.geometry[i as usize]);
            let dif = Vec4::from(sums.diffuse[i as usize]);
            let spec = Vec4::from(sums.specular[i as usize]);
            t_surface = g.w * inv_w;
            let gn = g.truncate();
            // Terms the frame does not show weigh nothing; with neither, no shadow ray.
            let sf = Surface {
                p: eye + t_surface * d,
                n: if gn.dot(gn) > 0.0 { gn.normalize() } else { -d },
                wo: -d,
                rho_d: shown(SHOW_DIRECT_DIFFUSE, dif.truncate() * inv_w),
                rho_s: shown(SHOW_DIRECT_SPECULAR, spec.truncate() * inv_w),
                alpha: if spec.w > 0.0 { dif.w / spec.w } else { 0.0 },
            };
            normal = sf.n;
            color = acc.truncate() * inv_w;
            // Baked direct light came with the attribute pass's sums.
            let rays = params.direct == DIRECT_RAYS;
            if rays && params.show & (SHOW_DIRECT_DIFFUSE | SHOW_DIRECT_SPECULAR) != 0 {
                color += direct(params, geo, lights, &sf, i);
            }
            let glossy = params.glossy_rays > 0 && sf.alpha >= MIN_ALPHA;
            if rays && glossy && params.show & SHOW_INDIRECT_SPECULAR != 0 {
                let g = Surface {
                    rho_s: spec.truncate() * inv_w,
                    ..sf
                };
                let shift = r2_shift(pcg_hash(
                    pcg_hash(params.seed ^ GLOSSY_SALT).wrapping_add(i),
                ));
                color += glossy_indirect(params, geo, lights, baked, &g, shift);
            }
        }
        // A light seen directly hides what lies behind it, or adds to its own surface where
        // it reflects; its radiance counts with the direct diffuse term, so that the parts a
        // frame can show add up to the whole.
        let seen = emitted(cam, params, (lights, geo.sky), d, t_surface);
        let c = match seen {
            Some((light, false)) => shown(SHOW_DIRECT_DIFFUSE, light),
            Some((light, true)) => color + shown(SHOW_DIRECT_DIFFUSE, light),
            None => color,
        };
        let c = c.extend(1.0);
        // A light's pixels carry the normal reversed: to the temporal pass a light and the
        // surface it lies on are two surfaces, so that no history carries its brightness onto
        // the ceiling.
        let normal = if seen.is_some() { -normal } else { normal };
        *out_surface = normal.extend(t_surface).to_array();
        // Refinement: the running mean of this frame and the `sample` frames before it.
        *out = if params.sample == 0 {
            c
        } else {
            let mean = Vec4::from(*out);
            mean + (c - mean) * (1.0 / (params.sample + 1) as f32)
        }
        .to_array();
    });
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::Shade,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
];
