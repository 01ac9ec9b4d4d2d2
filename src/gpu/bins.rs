//! Binned photons on the device (`sequence::Bins`): uploaded from the host, or read back
//! (the binning itself: `host::bin_photons`, `bake`).

use super::Gpu;
use super::exec::GpuExecutor;
use crate::bins::{DepositBins, PhotonBins};
use crate::error::Result;
use crate::sequence;

/// Binned photons on the device (see `PhotonBins`).
pub type GpuBins = sequence::Bins<wgpu::Buffer>;
impl GpuBins {
    /// Binned photons made elsewhere (the CPU mirror), for fitting on the device.
    pub fn upload(gpu: &Gpu, bins: &PhotonBins) -> Result<GpuBins> {
        Ok(GpuBins {
            params: bins.params,
            params_buf: gpu.uniform("bin params", &bins.params),
            cell_start: gpu.storage("bin cell start", &bins.cell_start)?,
            keys: gpu.storage("binned keys", &bins.keys)?,
            geom: gpu.storage("binned geometry", &bins.geom)?,
            power: gpu.storage("binned power", &bins.power)?,
            rank_chunks: 0,
        })
    }

    pub fn download(&self, gpu: &Gpu) -> Result<PhotonBins> {
        self.read_back(&mut GpuExecutor::new(
            gpu,
            &mut gpu.encoder("bins download"),
        ))
    }
}

/// Photon deposits on the device (see `bins::DepositBins`).
pub type GpuDeposits = sequence::Deposits<wgpu::Buffer>;

impl GpuDeposits {
    /// Deposits made elsewhere (the CPU mirror, an engine's `deposit_photons`), for fitting on
    /// the device.
    pub fn upload(gpu: &Gpu, deposits: &DepositBins) -> Result<GpuDeposits> {
        Ok(GpuDeposits {
            params: deposits.params,
            params_buf: gpu.uniform("deposit params", &deposits.params),
            bins: GpuBins::upload(gpu, &deposits.bins)?,
            spread: gpu.storage("deposit spread", &deposits.spread)?,
        })
    }
}
