//! The photons' estimate at each splat: binning, deposits, the light shared once a coverage
//! group, the covered share of the gather disk, and the smoothing.

use crate::bins::PhotonBins;
use crate::error::{Error, Result};
use crate::shaders::{Pass, Stage};
use crate::shared::bins::list_count;
use crate::types::{BinParams, DepositParams, EmParams, GridParams, Photon};

use super::{Executor, exclusive_scan, groups};

/// Binned photons where they were binned (see `bins::PhotonBins`).
pub struct Bins<B> {
    /// The binning's settings, with the photon count.
    pub params: BinParams,
    pub params_buf: B,
    pub cell_start: B,
    pub keys: B,
    pub geom: B,
    pub power: B,
    /// `bin_rank` dispatches the longest cell list needed.
    pub rank_chunks: u32,
}

impl<B> Bins<B> {
    /// The binned photons in host memory.
    pub fn read_back<E: Executor<Buffer = B>>(&self, ex: &mut E) -> Result<PhotonBins> {
        let n = self.params.photon_count as usize;
        Ok(PhotonBins {
            params: self.params,
            cell_start: ex.read(&self.cell_start, list_count(&self.params) as usize + 1)?,
            keys: ex.read(&self.keys, n)?,
            geom: ex.read(&self.geom, n)?,
            power: ex.read(&self.power, n)?,
        })
    }
}

/// Photon binning of the stored photons in `pages` (a buffer and its photon count each):
/// `bin_count` per page → exclusive scan → `bin_scatter` per page → (split: the longest cell
/// list sets the rank chunks) → `bin_rank` per chunk → `bin_place`. Every list (a cell's
/// sub-cell, `BinParams::sub`) comes out in key order.
pub fn bin_photons<E: Executor>(
    ex: &mut E,
    pages: &[(&E::Buffer, u32)],
    splats: &E::Buffer,
    params: &BinParams,
) -> Result<Bins<E::Buffer>> {
    let total: u64 = pages.iter().map(|p| p.1 as u64).sum();
    let n = u32::try_from(total).map_err(|_| Error::Invalid("too many photons to bin".into()))?;
    let mut page_params = Vec::with_capacity(pages.len());
    for &(_, count) in pages {
        let page = BinParams {
            photon_count: count,
            ..*params
        };
        page_params.push(ex.uniform("bin page params", &page)?);
    }
    let lists = list_count(params) as u64;
    let cell_start = ex.zeroed("bin cell start", (lists + 1) * 4)?;
    let chunks = ex.zeroed("bin rank chunks", 4)?;
    for (&(page, count), uniform) in pages.iter().zip(&page_params) {
        let bindings = [uniform, page, &cell_start, &chunks];
        ex.dispatch(Stage::BinCount, &bindings, groups(Stage::BinCount, count)?)?;
    }
    exclusive_scan(ex, &cell_start, lists as u32 + 1)?;

    // Entries to allocate (at least one: empty bindings are invalid).
    let len = total.max(1);
    let cursor = ex.zeroed("bin cursor", lists * 4)?;
    let scratch_keys = ex.zeroed("bin scratch keys", len * 8)?;
    let scratch_cells = ex.zeroed("bin scratch cells", len * 4)?;
    let scratch_geom = ex.zeroed("bin scratch geometry", len * 16)?;
    let scratch_power = ex.zeroed("bin scratch power", len * 16)?;
    for (&(page, count), uniform) in pages.iter().zip(&page_params) {
        let bindings = [
            uniform,
            page,
            &cell_start,
            &cursor,
            &scratch_keys,
            &scratch_cells,
            &scratch_geom,
            &scratch_power,
            splats,
        ];
        ex.dispatch(
            Stage::BinScatter,
            &bindings,
            groups(Stage::BinScatter, count)?,
        )?;
    }
    let rank_chunks = match ex.read::<u32>(&chunks, 1)?[..] {
        [c] => c,
        _ => return Err(Error::Gpu("bin chunk readback was short".into())),
    };

    let params = BinParams {
        photon_count: n,
        ..*params
    };
    let slots = ex.zeroed("bin slots", len * 4)?;
    for chunk in 0..rank_chunks {
        let pass = BinParams {
            rank_chunk: chunk,
            ..params
        };
        let pass = ex.uniform("bin rank params", &pass)?;
        let bindings = [&pass, &cell_start, &scratch_keys, &scratch_cells, &slots];
        ex.dispatch(Stage::BinRank, &bindings, groups(Stage::BinRank, n)?)?;
    }
    let params_buf = ex.uniform("bin params", &params)?;
    let keys = ex.zeroed("binned keys", len * 8)?;
    let geom = ex.zeroed("binned geometry", len * 16)?;
    let power = ex.zeroed("binned power", len * 16)?;
    let bindings = [
        &params_buf,
        &slots,
        &scratch_keys,
        &scratch_geom,
        &scratch_power,
        &keys,
        &geom,
        &power,
    ];
    ex.dispatch(Stage::BinPlace, &bindings, groups(Stage::BinPlace, n)?)?;
    Ok(Bins {
        params,
        params_buf,
        cell_start,
        keys,
        geom,
        power,
        rank_chunks,
    })
}

