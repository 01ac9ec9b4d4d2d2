//! One renderer over either engine. `Engine` is chosen once — the device, or the CPU mirror
//! where there is none or where it is a software rasterizer the mirror outruns — and a
//! `Renderer` made from it and a scene owns what every image needs on that engine: the
//! scene's splats and grid, the bake's lobes and direct light, the reference's binned
//! photons, the frame passes and the last image. It bakes, draws stills, moving frames,
//! references and path-traced images, tone-maps and reads back, with the same calls on either
//! engine; the
//! branch between the device (`gpu::renderer::FrameRenderer`) and the mirrors
//! (`cpu::frames`) is taken here and nowhere above.

use std::sync::Arc;
use std::time::Instant;

mod background;
mod engine;
mod measure;
mod window;
/// A smaller image upsampled onto a window's pixels as the present pass draws it (its mirror):
/// what a window shows of a moving frame drawn at a lower resolution.
pub use crate::cpu::present::upsample;
pub use background::{BakeEngine, BakeResult, Baking, PREVIEW_FRACTION, passes};
pub use engine::{Engine, EngineChoice, Fallback};
pub use measure::PresentTarget;
pub use window::{WindowFrame, WindowSurface, shown_in_window};

use crate::bake::{
    BakeDevice, Baked, Binned, Progress, SceneBuffers, StageReport, bake, bins_cpu, bins_gpu,
    on_device, on_mirror,
};
use crate::bins::PhotonBins;
use crate::camera::View;
use crate::cpu;
use crate::cpu::CpuExecutor;
use crate::direct::DirectMap;
use crate::em::{EmConfig, FitShape, GatherSetup, LobeMap};
use crate::error::{Error, Result};
use crate::frame::{FrameConfig, FramePlan, SceneExtent, Splatting, camera_uniform};
use crate::gpu::Gpu;
use crate::gpu::bins::GpuBins;
use crate::gpu::exec::GpuExecutor;
use crate::gpu::renderer::FrameRenderer;
use crate::gpu::scene::GpuScene;
pub use crate::gpu::{BackendChoice, Compiled};
use crate::grid::SplatGrid;
use crate::host::{self, FitFrom};
use crate::photons::{PhotonConfig, PhotonStats};
use crate::plan::BakeLimits;
use crate::scene::Scene;
use crate::sequence::{self, Executor};
use crate::timing::ms_since;
use crate::tone::ToneConfig;

/// What a bake reports of its stages (its lobes stay in the renderer).
#[derive(Clone, Debug)]
pub struct BakeReport {
    pub photons: StageReport,
    pub binning: StageReport,
    pub em: StageReport,
}

/// What `Renderer::bake_lit` reports besides the bake's stages.
#[derive(Clone, Debug)]
pub struct LitBake {
    pub bake: BakeReport,
    /// The grid the bake's engine built for it where that is not the renderer's (0 there).
    pub grid_ms: f64,
    /// The direct bake after it; 0 where the bake made it (final gathering's).
    pub direct_ms: f64,
}

/// A tone-mapped image: RGBA8 pixels (red in the low byte), rows from the top, and
/// (Σ log(ε + Y), count) of the log-average the operator keyed on.
pub struct Toned {
    pub rgba: Vec<u32>,
    pub log_sum: [f32; 2],
}

/// The scene's photons traced and read back to the host (`Renderer::trace_photons`).
pub struct TracedPhotons {
    pub map: crate::photons::PhotonMap,
    /// Reading them back from the device (0 on the mirror, where they are host memory).
    pub download_ms: f64,
}

/// The stored photons seen from a camera (`Renderer::photon_view`).
pub struct PhotonView {
    /// HDR pixels, rows from the top, scaled by the photons' power.
    pub hdr: Vec<[f32; 4]>,
    pub stats: PhotonStats,
    /// Drawing them, after the trace.
    pub draw_ms: f64,
}

