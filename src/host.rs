//! The bake's passes from host data to host data, written once over any executor: what the
//! renderer's engine runs for the parity tests, the benchmarks and the tools that hold their
//! photons, bins and lobes in host memory (`renderer::Engine`'s `bin_photons`,
//! `deposit_photons`, `fit_lobes`; `Renderer`'s `trace_photons`, `photon_view` and
//! `fit_lobes`, which trace its scene). Each uploads its input, runs the `sequence` of the
//! pass within the executor's `BakeLimits` and reads the result back. The bake itself
//! (`bake`) keeps everything in the executor's memory between passes.

use std::time::Instant;

use crate::bins::{DepositBins, PhotonBins, check_binned};
use crate::em::{EmConfig, GatherSetup, LobeMap};
use crate::error::{Error, Result};
use crate::photons::{PhotonConfig, emitters, page_photons};
use crate::plan::BakeLimits;
use crate::sequence::{self, DepositInput, Executor, FitInput, Gathering, Traced};
use crate::timing::ms_since;
use crate::types::{BinParams, DepositParams, GridParams, Light, Material, Photon, Splat};

/// Photons in host memory, in the pages they are uploaded as (one page holding them all,
/// or the store pages a device traced them into).
pub type PhotonPages<'a> = &'a [&'a [Photon]];

/// What a fit reads: binned photons, or binned deposits (`bins` then the deposits' bins,
/// every splat's irradiance from `deposit_share`).
#[derive(Clone, Copy)]
pub struct FitFrom<'a> {
    pub bins: &'a PhotonBins,
    pub deposits: Option<&'a DepositBins>,
}

impl<'a> FitFrom<'a> {
    /// A fit to binned photons.
    pub fn photons(bins: &'a PhotonBins) -> FitFrom<'a> {
        FitFrom {
            bins,
            deposits: None,
        }
    }

    /// A fit to binned deposits.
    pub fn deposits(deposits: &'a DepositBins) -> FitFrom<'a> {
        FitFrom {
            bins: &deposits.bins,
            deposits: Some(deposits),
        }
    }
}

fn count(len: usize, what: &str) -> Result<u32> {
    u32::try_from(len).map_err(|_| Error::Invalid(format!("too many {what}")))
}

/// Uploads `pages`, each its buffer and photon count.
fn upload_pages<E: Executor>(ex: &mut E, pages: PhotonPages) -> Result<Vec<(E::Buffer, u32)>> {
    pages
        .iter()
        .map(|page| {
            Ok((
                ex.upload("photons", page)?,
                count(page.len(), "photons in a page")?,
            ))
        })
        .collect()
}

/// Traces `cfg.photons` photons from `lights` (`sequence::trace_photons`) through the scene
/// the executor traces, with their `materials`, in pages of at most `limits.photon_page`
/// photons, which stay in the executor's memory. `progress` hears (paths done, total).
pub fn trace<E: Executor>(
    ex: &mut E,
    limits: &BakeLimits,
    (lights, materials): (&[Light], &E::Buffer),
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Traced<E::Buffer>> {
    cfg.validate()?;
    let emitters = emitters(lights, cfg.photons)?;
    let max_page = page_photons(cfg, limits.photon_page);
    sequence::trace_photons(ex, &emitters, materials, cfg, max_page, progress)
}

/// Bins the photons of `pages`, which landed on `splats` (`sequence::bin_photons`).
pub fn bin_photons<E: Executor>(
    ex: &mut E,
    limits: &BakeLimits,
    params: &BinParams,
    pages: PhotonPages,
    splats: &[Splat],
) -> Result<PhotonBins> {
    let total: u64 = pages.iter().map(|p| p.len() as u64).sum();
    check_binned(total, limits.binned_bytes)?;
    let uploaded = upload_pages(ex, pages)?;
    let pages: Vec<(&E::Buffer, u32)> = uploaded.iter().map(|(b, n)| (b, *n)).collect();
    let splats = ex.upload("splats", splats)?;
    sequence::bin_photons(ex, &pages, &splats, params)?.read_back(ex)
}

/// The deposits of the photons of `pages`, which landed on `splats`, binned over `grid`'s
/// box (`sequence::deposit_photons`), at most `limits.deposit_range` splats' deposits in one
/// buffer.
pub fn deposit_photons<E: Executor>(
    ex: &mut E,
    limits: &BakeLimits,
    params: &DepositParams,
    pages: PhotonPages,
    (splats, grid): (&[Splat], &GridParams),
) -> Result<DepositBins> {
    let uploaded = upload_pages(ex, pages)?;
    let pages: Vec<(&E::Buffer, u32)> = uploaded.iter().map(|(b, n)| (b, *n)).collect();
    let splat_buf = ex.upload("splats", splats)?;
    let range = (grid, limits.deposit_range);
    let d = sequence::deposit_photons(ex, &pages, &splat_buf, params, range)?;
    Ok(DepositBins {
        params: d.params,
        bins: d.bins.read_back(ex)?,
        spread: ex.read(&d.spread, splats.len())?,
    })
}

/// The lobe fit of `splats` (with their `materials`) to `from`, in `limits.fit_shape`
/// (`fit_select`, then `em_fit` over the same dispatch ranges and sum order on every
/// executor); with final gathering of `gathering`'s lights through the scene the executor
/// traces where it is given.
pub fn fit_lobes<E: Executor>(
    ex: &mut E,
    limits: &BakeLimits,
    cfg: &EmConfig,
    from: FitFrom,
    (splats, materials): (&[Splat], &[Material]),
    gathering: Option<&GatherSetup>,
) -> Result<LobeMap> {
    cfg.validate()?;
    let t = Instant::now();
    let splat_count = count(splats.len(), "splats for the lobe fit")?;
    let lights = match gathering {
        Some(g) => Some(ex.upload("lights", g.lights)?),
        None => None,
    };
    let bins = from.bins;
    let bin_params = ex.uniform("bin params", &bins.params)?;
    let cell_start = ex.upload("bin cell start", &bins.cell_start)?;
    let geom = ex.upload("binned geometry", &bins.geom)?;
    let power = ex.upload("binned power", &bins.power)?;
    let splat_buf = ex.upload("splats", splats)?;
    let material_buf = ex.upload("materials", materials)?;
    let deposit_bufs = match from.deposits {
        Some(d) => Some((
            d.params.reach,
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
            .map(|(setup, lights)| Gathering {
                setup,
                lights,
                splats,
                batch_bytes: limits.gather_batch_bytes,
            }),
        deposits: deposit_bufs
            .as_ref()
            .map(|(reach, params, keys, spread)| DepositInput {
                reach: *reach,
                params,
                keys,
                spread,
            }),
        groups: None,
        cover: None,
    };
    let fit = sequence::fit_lobes(ex, &input, cfg, limits.fit_shape)?;
    ex.finish()?;
    let stats = fit.stats(ms_since(t));
    fit.read_back(ex, cfg.lobes, splat_count, stats)
}
