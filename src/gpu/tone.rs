//! Tone mapping on the device: `sequence::tone_map` recorded into an encoder.

use super::Gpu;
use super::exec::GpuExecutor;
use crate::error::Result;
use crate::sequence;
use crate::tone::ToneConfig;

/// The tone-mapped image on the device.
pub type GpuToned = sequence::Toned<wgpu::Buffer>;

/// Records the tone mapping of `pixels` HDR pixels (`vec4<f32>` each) of `hdr`.
pub fn tone_map(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    hdr: &wgpu::Buffer,
    pixels: u32,
    cfg: &ToneConfig,
) -> Result<GpuToned> {
    sequence::tone_map(&mut GpuExecutor::new(gpu, encoder), hdr, pixels, cfg)
}
