//! Mirror of `wgsl/temporal.wgsl`: a moving frame blended into the last resolved image,
//! reprojected through the surface each pixel shows, the history kept where it showed a surface
//! the pixel shows now (or an edge neighbour does, within the pixel's footprint) and clamped to
//! the colour range of the pixel and its four edge neighbours.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use glam::{IVec2, Vec3, Vec4};
use rayon::prelude::*;

use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use crate::shared::splat::{pixel_ray, project_point};
use crate::shared::tone::luminance;
use crate::types::{Camera, TemporalParams};

pub const WG: u32 = 64;
/// A distance at least this large is no surface (shade writes `FAR` there).
const NO_SURFACE: f32 = 1.0e37;

/// The frame's pixels as `temporal` reads them.
pub struct TemporalInput<'a> {
    pub cam: &'a Camera,
    pub prev: &'a Camera,
    pub params: &'a TemporalParams,
    pub hdr: &'a [[f32; 4]],
    pub surface: &'a [[f32; 4]],
    pub history: &'a [[f32; 4]],
    pub history_surface: &'a [[f32; 4]],
    /// This frame's (Σ log(ε + Y), count), as `tonemap_reduce` sums it.
    pub log_sum: [f32; 2],
}

/// Resolves every pixel into `resolved` and `resolved_surface`.
pub fn temporal(
    input: &TemporalInput,
    resolved: &mut [[f32; 4]],
    resolved_surface: &mut [[f32; 4]],
) {
    let params = input.params;
    let pixels = (params.width * params.height) as usize;
    resolved
        .par_iter_mut()
        .zip(resolved_surface.par_iter_mut())
        .take(pixels)
        .enumerate()
        .for_each(|(i, (out, out_surface))| {
            (*out, *out_surface) = resolve(input, i as u32);
        });
}

/// The key of the weights' exposure: the tone map's default key.
const WEIGHT_KEY: f32 = 0.18;

/// The exposure that displays the frame of log-average sum `log_sum` (Σ log(ε + Y), count):
/// `WEIGHT_KEY` over its log-average luminance (1 where it has no finite pixel).
pub fn frame_exposure(log_sum: [f32; 2]) -> f32 {
    if log_sum[1] <= 0.0 {
        return 1.0;
    }
    WEIGHT_KEY / (log_sum[0] / log_sum[1]).exp()
}

/// A colour's weight in the resampling and the blend, its luminance scaled by the frame's
/// `exposure` (as displayed): bright pixels resampled every frame would otherwise bleed into
/// the dim ones around them.
fn weight_of(c: Vec3, exposure: f32) -> f32 {
    1.0 / (1.0 + exposure * luminance(c).max(0.0))
}

/// The point at distance `t` along pixel `q`'s ray in this frame's camera.
fn point_shown(input: &TemporalInput, q: IVec2, t: f32) -> Vec3 {
    Vec3::from(input.cam.eye) + t * pixel_ray(input.cam, q.as_vec2() + 0.5)
}

/// Surface `s` (normal, distance along its ray) that pixel `q` shows, as (normal, distance from
/// the last frame's eye); `NO_SURFACE` where it shows none.
fn seen_from_last_eye(input: &TemporalInput, q: IVec2, s: Vec4) -> Vec4 {
    if s.w >= NO_SURFACE {
        return s.truncate().extend(NO_SURFACE);
    }
    let p = point_shown(input, q, s.w);
    s.truncate()
        .extend((p - Vec3::from(input.prev.eye)).length())
}

/// Whether the last frame's surface `was` (normal, distance from its eye) is the surface
/// `seen` (`seen_from_last_eye`): both none, or distances within `depth_tolerance` and
/// normals within `normal_cos`.
fn same_surface_seen(params: &TemporalParams, was: Vec4, seen: Vec4) -> bool {
    let (was_shown, shown) = (was.w < NO_SURFACE, seen.w < NO_SURFACE);
    if !was_shown || !shown {
        return was_shown == shown;
    }
    (was.w - seen.w).abs() <= params.depth_tolerance * seen.w
        && was.truncate().dot(seen.truncate()) >= params.normal_cos
}

/// Edge neighbour `k` (0–3: right, left, down, up) of pixel `px`, clamped to the image.
fn edge_neighbour(px: IVec2, k: i32, size: IVec2) -> IVec2 {
    let sign = 1 - 2 * (k & 1);
    let step = if k >= 2 {
        IVec2::new(0, sign)
    } else {
        IVec2::new(sign, 0)
    };
    (px + step).clamp(IVec2::ZERO, size - 1)
}

/// Whether one of pixel `px`'s edge neighbours shows the last frame's surface `was` now.
fn shown_beside(input: &TemporalInput, px: IVec2, size: IVec2, was: Vec4) -> bool {
    (0..4).any(|k| {
        let q = edge_neighbour(px, k, size);
        let s = Vec4::from(input.surface[(q.y * size.x + q.x) as usize]);
        same_surface_seen(input.params, was, seen_from_last_eye(input, q, s))
    })
}

/// Whether what last-frame pixel `q` showed (surface `was`: normal, distance along its ray)
/// lies within pixel `px`'s footprint in this frame's image; nothing lies everywhere.
fn in_footprint(input: &TemporalInput, px: IVec2, q: IVec2, was: Vec4) -> bool {
    if was.w >= NO_SURFACE {
        return true;
    }
    let d = pixel_ray(input.prev, q.as_vec2() + 0.5);
    let now = project_point(input.cam, Vec3::from(input.prev.eye) + was.w * d);
    now.z > 0.0 && now.truncate().floor().as_ivec2() == px
}

