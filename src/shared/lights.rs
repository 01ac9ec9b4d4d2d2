//! Twin of `wgsl/shared/lights.wgsl`: the irradiance one point of a light brings to a surface
//! point, the stratified points of an area light, and where a ray meets one.

// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec2, Vec3};

use crate::shared::rng::{pcg_hash, unit_float};
use crate::shared::sampling::{PI, smoothstep};
use crate::shared::trace::FAR;
use crate::types::{Light, light_flags, light_kind};

/// Roughness below this gives no direct highlight (a mirror needs the lobes, not a sample).
pub const MIN_ALPHA: f32 = 1e-3;

pub struct LightSample {
    pub wi: Vec3,
    pub dist: f32,
    pub e: Vec3,
}

pub fn spot_falloff_mean(l: &Light) -> f32 {
    if l.cos_inner <= l.cos_outer {
        return 1.0;
    }
    ((l.cos_inner - l.cos_outer) * 0.5 + (1.0 - l.cos_inner)) / (1.0 - l.cos_outer)
}

pub fn sample_light(l: &Light, p: Vec3, u: f32, v: f32) -> LightSample {
    let power = Vec3::from(l.power);
    let axis = Vec3::from(l.direction);
    if l.kind == light_kind::DIRECTIONAL {
        return LightSample {
            wi: -axis,
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
