//! `lobelight view`: a winit window that draws the scene every frame through the offscreen
//! render's passes (splat passes, tone map) and one more, `present`, onto the window. The
//! window opens with direct light while the bake runs on a second thread on the same device,
//! and switches to full global illumination when the lobes arrive.
//!
//! Keys: mouse left drag orbits, right drag pans, wheel zooms; W A S D fly, Q E down and up;
//! the keys plus and minus change the exposure by half a stop, [ and ] the tone-map key; P
//! saves a screenshot; H prints the keys; Esc quits. `--frames N --screenshot OUT.png` draws N frames once the bake
//! is in, saves the last and exits (scripted runs and tests).

mod orbit;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop, OwnedDisplayHandle};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::bake::{BakeDevice, Progress, bake};
use crate::camera::View;
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::frame::{FrameConfig, Show, camera_uniform, shade_params};
use crate::gpu::frame::{FrameScene, FrameTargets, SplatPipelines};
use crate::gpu::present::PresentPipeline;
use crate::gpu::scene::GpuScene;
use crate::gpu::tone::tone_map;
use crate::gpu::{BackendChoice, Gpu};
use crate::scene::Scene;
use crate::tone::ToneConfig;
pub use orbit::Orbit;

pub const HELP: &str = "mouse: left drag orbit, right drag pan, wheel zoom | W A S D fly, Q E \
down/up | arrows move the light (re-bake) | 1 full, 2 direct, 3 indirect, 4 diffuse only, \
5 lobes only | + − exposure | [ ] key | P screenshot | H help | Esc quit";

#[derive(Clone, Debug)]
pub struct ViewOptions {
    pub width: u32,
    pub height: u32,
    pub backend: BackendChoice,
    pub frame: FrameConfig,
    pub tone: ToneConfig,
    /// Scripted run: draw this many frames once the bake is in, then exit.
    pub frames: Option<u32>,
    /// Where a scripted run saves its last frame.
    pub screenshot: Option<PathBuf>,
    /// The bake cache: loaded at start when it matches the scene, else written once the first
    /// bake is in (`render --cache`'s file format).
    pub cache: Option<PathBuf>,
}

pub fn view(scene: Scene, opts: ViewOptions) -> Result<()> {
    let event_loop =
        EventLoop::new().map_err(|e| Error::Gpu(format!("cannot open a window: {e}")))?;
    let display = event_loop.owned_display_handle();
    let mut app = App {
        scene: Arc::new(scene),
        opts,
        display,
        state: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Gpu(format!("the window's event loop failed: {e}")))?;
    app.error.map_or(Ok(()), Err)
}

struct App {
    scene: Arc<Scene>,
    opts: ViewOptions,
    display: OwnedDisplayHandle,
    state: Option<State>,
    error: Option<Error>,
}

