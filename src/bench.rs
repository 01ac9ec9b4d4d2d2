//! `lobelight bench …`: throughput with the figures that say whether the work was right.

use std::time::Instant;

use serde::Serialize;

use crate::bins::bin_params;
use crate::cpu;
use crate::em::{EmConfig, EmStats, FitShape, LobeFamily};
use crate::error::Result;
use crate::gpu::Gpu;
use crate::gpu::bins as gpu_bins;
use crate::gpu::em as gpu_em;
use crate::gpu::photons::trace_photons;
use crate::gpu::scene::GpuScene;
use crate::photons::{PhotonConfig, PhotonMap, PhotonStats, ms_since, photons_within};
use crate::scene::Scene;

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

/// Traces the scene's photons once, on the GPU or (without one) the CPU mirror. The GPU's
/// pipelines are compiled by a small warm-up trace first, which is not timed.
pub fn photons(scene: &Scene, gpu: Option<&Gpu>, cfg: &PhotonConfig) -> Result<PhotonBench> {
    let (map, grid_ms, download_ms, adapter, backend) = match gpu {
        Some(gpu) => {
            let on_gpu = GpuScene::upload(gpu, scene)?;
            let warm = PhotonConfig {
                photons: cfg.photons.min(4096),
                ..cfg.clone()
            };
            trace_photons(gpu, scene, &on_gpu, &warm, &mut |_, _| {})?;
            let traced = trace_photons(gpu, scene, &on_gpu, cfg, &mut |_, _| {})?;
            let t = Instant::now();
            let map = traced.download(gpu)?;
            (
                map,
                on_gpu.grid_ms,
                ms_since(t),
                gpu.info.name.clone(),
                gpu.backend_name().to_string(),
            )
        }
        None => {
            let (map, _, grid_ms) = cpu::trace_scene(scene, cfg, &mut |_, _| {})?;
            let threads = rayon::current_num_threads();
            (
                map,
                grid_ms,
                0.0,
                format!("CPU mirror ({threads} threads)"),
                "cpu".into(),
            )
        }
    };
    Ok(summarise(
        scene,
        map,
        grid_ms,
        download_ms,
        adapter,
        backend,
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
    pub photons_ms: f64,
    pub splats_fitted: u32,
    /// Photons gathered per fitted splat (within R, front side, inside the slab).
    pub mean_photons: f64,
    /// Fit error: negative log-likelihood per unit photon weight, mean over fitted splats.
    pub nll: f64,
    pub stats: EmStats,
}

/// Traces and bins the scene's photons, then times the lobe fit. On the GPU a first fit
/// compiles the pipelines and is not timed.
pub fn em(
    scene: &Scene,
    gpu: Option<&Gpu>,
    photons: &PhotonConfig,
    cfg: &EmConfig,
) -> Result<EmBench> {
    let cfg = EmConfig {
        fit_all: true,
        ..cfg.clone()
    };
    let (map, traced_stats, binning_ms, adapter, backend) = match gpu {
        Some(gpu) => {
            let on_gpu = GpuScene::upload(gpu, scene)?;
            let traced = trace_photons(gpu, scene, &on_gpu, photons, &mut |_, _| {})?;
            let traced_stats = traced.stats.clone();
            let params = bin_params(&on_gpu.grid.params, cfg.radius)?;
            let t = Instant::now();
            let bins = gpu_bins::bin_photons(gpu, &traced, &params)?;
            let binning_ms = ms_since(t);
            drop(traced);
            let n = scene.splats.len() as u32;
            let fit = |c: &EmConfig| {
                gpu_em::fit_lobes(gpu, &on_gpu.splats, &on_gpu.materials, n, &bins, c)
            };
            fit(&EmConfig {
                iterations: 1,
                ..cfg.clone()
            })?;
            let map = fit(&cfg)?.download(gpu)?;
            let name = gpu.info.name.clone();
            let backend = gpu.backend_name().to_string();
            (map, traced_stats, binning_ms, name, backend)
        }
        None => {
            let (traced, grid, _) = cpu::trace_scene(scene, photons, &mut |_, _| {})?;
            let params = bin_params(&grid.params, cfg.radius)?;
            let t = Instant::now();
            let bins = cpu::bin_photons(&params, &traced.photons)?;
            let binning_ms = ms_since(t);
            let map = cpu::fit_lobes(
                &cfg,
                &bins,
                &scene.splats,
                &scene.materials,
                FitShape::default(),
            )?;
            let threads = rayon::current_num_threads();
            let adapter = format!("CPU mirror ({threads} threads)");
            (map, traced.stats, binning_ms, adapter, "cpu".into())
        }
    };
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
        photons_ms: traced_stats.trace_ms,
        splats_fitted: s.fitted,
        mean_photons: map.mean_photons(),
        nll: map.nll(),
        stats: s.clone(),
    })
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
        write!(f, "throughput   {:.0} fits/s", self.fits_per_s)
    }
}
