//! `lobelight bench …`: throughput with the figures that say whether the work was right.

use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::bake::{self, Progress, SceneBuffers, bin_traced, deposit_traced};
use crate::camera::View;
use crate::cli::compare::difference;
use crate::cli::measure::median;
use crate::cli::render::Method;
use crate::cli::view::{ViewOptions, ViewReport};
use crate::em::{EmConfig, EmStats, LobeFamily, LobeMap};
use crate::error::Result;
use crate::frame::{FrameConfig, Splatting};

use crate::photons::{PhotonConfig, PhotonMap, PhotonStats, photons_within};
use crate::plan::{BakeLimits, BakePlan};
use crate::renderer::BackendChoice;
use crate::renderer::{Engine, Renderer, SceneWork, upsample};
use crate::scene::Scene;
use crate::sequence::Executor;
use crate::timing::ms_since;
use crate::tone::ToneConfig;
use crate::types::PresentParams;

#[derive(Debug, Serialize)]
pub struct PhotonBench {
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    /// Emitted photons per second of the trace stage (emission, tracing, storing, readbacks).
    pub photons_per_s: f64,
    pub emitted: u64,
    pub stored: u64,
    pub stored_ratio: f64,
    pub search_radius: f32,
    /// Mean number of stored photons within the search radius of a splat's centre.
    pub photons_per_splat: f64,
    pub stats: PhotonStats,
    pub stages: PhotonStages,
}

#[derive(Debug, Serialize)]
pub struct PhotonStages {
    pub grid_ms: f64,
    pub trace_ms: f64,
    pub download_ms: f64,
}

/// Traces the scene's photons once on `engine`. A small warm-up trace first compiles a
/// device's pipelines, and is not timed.
pub fn photons(scene: &Arc<Scene>, engine: &Engine, cfg: &PhotonConfig) -> Result<PhotonBench> {
    let renderer = Renderer::new(scene.clone(), engine)?;
    let warm = PhotonConfig {
        photons: cfg.photons.min(4096),
        ..cfg.clone()
    };
    renderer.trace_photons(&warm, &mut |_, _| {})?;
    let traced = renderer.trace_photons(cfg, &mut |_, _| {})?;
    Ok(summarise(
        scene,
        traced.map,
        renderer.grid_ms(),
        traced.download_ms,
        engine.adapter_and_threads(),
        engine.backend().to_string(),
    ))
}

fn summarise(
    scene: &Scene,
    map: PhotonMap,
    grid_ms: f64,
    download_ms: f64,
    adapter: String,
    backend: String,
) -> PhotonBench {
    let radius = scene.search_radius();
    let within = photons_within(&scene.splats, &map.photons, radius);
    let per_splat = within.iter().map(|&n| n as f64).sum::<f64>() / within.len().max(1) as f64;
    let s = map.stats;
    PhotonBench {
        scene: scene.path.display().to_string(),
        adapter,
        backend,
        splats: scene.splats.len(),
        photons_per_s: s.emitted as f64 / (s.trace_ms / 1e3),
        emitted: s.emitted,
        stored: s.stored,
        stored_ratio: s.stored_ratio(),
        search_radius: radius,
        photons_per_splat: per_splat,
        stages: PhotonStages {
            grid_ms,
            trace_ms: s.trace_ms,
            download_ms,
        },
        stats: s,
    }
}

impl std::fmt::Display for PhotonBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "scene        {}", self.scene)?;
        writeln!(f, "device       {} ({})", self.adapter, self.backend)?;
        writeln!(f, "splats       {}", self.splats)?;
        writeln!(
            f,
            "photons      {} emitted, {} stored ({:.1} %), {:.0} per splat within R = {}",
            self.emitted,
            self.stored,
            100.0 * self.stored_ratio,
            self.photons_per_splat,
            self.search_radius
        )?;
        writeln!(
            f,
            "paths        {} escaped, {} absorbed, {} at max depth, {} aborted",
            self.stats.escaped, self.stats.absorbed, self.stats.depth_capped, self.stats.aborted
        )?;
        writeln!(
            f,
            "store        {} batches, {} reruns after growth, {} pages",
            self.stats.batches, self.stats.reruns, self.stats.pages
        )?;
        writeln!(
            f,
            "time         grid {:.1} ms, trace {:.1} ms, download {:.1} ms",
            self.stages.grid_ms, self.stages.trace_ms, self.stages.download_ms
        )?;
        write!(
            f,
            "throughput   {:.3} M photons/s",
            self.photons_per_s / 1e6
        )
    }
}

