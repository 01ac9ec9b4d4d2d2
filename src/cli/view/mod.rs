//! `lobelight view`: a winit window that draws the scene every frame through the offscreen
//! render's passes (splat passes, tone map) and one more, `present`, onto the window. The
//! window opens with direct light while the bake runs on a second thread on the same device,
//! and switches to full global illumination when the lobes arrive.
//!
//! Keys: see `HELP`. A moved light bakes again at once, a preview with an eighth of the
//! photons first (`baking`). Moving frames keep `--target-ms` by drawing at a lower internal
//! resolution (`resolution`), which the present pass upsamples. `--frames N --screenshot
//! OUT.png` draws N frames once the bake is in, saves the last and exits (scripted runs and
//! tests; `--turn` turns the camera every frame).

mod orbit;
mod resolution;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop, OwnedDisplayHandle};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::camera::View;
use crate::cli::render::Method;
use crate::error::{Error, Result};
use crate::frame::{FrameConfig, Show, Terms, camera_uniform};
use crate::renderer::{BackendChoice, BakeEngine, Baking, Renderer};
pub use crate::renderer::{PREVIEW_FRACTION, passes};
use crate::renderer::{WindowFrame, WindowSurface, shown_in_window};
use crate::scene::Scene;
use crate::tone::ToneConfig;
use crate::types::Camera;
pub use orbit::Orbit;
pub use resolution::{DEFAULT_TARGET_MS, Resolution};

pub const HELP: &str = "mouse: left drag orbit, right drag pan, wheel zoom | W A S D fly, Q E \
down/up | arrows move the light (re-bake) | 1 full, 2 direct, 3 indirect, 4 diffuse only, \
5 lobes only | R reference / lobes | M photon view | + − exposure | [ ] key | P screenshot | \
H help | Esc quit";

#[derive(Clone, Debug)]
pub struct ViewOptions {
    pub width: u32,
    pub height: u32,
    pub backend: BackendChoice,
    pub frame: FrameConfig,
    pub tone: ToneConfig,
    /// What the window shows first (keys R and M switch).
    pub method: Method,
    /// Scripted run: draw this many frames once the bake is in, then exit.
    pub frames: Option<u32>,
    /// Where a scripted run saves its last frame.
    pub screenshot: Option<PathBuf>,
    /// Refinement frames a resting camera accumulates into the still image (`render --spp`'s
    /// frames, so both give the same image); 0: every frame is a moving frame.
    pub spp: u32,
    /// The bake cache: loaded at start when it matches the scene, else written once the first
    /// bake is in (`render --cache`'s file format).
    pub cache: Option<PathBuf>,
    /// Bake on the window's device even where it is a software rasterizer (`--gpu`).
    pub gpu_bake: bool,
    /// The moving frames' target time (ms): they are drawn smaller than the window where
    /// they would take longer (0: always at the window's size).
    pub target_ms: f64,
    /// Scripted run: degrees the camera turns about its up axis before each frame after the
    /// first (0: it stays).
    pub turn: f32,
}

/// What a scripted run measured.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ViewReport {
    pub width: u32,
    pub height: u32,
    /// Frames drawn with the full bake in, and their median time (frame, tone map, present).
    pub frames: u32,
    pub frame_ms: f64,
    pub bake_s: f64,
    /// 1000 / `frame_ms`.
    pub fps: f64,
    /// `--target-ms` (0: none) and `--turn`.
    pub target_ms: f64,
    pub degrees_per_frame: f32,
    /// Each of the frames: its time (ms), and the size it was drawn at before the present
    /// pass upsampled it to the window (the window's own at rest or without a target).
    pub frames_ms: Vec<f64>,
    pub drawn: Vec<[u32; 2]>,
    /// Each frame's level of detail in pixels of the size it was drawn at: `--lod`, coarser
    /// where the target asked for it (`Resolution::lod`).
    pub lod: Vec<f32>,
}

pub fn view(scene: Scene, opts: ViewOptions) -> Result<ViewReport> {
    let event_loop =
        EventLoop::new().map_err(|e| Error::Gpu(format!("cannot open a window: {e}")))?;
    let display = event_loop.owned_display_handle();
    let mut app = App {
        scene: Arc::new(scene),
        opts,
        display,
        state: None,
        error: None,
        report: ViewReport::default(),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Gpu(format!("the window's event loop failed: {e}")))?;
    app.error.map_or(Ok(app.report), Err)
}

