//! Object-ID images: which of the scene's surfaces (`Scene::surfaces`) each pixel shows, so
//! that an image's error can be measured per object (`lobelight compare --objects`) instead
//! of diluted by the walls around it.
//!
//! A pixel is traced at several points within it (the refinement frames' jitter, so the points
//! the still image averages): it names a surface only where every point sees that surface.
//! Pixels on an edge between surfaces hold `MIXED` and pixels that see no surface (or see a
//! light first) hold `NONE`; per-object figures leave both out, since an anti-aliased edge
//! pixel belongs to no one object. A light is a hundred times brighter than what it lights, so
//! a sliver of it between the points would swamp a surface's pixel: the pixels next to one
//! where a point sees a light are edges too.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::grid::SplatGrid;
use crate::scene::Scene;
use crate::shared::lights::area_light_hit;
use crate::shared::splat::{SHADOW_RAY_BUDGET, pixel_ray};
use crate::shared::trace::{FAR, Geometry, trace_ray};
use crate::types::{Camera, NO_SPLAT};

/// A pixel that shows no surface: the background, or a light in front of any surface.
pub const NONE: u16 = 0;
/// A pixel whose points see different surfaces (an edge).
pub const MIXED: u16 = u16::MAX;
/// Points traced per pixel: four times the still image's default refinement frames. With as
/// many points as frames, an edge pixel whose frames all fell on one side counted as that
/// side, while a path tracer's samples cover the whole pixel: the diffuse box's floor and
/// blocks read 2 % bright in direct light at 64² (16 points), 0.4–1.6 % at 64.
pub const SAMPLES: u32 = 64;

/// The ID of surface `k` (`Splat::object`) in an object-ID image.
pub fn id_of(surface: u32) -> u16 {
    (surface + 1) as u16
}

/// The surface an image ID names, if it names one.
pub fn surface_of(id: u16) -> Option<u32> {
    (id != NONE && id != MIXED).then(|| id as u32 - 1)
}

/// What a point of a pixel sees: a surface's ID, or NONE (with `LIGHT` where a light is in
/// front).
const LIGHT: u32 = 1 << 16;

/// The ID of the surface that the ray through `pixel` (continuous pixel coordinates) sees
/// first, or NONE, | LIGHT where that is a light.
fn seen(scene: &Scene, geo: &Geometry, cam: &Camera, pixel: Vec2) -> u32 {
    let o = Vec3::from(cam.eye);
    let d = pixel_ray(cam, pixel);
    let mut budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(geo, o, d, NO_SPLAT, FAR, &mut budget);
    let t_surface = if hit.splat == NO_SPLAT { FAR } else { hit.t };
    let light_first = scene.lights.iter().any(|l| {
        let t = area_light_hit(l, o, d);
        t > 0.0 && t < t_surface
    });
    if light_first {
        return NONE as u32 | LIGHT;
    }
    if hit.splat == NO_SPLAT || hit.aborted != 0 {
        return NONE as u32;
    }
    id_of(scene.splats[hit.splat as usize].object) as u32
}

/// The object-ID image of `cam` (`cam.size` pixels, row by row): per pixel the surface all of
/// its `samples` points see (`frame::jitter`'s for as many refinement frames), else
/// `MIXED`, or `NONE`.
pub fn object_ids(scene: &Scene, grid: &SplatGrid, cam: &Camera, samples: u32) -> Result<Vec<u16>> {
    if scene.surfaces.len() >= MIXED as usize - 1 {
        return Err(Error::Invalid(format!(
            "the scene has {} surfaces; an object-ID image (16 bits) names at most {}",
            scene.surfaces.len(),
            MIXED - 2
        )));
    }
    let geo = scene.geometry(grid);
    let cam = Camera {
        jitter: [0.0; 2],
        ..*cam
    };
    let (w, h) = (cam.size[0] as u32, cam.size[1] as u32);
    let points: Vec<Vec2> = (0..samples.max(1))
        .map(|k| Vec2::splat(0.5) + Vec2::from(crate::frame::jitter(k, samples)))
        .collect();
    // Per pixel: its ID, and whether a point of it sees a light.
    let pixels: Vec<(u16, bool)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let px = Vec2::new((i % w) as f32, (i / w) as f32);
            let first = seen(scene, &geo, &cam, px + points[0]);
            let mut agree = true;
            let mut light = first & LIGHT != 0;
            for &p in &points[1..] {
                let other = seen(scene, &geo, &cam, px + p);
                agree &= other == first;
                light |= other & LIGHT != 0;
            }
            let id = if agree { first as u16 } else { MIXED };
            (id, light)
        })
        .collect();
    let lit_nearby = |x: u32, y: u32| {
        let near = |a: u32, n: u32| a.saturating_sub(1)..=(a + 1).min(n - 1);
        near(y, h).any(|y| near(x, w).any(|x| pixels[(y * w + x) as usize].1))
    };
    Ok((0..w * h)
        .map(|i| {
            let id = pixels[i as usize].0;
            if surface_of(id).is_some() && lit_nearby(i % w, i / w) {
                MIXED
            } else {
                id
            }
        })
        .collect())
}
