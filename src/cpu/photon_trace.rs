//! Mirror of `wgsl/photon_trace.wgsl`. Workgroups run in parallel (rayon); their stored
//! photons are appended in workgroup order, so the mirror's output order is deterministic
//! (the GPU's is not; `Photon::key` is the same on both).
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;

use crate::shared::lights::{light_first, sample_sky_map};
use crate::shared::rng::*;
use crate::shared::sampling::*;
use crate::shared::trace::{FAR, Geometry, trace_ray};
use crate::shared::ward;
use crate::types::{Emitter, Material, NO_SPLAT, Photon, TraceCounters, TraceParams, light_kind};

pub const WG: u32 = 64;

/// The emitter owning a path: the last one whose first index is ≤ path (binary search).
fn find_emitter(params: &TraceParams, emitters: &[Emitter], path: u32) -> u32 {
    let (mut lo, mut hi) = (0u32, params.emitter_count);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if emitters[mid as usize].first <= path {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

struct Emission {
    origin: Vec3,
    direction: Vec3,
    power: Vec3,
}

fn emit(params: &TraceParams, emitters: &[Emitter], sky: &[[f32; 4]], path: u32, key: u32) -> Emission {
    let em = &emitters[find_emitter(params, emitters, path) as usize];
    let l = &em.light;
    let p1 = rand(key, 0, RNG_EMIT_POS_U);
    let p2 = rand(key, 0, RNG_EMIT_POS_V);
    let d1 = rand(key, 0, RNG_EMIT_DIR_U);
    let d2 = rand(key, 0, RNG_EMIT_DIR_V);
    let position = Vec3::from(l.position);
    let axis = Vec3::from(l.direction);
    let mut power = Vec3::from(em.photon_power);
    let (origin, direction) = match l.kind {
        light_kind::POINT => (position, sample_sphere(d1, d2)),
        light_kind::SPOT => {
            let v = sample_cone(d1, d2, l.cos_outer);
            let falloff = if l.cos_inner > l.cos_outer {
                smoothstep(l.cos_outer, l.cos_inner, v.z)
            } else {
                1.0
            };
            power *= falloff * em.falloff_norm;
            (position, to_world(&frame_of(axis), v))
        }
        light_kind::AREA => (
            position + p1 * Vec3::from(l.edge_u) + p2 * Vec3::from(l.edge_v),
            to_world(&frame_of(axis), sample_cosine(d1, d2)),
        ),
        light_kind::ENVIRONMENT => {
            // A direction by the map's distribution; the photon comes from a disk across the
            // scene's bounds, two of its radii out that way, and carries the disk's share of
            // the light arriving from there: L / pdf times the disk's area over the photons.
            let s = sample_sky_map(sky, l, d1, d2);
            let f = frame_of(-s.wi);
            let r = (l.area / PI).sqrt();
            let q = sample_disk(p1, p2) * r;
            power = s.e * (l.area / em.count as f32);
            (position + s.wi * (2.0 * r) + f.t * q.x + f.b * q.y, -s.wi)
        }
        // Directional and sun lights, from a disk of area `l.area` across the scene.
        _ => {
            let f = frame_of(axis);
            let q = sample_disk(p1, p2) * (l.area / PI).sqrt();
            let direction = if l.kind == light_kind::SUN {
                // Spread over the sun's cone (1 − cos exact in `cos_inner`).
                to_world(&f, polar(1.0 - d1 * l.cos_inner, d2))
            } else {
                axis
            };
            (position + f.t * q.x + f.b * q.y, direction)
        }
    };
    Emission {
        origin,
        direction,
        power,
    }
}

/// How a path ended, one counter each.
enum End {
    Escaped,
    Absorbed,
    DepthCapped,
    Aborted,
}

/// Whether the ray meets an area light's face before distance `t`: the photon ends there.
fn meets_light(params: &TraceParams, emitters: &[Emitter], o: Vec3, d: Vec3, t: f32) -> bool {
    emitters[..params.emitter_count as usize]
        .iter()
        .any(|e| light_first(&e.light, o, d, t))
}

/// One invocation of `main`: the photons it stores, in order, and how its path ended.
fn trace_path(
    params: &TraceParams,
    emitters: &[Emitter],
    materials: &[Material],
    geo: &Geometry,
    i: u32,
    out: &mut Vec<Photon>,
) -> End {
    let path = params.path_offset + i;
    let key = path_key(params.seed, path);
    let e = emit(params, emitters, geo.sky, path, key);
    let (mut o, mut d, mut power) = (e.origin, e.direction, e.power);
    let mut skip = NO_SPLAT;
    let mut budget = params.iteration_budget;
    for bounce in 0..params.max_depth {
        let hit = trace_ray(geo, o, d, skip, FAR, &mut budget);
        if hit.aborted != 0 {
            return End::Aborted;
        }
        if meets_light(params, emitters, o, d, hit.t) {
            return End::Absorbed;
        }
        if hit.splat == NO_SPLAT {
            return End::Escaped;
        }
        let s = &geo.splats[hit.splat as usize];
        let p = o + hit.t * d;
        let wi = -d;
        if bounce >= params.min_bounce {
            out.push(Photon {
                position: p.into(),
                bounce,
                direction: wi.into(),
                splat: hit.splat,
                power: power.into(),
                path,
            });
        }
        if bounce + 1 == params.max_depth {
            break;
        }
        let m = &materials[s.material as usize];
        let diffuse = Vec3::from(s.diffuse);
        let specular = Vec3::from(m.specular);
        let u = rand(key, bounce, RNG_ROULETTE);
        let u1 = rand(key, bounce, RNG_BOUNCE_U);
        let u2 = rand(key, bounce, RNG_BOUNCE_V);
        let f = frame_of(Vec3::from(s.normal));
        let next = ward::sample_bounce(&f, wi, diffuse, specular, m.roughness, u, u1, u2);
        if !next.alive {
            return End::Absorbed;
        }
        d = next.dir;
        power *= next.weight;
        o = p;
        skip = hit.splat;
    }
    End::DepthCapped
}

pub fn photon_trace(
    params: &TraceParams,
    emitters: &[Emitter],
    materials: &[Material],
    photons: &mut [Photon],
    counters: &mut TraceCounters,
    geo: &Geometry,
    groups: u32,
) {
    let per_group: Vec<(Vec<Photon>, [u32; 4])> = (0..groups)
        .into_par_iter()
        .map(|wg| {
            let mut stored = Vec::new();
            let mut ends = [0u32; 4];
            for lid in 0..WG {
                let i = wg * WG + lid;
                if i >= params.path_count {
                    continue;
                }
                let end = trace_path(params, emitters, materials, geo, i, &mut stored);
                ends[end as usize] += 1;
            }
            (stored, ends)
        })
        .collect();
    for (stored, ends) in per_group {
        for p in stored {
            let slot = counters.stored;
            counters.stored += 1;
            if slot < counters.capacity {
                photons[slot as usize] = p;
            } else {
                counters.overflow = 1;
            }
        }
        counters.escaped += ends[End::Escaped as usize];
        counters.absorbed += ends[End::Absorbed as usize];
        counters.depth_capped += ends[End::DepthCapped as usize];
        counters.aborted += ends[End::Aborted as usize];
    }
}

/// The executor's entry: `photon_trace`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, geo: &Geometry, groups: u32) -> Result<()> {
    let p = b.param(0)?;
    let emitters = b.get(1)?;
    let materials = b.get(2)?;
    let mut store = b.get_mut(3)?;
    let mut counters = b.get_mut(4)?;
    let counters = view_mut(&mut counters)
        .first_mut()
        .ok_or_else(|| b.internal("counters too short"))?;
    let (emitters, materials) = (view(&emitters), view(&materials));
    let store = view_mut(&mut store);
    photon_trace(&p, emitters, materials, store, counters, geo, groups);
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::PhotonTrace,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Traced(dispatch)),
    },
];
