//! The bake (docs/design.md §4–6): photons from the lights, deposited or binned, and the lobes
//! fitted to them, with a line of figures per stage. One sequence (`bake_on`), generic over
//! the executor, runs it from one plan of the scene (`BakePlan`) on the device or on the CPU
//! mirrors; `bake` and `bins_gpu` / `bins_cpu` only choose the executor. A frame needs only
//! its result, so a camera change never bakes again.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::bins::{PhotonBins, bin_params, check_binned};
use crate::cpu::{CpuBuffer, CpuExecutor};
use crate::direct::DirectMap;
use crate::em::{EmConfig, EmStats, FitShape, LobeMap};
use crate::error::{Error, Result};
use crate::fit_groups::CoverGroups;
use crate::gpu::Gpu;
use crate::gpu::exec::GpuExecutor;
use crate::gpu::renderer::FrameRenderer;
use crate::gpu::scene::GpuScene;
use crate::grid::SplatGrid;
use crate::photons::{PhotonMap, PhotonStats};
use crate::plan::{BakeLimits, BakePlan};
use crate::scene::Scene;
use crate::sequence::{
    self, Bins, CoverInput, DepositInput, Deposits, Executor, FitInput, Gathering, GroupInput,
    Traced,
};
use crate::timing::ms_since;
use crate::types::{EmParams, GridParams};

/// One stage's line of `--stats` / `--json` (docs/cli.md).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct StageReport {
    pub ran: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub emitted: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stored: Option<u64>,
    /// EM: splats whose lobes were fitted (glossy, with photons).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splats_fitted: Option<u32>,
    /// EM: splats with photons near them (their irradiance was gathered).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splats_lit: Option<u32>,
    /// EM: glossy splats served by another's fit (shared fits), besides those fitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splats_served: Option<u32>,
    /// EM: final gathering's rays.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rays: Option<u64>,
    /// EM: the direct bake final gathering's rays read, in `ms` (every splat's; the frames
    /// take it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direct_bake_ms: Option<f64>,
    /// EM: measures of a gather disk's covered share, one a coverage group (shared by the
    /// splats of a cell of R/16 that face alike).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coverages: Option<u32>,
    /// EM: splats whose photon estimate was widened (`estimate_smooth`), and of those the ones to
    /// the widest kernel.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splats_smoothed: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splats_smoothed_widest: Option<u32>,
    /// EM: lobes kept, and what the fitted splats would keep without pruning.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lobes_kept: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lobes_fitted: Option<u64>,
    /// Shade: the refinement frames the still image averages.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames: Option<u32>,
    pub skipped_reason: Option<String>,
}

impl StageReport {
    pub fn ran(ms: f64) -> StageReport {
        StageReport {
            ran: true,
            ms: Some(ms),
            ..Default::default()
        }
    }

    pub fn skipped(reason: &str) -> StageReport {
        StageReport {
            skipped_reason: Some(reason.into()),
            ..Default::default()
        }
    }
}

/// Where the bake runs: a device with the scene uploaded, or the CPU with the host grid.
#[derive(Clone, Copy)]
pub enum BakeDevice<'a> {
    Gpu(&'a Gpu, &'a GpuScene),
    Cpu(&'a SplatGrid),
}

impl BakeDevice<'_> {
    /// What this executor holds of a bake.
    pub fn limits(&self) -> BakeLimits {
        match self {
            BakeDevice::Gpu(gpu, _) => gpu.bake_limits(),
            BakeDevice::Cpu(_) => BakeLimits::host(),
        }
    }
}

pub struct Baked {
    pub lobes: LobeMap,
    /// The direct bake final gathering made (`None` where none ran, or from a cache): every
    /// splat's direct light of the scene's lights, as the frames bake it, so they take it.
    pub direct: Option<DirectMap>,
    pub photons: StageReport,
    pub binning: StageReport,
    pub em: StageReport,
}

/// Progress on stderr: a bar while photons are traced, a spinner for the other stages, and
/// one line per finished stage with its time and rate.
pub struct Progress {
    show: bool,
    /// Photons traced so far, for a reader on another thread (the viewer's title).
    traced: Option<Arc<AtomicU64>>,
}

impl Progress {
    pub fn new(show: bool) -> Progress {
        Progress { show, traced: None }
    }

    /// Whether it writes to stderr.
    pub fn shows(&self) -> bool {
        self.show
    }

