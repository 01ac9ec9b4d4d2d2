//! Photon binning on the device: `bin_count` and `bin_scatter` once per store page, an
//! exclusive scan between them, then `bin_rank` (once per chunk of the longest cell list) and
//! `bin_place`. The same passes as `cpu::bin_photons`, with identical lists as the result.

use super::Gpu;
use super::photons::GpuPhotons;
use super::scan;
use crate::bins::{PhotonBins, check_binned};
use crate::error::{Error, Result};
use crate::types::{BinParams, BinnedPhoton};

/// Binned photons on the device (see `PhotonBins`).
pub struct GpuBins {
    pub params: BinParams,
    pub params_buf: wgpu::Buffer,
    pub cell_start: wgpu::Buffer,
    pub keys: wgpu::Buffer,
    pub geom: wgpu::Buffer,
    pub power: wgpu::Buffer,
    /// `bin_rank` dispatches the longest cell list needed.
    pub rank_chunks: u32,
}

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
        let n = self.params.photon_count as usize;
        Ok(PhotonBins {
            params: self.params,
            cell_start: gpu.read(&self.cell_start, self.params.cell_count as usize + 1)?,
            keys: gpu.read(&self.keys, n)?,
            geom: gpu.read::<BinnedPhoton>(&self.geom, n)?,
            power: gpu.read(&self.power, n)?,
        })
    }
}

pub fn bin_photons(gpu: &Gpu, photons: &GpuPhotons, params: &BinParams) -> Result<GpuBins> {
    let total: u64 = photons.pages.iter().map(|p| p.count).sum();
    check_binned(total, gpu.max_binding_bytes())?;
    let n = total as u32;
    let page_params: Vec<(wgpu::Buffer, u32)> = photons
        .pages
        .iter()
        .map(|p| {
            let count = p.count as u32;
            let params = BinParams {
                photon_count: count,
                ..*params
            };
            (gpu.uniform("bin page params", &params), count)
        })
        .collect();
    let cells = params.cell_count as u64;
    let cell_start = gpu.storage_zeroed("bin cell start", (cells + 1) * 4)?;
    let chunks = gpu.storage_zeroed("bin rank chunks", 4)?;
    let mut encoder = gpu.encoder("bin count");
    for (page, (uniform, count)) in photons.pages.iter().zip(&page_params) {
        gpu.dispatch(
            &mut encoder,
            "bin_count",
            &[uniform, &page.buffer, &cell_start, &chunks],
            gpu.groups("bin_count", *count)?,
        )?;
    }
    scan::exclusive_scan(gpu, &mut encoder, &cell_start, params.cell_count + 1)?;

    // Entries to allocate (at least one: empty bindings are invalid).
    let len = total.max(1);
    let cursor = gpu.storage_zeroed("bin cursor", cells * 4)?;
    let scratch_keys = gpu.storage_zeroed("bin scratch keys", len * 8)?;
    let scratch_cells = gpu.storage_zeroed("bin scratch cells", len * 4)?;
    let scratch_geom = gpu.storage_zeroed("bin scratch geometry", len * 16)?;
    let scratch_power = gpu.storage_zeroed("bin scratch power", len * 16)?;
    for (page, (uniform, count)) in photons.pages.iter().zip(&page_params) {
        gpu.dispatch(
            &mut encoder,
            "bin_scatter",
            &[
                uniform,
                &page.buffer,
                &cell_start,
                &cursor,
                &scratch_keys,
                &scratch_cells,
                &scratch_geom,
                &scratch_power,
            ],
            gpu.groups("bin_scatter", *count)?,
        )?;
    }
    gpu.submit_and_wait(encoder)?;
    let rank_chunks = match gpu.read::<u32>(&chunks, 1)?[..] {
        [c] => c,
        _ => return Err(Error::Gpu("bin chunk readback was short".into())),
    };

    let params = BinParams {
        photon_count: n,
        ..*params
    };
    let slots = gpu.storage_zeroed("bin slots", len * 4)?;
    let mut encoder = gpu.encoder("bin rank");
    for chunk in 0..rank_chunks {
        let pass = gpu.uniform(
            "bin rank params",
            &BinParams {
                rank_chunk: chunk,
                ..params
            },
        );
        gpu.dispatch(
            &mut encoder,
            "bin_rank",
            &[&pass, &cell_start, &scratch_keys, &scratch_cells, &slots],
            gpu.groups("bin_rank", n)?,
        )?;
    }
    let params_buf = gpu.uniform("bin params", &params);
    let keys = gpu.storage_zeroed("binned keys", len * 8)?;
    let geom = gpu.storage_zeroed("binned geometry", len * 16)?;
    let power = gpu.storage_zeroed("binned power", len * 16)?;
    gpu.dispatch(
        &mut encoder,
        "bin_place",
        &[
            &params_buf,
            &slots,
            &scratch_keys,
            &scratch_geom,
            &scratch_power,
            &keys,
            &geom,
            &power,
        ],
        gpu.groups("bin_place", n)?,
    )?;
    gpu.submit_and_wait(encoder)?;
    Ok(GpuBins {
        params,
        params_buf,
        cell_start,
        keys,
        geom,
        power,
        rank_chunks,
    })
}