/// What the renderer holds on a device.
struct Device {
    gpu: Arc<Gpu>,
    scene: Arc<GpuScene>,
    /// Made the first time a frame, a reference or a path-traced image is drawn (the photon
    /// view needs none of its passes).
    frames: Option<Box<FrameRenderer>>,
    bins: Option<Binned<GpuBins>>,
    /// The renderer's lobes are newer than the frames': uploaded before the next image.
    stale: bool,
    /// A direct bake of the current lights made by the bake, uploaded with the lobes.
    direct: Option<DirectMap>,
    /// The last image tone-mapped (`Renderer::tone`, a window's frame), and its size.
    toned: Option<(crate::gpu::tone::GpuToned, (u32, u32))>,
    /// A background bake's photons (`take_bake`) and how many were emitted: the photon and
    /// reference views of a window draw them.
    photons: Option<(crate::gpu::photons::GpuPhotons, u64)>,
}

impl Device {
    /// The device, its frame passes (made the first time, `lobes` uploaded where they are
    /// newer) and the binned photons.
    fn parts(
        &mut self,
        scene: &Scene,
        lobes: &LobeMap,
    ) -> Result<(&Gpu, &mut FrameRenderer, Option<&Binned<GpuBins>>)> {
        let Device {
            gpu,
            scene: on_gpu,
            frames,
            bins,
            stale,
            direct,
            ..
        } = self;
        let frames = match frames {
            Some(frames) => frames,
            none => none.insert(Box::new(FrameRenderer::with_scene(
                gpu,
                scene,
                on_gpu.clone(),
            )?)),
        };
        if *stale {
            frames.set_lobes(gpu, scene, lobes)?;
            *stale = false;
        }
        if let Some(direct) = direct.take() {
            frames.set_direct(gpu, scene, &direct, 0.0)?;
        }
        Ok((gpu, frames, bins.as_ref()))
    }

    /// The frame passes an image was drawn with.
    fn drawn(&self) -> Result<&FrameRenderer> {
        self.frames
            .as_deref()
            .ok_or_else(|| Error::internal("an image was read before one was drawn"))
    }
}

/// What the renderer holds on the CPU mirror.
struct Mirror {
    grid: SplatGrid,
    grid_ms: f64,
    /// The scene's bounds and shadow bias, walked once.
    extent: SceneExtent,
    bins: Option<Binned<PhotonBins>>,
    /// Every splat's direct light of the scene's lights: final gathering's, or baked the
    /// first time a frame reads it.
    direct: Option<DirectMap>,
    /// The last image drawn.
    hdr: Vec<[f32; 4]>,
    /// The moving frames' history (`draw_moving` with `temporal`); none after a reset.
    history: Option<MirrorHistory>,
    /// The last image tone-mapped (`Renderer::tone`).
    toned: Option<Toned>,
}

/// The last moving frame on the mirror: its plan (jitter included), the moving frames since
/// the last reset, and its resolved image and kept surfaces.
struct MirrorHistory {
    plan: FramePlan,
    frames: u32,
    image: Vec<[f32; 4]>,
    surface: Vec<[f32; 4]>,
}

impl Mirror {
    /// The plan of a frame of `view` drawn with `lobes`, its direct bake made first where it
    /// is `needed` and the bake made none.
    fn plan(
        &mut self,
        scene: &Scene,
        lobes: &LobeMap,
        (view, cfg): (&View, &FrameConfig),
        needed: bool,
    ) -> Result<FramePlan> {
        if needed && self.direct.is_none() {
            self.direct = Some(cpu::frames::cpu_direct(scene, &self.grid)?);
        }
        let cam = camera_uniform(view, self.extent.bounds, cfg);
        let per_splat = lobes.lobes_per_splat;
        let plan = FramePlan::of(
            scene,
            &self.extent,
            per_splat,
            (&cam, cfg),
            Splatting::Raster,
        );
        Ok(plan)
    }

    /// The direct bake a frame reads: none where it reads none (`plan` made it where it does).
    fn read_direct(&self, needed: bool) -> &DirectMap {
        static NONE: DirectMap = DirectMap {
            direct: Vec::new(),
            visibility: Vec::new(),
        };
        self.direct.as_ref().filter(|_| needed).unwrap_or(&NONE)
    }
}

enum On {
    Device(Box<Device>),
    Mirror(Box<Mirror>),
}

