//! Host images and grids through the mirrors: the tone map, the photon view, the scan and the
//! grid build of `sequence` on a `CpuExecutor`. The bake's passes from host data run on
//! either engine (`host`, `renderer::Engine`); the mirrors themselves are the other modules
//! of `cpu`.

use crate::error::{Error, Result};
use crate::grid::SplatGrid;
use crate::sequence::{self, Executor};
use crate::shared::trace::Geometry;
use crate::types::{GridParams, Material, Photon, Splat};

use super::exec::CpuExecutor;

/// Tone mapping on the CPU mirror (`sequence::tone_map`); returns RGBA8 pixels and
/// (Σ log(ε + Y), count).
pub fn tone_map(cfg: &crate::tone::ToneConfig, hdr: &[[f32; 4]]) -> Result<(Vec<u32>, [f32; 2])> {
    let pixels = u32::try_from(hdr.len())
        .map_err(|_| Error::Invalid("too many pixels to tone-map".into()))?;
    let mut ex = CpuExecutor::default();
    let hdr = ex.upload("hdr image", hdr)?;
    let toned = sequence::tone_map(&mut ex, &hdr, pixels, cfg)?;
    let rgba = ex.read(&toned.rgba, pixels as usize)?;
    let log_sum = ex.read::<[f32; 2]>(&toned.log_sum, 1)?;
    Ok((rgba, log_sum.first().copied().unwrap_or_default()))
}

/// The photon view of `cam` on the CPU mirror (`sequence::photon_image`) over one page of
/// photons; HDR pixels, rows from the top.
pub fn photon_image(
    cam: &crate::types::Camera,
    materials: &[Material],
    photons: &[Photon],
    geo: &Geometry,
    scale: f32,
) -> Result<Vec<[f32; 4]>> {
    let count = u32::try_from(photons.len())
        .map_err(|_| Error::Invalid("too many photons to view".into()))?;
    let mut ex = CpuExecutor::tracing(*geo);
    let material_buf = ex.upload("materials", materials)?;
    let page = ex.upload("photons", photons)?;
    let hdr = sequence::photon_image(&mut ex, &material_buf, &[(&page, count)], cam, scale)?;
    ex.read(&hdr, (cam.size[0] as u32 * cam.size[1] as u32) as usize)
}

/// Exclusive scan of `values` in place on the CPU mirror (`sequence::exclusive_scan`).
pub fn exclusive_scan(values: &mut [u32]) -> Result<()> {
    let len = u32::try_from(values.len())
        .map_err(|_| Error::Invalid("too many values to scan".into()))?;
    let mut ex = CpuExecutor::default();
    let buffer = ex.upload("scan values", values)?;
    sequence::exclusive_scan(&mut ex, &buffer, len)?;
    values.copy_from_slice(&ex.read::<u32>(&buffer, values.len())?);
    Ok(())
}

/// The grid build on the CPU mirror (`sequence::build_grid`).
pub fn build_grid(params: &GridParams, splats: &[Splat]) -> Result<SplatGrid> {
    let mut ex = CpuExecutor::default();
    let splat_buf = ex.upload("splats", splats)?;
    sequence::build_grid(&mut ex, params, &splat_buf)?.read_back(&mut ex)
}

/// The scene's splat grid, built by the mirror.
pub fn scene_grid(scene: &crate::scene::Scene) -> Result<SplatGrid> {
    build_grid(
        &crate::grid::grid_params(&scene.splats, &scene.grid)?,
        &scene.splats,
    )
}
