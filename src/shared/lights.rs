//! Twin of `wgsl/shared/lights.wgsl`: the irradiance one point of a light brings to a surface
//! point, the stratified points of an area light, and where a ray meets one.

// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec2, Vec3};

use crate::shared::rng::{pcg_hash, unit_float};
use crate::shared::sampling::{PI, frame_of, polar, sample_cosine, smoothstep, to_world};
use crate::shared::trace::FAR;
use crate::types::{Light, light_flags, light_kind, stratified};

/// Roughness below this gives no direct highlight (a mirror needs the lobes, not a sample).
pub const MIN_ALPHA: f32 = 1e-3;

pub struct LightSample {
    pub wi: Vec3,
    pub dist: f32,
    pub e: Vec3,
}

/// An environment light's strata per side, in an area light's (`SKY_STRATA` in WGSL says why).
pub const SKY_STRATA: u32 = 2;

/// The side of the grid of strata a light of `kind` is sampled on, where an area light's has
/// `n`: 1 for a light sampled at one point.
pub fn strata_side(kind: u32, n: u32) -> u32 {
    match kind {
        light_kind::ENVIRONMENT => SKY_STRATA * n,
        k if stratified(k) => n,
        _ => 1,
    }
}

/// The solid angle of the sun's disk: 2π (1 − cos), `cos_inner` holding 1 − cos.
pub fn sun_solid_angle(l: &Light) -> f32 {
    2.0 * PI * l.cos_inner
}

/// The solid-angle pdf of light `l`'s sample along `wi` towards a surface of normal `n` (an
/// area light's point at distance `dist`): 0 for a light sampled at one point.
pub fn light_pdf(sky: &[[f32; 4]], l: &Light, (n, wi): (Vec3, Vec3), dist: f32) -> f32 {
    match l.kind {
        light_kind::AREA => {
            let cos_l = -wi.dot(Vec3::from(l.direction));
            if cos_l > 0.0 {
                dist * dist / (l.area * cos_l)
            } else {
                0.0
            }
        }
        light_kind::ENVIRONMENT => sky_pdf(sky, l, n, wi),
        light_kind::SUN => 1.0 / sun_solid_angle(l),
        _ => 0.0,
    }
}

/// The radiance light `l` sends along −d to a ray `d` that leaves the scene: a sky's, or the
/// sun's where `d` lies in its disk.
pub fn escaped_radiance(sky: &[[f32; 4]], l: &Light, d: Vec3) -> Vec3 {
    match l.kind {
        light_kind::ENVIRONMENT => sky_radiance(sky, l, d),
        light_kind::SUN if -d.dot(Vec3::from(l.direction)) >= l.cos_outer => {
            Vec3::from(l.power) / (l.area * sun_solid_angle(l))
        }
        _ => Vec3::ZERO,
    }
}

/// Rec. 709 luminance, the sky's sampling weight (`scene::sky`).
fn sky_luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The sky's width and height (`SkyTable`'s header; 0 × 0 where the scene has none).
fn sky_size(sky: &[[f32; 4]]) -> (u32, u32) {
    (sky[0][0] as u32, sky[0][1] as u32)
}