struct App {
    scene: Arc<Scene>,
    opts: ViewOptions,
    display: OwnedDisplayHandle,
    state: Option<State>,
    error: Option<Error>,
    report: ViewReport,
}

/// Everything a drawn window holds.
struct State {
    window: Arc<Window>,
    /// The scene on the device, the splat passes, the lobes, the last bake's photons and
    /// bins (reference and photon views), and the targets.
    renderer: Renderer,
    surface: WindowSurface,
    /// The scene's bounds (the frames' depth range), walked once.
    bounds: (glam::Vec3, glam::Vec3),
    /// Whether the lobes drawn are a preview bake's.
    preview: bool,
    orbit: Orbit,
    tone: ToneConfig,
    method: Method,
    /// Where bakes run (the device, or the CPU mirror where the device is a software
    /// rasterizer).
    engine: BakeEngine,
    /// The bake under way, and the counter that tells an older one to stop.
    baking: Option<Baking>,
    generation: Arc<AtomicU64>,
    /// How long the last full bake took (none while a bake runs).
    bake_s: Option<f64>,
    /// Frames drawn since the bake came in (scripted runs count these).
    frames_lit: u32,
    screenshots: u32,
    drag: Option<(MouseButton, (f64, f64))>,
    cursor: (f64, f64),
    frame_ms: f64,
    /// Frame times (ms) since the bake came in: a scripted run prints their median.
    lit_ms: Vec<f64>,
    /// What the last frame showed (camera, terms, method and light version): while it stays,
    /// the camera rests and frames refine the still image.
    still: Option<(Camera, Terms, Method, u64)>,
    /// Refinement frames the HDR image holds (0: a moving frame), and the most it takes.
    samples: u32,
    spp: u32,
    /// Bumped whenever new lobes or lights come in.
    version: u64,
    /// Which light the frame shows (keys 1–5).
    show: Show,
    /// The moving frames' internal resolution, and the size and level of detail the last
    /// frame was drawn at.
    resolution: Resolution,
    drawn: (u32, u32),
    drawn_lod: f32,
    /// Sizes and levels of detail of the frames since the bake came in (a scripted run
    /// reports them).
    lit_drawn: Vec<[u32; 2]>,
    lit_lod: Vec<f32>,
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
        let inner = window.inner_size();
        let size = (inner.width.max(1), inner.height.max(1));
        let scene = self.scene.clone();
        let at = (&self.display, &window);
        let (mut renderer, surface) = Renderer::for_window(scene, self.opts.backend, at, size)?;
        let cached = match &self.opts.cache {
            Some(path) => crate::cache::load(
                path,
                crate::cache::bake_key(&self.scene),
                self.scene.splats.len(),
            )?
            .ok(),
            None => None,
        };
        let generation = Arc::new(AtomicU64::new(0));
        let on_mirror = renderer.engine().is_software() && !self.opts.gpu_bake;
        if on_mirror {
            eprintln!(
                "lobelight: {} is a software rasterizer: bakes run on the CPU mirror ({} \
                 threads), faster here, and frames on it (--gpu bakes on it too)",
                renderer.engine().adapter(),
                rayon::current_num_threads()
            );
        }
        let engine = renderer.bake_engine(on_mirror)?;
        // A cached bake is in from the first frame; else direct light until the bake is.
        // The reference and photon views need the photons, which no cache holds.
        let (baking, bake_s) = match (&cached, self.opts.method) {
            (Some(_), Method::Lobes) => (None, Some(0.0)),
            _ => {
                let save = if cached.is_none() {
                    self.opts.cache.clone()
                } else {
                    None
                };
                let full = passes(&self.scene.bake, false);
                let b = renderer.spawn_bake(&engine, &self.scene, (full, save), &generation)?;
                (Some(b), None)
            }
        };
        if let Some(lobes) = cached {
            renderer.set_lobes(lobes);
        }
        eprintln!("{HELP}");
        Ok(State {
            window,
            renderer,
            surface,
            bounds: self.scene.bounds(),
            preview: false,
            orbit: Orbit::new(&self.scene.camera),
            tone: self.opts.tone,
            method: self.opts.method,
            engine,
            baking,
            generation,
            bake_s,
            frames_lit: 0,
            screenshots: 0,
            drag: None,
            cursor: (0.0, 0.0),
            frame_ms: 0.0,
            lit_ms: Vec::new(),
            still: None,
            samples: 0,
            spp: self.opts.spp,
            version: 0,
            show: Show::ALL
                .into_iter()
                .find(|s| s.terms() == self.opts.frame.show)
                .unwrap_or_default(),
            resolution: Resolution::new(self.opts.target_ms),
            drawn: size,
            drawn_lod: self.opts.frame.lod,
            lit_drawn: Vec::new(),
            lit_lod: Vec::new(),
        })
    }
}

