//! Back sides for open models (docs/design.md §4, "Open surfaces").
//!
//! Disks are one-sided: a ray meets a disk only against its normal. On a closed surface that is
//! what light does, since a disk's back faces the inside, which no light reaches. On an open
//! sheet (a scan from one viewpoint, a facade) it is not: light reaching the sheet from behind
//! passes through it, while light going the other way stops at its front. Light is then not
//! reciprocal, and the photons (light to surface) and the path tracer (surface to light) part:
//! by up to 12 % on the walls and floor round a scanned sheet, in indirect light, while direct
//! light (shadow rays both) agreed. A model whose backs face the scene therefore gets a back
//! side: each disk a twin behind it, facing the other way, of the same material and surface,
//! which closes the sheet into a thin shell, as a scanned object is.
//!
//! Whether a model's backs face the scene is traced at load: from the backs of up to `SAMPLES`
//! of its disks, rays along the back normal, four around it and one towards each light behind
//! the disk. A back sees the scene where such a ray's first disk shows it its front (a wall, the
//! floor, another part of the sheet) on `SEEING_RAYS` of the five, or a light ray reaches its
//! light; it faces an inside where the first disk shows its back (a closed model's far side).
//! Rays that leave the scene meet nothing. A model gets back sides when more than `OPEN_SHARE` of its sampled backs see the
//! scene; `sides = "one"` or `"two"` decides instead.

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use super::Scene;
use super::file::Sides;
use crate::grid::{GridConfig, SplatGrid, grid_params, host_lists};
use crate::shared::trace::{FAR, trace_sided};
use crate::types::{NO_SPLAT, Splat, light_kind};

/// Most disks of a model whose backs are traced: enough to tell a sheet from a closed model,
/// few enough that their rays cost milliseconds at any size. Most of the load's added time is
/// the cell lists of all the scene's splats, built once (+0.12 s for a 1 M-point scan).
pub const SAMPLES: usize = 4096;

/// Of the five rays around a back's normal, how many must meet a front for the back to see the
/// scene: one alone is often a neighbour's front across a fold or a rough patch (a closed
/// bunny's backs: 7.3 % with one, 5.2 % with two).
pub const SEEING_RAYS: usize = 2;

/// The share of a model's sampled backs that must see the scene for it to get back sides. The
/// backs of closed models that see it are those at holes, thin parts and misturned faces: 5.2 %
/// of the bunny's, 2.5 % and 2.3 % of the two dragons', 1.3 % of the Cornell box's OBJ (open
/// walls, closed blocks); a sheet's nearly all do (99.2–99.7 % of the bunny's single-view
/// scans). A model part open and part closed gets them too.
pub const OPEN_SHARE: f64 = 0.25;

/// How far behind its disk a back side lies, in the disk's radius: past the sag of a curved
/// surface between neighbours (a ray leaving one disk would otherwise meet its neighbour's
/// back side), thin against the model.
pub const BACK_OFFSET: f32 = 1.0;

/// Lights towards which a back looks, at most (the first of the scene's).
const LIGHT_RAYS: usize = 8;

/// Cell steps and disk tests one ray may take.
const RAY_BUDGET: u32 = 1 << 20;

/// A model's splats in the scene and which of them get a back side.
pub struct ModelSplats {
    /// The model's entry in `Scene::objects`.
    pub object: usize,
    pub range: Range<usize>,
    pub sides: Sides,
}

/// Adds back sides to the models that need them, each model's right after its own splats, and
/// counts them in the objects' summaries.
pub fn add_back_sides(scene: &mut Scene, models: &[ModelSplats]) -> Result<(), String> {
    // The scene's cell lists, built for the first model whose backs are traced.
    let mut lists = None;
    let open: Vec<bool> = (models.iter())
        .map(|m| match m.sides {
            Sides::One => false,
            Sides::Two => true,
            Sides::Auto => {
                let grid = lists.get_or_insert_with(|| cell_lists(scene));
                (grid.as_ref()).is_some_and(|g| open_share(scene, g, &m.range) > OPEN_SHARE)
            }
        })
        .collect();
    let added: usize = models
        .iter()
        .zip(&open)
        .filter(|(_, o)| **o)
        .map(|(m, _)| m.range.len())
        .sum();
    if added == 0 {
        return Ok(());
    }
    let total = (scene.splats.len() + added) as f64;
    scene
        .budget
        .check_points("the scene with its models' back sides", total)?;
    let mut splats = Vec::with_capacity(scene.splats.len() + added);
    let mut done = 0;
    for (m, &open) in models.iter().zip(&open) {
        splats.extend_from_slice(&scene.splats[done..m.range.end]);
        done = m.range.end;
        if open {
            splats.extend(scene.splats[m.range.clone()].iter().map(back_side));
            let summary = &mut scene.objects[m.object];
            summary.splats += m.range.len();
            summary.back_sides = m.range.len();
        }
    }
    splats.extend_from_slice(&scene.splats[done..]);
    scene.splats = splats;
    Ok(())
}