/// Work written once over any executor with the scene's buffers there (a benchmark's own
/// sequence of bake passes, say), which `Renderer::run` runs on its engine.
pub trait SceneWork {
    type Out;
    /// Runs on `ex`, which traces the scene, with its splats and materials in `on` and the
    /// engine's `limits`.
    fn run<E: Executor>(
        self,
        ex: &mut E,
        on: &SceneBuffers<E::Buffer>,
        limits: &BakeLimits,
    ) -> Result<Self::Out>;
}

/// A scene prepared on one engine, and everything drawn from it.
pub struct Renderer {
    scene: Arc<Scene>,
    engine: Engine,
    on: On,
    /// The bake's lobes (an empty map until a bake or `set_lobes`).
    lobes: LobeMap,
}

/// Runs `$body` with `$ex` an executor of `$renderer`'s engine that traces its scene (the
/// device's buffers or the mirror's grid) and `$limits` the engine's `BakeLimits`.
macro_rules! tracing_scene {
    ($renderer:expr, $label:literal, |$ex:ident, $limits:ident| $body:expr) => {
        match &$renderer.on {
            On::Device(d) => {
                let $limits = &d.gpu.bake_limits();
                let mut encoder = d.gpu.encoder($label);
                let $ex = &mut GpuExecutor::new(&d.gpu, &mut encoder).tracing(d.scene.geometry());
                $body
            }
            On::Mirror(m) => {
                let $limits = &BakeLimits::host();
                let $ex = &mut CpuExecutor::tracing($renderer.scene.geometry(&m.grid));
                $body
            }
        }
    };
}

fn unbinned() -> Error {
    Error::internal("a reference was drawn before its photons were binned")
}

impl Renderer {
    /// Prepares `scene` on `engine`: its splats and grid uploaded to the device, or the grid
    /// built on the host.
    pub fn new(scene: Arc<Scene>, engine: &Engine) -> Result<Renderer> {
        let on = match engine {
            Engine::Device(gpu) => On::Device(Box::new(Device {
                scene: Arc::new(GpuScene::upload(gpu, &scene)?),
                gpu: gpu.clone(),
                frames: None,
                bins: None,
                stale: false,
                direct: None,
                toned: None,
                photons: None,
            })),
            Engine::Mirror => {
                let t = std::time::Instant::now();
                let grid = cpu::scene_grid(&scene)?;
                On::Mirror(Box::new(Mirror {
                    grid,
                    grid_ms: ms_since(t),
                    extent: SceneExtent::of(&scene),
                    bins: None,
                    direct: None,
                    hdr: Vec::new(),
                    history: None,
                    toned: None,
                }))
            }
        };
        Ok(Renderer {
            scene,
            engine: engine.clone(),
            on,
            lobes: LobeMap::default(),
        })
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn engine(&self) -> &Engine {
        &self.engine
    }

    /// Runs `work` on the engine's executor over the scene as prepared there, and waits for
    /// it.
    pub fn run<W: SceneWork>(&self, work: W) -> Result<W::Out> {
        let scene = &self.scene;
        match &self.on {
            On::Device(d) => on_device(scene, &d.gpu, &d.scene, |ex, on| {
                work.run(ex, on, &d.gpu.bake_limits())
            }),
            On::Mirror(m) => on_mirror(scene, &m.grid, |ex, on| {
                work.run(ex, on, &BakeLimits::host())
            }),
        }
    }

    /// The grid build's milliseconds.
    pub fn grid_ms(&self) -> f64 {
        match &self.on {
            On::Device(d) => d.scene.grid_ms,
            On::Mirror(m) => m.grid_ms,
        }
    }

    /// The scene's splat grid in host memory: the mirror's, or read back from the device.
    pub fn read_grid(&self) -> Result<std::borrow::Cow<'_, SplatGrid>> {
        Ok(match &self.on {
            On::Device(d) => std::borrow::Cow::Owned(d.scene.grid.download(&d.gpu)?),
            On::Mirror(m) => std::borrow::Cow::Borrowed(&m.grid),
        })
    }

    /// The lobes frames are drawn with (an empty map before a bake).
    pub fn lobes(&self) -> &LobeMap {
        &self.lobes
    }