/// `bench em`: the lobe fit over every splat with photons (glossy or not, as the thesis
/// timed it), its throughput and its fit error.
#[derive(Debug, Serialize)]
pub struct EmBench {
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    pub family: LobeFamily,
    pub lobes: u32,
    pub iterations: u32,
    pub sparse: bool,
    pub search_radius: f32,
    pub stored: u64,
    /// Splats fitted per second of the EM stage (selection, fit and its dispatches).
    pub fits_per_s: f64,
    pub em_ms: f64,
    pub binning_ms: f64,
    /// The photons' deposits (`deposit_add`, `deposit_list`, their binning), where the fit
    /// a render runs reads them (`skipping`, `pruning`); like the binning, not in `em_ms`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deposits_ms: Option<f64>,
    pub photons_ms: f64,
    pub splats_fitted: u32,
    /// Photons gathered per fitted splat (within R, front side, inside the slab).
    pub mean_photons: f64,
    /// Fit error: negative log-likelihood per unit photon weight, mean over fitted splats.
    pub nll: f64,
    pub stats: EmStats,
    /// The same fit as a render runs it, skipping what the scene does not need (EM on glossy
    /// splats only, no lobes kept when none are fitted): the saving against the above.
    pub skipping: EmSkipping,
    /// That fit (pruning as the scene says) against the same with a fixed lobe count.
    pub pruning: EmPruning,
}

#[derive(Debug, Serialize)]
pub struct EmPruning {
    pub prune: bool,
    pub em_ms: f64,
    /// Lobes kept over all fitted splats, and their fit error (as `nll`).
    pub lobes: u64,
    pub nll: f64,
    pub fixed_em_ms: f64,
    pub fixed_lobes: u64,
    pub fixed_nll: f64,
}

#[derive(Debug, Serialize)]
pub struct EmSkipping {
    pub em_ms: f64,
    /// `em_ms` by pass: selection, irradiance gather of the splats not fitted, fit.
    pub select_ms: f64,
    pub gather_ms: f64,
    pub fit_ms: f64,
    /// With final gathering: the direct bake and the rays (their fit is in `fit_ms`).
    pub final_gather_ms: f64,
    /// The direct bake's part of `final_gather_ms` (every splat's).
    pub direct_bake_ms: f64,
    pub splats_fitted: u32,
    /// Glossy splats served by another's fit (shared fits), and final gathering's rays.
    pub splats_served: u32,
    pub rays: u64,
    /// Measures of a gather disk's covered share (one a coverage group).
    pub coverages: u32,
    /// The shared fits' cell in search radii (0: none).
    pub share: f32,
    /// Bytes of lobes the bake keeps, skipping and fitting every splat.
    pub lobe_bytes: u64,
    pub lobe_bytes_fit_all: u64,
}

/// Traces and bins the scene's photons, then times the lobe fit. On a device a first fit
/// compiles the pipelines and is not timed.
pub fn em(
    scene: &Arc<Scene>,
    engine: &Engine,
    photons: &PhotonConfig,
    cfg: &EmConfig,
) -> Result<EmBench> {
    let cfg = EmConfig {
        fit_all: true,
        ..cfg.clone()
    };
    let skip_cfg = EmConfig {
        fit_all: false,
        ..cfg.clone()
    };
    let fixed_cfg = EmConfig {
        prune: false,
        ..skip_cfg.clone()
    };
    let renderer = Renderer::new(scene.clone(), engine)?;
    let fits = renderer.run(EmFitsWork {
        scene,
        photons,
        cfgs: [&cfg, &skip_cfg, &fixed_cfg],
        warm: engine.is_device(),
    })?;
    let (adapter, backend) = (engine.adapter_and_threads(), engine.backend().to_string());
    let EmFits {
        fits: [map, skipping, fixed],
        traced: traced_stats,
        binning_ms,
        deposits_ms,
    } = fits;
    let s = &map.stats;
    Ok(EmBench {
        scene: scene.path.display().to_string(),
        adapter,
        backend,
        splats: scene.splats.len(),
        family: cfg.family,
        lobes: cfg.lobes,
        iterations: cfg.iterations,
        sparse: cfg.sparse,
        search_radius: cfg.radius,
        stored: traced_stats.stored,
        fits_per_s: s.fitted as f64 / (s.ms / 1e3),
        em_ms: s.ms,
        binning_ms,
        deposits_ms,
        photons_ms: traced_stats.trace_ms,
        splats_fitted: s.fitted,
        mean_photons: map.mean_photons(),
        nll: map.nll(),
        stats: s.clone(),
        skipping: EmSkipping {
            em_ms: skipping.stats.ms,
            select_ms: skipping.stats.select_ms,
            gather_ms: skipping.stats.gather_ms,
            fit_ms: skipping.stats.fit_ms,
            final_gather_ms: skipping.stats.final_gather_ms,
            direct_bake_ms: skipping.stats.direct_bake_ms,
            splats_fitted: skipping.stats.fitted,
            splats_served: skipping.stats.served,
            rays: skipping.stats.rays,
            coverages: skipping.stats.coverages,
            share: skip_cfg.share,
            lobe_bytes: lobe_bytes(&skipping),
            lobe_bytes_fit_all: lobe_bytes(&map),
        },
        pruning: EmPruning {
            prune: cfg.prune,
            em_ms: skipping.stats.ms,
            lobes: skipping.lobes.len() as u64,
            nll: skipping.nll(),
            fixed_em_ms: fixed.stats.ms,
            fixed_lobes: fixed.lobes.len() as u64,
            fixed_nll: fixed.nll(),
        },
    })
}

