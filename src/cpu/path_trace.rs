//! Mirror of `wgsl/path_trace.wgsl`: one path-traced sample per pixel added to the running
//! mean, with next-event estimation weighted against BRDF sampling by the power heuristic.
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{IVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::grid::{cell_index, point_cell};
use crate::shared::lights::{
    MIN_ALPHA, area_light_hit, escaped_radiance, light_pdf, sample_light, shadow_reach,
};
use crate::shared::rng::{
    RNG_BOUNCE_U, RNG_BOUNCE_V, RNG_EMIT_POS_U, RNG_EMIT_POS_V, RNG_ROULETTE, path_key, pcg_hash,
    rand,
};
use crate::shared::sampling::{PI, frame_of, power_heuristic};
use crate::shared::splat::FRONT_COS_MIN;
use crate::shared::splat::{
    SHADOW_RAY_BUDGET, SHOW_DIRECT_DIFFUSE, SHOW_DIRECT_SPECULAR, SHOW_INDIRECT_DIFFUSE,
    SHOW_INDIRECT_SPECULAR, pixel_ray, splat_weight,
};
use crate::shared::trace::{FAR, Geometry, trace_ray};
use crate::shared::ward::{mean3, sample_bounce, ward_pdf, ward_specular};
use crate::types::{Camera, Hit, Light, Material, NO_SPLAT, PathParams, light_flags};

pub const WG: u32 = 64;
pub const RNG_LIGHT_U: u32 = 7;
pub const RNG_LIGHT_V: u32 = 8;

fn brdf_pdf(n: Vec3, wo: Vec3, wi: Vec3, pd: f32, ps: f32, alpha: f32) -> f32 {
    let ci = n.dot(wi);
    if !(ci > 0.0) {
        return 0.0;
    }
    let mut pdf = pd * ci / PI;
    if ps > 0.0 && alpha >= MIN_ALPHA {
        pdf += ps * ward_pdf(n, wo, wi, alpha);
    }
    pdf
}

fn brdf(n: Vec3, wo: Vec3, wi: Vec3, rho_d: Vec3, m: &Material, wd: f32, ws: f32) -> Vec3 {
    let mut f = rho_d / PI * wd;
    if m.roughness >= MIN_ALPHA {
        f += Vec3::from(m.specular) * ward_specular(n, wi, wo, m.roughness) * ws;
    }
    f
}

/// How far past a hit, in each disk's radii along the ray, the disks that blend into its normal
/// may lie: the splat frame's depth tolerance.
pub const BLEND_DEPTH: f32 = 1.0;
/// The largest neighbour, in hit-disk radii, whose hit the search is sure to find.
pub const BLEND_REACH: f32 = 1.5;

/// `blended_normal` in WGSL: the normal of the surface the splat frame shows where the ray
/// `(o, d)` meets disk `hit.splat` (the disks of its surface the ray meets within
/// `BLEND_DEPTH` radii past it, weighted by the splat kernel), searched in the same cells in
/// the same order.
fn blended_normal(geo: &Geometry, o: Vec3, d: Vec3, hit: &Hit, skip: u32) -> Vec3 {
    let g = &geo.grid.params;
    let h = &geo.splats[hit.splat as usize];
    let hn = Vec3::from(h.normal);
    let p = o + hit.t * d;
    let end = p + (BLEND_REACH * BLEND_DEPTH * h.radius) * d;
    let top = IVec3::new(g.dims[0] as i32, g.dims[1] as i32, g.dims[2] as i32) - 1;
    let a = point_cell(p.min(end), g).clamp(IVec3::ZERO, top);
    let b = point_cell(p.max(end), g).clamp(IVec3::ZERO, top);
    let mut budget = SHADOW_RAY_BUDGET;
    let mut sum = Vec3::ZERO;
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                let c = IVec3::new(x, y, z);
                for &j in geo.grid.cell(cell_index(c.as_uvec3(), g)) {
                    if budget == 0 {
                        break;
                    }
                    budget -= 1;
                    let s = &geo.splats[j as usize];
                    let sn = Vec3::from(s.normal);
                    if j == skip || sn.dot(hn) < FRONT_COS_MIN {
                        continue;
                    }
                    let t = geo.intersect(s, o, d);
                    if !(t >= hit.t && t <= hit.t + BLEND_DEPTH * s.radius) {
                        continue;
                    }
                    let q = o + t * d;
                    if point_cell(q, g) != c {
                        continue;
                    }
                    let r = q - Vec3::from(s.center);
                    sum += splat_weight(r.dot(r) / (s.radius * s.radius)) * sn;
                }
            }
        }
    }
    if sum.dot(sum) > 0.0 {
        sum.normalize()
    } else {
        hn
    }
}