/// The twin of disk `s` that faces the other way, `BACK_OFFSET` of its radius behind it.
pub fn back_side(s: &Splat) -> Splat {
    let n = Vec3::from(s.normal);
    Splat {
        center: (Vec3::from(s.center) - BACK_OFFSET * s.radius * n).into(),
        normal: (-n).into(),
        ..*s
    }
}

/// The cell lists the backs' rays walk: a cell a splat (a grid of the stages' shape would take
/// 8, for rays that are few), none where the scene's bounds make no grid.
fn cell_lists(scene: &Scene) -> Option<SplatGrid> {
    let config = GridConfig {
        cells_per_splat: 1.0,
        ..scene.grid
    };
    let params = grid_params(&scene.splats, &config).ok()?;
    Some(host_lists(&params, &scene.splats))
}

/// The share of the sampled disks of `range` whose backs see the scene.
fn open_share(scene: &Scene, grid: &SplatGrid, range: &Range<usize>) -> f64 {
    if range.is_empty() {
        return 0.0;
    }
    let geo = scene.geometry(grid);
    let stride = range.len().div_ceil(SAMPLES);
    let sampled: Vec<usize> = range.clone().step_by(stride).collect();
    let seeing = sampled
        .par_iter()
        .filter(|&&i| back_sees_scene(scene, &geo, i))
        .count();
    seeing as f64 / sampled.len() as f64
}

/// Whether the back of splat `i` sees the scene (the module's comment).
fn back_sees_scene(scene: &Scene, geo: &crate::shared::trace::Geometry, i: usize) -> bool {
    let s = &scene.splats[i];
    let (c, n) = (Vec3::from(s.center), Vec3::from(s.normal));
    // Rays start a radius out, past the neighbours' planes a curved surface tilts across.
    let from = |d: Vec3| c + s.radius * d;
    let meets_front = |d: Vec3, t_max: f32| -> Option<bool> {
        let mut budget = RAY_BUDGET;
        let hit = trace_sided::<true>(geo, from(d), d, i as u32, t_max, &mut budget);
        if hit.aborted != 0 {
            return Some(false);
        }
        (hit.splat != NO_SPLAT)
            .then(|| Vec3::from(geo.splats[hit.splat as usize].normal).dot(d) < 0.0)
    };
    let (t1, t2) = n.any_orthonormal_pair();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let around = [-n, h * (t1 - n), h * (-t1 - n), h * (t2 - n), h * (-t2 - n)];
    let seeing = around
        .iter()
        .filter(|&&d| meets_front(d, FAR) == Some(true));
    if seeing.count() >= SEEING_RAYS {
        return true;
    }
    scene.lights.iter().take(LIGHT_RAYS).any(|l| {
        let p = Vec3::from(l.position);
        let (to, dist) = match l.kind {
            light_kind::DIRECTIONAL | light_kind::SUN => (-Vec3::from(l.direction), FAR),
            // A sky lights a back from the way it faces.
            light_kind::ENVIRONMENT => (-n, FAR),
            light_kind::AREA => {
                let centre = p + 0.5 * (Vec3::from(l.edge_u) + Vec3::from(l.edge_v));
                if (c - centre).dot(Vec3::from(l.direction)) <= 0.0 {
                    return false;
                }
                let v = centre - c;
                (v.normalize_or_zero(), v.length() - s.radius)
            }
            _ => {
                let v = p - c;
                (v.normalize_or_zero(), v.length() - s.radius)
            }
        };
        to.dot(n) < 0.0 && dist > 0.0 && meets_front(to, dist).unwrap_or(true)
    })
}