/// What `em` times: the fit of every splat over the photons (the thesis's), the fit as a
/// render runs it, and that fit with a fixed lobe count; with the photons' figures and the
/// binning's and deposits' times.
struct EmFits {
    fits: [LobeMap; 3],
    traced: PhotonStats,
    binning_ms: f64,
    deposits_ms: Option<f64>,
}

/// `em`'s work on the renderer's engine: traces, bins, deposits where the fit as rendered
/// reads deposits, and fits with each of `cfgs` (every splat over the photons; as rendered; as
/// rendered with a fixed lobe count) on one executor. With `warm`, fits of one iteration
/// compile the pipelines first.
struct EmFitsWork<'a> {
    scene: &'a Scene,
    photons: &'a PhotonConfig,
    cfgs: [&'a EmConfig; 3],
    warm: bool,
}

impl SceneWork for EmFitsWork<'_> {
    type Out = EmFits;

    fn run<E: Executor>(
        self,
        ex: &mut E,
        on: &SceneBuffers<E::Buffer>,
        limits: &BakeLimits,
    ) -> Result<EmFits> {
        let [_, rendered, _] = self.cfgs;
        let plan = BakePlan::of(self.scene, self.photons.clone(), rendered.clone(), *limits)?;
        em_fits(ex, self.scene, &plan, on, self.cfgs, self.warm)
    }
}

/// `EmFitsWork` within its plan.
fn em_fits<E: Executor>(
    ex: &mut E,
    scene: &Scene,
    plan: &BakePlan,
    on: &SceneBuffers<E::Buffer>,
    [all, rendered, fixed]: [&EmConfig; 3],
    warm: bool,
) -> Result<EmFits> {
    let quiet = Progress::new(false);
    let traced = bake::trace(ex, plan, on, &quiet)?;
    let binned = bin_traced(ex, plan, on, &traced, &quiet)?;
    let deposits = match plan.deposits {
        Some(_) => Some(deposit_traced(ex, plan, on, &traced, &quiet)?),
        None => None,
    };
    let stats = traced.stats.clone();
    drop(traced);
    // The fit of every splat reads the photons; the render's fits read what its estimate reads.
    let fit = |ex: &mut E, em: &EmConfig, as_rendered: bool| {
        let input = match (&deposits, as_rendered) {
            (Some((d, _)), true) => (&d.bins, Some(d)),
            _ => (&binned.bins, None),
        };
        // The fit of every splat is the thesis's, each splat its own (the plan's groups hold
        // the glossy splats alone).
        let plan = BakePlan {
            em: em.clone(),
            groups: plan.groups.clone().filter(|_| !em.fit_all),
            ..plan.clone()
        };
        Ok(bake::fit(ex, scene, &plan, on, input, &quiet)?.0)
    };
    if warm {
        let once = |em: &EmConfig| EmConfig {
            iterations: 1,
            ..em.clone()
        };
        fit(ex, &once(all), false)?;
        fit(ex, &once(rendered), true)?;
    }
    Ok(EmFits {
        fits: [
            fit(ex, all, false)?,
            fit(ex, rendered, true)?,
            fit(ex, fixed, true)?,
        ],
        traced: stats,
        binning_ms: binned.binning.ms.unwrap_or_default(),
        deposits_ms: deposits.and_then(|d| d.1.ms),
    })
}

fn lobe_bytes(map: &LobeMap) -> u64 {
    (map.lobes.len() * size_of::<crate::types::Lobe>()) as u64
}

