//! A scene on the device: splats, materials and the splat grid, uploaded and built once and
//! shared by every stage. Bind group 1 of the tracing stages is `geometry()`.

use std::time::Instant;

use super::Gpu;
use super::grid::{GpuGrid, build_grid};
use crate::error::Result;
use crate::grid::grid_params;
use crate::photons::ms_since;
use crate::scene::Scene;

pub struct GpuScene {
    pub splats: wgpu::Buffer,
    pub materials: wgpu::Buffer,
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
        Ok(GpuScene {
            splats,
            materials,
            grid,
            grid_ms: ms_since(t),
        })
    }

    /// Bind group 1 of tracing stages, in binding order (see `wgsl/shared/trace.wgsl`).
    pub fn geometry(&self) -> [&wgpu::Buffer; 5] {
        [
            &self.grid.params_buf,
            &self.splats,
            &self.grid.cell_start,
            &self.grid.cell_splats,
            &self.grid.cell_dist,
        ]
    }
}
