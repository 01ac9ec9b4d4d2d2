//! Splat grid build on the GPU: count → exclusive scan → scatter → rank, the same passes as
//! `cpu::build_grid`. The result stays on the device for tracing; `download` brings it back.

use super::{Gpu, scan};
use crate::error::{Error, Result};
use crate::grid::{SplatGrid, check_cell_len};
use crate::types::{DistanceParams, GridParams};

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

pub fn build_grid(gpu: &Gpu, params: &GridParams, splats: &wgpu::Buffer) -> Result<GpuGrid> {
    let params_buf = gpu.uniform("grid params", params);
    let cells = params.cell_count as u64;
    let cell_start = gpu.storage_zeroed("cell start", (cells + 1) * 4)?;

    let max_cell_len = gpu.storage_zeroed("grid max cell length", 4)?;
    let mut encoder = gpu.encoder("grid count");
    gpu.dispatch(
        &mut encoder,
        "grid_count",
        &[&params_buf, splats, &cell_start, &max_cell_len],
        gpu.groups("grid_count", params.splat_count)?,
    )?;
    scan::exclusive_scan(gpu, &mut encoder, &cell_start, params.cell_count + 1)?;
    // stats = [entry total (last scan value), longest cell list]
    let stats = gpu.storage_zeroed("grid stats", 8)?;
    encoder.copy_buffer_to_buffer(&cell_start, cells * 4, &stats, 0, 4);
    encoder.copy_buffer_to_buffer(&max_cell_len, 0, &stats, 4, 4);
    gpu.submit_and_wait(encoder)?;

    // The total sizes the entry list; this readback is the only sync of the build.
    let stats: Vec<u32> = gpu.read(&stats, 2)?;
    let (entries, max_cell_len) = match stats[..] {
        [e, m] => (e, m),
        _ => return Err(Error::Gpu("grid stats readback was short".into())),
    };
    check_cell_len(max_cell_len)?;

    let params = GridParams {
        entry_count: entries,
        ..*params
    };
    gpu.queue
        .write_buffer(&params_buf, 0, bytemuck::bytes_of(&params));
    let bytes = entries as u64 * 4;
    let cursor = gpu.storage_zeroed("cell cursor", cells * 4)?;
    let scratch_splats = gpu.storage_zeroed("scratch splats", bytes)?;
    let scratch_cells = gpu.storage_zeroed("scratch cells", bytes)?;
    let cell_splats = gpu.storage_zeroed("cell splats", bytes)?;
    let mut encoder = gpu.encoder("grid scatter");
    gpu.dispatch(
        &mut encoder,
        "grid_scatter",
        &[
            &params_buf,
            splats,
            &cell_start,
            &cursor,
            &scratch_splats,
            &scratch_cells,
        ],
        gpu.groups("grid_scatter", params.splat_count)?,
    )?;
    gpu.dispatch(
        &mut encoder,
        "grid_rank",
        &[
            &params_buf,
            &cell_start,
            &scratch_splats,
            &scratch_cells,
            &cell_splats,
        ],
        gpu.groups("grid_rank", entries)?,
    )?;
    let cell_dist = distance_field(gpu, &mut encoder, &params_buf, &params, &cell_start)?;
    gpu.submit_and_wait(encoder)?;
    Ok(GpuGrid {
        params,
        params_buf,
        cell_start,
        cell_splats,
        cell_dist,
        entries,
    })
}

/// Records passes x, y, z of `grid_distance`; returns the field's buffer.
fn distance_field(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    grid: &wgpu::Buffer,
    params: &GridParams,
    cell_start: &wgpu::Buffer,
) -> Result<wgpu::Buffer> {
    let bytes = params.cell_count as u64 * 4;
    let a = gpu.storage_zeroed("cell distance", bytes)?;
    let b = gpu.storage_zeroed("cell distance scratch", bytes)?;
    let groups = gpu.groups("grid_distance", params.cell_count)?;
    let passes: [(u32, &wgpu::Buffer, &wgpu::Buffer); 3] =
        [(0, cell_start, &a), (1, &a, &b), (2, &b, &a)];
    for (axis, src, dst) in passes {
        let pass = gpu.uniform(
            "distance pass",
            &DistanceParams {
                axis,
                ..Default::default()
            },
        );
        gpu.dispatch(
            encoder,
            "grid_distance",
            &[&pass, grid, cell_start, src, dst],
            groups,
        )?;
    }
    Ok(a)
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
