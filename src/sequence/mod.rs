//! Each multi-dispatch stage's sequence of dispatches, written once. A sequence is generic over
//! an `Executor`: the device's (`gpu::GpuExecutor`, which records into a command encoder) or
//! the CPU mirror's (`cpu::CpuExecutor`, which runs each stage's mirror at once). Both run the
//! same dispatches in the same order with the same group counts, taken from the WGSL
//! (`shaders::stage_shape`). A readback that decides later work (`Executor::read`) is an
//! explicit split point: the device submits what it recorded and waits.
//!
//! docs/architecture.md §3 lists the sequences and their split points.

use bytemuck::Pod;

use crate::error::Result;
use crate::shaders::stage_shape;
use crate::shaders::{Pass, Stage};
use crate::shared::dispatch::groups_for;
use crate::types::ScanParams;

mod estimate;
mod fit;
mod grid;
mod image;
mod photons;

pub use estimate::*;
pub use fit::*;
pub use grid::*;
pub use image::*;
pub use photons::*;

/// Where a sequence runs: buffers, uniforms, dispatches by stage name, copies and readbacks.
pub trait Executor {
    type Buffer: Clone;
    /// A zeroed buffer of `bytes` bytes (at least one 4-byte word).
    fn zeroed(&mut self, label: &'static str, bytes: u64) -> Result<Self::Buffer>;
    /// A buffer holding `data` (one zeroed element when it is empty).
    fn upload<T: Pod>(&mut self, label: &'static str, data: &[T]) -> Result<Self::Buffer>;
    /// A uniform holding `value`.
    fn uniform<T: Pod>(&mut self, label: &'static str, value: &T) -> Result<Self::Buffer>;
    /// One dispatch of `pass` (a stage's `main`, or another of its entry points) over
    /// `groups` workgroups, `bindings` in binding order.
    fn dispatch(
        &mut self,
        pass: impl Into<Pass>,
        bindings: &[&Self::Buffer],
        groups: u32,
    ) -> Result<()>;
    /// `dispatch` of a tracing stage, whose bind group 1 is the scene's geometry (splats and
    /// grid) that the executor was made with.
    fn dispatch_traced(
        &mut self,
        pass: impl Into<Pass>,
        bindings: &[&Self::Buffer],
        groups: u32,
    ) -> Result<()>;
    /// `dispatch` of the stage's variant with `defines` and pipeline-overridable `constants`
    /// (the mirrors read the same settings from the stage's parameters).
    fn dispatch_variant(
        &mut self,
        stage: Stage,
        defines: &[&'static str],
        constants: &[(&'static str, f64)],
        bindings: &[&Self::Buffer],
        groups: u32,
    ) -> Result<()>;
    /// Copies `bytes` bytes between two buffers.
    fn copy(
        &mut self,
        src: &Self::Buffer,
        src_offset: u64,
        dst: &Self::Buffer,
        dst_offset: u64,
        bytes: u64,
    ) -> Result<()>;
    /// A split point: what is recorded runs, then the first `count` values of `buffer` come
    /// back.
    fn read<T: Pod>(&mut self, buffer: &Self::Buffer, count: usize) -> Result<Vec<T>>;
    /// A split point with nothing read: what is recorded runs, and is done when this returns
    /// (a stage's time ends here).
    fn finish(&mut self) -> Result<()>;
}

/// Workgroups of `stage` that cover `n` values (its WGSL's workgroup size × items).
pub fn groups(stage: Stage, n: u32) -> Result<u32> {
    Ok(groups_for(n, stage_shape(stage)?.per_group(stage)?))
}

/// Exclusive scan of the first `len` values of `values` in place: `scan_reduce` writes one sum
/// per block, the block sums are scanned recursively, and `scan_apply` finishes each block.
pub fn exclusive_scan<E: Executor>(ex: &mut E, values: &E::Buffer, len: u32) -> Result<()> {
    let blocks = groups(Stage::ScanReduce, len)?;
    let params = ScanParams {
        len,
        ..Default::default()
    };
    let params = ex.uniform("scan params", &params)?;
    if blocks <= 1 {
        let zero = ex.upload("scan zero offset", &[0u32])?;
        return ex.dispatch(Stage::ScanApply, &[&params, values, &zero], blocks);
    }
    let block_sums = ex.zeroed("scan block sums", blocks as u64 * 4)?;
    ex.dispatch(Stage::ScanReduce, &[&params, values, &block_sums], blocks)?;
    exclusive_scan(ex, &block_sums, blocks)?;
    ex.dispatch(Stage::ScanApply, &[&params, values, &block_sums], blocks)
}
