//! `lobelight render`: bake and draw a scene to an image, with per-stage figures.
//! So far one method: `photons`, the stored photons seen from the camera (thesis Fig. 3.1).

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::camera::View;
use crate::cpu;
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::gpu::photons::trace_photons;
use crate::gpu::scene::GpuScene;
use crate::grid::SplatGrid;
use crate::photons::{PhotonConfig, PhotonMap, ms_since};
use crate::scene::Scene;
use crate::shared::tone::srgb_byte;
use crate::shared::trace::{Geometry, trace_ray};
use crate::types::{Material, NO_SPLAT, Photon};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Stored photons drawn as points where the camera sees them.
    Photons,
}

#[derive(Clone, Debug)]
pub struct Options {
    pub method: Method,
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

/// One stage's line of `--stats` / `--json` (DESIGN.md §12).
#[derive(Clone, Debug, Default, Serialize)]
pub struct StageReport {
    pub ran: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub emitted: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stored: Option<u64>,
    pub skipped_reason: Option<String>,
}

impl StageReport {
    fn ran(ms: f64) -> StageReport {
        StageReport {
            ran: true,
            ms: Some(ms),
            ..Default::default()
        }
    }

    fn skipped(reason: &str) -> StageReport {
        StageReport {
            skipped_reason: Some(reason.into()),
            ..Default::default()
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Stages {
    pub grid: StageReport,
    pub photons: StageReport,
    pub binning: StageReport,
    pub em: StageReport,
    pub shade: StageReport,
    pub tonemap: StageReport,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderReport {
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    pub method: Method,
    pub output: String,
    pub width: u32,
    pub height: u32,
    pub stages: Stages,
}

impl std::fmt::Display for RenderReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "device   {} ({})", self.adapter, self.backend)?;
        writeln!(f, "splats   {}", self.splats)?;
        let s = &self.stages;
        let rows = [
            ("grid", &s.grid),
            ("photons", &s.photons),
            ("binning", &s.binning),
            ("em", &s.em),
            ("shade", &s.shade),
            ("tonemap", &s.tonemap),
        ];
        for (name, r) in rows {
            match (r.ran, r.ms, &r.skipped_reason) {
                (true, Some(ms), _) => writeln!(f, "{name:<8} {ms:>9.1} ms")?,
                (_, _, Some(why)) => writeln!(f, "{name:<8}   skipped: {why}")?,
                _ => writeln!(f, "{name:<8}   ran")?,
            }
        }
        write!(
            f,
            "wrote    {} ({}×{})",
            self.output, self.width, self.height
        )
    }
}

fn progress_bar(show: bool, total: u64) -> indicatif::ProgressBar {
    if !show {
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
    bar.set_message("tracing");
    bar
}

/// Traces the scene's photons on the GPU or the CPU mirror; returns them with the grid (on the
/// host, for visibility) and the grid build time.
fn bake_photons(
    scene: &Scene,
    gpu: Option<&Gpu>,
    show_progress: bool,
) -> Result<(PhotonMap, SplatGrid, f64)> {
    let cfg = PhotonConfig::from_scene(scene);
    let bar = progress_bar(show_progress, cfg.photons);
    let mut progress = |done: u64, _total: u64| bar.set_position(done);
    let out = match gpu {
        Some(gpu) => {
            let on_gpu = GpuScene::upload(gpu, scene)?;
            let traced = trace_photons(gpu, scene, &on_gpu, &cfg, &mut progress)?;
            (
                traced.download(gpu)?,
                on_gpu.grid.download(gpu)?,
                on_gpu.grid_ms,
            )
        }
        None => cpu::trace_scene(scene, &cfg, &mut progress)?,
    };
    bar.finish_and_clear();
    Ok(out)
}

pub fn render(
    scene: &Scene,
    gpu: Option<&Gpu>,
    opts: &Options,
    output: &Path,
) -> Result<RenderReport> {
    let [w0, h0] = scene.camera.resolution;
    let (width, height) = (opts.width.unwrap_or(w0), opts.height.unwrap_or(h0));
    crate::scene::check_resolution(width, height).map_err(Error::Invalid)?;
    let (map, grid, grid_ms) = bake_photons(scene, gpu, opts.progress)?;
    let t = Instant::now();
    let view = View::new(&scene.camera, width, height);
    let geo = Geometry {
        grid: &grid,
        splats: &scene.splats,
    };
    let image = draw_photons(&view, &geo, &scene.materials, &map.photons);
    write_png(output, &image, width, height)?;
    let not_built = "not part of --method photons";
    Ok(RenderReport {
        adapter: gpu.map_or_else(|| "CPU mirror".to_string(), |g| g.info.name.clone()),
        backend: gpu.map_or("cpu", |g| g.backend_name()).to_string(),
        splats: scene.splats.len(),
        method: opts.method,
        output: output.display().to_string(),
        width,
        height,
        stages: Stages {
            grid: StageReport::ran(grid_ms),
            photons: StageReport {
                emitted: Some(map.stats.emitted),
                stored: Some(map.stats.stored),
                ..StageReport::ran(map.stats.trace_ms)
            },
            binning: StageReport::skipped(not_built),
            em: StageReport::skipped(not_built),
            // Drawing the photons, on the CPU.
            shade: StageReport::ran(ms_since(t)),
            tonemap: StageReport::skipped("photon view is scaled by its 99.5th percentile"),
        },
    })
}

/// Sums the power of the photons the camera sees (on the front of their splat, with nothing
/// in between) into their pixels, times the splat's albedo (ρd + ρs): a photon stores the
/// power that arrives, and the wall colours only show in what leaves.
pub fn draw_photons(
    view: &View,
    geo: &Geometry,
    materials: &[Material],
    photons: &[Photon],
) -> Vec<[f32; 3]> {
    let (w, h) = (view.width as usize, view.height as usize);
    let visible: Vec<(usize, Vec3)> = photons
        .par_iter()
        .filter_map(|p| {
            let pos = Vec3::from(p.position);
            let (x, y) = view.project(pos)?;
            let s = &geo.splats[p.splat as usize];
            let to_eye = view.eye - pos;
            if Vec3::from(s.normal).dot(to_eye) <= 0.0 {
                return None;
            }
            let dist = to_eye.length();
            let mut budget = crate::photons::ITERATION_BUDGET;
            let hit = trace_ray(geo, pos, to_eye / dist, p.splat, dist * 0.999, &mut budget);
            let albedo =
                Vec3::from(s.diffuse) + Vec3::from(materials[s.material as usize].specular);
            (hit.splat == NO_SPLAT && hit.aborted == 0)
                .then(|| (y as usize * w + x as usize, Vec3::from(p.power) * albedo))
        })
        .collect();
    let mut image = vec![Vec3::ZERO; w * h];
    for (i, power) in visible {
        image[i] += power;
    }
    image.into_iter().map(|c| c.to_array()).collect()
}

/// Writes an HDR image as PNG, scaled so that the 99.5th percentile of the lit pixels' largest
/// channel maps to white, then sRGB-encoded.
pub fn write_png(path: &Path, image: &[[f32; 3]], width: u32, height: u32) -> Result<()> {
    let mut peaks: Vec<f32> = image
        .iter()
        .map(|c| c[0].max(c[1]).max(c[2]))
        .filter(|&m| m > 0.0 && m.is_finite())
        .collect();
    peaks.sort_by(f32::total_cmp);
    let white = peaks
        .get((peaks.len() as f64 * 0.995) as usize)
        .or(peaks.last())
        .copied()
        .unwrap_or(1.0);
    let bytes: Vec<u8> = image
        .iter()
        .flat_map(|c| c.map(|v| srgb_byte(v / white) as u8))
        .collect();
    let img = image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Invalid("image buffer has the wrong size".into()))?;
    img.save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))
}