    /// Draws and bakes another scene from now on: its splats uploaded and its grid built
    /// anew, the device's passes kept compiled; no lobes until a bake or `set_lobes`.
    pub fn set_scene(&mut self, scene: Arc<Scene>) -> Result<()> {
        match &mut self.on {
            On::Device(d) => {
                d.scene = match &mut d.frames {
                    Some(frames) => {
                        frames.set_scene(&d.gpu, &scene)?;
                        frames.on_gpu.clone()
                    }
                    None => Arc::new(GpuScene::upload(&d.gpu, &scene)?),
                };
                (d.bins, d.direct, d.stale) = (None, None, false);
            }
            On::Mirror(m) => {
                let t = std::time::Instant::now();
                m.grid = cpu::scene_grid(&scene)?;
                m.grid_ms = ms_since(t);
                m.extent = SceneExtent::of(&scene);
                (m.bins, m.direct, m.history) = (None, None, None);
            }
        }
        self.scene = scene;
        self.lobes = LobeMap::default();
        Ok(())
    }

    /// Draws and bakes `scene` from now on, which holds this one's splats, materials and
    /// clips with other lights or other bake settings (a moved light, a preview bake): the
    /// grid stays, the lobes stay until the next bake, and the direct light is baked again
    /// where the lights changed. Other geometry needs a new renderer.
    pub fn relight(&mut self, scene: Arc<Scene>) -> Result<()> {
        let old = &self.scene;
        let same = Arc::ptr_eq(&scene, old)
            || bytemuck::cast_slice::<_, u8>(&scene.splats)
                == bytemuck::cast_slice::<_, u8>(&old.splats)
                && bytemuck::cast_slice::<_, u8>(&scene.materials)
                    == bytemuck::cast_slice::<_, u8>(&old.materials)
                && bytemuck::cast_slice::<_, u8>(&scene.clips)
                    == bytemuck::cast_slice::<_, u8>(&old.clips);
        if !same {
            return Err(Error::Invalid(
                "relight keeps the scene's splats, materials and clips; another scene needs \
                 a renderer of its own"
                    .into(),
            ));
        }
        let moved = scene.lights != old.lights;
        match &mut self.on {
            On::Device(d) => {
                if let Some(frames) = &mut d.frames {
                    frames.set_lights(&d.gpu, &scene)?;
                }
                if moved {
                    (d.direct, d.bins) = (None, None);
                }
            }
            On::Mirror(m) => {
                if moved {
                    (m.direct, m.bins, m.history) = (None, None, None);
                }
            }
        }
        self.scene = scene;
        Ok(())
    }

    /// Bakes the scene's light (photons → deposits or bins → lobes) and keeps it for the
    /// images to come.
    pub fn bake(&mut self, progress: &Progress) -> Result<BakeReport> {
        let scene = &self.scene;
        let baked = match &self.on {
            On::Device(d) => bake(scene, BakeDevice::Gpu(&d.gpu, &d.scene), progress)?,
            On::Mirror(m) => bake(scene, BakeDevice::Cpu(&m.grid), progress)?,
        };
        let report = BakeReport {
            photons: baked.photons.clone(),
            binning: baked.binning.clone(),
            em: baked.em.clone(),
        };
        self.set_baked(baked);
        Ok(report)
    }

    /// The bake from the cache file `cache` when it was made for this scene and these bake
    /// settings, else baked (and saved there where a file is named); whether it was loaded.
    pub fn bake_cached(
        &mut self,
        cache: Option<&std::path::Path>,
        progress: &Progress,
    ) -> Result<(BakeReport, bool)> {
        use crate::cache::{self, Miss};
        let scene = self.scene();
        let key = cache::bake_key(scene);
        if let Some(path) = cache {
            match cache::load(path, key, scene.splats.len())? {
                Ok(lobes) => {
                    let why = format!("bake loaded from {}", path.display());
                    if progress.shows() {
                        eprintln!("{why}");
                    }
                    let skipped = StageReport::skipped(&why);
                    self.set_lobes(lobes);
                    let report = BakeReport {
                        photons: skipped.clone(),
                        binning: skipped.clone(),
                        em: skipped,
                    };
                    return Ok((report, true));
                }
                Err(Miss::Stale) if progress.shows() => eprintln!(
                    "{}: the scene or a bake setting changed since it was written; baking again",
                    path.display()
                ),
                Err(_) => {}
            }
        }
        let report = self.bake(progress)?;
        if let Some(path) = cache {
            cache::save(path, key, self.lobes())?;
        }
        Ok((report, false))
    }

