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
pub struct GpuGrid {
    pub params: GridParams,
    pub params_buf: wgpu::Buffer,
    /// `cell_count + 1` offsets into `cell_splats`.
    pub cell_start: wgpu::Buffer,
    pub cell_splats: wgpu::Buffer,
    /// Distance field for empty-space skipping (see `SplatGrid::cell_dist`).
    pub cell_dist: wgpu::Buffer,
    /// Number of (cell, splat) entries.
    pub entries: u32,
}

/// Builds the grid of `splats` on the device (`sequence::build_grid`); one readback (the
/// entry total) splits it in two submissions.
pub fn build_grid(gpu: &Gpu, params: &GridParams, splats: &wgpu::Buffer) -> Result<GpuGrid> {
    let mut encoder = gpu.encoder("grid build");
    let built = sequence::build_grid(&mut GpuExecutor::new(gpu, &mut encoder), params, splats)?;
    gpu.submit_and_wait(encoder)?;
    Ok(GpuGrid {
        params: built.params,
        params_buf: built.params_buf,
        cell_start: built.cell_start,
        cell_splats: built.cell_splats,
        cell_dist: built.cell_dist,
        entries: built.params.entry_count,
    })
}

impl GpuGrid {
    pub fn download(&self, gpu: &Gpu) -> Result<SplatGrid> {
        Ok(SplatGrid {
            params: self.params,
            cell_start: gpu.read(&self.cell_start, self.params.cell_count as usize + 1)?,
            cell_splats: gpu.read(&self.cell_splats, self.entries as usize)?,
            cell_dist: gpu.read(&self.cell_dist, self.params.cell_count as usize)?,
        })
    }
}
