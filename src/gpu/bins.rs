//! Photon binning on the device: `sequence::bin_photons` over every store page, as
//! `cpu::bin_photons` runs it over one, with identical lists as the result.

use super::Gpu;
use super::exec::GpuExecutor;
use super::photons::GpuPhotons;
use crate::bins::DepositBins;
use crate::bins::{PhotonBins, check_binned};
use crate::error::Result;
use crate::sequence::{self, Executor};
use crate::types::{BinParams, DepositParams, GridParams};

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

/// Bins the photons of every store page on the device (`sequence::bin_photons`), which landed
/// on `splats`.
pub fn bin_photons(
    gpu: &Gpu,
    photons: &GpuPhotons,
    splats: &wgpu::Buffer,
    params: &BinParams,
) -> Result<GpuBins> {
    let total: u64 = photons.pages.iter().map(|p| p.count).sum();
    check_binned(total, gpu.bake_limits().binned_bytes)?;
    let pages: Vec<(&wgpu::Buffer, u32)> = photons
        .pages
        .iter()
        .map(|p| (&p.buffer, p.count as u32))
        .collect();
    let mut encoder = gpu.encoder("binning");
    let mut ex = GpuExecutor::new(gpu, &mut encoder);
    let bins = sequence::bin_photons(&mut ex, &pages, splats, params)?;
    gpu.submit_and_wait(encoder)?;
    Ok(bins)
}

/// Photon deposits on the device (see `bins::DepositBins`).
pub type GpuDeposits = sequence::Deposits<wgpu::Buffer>;

impl GpuDeposits {
    pub fn download(&self, gpu: &Gpu) -> Result<DepositBins> {
        let mut encoder = gpu.encoder("deposits download");
        let mut ex = GpuExecutor::new(gpu, &mut encoder);
        Ok(DepositBins {
            params: self.params,
            bins: self.bins.read_back(&mut ex)?,
            spread: ex.read(&self.spread, self.params.splat_count as usize)?,
        })
    }
}

/// The deposits of the photons of every store page on the device
/// (`sequence::deposit_photons`), which landed on `splats`, binned over `grid`'s box.
pub fn deposit_photons(
    gpu: &Gpu,
    photons: &GpuPhotons,
    splats: &wgpu::Buffer,
    params: &DepositParams,
    grid: &GridParams,
) -> Result<GpuDeposits> {
    let range = gpu.bake_limits().deposit_range;
    let pages: Vec<(&wgpu::Buffer, u32)> = photons
        .pages
        .iter()
        .map(|p| (&p.buffer, p.count as u32))
        .collect();
    let mut encoder = gpu.encoder("deposits");
    let mut ex = GpuExecutor::new(gpu, &mut encoder);
    let deposits = sequence::deposit_photons(&mut ex, &pages, splats, params, (grid, range))?;
    gpu.submit_and_wait(encoder)?;
    Ok(deposits)
}