/// Everything a drawn window holds.
struct State {
    window: Arc<Window>,
    gpu: Arc<Gpu>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    on_gpu: GpuScene,
    pipelines: SplatPipelines,
    present: PresentPipeline,
    frame_scene: FrameScene,
    lobes: LobeMap,
    targets: FrameTargets,
    orbit: Orbit,
    tone: ToneConfig,
    bake: Option<Receiver<Result<LobeMap>>>,
    bake_start: Instant,
    bake_s: Option<f64>,
    /// Frames drawn since the bake came in (scripted runs count these).
    frames_lit: u32,
    screenshots: u32,
    drag: Option<(MouseButton, (f64, f64))>,
    cursor: (f64, f64),
    frame_ms: f64,
    /// Frame times (ms) since the bake came in: a scripted run prints their median.
    lit_ms: Vec<f64>,
    /// Which light the frame shows (keys 1–5).
    show: Show,
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<State> {
        let size = PhysicalSize::new(self.opts.width, self.opts.height);
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title("lobelight")
                        .with_inner_size(size),
                )
                .map_err(|e| Error::Gpu(format!("cannot open a window: {e}")))?,
        );
        let (gpu, surface) = Gpu::for_window(self.opts.backend, &self.display, &window)?;
        let gpu = Arc::new(gpu);
        let caps = surface.get_capabilities(&gpu.adapter);
        // A plain (non-sRGB) 8-bit format takes the tone map's bytes as they are.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or(caps.formats.first().copied())
            .ok_or_else(|| Error::Gpu("the window's surface offers no format".into()))?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: inner.width.max(1),
            height: inner.height.max(1),
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
        let on_gpu = GpuScene::upload(&gpu, &self.scene)?;
        let pipelines = SplatPipelines::new(&gpu)?;
        let present = PresentPipeline::new(&gpu, format)?;
        let targets = pipelines.targets(&gpu, config.width, config.height)?;
        let cached = match &self.opts.cache {
            Some(path) => crate::cache::load(
                path,
                crate::cache::bake_key(&self.scene),
                self.scene.splats.len(),
            )?
            .ok(),
            None => None,
        };
        // A cached bake is in from the first frame; else direct light until the bake is.
        let (receive, bake_s) = match cached {
            Some(_) => (None, Some(0.0)),
            None => {
                let save = self.opts.cache.clone();
                (Some(spawn_bake(&gpu, &self.scene, save)), None)
            }
        };
        let lobes = cached.unwrap_or_default();
        let frame_scene = FrameScene::upload(&gpu, &self.scene, &lobes)?;
        eprintln!("{HELP}");
        Ok(State {
            window,
            gpu,
            surface,
            config,
            on_gpu,
            pipelines,
            present,
            frame_scene,
            lobes,
            targets,
            orbit: Orbit::new(&self.scene.camera),
            tone: self.opts.tone,
            bake: receive,
            bake_start: Instant::now(),
            bake_s,
            frames_lit: 0,
            screenshots: 0,
            drag: None,
            cursor: (0.0, 0.0),
            frame_ms: 0.0,
            lit_ms: Vec::new(),
            show: Show::ALL
                .into_iter()
                .find(|s| s.mask() == self.opts.frame.show)
                .unwrap_or_default(),
        })
    }
}

impl State {
    /// Takes the bake's result when it has come in.
    fn poll_bake(&mut self, scene: &Scene) -> Result<()> {
        let Some(rx) = &self.bake else {
            return Ok(());
        };
        match rx.try_recv() {
            Ok(lobes) => {
                self.lobes = lobes?;
                self.frame_scene = FrameScene::upload(&self.gpu, scene, &self.lobes)?;
                self.bake = None;
                self.bake_s = Some(self.bake_start.elapsed().as_secs_f64());
            }
            Err(TryRecvError::Empty) => {}
            Err(TryRecvError::Disconnected) => {
                return Err(Error::Gpu("the bake stopped without a result".into()));
            }
        }
        Ok(())
    }

    fn resize(&mut self, size: PhysicalSize<u32>) -> Result<()> {
        if size.width == 0 || size.height == 0 {
            return Ok(()); // minimised: nothing to draw into
        }
        self.config.width = size.width;
        self.config.height = size.height;
        self.surface.configure(&self.gpu.device, &self.config);
        self.targets = self.pipelines.targets(&self.gpu, size.width, size.height)?;
        Ok(())
    }

