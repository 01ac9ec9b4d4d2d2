//! The CPU mirrors run as a host runs the device: each multi-stage pass of `sequence` on a
//! `CpuExecutor` (tone map, grid, photons, binning, deposits, lobe fit), for the CPU bake
//! (`--cpu`) and the parity tests. The mirrors themselves are the other modules of `cpu`.

use std::time::Instant;

pub use crate::bins::DepositBins;
use crate::bins::PhotonBins;
use crate::em::{EmConfig, FitShape, GatherSetup, LobeMap};
use crate::error::{Error, Result};
use crate::grid::SplatGrid;
use crate::photons::{PhotonConfig, PhotonMap, emitters};
use crate::plan::GATHER_BATCH_BYTES;
use crate::shared::trace::Geometry;
use crate::timing::ms_since;
use crate::types::{BinParams, DepositParams, GridParams, Splat};
use crate::types::{Light, Material, Photon};

use super::exec::CpuExecutor;

use crate::sequence::{self, DepositInput, Executor, FitInput, Gathering};

/// Tone mapping on the CPU mirror (`sequence::tone_map`); returns RGBA8 pixels and
/// (Σ log(ε + Y), count).
pub fn tone_map(cfg: &crate::tone::ToneConfig, hdr: &[[f32; 4]]) -> Result<(Vec<u32>, [f32; 2])> {
    let pixels = u32::try_from(hdr.len())
        .map_err(|_| Error::Invalid("too many pixels to tone-map".into()))?;
    let mut ex = CpuExecutor::default();
    let hdr = ex.upload("hdr image", hdr)?;
    let toned = sequence::tone_map(&mut ex, &hdr, pixels, cfg)?;
    let rgba = ex.read(&toned.rgba, pixels as usize)?;
    let log_sum = ex.read::<[f32; 2]>(&toned.log_sum, 1)?;
    Ok((rgba, log_sum.first().copied().unwrap_or_default()))
}

/// The photon view of `cam` on the CPU mirror (`sequence::photon_image`) over one page of
/// photons; HDR pixels, rows from the top.
pub fn photon_image(
    cam: &crate::types::Camera,
    materials: &[Material],
    photons: &[Photon],
    geo: &Geometry,
    scale: f32,
) -> Result<Vec<[f32; 4]>> {
    let count = u32::try_from(photons.len())
        .map_err(|_| Error::Invalid("too many photons to view".into()))?;
    let mut ex = CpuExecutor::tracing(*geo);
    let material_buf = ex.upload("materials", materials)?;
    let page = ex.upload("photons", photons)?;
    let hdr = sequence::photon_image(&mut ex, &material_buf, &[(&page, count)], cam, scale)?;
    ex.read(&hdr, (cam.size[0] as u32 * cam.size[1] as u32) as usize)
}

/// Exclusive scan of `values` in place on the CPU mirror (`sequence::exclusive_scan`).
pub fn exclusive_scan(values: &mut [u32]) -> Result<()> {
    let len = u32::try_from(values.len())
        .map_err(|_| Error::Invalid("too many values to scan".into()))?;
    let mut ex = CpuExecutor::default();
    let buffer = ex.upload("scan values", values)?;
    sequence::exclusive_scan(&mut ex, &buffer, len)?;
    values.copy_from_slice(&ex.read::<u32>(&buffer, values.len())?);
    Ok(())
}

/// The grid build on the CPU mirror (`sequence::build_grid`).
pub fn build_grid(params: &GridParams, splats: &[Splat]) -> Result<SplatGrid> {
    let mut ex = CpuExecutor::default();
    let splat_buf = ex.upload("splats", splats)?;
    sequence::build_grid(&mut ex, params, &splat_buf)?.read_back(&mut ex)
}

