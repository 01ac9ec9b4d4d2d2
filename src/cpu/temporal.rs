//! Mirror of `wgsl/temporal.wgsl`: a moving frame blended into the last resolved image,
//! reprojected through the surface each pixel shows, the history kept where it showed the same
//! surface and clamped to the colour range of the pixel and its four edge neighbours.

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

/// A colour's weight in the resampling and the blend: bright pixels resampled every frame
/// would otherwise bleed into the dim ones around them.
fn weight_of(c: Vec3) -> f32 {
    1.0 / (1.0 + luminance(c).max(0.0))
}

fn resolve(input: &TemporalInput, i: u32) -> ([f32; 4], [f32; 4]) {
    let TemporalInput {
        cam, prev, params, ..
    } = *input;
    let index = |q: IVec2| (q.y as u32 * params.width + q.x as u32) as usize;
    let px = IVec2::new((i % params.width) as i32, (i / params.width) as i32);
    let size = IVec2::new(params.width as i32, params.height as i32);
    let current = Vec4::from(input.hdr[i as usize]).truncate();
    // The neighbourhood's colour range: the pixel and its four edge neighbours.
    let (mut lo, mut hi) = (current, current);
    for k in 0..4 {
        let sign = 1 - 2 * (k & 1);
        let step = if k >= 2 {
            IVec2::new(0, sign)
        } else {
            IVec2::new(sign, 0)
        };
        let q = (px + step).clamp(IVec2::ZERO, size - 1);
        let c = Vec4::from(input.hdr[index(q)]).truncate();
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let own = Vec4::from(input.surface[i as usize]);
    let shows = own.w < NO_SURFACE;
    let mut out = current.extend(1.0);
    if params.reset == 0 {
        // Where the surface is now and was in the last frame's image: a point, or where the
        // pixel shows none, a direction (the same from either eye).
        let d = pixel_ray(cam, px.as_vec2() + 0.5);
        let (eye, prev_eye) = (Vec3::from(cam.eye), Vec3::from(prev.eye));
        let p = eye + own.w * d;
        let now = project_point(cam, if shows { p } else { eye + d });
        let was = project_point(prev, if shows { p } else { prev_eye + d });
        let expected = (p - prev_eye).length();
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
            let was_shown = was_surface.w < NO_SURFACE;
            let mut same = !shows && !was_shown;
            if shows && was_shown {
                same = (was_surface.w - expected).abs() <= params.depth_tolerance * expected
                    && was_surface.truncate().dot(own.truncate()) >= params.normal_cos;
            }
            if same {
                let wx = if k & 1 == 1 { f.x } else { 1.0 - f.x };
                let wy = if k >= 2 { f.y } else { 1.0 - f.y };
                let b = wx * wy;
                let h = Vec4::from(input.history[j]);
                let w = b * weight_of(h.truncate());
                sum += (w * h.truncate()).extend(b * h.w);
                weight += w;
                bilinear += b;
            }
        }
        if weight > 0.0 {
            let kept = (sum.truncate() / weight).clamp(lo, hi);
            let frames = (sum.w / bilinear + 1.0).min(params.max_frames as f32);
            let wc = weight_of(current) / frames;
            let wh = weight_of(kept) * (1.0 - 1.0 / frames);
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
    let input = TemporalInput {
        cam: &cam,
        prev: &prev,
        params: &params,
        hdr: view(&hdr),
        surface: view(&surface),
        history: view(&history),
        history_surface: view(&history_surface),
    };
    temporal(
        &input,
        view_mut(&mut resolved),
        view_mut(&mut resolved_surface),
    );
    Ok(())
}