    /// Draws one frame; returns the tone-mapped image's buffer (for screenshots), or none
    /// when the surface could not give a texture this time.
    fn draw(&mut self, scene: &Scene, frame: &FrameConfig) -> Result<Option<wgpu::Buffer>> {
        let (w, h) = (self.config.width, self.config.height);
        if self.targets.width != w || self.targets.height != h {
            return Ok(None);
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(None);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                return Ok(None);
            }
            other => {
                return Err(Error::Gpu(format!(
                    "the window's surface failed: {other:?}"
                )));
            }
        };
        let start = Instant::now();
        let view = View::new(&self.orbit.camera(), w, h);
        let cam = camera_uniform(&view, scene.bounds(), frame);
        let frame = FrameConfig {
            show: self.show.mask(),
            ..frame.clone()
        };
        let params = shade_params(scene, &self.lobes, &frame);
        let gpu = &self.gpu;
        let mut encoder = gpu.encoder("view frame");
        let buffers = self.frame_scene.buffers(&self.on_gpu);
        self.pipelines
            .draw(gpu, &mut encoder, &buffers, &cam, &params, &self.targets)?;
        let toned = tone_map(gpu, &mut encoder, &self.targets.hdr, w * h, &self.tone)?;
        let target = texture.texture.create_view(&Default::default());
        self.present
            .record(gpu, &mut encoder, &target, &toned.rgba, (w, h));
        gpu.submit_and_wait(encoder)?;
        gpu.queue.present(texture);
        self.frame_ms = crate::photons::ms_since(start);
        Ok(Some(toned.rgba))
    }

    fn title(&self, scene: &Scene) -> String {
        let light = match self.bake_s {
            Some(s) => format!("global illumination (baked in {s:.1} s)"),
            None => format!(
                "{}; baking… {:.0} s",
                if self.lobes.light.is_empty() {
                    "direct light"
                } else {
                    "indirect light of the last bake"
                },
                self.bake_start.elapsed().as_secs_f64()
            ),
        };
        format!(
            "lobelight — {:.1} fps, {:.0} ms — {} splats, {} photons — {light} — showing {:?} — H: keys",
            1e3 / self.frame_ms.max(1e-3),
            self.frame_ms,
            scene.splats.len(),
            scene.bake.photons,
            self.show
        )
    }

    fn screenshot(&self, rgba: &wgpu::Buffer, path: &std::path::Path) -> Result<()> {
        let (w, h) = (self.config.width, self.config.height);
        let pixels = self.gpu.read::<u32>(rgba, (w * h) as usize)?;
        crate::render::write_rgba8(path, &pixels, w, h)
    }

    fn key(&mut self, key: &Key) -> Option<KeyAction> {
        let step = 0.05;
        match key {
            Key::Named(NamedKey::Escape) => return Some(KeyAction::Quit),
            Key::Named(NamedKey::ArrowLeft) => return Some(KeyAction::MoveLight(-1.0, 0.0)),
            Key::Named(NamedKey::ArrowRight) => return Some(KeyAction::MoveLight(1.0, 0.0)),
            Key::Named(NamedKey::ArrowUp) => return Some(KeyAction::MoveLight(0.0, -1.0)),
            Key::Named(NamedKey::ArrowDown) => return Some(KeyAction::MoveLight(0.0, 1.0)),
            Key::Character(c) => match c.as_str() {
                "w" | "W" => self.orbit.fly(step, 0.0, 0.0),
                "s" | "S" => self.orbit.fly(-step, 0.0, 0.0),
                "a" | "A" => self.orbit.fly(0.0, -step, 0.0),
                "d" | "D" => self.orbit.fly(0.0, step, 0.0),
                "q" | "Q" => self.orbit.fly(0.0, 0.0, -step),
                "e" | "E" => self.orbit.fly(0.0, 0.0, step),
                "+" | "=" => self.tone.exposure += 0.5,
                "-" => self.tone.exposure -= 0.5,
                "[" => self.tone.key = (self.tone.key / 1.25).max(0.01),
                "]" => self.tone.key = (self.tone.key * 1.25).min(1.0),
                "p" | "P" => return Some(KeyAction::Screenshot),
                "1" | "2" | "3" | "4" | "5" => {
                    let k = c.as_str().parse::<usize>().unwrap_or(1) - 1;
                    let show = Show::ALL[k.min(Show::ALL.len() - 1)];
                    self.show = show;
                }
                "h" | "H" => eprintln!("{HELP}"),
                _ => {}
            },
            _ => {}
        }
        None
    }
}

/// Bakes `scene` on a second thread on the same device, beside the frames, and saves the
/// result to `cache` when given.
fn spawn_bake(
    gpu: &Arc<Gpu>,
    scene: &Arc<Scene>,
    cache: Option<PathBuf>,
) -> Receiver<Result<LobeMap>> {
    let (send, receive) = channel();
    let (gpu, scene) = (gpu.clone(), scene.clone());
    std::thread::spawn(move || {
        let baked = GpuScene::upload(&gpu, &scene).and_then(|on_gpu| {
            let device = BakeDevice::Gpu(&gpu, &on_gpu);
            let lobes = bake(&scene, device, &Progress::new(false))?.lobes;
            if let Some(path) = cache {
                crate::cache::save(&path, crate::cache::bake_key(&scene), &lobes)?;
            }
            Ok(lobes)
        });
        // The window may be gone, or a newer bake started: nothing need wait for this one.
        let _ = send.send(baked);
    });
    receive
}

/// How far an arrow key moves the first light, as a fraction of the scene's size.
const LIGHT_STEP: f32 = 0.05;