/// The photon pass on the CPU mirror (`sequence::trace_photons`), in one page (host memory
/// has no binding limit), sorted by `Photon::key`.
pub fn trace_photons(
    lights: &[Light],
    materials: &[Material],
    geo: &Geometry,
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<PhotonMap> {
    cfg.validate()?;
    let emitters = emitters(lights, cfg.photons)?;
    let mut ex = CpuExecutor::tracing(*geo);
    let material_buf = ex.upload("materials", materials)?;
    let max_page = u32::MAX as u64;
    let traced =
        sequence::trace_photons(&mut ex, &emitters, &material_buf, cfg, max_page, progress)?;
    traced.read_back(&mut ex)
}

/// The scene's splat grid, built by the mirror.
pub fn scene_grid(scene: &crate::scene::Scene) -> Result<SplatGrid> {
    build_grid(
        &crate::grid::grid_params(&scene.splats, &scene.grid)?,
        &scene.splats,
    )
}

/// The scene's grid and photons on the CPU: what the GPU path keeps on the device, here on
/// the host. Returns the photons, the grid and the grid build time in ms.
pub fn trace_scene(
    scene: &crate::scene::Scene,
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(PhotonMap, SplatGrid, f64)> {
    let t = Instant::now();
    let grid = scene_grid(scene)?;
    let grid_ms = ms_since(t);
    let geo = scene.geometry(&grid);
    let map = trace_photons(&scene.lights, &scene.materials, &geo, cfg, progress)?;
    Ok((map, grid, grid_ms))
}

/// Photon binning on the CPU mirror (`sequence::bin_photons`) over one page holding every
/// photon, which landed on `splats`.
pub fn bin_photons(params: &BinParams, photons: &[Photon], splats: &[Splat]) -> Result<PhotonBins> {
    let n = u32::try_from(photons.len())
        .map_err(|_| Error::Invalid("too many photons to bin".into()))?;
    let mut ex = CpuExecutor::default();
    let page = ex.upload("photons", photons)?;
    let splats = ex.upload("splats", splats)?;
    sequence::bin_photons(&mut ex, &[(&page, n)], &splats, params)?.read_back(&mut ex)
}

/// The lobe fit on the CPU: `em_select`, then `em_fit` over the same dispatch ranges and
/// with the same sum order as the GPU path on a device of the given shape.
pub fn fit_lobes(
    cfg: &EmConfig,
    bins: &PhotonBins,
    splats: &[Splat],
    materials: &[Material],
    shape: FitShape,
) -> Result<LobeMap> {
    fit_lobes_gathering(cfg, bins, splats, materials, shape, None)
}

/// `fit_lobes`, with final gathering through `grid` where `cfg.gather` asks for it.
pub fn fit_lobes_gathering(
    cfg: &EmConfig,
    bins: &PhotonBins,
    splats: &[Splat],
    materials: &[Material],
    shape: FitShape,
    gathering: Option<(Geometry, &GatherSetup)>,
) -> Result<LobeMap> {
    fit_binned(cfg, (bins, None), (splats, materials), shape, gathering)
}

/// The deposits of `photons`, which landed on `splats`, binned over `grid`'s box.
pub fn deposit_photons(
    params: &DepositParams,
    photons: &[Photon],
    splats: &[Splat],
    grid: &GridParams,
) -> Result<DepositBins> {
    let n = u32::try_from(photons.len())
        .map_err(|_| Error::Invalid("too many photons to deposit".into()))?;
    let mut ex = CpuExecutor::default();
    let page = ex.upload("photons", photons)?;
    let splat_buf = ex.upload("splats", splats)?;
    let range = params.splat_count;
    let d = sequence::deposit_photons(&mut ex, &[(&page, n)], &splat_buf, params, (grid, range))?;
    Ok(DepositBins {
        params: d.params,
        bins: d.bins.read_back(&mut ex)?,
        spread: ex.read(&d.spread, splats.len())?,
    })
}

/// The lobe fit with every splat's irradiance from `deposits` (`em_share`) and the fitted
/// splats' lobes from final gathering through `gathering`'s scene.
pub fn fit_lobes_to_deposits(
    cfg: &EmConfig,
    deposits: &DepositBins,
    splats: &[Splat],
    materials: &[Material],
    shape: FitShape,
    gathering: Option<(Geometry, &GatherSetup)>,
) -> Result<LobeMap> {
    let binned = (&deposits.bins, Some(deposits));
    fit_binned(cfg, binned, (splats, materials), shape, gathering)
}

/// The lobe fit over binned photons, or over binned deposits where they are given.
fn fit_binned(
    cfg: &EmConfig,
    (bins, deposits): (&PhotonBins, Option<&DepositBins>),
    (splats, materials): (&[Splat], &[Material]),
    shape: FitShape,
    gathering: Option<(Geometry, &GatherSetup)>,
) -> Result<LobeMap> {
    let t = Instant::now();
    let splat_count = u32::try_from(splats.len())
        .map_err(|_| Error::Invalid("too many splats for the lobe fit".into()))?;
    let mut ex = match gathering {
        Some((geo, _)) => CpuExecutor::tracing(geo),
        None => CpuExecutor::default(),
    };
    let lights = match gathering {
        Some((_, g)) => Some(ex.upload("lights", g.lights)?),
        None => None,
    };
    let bin_params = ex.uniform("bin params", &bins.params)?;
    let cell_start = ex.upload("bin cell start", &bins.cell_start)?;
    let geom = ex.upload("binned geometry", &bins.geom)?;
    let power = ex.upload("binned power", &bins.power)?;
    let splat_buf = ex.upload("splats", splats)?;
    let material_buf = ex.upload("materials", materials)?;
    let deposit_bufs = match deposits {
        Some(d) => Some((
            ex.uniform("deposit params", &d.params)?,
            ex.upload("deposit keys", &d.bins.keys)?,
            ex.upload("deposit spread", &d.spread)?,
        )),
        None => None,
    };
    let input = FitInput {
        bin_params: &bin_params,
        cell_start: &cell_start,
        geom: &geom,
        power: &power,
        splats: &splat_buf,
        materials: &material_buf,
        splat_count,
        gathering: gathering
            .zip(lights.as_ref())
            .map(|((_, setup), lights)| Gathering {
                setup,
                lights,
                splats,
                batch_bytes: GATHER_BATCH_BYTES,
            }),
        deposits: deposit_bufs
            .as_ref()
            .map(|(params, keys, spread)| DepositInput {
                reach: deposits.map_or(0.0, |d| d.params.reach),
                params,
                keys,
                spread,
            }),
        groups: None,
        cover: None,
    };
    let fit = sequence::fit_lobes(&mut ex, &input, cfg, shape)?;
    fit.read_back(&mut ex, cfg.lobes, splat_count, fit.stats(ms_since(t)))
}
