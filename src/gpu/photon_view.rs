//! The photon view on the device: `photon_view` once per photon page into fixed-point sums,
//! then `photon_resolve` into an HDR image for the tone map. Mirrors `cpu::photon_image`.

use super::Gpu;
use super::photons::GpuPhotons;
use super::scene::GpuScene;
use crate::error::Result;
use crate::types::{Camera, PhotonViewParams};

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
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let pixels = width * height;
    let sums = gpu.storage_zeroed("photon view sums", pixels.max(1) as u64 * 12)?;
    let cam_buf = gpu.uniform("camera", cam);
    for page in photons.pages.iter().filter(|p| p.count > 0) {
        let params = PhotonViewParams {
            count: page.count as u32,
            width,
            height,
            scale,
        };
        let params_buf = gpu.uniform("photon view params", &params);
        let own = [
            &params_buf,
            &cam_buf,
            &on_gpu.materials,
            &page.buffer,
            &sums,
        ];
        gpu.dispatch_groups(
            encoder,
            "photon_view",
            &[&own, &on_gpu.geometry()],
            gpu.groups("photon_view", params.count)?,
        )?;
    }
    let hdr = gpu.storage_zeroed("photon view", pixels.max(1) as u64 * 16)?;
    let params = gpu.uniform(
        "photon resolve params",
        &PhotonViewParams {
            count: pixels,
            width,
            height,
            scale,
        },
    );
    gpu.dispatch(
        encoder,
        "photon_resolve",
        &[&params, &sums, &hdr],
        gpu.groups("photon_resolve", pixels)?,
    )?;
    Ok(hdr)
}