impl State {
    /// Takes a bake pass's result when one has come in.
    fn poll_bake(&mut self) -> Result<()> {
        let Some(baking) = self.baking.as_mut() else {
            return Ok(());
        };
        let Some(result) = baking.poll()? else {
            return Ok(());
        };
        if !result.preview {
            self.baking = None;
            self.bake_s = Some(result.seconds);
            eprintln!(
                "bake: {} photons in {:.2} s",
                result.emitted, result.seconds
            );
        } else {
            eprintln!(
                "preview bake: {} photons in {:.2} s",
                result.emitted, result.seconds
            );
        }
        self.preview = result.preview;
        self.renderer.take_bake(result)?;
        self.version += 1;
        Ok(())
    }

    /// Bakes `scene` again (a moved light: a preview first) or for the photons a view needs.
    fn rebake(&mut self, scene: &Arc<Scene>, preview: bool) -> Result<()> {
        let counts = passes(&scene.bake, preview);
        let b =
            (self.renderer).spawn_bake(&self.engine, scene, (counts, None), &self.generation)?;
        self.baking = Some(b);
        self.bake_s = None;
        Ok(())
    }

    fn resize(&mut self, size: PhysicalSize<u32>) -> Result<()> {
        self.surface
            .resize(&self.renderer, (size.width, size.height));
        // Too large for this device: say so and draw nothing until the window is smaller
        // (`draw` skips frames the device cannot hold).
        if let Err(e) = self.renderer.engine().check_image(size.width, size.height) {
            eprintln!("lobelight: {e}");
        }
        Ok(())
    }

    /// Draws one frame of the chosen method and presents it; returns the size it was drawn
    /// at (a moving frame's internal resolution, else the window's), or none when the surface
    /// could not give a texture this time.
    fn draw(&mut self, frame: &FrameConfig) -> Result<Option<(u32, u32)>> {
        let (w, h) = self.surface.size();
        // A window too large for this device draws nothing until it is smaller (`resize`
        // said so).
        if self.renderer.engine().check_image(w, h).is_err() {
            return Ok(None);
        }
        let start = Instant::now();
        let frame = FrameConfig {
            show: self.show.terms(),
            ..frame.clone()
        };
        let camera = self.orbit.camera();
        let window = View::new(&camera, w, h);
        let tone = self.tone;
        let present = |s: &mut State, shown: WindowFrame| {
            s.renderer.present_frame(&mut s.surface, &shown, &tone)
        };
        let (drawn, lod) = match (self.method, self.renderer.has_photons()) {
            (Method::Photons, true) => (
                present(self, WindowFrame::Photons(&window, &frame))?,
                frame.lod,
            ),
            (Method::Reference, true) => (
                present(self, WindowFrame::Reference(&window, &frame))?,
                frame.lod,
            ),
            // The lobes, and what shows while the photons a view needs are on their way: a
            // moving frame (at the internal resolution), then refinement frames while the
            // camera rests, then the still image as it stands (at the window's size).
            _ => {
                let cam = camera_uniform(&window, self.bounds, &frame);
                let key = Some((cam, frame.show, self.method, self.version));
                // Without refinement every frame is drawn anew, as for a moving camera.
                if self.still != key || self.spp == 0 {
                    if frame.needs_direct_bake()
                        && let Some(ms) = self.renderer.ensure_direct()?
                    {
                        eprintln!("direct bake: {ms:.0} ms");
                    }
                    let (iw, ih) = self.resolution.size((w, h));
                    let moving = FrameConfig {
                        lod: self.resolution.lod(frame.lod),
                        ..frame.clone()
                    };
                    let view = View::new(&camera, iw, ih);
                    let drawn = present(self, WindowFrame::Moving(&view, &moving))?;
                    if drawn.is_some() {
                        (self.still, self.samples) = (key, 0);
                    }
                    (drawn, moving.lod)
                } else if self.samples < self.spp {
                    let sample = WindowFrame::Sample(&window, &frame, self.samples, self.spp);
                    let drawn = present(self, sample)?;
                    self.samples += u32::from(drawn.is_some());
                    (drawn, frame.lod)
                } else {
                    (present(self, WindowFrame::Again)?, frame.lod)
                }
            }
        };
        let Some(drawn) = drawn else {
            return Ok(None);
        };
        self.frame_ms = crate::timing::ms_since(start);
        (self.drawn, self.drawn_lod) = (drawn, lod);
        // Moving frames (which leave no refinement sample) keep the target; refinement
        // frames are at the window's size anyway.
        if self.samples == 0 && self.method == Method::Lobes {
            self.resolution.record(self.frame_ms);
        }
        Ok(Some(drawn))
    }