    /// Bakes the scene's light on `engine` — the renderer's own, or another (the mirror beside
    /// a software rasterizer that draws, which it outruns at baking) — and its direct light
    /// where the bake made none, there too; draws with both from now on.
    pub fn bake_lit(&mut self, engine: &Engine, progress: &Progress) -> Result<LitBake> {
        let same = match (engine, &self.engine) {
            (Engine::Mirror, Engine::Mirror) => true,
            (Engine::Device(a), Engine::Device(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        if same {
            let (bake, direct_ms) = self.bake_with_direct(progress)?;
            return Ok(LitBake {
                bake,
                grid_ms: 0.0,
                direct_ms,
            });
        }
        let mut there = Renderer::new(self.scene.clone(), engine)?;
        let (bake, direct_ms) = there.bake_with_direct(progress)?;
        let direct = match &mut there.on {
            On::Device(d) => match (d.direct.take(), &mut d.frames) {
                (Some(direct), _) => Some(direct),
                (None, Some(frames)) => Some(frames.read_direct(&d.gpu, &self.scene)?),
                (None, None) => None,
            },
            On::Mirror(m) => m.direct.take(),
        };
        self.set_baked(Baked {
            lobes: std::mem::take(&mut there.lobes),
            direct,
            photons: StageReport::default(),
            binning: StageReport::default(),
            em: StageReport::default(),
        });
        Ok(LitBake {
            bake,
            grid_ms: there.grid_ms(),
            direct_ms,
        })
    }

    /// `bake`, then the direct bake where the bake made none: its report and the direct
    /// bake's milliseconds (0 where the bake made it).
    fn bake_with_direct(&mut self, progress: &Progress) -> Result<(BakeReport, f64)> {
        let bake = self.bake(progress)?;
        let direct_ms = match self.made_direct() {
            true => 0.0,
            false => self.bake_direct()?,
        };
        Ok((bake, direct_ms))
    }

    /// Whether a direct bake of the current lights waits to be drawn with (final gathering
    /// made one, or `bake_direct` did), in host memory.
    fn made_direct(&self) -> bool {
        match &self.on {
            On::Device(d) => d.direct.is_some(),
            On::Mirror(m) => m.direct.is_some(),
        }
    }

    /// Draws with a bake made elsewhere from now on: its lobes, and the direct bake final
    /// gathering made where it ran (else the direct light of the lights as they are, made
    /// already or when a frame first reads it).
    pub fn set_baked(&mut self, baked: Baked) {
        match &mut self.on {
            On::Device(d) => {
                d.stale = true;
                if baked.direct.is_some() {
                    d.direct = baked.direct;
                }
            }
            On::Mirror(m) => {
                if baked.direct.is_some() {
                    m.direct = baked.direct;
                }
                m.history = None;
            }
        }
        self.lobes = baked.lobes;
    }

    /// Draws with `lobes` from now on (a bake loaded from a cache, or kept from before).
    pub fn set_lobes(&mut self, lobes: LobeMap) {
        self.set_baked(Baked {
            lobes,
            direct: None,
            photons: StageReport::default(),
            binning: StageReport::default(),
            em: StageReport::default(),
        })
    }

    /// Bakes the direct light of the scene's lights into every splat now (frames that read
    /// it would otherwise bake it first); returns its milliseconds.
    pub fn bake_direct(&mut self) -> Result<f64> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, _) = d.parts(scene, &self.lobes)?;
                frames.bake_direct(gpu, scene)
            }
            On::Mirror(m) => {
                let t = std::time::Instant::now();
                m.direct = Some(cpu::frames::cpu_direct(scene, &m.grid)?);
                Ok(ms_since(t))
            }
        }
    }

    /// Draws the lobes' frame of `view` with `spp` refinement frames (`frame::refinement`),
    /// `each(k)` called after frame `k`; `spp` 0 is the frame a moving camera gets (direct
    /// light as `cfg.direct` says). Keeps the HDR image for `read_hdr` and `tone_map`.
    pub fn draw(
        &mut self,
        view: &View,
        cfg: &FrameConfig,
        spp: u32,
        mut each: impl FnMut(u32),
    ) -> Result<()> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, _) = d.parts(scene, &self.lobes)?;
                match spp {
                    0 => frames.draw(gpu, scene, view, cfg)?,
                    spp => frames.draw_refined(gpu, scene, view, cfg, spp, each)?,
                };
            }
            On::Mirror(m) => {
                // A refinement frame casts shadow rays; its glossy rays read the direct bake.
                let needed = match spp {
                    0 => cfg.needs_direct_bake(),
                    _ => cfg.glossy_rays > 0,
                };
                let plan = m.plan(scene, &self.lobes, (view, cfg), needed)?;
                let light = (&self.lobes, m.read_direct(needed));
                m.hdr = cpu::frames::cpu_draw(scene, &m.grid, light, &plan, spp);
                (0..spp).for_each(&mut each);
            }
        }
        Ok(())
    }

    /// Draws the moving frame of `view`: with `cfg.temporal`, jittered and blended with the
    /// moving frames before it (`sequence::temporal`; none before it after a reset: new lobes,
    /// lights, size or shading), else the frame a moving camera gets alone (`draw` with no
    /// refinement frames). Keeps the HDR image, the resolved one.
    pub fn draw_moving(&mut self, view: &View, cfg: &FrameConfig) -> Result<()> {
        let scene = &self.scene;
        let m = match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, _) = d.parts(scene, &self.lobes)?;
                frames.draw_moving(gpu, scene, view, cfg)?;
                return Ok(());
            }
            On::Mirror(m) => m,
        };
        let needed = cfg.needs_direct_bake();
        let plan = m.plan(scene, &self.lobes, (view, cfg), needed)?;
        // A frame drawn alone, or shaded otherwise, ends the history.
        let alike =
            |h: &MirrorHistory| h.plan.params == plan.params && h.plan.view.size == plan.view.size;
        let last = m.history.take().filter(|h| cfg.temporal && alike(h));
        if !cfg.temporal {
            let light = (&self.lobes, m.read_direct(needed));
            m.hdr = cpu::frames::cpu_draw(scene, &m.grid, light, &plan, 0);
            return Ok(());
        }
        let frames = last.as_ref().map_or(0, |h| h.frames);
        let next = plan.jittered(crate::frame::temporal_jitter(frames));
        let light = (&self.lobes, m.read_direct(needed));
        let (hdr, surface) = cpu::frames::cpu_draw_surface(scene, &m.grid, light, &next, 0);
        let (image, kept) = temporal_on_mirror(&next, last.as_ref(), (&hdr, &surface))?;
        m.hdr = image.clone();
        m.history = Some(MirrorHistory {
            plan: next,
            frames: frames + 1,
            image,
            surface: kept,
        });
        Ok(())
    }

    /// Traces and bins the scene's photons for references (no lobes); returns the reports of
    /// the trace and of the binning.
    pub fn bin_photons(&mut self, progress: &Progress) -> Result<[StageReport; 2]> {
        let scene = &self.scene;
        Ok(match &mut self.on {
            On::Device(d) => {
                let binned = bins_gpu(scene, &d.gpu, &d.scene, progress)?;
                let binned = d.bins.insert(binned);
                [binned.photons.clone(), binned.binning.clone()]
            }
            On::Mirror(m) => {
                let binned = m.bins.insert(bins_cpu(scene, &m.grid, progress)?);
                [binned.photons.clone(), binned.binning.clone()]
            }
        })
    }

    /// Draws the reference of `view` from the binned photons (`bin_photons` first): per pixel
    /// the photons within the gather radius with the exact BRDF, the direct light by shadow
    /// rays.
    pub fn draw_reference(&mut self, view: &View, cfg: &FrameConfig) -> Result<()> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, binned) = d.parts(scene, &self.lobes)?;
                let binned = binned.ok_or_else(unbinned)?;
                let bins = (&binned.bins, &binned.em);
                frames.draw_reference(gpu, scene, bins, view, cfg)?;
            }
            On::Mirror(m) => {
                let binned = m.bins.as_ref().ok_or_else(unbinned)?;
                let cam = camera_uniform(view, m.extent.bounds, cfg);
                let (bins, em) = (&binned.bins, &binned.em);
                m.hdr = cpu::frames::cpu_reference(scene, &m.grid, bins, em, &cam, cfg);
            }
        }
        Ok(())
    }

    /// Path-traces `view`: `spp` samples per pixel of the light terms `cfg.show`, `each(k)`
    /// called after sample `k`. Needs no bake.
    pub fn draw_path(
        &mut self,
        view: &View,
        cfg: &FrameConfig,
        spp: u32,
        mut each: impl FnMut(u32),
    ) -> Result<()> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, _) = d.parts(scene, &self.lobes)?;
                frames.draw_path(gpu, scene, view, cfg.show, spp, each)?;
            }
            On::Mirror(m) => {
                let cam = camera_uniform(view, m.extent.bounds, cfg);
                m.hdr = cpu::frames::cpu_path(scene, &m.grid, &cam, cfg.show, spp)?;
                (0..spp.max(1)).for_each(&mut each);
            }
        }
        Ok(())
    }

    /// Traces `cfg`'s photons from the scene's lights (`host::trace`) and reads them back;
    /// `on_batch` hears (paths done, total).
    pub fn trace_photons(
        &self,
        cfg: &PhotonConfig,
        on_batch: &mut dyn FnMut(u64, u64),
    ) -> Result<TracedPhotons> {
        let scene = &self.scene;
        tracing_scene!(self, "photon trace", |ex, limits| {
            let materials = ex.upload("materials", &scene.materials)?;
            let traced = host::trace(ex, limits, (&scene.lights, &materials), cfg, on_batch)?;
            let t = Instant::now();
            let map = traced.read_back(ex)?;
            Ok(TracedPhotons {
                map,
                download_ms: ms_since(t),
            })
        })
    }

    /// Traces the scene's photons and draws the stored ones seen from `view` (thesis Fig.
    /// 3.1, `sequence::photon_image`); `on_batch` hears (paths done, total).
    pub fn photon_view(
        &self,
        view: &View,
        cfg: &FrameConfig,
        on_batch: &mut dyn FnMut(u64, u64),
    ) -> Result<PhotonView> {
        let scene = &self.scene;
        let photons = PhotonConfig::from_scene(scene);
        let cam = camera_uniform(view, scene.bounds(), cfg);
        let scale = cpu::photon_view::scene_scale(&scene.lights, photons.photons)?;
        let pixels = (view.width * view.height) as usize;
        tracing_scene!(self, "photon view", |ex, limits| {
            let materials = ex.upload("materials", &scene.materials)?;
            let lit = (&scene.lights[..], &materials);
            let traced = host::trace(ex, limits, lit, &photons, on_batch)?;
            let t = Instant::now();
            let pages: Vec<_> = traced
                .pages
                .iter()
                .map(|p| (&p.buffer, p.count as u32))
                .collect();
            let hdr = sequence::photon_image(ex, &materials, &pages, &cam, scale)?;
            let hdr = ex.read(&hdr, pixels)?;
            Ok(PhotonView {
                hdr,
                stats: traced.stats,
                draw_ms: ms_since(t),
            })
        })
    }

    /// The lobe fit of the scene's splats to `from` in `shape` (`host::fit_lobes`), with final
    /// gathering of `gathering`'s lights through the scene where it is given.
    pub fn fit_lobes(
        &self,
        cfg: &EmConfig,
        from: FitFrom,
        shape: FitShape,
        gathering: Option<&GatherSetup>,
    ) -> Result<LobeMap> {
        self.engine.check_shape(shape)?;
        let scene = &self.scene;
        tracing_scene!(self, "lobe fit", |ex, limits| {
            let limits = &BakeLimits {
                fit_shape: shape,
                ..*limits
            };
            let of = (&scene.splats[..], &scene.materials[..]);
            host::fit_lobes(ex, limits, cfg, from, of, gathering)
        })
    }

    /// Which scene surface each pixel of `view` shows (`objects::object_ids`, on the host,
    /// over the engine's grid).
    pub fn object_ids(&self, view: &View, cfg: &FrameConfig) -> Result<Vec<u16>> {
        let scene = &self.scene;
        let cam = camera_uniform(view, scene.bounds(), cfg);
        let grid = self.read_grid()?;
        crate::objects::object_ids(scene, &grid, &cam, crate::objects::SAMPLES)
    }

    /// The last image's linear HDR pixels, rows from the top.
    pub fn read_hdr(&self) -> Result<Vec<[f32; 4]>> {
        match &self.on {
            On::Device(d) => d.drawn()?.read_hdr(&d.gpu),
            On::Mirror(m) => Ok(m.hdr.clone()),
        }
    }

    /// The last image tone-mapped (`sequence::tone_map`) and read back.
    pub fn tone_map(&mut self, tone: &ToneConfig) -> Result<Toned> {
        self.tone(tone)?;
        self.read_toned()
    }

    /// Tone-maps the last image and keeps it where it was drawn (`read_toned`, `present`).
    pub fn tone(&mut self, tone: &ToneConfig) -> Result<()> {
        match &mut self.on {
            On::Device(d) => {
                let frames = d.drawn()?;
                let targets = frames.targets()?;
                let size = (targets.width, targets.height);
                d.toned = Some((frames.tone_map(&d.gpu, tone)?, size));
            }
            On::Mirror(m) => {
                let (rgba, log_sum) = cpu::tone_map(tone, &m.hdr)?;
                m.toned = Some(Toned { rgba, log_sum });
            }
        }
        Ok(())
    }

    /// The last image `tone` tone-mapped, in host memory.
    pub fn read_toned(&self) -> Result<Toned> {
        let untoned = || Error::internal("an image was read before it was tone-mapped");
        match &self.on {
            On::Device(d) => {
                let (gpu, (toned, size)) = (&d.gpu, d.toned.as_ref().ok_or_else(untoned)?);
                let pixels = (size.0 * size.1) as usize;
                let log_sum = gpu.read::<[f32; 2]>(&toned.log_sum, 1)?;
                Ok(Toned {
                    rgba: gpu.read::<u32>(&toned.rgba, pixels)?,
                    log_sum: log_sum.first().copied().unwrap_or_default(),
                })
            }
            On::Mirror(m) => {
                let toned = m.toned.as_ref().ok_or_else(untoned)?;
                Ok(Toned {
                    rgba: toned.rgba.clone(),
                    log_sum: toned.log_sum,
                })
            }
        }
    }
}