    /// Quiet, but counting the photons traced into `traced`.
    pub fn counting(traced: Arc<AtomicU64>) -> Progress {
        Progress {
            show: false,
            traced: Some(traced),
        }
    }

    /// Records that `done` photons are traced.
    fn traced(&self, done: u64) {
        if let Some(t) = &self.traced {
            t.store(done, Ordering::Relaxed);
        }
    }

    /// A bar over `total` photons.
    pub fn bar(&self, total: u64) -> Bar {
        self.bar_of(total, "photons")
    }

    /// A bar over `total` things of `unit` ("frames"), with their rate and the time left.
    pub fn bar_of(&self, total: u64, unit: &str) -> Bar {
        #[cfg(feature = "progress")]
        if self.show {
            let bar = indicatif::ProgressBar::new(total);
            let template = format!(
                "{{msg:>8}} [{{bar:30}}] {{human_pos}}/{{human_len}} {unit}, {{per_sec}}, eta {{eta}}"
            );
            bar.set_style(
                indicatif::ProgressStyle::with_template(&template)
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            bar.set_message(unit.to_string());
            return Bar(Some(bar));
        }
        let _ = (total, unit);
        Bar::hidden()
    }

    fn spinner(&self, stage: &str) -> Bar {
        #[cfg(feature = "progress")]
        if self.show {
            let bar = indicatif::ProgressBar::new_spinner();
            bar.set_message(format!("{stage:>8} …"));
            bar.enable_steady_tick(std::time::Duration::from_millis(120));
            return Bar(Some(bar));
        }
        let _ = stage;
        Bar::hidden()
    }

    /// Runs `work` under a spinner named `stage`, then prints the stage's line; returns its
    /// result and its milliseconds.
    fn timed<T>(&self, stage: &str, work: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
        let spin = self.spinner(stage);
        let t = Instant::now();
        let out = work();
        let ms = ms_since(t);
        spin.finish_and_clear();
        let out = out?;
        self.done(stage, ms, "");
        Ok((out, ms))
    }

    /// Prints a finished stage's line.
    pub fn done(&self, stage: &str, ms: f64, rate: &str) {
        if self.show {
            eprintln!("{stage:>8} {:>9.1} ms  {rate}", ms);
        }
    }
}

/// A progress bar or spinner on stderr (feature `progress`); hidden when quiet.
pub struct Bar(#[cfg(feature = "progress")] Option<indicatif::ProgressBar>);

impl Bar {
    fn hidden() -> Bar {
        Bar(
            #[cfg(feature = "progress")]
            None,
        )
    }

    pub fn set_position(&self, done: u64) {
        #[cfg(feature = "progress")]
        if let Some(bar) = &self.0 {
            bar.set_position(done);
        }
        let _ = done;
    }

    pub fn finish_and_clear(&self) {
        #[cfg(feature = "progress")]
        if let Some(bar) = &self.0 {
            bar.finish_and_clear();
        }
    }
}

/// Photons traced and binned, on the device that made them (`GpuBins` or `PhotonBins`):
/// what the lobe fit and the reference renderer read.
pub struct Binned<B> {
    pub bins: B,
    /// The binning's search radius and slab (`EmConfig::params`; the reference reads them).
    pub em: EmParams,
    pub photons: StageReport,
    pub binning: StageReport,
}

/// The scene where a bake runs: its splats and their materials in the executor's buffers,
/// and the grid's box (the deposits are binned over it).
pub struct SceneBuffers<'a, B> {
    pub splats: &'a B,
    pub materials: &'a B,
    pub splat_count: u32,
    pub grid: &'a GridParams,
}

/// How far a bake goes: the photons binned (what the reference renderer reads), or the lobes
/// fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BakeTo {
    Bins,
    Lobes,
}

/// A bake where it ran: the photons traced, binned where the fit or the reference read bins
/// (a fit over deposits bins none), the lobes in host memory where they were fitted, and the
/// reports of the tracing and of the binning or deposits.
pub struct BakeRun<B> {
    pub traced: Traced<B>,
    pub binned: Option<Binned<Bins<B>>>,
    pub lobes: Option<LobeMap>,
    /// The direct bake of the fit's final gathering, in host memory.
    pub direct: Option<DirectMap>,
    pub photons: StageReport,
    pub binning: StageReport,
}

impl<B> BakeRun<B> {
    /// The lobes of a bake to the lobes.
    pub fn take_lobes(&mut self) -> Result<LobeMap> {
        self.lobes
            .take()
            .ok_or_else(|| Error::internal("a bake to the lobes came back without them"))
    }