/// Per-splat photon deposits (design §6, "Deposits"), listed as one record a splat with
/// photons and binned as photons are, for `deposit_share`.
pub struct Deposits<B> {
    pub params: DepositParams,
    pub params_buf: B,
    /// The records binned: key (splat, 0), their photons' mean position, total power.
    pub bins: Bins<B>,
    /// Per splat: its photons' spread (the radius of a uniform disk as spread) and count.
    pub spread: B,
}

/// Photon deposits of the stored photons in `pages` (a buffer and its photon count each),
/// with at most `range` splats' deposits in one buffer: per range of splats, `deposit_add` per
/// photon page → `deposit_list` → (split: the ranges' record counts) → `bin_photons` of
/// the records, one page a range, in cells of `params.reach` over `grid`'s box.
pub fn deposit_photons<E: Executor>(
    ex: &mut E,
    pages: &[(&E::Buffer, u32)],
    splats: &E::Buffer,
    params: &DepositParams,
    (grid, range): (&GridParams, u32),
) -> Result<Deposits<E::Buffer>> {
    let n = params.splat_count;
    let words = crate::shared::deposits::DEPOSIT_WORDS as u64;
    let range = range.max(1);
    // A range lists at most one record a photon: a scan of many splats lit by few photons
    // allocates no list for the dark ones.
    let stored: u64 = pages.iter().map(|p| p.1 as u64).sum();
    let params_buf = ex.uniform("deposit params", params)?;
    let spread = ex.zeroed("deposit spread", (n as u64).max(1) * 8)?;
    let mut lists = Vec::new();
    for first in (0..n.max(1)).step_by(range as usize) {
        let count = range.min(n - first.min(n));
        let in_range = DepositParams {
            first_splat: first,
            splat_count: count,
            ..*params
        };
        let deposits = ex.zeroed("deposits", (count as u64).max(1) * words * 4)?;
        for &(page, photons) in pages {
            let page_params = DepositParams {
                photon_count: photons,
                ..in_range
            };
            let uniform = ex.uniform("deposit page params", &page_params)?;
            let bindings = [&uniform, page, splats, &deposits];
            ex.dispatch(
                Stage::DepositAdd,
                &bindings,
                groups(Stage::DepositAdd, photons)?,
            )?;
        }
        let uniform = ex.uniform("deposit range params", &in_range)?;
        let records = (count as u64).min(stored).max(1);
        let list = ex.zeroed("deposit list", records * size_of::<Photon>() as u64)?;
        let listed = ex.zeroed("deposits listed", 4)?;
        let bindings = [&uniform, splats, &deposits, &list, &spread, &listed];
        ex.dispatch(
            Stage::DepositList,
            &bindings,
            groups(Stage::DepositList, count)?,
        )?;
        lists.push((list, listed));
    }
    let mut records = Vec::with_capacity(lists.len());
    for (list, listed) in &lists {
        match ex.read::<u32>(listed, 1)?[..] {
            [c] => records.push((list, c)),
            _ => return Err(Error::Gpu("deposit count readback was short".into())),
        }
    }
    let total: u64 = records.iter().map(|r| r.1 as u64).sum();
    let bin = crate::bins::bin_params(grid, params.reach, total)?;
    let bins = bin_photons(ex, &records, splats, &bin)?;
    Ok(Deposits {
        params: *params,
        params_buf,
        bins,
        spread,
    })
}

/// Where `estimate_smooth` finds a splat's neighbours: the binned deposits' records (their
/// parameters, the bins' parameters, list starts and keys) and the splats.
pub struct Records<'a, B> {
    pub deposit_params: &'a B,
    pub bin_params: &'a B,
    pub splats: &'a B,
    pub cell_start: &'a B,
    pub keys: &'a B,
}

/// The coverage groups in the executor's memory (`fit_groups::CoverGroups::words`).
pub struct CoverInput<'a, B> {
    pub words: &'a B,
    pub groups: u32,
}

/// What `deposit_share` reads: the binned deposits (their parameters, the bins' parameters, list
/// starts, keys, geometry and power, each splat's spread) and the splats and materials.
pub struct SharedDeposits<'a, B> {
    pub deposit_params: &'a B,
    pub bin_params: &'a B,
    pub splats: &'a B,
    pub materials: &'a B,
    pub cell_start: &'a B,
    pub keys: &'a B,
    pub geom: &'a B,
    pub power: &'a B,
    pub spread: &'a B,
}

