//! A scene on the device: splats, materials and the splat grid, uploaded and built once and
//! shared by every stage. Bind group 1 of the tracing stages is `geometry()`.

use std::time::Instant;

use super::Gpu;
use super::exec::GeometryBuffers;
use super::grid::{GpuGrid, build_grid};
use crate::error::Result;
use crate::grid::grid_params;
use crate::scene::Scene;
use crate::shared::splat::DRAWN_CLIPS;
use crate::timing::ms_since;
use crate::types::{Splat, SurfaceClip};

pub struct GpuScene {
    pub splats: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    /// `Scene::clips`, at least one entry (a zero clip keeps every hit).
    pub clips: wgpu::Buffer,
    /// The drawing passes' uniform of clips (`drawn_clips`).
    pub drawn_clips: wgpu::Buffer,
    /// The environment light's map (`Scene::sky`), and whether the scene has one.
    pub sky: wgpu::Buffer,
    pub has_sky: bool,
    pub grid: GpuGrid,
    /// Time to upload the splats and build the grid.
    pub grid_ms: f64,
}

impl GpuScene {
    pub fn upload(gpu: &Gpu, scene: &Scene) -> Result<GpuScene> {
        let t = Instant::now();
        let params = grid_params(&scene.splats, &scene.grid)?;
        let splats = gpu.storage("splats", &scene.splats)?;
        let materials = gpu.storage("materials", &scene.materials)?;
        let grid = build_grid(gpu, &params, &splats)?;
        let clips = gpu.storage("surface clips", &device_clips(&scene.clips, &scene.splats))?;
        let drawn = drawn_clips(&scene.clips);
        let drawn_clips = gpu.uniform("drawn clips", &drawn);
        let sky = gpu.storage("sky", scene.sky.entries())?;
        Ok(GpuScene {
            splats,
            materials,
            clips,
            drawn_clips,
            sky,
            has_sky: scene.sky.entries().len() > 1,
            grid,
            grid_ms: ms_since(t),
        })
    }

    /// Bind group 1 of tracing stages, in binding order (see `wgsl/shared/trace.wgsl`).
    pub fn geometry(&self) -> GeometryBuffers<'_> {
        [
            &self.grid.params_buf,
            &self.splats,
            &self.grid.cell_start,
            &self.grid.cell_splats,
            &self.grid.cell_dist,
            &self.clips,
            &self.sky,
        ]
    }
}

/// The clips the drawing passes hold (`wgsl/shared/drawn_clip.wgsl`): the first
/// `DRAWN_CLIPS` − 1 surfaces', then zero (a later surface is drawn unclipped, as the mirror
/// draws it).
pub fn drawn_clips(clips: &[SurfaceClip]) -> [SurfaceClip; DRAWN_CLIPS] {
    let mut out = [SurfaceClip::default(); DRAWN_CLIPS];
    for (slot, c) in out.iter_mut().zip(clips.iter().take(DRAWN_CLIPS - 1)) {
        *slot = *c;
    }
    out
}

/// A scene's surface clips as the device binds them: an entry for every surface a splat names
/// (a zero clip, which keeps every hit, for those the scene has none for, as the mirror reads
/// them), at least one.
pub fn device_clips(clips: &[SurfaceClip], splats: &[Splat]) -> Vec<SurfaceClip> {
    let named = splats
        .iter()
        .map(|s| s.object as usize + 1)
        .max()
        .unwrap_or(0);
    let mut out = clips.to_vec();
    out.resize(clips.len().max(named).max(1), SurfaceClip::default());
    out
}