    /// The bins of a bake to the bins.
    pub fn take_binned(&mut self) -> Result<Binned<Bins<B>>> {
        self.binned
            .take()
            .ok_or_else(|| Error::internal("a bake to the bins came back without them"))
    }

    /// What the host keeps of a bake to the lobes: the lobes, the direct bake final
    /// gathering made, and the tracing's and the binning's reports.
    fn kept(mut self) -> Result<(LobeMap, Option<DirectMap>, StageReport, StageReport)> {
        Ok((self.take_lobes()?, self.direct, self.photons, self.binning))
    }
}

/// The bake: `trace` → `deposit` or `bin` → `fit` (which bakes the direct light its final
/// gathering reads), on any executor, every figure from `plan`. Each stage ends in a split
/// point, so that its time is its own.
pub fn bake_on<E: Executor>(
    ex: &mut E,
    scene: &Scene,
    plan: &BakePlan,
    on: &SceneBuffers<E::Buffer>,
    to: BakeTo,
    progress: &Progress,
) -> Result<BakeRun<E::Buffer>> {
    let traced = trace(ex, plan, on, progress)?;
    let photons = traced_report(&traced.stats);
    if to == BakeTo::Lobes && plan.em.uses_deposits() {
        // The photons are deposited, not binned: the binning's report is the deposits'.
        let (deposits, binning) = deposit_traced(ex, plan, on, &traced, progress)?;
        let (lobes, direct) = fit(
            ex,
            scene,
            plan,
            on,
            (&deposits.bins, Some(&deposits)),
            progress,
        )?;
        return Ok(BakeRun {
            traced,
            binned: None,
            lobes: Some(lobes),
            direct,
            photons,
            binning,
        });
    }
    let binned = bin_traced(ex, plan, on, &traced, progress)?;
    let (lobes, direct) = match to {
        BakeTo::Lobes => {
            let (lobes, direct) = fit(ex, scene, plan, on, (&binned.bins, None), progress)?;
            (Some(lobes), direct)
        }
        BakeTo::Bins => (None, None),
    };
    Ok(BakeRun {
        traced,
        lobes,
        direct,
        photons,
        binning: binned.binning.clone(),
        binned: Some(binned),
    })
}

/// Runs `work` on the device's executor over `scene` as uploaded (`on_gpu`), then waits for
/// the device.
pub fn on_device<R>(
    scene: &Scene,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    work: impl FnOnce(&mut GpuExecutor, &SceneBuffers<wgpu::Buffer>) -> Result<R>,
) -> Result<R> {
    let mut encoder = gpu.encoder("bake");
    let mut ex = GpuExecutor::new(gpu, &mut encoder).tracing(on_gpu.geometry());
    let on = SceneBuffers {
        splats: &on_gpu.splats,
        materials: &on_gpu.materials,
        splat_count: splat_count(scene)?,
        grid: &on_gpu.grid.params,
    };
    let out = work(&mut ex, &on)?;
    ex.finish()?;
    Ok(out)
}

/// Runs `work` on the CPU mirrors' executor over the scene and its host `grid`.
pub fn on_mirror<R>(
    scene: &Scene,
    grid: &SplatGrid,
    work: impl FnOnce(&mut CpuExecutor, &SceneBuffers<CpuBuffer>) -> Result<R>,
) -> Result<R> {
    let mut ex = CpuExecutor::tracing(scene.geometry(grid));
    let splats = ex.upload("splats", &scene.splats)?;
    let materials = ex.upload("materials", &scene.materials)?;
    let on = SceneBuffers {
        splats: &splats,
        materials: &materials,
        splat_count: splat_count(scene)?,
        grid: &grid.params,
    };
    work(&mut ex, &on)
}

/// The scene's splat count as the stages' uniforms hold it.
fn splat_count(scene: &Scene) -> Result<u32> {
    u32::try_from(scene.splats.len())
        .map_err(|_| Error::DeviceLimit("more than 2³² splats in one scene".into()))
}