/// What pixel `px`'s history moved with: the point it shows (`own`, at `p`); where it shows
/// none, the nearest surface an edge neighbour shows; else `None`, its view direction (a
/// point at infinity). See `moved_point` in the WGSL.
fn moved_point(input: &TemporalInput, px: IVec2, size: IVec2, own: Vec4, p: Vec3) -> Option<Vec3> {
    if own.w < NO_SURFACE {
        return Some(p);
    }
    let mut nearest = None;
    let mut t = NO_SURFACE;
    for k in 0..4 {
        let q = edge_neighbour(px, k, size);
        let s = input.surface[(q.y * size.x + q.x) as usize];
        if s[3] < t {
            t = s[3];
            nearest = Some(point_shown(input, q, t));
        }
    }
    nearest
}

fn resolve(input: &TemporalInput, i: u32) -> ([f32; 4], [f32; 4]) {
    let TemporalInput {
        cam, prev, params, ..
    } = *input;
    let index = |q: IVec2| (q.y as u32 * params.width + q.x as u32) as usize;
    let px = IVec2::new((i % params.width) as i32, (i / params.width) as i32);
    let size = IVec2::new(params.width as i32, params.height as i32);
    let current = Vec4::from(input.hdr[i as usize]).truncate();
    let own = Vec4::from(input.surface[i as usize]);
    let shows = own.w < NO_SURFACE;
    // The neighbourhood's colour range: the pixel and its four edge neighbours.
    let (mut lo, mut hi) = (current, current);
    for k in 0..4 {
        let c = Vec4::from(input.hdr[index(edge_neighbour(px, k, size))]).truncate();
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let mut out = current.extend(1.0);
    if params.reset == 0 {
        let exposure = frame_exposure(input.log_sum);
        // Where the surface is now and was in the last frame's image: a point, or where the
        // pixel shows none, a direction (the same from either eye).
        let d = pixel_ray(cam, px.as_vec2() + 0.5);
        let (eye, prev_eye) = (Vec3::from(cam.eye), Vec3::from(prev.eye));
        let p = eye + own.w * d;
        // The pixel's own surface as `seen_from_last_eye` gives it, from the ray already cast.
        let seen = own.truncate().extend(if shows {
            (p - prev_eye).length()
        } else {
            NO_SURFACE
        });
        let (now, was) = match moved_point(input, px, size, own, p) {
            Some(m) => (project_point(cam, m), project_point(prev, m)),
            None => (
                project_point(cam, eye + d),
                project_point(prev, prev_eye + d),
            ),
        };
        // The pixel's centre moved as the surface did; pixel k's centre is at k + 0.5.
        let at = px.as_vec2() + (was.truncate() - now.truncate());
        let base = at.floor();
        let f = at - base;
        let mut sum = Vec4::ZERO;
        let mut weight = 0.0;
        let mut bilinear = 0.0;
        for k in 0..4 {
            let q = base.as_ivec2() + IVec2::new(k & 1, k >> 1);
            let inside = q.cmpge(IVec2::ZERO).all() && q.cmplt(size).all();
            if !inside || was.z <= 0.0 {
                continue;
            }
            let j = index(q);
            let was_surface = Vec4::from(input.history_surface[j]);
            // A surface only a neighbour shows counts where this pixel's footprint held it (the
            // neighbours are read only then: on edges).
            let same = same_surface_seen(params, was_surface, seen)
                || (shown_beside(input, px, size, was_surface)
                    && in_footprint(input, px, q, was_surface));
            if same {
                let wx = if k & 1 == 1 { f.x } else { 1.0 - f.x };
                let wy = if k >= 2 { f.y } else { 1.0 - f.y };
                let b = wx * wy;
                let h = Vec4::from(input.history[j]);
                let w = b * weight_of(h.truncate(), exposure);
                sum += (w * h.truncate()).extend(b * h.w);
                weight += w;
                bilinear += b;
            }
        }
        if weight > 0.0 {
            let kept = (sum.truncate() / weight).clamp(lo, hi);
            let frames = (sum.w / bilinear + 1.0).min(params.max_frames as f32);
            let wc = weight_of(current, exposure) / frames;
            let wh = weight_of(kept, exposure) * (1.0 - 1.0 / frames);
            out = ((wc * current + wh * kept) / (wc + wh)).extend(frames);
        }
    }
    (out.to_array(), own.to_array())
}

/// The executor's entry: `temporal`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, _groups: u32) -> Result<()> {
    let cam: Camera = b.param(0)?;
    let prev: Camera = b.param(1)?;
    let params: TemporalParams = b.param(2)?;
    let (hdr, surface) = (b.get(3)?, b.get(4)?);
    let (history, history_surface) = (b.get(5)?, b.get(6)?);
    let mut resolved = b.get_mut(7)?;
    let mut resolved_surface = b.get_mut(8)?;
    let log_sum = view::<[f32; 2]>(&b.get(9)?)
        .first()
        .copied()
        .unwrap_or_default();
    let input = TemporalInput {
        cam: &cam,
        prev: &prev,
        params: &params,
        hdr: view(&hdr),
        surface: view(&surface),
        history: view(&history),
        history_surface: view(&history_surface),
        log_sum,
    };
    temporal(
        &input,
        view_mut(&mut resolved),
        view_mut(&mut resolved_surface),
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::Temporal,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
