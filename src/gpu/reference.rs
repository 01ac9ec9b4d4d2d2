//! The reference renderer on the device (thesis §4.2): `reference_gather` casts each pixel's
//! ray and gathers the photon map there into the attribute targets, then the frame's own
//! shade pass adds direct light. Built apart from `SplatPipelines`, so frames that never ask
//! for a reference never compile it.

use super::bins::GpuBins;
use super::exec::SKY_BINDING;
use super::passes::{FrameTargets, PassBuffers, SplatPipelines, raster_pipeline};
use super::{Gpu, buffer_entries};
use crate::error::Result;
use crate::shaders::Stage;
use crate::types::{Camera, EmParams, ShadeParams};

pub struct ReferencePipeline {
    gather: wgpu::RenderPipeline,
}

impl ReferencePipeline {
    /// The gather pass, writing targets of `splat`'s format.
    pub fn new(gpu: &Gpu, splat: &SplatPipelines) -> Result<ReferencePipeline> {
        let target = Some(wgpu::ColorTargetState {
            format: splat.format(),
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        });
        let targets = [target.clone(), target.clone(), target.clone(), target];
        let gather = raster_pipeline(gpu, Stage::ReferenceGather, None, &targets)?;
        gpu.check()?;
        Ok(ReferencePipeline { gather })
    }

    /// Records the reference image of `cam` into `out.hdr`: the gather, then `splat`'s shade.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        splat: &SplatPipelines,
        scene: &PassBuffers,
        bins: &GpuBins,
        em: &EmParams,
        cam: &Camera,
        params: &ShadeParams,
        out: &FrameTargets,
    ) -> Result<()> {
        let cam_buf = gpu.uniform("camera", cam);
        let em_buf = gpu.uniform("reference params", em);
        let own = [
            &cam_buf,
            &em_buf,
            scene.materials,
            &bins.params_buf,
            &bins.cell_start,
            &bins.geom,
            &bins.power,
        ];
        // The gather reads no light: its derived layout has the geometry but the sky.
        let geometry = &scene.geometry[..SKY_BINDING];
        if !gpu
            .paging(Stage::ReferenceGather, &[&own, geometry])?
            .arrays
            .is_empty()
        {
            return Err(crate::Error::DeviceLimit(
                "the photon-map reference binds the scene's splats and grid whole; this scene's \
                 do not fit one storage binding (use --method path)"
                    .into(),
            ));
        }
        let groups: Vec<wgpu::BindGroup> = [buffer_entries(&own), buffer_entries(geometry)]
            .iter()
            .enumerate()
            .map(|(g, entries)| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(Stage::ReferenceGather.name()),
                    layout: &self.gather.get_bind_group_layout(g as u32),
                    entries,
                })
            })
            .collect();
        let color = out.cleared_sums();
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(Stage::ReferenceGather.name()),
                color_attachments: &color,
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.gather);
            for (g, group) in groups.iter().enumerate() {
                pass.set_bind_group(g as u32, group, &[]);
            }
            pass.draw(0..3, 0..1);
        }
        splat.shade(gpu, encoder, scene, cam, params, out)
    }
}