impl std::fmt::Display for EmBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "scene        {}", self.scene)?;
        writeln!(f, "device       {} ({})", self.adapter, self.backend)?;
        writeln!(
            f,
            "fit          {:?}, {} lobes, {} iterations{}, R = {}",
            self.family,
            self.lobes,
            self.iterations,
            if self.sparse { ", sparse" } else { "" },
            self.search_radius
        )?;
        writeln!(
            f,
            "splats       {} of {} fitted, {:.1} photons each (most candidates {})",
            self.splats_fitted, self.splats, self.mean_photons, self.stats.max_candidates
        )?;
        writeln!(
            f,
            "time         photons {:.1} ms ({} stored), binning {:.1} ms, EM {:.1} ms in {} dispatches",
            self.photons_ms, self.stored, self.binning_ms, self.em_ms, self.stats.dispatches
        )?;
        writeln!(f, "fit error    {:.4} nats per unit weight", self.nll)?;
        writeln!(f, "throughput   {:.0} fits/s", self.fits_per_s)?;
        let k = &self.skipping;
        write!(
            f,
            "skipping     EM {:.1} ms on {} glossy splats (all: {:.1} ms), lobes kept {:.1} MB \
             (all: {:.1} MB)",
            k.em_ms,
            k.splats_fitted,
            self.em_ms,
            k.lobe_bytes as f64 / 1e6,
            k.lobe_bytes_fit_all as f64 / 1e6
        )?;
        if k.share > 0.0 {
            write!(
                f,
                "\nshared fits  cells of {} R: {} fits serve {} more glossy splats, {} rays \
                 (rays {:.1} ms with the direct bake's {:.1} ms, fit {:.1} ms)",
                k.share,
                k.splats_fitted,
                k.splats_served,
                k.rays,
                k.final_gather_ms,
                k.direct_bake_ms,
                k.fit_ms
            )?;
        }
        let p = &self.pruning;
        write!(
            f,
            "\npruning      {}: {} lobes, EM {:.1} ms, fit error {:.4} (fixed count: {} lobes, \
             {:.1} ms, {:.4})",
            if p.prune { "on" } else { "off" },
            p.lobes,
            p.em_ms,
            p.nll,
            p.fixed_lobes,
            p.fixed_em_ms,
            p.fixed_nll
        )
    }
}

/// `bench frame`: the time of one frame (splat passes, shading, tone mapping) of a baked
/// scene at each size, the bake done once beforehand as the viewer does.
#[derive(Debug, Serialize)]
pub struct FrameBench {
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    /// Splats with lobes (glossy, with photons): the ones whose fragments evaluate lobes.
    pub splats_fitted: u32,
    pub lights: usize,
    pub area_samples: u32,
    /// Where the timed frames' direct light came from: "baked" or "rays" (`--direct`).
    pub direct: &'static str,
    /// How splats became pixels: "raster" (the visibility and attribute render passes) or
    /// "compute" (the compute splatter; `passes_ms` are then its tile binning, its tile pass
    /// and shade).
    pub splatter: &'static str,
    /// The moving frames' level of detail, in pixels (`--lod`; 0: every splat drawn).
    pub lod: f32,
    /// Glossy rays a pixel and refinement frame (`--glossy-rays`; 0: the lobes).
    pub glossy_rays: u32,
    /// Baked direct light: the direct bake of the lights, once before the frames (what a moved
    /// light costs before its indirect bake).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direct_bake_ms: Option<f64>,
    /// `frame_ms` at the first size (512²), for scripts that want one number.
    pub frame_ms: f64,
    pub sizes: Vec<FrameTiming>,
    /// GPU, at the first size: the still image a resting camera refines to, and how far the
    /// moving frame is from it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<RefinementTiming>,
    /// `--window`: frames drawn in a 1280×720 window by the viewer, swap chain included.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<ViewReport>,
    /// `--window`: a scripted orbit in the window with the viewer's target frame time
    /// (`--target-ms`), every frame a moving frame, and how far its frames are from the still
    /// images of their views.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_orbit: Option<WindowOrbit>,
    /// GPU: the moving frames of a scripted orbit against the still images of their views
    /// (`--orbit FRAMES`, 0: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orbit: Option<OrbitAccuracy>,
}

/// How far the moving frames of an orbit are from the still images of their views.
#[derive(Debug, Serialize)]
pub struct OrbitAccuracy {
    pub frames: u32,
    /// Degrees the scene's camera turns a frame, about its up axis through its target.
    pub degrees_per_frame: f32,
    pub width: u32,
    pub height: u32,
    /// Refinement frames of each view's still image.
    pub spp: u32,
    /// Median over the orbit of each moving frame's relMSE against its view's still image:
    /// with the temporal pass (`--taa`; the history carried from frame to frame as in the
    /// viewer), and each frame drawn alone.
    pub median_rel_mse: f64,
    pub median_rel_mse_alone: f64,
    /// Each frame's, in order.
    pub rel_mse: Vec<f64>,
    pub rel_mse_alone: Vec<f64>,
}

