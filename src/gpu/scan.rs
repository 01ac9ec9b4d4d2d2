//! Multi-level exclusive scan of a u32 buffer in place on the device: `sequence::exclusive_scan`
//! recorded into an encoder. Any length the buffer limits allow.

use super::Gpu;
use super::exec::GpuExecutor;
use crate::error::Result;
use crate::sequence;

/// Records the scan of the first `len` values of `values` into `encoder`.
pub fn exclusive_scan(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    values: &wgpu::Buffer,
    len: u32,
) -> Result<()> {
    sequence::exclusive_scan(&mut GpuExecutor::new(gpu, encoder), values, len)
}