/// The first of `count` entries from `first` whose component `c` exceeds `x` (a cumulative
/// distribution's pick), the last where none does.
fn sky_pick(sky: &[[f32; 4]], first: u32, count: u32, c: usize, x: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, count - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if sky[(first + mid) as usize][c] > x {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// Where `x` lies between the cumulative shares before and at entry `k` (of the run from
/// `first`), in [0, 1).
fn sky_remap(sky: &[[f32; 4]], first: u32, k: u32, c: usize, x: f32) -> f32 {
    let before = if k > 0 {
        sky[(first + k - 1) as usize][c]
    } else {
        0.0
    };
    let span = sky[(first + k) as usize][c] - before;
    if span > 0.0 {
        ((x - before) / span).clamp(0.0, 0.999_999)
    } else {
        0.5
    }
}

/// The solid-angle pdf of sampling texel (x, y) at sin θ, by the texel's radiance `c`.
fn sky_texel_pdf(sky: &[[f32; 4]], c: Vec3, y: u32, sin_theta: f32) -> f32 {
    let (w, h) = sky_size(sky);
    let sin_row = (PI * (y as f32 + 0.5) / h as f32).sin();
    let pdf_uv = sky_luminance(c) * sin_row * (w * h) as f32 / sky[0][2];
    if sin_theta > 0.0 {
        pdf_uv / (2.0 * PI * PI * sin_theta)
    } else {
        0.0
    }
}

/// The texel of `sky` that direction `d` (world) looks at through environment light `l`'s
/// frame: its entry, its row, and the sine of `d`'s angle to the map's up axis.
fn sky_texel(sky: &[[f32; 4]], l: &Light, d: Vec3) -> (usize, u32, f32) {
    let (w, h) = sky_size(sky);
    let local = Vec3::new(
        d.dot(Vec3::from(l.edge_u)),
        d.dot(Vec3::from(l.direction)),
        d.dot(Vec3::from(l.edge_v)),
    );
    let mut u = local.x.atan2(-local.z) / (2.0 * PI);
    if u < 0.0 {
        u += 1.0;
    }
    // sin θ from the two other components, θ by atan2: exact near the poles, where
    // sqrt(1 − cos²) and acos lose their digits.
    let sin_theta = Vec2::new(local.x, local.z).length();
    let v = sin_theta.atan2(local.y) / PI;
    let x = ((u * w as f32) as u32).min(w - 1);
    let y = ((v * h as f32) as u32).min(h - 1);
    ((1 + y * w + x) as usize, y, sin_theta)
}

/// `Sky::irradiance`'s grid of normals: 128 × 65, 2.8° a step, where reading it bilinearly is
/// within about 0.1 % of the irradiance round a sun-like peak.
pub const IRRADIANCE_W: u32 = 128;
pub const IRRADIANCE_H: u32 = 65;

/// The unshadowed irradiance environment light `l` gives a surface of normal `n`: its table
/// (`Sky::irradiance`, after the map's rows; its first and last rows the poles) read
/// bilinearly, across the seam at φ = 0.
pub fn sky_irradiance(sky: &[[f32; 4]], l: &Light, n: Vec3) -> Vec3 {
    let (w, h) = sky_size(sky);
    let first = 1 + w * h + h;
    let local = Vec3::new(
        n.dot(Vec3::from(l.edge_u)),
        n.dot(Vec3::from(l.direction)),
        n.dot(Vec3::from(l.edge_v)),
    );
    let u = local.x.atan2(-local.z) / (2.0 * PI);
    let v = Vec2::new(local.x, local.z).length().atan2(local.y) / PI;
    let (ew, eh) = (IRRADIANCE_W as f32, IRRADIANCE_H as f32);
    let fx = u * ew;
    let fy = (v * (eh - 1.0)).clamp(0.0, eh - 1.0);
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let wrap = |x: f32| (x.rem_euclid(ew) as u32).min(IRRADIANCE_W - 1);
    let (xa, xb) = (wrap(x0), wrap(x0 + 1.0));
    let ya = y0 as u32;
    let yb = (ya + 1).min(IRRADIANCE_H - 1);
    let at = |x: u32, y: u32| Vec3::from_slice(&sky[(first + y * IRRADIANCE_W + x) as usize][..3]);
    let top = at(xa, ya).lerp(at(xb, ya), tx);
    let bottom = at(xa, yb).lerp(at(xb, yb), tx);
    top.lerp(bottom, ty)
}

/// The radiance environment light `l` sends along −d (arriving from direction `d`).
pub fn sky_radiance(sky: &[[f32; 4]], l: &Light, d: Vec3) -> Vec3 {
    Vec3::from_slice(&sky[sky_texel(sky, l, d).0][..3])
}

/// The solid-angle pdf with which `sample_sky_map` picks direction `d` of environment light `l`.
pub fn sky_map_pdf(sky: &[[f32; 4]], l: &Light, d: Vec3) -> f32 {
    let (entry, y, sin_theta) = sky_texel(sky, l, d);
    sky_texel_pdf(sky, Vec3::from_slice(&sky[entry][..3]), y, sin_theta)
}

/// The solid-angle pdf with which `sample_light` picks direction `d` of environment light `l`
/// for a surface of normal `n`: half by the map, half by the cosine about `n`.
pub fn sky_pdf(sky: &[[f32; 4]], l: &Light, n: Vec3, d: Vec3) -> f32 {
    0.5 * (sky_map_pdf(sky, l, d) + n.dot(d).max(0.0) / PI)
}

/// A direction of environment light `l` picked by the unit square's point (u, v) in
/// proportion to its radiance's luminance times its solid angle: the row by the rows' shares,
/// the texel by its row's, the point within the texel uniformly. `e` is its radiance over its
/// pdf (zero where the pdf is). Photons leave the sky so; surfaces take `sample_sky`.
pub fn sample_sky_map(sky: &[[f32; 4]], l: &Light, u: f32, v: f32) -> LightSample {
    let (w, h) = sky_size(sky);
    let rows = 1 + w * h;
    let y = sky_pick(sky, rows, h, 0, v);
    let fy = sky_remap(sky, rows, y, 0, v);
    let x = sky_pick(sky, 1 + y * w, w, 3, u);
    let fx = sky_remap(sky, 1 + y * w, x, 3, u);
    let phi = 2.0 * PI * (x as f32 + fx) / w as f32;
    let theta = PI * (y as f32 + fy) / h as f32;
    let (sin_t, cos_t) = theta.sin_cos();
    let (sin_p, cos_p) = phi.sin_cos();
    let wi = (sin_t * sin_p) * Vec3::from(l.edge_u)
        + cos_t * Vec3::from(l.direction)
        + (-sin_t * cos_p) * Vec3::from(l.edge_v);
    let c = Vec3::from_slice(&sky[(1 + y * w + x) as usize][..3]);
    let pdf = sky_texel_pdf(sky, c, y, sin_t);
    let e = if pdf > 0.0 { c / pdf } else { Vec3::ZERO };
    LightSample { wi, dist: FAR, e }
}

/// A direction of environment light `l` towards a surface of normal `n`: the unit square's
/// left half picks it by the map (`sample_sky_map`), its right half by the cosine about `n`,
/// and `e` weighs the radiance by the power heuristic of the two, each taking half the
/// samples (`e = 2 w L / p` of its own strategy; why in `wgsl/shared/lights.wgsl`).
fn sample_sky(sky: &[[f32; 4]], l: &Light, n: Vec3, u: f32, v: f32) -> LightSample {
    let by_map = u < 0.5;
    let wi = if by_map {
        sample_sky_map(sky, l, 2.0 * u, v).wi
    } else {
        to_world(&frame_of(n), sample_cosine(2.0 * u - 1.0, v))
    };
    let p_map = sky_map_pdf(sky, l, wi);
    let p_cos = n.dot(wi).max(0.0) / PI;
    let own = if by_map { p_map } else { p_cos };
    let both = p_map * p_map + p_cos * p_cos;
    let e = if own > 0.0 {
        sky_radiance(sky, l, wi) * (2.0 * own / both)
    } else {
        Vec3::ZERO
    };
    LightSample { wi, dist: FAR, e }
}

pub fn spot_falloff_mean(l: &Light) -> f32 {
    if l.cos_inner <= l.cos_outer {
        return 1.0;
    }
    ((l.cos_inner - l.cos_outer) * 0.5 + (1.0 - l.cos_inner)) / (1.0 - l.cos_outer)
}

/// A point of light `l` towards `p`, a surface of normal `n`: (u, v) picks the point of an
/// area light, the direction of an environment light (whose map `sky` holds, `SkyTable`) or
/// of the sun's disk.
pub fn sample_light(sky: &[[f32; 4]], l: &Light, p: Vec3, n: Vec3, u: f32, v: f32) -> LightSample {
    if l.kind == light_kind::ENVIRONMENT {
        return sample_sky(sky, l, n, u, v);
    }
    sample_emitter(l, p, u, v)
}

/// `sample_light` of any light but the sky, which reads no map (`sample_emitter` in WGSL).
pub fn sample_emitter(l: &Light, p: Vec3, u: f32, v: f32) -> LightSample {
    let power = Vec3::from(l.power);
    let axis = Vec3::from(l.direction);
    if l.kind == light_kind::DIRECTIONAL || l.kind == light_kind::SUN {
        let wi = if l.kind == light_kind::SUN {
            // Uniform over the disk's cone (`sample_cone`, with 1 − cos exact).
            to_world(&frame_of(-axis), polar(1.0 - u * l.cos_inner, v))
        } else {
            -axis
        };
        return LightSample {
            wi,
            dist: FAR,
            e: power / l.area,
        };
    }
    let mut q = Vec3::from(l.position);
    if l.kind == light_kind::AREA {
        q += u * Vec3::from(l.edge_u) + v * Vec3::from(l.edge_v);
    }
    let to = q - p;
    let d2 = to.dot(to);
    let dist = d2.sqrt();
    let wi = to / dist;
    let cos_l = -wi.dot(axis);
    let e = if l.kind == light_kind::AREA {
        power * (cos_l.max(0.0) / (PI * d2))
    } else if l.kind == light_kind::SPOT {
        let ramp = if l.cos_inner > l.cos_outer {
            smoothstep(l.cos_outer, l.cos_inner, cos_l)
        } else {
            1.0
        };
        let inside = if cos_l >= l.cos_outer { ramp } else { 0.0 };
        let solid_angle = 2.0 * PI * (1.0 - l.cos_outer);
        power * (inside / (spot_falloff_mean(l) * solid_angle * d2))
    } else {
        power / (4.0 * PI * d2)
    };
    LightSample { wi, dist, e }
}

pub fn area_point(j: u32, n: u32, r: u32, jitter: bool) -> Vec2 {
    let inv_n = 1.0 / n as f32;
    let o = if jitter {
        Vec2::new(
            unit_float(pcg_hash(r)),
            unit_float(pcg_hash(r.wrapping_add(1))),
        )
    } else {
        Vec2::splat(0.5)
    };
    (Vec2::new((j % n) as f32, (j / n) as f32) + o) * inv_n
}

/// Whether ray `(o, d)` meets area light `l` before distance `t` (a surface's hit) and ends
/// there. A light that reflects (`light_flags::REFLECTS`) ends nothing: the ray goes on to its
/// surface's splats just behind its face, which reflect as any surface does.
pub fn light_first(l: &Light, o: Vec3, d: Vec3, t: f32) -> bool {
    if l.flags & light_flags::REFLECTS != 0 {
        return false;
    }
    let tl = area_light_hit(l, o, d);
    tl > 0.0 && tl < t
}

/// How far a shadow ray from `o` (its surface point lifted by `bias`) towards a sample of light
/// `l` at `dist` from that point looks for what shadows it: `dist - bias`, and for a light that
/// reflects no farther than its face, so that its own surface just behind that face never
/// shadows it (the lifted ray can cross the face before `dist - bias`).
pub fn shadow_reach(l: &Light, o: Vec3, wi: Vec3, dist: f32, bias: f32) -> f32 {
    let reach = dist - bias;
    if l.flags & light_flags::REFLECTS == 0 {
        return reach;
    }
    let t = area_light_hit(l, o, wi);
    if t > 0.0 { reach.min(t) } else { reach }
}

/// Where ray `(o, d)` meets area light `l`'s emitting face: `t > 0`, or -1 when it misses it.
pub fn area_light_hit(l: &Light, o: Vec3, d: Vec3) -> f32 {
    let axis = Vec3::from(l.direction);
    let denom = d.dot(axis);
    if l.kind != light_kind::AREA || !(denom < 0.0) {
        return -1.0;
    }
    let corner = Vec3::from(l.position);
    let (eu, ev) = (Vec3::from(l.edge_u), Vec3::from(l.edge_v));
    let t = (corner - o).dot(axis) / denom;
    let q = o + t * d - corner;
    let u = q.dot(eu) / eu.dot(eu);
    let v = q.dot(ev) / ev.dot(ev);
    if t > 0.0 && (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v) {
        t
    } else {
        -1.0
    }
}