/// Traces, then deposits or bins, and fits, from one plan of the scene (`BakePlan`) on
/// `device`; the lobes come back to the host (a few bytes per splat), from where a cache file
/// or any device can take them.
pub fn bake(scene: &Scene, device: BakeDevice, progress: &Progress) -> Result<Baked> {
    let plan = BakePlan::new(scene, device.limits())?;
    let to = BakeTo::Lobes;
    let (lobes, direct, photons, binning) = match device {
        BakeDevice::Gpu(gpu, on_gpu) => on_device(scene, gpu, on_gpu, |ex, on| {
            bake_on(ex, scene, &plan, on, to, progress)?.kept()
        })?,
        BakeDevice::Cpu(grid) => on_mirror(scene, grid, |ex, on| {
            bake_on(ex, scene, &plan, on, to, progress)?.kept()
        })?,
    };
    let em_cfg = &plan.em;
    let s = &lobes.stats;
    let lit = lit(s, em_cfg);
    progress.done(
        "em",
        s.ms,
        &format!(
            "{} of {} splats with photons fitted{} ({:.0} fits/s, {:.2} M rays/s){}",
            s.fitted,
            lit,
            match s.served {
                0 => String::new(),
                n => format!(", {n} more served by their fits"),
            },
            s.fitted as f64 / (s.ms / 1e3).max(1e-9),
            s.rays as f64 / (s.final_gather_ms * 1e3).max(1e-9),
            match s.direct_bake_ms {
                0.0 => String::new(),
                ms => format!("; every splat's direct bake {ms:.0} ms of it"),
            },
        ),
    );
    let em = StageReport {
        splats_fitted: Some(s.fitted),
        splats_lit: Some(lit),
        splats_served: Some(s.served),
        rays: Some(s.rays),
        direct_bake_ms: Some(s.direct_bake_ms),
        coverages: Some(s.coverages),
        splats_smoothed: Some(s.smoothed[1] + s.smoothed[2]),
        splats_smoothed_widest: Some(s.smoothed[2]),
        lobes_kept: Some(lobes.lobes.len() as u64),
        lobes_fitted: Some(s.fitted as u64 * em_cfg.lobes as u64),
        skipped_reason: Some(em_skipped(&lobes, em_cfg, scene.splats.len())),
        ..StageReport::ran(s.ms)
    };
    Ok(Baked {
        photons,
        binning,
        em,
        lobes,
        direct,
    })
}

/// Traces and bins the scene's photons on the device, for the reference renderer (no lobes).
pub fn bins_gpu(
    scene: &Scene,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    progress: &Progress,
) -> Result<Binned<Bins<wgpu::Buffer>>> {
    let plan = BakePlan::new(scene, gpu.bake_limits())?;
    on_device(scene, gpu, on_gpu, |ex, on| {
        bake_on(ex, scene, &plan, on, BakeTo::Bins, progress)?.take_binned()
    })
}

/// Traces and bins the scene's photons on the CPU mirrors, for the reference renderer; the
/// bins come back to the host.
pub fn bins_cpu(
    scene: &Scene,
    grid: &SplatGrid,
    progress: &Progress,
) -> Result<Binned<PhotonBins>> {
    let plan = BakePlan::new(scene, BakeLimits::host())?;
    on_mirror(scene, grid, |ex, on| {
        let binned = bake_on(ex, scene, &plan, on, BakeTo::Bins, progress)?.take_binned()?;
        Ok(Binned {
            bins: binned.bins.read_back(ex)?,
            em: binned.em,
            photons: binned.photons,
            binning: binned.binning,
        })
    })
}

/// A bake on the CPU mirror: its lobes, its photons (for views that draw them) and the
/// reports of its tracing and of its binning or deposits.
pub struct MirrorBake {
    pub lobes: LobeMap,
    pub map: PhotonMap,
    pub photons: StageReport,
    pub binning: StageReport,
}

/// Bakes on the CPU mirror and reads the photons back too: the viewer's bake where the CPU
/// mirror outruns the window's software rasterizer (its photon view draws them).
pub fn baked_on_mirror(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    progress: &Progress,
) -> Result<MirrorBake> {
    on_mirror(scene, grid, |ex, on| {
        let mut run = bake_on(ex, scene, plan, on, BakeTo::Lobes, progress)?;
        Ok(MirrorBake {
            lobes: run.take_lobes()?,
            map: run.traced.read_back(ex)?,
            photons: run.photons,
            binning: run.binning,
        })
    })
}

/// The photon pass (`sequence::trace_photons`) with its bar.
pub fn trace<E: Executor>(
    ex: &mut E,
    plan: &BakePlan,
    on: &SceneBuffers<E::Buffer>,
    progress: &Progress,
) -> Result<Traced<E::Buffer>> {
    let bar = progress.bar(plan.photons.photons);
    let mut on_batch = |done: u64, _total: u64| {
        bar.set_position(done);
        progress.traced(done);
    };
    let (emitters, cfg) = (&plan.emitters, &plan.photons);
    let traced = sequence::trace_photons(
        ex,
        emitters,
        on.materials,
        cfg,
        plan.photon_page,
        &mut on_batch,
    )?;
    ex.finish()?;
    bar.finish_and_clear();
    progress_photons(progress, &traced.stats);
    Ok(traced)
}

