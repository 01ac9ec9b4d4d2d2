//! Tone mapping on the device: `tonemap_reduce` level by level down to one (Σ log, count),
//! then `tonemap_apply` per pixel. Mirrors `cpu::tone_map`.

use super::Gpu;
use crate::error::Result;
use crate::tone::{ToneConfig, reduce_levels};

/// The tone-mapped image on the device.
pub struct GpuToned {
    /// RGBA8 sRGB, one u32 per pixel.
    pub rgba: wgpu::Buffer,
    /// (Σ log(ε + Y), count) over the finite pixels.
    pub log_sum: wgpu::Buffer,
}

/// Records the tone mapping of `pixels` HDR pixels (`vec4<f32>` each) of `hdr`.
pub fn tone_map(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    hdr: &wgpu::Buffer,
    pixels: u32,
    cfg: &ToneConfig,
) -> Result<GpuToned> {
    cfg.validate()?;
    let mut sums_in = gpu.storage_zeroed("tone sums", 8)?;
    let block = super::shaders::stage_shape("tonemap_reduce")?.per_group("tonemap_reduce")?;
    for (level, &count) in reduce_levels(pixels, block).iter().enumerate() {
        let blocks = crate::shared::dispatch::groups_for(count, block).max(1);
        let sums_out = gpu.storage_zeroed("tone sums", blocks as u64 * 8)?;
        let params = gpu.uniform("tone params", &cfg.params(count, level as u32));
        gpu.dispatch(
            encoder,
            "tonemap_reduce",
            &[&params, hdr, &sums_in, &sums_out],
            blocks,
        )?;
        sums_in = sums_out;
    }
    let rgba = gpu.storage_zeroed("tone-mapped image", pixels.max(1) as u64 * 4)?;
    let params = gpu.uniform("tone params", &cfg.params(pixels, 0));
    gpu.dispatch(
        encoder,
        "tonemap_apply",
        &[&params, hdr, &sums_in, &rgba],
        gpu.groups("tonemap_apply", pixels)?,
    )?;
    Ok(GpuToned {
        rgba,
        log_sum: sums_in,
    })
}
