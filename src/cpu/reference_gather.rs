//! Mirror of `wgsl/reference_gather.wgsl`: per pixel, the visible point by ray casting and the
//! radiance the photons within R reflect there by the exact Ward BRDF, kernel-weighted; the
//! attribute pass's four targets with weight 1 (zero where the ray misses).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::MirrorRow;
use crate::shaders::Stage;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::splat_attributes::Attributes;
use crate::bins::PhotonBins;
use crate::shared::bins::{SURFACE_COS_MIN, bin_box, bin_row, bin_row_count};
use crate::shared::octahedral::{oct_decode, surface_decode};
use crate::shared::sampling::PI;
use crate::shared::splat::{SHADOW_RAY_BUDGET, pixel_ray};
use crate::shared::trace::{FAR, Geometry, trace_ray};
use crate::shared::ward::ward_specular;
use crate::types::{Camera, EmParams, Material, NO_SPLAT};

/// Radiance the photons within R of `p` reflect towards `wo`, on a splat of normal `n`.
#[allow(clippy::too_many_arguments)]
fn gather(
    em: &EmParams,
    bins: &PhotonBins,
    p: Vec3,
    n: Vec3,
    wo: Vec3,
    rho_d: Vec3,
    m: &Material,
    slab: f32,
) -> Vec3 {
    let bx = bin_box(p, em.radius, &bins.params);
    let kernel = 2.0 * em.inv_area;
    let inv_r2 = 1.0 / em.radius2;
    let mut sum = Vec3::ZERO;
    for r in 0..bin_row_count(&bx) {
        let row = bin_row(&bx, r, &bins.params);
        for j in bins.cell_start[row.x as usize]..bins.cell_start[row.y as usize] {
            let g = &bins.geom[j as usize];
            let d = Vec3::from(g.position) - p;
            let d2 = d.dot(d);
            if d2 > em.radius2 || d.dot(n).abs() > slab {
                continue;
            }
            let power = bins.power[j as usize];
            let wi = oct_decode(g.direction);
            if wi.dot(n) <= 0.0 || surface_decode(power[3]).dot(n) < SURFACE_COS_MIN {
                continue;
            }
            let f = rho_d / PI + Vec3::from(m.specular) * ward_specular(n, wi, wo, m.roughness);
            sum += (kernel * (1.0 - d2 * inv_r2)) * f * Vec3::new(power[0], power[1], power[2]);
        }
    }
    sum
}

/// The four targets of one pixel, or none where its ray meets no splat.
fn pixel(
    cam: &Camera,
    em: &EmParams,
    materials: &[Material],
    bins: &PhotonBins,
    geo: &Geometry,
    centre: Vec2,
) -> Option<[[f32; 4]; 4]> {
    let eye = Vec3::from(cam.eye);
    let d = pixel_ray(cam, centre);
    let mut budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(geo, eye, d, NO_SPLAT, FAR, &mut budget);
    if hit.splat == NO_SPLAT {
        return None;
    }
    let s = &geo.splats[hit.splat as usize];
    let m = &materials[s.material as usize];
    let gloss = (m.specular[0] + m.specular[1] + m.specular[2]) * (1.0 / 3.0);
    let p = eye + hit.t * d;
    let (n, rho_d) = (Vec3::from(s.normal), Vec3::from(s.diffuse));
    let radiance = gather(em, bins, p, n, -d, rho_d, m, em.slab * s.radius);
    Some([
        radiance.extend(1.0).to_array(),
        n.extend(hit.t).to_array(),
        rho_d.extend(gloss * m.roughness).to_array(),
        Vec3::from(m.specular).extend(gloss).to_array(),
    ])
}

pub fn reference_gather(
    cam: &Camera,
    em: &EmParams,
    materials: &[Material],
    bins: &PhotonBins,
    geo: &Geometry,
) -> Attributes {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let pixels: Vec<[[f32; 4]; 4]> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            let centre = Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            pixel(cam, em, materials, bins, geo, centre).unwrap_or_default()
        })
        .collect();
    let target = |k: usize| pixels.iter().map(|p| p[k]).collect();
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
        stage: Stage::ReferenceGather,
        entry: "main",
        workgroup_size: None,
        items: 1,
        run: None,
    },
];
