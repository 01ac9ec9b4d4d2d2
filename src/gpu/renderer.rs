//! The frames on the device. `FrameRenderer` owns what every frame needs — the scene's splats
//! and grid on the device, the compiled splat passes, the bake's lobes and the lights, and
//! targets for the image size (rebuilt only when the size changes) — and offers the frame's
//! sequence: draw from a view, tone map, read back. The engine-neutral `renderer::Renderer`
//! drives it on a device; the viewer and the frame benchmarks, which record into their own
//! submissions, use it directly.
//!
//! `draw*` record, submit and wait; `record*` only record into a caller's encoder (the viewer
//! adds its tone map and present pass to the same submission).

use std::sync::Arc;

use crate::camera::View;
use crate::direct::{DirectMap, direct_params_biased};
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::frame::{
    Direct, FrameConfig, FramePlan, SceneExtent, Terms, camera_uniform, path_params,
    shade_params_for, temporal_jitter, temporal_params,
};
use crate::gpu::Gpu;
use crate::gpu::bins::GpuBins;
use crate::gpu::exec::GpuExecutor;
use crate::gpu::passes::{FrameScene, FrameTargets, PassBuffers, SplatPipelines};
use crate::gpu::reference::ReferencePipeline;
use crate::gpu::scene::GpuScene;
use crate::gpu::tone::{GpuToned, tone_map};
use crate::scene::Scene;
use crate::sequence::{TemporalHistory, path_sample};
use crate::tone::ToneConfig;
use crate::types::{Camera, EmParams, Light, PathParams};

pub struct FrameRenderer {
    /// The splats, materials and grid (shared with a bake on another thread).
    pub on_gpu: Arc<GpuScene>,
    pub pipelines: SplatPipelines,
    /// Built the first time a reference is drawn.
    reference: Option<ReferencePipeline>,
    frame_scene: FrameScene,
    /// The most lobes a splat of the uploaded map has (the shade pass's loop bound).
    lobes_per_splat: u32,
    /// How long the direct bake of the current lights took; none until it is made (after a
    /// new scene or new lights).
    direct_ms: Option<f64>,
    /// The lights on the device.
    lights: Vec<Light>,
    /// The scene's bounds and shadow bias, walked once per scene, not per frame.
    extent: SceneExtent,
    targets: Option<FrameTargets>,
    /// The targets of the size before, kept for a renderer that switches between two sizes
    /// (the viewer's moving frames at a lower internal resolution, its still image at the
    /// window's), so that a switch allocates nothing.
    spare: Option<FrameTargets>,
    /// The moving frames' history (`record_moving`); none after a reset.
    history: Option<History>,
}

/// A moving frame about to be drawn: the history it continues, and what it will be.
struct Moving {
    last: Option<History>,
    next: History,
}