    /// The image on screen is final until something changes: the lobes' still image is
    /// complete and no bake is running.
    fn at_rest(&self) -> bool {
        self.method == Method::Lobes
            && self.spp > 0
            && self.samples >= self.spp
            && self.baking.is_none()
    }

    fn title(&self, scene: &Scene) -> String {
        let light = match (&self.baking, self.bake_s) {
            (None, Some(s)) => format!("global illumination (baked in {s:.1} s)"),
            (Some(b), _) => {
                let traced = b.traced.load(std::sync::atomic::Ordering::Relaxed);
                let total = b.photons();
                let stage = if traced < total {
                    format!(
                        "tracing {:.0} %",
                        100.0 * traced as f64 / total.max(1) as f64
                    )
                } else {
                    "fitting lobes".to_string()
                };
                format!(
                    "{}; baking {total} photons: {stage}, {:.1} s",
                    match (self.renderer.has_photons(), self.preview) {
                        (true, true) => "preview bake",
                        (true, false) => "indirect light of the last bake",
                        (false, _) => "direct light",
                    },
                    b.started.elapsed().as_secs_f64()
                )
            }
            (None, None) => "direct light".into(),
        };
        let waiting = self.method != Method::Lobes && !self.renderer.has_photons();
        let still = match (self.method, self.samples) {
            // The internal resolution (`--target-ms`) the present pass upsamples.
            (Method::Lobes, 0) if self.drawn_lod > 0.0 => format!(
                " — moving at {}×{}, level of detail {:.1} px",
                self.drawn.0, self.drawn.1, self.drawn_lod
            ),
            (Method::Lobes, 0) => format!(" — moving at {}×{}", self.drawn.0, self.drawn.1),
            (Method::Lobes, k) => format!(" — still: {k}/{} samples", self.spp),
            _ => String::new(),
        };
        format!(
            "lobelight — {:.1} fps, {:.0} ms{still} — {} splats, {} photons — {light} — {:?}{}, \
             showing {:?} — H: keys",
            1e3 / self.frame_ms.max(1e-3),
            self.frame_ms,
            scene.splats.len(),
            scene.bake.photons,
            self.method,
            if waiting { " (waits for photons)" } else { "" },
            self.show
        )
    }