/// The window's orbit with a target frame time: what the viewer measured, and each checked
/// frame (drawn again offscreen at the size the window drew it, upsampled with the present
/// pass's weights) against the still image of its view at the window's size.
#[derive(Debug, Serialize)]
pub struct WindowOrbit {
    #[serde(flatten)]
    pub window: ViewReport,
    /// The frames checked, their relMSE, and its median.
    pub checked: Vec<u32>,
    pub rel_mse: Vec<f64>,
    pub median_rel_mse: f64,
    /// The frames the controller settled on: those after its last step at the size and level
    /// of detail of the last frame (the first there left out: it makes its targets), and
    /// their median time and rate.
    pub settled_frames: u32,
    pub settled_ms: f64,
    pub settled_fps: f64,
}

/// The times of the orbit's frames drawn at the last frame's size and level of detail, after
/// the first of them.
fn settled_times(w: &ViewReport) -> Vec<f64> {
    let rung = |k: usize| (w.drawn.get(k).copied(), w.lod.get(k).copied());
    let last = w.frames_ms.len().saturating_sub(1);
    let first = (0..=last)
        .rev()
        .take_while(|&k| rung(k) == rung(last))
        .last()
        .unwrap_or(0);
    w.frames_ms.iter().skip(first + 1).copied().collect()
}

/// `bench frame`'s orbit: frames, size and turn a frame.
pub const ORBIT_FRAMES: u32 = 30;
const ORBIT_SIZE: (u32, u32) = (256, 256);
const ORBIT_DEGREES_PER_FRAME: f32 = 0.5;

/// The still image of `view` (`REFINEMENT_SPP` refinement frames, timed one by one) against
/// the moving frame drawn alone.
fn refine(renderer: &mut Renderer, view: &View, cfg: &FrameConfig) -> Result<RefinementTiming> {
    // A moving frame alone (no temporal history), whatever `cfg.temporal` says.
    renderer.draw(view, cfg, 0, |_| {})?;
    let moving = renderer.read_hdr()?;
    let mut ms = Vec::new();
    let mut last = Instant::now();
    renderer.draw(view, cfg, REFINEMENT_SPP, |_| {
        ms.push(ms_since(last));
        last = Instant::now();
    })?;
    let still = renderer.read_hdr()?;
    Ok(RefinementTiming {
        spp: REFINEMENT_SPP,
        frame_ms: median(ms),
        moving_rel_mse: difference(&moving, &still)?.rel_mse,
    })
}

/// Draws `frames` moving frames of the scene's camera turning about its up axis, with the
/// temporal pass (its history carried from frame to frame as in the viewer) and alone, each
/// compared with its view's still image (`REFINEMENT_SPP` refinement frames).
fn orbit(renderer: &mut Renderer, cfg: &FrameConfig, frames: u32) -> Result<OrbitAccuracy> {
    let scene = renderer.scene().clone();
    let (w, h) = ORBIT_SIZE;
    let axis = glam::Vec3::from(scene.camera.up);
    let temporal = FrameConfig {
        temporal: true,
        ..cfg.clone()
    };
    let (mut rel_mse, mut rel_mse_alone) = (Vec::new(), Vec::new());
    for k in 0..frames {
        let turn = ORBIT_DEGREES_PER_FRAME * k as f32;
        let view = View::new(
            &crate::scene::views::turned(&scene.camera, axis, turn),
            w,
            h,
        );
        renderer.draw_moving(&view, &temporal)?;
        let moving = renderer.read_hdr()?;
        // `draw` draws the frame alone, whatever `cfg.temporal` says.
        renderer.draw(&view, cfg, 0, |_| {})?;
        let single = renderer.read_hdr()?;
        renderer.draw(&view, cfg, REFINEMENT_SPP, |_| {})?;
        let still = renderer.read_hdr()?;
        rel_mse.push(difference(&moving, &still)?.rel_mse);
        rel_mse_alone.push(difference(&single, &still)?.rel_mse);
    }
    Ok(OrbitAccuracy {
        frames,
        degrees_per_frame: ORBIT_DEGREES_PER_FRAME,
        width: w,
        height: h,
        spp: REFINEMENT_SPP,
        median_rel_mse: median(rel_mse.clone()),
        median_rel_mse_alone: median(rel_mse_alone.clone()),
        rel_mse,
        rel_mse_alone,
    })
}

