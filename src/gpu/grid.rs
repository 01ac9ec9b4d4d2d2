//! Splat grid build on the device: `sequence::build_grid` (count → exclusive scan → scatter →
//! rank → distance field), as `cpu::build_grid` runs it. The result stays on the device for
//! tracing; `download` brings it back.

use super::Gpu;
use super::exec::GpuExecutor;
use crate::error::Result;
use crate::grid::SplatGrid;
use crate::sequence;
use crate::types::GridParams;

/// The grid on the device.
pub type GpuGrid = sequence::BuiltGrid<wgpu::Buffer>;

/// Builds the grid of `splats` on the device (`sequence::build_grid`); one readback (the
/// entry total) splits it in two submissions.
pub fn build_grid(gpu: &Gpu, params: &GridParams, splats: &wgpu::Buffer) -> Result<GpuGrid> {
    let mut encoder = gpu.encoder("grid build");
    let built = sequence::build_grid(&mut GpuExecutor::new(gpu, &mut encoder), params, splats)?;
    gpu.submit_and_wait(encoder)?;
    Ok(built)
}

impl GpuGrid {
    pub fn download(&self, gpu: &Gpu) -> Result<SplatGrid> {
        self.read_back(&mut GpuExecutor::new(
            gpu,
            &mut gpu.encoder("grid download"),
        ))
    }
}