/// The pages of stored photons as the binning passes take them.
fn pages<B>(traced: &Traced<B>) -> Vec<(&B, u32)> {
    traced
        .pages
        .iter()
        .map(|p| (&p.buffer, p.count as u32))
        .collect()
}

/// Photon binning (`sequence::bin_photons`) of traced photons in cells of the search radius,
/// with what the reference renderer reads beside the bins.
pub fn bin_traced<E: Executor>(
    ex: &mut E,
    plan: &BakePlan,
    on: &SceneBuffers<E::Buffer>,
    traced: &Traced<E::Buffer>,
    progress: &Progress,
) -> Result<Binned<Bins<E::Buffer>>> {
    let stored = traced.stats.stored;
    let (bins, ms) = progress.timed("binning", || {
        check_binned(stored, plan.limits.binned_bytes)?;
        let params = bin_params(on.grid, plan.em.radius, stored)?;
        let bins = sequence::bin_photons(ex, &pages(traced), on.splats, &params)?;
        ex.finish()?;
        Ok(bins)
    })?;
    Ok(Binned {
        bins,
        em: plan.em.params(on.splat_count, 0, FitShape::default()),
        photons: traced_report(&traced.stats),
        binning: StageReport::ran(ms),
    })
}

/// Photon deposits (`sequence::deposit_photons`) of traced photons, as many splats' a buffer
/// as the executor holds, with their report.
pub fn deposit_traced<E: Executor>(
    ex: &mut E,
    plan: &BakePlan,
    on: &SceneBuffers<E::Buffer>,
    traced: &Traced<E::Buffer>,
    progress: &Progress,
) -> Result<(Deposits<E::Buffer>, StageReport)> {
    let params = plan.deposits.as_ref().ok_or_else(|| {
        Error::internal("the bake's plan has no deposits for a fit that reads them")
    })?;
    let (deposits, ms) = progress.timed("deposits", || {
        let range = (on.grid, plan.limits.deposit_range);
        let deposits = sequence::deposit_photons(ex, &pages(traced), on.splats, params, range)?;
        ex.finish()?;
        Ok(deposits)
    })?;
    Ok((deposits, StageReport::ran(ms)))
}

/// The lobe fit (`sequence::fit_lobes`) over binned photons, or with every splat's irradiance
/// from `deposits` where they are given, with final gathering through the scene; the lobes
/// come back to the host, with the direct bake final gathering made (where it ran).
pub fn fit<E: Executor>(
    ex: &mut E,
    scene: &Scene,
    plan: &BakePlan,
    on: &SceneBuffers<E::Buffer>,
    (bins, deposits): (&Bins<E::Buffer>, Option<&Deposits<E::Buffer>>),
    progress: &Progress,
) -> Result<(LobeMap, Option<DirectMap>)> {
    let spin = progress.spinner("em");
    let t = Instant::now();
    let setup = plan.gather_setup(scene);
    let lights = ex.upload("lights", &scene.lights)?;
    let words = match &plan.groups {
        Some(g) => Some((g, ex.upload("fit groups", &g.words)?)),
        None => None,
    };
    let cover = CoverGroups::new(&scene.splats, plan.em.radius, plan.groups.as_ref())?;
    let cover_words = ex.upload("coverage groups", &cover.words)?;
    let input = FitInput {
        bin_params: &bins.params_buf,
        cell_start: &bins.cell_start,
        geom: &bins.geom,
        power: &bins.power,
        splats: on.splats,
        materials: on.materials,
        splat_count: on.splat_count,
        gathering: Some(Gathering {
            setup: &setup,
            lights: &lights,
            splats: &scene.splats,
            batch_bytes: plan.limits.gather_batch_bytes,
        }),
        deposits: deposits.map(|d| DepositInput {
            reach: d.params.reach,
            params: &d.params_buf,
            keys: &d.bins.keys,
            spread: &d.spread,
        }),
        groups: words.as_ref().map(|(g, words)| GroupInput {
            words,
            starts_at: g.starts_at(),
            members_at: g.members_at(),
        }),
        cover: Some(CoverInput {
            words: &cover_words,
            groups: cover.groups,
        }),
    };
    let em = &plan.em;
    let fitted = sequence::fit_lobes(ex, &input, em, plan.limits.fit_shape)?;
    ex.finish()?;
    let stats = fitted.stats(ms_since(t));
    let direct = match &fitted.direct {
        Some(d) => Some(d.read_back(ex, &plan.direct)?),
        None => None,
    };
    let mut lobes = fitted.read_back(ex, em.lobes, on.splat_count, stats)?;
    if let Some(g) = &plan.groups {
        lobes.stats.served = g.serve(&mut lobes);
    }
    lobes.stats.rays = lobes.stats.fitted as u64 * em.gather as u64 * em.gather as u64;
    lobes.stats.coverages = cover.groups;
    spin.finish_and_clear();
    Ok((lobes, direct))
}