#[derive(Debug, Serialize)]
pub struct FrameTiming {
    pub width: u32,
    pub height: u32,
    /// Median over the timed frames of shade + tone map.
    pub frame_ms: f64,
    pub fps: f64,
    /// Medians of the two parts: the splat passes with shading (and the temporal pass), and
    /// tone mapping.
    pub shade_ms: f64,
    pub tonemap_ms: f64,
    /// GPU: medians of the visibility, attribute and shade passes, each waited for (with baked
    /// direct light the attribute pass includes `splat_shade` before it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub passes_ms: Option<[f64; 3]>,
    /// GPU: median of the temporal pass (`--taa`; 0 without), waited for apart.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temporal_ms: Option<f64>,
    /// GPU: median of the present pass (the tone-mapped bytes drawn onto a window-format
    /// BGRA8 texture of this size), apart from `frame_ms`; what a window adds to a frame
    /// besides the swap chain itself.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub present_ms: Option<f64>,
    pub frames: u32,
}

#[derive(Debug, Serialize)]
pub struct RefinementTiming {
    /// Refinement frames the still image averages.
    pub spp: u32,
    /// Median milliseconds of one refinement frame (jittered, shadow rays), tone map apart.
    pub frame_ms: f64,
    /// relMSE against the still image of a moving frame drawn alone (no temporal history:
    /// the first frame of a motion; the orbit's figures are the frames that follow).
    pub moving_rel_mse: f64,
}

/// Refinement frames of `bench frame`'s still image.
pub const REFINEMENT_SPP: u32 = 32;

/// The sizes `bench frame` times: a square, the viewer's window and full HD.
pub const FRAME_SIZES: [(u32, u32); 3] = [(512, 512), (1280, 720), (1920, 1080)];
const TIMED_FRAMES: u32 = 5;

/// Bakes the scene once, then times frames at each of `FRAME_SIZES` (one untimed warm-up
/// frame per size compiles the pipelines and allocates the targets). On a device each pass is
/// waited for apart, the present pass is timed onto a window-format texture, and the still
/// image, the orbit and the window's orbit are checked.
pub fn frame(
    scene: &Arc<Scene>,
    engine: &Engine,
    (cfg, tone): (&FrameConfig, &ToneConfig),
    orbit_frames: u32,
    window_orbit: Option<ViewReport>,
) -> Result<FrameBench> {
    cfg.validate()?;
    let mut renderer = Renderer::new(scene.clone(), engine)?;
    renderer.bake(&Progress::new(false))?;
    let fitted = renderer.lobes().stats.fitted;
    let direct_bake_ms = match cfg.needs_direct_bake() {
        true => Some(renderer.bake_direct()?),
        false => None,
    };
    let splatter = match renderer.splatting(cfg)? {
        Splatting::Compute => "compute",
        Splatting::Raster => "raster",
    };
    let mut sizes = Vec::new();
    let mut refinement = None;
    for (w, h) in FRAME_SIZES {
        let view = View::new(&scene.camera, w, h);
        let window = renderer.offscreen_target((w, h))?;
        let (mut times, mut pass_ms, mut present_ms) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..=TIMED_FRAMES {
            let t = Instant::now();
            let passes = renderer.draw_timed(&view, cfg)?;
            // The device's passes each waited for; the mirror's frame as a whole.
            let shade = passes.map_or_else(|| ms_since(t), |p| p.iter().sum());
            pass_ms.extend(passes);
            let t = Instant::now();
            renderer.tone(tone)?;
            times.push((shade, ms_since(t)));
            if let Some(window) = &window {
                let t = Instant::now();
                renderer.present(window)?;
                present_ms.push(ms_since(t));
            }
        }
        let mut t = timing(w, h, &times[1..]);
        if let [_, timed @ ..] = &pass_ms[..] {
            t.passes_ms = Some(std::array::from_fn(|k| {
                median(timed.iter().map(|p| p[k]).collect())
            }));
            t.temporal_ms = Some(median(timed.iter().map(|p| p[3]).collect()));
        }
        if let [_, timed @ ..] = &present_ms[..] {
            t.present_ms = Some(median(timed.to_vec()));
        }
        sizes.push(t);
        if refinement.is_none() && engine.is_device() {
            refinement = Some(refine(&mut renderer, &view, cfg)?);
        }
    }
    let (mut orbit_accuracy, mut window_checked) = (None, None);
    if engine.is_device() && orbit_frames > 0 {
        orbit_accuracy = Some(orbit(&mut renderer, cfg, orbit_frames)?);
    }
    if let Some(w) = window_orbit.filter(|_| engine.is_device()) {
        window_checked = Some(check_window_orbit(&mut renderer, cfg, w)?);
    }
    let (adapter, backend) = (engine.adapter_and_threads(), engine.backend().to_string());
    Ok(FrameBench {
        scene: scene.path.display().to_string(),
        adapter,
        backend,
        splats: scene.splats.len(),
        splats_fitted: fitted,
        lights: scene.lights.len(),
        area_samples: cfg.area_samples,
        direct: cfg.direct.name(),
        splatter,
        lod: cfg.lod,
        glossy_rays: cfg.glossy_rays,
        direct_bake_ms,
        frame_ms: sizes[0].frame_ms,
        sizes,
        refinement,
        window: None,
        window_orbit: window_checked,
        orbit: orbit_accuracy,
    })
}

