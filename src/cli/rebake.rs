//! `bench rebake`: what a moved light costs. The viewer's arrow keys move the first light and
//! bake again on the scene already on the device (no grid rebuild): a preview with an eighth
//! of the photons and a third of the EM iterations, then the full bake. This times both over a few moves and measures the
//! preview's error against the full bake's frame, so the preview's speed comes with its price.

use std::time::Instant;

use serde::Serialize;

use crate::bake::{BakeDevice, Progress, bake};
use crate::camera::View;
use crate::cli::compare::difference;
use crate::cli::measure::median;
use crate::cli::view::{move_first_light, passes};
use crate::cpu;
use crate::cpu::frames::{cpu_direct, cpu_frame_into};
use crate::direct::DirectMap;
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::frame::{FrameConfig, camera_uniform, shade_params};
use crate::gpu::Gpu;
use crate::grid::SplatGrid;
use crate::renderer::FrameRenderer;
use crate::scene::Scene;
use crate::timing::ms_since;

/// Light moves timed (one arrow-key step each, along x).
pub const MOVES: u32 = 3;
/// The size of the frames the preview is compared on.
const IMAGE: (u32, u32) = (256, 256);

#[derive(Debug, Serialize)]
pub struct RebakeBench {
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    pub photons: u64,
    pub preview_photons: u64,
    pub preview_iterations: u32,
    /// Uploading the splats and building the grid: paid once, not by a re-bake.
    pub grid_ms: f64,
    /// The first bake (pipelines compiled on the way).
    pub bake_ms: f64,
    /// Medians over the moves: the moved light's direct bake (made first, so its direct light
    /// and shadows follow at once), the full re-bake of the indirect light and the preview bake.
    pub direct_ms: f64,
    pub rebake_ms: f64,
    pub preview_ms: f64,
    /// Photons traced per second by the full re-bake.
    pub photons_per_s: f64,
    /// Median relMSE of the preview's frame against the full bake's (256², same light).
    pub preview_rel_mse: f64,
    pub moves: u32,
}

/// Where it runs: the device with the scene on it, or the CPU mirror with its grid.
enum Place<'a> {
    Gpu(&'a Gpu, Box<FrameRenderer>),
    /// The grid, and the direct bake of the lights as they last moved.
    Cpu(SplatGrid, DirectMap),
}

impl Place<'_> {
    fn bake(&self, scene: &Scene) -> Result<(LobeMap, f64)> {
        let quiet = Progress::new(false);
        let t = Instant::now();
        let device = match self {
            Place::Gpu(gpu, renderer) => BakeDevice::Gpu(gpu, &renderer.on_gpu),
            Place::Cpu(grid, _) => BakeDevice::Cpu(grid),
        };
        let lobes = bake(scene, device, &quiet)?.lobes;
        Ok((lobes, ms_since(t)))
    }

    /// The direct bake of the scene's lights, in milliseconds.
    fn bake_direct(&mut self, scene: &Scene) -> Result<f64> {
        let t = Instant::now();
        match self {
            Place::Gpu(gpu, renderer) => {
                renderer.bake_direct(gpu, scene)?;
            }
            Place::Cpu(grid, direct) => *direct = cpu_direct(scene, grid)?,
        }
        Ok(ms_since(t))
    }

    /// The frame of the scene's camera with `lobes`, linear HDR.
    fn image(&mut self, scene: &Scene, lobes: &LobeMap) -> Result<Vec<[f32; 4]>> {
        let cfg = FrameConfig::default();
        let view = View::new(&scene.camera, IMAGE.0, IMAGE.1);
        match self {
            Place::Gpu(gpu, renderer) => {
                renderer.set_lobes(gpu, scene, lobes)?;
                renderer.draw(gpu, scene, &view, &cfg)?;
                renderer.read_hdr(gpu)
            }
            Place::Cpu(grid, direct) => {
                let cam = camera_uniform(&view, scene.bounds(), &cfg);
                let params = shade_params(scene, lobes, &cfg);
                let mut hdr = vec![[0.0; 4]; (IMAGE.0 * IMAGE.1) as usize];
                cpu_frame_into(scene, grid, lobes, direct, &cam, &params, &mut hdr);
                Ok(hdr)
            }
        }
    }
}

