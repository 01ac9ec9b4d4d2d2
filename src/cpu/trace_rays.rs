//! Mirror of `wgsl/trace_rays.wgsl`.

use super::MirrorRow;
use crate::shaders::Stage;
use glam::Vec3;

use crate::shared::trace::{Geometry, trace_ray};
use crate::types::{Hit, Ray, TraceParams};

pub const WG: u32 = 64;

pub fn trace_rays(
    params: &TraceParams,
    rays: &[Ray],
    hits: &mut [Hit],
    geo: &Geometry,
    groups: u32,
) {
    for wg in 0..groups {
        for lid in 0..WG {
            let i = wg * WG + lid;
            if i >= params.path_count {
                continue;
            }
            let r = &rays[i as usize];
            let mut budget = params.iteration_budget;
            hits[i as usize] = trace_ray(
                geo,
                Vec3::from(r.origin),
                Vec3::from(r.direction),
                r.skip,
                r.t_max,
                &mut budget,
            );
        }
    }
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::TraceRays,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
];