/// An image and the surface each of its pixels shows, in host memory.
type ImageAndSurface = (Vec<[f32; 4]>, Vec<[f32; 4]>);

/// The temporal pass on the mirror (`sequence::temporal`) of the moving frame `next` drawn as
/// `now` (its image and surfaces), blended with `last`'s history: the resolved image and the
/// surfaces it kept, the next frame's history.
fn temporal_on_mirror(
    next: &FramePlan,
    last: Option<&MirrorHistory>,
    (hdr, surface): (&[[f32; 4]], &[[f32; 4]]),
) -> Result<ImageAndSurface> {
    use crate::sequence::{Executor, TemporalHistory, temporal};
    let [w, h] = next.view.size.map(|x| x as u32);
    let pixels = (w * h) as usize;
    let params = crate::frame::temporal_params(w, h, last.is_none());
    let prev = last.map_or(next.view, |l| l.plan.view);
    let mut ex = cpu::CpuExecutor::default();
    let blank = vec![[0.0f32; 4]; pixels];
    let (last_image, last_surface) = last.map_or((&blank, &blank), |l| (&l.image, &l.surface));
    let hdr = ex.upload("hdr", hdr)?;
    let surface = ex.upload("surface", surface)?;
    let from = (
        ex.upload("history", last_image)?,
        ex.upload("history surface", last_surface)?,
    );
    let bytes = pixels as u64 * 16;
    let to = (
        ex.zeroed("resolved", bytes)?,
        ex.zeroed("kept surface", bytes)?,
    );
    let last = TemporalHistory {
        image: &from.0,
        surface: &from.1,
    };
    let next_history = TemporalHistory {
        image: &to.0,
        surface: &to.1,
    };
    temporal(
        &mut ex,
        &next.view,
        &prev,
        &params,
        &hdr,
        &surface,
        last,
        next_history,
    )?;
    Ok((ex.read(&hdr, pixels)?, ex.read(&to.1, pixels)?))
}