pub fn rebake(scene: &Scene, gpu: Option<&Gpu>) -> Result<RebakeBench> {
    let [quick, full] = &passes(&scene.bake, true)[..] else {
        return Err(Error::Invalid(format!(
            "bench rebake needs a scene with enough photons for a preview bake (it has {}; \
             use --photons 1000000)",
            scene.bake.photons
        )));
    };
    let t = Instant::now();
    let (mut place, adapter, backend) = match gpu {
        Some(gpu) => {
            let renderer = FrameRenderer::new(gpu, scene)?;
            let name = (gpu.info.name.clone(), gpu.backend_name().to_string());
            (Place::Gpu(gpu, Box::new(renderer)), name.0, name.1)
        }
        None => {
            let grid = cpu::scene_grid(scene)?;
            let threads = rayon::current_num_threads();
            let adapter = format!("CPU mirror ({threads} threads)");
            let direct = cpu_direct(scene, &grid)?;
            (Place::Cpu(grid, direct), adapter, "cpu".to_string())
        }
    };
    let grid_ms = ms_since(t);
    let (_, bake_ms) = place.bake(scene)?;
    let (mut full_ms, mut preview_ms, mut errors) = (Vec::new(), Vec::new(), Vec::new());
    let mut direct_ms = Vec::new();
    for k in 1..=MOVES {
        let moved = move_first_light(scene, k as f32, 0.0)
            .ok_or_else(|| Error::Invalid("bench rebake needs a scene with a light".into()))?;
        direct_ms.push(place.bake_direct(&moved)?);
        let mut preview = moved.clone();
        preview.bake = quick.clone();
        let (quick, ms) = place.bake(&preview)?;
        preview_ms.push(ms);
        let (full, ms) = place.bake(&moved)?;
        full_ms.push(ms);
        let preview_image = place.image(&moved, &quick)?;
        let d = difference(&preview_image, &place.image(&moved, &full)?)?;
        errors.push(d.rel_mse);
    }
    let rebake_ms = median(full_ms);
    let photons = full.photons;
    Ok(RebakeBench {
        scene: scene.path.display().to_string(),
        adapter,
        backend,
        splats: scene.splats.len(),
        photons,
        preview_photons: quick.photons,
        preview_iterations: quick.iterations,
        grid_ms,
        bake_ms,
        direct_ms: median(direct_ms),
        rebake_ms,
        preview_ms: median(preview_ms),
        photons_per_s: photons as f64 / (rebake_ms / 1e3).max(1e-9),
        preview_rel_mse: median(errors),
        moves: MOVES,
    })
}

impl std::fmt::Display for RebakeBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "scene        {}", self.scene)?;
        writeln!(f, "device       {} ({})", self.adapter, self.backend)?;
        writeln!(
            f,
            "scene        {} splats, grid built once in {:.1} ms; first bake {:.1} ms",
            self.splats, self.grid_ms, self.bake_ms
        )?;
        writeln!(
            f,
            "direct       {:.1} ms: the moved light's direct bake, before the indirect light's",
            self.direct_ms
        )?;
        writeln!(
            f,
            "re-bake      {:.1} ms for {} photons ({:.2} M photons/s), median of {} light moves",
            self.rebake_ms,
            self.photons,
            self.photons_per_s / 1e6,
            self.moves
        )?;
        write!(
            f,
            "preview      {:.1} ms for {} photons and {} EM iterations, relMSE {:.4} against \
             the full re-bake",
            self.preview_ms, self.preview_photons, self.preview_iterations, self.preview_rel_mse
        )
    }
}
