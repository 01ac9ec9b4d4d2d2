//! Multi-level exclusive scan of a u32 buffer in place: `scan_reduce` writes one sum per block
//! of `WG × ITEMS` values, the block sums are scanned recursively, and `scan_apply` finishes each
//! block. Any length the buffer limits allow. Mirrors `cpu::exclusive_scan`.

use super::Gpu;
use crate::error::Result;
use crate::types::ScanParams;

/// Records the scan of the first `len` values of `values` into `encoder`.
pub fn exclusive_scan(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    values: &wgpu::Buffer,
    len: u32,
) -> Result<()> {
    let blocks = gpu.groups("scan_reduce", len)?;
    let params = gpu.uniform(
        "scan params",
        &ScanParams {
            len,
            ..Default::default()
        },
    );
    if blocks <= 1 {
        let zero = gpu.storage("scan zero offset", &[0u32])?;
        return gpu.dispatch(encoder, "scan_apply", &[&params, values, &zero], blocks);
    }
    let block_sums = gpu.storage_zeroed("scan block sums", blocks as u64 * 4)?;
    gpu.dispatch(
        encoder,
        "scan_reduce",
        &[&params, values, &block_sums],
        blocks,
    )?;
    exclusive_scan(gpu, encoder, &block_sums, blocks)?;
    gpu.dispatch(
        encoder,
        "scan_apply",
        &[&params, values, &block_sums],
        blocks,
    )
}
