//! The photon pass on the device: `sequence::trace_photons` (batches of `photon_trace`
//! appending to a store of pages, the counters read back after each), with pages no larger
//! than the device's largest binding.

use super::Gpu;
use super::exec::GpuExecutor;
use super::scene::GpuScene;
use crate::error::Result;
use crate::photons::{PhotonConfig, PhotonMap, emitters, page_photons};
use crate::scene::Scene;
use crate::sequence;

/// One store buffer on the device and how many photons it holds.
pub type PhotonPage = sequence::Page<wgpu::Buffer>;

/// Stored photons on the device.
pub type GpuPhotons = sequence::Traced<wgpu::Buffer>;

impl GpuPhotons {
    /// All stored photons, sorted by `Photon::key`.
    pub fn download(&self, gpu: &Gpu) -> Result<PhotonMap> {
        self.read_back(&mut GpuExecutor::new(
            gpu,
            &mut gpu.encoder("photon download"),
        ))
    }
}

impl GpuPhotons {
    /// One page holding `photons` (for tests and for binning photons traced elsewhere).
    pub fn upload(gpu: &Gpu, map: &PhotonMap) -> Result<GpuPhotons> {
        let count = map.photons.len() as u64;
        Ok(GpuPhotons {
            pages: vec![PhotonPage {
                buffer: gpu.storage("photons", &map.photons)?,
                capacity: count,
                count,
            }],
            stats: map.stats.clone(),
        })
    }
}

/// Traces `cfg.photons` photons from the scene's lights (`sequence::trace_photons`), in pages
/// no larger than the device's largest binding. `progress` hears (paths done, total).
pub fn trace_photons(
    gpu: &Gpu,
    scene: &Scene,
    on_gpu: &GpuScene,
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<GpuPhotons> {
    cfg.validate()?;
    let emitters = emitters(&scene.lights, cfg.photons)?;
    let max_page = page_photons(cfg, gpu.bake_limits().photon_page);
    let mut encoder = gpu.encoder("photon trace");
    let mut ex = GpuExecutor::new(gpu, &mut encoder).tracing(on_gpu.geometry());
    let traced = sequence::trace_photons(
        &mut ex,
        &emitters,
        &on_gpu.materials,
        cfg,
        max_page,
        progress,
    )?;
    gpu.submit_and_wait(encoder)?;
    Ok(traced)
}
