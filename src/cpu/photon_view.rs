//! Mirror of `wgsl/photon_view.wgsl`: the photons the camera sees, summed in fixed point into
//! their pixels (wrapping like the device's `atomicAdd`; the sum does not depend on order).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use glam::Vec3;
use rayon::prelude::*;

use crate::error::Result;
use crate::photons::emitters;
use crate::shared::splat::{SHADOW_RAY_BUDGET, clip_position};
use crate::shared::trace::{Geometry, trace_ray};
use crate::types::{Camera, Light, Material, NO_SPLAT, Photon, PhotonViewParams};

pub const WG: u32 = 64;
/// Most fixed-point units one photon adds (see the shader).
pub const PHOTON_CAP: f32 = 65536.0;

/// Fixed-point units per unit of power for photons of about `photon_power` each: 1024 units
/// a photon, so a pixel holds four million photons before its 32 bits wrap.
pub fn fixed_scale(photon_power: f32) -> f32 {
    if photon_power.is_finite() && photon_power > 0.0 {
        1024.0 / photon_power
    } else {
        1.0
    }
}

/// `fixed_scale` for the photons of `lights` when `photons` are emitted: the largest
/// channel of the largest emitted photon power.
pub fn scene_scale(lights: &[Light], photons: u64) -> Result<f32> {
    let largest = emitters(lights, photons)?
        .iter()
        .map(|e| Vec3::from(e.photon_power).max_element())
        .fold(0.0f32, f32::max);
    Ok(fixed_scale(largest))
}

/// The pixel `p` projects into (the raster passes' projection, `clip_position`), or none
/// behind the camera or outside the image.
pub fn project_pixel(cam: &Camera, p: Vec3) -> Option<(u32, u32)> {
    let clip = clip_position(cam, p);
    if clip.w <= 0.0 {
        return None;
    }
    let (ndc_x, ndc_y) = (clip.x / clip.w, clip.y / clip.w);
    let x = (ndc_x * 0.5 + 0.5) * cam.size[0];
    let y = (0.5 - ndc_y * 0.5) * cam.size[1];
    let inside = (0.0..cam.size[0]).contains(&x) && (0.0..cam.size[1]).contains(&y);
    inside.then_some((x as u32, y as u32))
}

/// Adds `photons` (one page, `params.count` of them) into `sums` (3 per pixel).
pub fn photon_view(
    params: &PhotonViewParams,
    cam: &Camera,
    materials: &[Material],
    photons: &[Photon],
    sums: &mut [u32],
    geo: &Geometry,
) {
    let eye = Vec3::from(cam.eye);
    let seen: Vec<(usize, [u32; 3])> = photons[..params.count as usize]
        .par_iter()
        .filter_map(|p| {
            let pos = Vec3::from(p.position);
            let (x, y) = project_pixel(cam, pos)?;
            let s = &geo.splats[p.splat as usize];
            let to_eye = eye - pos;
            if Vec3::from(s.normal).dot(to_eye) <= 0.0 {
                return None;
            }
            let dist = to_eye.length();
            let mut budget = SHADOW_RAY_BUDGET;
            let hit = trace_ray(geo, pos, to_eye / dist, p.splat, dist * 0.999, &mut budget);
            if hit.splat != NO_SPLAT || hit.aborted != 0 {
                return None;
            }
            let albedo =
                Vec3::from(s.diffuse) + Vec3::from(materials[s.material as usize].specular);
            let units = (Vec3::from(p.power) * albedo * params.scale).min(Vec3::splat(PHOTON_CAP));
            let at = 3 * (y * params.width + x) as usize;
            Some((at, units.to_array().map(|u| u as u32)))
        })
        .collect();
    for (at, units) in seen {
        for c in 0..3 {
            sums[at + c] = sums[at + c].wrapping_add(units[c]);
        }
    }
}

/// The executor's entry: `photon_view`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, _groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let cam = b.param(1)?;
    let materials = b.get(2)?;
    let photons = b.get(3)?;
    let mut sums = b.get_mut(4)?;
    let (materials, photons) = (view(&materials), view(&photons));
    photon_view(&p, &cam, materials, photons, &mut sums, geo);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::PhotonView,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
];