/// What the last moving frame was drawn with, which the next one's history must share.
#[derive(Clone, Copy)]
struct History {
    /// Its plan, jitter included.
    plan: FramePlan,
    /// Moving frames since the last reset: picks the jitter and which history buffer is the
    /// last frame's.
    frames: u32,
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
            reference: None,
            on_gpu,
            lobes_per_splat: lobes.lobes_per_splat,
            direct_ms: None,
            lights: scene.lights.clone(),
            extent: SceneExtent::of(scene),
            targets: None,
            spare: None,
            history: None,
        })
    }

    /// Draws another scene from now on, with the passes already compiled; no lobes until
    /// `bake` or `set_lobes`.
    pub fn set_scene(&mut self, gpu: &Gpu, scene: &Scene) -> Result<()> {
        self.on_gpu = Arc::new(GpuScene::upload(gpu, scene)?);
        self.frame_scene = FrameScene::upload(gpu, scene, &LobeMap::default())?;
        self.lobes_per_splat = 0;
        self.direct_ms = None;
        self.lights = scene.lights.clone();
        self.extent = SceneExtent::of(scene);
        self.history = None;
        Ok(())
    }

    /// Keeps a bake's lobes for the frames to come, and the direct bake final gathering made
    /// where it ran (the frames' own: the same lights, samples, seed and shadow bias).
    pub fn set_baked(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        (lobes, direct): (&LobeMap, Option<&DirectMap>),
    ) -> Result<()> {
        self.set_lobes(gpu, scene, lobes)?;
        if let Some(direct) = direct {
            self.set_direct(gpu, scene, direct, 0.0)?;
        }
        Ok(())
    }

    /// Draws with `lobes` and the scene's lights from now on (a bake loaded from a cache or
    /// made elsewhere).
    pub fn set_lobes(&mut self, gpu: &Gpu, scene: &Scene, lobes: &LobeMap) -> Result<()> {
        self.frame_scene.splat_light = gpu.storage("splat light", &lobes.light)?;
        self.frame_scene.lobes = gpu.storage("lobes", &lobes.lobes)?;
        self.lobes_per_splat = lobes.lobes_per_splat;
        self.history = None;
        self.set_lights(gpu, scene)
    }

    /// Draws with the scene's lights from now on, the lobes unchanged (a moved light's direct
    /// light, before its indirect bake is in). Lights that changed need a new direct bake,
    /// made before the next frame that needs it, or at once by `bake_direct`.
    pub fn set_lights(&mut self, gpu: &Gpu, scene: &Scene) -> Result<()> {
        if self.lights != scene.lights {
            self.frame_scene.lights = gpu.storage("lights", &scene.lights)?;
            self.lights = scene.lights.clone();
            self.direct_ms = None;
            self.history = None;
        }
        Ok(())
    }

    /// Bakes the direct light of the current lights into every splat (`sequence::bake_direct`)
    /// and waits; returns its milliseconds.
    pub fn bake_direct(&mut self, gpu: &Gpu, scene: &Scene) -> Result<f64> {
        let start = std::time::Instant::now();
        self.set_lights(gpu, scene)?;
        let params = direct_params_biased(scene, self.extent.shadow_bias);
        let order = match &mut self.frame_scene.direct_order {
            Some(order) => order,
            none => {
                none.insert(gpu.storage("direct order", &crate::grid::splat_order(&scene.splats))?)
            }
        };
        let mut encoder = gpu.encoder("direct bake");
        let mut ex = GpuExecutor::new(gpu, &mut encoder).tracing(self.on_gpu.geometry());
        let lights = &self.frame_scene.lights;
        let direct = crate::sequence::bake_direct(&mut ex, lights, order, &params)?;
        gpu.submit_and_wait(encoder)?;
        self.frame_scene.direct = direct;
        self.history = None;
        let ms = crate::timing::ms_since(start);
        self.direct_ms = Some(ms);
        Ok(ms)
    }

    /// Draws with a direct bake of the scene's lights made elsewhere (the CPU mirror's,
    /// `cpu::frames::cpu_direct`, or the one final gathering made), which took `ms`.
    pub fn set_direct(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        baked: &DirectMap,
        ms: f64,
    ) -> Result<()> {
        self.set_lights(gpu, scene)?;
        self.frame_scene.direct = crate::sequence::DirectBake {
            direct: gpu.storage("direct light", &baked.direct)?,
            visibility: gpu.storage("light visibility", &baked.visibility)?,
        };
        self.direct_ms = Some(ms);
        self.history = None;
        Ok(())
    }

    /// The scene's bounds and shadow bias, as the frames read them.
    pub fn extent(&self) -> SceneExtent {
        self.extent
    }

    /// Whether the current lights' direct bake is made.
    pub fn direct_is_baked(&self) -> bool {
        self.direct_ms.is_some()
    }

    /// The direct bake's milliseconds, baking it first if the lights changed since.
    pub fn ensure_direct(&mut self, gpu: &Gpu, scene: &Scene) -> Result<f64> {
        match self.direct_ms {
            Some(ms) => Ok(ms),
            None => self.bake_direct(gpu, scene),
        }
    }

    /// The direct bake of the current lights in host memory (tests, comparisons).
    pub fn read_direct(&mut self, gpu: &Gpu, scene: &Scene) -> Result<DirectMap> {
        self.ensure_direct(gpu, scene)?;
        let params = direct_params_biased(scene, self.extent.shadow_bias);
        let mut encoder = gpu.encoder("direct read");
        let mut ex = GpuExecutor::new(gpu, &mut encoder);
        self.frame_scene.direct.read_back(&mut ex, &params)
    }

    /// Targets of `width × height`: the current ones, the spare ones where they have that size
    /// (the two swap), else made anew (the current ones become the spare).
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<&FrameTargets> {
        let fits = |t: &FrameTargets| t.width == width && t.height == height;
        if !self.targets.as_ref().is_some_and(fits) {
            let next = match self.spare.take() {
                Some(spare) if fits(&spare) => spare,
                _ => self.pipelines.targets(gpu, width, height)?,
            };
            self.spare = self.targets.replace(next);
            self.history = None;
        }
        self.targets()
    }

    /// The current targets (after `resize` or a draw).
    pub fn targets(&self) -> Result<&FrameTargets> {
        self.targets
            .as_ref()
            .ok_or_else(|| Error::internal("the frame renderer has no targets yet"))
    }

    /// The plan of a frame of `cam` (a view's camera uniform) with the lobes uploaded.
    fn plan(&self, scene: &Scene, cam: &Camera, cfg: &FrameConfig) -> Result<FramePlan> {
        let splatting = self.pipelines.splatting(cfg.splatter)?;
        let lobes = self.lobes_per_splat;
        Ok(FramePlan::of(
            scene,
            &self.extent,
            lobes,
            (cam, cfg),
            splatting,
        ))
    }

    /// Records the lobes' frame of `cam` into the current targets; returns their HDR image.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene,
        cam: &Camera,
        cfg: &FrameConfig,
    ) -> Result<&wgpu::Buffer> {
        let plan = self.plan(scene, cam, cfg)?;
        self.record_plan(gpu, encoder, scene, &plan)
    }

    /// Records the moving frame of `cam`: with `cfg.temporal`, jittered and blended with the
    /// moving frames before it (`sequence::temporal`; none before it after a reset: a new
    /// scene, lobes, lights or size, or other shading), else as `record`. Returns the HDR
    /// image, the resolved one.
    pub fn record_moving(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene,
        cam: &Camera,
        cfg: &FrameConfig,
    ) -> Result<&wgpu::Buffer> {
        if !cfg.temporal {
            self.history = None;
            return self.record(gpu, encoder, scene, cam, cfg);
        }
        let moving = self.next_moving(&self.plan(scene, cam, cfg)?);
        self.record_plan(gpu, encoder, scene, &moving.next.plan)?;
        self.record_temporal(gpu, encoder, &moving)?;
        self.history = Some(moving.next);
        Ok(&self.targets()?.hdr)
    }

    /// The next moving frame of `plan`: its jitter, and the history it continues where the
    /// last moving frame was shaded alike.
    fn next_moving(&self, plan: &FramePlan) -> Moving {
        let alike =
            |h: &History| h.plan.params == plan.params && h.plan.splatting == plan.splatting;
        let last = self.history.filter(alike);
        let frames = last.map_or(0, |h| h.frames);
        let next = History {
            plan: plan.jittered(temporal_jitter(frames)),
            frames: frames + 1,
        };
        Moving { last, next }
    }

    /// Records the temporal pass of a moving frame, its splat passes recorded.
    fn record_temporal(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        moving: &Moving,
    ) -> Result<()> {
        let t = self.targets()?;
        let (cam, last) = (&moving.next.plan.view, moving.last);
        let params = temporal_params(t.width, t.height, last.is_none());
        let prev = last.map_or(*cam, |h| h.plan.view);
        // Frame k since the reset reads history buffer k % 2 and writes the other.
        let k = moving.next.frames - 1;
        let history = t.history(gpu)?;
        let [from, to] = [k % 2, (k + 1) % 2].map(|b| TemporalHistory {
            image: &history.image[b as usize],
            surface: &history.surface[b as usize],
        });
        let mut ex = GpuExecutor::new(gpu, encoder);
        crate::sequence::temporal(&mut ex, cam, &prev, &params, &t.hdr, &t.surface, from, to)
    }

    /// Records refinement frame `k` of `spp` of `cam` (`FramePlan::refinement`): jittered,
    /// with its share of shadow rays, added to the running mean in the HDR image, which holds
    /// the still image once `k + 1 == spp`. Returns the HDR image.
    #[allow(clippy::too_many_arguments)]
    pub fn record_sample(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene,
        cam: &Camera,
        cfg: &FrameConfig,
        k: u32,
        spp: u32,
    ) -> Result<&wgpu::Buffer> {
        let plan = self.plan(scene, cam, cfg)?.refinement(k, spp);
        self.record_plan(gpu, encoder, scene, &plan)
    }

    /// Records the splat passes of `plan` into the current targets.
    fn record_plan(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene,
        plan: &FramePlan,
    ) -> Result<&wgpu::Buffer> {
        if plan.reads_direct_bake() && self.direct_ms.is_none() {
            return Err(Error::Internal(
                "baked direct light was asked for before the lights' direct bake".into(),
            ));
        }
        let targets = self.targets()?;
        let buffers = self.frame_buffers(gpu, scene, plan)?;
        self.pipelines.draw(gpu, encoder, &buffers, plan, targets)?;
        Ok(&targets.hdr)
    }

    /// What the splat passes bind for a frame of `plan`, the level of detail's merge tree
    /// built first where the frame draws with it.
    fn frame_buffers(&self, gpu: &Gpu, scene: &Scene, plan: &FramePlan) -> Result<PassBuffers<'_>> {
        if plan.reads_direct_bake() {
            self.frame_scene.ensure_tree(gpu, scene, plan.merged())?;
        }
        Ok(self.frame_scene.buffers(&self.on_gpu, plan.merged()))
    }

    /// Records the reference image of `cam` from binned photons (`bins`, with the binning's
    /// `em` parameters) into the current targets: the photon gather with the exact BRDF, then
    /// the same shade pass with no lobes. Returns the HDR image.
    #[allow(clippy::too_many_arguments)]
    pub fn record_reference(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene,
        bins: &GpuBins,
        em: &EmParams,
        cam: &Camera,
        cfg: &FrameConfig,
    ) -> Result<&wgpu::Buffer> {
        if self.reference.is_none() {
            self.reference = Some(ReferencePipeline::new(gpu, &self.pipelines)?);
        }
        let (Some(reference), Some(targets)) = (&self.reference, &self.targets) else {
            return Err(Error::Internal(
                "the frame renderer has no targets yet".into(),
            ));
        };
        // The shade pass reads no lobes here: none per splat gives it its other settings, and
        // the gather has no baked direct light to add: shadow rays. Its photons give the
        // glossy light too, with the exact BRDF: no glossy rays.
        let cfg = FrameConfig {
            direct: Direct::Rays,
            glossy_rays: 0,
            ..cfg.clone()
        };
        let params = shade_params_for(scene, 0, self.extent.shadow_bias, &cfg);
        let buffers = self.frame_scene.buffers(&self.on_gpu, false);
        reference.draw(
            gpu,
            encoder,
            &self.pipelines,
            &buffers,
            bins,
            em,
            cam,
            &params,
            targets,
        )?;
        Ok(&targets.hdr)
    }

    /// Targets of `view`'s size and the direct bake where `cfg` reads it; returns `view`'s
    /// camera uniform.
    fn prepare(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<Camera> {
        self.resize(gpu, view.width, view.height)?;
        if cfg.needs_direct_bake() {
            self.ensure_direct(gpu, scene)?;
        }
        Ok(camera_uniform(view, self.extent.bounds, cfg))
    }

    /// Draws the lobes' frame of `view` (its size and camera) and waits.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<&FrameTargets> {
        let cam = self.prepare(gpu, scene, view, cfg)?;
        gpu.record_and_wait("frame", |e| self.record(gpu, e, scene, &cam, cfg).map(drop))?;
        self.targets()
    }

    /// Draws the moving frame of `view` (`record_moving`) and waits.
    pub fn draw_moving(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<&FrameTargets> {
        let cam = self.prepare(gpu, scene, view, cfg)?;
        gpu.record_and_wait("moving frame", |e| {
            self.record_moving(gpu, e, scene, &cam, cfg).map(drop)
        })?;
        self.targets()
    }

    /// Draws the still image of `view`: `spp` refinement frames, one submission each, with
    /// `each(k)` called after frame `k` (progress). The HDR image holds their mean.
    pub fn draw_refined(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
        spp: u32,
        mut each: impl FnMut(u32),
    ) -> Result<&FrameTargets> {
        let cam = self.prepare(gpu, scene, view, cfg)?;
        for k in 0..spp.max(1) {
            gpu.record_and_wait("refinement frame", |e| {
                self.record_sample(gpu, e, scene, &cam, cfg, k, spp)
                    .map(drop)
            })?;
            each(k);
        }
        self.targets()
    }

    /// Draws the reference image of `view` from binned photons and waits.
    pub fn draw_reference(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        (bins, em): (&GpuBins, &EmParams),
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<&FrameTargets> {
        self.resize(gpu, view.width, view.height)?;
        let cam = camera_uniform(view, self.extent.bounds, cfg);
        gpu.record_and_wait("reference", |e| {
            self.record_reference(gpu, e, scene, bins, em, &cam, cfg)
                .map(drop)
        })?;
        self.targets()
    }

    /// The path-traced image of `view` (`sequence::path_sample`): `spp` samples per pixel, one
    /// submission each, with `each(k)` called after sample `k`, of the light terms `show`
    /// (`FrameConfig::show`). Needs no bake; the HDR image holds their mean.
    pub fn draw_path(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        show: Terms,
        spp: u32,
        mut each: impl FnMut(u32),
    ) -> Result<&FrameTargets> {
        self.resize(gpu, view.width, view.height)?;
        self.set_lights(gpu, scene)?;
        let cam = camera_uniform(view, self.extent.bounds, &FrameConfig::default());
        let cam_buf = gpu.uniform("camera", &cam);
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| Error::internal("the frame renderer has no targets yet"))?;
        let first = path_params(scene, &cam, show, self.extent.shadow_bias);
        for k in 0..spp.max(1) {
            let mut encoder = gpu.encoder("path sample");
            let mut ex = GpuExecutor::new(gpu, &mut encoder).tracing(self.on_gpu.geometry());
            let params = PathParams { sample: k, ..first };
            let (materials, lights) = (&self.on_gpu.materials, &self.frame_scene.lights);
            path_sample(&mut ex, &params, &cam_buf, materials, lights, &targets.hdr)?;
            gpu.submit_and_wait(encoder)?;
            each(k);
        }
        self.targets()
    }

    /// The moving frame of `view` (`draw_moving`) with a wait after each splat pass and after
    /// the temporal pass: the milliseconds of each, the temporal pass's last (0 without it)
    /// (benchmarks; slower than `draw_moving`, which waits once).
    pub fn draw_timed(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<[f64; 4]> {
        let cam = self.prepare(gpu, scene, view, cfg)?;
        let plan = self.plan(scene, &cam, cfg)?;
        let moving = cfg.temporal.then(|| self.next_moving(&plan));
        let plan = moving.as_ref().map_or(plan, |m| m.next.plan);
        let buffers = self.frame_buffers(gpu, scene, &plan)?;
        let [visibility, attributes, shade] =
            self.pipelines
                .draw_timed(gpu, &buffers, &plan, self.targets()?)?;
        let mut temporal = 0.0;
        self.history = None;
        if let Some(moving) = moving {
            let t = std::time::Instant::now();
            gpu.record_and_wait("temporal", |e| self.record_temporal(gpu, e, &moving))?;
            temporal = crate::timing::ms_since(t);
            self.history = Some(moving.next);
        }
        Ok([visibility, attributes, shade, temporal])
    }

    /// The selection alone of the moving frame of `view` (`SplatPipelines::select_timed`):
    /// its milliseconds, waited for (benchmarks).
    pub fn select_timed(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
        view: &View,
        cfg: &FrameConfig,
    ) -> Result<f64> {
        let cam = self.prepare(gpu, scene, view, cfg)?;
        let plan = self.plan(scene, &cam, cfg)?;
        let buffers = self.frame_buffers(gpu, scene, &plan)?;
        self.pipelines.select_timed(gpu, &buffers, &plan)
    }

    /// Records the tone mapping of the current targets' HDR image.
    pub fn record_tone_map(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        tone: &ToneConfig,
    ) -> Result<GpuToned> {
        let targets = self.targets()?;
        let pixels = targets.width * targets.height;
        tone_map(gpu, encoder, &targets.hdr, pixels, tone)
    }

    /// Tone-maps the last frame drawn and waits.
    pub fn tone_map(&self, gpu: &Gpu, tone: &ToneConfig) -> Result<GpuToned> {
        gpu.record_and_wait("tone map", |e| self.record_tone_map(gpu, e, tone))
    }

    /// The last frame's linear HDR pixels, rows from the top.
    pub fn read_hdr(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        let targets = self.targets()?;
        gpu.read(&targets.hdr, (targets.width * targets.height) as usize)
    }

    /// The splats the last frame of baked direct light drew, as `splat_list` listed them, and
    /// each one's drawn radius (the selection's parity with `cpu::splat_select::selection`).
    pub fn read_selection(&self, gpu: &Gpu) -> Result<(Vec<u32>, Vec<f32>)> {
        let fs = &self.frame_scene;
        let count = gpu.read::<u32>(&fs.selected_count, 1)?[0] as usize;
        let selected: Vec<u32> = gpu.read(&fs.selected, count)?;
        let splats = self.on_gpu.grid.params.splat_count as usize;
        let drawn: Vec<f32> = gpu.read(&fs.drawn, splats)?;
        let radii = selected.iter().map(|&i| drawn[i as usize]).collect();
        Ok((selected, radii))
    }
}
