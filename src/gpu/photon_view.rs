//! The photon view on the device: `sequence::photon_image` over every photon page, as
//! `cpu::photon_image` runs it over one.

use super::Gpu;
use super::exec::GpuExecutor;
use super::photons::GpuPhotons;
use super::scene::GpuScene;
use crate::error::Result;
use crate::sequence;
use crate::types::Camera;

/// Records the photon view of `cam` (`width × height`, from `cam.size`); returns the HDR
/// image buffer (`vec4<f32>` per pixel, rows from the top).
pub fn photon_image(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    on_gpu: &GpuScene,
    photons: &GpuPhotons,
    cam: &Camera,
    scale: f32,
) -> Result<wgpu::Buffer> {
    let pages: Vec<(&wgpu::Buffer, u32)> = photons
        .pages
        .iter()
        .map(|p| (&p.buffer, p.count as u32))
        .collect();
    let mut ex = GpuExecutor::new(gpu, encoder).tracing(on_gpu.geometry());
    sequence::photon_image(&mut ex, &on_gpu.materials, &pages, cam, scale)
}
