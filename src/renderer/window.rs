//! A renderer's frames in a window: the window's surface and the present pass onto it
//! (`WindowSurface`), each frame drawn, tone-mapped and presented in one submission
//! (`Renderer::present_frame`), and bakes on a second thread beside them (`background`),
//! whose photons the photon and reference views draw. A window shows a device's frames: the
//! bake may run on the CPU mirror beside a software rasterizer (`BakeEngine`), the frames not.

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;

use super::background::{self, BakeEngine, BakeResult, Baking};
use super::{Device, Engine, On, Renderer};
use crate::bake::{Progress, bin_traced, on_device};
use crate::camera::View;
use crate::cpu::photon_view::scene_scale;
use crate::error::{Error, Result};
use crate::frame::{FrameConfig, camera_uniform};
use crate::gpu::photon_view::photon_image;
use crate::gpu::present::PresentPipeline;
use crate::gpu::scene::GpuScene;
use crate::gpu::tone::tone_map;
use crate::gpu::{BackendChoice, Gpu};
use crate::plan::BakePlan;
use crate::scene::{BakeDesc, Scene};
use crate::tone::ToneConfig;
use crate::types::PresentParams;

/// A window's surface, configured at the window's size, and the present pass onto it.
pub struct WindowSurface {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    present: PresentPipeline,
}

/// What a window's frame shows.
pub enum WindowFrame<'a> {
    /// The lobes' moving frame of the view (its size the internal resolution).
    Moving(&'a View, &'a FrameConfig),
    /// Refinement frame `k` of `spp` of the still image of the view.
    Sample(&'a View, &'a FrameConfig, u32, u32),
    /// The photon-map reference of the view, from the background bake's photons (binned the
    /// first time it is shown).
    Reference(&'a View, &'a FrameConfig),
    /// The background bake's stored photons seen from the view.
    Photons(&'a View, &'a FrameConfig),
    /// The last image again (a still image complete).
    Again,
}

