//! `bench rebake`: what a moved light costs. The viewer's arrow keys move the first light and
//! bake again on the scene already on the device (no grid rebuild): a preview with an eighth
//! of the photons and a third of the EM iterations, then the full bake. This times both over a few moves and measures the
//! preview's error against the full bake's frame, so the preview's speed comes with its price.

use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::bake::Progress;
use crate::camera::View;
use crate::cli::compare::difference;
use crate::cli::measure::median;
use crate::cli::view::{move_first_light, passes};
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::frame::FrameConfig;
use crate::renderer::{Engine, Renderer};
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

/// Bakes the renderer's scene as `scene` says (its lights and bake settings); returns the
/// lobes and the bake's milliseconds.
fn bake_as(renderer: &mut Renderer, scene: Arc<Scene>) -> Result<(LobeMap, f64)> {
    renderer.relight(scene)?;
    let t = Instant::now();
    renderer.bake(&Progress::new(false))?;
    Ok((renderer.lobes().clone(), ms_since(t)))
}

/// The frame of the scene's camera with `lobes`, linear HDR.
fn image(renderer: &mut Renderer, lobes: &LobeMap) -> Result<Vec<[f32; 4]>> {
    let view = View::new(&renderer.scene().camera, IMAGE.0, IMAGE.1);
    renderer.set_lobes(lobes.clone());
    renderer.draw(&view, &FrameConfig::default(), 0, |_| {})?;
    renderer.read_hdr()
}

pub fn rebake(scene: &Arc<Scene>, engine: &Engine) -> Result<RebakeBench> {
    let [quick, full] = &passes(&scene.bake, true)[..] else {
        return Err(Error::Invalid(format!(
            "bench rebake needs a scene with enough photons for a preview bake (it has {}; \
             use --photons 1000000)",
            scene.bake.photons
        )));
    };
    let mut renderer = Renderer::new(scene.clone(), engine)?;
    let grid_ms = renderer.grid_ms();
    let (_, bake_ms) = bake_as(&mut renderer, scene.clone())?;
    let (mut full_ms, mut preview_ms, mut errors) = (Vec::new(), Vec::new(), Vec::new());
    let mut direct_ms = Vec::new();
    for k in 1..=MOVES {
        let moved = move_first_light(scene, k as f32, 0.0)
            .ok_or_else(|| Error::Invalid("bench rebake needs a scene with a light".into()))?;
        let moved = Arc::new(moved);
        renderer.relight(moved.clone())?;
        direct_ms.push(renderer.bake_direct()?);
        let mut preview = (*moved).clone();
        preview.bake = quick.clone();
        let (quick, ms) = bake_as(&mut renderer, Arc::new(preview))?;
        preview_ms.push(ms);
        let (full, ms) = bake_as(&mut renderer, moved)?;
        full_ms.push(ms);
        let preview_image = image(&mut renderer, &quick)?;
        let d = difference(&preview_image, &image(&mut renderer, &full)?)?;
        errors.push(d.rel_mse);
    }
    let rebake_ms = median(full_ms);
    let photons = full.photons;
    let adapter = engine.adapter_and_threads();
    Ok(RebakeBench {
        scene: scene.path.display().to_string(),
        adapter,
        backend: engine.backend().to_string(),
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
