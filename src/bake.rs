//! The bake (docs/design.md §4–6): photons from the lights, binned, and the lobes fitted to them,
//! on the device or on the CPU mirror, with a line of figures per stage. A frame needs only
//! its result, so a camera change never bakes again.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::bins::{PhotonBins, bin_params};
use crate::cpu;
use crate::direct::direct_params;
use crate::em::{EmConfig, FitShape, GatherSetup, LobeMap};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::gpu::bins::{GpuBins, GpuDeposits, bin_photons, deposit_photons};
use crate::gpu::em::{fit_lobes_gathering, fit_lobes_to_deposits};
use crate::gpu::photons::{GpuPhotons, trace_photons};
use crate::gpu::scene::GpuScene;
use crate::grid::SplatGrid;
use crate::photons::{PhotonMap, PhotonStats};
use crate::plan::BakePlan;
use crate::scene::Scene;
use crate::timing::ms_since;
use crate::types::{DepositParams, EmParams};

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

pub struct Baked {
    pub lobes: LobeMap,
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
        #[cfg(feature = "progress")]
        if self.show {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{msg:>8} [{bar:30}] {human_pos}/{human_len} photons, {per_sec}, eta {eta}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            bar.set_message("photons");
            return Bar(Some(bar));
        }
        let _ = total;
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

fn binned<B>(plan: &BakePlan, splats: usize, bins: B, stats: &PhotonStats, ms: f64) -> Binned<B> {
    Binned {
        bins,
        em: plan.em.params(splats as u32, 0, FitShape::default()),
        photons: traced_report(stats),
        binning: StageReport::ran(ms),
    }
}

/// The photon pass's report.
fn traced_report(stats: &PhotonStats) -> StageReport {
    StageReport {
        emitted: Some(stats.emitted),
        stored: Some(stats.stored),
        ..StageReport::ran(stats.trace_ms)
    }
}

/// Traces and bins on the device.
pub fn bins_gpu(
    scene: &Scene,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    progress: &Progress,
) -> Result<Binned<GpuBins>> {
    let plan = BakePlan::new(scene)?;
    let traced = traced_gpu(scene, &plan, gpu, on_gpu, progress)?;
    binned_gpu(scene, &plan, gpu, on_gpu, &traced, progress)
}

/// Bins photons traced on the device.
pub fn binned_gpu(
    scene: &Scene,
    plan: &BakePlan,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    traced: &GpuPhotons,
    progress: &Progress,
) -> Result<Binned<GpuBins>> {
    let stats = &traced.stats;
    let (bins, ms) = progress.timed("binning", || {
        let params = bin_params(&on_gpu.grid.params, plan.em.radius, stats.stored)?;
        bin_photons(gpu, traced, &on_gpu.splats, &params)
    })?;
    Ok(binned(plan, scene.splats.len(), bins, stats, ms))
}

/// Traces and bins on the CPU mirror.
pub fn bins_cpu(
    scene: &Scene,
    grid: &SplatGrid,
    progress: &Progress,
) -> Result<Binned<PhotonBins>> {
    binned_cpu(scene, &BakePlan::new(scene)?, grid, progress)
}

fn binned_cpu(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    progress: &Progress,
) -> Result<Binned<PhotonBins>> {
    let map = traced_cpu(scene, plan, grid, progress)?;
    binned_of(scene, plan, grid, &map, progress)
}

/// Bins photons traced on the CPU mirror.
fn binned_of(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    map: &PhotonMap,
    progress: &Progress,
) -> Result<Binned<PhotonBins>> {
    let (bins, ms) = progress.timed("binning", || {
        let params = bin_params(&grid.params, plan.em.radius, map.stats.stored)?;
        cpu::bin_photons(&params, &map.photons, &scene.splats)
    })?;
    Ok(binned(plan, scene.splats.len(), bins, &map.stats, ms))
}

/// A bake on the CPU mirror: its lobes, its photons (for views that draw them) and the
/// reports of its tracing and of its binning or deposits.
pub struct MirrorBake {
    pub lobes: LobeMap,
    pub map: PhotonMap,
    pub photons: StageReport,
    pub binning: StageReport,
}

/// Bakes on the CPU mirror: `bake`'s CPU path, and the viewer's bake where the CPU mirror
/// outruns the window's software rasterizer.
pub fn baked_on_mirror(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    progress: &Progress,
) -> Result<MirrorBake> {
    let map = traced_cpu(scene, plan, grid, progress)?;
    if plan.em.uses_deposits() {
        // The photons are deposited, not binned: the binning's report is the deposits'.
        let (deposits, ms) = deposits_cpu(scene, plan, grid, &map, progress)?;
        let binned = (&deposits.bins, Some(&deposits));
        return Ok(MirrorBake {
            lobes: fit_on_cpu(scene, plan, grid, binned, progress)?,
            photons: traced_report(&map.stats),
            binning: StageReport::ran(ms),
            map,
        });
    }
    let b = binned_of(scene, plan, grid, &map, progress)?;
    Ok(MirrorBake {
        lobes: fit_on_cpu(scene, plan, grid, (&b.bins, None), progress)?,
        photons: b.photons,
        binning: b.binning,
        map,
    })
}

/// Traces on the CPU mirror.
fn traced_cpu(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    progress: &Progress,
) -> Result<PhotonMap> {
    let bar = progress.bar(plan.photons.photons);
    let mut on_batch = |done: u64, _total: u64| {
        bar.set_position(done);
        progress.traced(done);
    };
    let map = cpu::trace_photons(
        &scene.lights,
        &scene.materials,
        &scene.geometry(grid),
        &plan.photons,
        &mut on_batch,
    )?;
    bar.finish_and_clear();
    progress_photons(progress, &map.stats);
    Ok(map)
}

/// Traces on the device.
pub fn traced_gpu(
    scene: &Scene,
    plan: &BakePlan,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    progress: &Progress,
) -> Result<GpuPhotons> {
    let bar = progress.bar(plan.photons.photons);
    let mut on_batch = |done: u64, _total: u64| {
        bar.set_position(done);
        progress.traced(done);
    };
    let traced = trace_photons(gpu, scene, on_gpu, &plan.photons, &mut on_batch)?;
    bar.finish_and_clear();
    progress_photons(progress, &traced.stats);
    Ok(traced)
}

/// The deposits' uniform of a plan whose fit reads deposits.
fn planned_deposits(plan: &BakePlan) -> Result<&DepositParams> {
    plan.deposits
        .as_ref()
        .ok_or_else(|| Error::internal("the bake's plan has no deposits for a fit that reads them"))
}

/// Photon deposits on the device, with their time as the binning's.
fn deposits_gpu(
    plan: &BakePlan,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    traced: &GpuPhotons,
    progress: &Progress,
) -> Result<(GpuDeposits, f64)> {
    let params = planned_deposits(plan)?;
    progress.timed("deposits", || {
        deposit_photons(gpu, traced, &on_gpu.splats, params, &on_gpu.grid.params)
    })
}

/// Photon deposits on the CPU mirror, with their time as the binning's.
fn deposits_cpu(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    map: &PhotonMap,
    progress: &Progress,
) -> Result<(cpu::DepositBins, f64)> {
    let params = planned_deposits(plan)?;
    progress.timed("deposits", || {
        cpu::deposit_photons(params, &map.photons, &scene.splats, &grid.params)
    })
}

/// Fits the lobes on the device to the traced photons: over their deposits where the scene's
/// estimate asks for them (`EmConfig::uses_deposits`), else over their bins, binned here and
/// returned (the deposits need none: the reference view bins them when it is shown). The
/// lobes come back to the host.
pub fn fit_gpu(
    scene: &Scene,
    plan: &BakePlan,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    traced: &GpuPhotons,
    progress: &Progress,
) -> Result<(LobeMap, Option<Binned<GpuBins>>)> {
    if plan.em.uses_deposits() {
        let (deposits, _) = deposits_gpu(plan, gpu, on_gpu, traced, progress)?;
        let binned = (&deposits.bins, Some(&deposits));
        return Ok((
            fit_on_gpu(scene, plan, gpu, on_gpu, binned, progress)?,
            None,
        ));
    }
    let binned = binned_gpu(scene, plan, gpu, on_gpu, traced, progress)?;
    let lobes = fit_on_gpu(scene, plan, gpu, on_gpu, (&binned.bins, None), progress)?;
    Ok((lobes, Some(binned)))
}

/// Fits the lobes on the device to binned photons, or with the irradiance from `deposits`
/// where they are given.
fn fit_on_gpu(
    scene: &Scene,
    plan: &BakePlan,
    gpu: &Gpu,
    on_gpu: &GpuScene,
    (bins, deposits): (&GpuBins, Option<&GpuDeposits>),
    progress: &Progress,
) -> Result<LobeMap> {
    let spin = progress.spinner("em");
    let n = scene.splats.len() as u32;
    let setup = plan.gather_setup(scene);
    let fitted = match deposits {
        Some(d) => fit_lobes_to_deposits(gpu, on_gpu, n, d, &plan.em, &setup)?,
        None => fit_lobes_gathering(gpu, on_gpu, n, bins, &plan.em, &setup)?,
    };
    let lobes = fitted.download(gpu)?;
    spin.finish_and_clear();
    Ok(lobes)
}

/// Fits the lobes on the CPU mirror to binned photons, or with the irradiance from
/// `deposits` where they are given.
fn fit_on_cpu(
    scene: &Scene,
    plan: &BakePlan,
    grid: &SplatGrid,
    (bins, deposits): (&PhotonBins, Option<&cpu::DepositBins>),
    progress: &Progress,
) -> Result<LobeMap> {
    let spin = progress.spinner("em");
    let (splats, materials) = (&scene.splats, &scene.materials);
    let shape = FitShape::default();
    let setup = plan.gather_setup(scene);
    let gathering = Some((scene.geometry(grid), &setup));
    let em = &plan.em;
    let lobes = match deposits {
        Some(d) => cpu::fit_lobes_to_deposits(em, d, splats, materials, shape, gathering),
        None => cpu::fit_lobes_gathering(em, bins, splats, materials, shape, gathering),
    }?;
    spin.finish_and_clear();
    Ok(lobes)
}

/// What final gathering reads of `scene` (`EmConfig::gather`): its lights, baked as frames
/// bake them, and rays that start where shadow rays do.
pub fn gather_setup(scene: &Scene) -> GatherSetup<'_> {
    GatherSetup::new(&scene.lights, direct_params(scene))
}