/// Frames `bench frame --window` draws in the window (after the bake).
pub const WINDOW_FRAMES: u32 = 10;
/// The window's size.
pub const WINDOW_SIZE: (u32, u32) = (1280, 720);

/// The window orbit's frames and turn a frame (`bench frame`'s orbit's).
pub const WINDOW_ORBIT_FRAMES: u32 = ORBIT_FRAMES;
/// Every this many frames one is checked against its still image (the last of each run, when
/// the internal resolution has settled).
const WINDOW_ORBIT_CHECK: u32 = 10;

/// Opens the viewer on `scene` at `WINDOW_SIZE`, bakes, draws and closes: the frames' times
/// with the window's swap chain, and the sizes the viewer drew them at. Without a target,
/// `WINDOW_FRAMES` moving frames of the scene's camera at the window's size; with `target_ms`
/// (the viewer's `--target-ms`), an orbit of `WINDOW_ORBIT_FRAMES` frames turning
/// `ORBIT_DEGREES_PER_FRAME` a frame.
pub fn window_frames(
    scene: &Scene,
    frame: FrameConfig,
    tone: ToneConfig,
    backend: BackendChoice,
    target_ms: Option<f64>,
) -> Result<ViewReport> {
    let (frames, turn) = match target_ms {
        Some(_) => (WINDOW_ORBIT_FRAMES, ORBIT_DEGREES_PER_FRAME),
        None => (WINDOW_FRAMES, 0.0),
    };
    let opts = ViewOptions {
        width: WINDOW_SIZE.0,
        height: WINDOW_SIZE.1,
        backend,
        frame,
        tone,
        method: Method::Lobes,
        frames: Some(frames),
        // Every frame a moving frame: what a camera in motion gets.
        spp: 0,
        screenshot: None,
        cache: None,
        // The frames are measured; the bake only has to come in.
        gpu_bake: false,
        target_ms: target_ms.unwrap_or(0.0),
        turn,
    };
    crate::cli::view::view(scene.clone(), opts)
}

/// Draws the window orbit's frames again offscreen, each at the size and level of detail the
/// window drew it (with the temporal pass's history where `cfg` has it), and checks every
/// `WINDOW_ORBIT_CHECK`-th, upsampled to the window's size as the present pass does, against
/// the still image of its view (`REFINEMENT_SPP` refinement frames at the window's size).
fn check_window_orbit(
    renderer: &mut Renderer,
    cfg: &FrameConfig,
    window: ViewReport,
) -> Result<WindowOrbit> {
    let scene = renderer.scene().clone();
    let axis = glam::Vec3::from(scene.camera.up);
    let size = (window.width, window.height);
    let camera = |k: u32| {
        let turn = window.degrees_per_frame * k as f32;
        crate::scene::views::turned(&scene.camera, axis, turn)
    };
    let checked: Vec<u32> = (0..window.frames)
        .filter(|k| k % WINDOW_ORBIT_CHECK == WINDOW_ORBIT_CHECK - 1)
        .collect();
    // The moving frames first, all of them in order (a still image between two would reset
    // the temporal history), keeping the checked ones upsampled.
    let mut shown = Vec::new();
    for (k, drawn) in window.drawn.iter().enumerate() {
        let view = View::new(&camera(k as u32), drawn[0], drawn[1]);
        let moving = FrameConfig {
            lod: window.lod.get(k).copied().unwrap_or(cfg.lod),
            ..cfg.clone()
        };
        renderer.draw_moving(&view, &moving)?;
        if checked.contains(&(k as u32)) {
            let params = PresentParams::new((drawn[0], drawn[1]), size, false);
            shown.push(upsample(&params, &renderer.read_hdr()?));
        }
    }
    let mut rel_mse = Vec::new();
    for (&k, image) in checked.iter().zip(&shown) {
        let view = View::new(&camera(k), size.0, size.1);
        renderer.draw(&view, cfg, REFINEMENT_SPP, |_| {})?;
        rel_mse.push(difference(image, &renderer.read_hdr()?)?.rel_mse);
    }
    let settled = settled_times(&window);
    let settled_ms = median(settled.clone());
    Ok(WindowOrbit {
        window,
        checked,
        median_rel_mse: median(rel_mse.clone()),
        rel_mse,
        settled_frames: settled.len() as u32,
        settled_ms,
        settled_fps: if settled.is_empty() {
            0.0
        } else {
            1e3 / settled_ms.max(1e-9)
        },
    })
}