impl Renderer {
    /// A renderer of `scene` on the device that shows `window` (with `backend`), and the
    /// window's surface, in a plain (non-sRGB) 8-bit format where it offers one (the tone
    /// map's bytes as they are).
    pub fn for_window<D, W>(
        scene: Arc<Scene>,
        backend: BackendChoice,
        (display, window): (&D, &Arc<W>),
        (width, height): (u32, u32),
    ) -> Result<(Renderer, WindowSurface)>
    where
        D: wgpu::rwh::HasDisplayHandle + Clone + std::fmt::Debug + Send + Sync + 'static,
        W: wgpu::DisplayAndWindowHandle + 'static,
    {
        let (gpu, surface) = Gpu::for_window(backend, display, window)?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or(caps.formats.first().copied())
            .ok_or_else(|| Error::Gpu("the window's surface offers no format".into()))?;
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: width.max(1),
            height: height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&gpu.device, &config);
        let present = PresentPipeline::new(&gpu, format)?;
        let renderer = Renderer::new(scene, &Engine::Device(Arc::new(gpu)))?;
        let surface = WindowSurface {
            surface,
            config,
            present,
        };
        Ok((renderer, surface))
    }

    /// The device a window shows, its scene and frame passes (made the first time).
    fn window_device(&mut self) -> Result<&mut Device> {
        match &mut self.on {
            On::Device(d) => Ok(d),
            On::Mirror(_) => Err(Error::internal("a window shows a device's frames")),
        }
    }

    /// Bakes the direct light frames read where none is baked yet: its milliseconds where it
    /// baked.
    pub fn ensure_direct(&mut self) -> Result<Option<f64>> {
        let baked = match &self.on {
            On::Device(d) => {
                d.direct.is_some() || d.frames.as_ref().is_some_and(|f| f.direct_is_baked())
            }
            On::Mirror(m) => m.direct.is_some(),
        };
        match baked {
            true => Ok(None),
            false => self.bake_direct().map(Some),
        }
    }

    /// Draws `frame`, tone-maps it with `tone` and presents it onto the surface's next
    /// texture, in one submission: the size it was drawn at (a moving frame's internal
    /// resolution, upsampled by the present pass), or none where the surface gave no texture
    /// this time (`read_toned` reads the image back).
    pub fn present_frame(
        &mut self,
        surface: &mut WindowSurface,
        frame: &WindowFrame,
        tone: &ToneConfig,
    ) -> Result<Option<(u32, u32)>> {
        let gpu = self.window_device()?.gpu.clone();
        let Some(texture) = surface.next_texture(&gpu)? else {
            return Ok(None);
        };
        let scene = self.scene.clone();
        let bounds = match &self.on {
            On::Device(d) => d
                .frames
                .as_ref()
                .map_or_else(|| scene.bounds(), |f| f.extent().bounds),
            On::Mirror(m) => m.extent.bounds,
        };
        if let WindowFrame::Reference(..) = frame {
            self.bin_background_photons()?;
        }
        let lobes = &self.lobes;
        let d = match &mut self.on {
            On::Device(d) => d,
            On::Mirror(_) => return Err(Error::internal("a window shows a device's frames")),
        };
        let mut encoder = gpu.encoder("window frame");
        let photons = match frame {
            WindowFrame::Photons(view, cfg) => {
                let (photons, emitted) = d.photons.as_ref().ok_or_else(no_photons)?;
                let cam = camera_uniform(view, bounds, cfg);
                let scale = scene_scale(&scene.lights, *emitted)?;
                let hdr = photon_image(&gpu, &mut encoder, &d.scene, photons, &cam, scale)?;
                Some((hdr, (view.width, view.height)))
            }
            _ => None,
        };
        let (_, frames, binned) = d.parts(&scene, lobes)?;
        let (hdr, size): (Cow<wgpu::Buffer>, (u32, u32)) = match (frame, photons) {
            (_, Some((hdr, size))) => (Cow::Owned(hdr), size),
            (WindowFrame::Reference(view, cfg), None) => {
                let binned = binned.ok_or_else(no_photons)?;
                frames.resize(&gpu, view.width, view.height)?;
                let cam = camera_uniform(view, bounds, cfg);
                let (bins, em) = (&binned.bins, &binned.em);
                let hdr =
                    frames.record_reference(&gpu, &mut encoder, &scene, bins, em, &cam, cfg)?;
                (Cow::Borrowed(hdr), (view.width, view.height))
            }
            (WindowFrame::Moving(view, cfg), None) => {
                frames.resize(&gpu, view.width, view.height)?;
                let cam = camera_uniform(view, bounds, cfg);
                frames.record_moving(&gpu, &mut encoder, &scene, &cam, cfg)?;
                let t = frames.targets()?;
                (Cow::Borrowed(&t.hdr), (t.width, t.height))
            }
            (WindowFrame::Sample(view, cfg, k, spp), None) => {
                frames.resize(&gpu, view.width, view.height)?;
                let cam = camera_uniform(view, bounds, cfg);
                frames.record_sample(&gpu, &mut encoder, &scene, &cam, cfg, *k, *spp)?;
                let t = frames.targets()?;
                (Cow::Borrowed(&t.hdr), (t.width, t.height))
            }
            (WindowFrame::Again | WindowFrame::Photons(..), None) => {
                let t = frames.targets()?;
                (Cow::Borrowed(&t.hdr), (t.width, t.height))
            }
        };
        let toned = tone_map(&gpu, &mut encoder, &hdr, size.0 * size.1, tone)?;
        drop(hdr);
        let target = texture.texture.create_view(&Default::default());
        let window = (surface.config.width, surface.config.height);
        (surface.present).record(&gpu, &mut encoder, &target, &toned.rgba, size, window);
        gpu.submit_and_wait(encoder)?;
        gpu.queue.present(texture);
        d.toned = Some((toned, size));
        Ok(Some(size))
    }

    /// Bins the background bake's photons for the reference view where the bake binned none
    /// (its fit read deposits).
    fn bin_background_photons(&mut self) -> Result<()> {
        let scene = self.scene.clone();
        let d = self.window_device()?;
        if d.bins.is_some() {
            return Ok(());
        }
        let (photons, _) = d.photons.as_ref().ok_or_else(no_photons)?;
        let plan = BakePlan::new(&scene, d.gpu.bake_limits())?;
        let quiet = Progress::new(false);
        let binned = on_device(&scene, &d.gpu, &d.scene, |ex, on| {
            bin_traced(ex, &plan, on, photons, &quiet)
        })?;
        d.bins = Some(binned);
        Ok(())
    }

    /// Whether a background bake's photons are in (the photon and reference views draw them).
    pub fn has_photons(&self) -> bool {
        matches!(&self.on, On::Device(d) if d.photons.is_some())
    }

    /// Where background bakes of this renderer's scene run: the device, or the mirror (its
    /// grid built now).
    pub fn bake_engine(&self, on_mirror: bool) -> Result<BakeEngine> {
        match on_mirror {
            true => BakeEngine::mirror(&self.scene),
            false => Ok(BakeEngine::Device),
        }
    }

    /// Starts a bake of `scene` (this renderer's splats, its lights perhaps moved) over
    /// `passes` on a second thread, as generation `generation`'s next; the full (last) pass is
    /// saved to `cache` when given. `take_bake` takes each pass's result.
    pub fn spawn_bake(
        &self,
        engine: &BakeEngine,
        scene: &Arc<Scene>,
        (passes, cache): (Vec<BakeDesc>, Option<PathBuf>),
        generation: &Arc<AtomicU64>,
    ) -> Result<Baking> {
        let On::Device(d) = &self.on else {
            return Err(Error::internal("background bakes serve a window's device"));
        };
        let on: (&Arc<Gpu>, &Arc<GpuScene>) = (&d.gpu, &d.scene);
        Ok(background::spawn(
            on, engine, scene, passes, cache, generation,
        ))
    }

    /// Draws with a background bake's pass from now on: its lobes, and its photons (and bins,
    /// where it binned them) for the photon and reference views.
    pub fn take_bake(&mut self, result: BakeResult) -> Result<()> {
        let d = self.window_device()?;
        d.photons = Some((result.photons, result.emitted));
        d.bins = result.binned;
        self.set_lobes(result.lobes);
        Ok(())
    }
}