/// The radiance of the lights a ray `d` that left the scene sees (a sky, the sun's disk), each
/// weighted by the power heuristic against its next-event pdf where a BRDF sample of pdf
/// `pdf_brdf` at a surface of normal `n` chose `d` (0: the camera's ray, which sees them whole).
fn escaped(sky: &[[f32; 4]], lights: &[Light], (d, n): (Vec3, Vec3), pdf_brdf: f32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for l in lights {
        let radiance = escaped_radiance(sky, l, d);
        if radiance.cmple(Vec3::ZERO).all() {
            continue;
        }
        let w = if pdf_brdf > 0.0 {
            power_heuristic(pdf_brdf, light_pdf(sky, l, (n, d), FAR))
        } else {
            1.0
        };
        sum += radiance * w;
    }
    sum
}

fn shown(show: u32, bits: u32) -> f32 {
    if show & bits != 0 { 1.0 } else { 0.0 }
}

/// One sample of pixel `i`.
fn sample(
    params: &PathParams,
    cam: &Camera,
    materials: &[Material],
    lights: &[Light],
    geo: &Geometry,
    i: u32,
) -> Vec3 {
    // The seed hashed before the sample is added: seeds s and s + 1 share no sample.
    let key = path_key(
        pcg_hash(pcg_hash(params.seed).wrapping_add(params.sample)),
        i,
    );
    let px = Vec2::new((i % params.width) as f32, (i / params.width) as f32);
    let jitter = Vec2::new(rand(key, 0, RNG_EMIT_POS_U), rand(key, 0, RNG_EMIT_POS_V));
    let mut o = Vec3::from(cam.eye);
    let mut d = pixel_ray(cam, px + jitter);
    let mut throughput = Vec3::ONE;
    let mut radiance = Vec3::ZERO;
    let mut skip = NO_SPLAT;
    let mut pdf_brdf = 0.0;
    // The normal of the surface the ray left (the sky's next-event pdf there).
    let mut from_normal = Vec3::ZERO;
    let mut hit_shown = shown(params.show, SHOW_DIRECT_DIFFUSE);
    let mut later_shown = 1.0;
    let lights = &lights[..params.light_count as usize];
    for depth in 0..=params.max_depth {
        let mut budget = SHADOW_RAY_BUDGET;
        let hit = trace_ray(geo, o, d, skip, FAR, &mut budget);
        let t_surface = if hit.splat == NO_SPLAT { FAR } else { hit.t };
        let mut light_t = t_surface;
        let mut seen = None;
        for (li, l) in lights.iter().enumerate() {
            let t = area_light_hit(l, o, d);
            if t > 0.0 && t < light_t {
                light_t = t;
                seen = Some(li);
            }
        }
        if let Some(li) = seen {
            let l = &lights[li];
            let mut w = 1.0;
            if pdf_brdf > 0.0 {
                let pdf_light = light_t * light_t / (l.area * -d.dot(Vec3::from(l.direction)));
                w = power_heuristic(pdf_brdf, pdf_light);
            }
            radiance += throughput * (Vec3::from(l.power) / (PI * l.area)) * (w * hit_shown);
            // A light that reflects goes on to its own surface, just behind its face.
            if l.flags & light_flags::REFLECTS == 0 {
                break;
            }
        }
        // A ray that leaves the scene sees the sky and the sun.
        if hit.splat == NO_SPLAT && hit.aborted == 0 {
            let background = Vec4::from(params.background);
            // The camera's own ray sees the background where it is a colour.
            let seen = if depth == 0 && background.w > 0.0 {
                background.truncate()
            } else {
                escaped(geo.sky, lights, (d, from_normal), pdf_brdf)
            };
            radiance += throughput * seen * hit_shown;
        }
        if hit.splat == NO_SPLAT || hit.aborted != 0 || depth == params.max_depth {
            break;
        }
        let s = &geo.splats[hit.splat as usize];
        let m = &materials[s.material as usize];
        let p = o + hit.t * d;
        // The camera sees the blended surface; past it, the disks' own normals (see WGSL).
        let n = match depth {
            0 => blended_normal(geo, o, d, &hit, skip),
            _ => Vec3::from(s.normal),
        };
        let wo = -d;
        let (rho_d, rho_s) = (Vec3::from(s.diffuse), Vec3::from(m.specular));
        let (pd, ps) = (mean3(rho_d), mean3(rho_s));
        for (li, l) in lights.iter().enumerate() {
            let lkey = pcg_hash(key.wrapping_add(li as u32));
            let (u, v) = (
                rand(lkey, depth, RNG_LIGHT_U),
                rand(lkey, depth, RNG_LIGHT_V),
            );
            let ls = sample_light(geo.sky, l, p, n, u, v);
            let cos_i = n.dot(ls.wi);
            if !(cos_i > 0.0) || ls.e.cmple(Vec3::ZERO).all() {
                continue;
            }
            let mut shadow_budget = SHADOW_RAY_BUDGET;
            // Off the surface as the renderer's shadow rays start (design §10).
            let o_shadow = p + params.shadow_bias * n;
            let reach = shadow_reach(l, o_shadow, ls.wi, ls.dist, params.shadow_bias);
            let blocked = trace_ray(geo, o_shadow, ls.wi, hit.splat, reach, &mut shadow_budget);
            if blocked.splat != NO_SPLAT {
                continue;
            }
            let pdf_light = light_pdf(geo.sky, l, (n, ls.wi), ls.dist);
            let w = if pdf_light > 0.0 {
                power_heuristic(pdf_light, brdf_pdf(n, wo, ls.wi, pd, ps, m.roughness))
            } else {
                1.0
            };
            let (wd, ws) = if depth == 0 {
                (
                    shown(params.show, SHOW_DIRECT_DIFFUSE),
                    shown(params.show, SHOW_DIRECT_SPECULAR),
                )
            } else {
                (later_shown, later_shown)
            };
            radiance += throughput * brdf(n, wo, ls.wi, rho_d, m, wd, ws) * ls.e * (cos_i * w);
        }
        if depth + 1 == params.max_depth {
            break;
        }
        let u = rand(key, depth + 1, RNG_ROULETTE);
        let u1 = rand(key, depth + 1, RNG_BOUNCE_U);
        let u2 = rand(key, depth + 1, RNG_BOUNCE_V);
        let next = sample_bounce(&frame_of(n), wo, rho_d, rho_s, m.roughness, u, u1, u2);
        if !next.alive {
            break;
        }
        let wi = next.dir;
        throughput *= next.weight;
        if depth == 0 {
            let (direct, indirect) = if next.specular {
                (SHOW_DIRECT_SPECULAR, SHOW_INDIRECT_SPECULAR)
            } else {
                (SHOW_DIRECT_DIFFUSE, SHOW_INDIRECT_DIFFUSE)
            };
            hit_shown = shown(params.show, direct);
            later_shown = shown(params.show, indirect);
        } else {
            hit_shown = later_shown;
        }
        let mirror = next.specular && m.roughness < MIN_ALPHA;
        pdf_brdf = if mirror {
            0.0
        } else {
            brdf_pdf(n, wo, wi, pd, ps, m.roughness)
        };
        o = p;
        d = wi;
        skip = hit.splat;
        from_normal = n;
    }
    radiance
}

/// Adds sample `params.sample` of every pixel to the running mean in `hdr`.
pub fn path_trace(
    params: &PathParams,
    cam: &Camera,
    materials: &[Material],
    lights: &[Light],
    hdr: &mut [[f32; 4]],
    geo: &Geometry,
) {
    let pixels = (params.width * params.height) as usize;
    hdr[..pixels]
        .par_iter_mut()
        .enumerate()
        .for_each(|(i, px)| {
            let c = sample(params, cam, materials, lights, geo, i as u32).extend(1.0);
            *px = if params.sample == 0 {
                c
            } else {
                let mean = Vec4::from(*px);
                mean + (c - mean) * (1.0 / (params.sample + 1) as f32)
            }
            .to_array();
        });
}

/// The executor's entry: `path_trace`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let cam = b.param(1)?;
    let materials = b.get(2)?;
    let lights = b.get(3)?;
    let mut hdr = b.get_mut(4)?;
    let (materials, lights) = (view(&materials), view(&lights));
    path_trace(&p, &cam, materials, lights, view_mut(&mut hdr), geo);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::PathTrace,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
];
