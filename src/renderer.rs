//! One frame renderer on the device. It owns what every frame needs — the scene's splats and
//! grid on the device, the compiled splat passes, the bake's lobes and the lights, and targets
//! for the image size (rebuilt only when the size changes) — and offers the frame's whole
//! sequence: bake, draw from a view, tone map, read back. The camera and shading uniforms are
//! made per draw from the view and the frame settings.

use std::sync::Arc;

use crate::bake::{BakeDevice, Baked, Progress, bake};
use crate::camera::View;
use crate::em::LobeMap;
use crate::error::Result;
use crate::frame::{FrameConfig, camera_uniform, shade_params_for};
use crate::gpu::Gpu;
use crate::gpu::frame::{FrameScene, FrameTargets, SplatPipelines};
use crate::gpu::scene::GpuScene;
use crate::gpu::tone::{GpuToned, tone_map};
use crate::scene::Scene;
use crate::tone::ToneConfig;

pub struct FrameRenderer {
    /// The splats, materials and grid (shared with a bake on another thread).
    pub on_gpu: Arc<GpuScene>,
    pub pipelines: SplatPipelines,
    frame_scene: FrameScene,
    /// The most lobes a splat of the uploaded map has (the shade pass's loop bound).
    lobes_per_splat: u32,
    targets: Option<FrameTargets>,
}

impl FrameRenderer {
    /// Uploads the scene and compiles the passes; no lobes until `bake` or `set_lobes`.
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<FrameRenderer> {
        Self::with_scene(gpu, scene, Arc::new(GpuScene::upload(gpu, scene)?))
    }

    /// A renderer over a scene already on the device.
    pub fn with_scene(gpu: &Gpu, scene: &Scene, on_gpu: Arc<GpuScene>) -> Result<FrameRenderer> {
        let lobes = LobeMap::default();
        Ok(FrameRenderer {
            frame_scene: FrameScene::upload(gpu, scene, &lobes)?,
            pipelines: SplatPipelines::new(gpu)?,
            on_gpu,
            lobes_per_splat: lobes.lobes_per_splat,
            targets: None,
        })
    }

    /// Bakes the scene's light on the device and keeps the lobes for the frames to come.
    pub fn bake(&mut self, gpu: &Gpu, scene: &Scene, progress: &Progress) -> Result<Baked> {
        let baked = bake(scene, BakeDevice::Gpu(gpu, &self.on_gpu), progress)?;
        self.set_lobes(gpu, scene, &baked.lobes)?;
        Ok(baked)
    }

    /// Draws with `lobes` from now on (a bake loaded from a cache or made elsewhere).
    pub fn set_lobes(&mut self, gpu: &Gpu, scene: &Scene, lobes: &LobeMap) -> Result<()> {
        self.frame_scene = FrameScene::upload(gpu, scene, lobes)?;
        self.lobes_per_splat = lobes.lobes_per_splat;
        Ok(())
    }

    /// Targets of `width × height`, made anew only when the size changed.
    pub fn targets(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<&FrameTargets> {
        let fits = |t: &FrameTargets| t.width == width && t.height == height;
        if !self.targets.as_ref().is_some_and(fits) {
            self.targets = Some(self.pipelines.targets(gpu, width, height)?);
        }
        self.targets_drawn()
    }

    /// Draws the frame of `view` (its size and camera) into the targets' HDR image and waits.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<&FrameTargets> {
        self.targets(gpu, view.width, view.height)?;
        let cam = camera_uniform(view, scene.bounds(), cfg);
        let params = shade_params_for(scene, self.lobes_per_splat, cfg);
        let buffers = self.frame_scene.buffers(&self.on_gpu);
        let targets = self.targets_drawn()?;
        let mut encoder = gpu.encoder("frame");
        self.pipelines
            .draw(gpu, &mut encoder, &buffers, &cam, &params, targets)?;
        gpu.submit_and_wait(encoder)?;
        Ok(targets)
    }

    /// Tone-maps the last frame drawn and waits.
    pub fn tone_map(&self, gpu: &Gpu, tone: &ToneConfig) -> Result<GpuToned> {
        let targets = self.targets_drawn()?;
        let mut encoder = gpu.encoder("tone map");
        let toned = tone_map(
            gpu,
            &mut encoder,
            &targets.hdr,
            targets.width * targets.height,
            tone,
        )?;
        gpu.submit_and_wait(encoder)?;
        Ok(toned)
    }

    /// The last frame's linear HDR pixels, rows from the top.
    pub fn read_hdr(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        let targets = self.targets_drawn()?;
        gpu.read(&targets.hdr, (targets.width * targets.height) as usize)
    }

    fn targets_drawn(&self) -> Result<&FrameTargets> {
        self.targets
            .as_ref()
            .ok_or_else(|| crate::Error::Invalid("no frame has been drawn yet".into()))
    }
}