/// `deposit_share`: each of `params.splat_count` splats' photon irradiance from the deposits around
/// it into `light`, summed once a group of `cover` (once a splat without) at its leader and
/// copied to the members; the splats lit that are not fitted counted in `counters[3]`.
pub fn share_light<E: Executor>(
    ex: &mut E,
    params: &EmParams,
    d: &SharedDeposits<E::Buffer>,
    (light, counters): (&E::Buffer, &E::Buffer),
    cover: Option<&CoverInput<'_, E::Buffer>>,
) -> Result<()> {
    let n = params.splat_count;
    let mut own = None;
    let (words, count) = group_words(ex, cover, n, &mut own)?;
    for (pass, p, invocations) in group_passes(Stage::DepositShare, "copy", params, count) {
        let uniform = ex.uniform("em share params", &p)?;
        let bindings = [
            &uniform,
            d.deposit_params,
            d.bin_params,
            d.splats,
            d.materials,
            counters,
            d.cell_start,
            d.keys,
            d.geom,
            d.power,
            d.spread,
            light,
            words,
        ];
        let groups = groups(Stage::DepositShare, invocations)?;
        ex.dispatch(pass, &bindings, groups)?;
    }
    Ok(())
}

/// `estimate_coverage`: each of `params.splat_count` splats' photon irradiance in `light` divided
/// by the share of its gather disk (radius and slab from `params`) that its surface covers,
/// measured once a group of `cover` (once a splat without); a splat whose lobes the photon fit
/// wrote keeps its light (the lobes carry their own). The executor must trace the scene's geometry.
pub fn cover_light<E: Executor>(
    ex: &mut E,
    params: &EmParams,
    light: &E::Buffer,
    cover: Option<&CoverInput<'_, E::Buffer>>,
) -> Result<()> {
    let mut own = None;
    let (words, count) = group_words(ex, cover, params.splat_count, &mut own)?;
    let shares = ex.zeroed("coverage shares", count.max(1) as u64 * 4)?;
    for (pass, p, invocations) in group_passes(Stage::EstimateCoverage, "apply", params, count) {
        let uniform = ex.uniform("em coverage params", &p)?;
        let bindings = [&uniform, light, words, &shares];
        let groups = groups(Stage::EstimateCoverage, invocations)?;
        ex.dispatch_traced(pass, &bindings, groups)?;
    }
    Ok(())
}

/// A stage's two passes over coverage groups, each pass's entry point, uniform and
/// invocations: its `main` once a group (`groups` of them, at the leaders), its entry point
/// `second` once a splat.
fn group_passes(
    stage: Stage,
    second: &'static str,
    params: &EmParams,
    groups: u32,
) -> [(Pass, EmParams, u32); 2] {
    let first = EmParams {
        active_count: groups,
        ..*params
    };
    [
        (stage.into(), first, groups),
        (stage.entry(second), *params, params.splat_count),
    ]
}

/// The coverage groups' words and their count: `cover`'s, else groups of one splat each, its
/// own leader (`CoverGroups::words`' layout), uploaded into `own`.
fn group_words<'b, E: Executor>(
    ex: &mut E,
    cover: Option<&CoverInput<'b, E::Buffer>>,
    n: u32,
    own: &'b mut Option<E::Buffer>,
) -> Result<(&'b E::Buffer, u32)> {
    match cover {
        Some(c) => Ok((c.words, c.groups)),
        None => {
            let words: Vec<u32> = (0..n).chain(0..n).collect();
            let buffer = own.insert(ex.upload("one splat a group", &words)?);
            Ok((&*buffer, n))
        }
    }
}

/// `estimate_smooth` (design §6, "Smoothing"): each splat's photon irradiance, the least noisy of
/// its own and planes fitted to its surface's estimates within half of and all of the widest
/// kernel that agree with it within their noise, chosen once a group of `cover` (once a splat
/// without). Two passes: the first chooses at each group's leader from the neighbours' light
/// into a buffer of its own, the second reads the group's plane at each member into `light`.
/// Returns the smoothed splats by the scale they took (own, half, widest) and how many of them
/// took a choice from an even subset of its box's records (past `SMOOTH_BUDGET`).
pub fn smooth_light<E: Executor>(
    ex: &mut E,
    params: &EmParams,
    records: &Records<E::Buffer>,
    light: &E::Buffer,
    cover: Option<&CoverInput<'_, E::Buffer>>,
) -> Result<[u32; 4]> {
    let n = params.splat_count;
    let mut own = None;
    let (words, count) = group_words(ex, cover, n, &mut own)?;
    let smoothed = ex.zeroed("smoothing choices", count.max(1) as u64 * 48)?;
    let counters = ex.zeroed("smoothing counters", 16)?;
    for (pass, p, invocations) in group_passes(Stage::EstimateSmooth, "apply", params, count) {
        let uniform = ex.uniform("em smooth params", &p)?;
        let bindings = [
            &uniform,
            records.deposit_params,
            records.bin_params,
            records.splats,
            records.cell_start,
            records.keys,
            light,
            &smoothed,
            &counters,
            words,
        ];
        let groups = groups(Stage::EstimateSmooth, invocations)?;
        ex.dispatch(pass, &bindings, groups)?;
    }
    match ex.read::<u32>(&counters, 4)?[..] {
        [a, b, c, d] => Ok([a, b, c, d]),
        _ => Err(Error::Gpu("smoothing counters readback was short".into())),
    }
}