fn timing(width: u32, height: u32, times: &[(f64, f64)]) -> FrameTiming {
    let frame_ms = median(times.iter().map(|(a, b)| a + b).collect());
    FrameTiming {
        width,
        height,
        frame_ms,
        fps: 1e3 / frame_ms,
        shade_ms: median(times.iter().map(|t| t.0).collect()),
        tonemap_ms: median(times.iter().map(|t| t.1).collect()),
        passes_ms: None,
        temporal_ms: None,
        present_ms: None,
        frames: times.len() as u32,
    }
}

impl std::fmt::Display for FrameBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "scene        {}", self.scene)?;
        writeln!(f, "device       {} ({})", self.adapter, self.backend)?;
        writeln!(
            f,
            "splats       {} ({} with lobes), {} lights, {}² area samples",
            self.splats, self.splats_fitted, self.lights, self.area_samples
        )?;
        write!(
            f,
            "direct       {}, {} splatter, level of detail {} px, {} glossy rays",
            self.direct, self.splatter, self.lod, self.glossy_rays
        )?;
        if let Some(ms) = self.direct_bake_ms {
            write!(f, "; direct bake {ms:.1} ms")?;
        }
        writeln!(f)?;
        for (i, s) in self.sizes.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(
                f,
                "{:>4}×{:<4}    {:.1} ms/frame ({:.1} fps): shade {:.1} ms, tone map {:.1} ms",
                s.width, s.height, s.frame_ms, s.fps, s.shade_ms, s.tonemap_ms
            )?;
            if let Some([v, a, sh]) = s.passes_ms {
                write!(f, " (visibility {v:.1}, attributes {a:.1}, shade {sh:.1}")?;
                match s.temporal_ms {
                    Some(t) if t > 0.0 => write!(f, ", temporal {t:.1})")?,
                    _ => write!(f, ")")?,
                }
            }
            if let Some(p) = s.present_ms {
                write!(f, "; present {p:.1} ms")?;
            }
        }
        if let Some(r) = &self.refinement {
            write!(
                f,
                "\nrefinement   {:.1} ms/frame; the moving frame's relMSE against the {}-frame \
                 still image: {:.5}",
                r.frame_ms, r.spp, r.moving_rel_mse
            )?;
        }
        if let Some(o) = &self.orbit {
            write!(
                f,
                "\norbit        {} frames at {}×{}, {}° a frame: median relMSE against each \
                 view's still image {:.5} with --taa, {:.5} each frame alone",
                o.frames,
                o.width,
                o.height,
                o.degrees_per_frame,
                o.median_rel_mse,
                o.median_rel_mse_alone
            )?;
        }
        if let Some(w) = &self.window {
            write!(
                f,
                "\nwindow       {}×{}: {:.1} ms/frame ({:.1} fps) over {} frames, swap chain included",
                w.width,
                w.height,
                w.frame_ms,
                1e3 / w.frame_ms.max(1e-9),
                w.frames
            )?;
        }
        if let Some(o) = &self.window_orbit {
            let w = &o.window;
            let mut sizes: Vec<u32> = w.drawn.iter().map(|d| d[0]).collect();
            sizes.sort_unstable();
            let widths = match (sizes.first(), sizes.last()) {
                (Some(lo), Some(hi)) => format!("{lo}–{hi}"),
                _ => "none".to_string(),
            };
            let coarsest = w.lod.iter().copied().fold(0.0f32, f32::max);
            write!(
                f,
                "\nwindow orbit {} frames, {}° a frame, target {} ms: {:.1} ms/frame ({:.1} fps), \
                 drawn {} pixels wide, level of detail up to {:.1} px; settled {:.1} ms/frame \
                 ({:.1} fps) over its last {} frames; relMSE against each checked view's still \
                 image {:.5}",
                w.frames,
                w.degrees_per_frame,
                w.target_ms,
                w.frame_ms,
                w.fps,
                widths,
                coarsest,
                o.settled_ms,
                o.settled_fps,
                o.settled_frames,
                o.median_rel_mse
            )?;
        }
        Ok(())
    }
}
