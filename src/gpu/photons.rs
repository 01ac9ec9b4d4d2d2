//! Stored photons on the device (`sequence::Traced`): read back, or uploaded from the host
//! (the photon pass itself: `host::trace`, `bake::trace`).

use super::Gpu;
use super::exec::GpuExecutor;
use crate::error::Result;
use crate::photons::PhotonMap;
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