enum KeyAction {
    Quit,
    Screenshot,
    /// Move the first light by (x, z) steps and bake again.
    MoveLight(f32, f32),
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let scene = self.scene.clone();
        let Some(state) = self.state.as_mut() else {
            return Ok(());
        };
        state.poll_bake(&scene)?;
        let scripted = self.opts.frames.is_some();
        // A scripted run waits for the bake: its frames are meant to show the full light.
        if scripted && state.bake.is_some() {
            std::thread::sleep(std::time::Duration::from_millis(20));
            state.window.request_redraw();
            return Ok(());
        }
        let Some(rgba) = state.draw(&scene, &self.opts.frame)? else {
            state.window.request_redraw();
            return Ok(());
        };
        if state.bake.is_none() {
            state.frames_lit += 1;
            state.lit_ms.push(state.frame_ms);
        }
        state.window.set_title(&state.title(&scene));
        if let Some(n) = self.opts.frames
            && state.frames_lit >= n
        {
            if let Some(path) = &self.opts.screenshot {
                state.screenshot(&rgba, path)?;
                eprintln!("wrote {}", path.display());
            }
            let mut ms = state.lit_ms.clone();
            ms.sort_by(f64::total_cmp);
            eprintln!(
                "{} frames of {}×{} in the window: median {:.1} ms (frame, tone map and \
                 present); bake {:.1} s",
                ms.len(),
                state.config.width,
                state.config.height,
                ms.get(ms.len() / 2).copied().unwrap_or(0.0),
                state.bake_s.unwrap_or(0.0)
            );
            event_loop.exit();
            return Ok(());
        }
        state.window.request_redraw();
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(state) => {
                state.window.request_redraw();
                self.state = Some(state);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            other => self.input(event_loop, other),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }
}

impl App {
    fn input(&mut self, event_loop: &ActiveEventLoop, event: WindowEvent) -> Result<()> {
        let Some(state) = self.state.as_mut() else {
            return Ok(());
        };
        match event {
            WindowEvent::Resized(size) => state.resize(size)?,
            WindowEvent::MouseInput {
                state: pressed,
                button,
                ..
            } => {
                state.drag = (pressed == ElementState::Pressed).then_some((button, state.cursor));
            }
            WindowEvent::CursorMoved { position, .. } => {
                state.cursor = (position.x, position.y);
                if let Some((button, from)) = state.drag {
                    let (dx, dy) = ((position.x - from.0) as f32, (position.y - from.1) as f32);
                    match button {
                        MouseButton::Left => state.orbit.turn(dx, dy),
                        _ => state.orbit.pan(dx, dy),
                    }
                    state.drag = Some((button, state.cursor));
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                state.orbit.zoom(lines);
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                match state.key(&event.logical_key) {
                    Some(KeyAction::Quit) => event_loop.exit(),
                    Some(KeyAction::Screenshot) => {
                        state.screenshots += 1;
                        let path = PathBuf::from(format!("lobelight-{}.png", state.screenshots));
                        // The next frame's image is the one on screen after this key.
                        if let Some(rgba) = state.draw(&self.scene, &self.opts.frame)? {
                            state.screenshot(&rgba, &path)?;
                            eprintln!("wrote {}", path.display());
                        }
                    }
                    Some(KeyAction::MoveLight(dx, dz)) => {
                        let Some(first) = self.scene.lights.first() else {
                            return Ok(());
                        };
                        let (lo, hi) = self.scene.bounds();
                        let step = LIGHT_STEP * (hi - lo).max_element();
                        let mut moved = (*self.scene).clone();
                        let mut light = *first;
                        light.position[0] += dx * step;
                        light.position[2] += dz * step;
                        moved.lights[0] = light;
                        self.scene = Arc::new(moved);
                        // Direct light follows at once; the indirect light with the new bake
                        // (a bake still running for the old position is left to finish unheard).
                        state.frame_scene =
                            FrameScene::upload(&state.gpu, &self.scene, &state.lobes)?;
                        state.bake = Some(spawn_bake(&state.gpu, &self.scene, None));
                        state.bake_start = Instant::now();
                        state.bake_s = None;
                    }
                    None => {}
                }
            }
            _ => {}
        }
        Ok(())
    }
}
