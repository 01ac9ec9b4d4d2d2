//! Bakes on a second thread beside a window's frames (the same device, or the CPU mirror
//! beside a software rasterizer): the viewer's. A bake sends its result after each of its
//! passes: a light that moved gets a quick preview bake with a
//! fraction of the photons first, then the full bake. Starting a newer bake makes the older
//! one stop at its next pass (a generation counter), so keys pressed in a row never queue
//! bakes up. The photons stay on the device for the photon view, and their bins for the
//! reference view (binned when it is first shown, where the bake needed no bins).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Instant;

use crate::bake::{BakeTo, Binned, Progress, bake_on, baked_on_mirror, on_device};
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::gpu::bins::GpuBins;
use crate::gpu::photons::GpuPhotons;
use crate::gpu::scene::GpuScene;
use crate::grid::SplatGrid;
use crate::plan::{BakeLimits, BakePlan};
use crate::scene::{BakeDesc, Scene};
use crate::timing::ms_since;

/// A preview bake traces this fraction of the scene's photons, with this fraction of its EM
/// iterations (at least `PREVIEW_MIN_ITERATIONS`): the fit's cost per splat does not shrink
/// with the photons.
pub const PREVIEW_FRACTION: u64 = 8;
const PREVIEW_ITERATIONS: u32 = 3;
const PREVIEW_MIN_ITERATIONS: u32 = 2;
/// Scenes with fewer photons than this bake in full at once.
const PREVIEW_MIN: u64 = 200_000;

/// One finished pass of a bake.
pub struct BakeResult {
    pub lobes: LobeMap,
    pub photons: GpuPhotons,
    /// The photons binned, where the bake binned them (the photon fit); else the reference
    /// view bins them the first time it is shown.
    pub binned: Option<Binned<GpuBins>>,
    /// Photons emitted in this pass.
    pub emitted: u64,
    /// More passes follow (this one is a preview).
    pub preview: bool,
    /// Time from the bake's start to this result.
    pub seconds: f64,
}

/// Where background bakes run: on the window's device, or on the CPU mirror (with the scene's
/// grid built on the host), which bakes faster where the device is a software rasterizer; the
/// lobes and photons go to the device either way.
#[derive(Clone)]
pub enum BakeEngine {
    Device,
    Mirror(Arc<SplatGrid>),
}

impl BakeEngine {
    /// The CPU mirror, with `scene`'s grid built on the host (the same splats' scenes, lights
    /// moved, bake there too).
    pub fn mirror(scene: &Scene) -> Result<BakeEngine> {
        Ok(BakeEngine::Mirror(Arc::new(crate::cpu::scene_grid(scene)?)))
    }
}

/// A bake running on its thread.
pub struct Baking {
    receive: Receiver<Result<BakeResult>>,
    pub started: Instant,
    /// Photons traced so far in the pass under way.
    pub traced: Arc<AtomicU64>,
    passes: Vec<u64>,
    /// Passes received.
    received: usize,
}

/// The bake settings of a bake's passes: a preview first when asked and worth it.
pub fn passes(full: &BakeDesc, preview: bool) -> Vec<BakeDesc> {
    if preview && full.photons >= PREVIEW_MIN {
        let quick = BakeDesc {
            photons: full.photons / PREVIEW_FRACTION,
            iterations: (full.iterations / PREVIEW_ITERATIONS).max(PREVIEW_MIN_ITERATIONS),
            ..full.clone()
        };
        vec![quick, full.clone()]
    } else {
        vec![full.clone()]
    }
}

/// Starts a bake of `scene` over `passes`, as generation `generation.fetch_add(1) + 1`; the
/// full (last) pass is saved to `cache` when given.
pub(super) fn spawn(
    (gpu, on_gpu): (&Arc<Gpu>, &Arc<GpuScene>),
    engine: &BakeEngine,
    scene: &Arc<Scene>,
    passes: Vec<BakeDesc>,
    cache: Option<PathBuf>,
    generation: &Arc<AtomicU64>,
) -> Baking {
    let (send, receive) = channel();
    let mine = generation.fetch_add(1, Ordering::SeqCst) + 1;
    let (gpu, on_gpu, engine, scene, generation) = (
        gpu.clone(),
        on_gpu.clone(),
        engine.clone(),
        scene.clone(),
        generation.clone(),
    );
    let started = Instant::now();
    let counts = passes.iter().map(|p| p.photons).collect();
    let traced = Arc::new(AtomicU64::new(0));
    let counter = traced.clone();
    std::thread::spawn(move || {
        let last = passes.len().saturating_sub(1);
        for (k, settings) in passes.iter().enumerate() {
            if generation.load(Ordering::SeqCst) != mine {
                return; // a newer bake took over
            }
            let mut pass = (*scene).clone();
            pass.bake = settings.clone();
            counter.store(0, Ordering::Relaxed);
            let baked = bake_pass(&gpu, &on_gpu, &engine, &pass, k < last, started, &counter);
            let baked = baked.and_then(|b| {
                if let (Some(path), false) = (&cache, b.preview) {
                    crate::cache::save(path, crate::cache::bake_key(&scene), &b.lobes)?;
                }
                Ok(b)
            });
            let failed = baked.is_err();
            // The window may be gone: nothing need wait for this bake then.
            if send.send(baked).is_err() || failed {
                return;
            }
        }
    });
    Baking {
        receive,
        started,
        traced,
        passes: counts,
        received: 0,
    }
}

fn bake_pass(
    gpu: &Gpu,
    on_gpu: &GpuScene,
    engine: &BakeEngine,
    scene: &Scene,
    preview: bool,
    started: Instant,
    traced: &Arc<AtomicU64>,
) -> Result<BakeResult> {
    let progress = Progress::counting(traced.clone());
    if let BakeEngine::Mirror(grid) = engine {
        let plan = BakePlan::new(scene, BakeLimits::host())?;
        let baked = baked_on_mirror(scene, &plan, grid, &progress)?;
        return Ok(BakeResult {
            emitted: baked.map.stats.emitted,
            photons: GpuPhotons::upload(gpu, &baked.map)?,
            lobes: baked.lobes,
            binned: None,
            preview,
            seconds: ms_since(started) / 1e3,
        });
    }
    let plan = BakePlan::new(scene, gpu.bake_limits())?;
    let mut run = on_device(scene, gpu, on_gpu, |ex, on| {
        bake_on(ex, scene, &plan, on, BakeTo::Lobes, &progress)
    })?;
    Ok(BakeResult {
        lobes: run.take_lobes()?,
        emitted: run.traced.stats.emitted,
        photons: run.traced,
        binned: run.binned,
        preview,
        seconds: ms_since(started) / 1e3,
    })
}

impl Baking {
    /// Photons of the pass under way.
    pub fn photons(&self) -> u64 {
        let last = self.passes.len().saturating_sub(1);
        self.passes
            .get(self.received.min(last))
            .copied()
            .unwrap_or(0)
    }

    /// The next pass's result when it has come in.
    pub fn poll(&mut self) -> Result<Option<BakeResult>> {
        match self.receive.try_recv() {
            Ok(result) => {
                self.received += 1;
                Ok(Some(result?))
            }
            Err(TryRecvError::Empty) => Ok(None),
            Err(TryRecvError::Disconnected) => {
                Err(Error::Gpu("the bake stopped without a result".into()))
            }
        }
    }
}
