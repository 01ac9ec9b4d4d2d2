//! The lobe fit on the device: `sequence::fit_lobes` (`em_select`, the list's length read
//! back, then `em_fit` one workgroup per listed splat), in the device's shape.

use std::time::Instant;

use super::Gpu;
use super::bins::GpuBins;
use super::exec::GpuExecutor;
use crate::em::{EmConfig, EmStats, FitShape, LobeMap, workgroup_size};
use crate::error::{Error, Result};
use crate::plan::{BakeLimits, GATHER_BATCH_BYTES};
use crate::sequence::{self, FitInput};
use crate::timing::ms_since;

/// The fit's output on the device.
pub struct GpuLobes {
    pub lobes_per_splat: u32,
    pub fit: sequence::Fit<wgpu::Buffer>,
    pub splat_count: u32,
    pub stats: EmStats,
}

impl GpuLobes {
    /// The fit on the host, its lobes packed (`sequence::Fit::read_back`).
    pub fn download(&self, gpu: &Gpu) -> Result<LobeMap> {
        let mut encoder = gpu.encoder("lobes download");
        let mut ex = GpuExecutor::new(gpu, &mut encoder);
        let (per_splat, n) = (self.lobes_per_splat, self.splat_count);
        self.fit
            .read_back(&mut ex, per_splat, n, self.stats.clone())
    }
}

/// The fit's shape on this device: loop-limited on llvmpipe (which silently cuts long shader
/// loops); a subgroup reduction where subgroup operations are enabled and a subgroup always
/// holds the whole workgroup.
pub fn fit_shape(gpu: &Gpu) -> FitShape {
    let loop_limited = gpu.is_software();
    FitShape {
        loop_limited,
        subgroup_reduce: gpu.subgroups
            && gpu.info.subgroup_min_size >= workgroup_size(loop_limited),
    }
}

impl Gpu {
    /// What this device holds of a bake (`plan::BakeLimits`): photon pages and deposit
    /// buffers of one binding, the binning's arrays paged, gathering batches of one page, and
    /// the fit in the device's shape.
    pub fn bake_limits(&self) -> BakeLimits {
        let photon = std::mem::size_of::<crate::types::Photon>() as u64;
        let deposit = crate::shared::deposits::DEPOSIT_WORDS as u64 * 4;
        BakeLimits {
            photon_page: self.max_binding_bytes() / photon,
            binned_bytes: self.max_array_bytes(16),
            deposit_range: (self.page_bytes() / deposit).clamp(1, u32::MAX as u64) as u32,
            gather_batch_bytes: self.page_bytes().min(GATHER_BATCH_BYTES),
            fit_shape: fit_shape(self),
        }
    }
}

/// Fits lobes to the binned photons around each of the `splat_count` splats in `splats`
/// (with their `materials`), in the device's shape: the photon fit (`cfg.gather` 0; the
/// bake's fit, with final gathering through the scene, is `bake::fit`).
pub fn fit_lobes(
    gpu: &Gpu,
    splats: &wgpu::Buffer,
    materials: &wgpu::Buffer,
    splat_count: u32,
    bins: &GpuBins,
    cfg: &EmConfig,
) -> Result<GpuLobes> {
    fit_lobes_shaped(
        gpu,
        splats,
        materials,
        splat_count,
        bins,
        cfg,
        fit_shape(gpu),
    )
}

/// `fit_lobes` in a given shape (tests run both reductions on one device).
pub fn fit_lobes_shaped(
    gpu: &Gpu,
    splats: &wgpu::Buffer,
    materials: &wgpu::Buffer,
    splat_count: u32,
    bins: &GpuBins,
    cfg: &EmConfig,
    shape: FitShape,
) -> Result<GpuLobes> {
    fit_on_device(gpu, (splats, materials, splat_count), bins, cfg, shape)
}

/// The photon fit of `splats` (their buffer, their materials', their count); the bake's fit,
/// with final gathering, is `bake::fit`.
fn fit_on_device(
    gpu: &Gpu,
    (splats, materials, splat_count): (&wgpu::Buffer, &wgpu::Buffer, u32),
    bins: &GpuBins,
    cfg: &EmConfig,
    shape: FitShape,
) -> Result<GpuLobes> {
    cfg.validate()?;
    if shape.subgroup_reduce && !fit_shape(gpu).subgroup_reduce {
        return Err(Error::DeviceLimit(
            "this device cannot reduce the fit's sums with subgroup operations".into(),
        ));
    }
    let t = Instant::now();
    let input = FitInput {
        bin_params: &bins.params_buf,
        cell_start: &bins.cell_start,
        geom: &bins.geom,
        power: &bins.power,
        splats,
        materials,
        splat_count,
        gathering: None,
        deposits: None,
        groups: None,
        cover: None,
    };
    let mut encoder = gpu.encoder("lobe fit");
    let mut ex = GpuExecutor::new(gpu, &mut encoder);
    let fit = sequence::fit_lobes(&mut ex, &input, cfg, shape)?;
    gpu.submit_and_wait(encoder)?;
    Ok(GpuLobes {
        lobes_per_splat: cfg.lobes,
        splat_count,
        stats: fit.stats(ms_since(t)),
        fit,
    })
}