/// Splats with photons near them: those the fit listed, and with deposits the glossy splats
/// served by shared fits, which `deposit_share` lit and no list holds (the photons' estimate lists
/// them for their irradiance).
fn lit(s: &EmStats, cfg: &EmConfig) -> u32 {
    s.listed + if cfg.uses_deposits() { s.served } else { 0 }
}

/// The photon pass's report.
fn traced_report(stats: &PhotonStats) -> StageReport {
    StageReport {
        emitted: Some(stats.emitted),
        stored: Some(stats.stored),
        ..StageReport::ran(stats.trace_ms)
    }
}

/// What the lobe fit left out, and why: splats without photons cost nothing, diffuse ones
/// only their irradiance gather, with nothing glossy lit no EM runs and no lobes are kept, and
/// pruning drops the lobes the photons do not need.
fn em_skipped(map: &LobeMap, cfg: &EmConfig, splats: usize) -> String {
    let s = &map.stats;
    let lit = lit(s, cfg);
    let dark = splats.saturating_sub(lit as usize);
    let served = match s.served {
        0 => String::new(),
        n => format!(" ({n} more glossy splats served by their groups' fits)"),
    };
    // Where coverage groups hold several splats (a dense scan), say how many measures served.
    let covered = match s.coverages as usize {
        0 => String::new(),
        n if n >= splats => String::new(),
        n => format!("; coverage measured {n} times for {splats} splats"),
    };
    let covered = covered + &smoothed(&s.smoothed);
    if s.fitted == 0 {
        format!(
            "no EM and no lobes kept: no glossy splat has photons (irradiance gathered on {} \
             splats; {dark} without photons skipped{covered})",
            s.listed
        )
    } else {
        format!(
            "EM on {} glossy splats only{served}: {} diffuse splats gathered irradiance only, \
             {dark} without photons skipped{}",
            s.fitted,
            lit.saturating_sub(s.fitted + s.served),
            if cfg.prune {
                format!(
                    "; {} of {} lobes kept, the rest pruned",
                    map.lobes.len(),
                    s.fitted as u64 * cfg.lobes as u64
                )
            } else {
                String::new()
            } + &covered
        )
    }
}

/// What `estimate_smooth` did, for the stage's detail: how many lit splats took a wider estimate
/// than their own, and how many fitted a subset of their crowded boxes.
fn smoothed(counts: &[u32; 4]) -> String {
    let [own, half, widest, crowded] = *counts;
    if own + half + widest == 0 {
        return String::new();
    }
    let crowded = match crowded {
        0 => String::new(),
        n => format!(", {n} by a choice from a subset of the neighbours"),
    };
    format!(
        "; {} of {} lit splats smoothed ({widest} to the widest kernel{crowded})",
        half + widest,
        own + half + widest
    )
}

fn progress_photons(progress: &Progress, s: &PhotonStats) {
    progress.done(
        "photons",
        s.trace_ms,
        &format!(
            "{} emitted, {} stored ({:.2} M photons/s)",
            s.emitted,
            s.stored,
            s.emitted as f64 / (s.trace_ms * 1e3).max(1e-9)
        ),
    );
}

/// Bakes on the device over the scene `frames` draws, and keeps the lobes for its frames
/// (the viewer and the frame benchmarks, which draw on the device whichever engine bakes).
pub fn bake_frames(
    gpu: &Gpu,
    frames: &mut FrameRenderer,
    scene: &Scene,
    progress: &Progress,
) -> Result<Baked> {
    let baked = bake(scene, BakeDevice::Gpu(gpu, &frames.on_gpu), progress)?;
    frames.set_baked(gpu, scene, (&baked.lobes, baked.direct.as_ref()))?;
    Ok(baked)
}
