//! `lobelight bench …`: throughput with the figures that say whether the work was right.

use std::time::Instant;

use serde::Serialize;

use crate::cpu;
use crate::error::Result;
use crate::gpu::Gpu;
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