fn no_photons() -> Error {
    Error::internal("a view of the photons was drawn before a bake brought them")
}

impl WindowSurface {
    /// The window's size in pixels, as the surface is configured.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Configures the surface at the window's new size (a minimised window, 0 wide or high,
    /// keeps the last).
    pub fn resize(&mut self, renderer: &Renderer, (width, height): (u32, u32)) {
        if width == 0 || height == 0 {
            return;
        }
        if let Some(gpu) = renderer.engine().gpu() {
            (self.config.width, self.config.height) = (width, height);
            self.surface.configure(&gpu.device, &self.config);
        }
    }

    /// The surface's next texture, or none this time (timed out, hidden, or reconfigured
    /// after it went out of date).
    fn next_texture(&mut self, gpu: &Gpu) -> Result<Option<wgpu::SurfaceTexture>> {
        Ok(match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => None,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                // Configured again; the next frame draws.
                self.surface.configure(&gpu.device, &self.config);
                None
            }
            other => {
                return Err(Error::Gpu(format!(
                    "the window's surface failed: {other:?}"
                )));
            }
        })
    }
}

/// `rgba`, an image of `image` pixels, as a window of `window` pixels shows it: upsampled as
/// the present pass does (its mirror) where it is smaller.
pub fn shown_in_window(rgba: &[u32], image: (u32, u32), window: (u32, u32)) -> Vec<u32> {
    if image == window {
        return rgba.to_vec();
    }
    let params = PresentParams::new(image, window, false);
    crate::cpu::present::present(&params, rgba)
        .iter()
        .map(|c| {
            let byte = |v: f32| (v * 255.0).round().clamp(0.0, 255.0) as u32;
            byte(c[0]) | byte(c[1]) << 8 | byte(c[2]) << 16 | 0xff00_0000
        })
        .collect()
}