/// Traces, then deposits or bins, and fits, from one plan of the scene (`BakePlan`); the lobes
/// come back to the host (a few bytes per splat), from where a cache file or any device can
/// take them.
pub fn bake(scene: &Scene, device: BakeDevice, progress: &Progress) -> Result<Baked> {
    let plan = BakePlan::new(scene)?;
    let em_cfg = &plan.em;
    let (lobes, photons, binning) = match device {
        // The photons are deposited, not binned: the binning's report is the deposits'.
        BakeDevice::Gpu(gpu, on_gpu) if em_cfg.uses_deposits() => {
            let traced = traced_gpu(scene, &plan, gpu, on_gpu, progress)?;
            let (deposits, ms) = deposits_gpu(&plan, gpu, on_gpu, &traced, progress)?;
            let binned = (&deposits.bins, Some(&deposits));
            let lobes = fit_on_gpu(scene, &plan, gpu, on_gpu, binned, progress)?;
            (lobes, traced_report(&traced.stats), StageReport::ran(ms))
        }
        BakeDevice::Gpu(gpu, on_gpu) => {
            let traced = traced_gpu(scene, &plan, gpu, on_gpu, progress)?;
            let b = binned_gpu(scene, &plan, gpu, on_gpu, &traced, progress)?;
            let lobes = fit_on_gpu(scene, &plan, gpu, on_gpu, (&b.bins, None), progress)?;
            (lobes, b.photons, b.binning)
        }
        BakeDevice::Cpu(grid) => {
            let b = baked_on_mirror(scene, &plan, grid, progress)?;
            (b.lobes, b.photons, b.binning)
        }
    };
    let s = &lobes.stats;
    progress.done(
        "em",
        s.ms,
        &format!(
            "{} of {} splats with photons fitted ({:.0} fits/s)",
            s.fitted,
            s.listed,
            s.fitted as f64 / (s.ms / 1e3).max(1e-9)
        ),
    );
    let em = StageReport {
        splats_fitted: Some(s.fitted),
        splats_lit: Some(s.listed),
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
    })
}

/// What the lobe fit left out, and why: splats without photons cost nothing, diffuse ones
/// only their irradiance gather, with nothing glossy lit no EM runs and no lobes are kept, and
/// pruning drops the lobes the photons do not need.
fn em_skipped(map: &LobeMap, cfg: &EmConfig, splats: usize) -> String {
    let s = &map.stats;
    let dark = splats.saturating_sub(s.listed as usize);
    if s.fitted == 0 {
        format!(
            "no EM and no lobes kept: no glossy splat has photons (irradiance gathered on {} \
             splats; {dark} without photons skipped)",
            s.listed
        )
    } else {
        format!(
            "EM on {} glossy splats only: {} diffuse splats gathered irradiance only, {dark} \
             without photons skipped{}",
            s.fitted,
            s.listed - s.fitted,
            if cfg.prune {
                format!(
                    "; {} of {} lobes kept, the rest pruned",
                    map.lobes.len(),
                    s.fitted as u64 * cfg.lobes as u64
                )
            } else {
                String::new()
            }
        )
    }
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
