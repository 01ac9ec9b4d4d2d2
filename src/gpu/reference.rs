//! The reference renderer on the device (thesis §4.2): `reference_gather` casts each pixel's
//! ray and gathers the photon map there into the attribute targets, then the frame's own
//! shade pass adds direct light. Built apart from `SplatPipelines`, so frames that never ask
//! for a reference never compile it.

use super::bins::GpuBins;
use super::frame::{FrameScene, FrameTargets, SceneBuffers, SplatPipelines, raster_pipeline};
use super::scene::GpuScene;
use super::{Gpu, buffer_entries};
use crate::em::LobeMap;
use crate::error::Result;
use crate::frame::{FrameConfig, shade_params};
use crate::scene::Scene;
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
        let gather = raster_pipeline(gpu, "reference_gather", None, &targets)?;
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
        scene: &SceneBuffers,
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
        let groups: Vec<wgpu::BindGroup> = [buffer_entries(&own), buffer_entries(&scene.geometry)]
            .iter()
            .enumerate()
            .map(|(g, entries)| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("reference_gather"),
                    layout: &self.gather.get_bind_group_layout(g as u32),
                    entries,
                })
            })
            .collect();
        let color = out.cleared_sums();
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("reference_gather"),
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

    /// The reference image of `cam` (`width × height`) from photons binned on the device, in
    /// fresh targets whose `hdr` holds it once this returns.
    #[allow(clippy::too_many_arguments)]
    pub fn image(
        &self,
        gpu: &Gpu,
        splat: &SplatPipelines,
        scene: &Scene,
        on_gpu: &GpuScene,
        bins: &GpuBins,
        em: &EmParams,
        cam: &Camera,
        cfg: &FrameConfig,
        (width, height): (u32, u32),
    ) -> Result<FrameTargets> {
        // The shade pass reads no lobes: an empty map gives it its other settings.
        let no_lobes = LobeMap::default();
        let params = shade_params(scene, &no_lobes, cfg);
        let frame_scene = FrameScene::upload(gpu, scene, &no_lobes)?;
        let targets = splat.targets(gpu, width, height)?;
        let mut encoder = gpu.encoder("reference");
        let buffers = frame_scene.buffers(on_gpu);
        self.draw(
            gpu,
            &mut encoder,
            splat,
            &buffers,
            bins,
            em,
            cam,
            &params,
            &targets,
        )?;
        gpu.submit_and_wait(encoder)?;
        Ok(targets)
    }
}
