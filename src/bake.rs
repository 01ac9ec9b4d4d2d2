//! The bake (DESIGN.md §4–6): photons from the lights, binned, and the lobes fitted to them,
//! on the device or on the CPU mirror, with a line of figures per stage. A frame needs only
//! its result, so a camera change never bakes again.

use std::time::{Duration, Instant};

use crate::bins::bin_params;
use crate::cpu;
use crate::em::{EmConfig, FitShape, LobeMap};
use crate::error::Result;
use crate::gpu::Gpu;
use crate::gpu::bins::bin_photons;
use crate::gpu::em::fit_lobes;
use crate::gpu::photons::trace_photons;
use crate::gpu::scene::GpuScene;
use crate::grid::SplatGrid;
use crate::photons::{PhotonConfig, ms_since};
use crate::render::StageReport;
use crate::scene::Scene;
use crate::shared::trace::Geometry;

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
}

impl Progress {
    pub fn new(show: bool) -> Progress {
        Progress { show }
    }

    /// A bar over `total` photons.
    pub fn bar(&self, total: u64) -> indicatif::ProgressBar {
        if !self.show {
            return indicatif::ProgressBar::hidden();
        }
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg:>8} [{bar:30}] {human_pos}/{human_len} photons, {per_sec}, eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_message("photons");
        bar
    }

    fn spinner(&self, stage: &str) -> indicatif::ProgressBar {
        if !self.show {
            return indicatif::ProgressBar::hidden();
        }
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_message(format!("{stage:>8} …"));
        bar.enable_steady_tick(Duration::from_millis(120));
        bar
    }

    /// Prints a finished stage's line.
    pub fn done(&self, stage: &str, ms: f64, rate: &str) {
        if self.show {
            eprintln!("{stage:>8} {:>9.1} ms  {rate}", ms);
        }
    }
}

/// Traces, bins and fits; the lobes come back to the host (a few bytes per splat), from
/// where a cache file or any device can take them.
pub fn bake(scene: &Scene, device: BakeDevice, progress: &Progress) -> Result<Baked> {
    let photon_cfg = PhotonConfig::from_scene(scene);
    let em_cfg = EmConfig::from_scene(scene);
    let bar = progress.bar(photon_cfg.photons);
    let mut on_batch = |done: u64, _total: u64| bar.set_position(done);
    let (lobes, stats, binning_ms) = match device {
        BakeDevice::Gpu(gpu, on_gpu) => {
            let traced = trace_photons(gpu, scene, on_gpu, &photon_cfg, &mut on_batch)?;
            bar.finish_and_clear();
            let stats = traced.stats.clone();
            progress_photons(progress, &stats);
            let spin = progress.spinner("binning");
            let t = Instant::now();
            let params = bin_params(&on_gpu.grid.params, em_cfg.radius)?;
            let bins = bin_photons(gpu, &traced, &params)?;
            drop(traced);
            let binning_ms = ms_since(t);
            spin.finish_and_clear();
            progress.done("binning", binning_ms, "");
            let spin = progress.spinner("em");
            let n = scene.splats.len() as u32;
            let fitted = fit_lobes(gpu, &on_gpu.splats, &on_gpu.materials, n, &bins, &em_cfg)?;
            let lobes = fitted.download(gpu)?;
            spin.finish_and_clear();
            (lobes, stats, binning_ms)
        }
        BakeDevice::Cpu(grid) => {
            let geo = Geometry {
                grid,
                splats: &scene.splats,
            };
            let map = cpu::trace_photons(
                &scene.lights,
                &scene.materials,
                &geo,
                &photon_cfg,
                &mut on_batch,
            )?;
            bar.finish_and_clear();
            progress_photons(progress, &map.stats);
            let spin = progress.spinner("binning");
            let t = Instant::now();
            let bins = cpu::bin_photons(&bin_params(&grid.params, em_cfg.radius)?, &map.photons)?;
            let binning_ms = ms_since(t);
            spin.finish_and_clear();
            progress.done("binning", binning_ms, "");
            let spin = progress.spinner("em");
            let lobes = cpu::fit_lobes(
                &em_cfg,
                &bins,
                &scene.splats,
                &scene.materials,
                FitShape::default(),
            )?;
            spin.finish_and_clear();
            (lobes, map.stats, binning_ms)
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
        skipped_reason: (s.fitted == 0)
            .then(|| "no glossy splat has photons: only total irradiance was gathered".to_string()),
        ..StageReport::ran(s.ms)
    };
    Ok(Baked {
        photons: StageReport {
            emitted: Some(stats.emitted),
            stored: Some(stats.stored),
            ..StageReport::ran(stats.trace_ms)
        },
        binning: StageReport::ran(binning_ms),
        em,
        lobes,
    })
}

fn progress_photons(progress: &Progress, s: &crate::photons::PhotonStats) {
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
