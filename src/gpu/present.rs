//! The window's last pass (`wgsl/present.wgsl`): the tone-mapped image drawn onto a surface
//! texture (or any colour target of the same format, which is how its test reads it back),
//! upsampled where the image is smaller than the target.

use super::passes::raster_pipeline_at;
use super::{Gpu, buffer_entries};
use crate::error::Result;
use crate::shaders::{Paging, Stage};
use crate::types::PresentParams;

pub struct PresentPipeline {
    pipeline: wgpu::RenderPipeline,
    /// The target's format is sRGB: the shader decodes the bytes the hardware will encode.
    decode: bool,
}

impl PresentPipeline {
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Result<PresentPipeline> {
        let target = Some(wgpu::ColorTargetState {
            format,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        });
        let decode = format.is_srgb();
        let constants = [("DECODE", f64::from(u8::from(decode)))];
        let entries = ["vs_main", "fs_main"];
        let paging = Paging::default();
        let pipeline = raster_pipeline_at(
            gpu,
            Stage::Present,
            entries,
            None,
            &[target],
            &paging,
            &constants,
        )?;
        gpu.check()?;
        Ok(PresentPipeline { pipeline, decode })
    }

    /// The uniform of an image of `image` pixels (width, height) drawn onto a target of
    /// `target` pixels.
    pub fn params(&self, image: (u32, u32), target: (u32, u32)) -> PresentParams {
        PresentParams::new(image, target, self.decode)
    }

    /// Records the draw of `rgba` (`image` packed sRGB pixels, width and height) onto `view`,
    /// a target of `target` pixels.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        rgba: &wgpu::Buffer,
        image: (u32, u32),
        target: (u32, u32),
    ) {
        let params = gpu.uniform("present params", &self.params(image, target));
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(Stage::Present.name()),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &buffer_entries(&[&params, rgba]),
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(Stage::Present.name()),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
}
