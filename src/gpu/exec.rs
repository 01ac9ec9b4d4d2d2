//! The device's executor of `sequence`s: records every dispatch and copy into a command
//! encoder; a readback submits what is recorded, waits, and goes on in a fresh encoder.

use bytemuck::Pod;

use super::Gpu;
use crate::error::Result;
use crate::sequence::Executor;
use crate::shaders::{Pass, Stage};

/// Buffers in bind group 1 of the tracing stages (`GpuScene::geometry`).
pub const GEOMETRY_BINDINGS: usize = 7;
/// The sky's binding in that group, the last (`Scene::sky`): a raster stage that reads no
/// light (the photon-map reference's gather) binds the ones before it.
pub const SKY_BINDING: usize = 6;

/// Bind group 1 of the tracing stages, in binding order (see `wgsl/shared/trace.wgsl`).
pub type GeometryBuffers<'a> = [&'a wgpu::Buffer; GEOMETRY_BINDINGS];

pub struct GpuExecutor<'a> {
    gpu: &'a Gpu,
    encoder: &'a mut wgpu::CommandEncoder,
    /// Bind group 1 of the tracing stages (`GpuScene::geometry`).
    geometry: Option<GeometryBuffers<'a>>,
}

impl<'a> GpuExecutor<'a> {
    /// Records into `encoder`; the caller submits it (after any readback, what is left).
    pub fn new(gpu: &'a Gpu, encoder: &'a mut wgpu::CommandEncoder) -> GpuExecutor<'a> {
        GpuExecutor {
            gpu,
            encoder,
            geometry: None,
        }
    }

    /// Tracing stages walk the splats and grid of `geometry` (`GpuScene::geometry`).
    pub fn tracing(mut self, geometry: GeometryBuffers<'a>) -> GpuExecutor<'a> {
        self.geometry = Some(geometry);
        self
    }
}

impl Executor for GpuExecutor<'_> {
    type Buffer = wgpu::Buffer;

    fn zeroed(&mut self, label: &'static str, bytes: u64) -> Result<wgpu::Buffer> {
        self.gpu.storage_zeroed(label, bytes)
    }

    fn upload<T: Pod>(&mut self, label: &'static str, data: &[T]) -> Result<wgpu::Buffer> {
        self.gpu.storage(label, data)
    }

    fn uniform<T: Pod>(&mut self, label: &'static str, value: &T) -> Result<wgpu::Buffer> {
        Ok(self.gpu.uniform(label, value))
    }

    fn dispatch(
        &mut self,
        pass: impl Into<Pass>,
        bindings: &[&wgpu::Buffer],
        groups: u32,
    ) -> Result<()> {
        self.gpu
            .dispatch_groups(self.encoder, pass, &[bindings], groups)
    }

    fn dispatch_traced(
        &mut self,
        pass: impl Into<Pass>,
        bindings: &[&wgpu::Buffer],
        groups: u32,
    ) -> Result<()> {
        let pass = pass.into();
        let geometry = self
            .geometry
            .ok_or_else(|| crate::Error::Internal(format!("{pass}: no scene geometry to trace")))?;
        self.gpu
            .dispatch_groups(self.encoder, pass, &[bindings, &geometry], groups)
    }

    fn dispatch_variant(
        &mut self,
        stage: Stage,
        defines: &[&'static str],
        constants: &[(&'static str, f64)],
        bindings: &[&wgpu::Buffer],
        groups: u32,
    ) -> Result<()> {
        let paging = self.gpu.paging(stage, &[bindings])?;
        let pipeline = self.gpu.variant_paged(stage, defines, constants, &paging)?;
        self.gpu
            .dispatch_pipeline(self.encoder, stage, &pipeline, &paging, &[bindings], groups)
    }

    fn copy(
        &mut self,
        src: &wgpu::Buffer,
        src_offset: u64,
        dst: &wgpu::Buffer,
        dst_offset: u64,
        bytes: u64,
    ) -> Result<()> {
        self.encoder
            .copy_buffer_to_buffer(src, src_offset, dst, dst_offset, bytes);
        Ok(())
    }

    fn read<T: Pod>(&mut self, buffer: &wgpu::Buffer, count: usize) -> Result<Vec<T>> {
        let recorded = std::mem::replace(self.encoder, self.gpu.encoder("after a readback"));
        self.gpu.submit_and_wait(recorded)?;
        self.gpu.read(buffer, count)
    }

    fn finish(&mut self) -> Result<()> {
        let recorded = std::mem::replace(self.encoder, self.gpu.encoder("after a split point"));
        self.gpu.submit_and_wait(recorded)
    }
}
