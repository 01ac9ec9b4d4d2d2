//! The lobe fit on the device: `em_select` lists the splats with photons near them, the host
//! reads the list's length (and the most candidates any splat has, which sizes the dispatches
//! on a loop-limited device), then `em_fit` runs one workgroup per listed splat, in one
//! dispatch or in several that hand the mixture over through the lobe buffer.

use std::time::Instant;

use super::Gpu;
use super::bins::GpuBins;
use crate::em::{
    EmConfig, EmStats, FitShape, LobeMap, dispatch_ranges, iterations_per_dispatch, workgroup_size,
};
use crate::error::{Error, Result};
use crate::photons::ms_since;
use crate::types::{EmParams, Lobe, SplatLight};

/// The fit's output on the device.
pub struct GpuLobes {
    pub lobes_per_splat: u32,
    pub lobes: wgpu::Buffer,
    pub light: wgpu::Buffer,
    pub splat_count: u32,
    pub stats: EmStats,
}

impl GpuLobes {
    /// The fit on the host, its lobes packed (`LobeMap::pack`); with nothing fitted no lobe
    /// is read back.
    pub fn download(&self, gpu: &Gpu) -> Result<LobeMap> {
        let n = self.splat_count as usize;
        let dense = if self.stats.fitted == 0 {
            Vec::new()
        } else {
            gpu.read::<Lobe>(&self.lobes, n * self.lobes_per_splat as usize)?
        };
        let light = gpu.read::<SplatLight>(&self.light, n)?;
        let per_splat = if dense.is_empty() {
            0
        } else {
            self.lobes_per_splat
        };
        let mut map = LobeMap::pack(per_splat, &dense, light, self.stats.clone());
        map.stats.photons = map.fitted().map(|l| l.photons as u64).sum();
        Ok(map)
    }
}

/// The fit's shape on this device: loop-limited on llvmpipe (which silently cuts long shader
/// loops); a subgroup reduction where subgroup operations are enabled and a subgroup always
/// holds the whole workgroup.
pub fn fit_shape(gpu: &Gpu) -> FitShape {
    let loop_limited = gpu.info.device_type == wgpu::DeviceType::Cpu;
    FitShape {
        loop_limited,
        subgroup_reduce: gpu.subgroups
            && gpu.info.subgroup_min_size >= workgroup_size(loop_limited),
    }
}

/// Fits lobes to the binned photons around each of the `splat_count` splats in `splats`
/// (with their `materials`), in the device's shape.
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
    cfg.validate()?;
    if shape.subgroup_reduce && !fit_shape(gpu).subgroup_reduce {
        return Err(Error::Invalid(
            "this device cannot reduce the fit's sums with subgroup operations".into(),
        ));
    }
    let t = Instant::now();
    let n = splat_count as u64;
    let lobes = gpu.storage_zeroed("lobes", (n * cfg.lobes as u64).max(1) * 32)?;
    let light = gpu.storage_zeroed("splat light", n.max(1) * 32)?;
    let fit_list = gpu.storage_zeroed("fit list", n.max(1) * 4)?;
    let counters = gpu.storage_zeroed("em counters", 12)?;
    let select = gpu.uniform("em select params", &cfg.params(splat_count, 0, shape));
    let mut encoder = gpu.encoder("em select");
    gpu.dispatch(
        &mut encoder,
        "em_select",
        &[
            &select,
            &bins.params_buf,
            splats,
            materials,
            &bins.cell_start,
            &fit_list,
            &counters,
        ],
        gpu.groups("em_select", splat_count)?,
    )?;
    gpu.submit_and_wait(encoder)?;
    let (listed, max_candidates, fitted) = match gpu.read::<u32>(&counters, 3)?[..] {
        [a, b, c] => (a, b, c),
        _ => return Err(Error::Gpu("em counters readback was short".into())),
    };
    let chunk = iterations_per_dispatch(cfg, max_candidates, shape.loop_limited)?;
    let constants = [
        ("LOBES", cfg.lobes as f64),
        ("FAMILY", cfg.family.code() as f64),
        ("WG", workgroup_size(shape.loop_limited) as f64),
        ("SPARSE", f64::from(u8::from(cfg.sparse))),
    ];
    let defines: &[&str] = if shape.subgroup_reduce {
        &["subgroups"]
    } else {
        &[]
    };
    let pipeline = gpu.variant("em_fit", defines, &constants)?;
    let mut encoder = gpu.encoder("em fit");
    let mut dispatches = 0;
    for (begin, end) in dispatch_ranges(cfg.iterations, chunk) {
        let params = EmParams {
            iteration_begin: begin,
            iteration_end: end,
            ..cfg.params(splat_count, listed, shape)
        };
        let uniform = gpu.uniform("em params", &params);
        gpu.dispatch_pipeline(
            &mut encoder,
            "em_fit",
            &pipeline,
            &[&[
                &uniform,
                &bins.params_buf,
                splats,
                &fit_list,
                &bins.cell_start,
                &bins.geom,
                &bins.power,
                &lobes,
                &light,
            ]],
            listed,
        )?;
        dispatches += 1;
    }
    gpu.submit_and_wait(encoder)?;
    Ok(GpuLobes {
        lobes_per_splat: cfg.lobes,
        lobes,
        light,
        splat_count,
        stats: EmStats {
            listed,
            fitted,
            max_candidates,
            photons: 0,
            dispatches,
            ms: ms_since(t),
        },
    })
}