    /// Saves the last tone-mapped image, drawn at `image` pixels, as the window showed it: a
    /// moving frame drawn smaller is upsampled as the present pass did (its mirror).
    fn screenshot(&self, image: (u32, u32), path: &std::path::Path) -> Result<()> {
        let toned = self.renderer.read_toned()?;
        let window = self.surface.size();
        let shown = shown_in_window(&toned.rgba, image, window);
        crate::cli::render::write_rgba8(path, &shown, window.0, window.1)
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
                "r" | "R" => return Some(KeyAction::Method(Method::Reference)),
                "m" | "M" => return Some(KeyAction::Method(Method::Photons)),
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

/// How far an arrow key moves the first light, as a fraction of the scene's size.
pub const LIGHT_STEP: f32 = 0.05;

/// `scene` with its first light moved by `(dx, dz)` steps of `LIGHT_STEP` along x and z, as
/// the arrow keys move it; none for a scene without lights.
pub fn move_first_light(scene: &Scene, dx: f32, dz: f32) -> Option<Scene> {
    let first = scene.lights.first()?;
    let (lo, hi) = scene.bounds();
    let step = LIGHT_STEP * (hi - lo).max_element();
    let mut moved = scene.clone();
    let mut light = *first;
    light.position[0] += dx * step;
    light.position[2] += dz * step;
    // Its surface's splats stay where the scene put them: the moved light reflects nothing.
    light.flags &= !crate::types::light_flags::REFLECTS;
    moved.lights[0] = light;
    Some(moved)
}

enum KeyAction {
    Quit,
    Screenshot,
    /// Show this method, or the lobes again when it is on.
    Method(Method),
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
        state.poll_bake()?;
        let scripted = self.opts.frames.is_some();
        // A scripted run waits for the bake: its frames are meant to show the full light.
        if scripted && state.baking.is_some() {
            std::thread::sleep(std::time::Duration::from_millis(20));
            state.window.request_redraw();
            return Ok(());
        }
        let Some(drawn) = state.draw(&self.opts.frame)? else {
            state.window.request_redraw();
            return Ok(());
        };
        if state.baking.is_none() {
            state.frames_lit += 1;
            state.lit_ms.push(state.frame_ms);
            state.lit_drawn.push([state.drawn.0, state.drawn.1]);
            state.lit_lod.push(state.drawn_lod);
            // A scripted orbit: the next frame's camera.
            state.orbit.spin(self.opts.turn);
        }
        state.window.set_title(&state.title(&scene));
        if let Some(n) = self.opts.frames
            && state.frames_lit >= n
        {
            if let Some(path) = &self.opts.screenshot {
                state.screenshot(drawn, path)?;
                eprintln!("wrote {}", path.display());
            }
            let frame_ms = crate::cli::measure::median(state.lit_ms.clone());
            let (width, height) = state.surface.size();
            self.report = ViewReport {
                width,
                height,
                frames: state.lit_ms.len() as u32,
                frame_ms,
                bake_s: state.bake_s.unwrap_or(0.0),
                fps: 1e3 / frame_ms.max(1e-9),
                target_ms: self.opts.target_ms,
                degrees_per_frame: self.opts.turn,
                frames_ms: state.lit_ms.clone(),
                drawn: state.lit_drawn.clone(),
                lod: state.lit_lod.clone(),
            };
            let r = &self.report;
            eprintln!(
                "{} frames of {}×{} in the window: median {:.1} ms (frame, tone map and \
                 present); bake {:.1} s",
                r.frames, r.width, r.height, r.frame_ms, r.bake_s
            );
            event_loop.exit();
            return Ok(());
        }
        // A finished still image with nothing baking waits for input instead of drawing the
        // same frame again (the event loop sleeps; `input` asks for the next frame).
        if scripted || !state.at_rest() {
            state.window.request_redraw();
        }
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
        // Whatever the event changed shows in the next frame (a resting viewer draws none
        // unasked).
        state.window.request_redraw();
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
                        if let Some(drawn) = state.draw(&self.opts.frame)? {
                            state.screenshot(drawn, &path)?;
                            eprintln!("wrote {}", path.display());
                        }
                    }
                    Some(KeyAction::Method(method)) => {
                        state.method = if state.method == method {
                            Method::Lobes
                        } else {
                            method
                        };
                        // A cached start has no photons: bake them (the lobes stay on).
                        if state.method != Method::Lobes
                            && !state.renderer.has_photons()
                            && state.baking.is_none()
                        {
                            state.rebake(&self.scene, false)?;
                        }
                    }
                    Some(KeyAction::MoveLight(dx, dz)) => {
                        let Some(moved) = move_first_light(&self.scene, dx, dz) else {
                            return Ok(());
                        };
                        self.scene = Arc::new(moved);
                        // Direct light follows at once; the indirect light with the preview
                        // bake, then the full one (a bake for the old position stops).
                        state.renderer.relight(self.scene.clone())?;
                        state.version += 1;
                        state.rebake(&self.scene, true)?;
                    }
                    None => {}
                }
            }
            _ => {}
        }
        Ok(())
    }
}
