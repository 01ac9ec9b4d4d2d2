//! Each multi-dispatch stage's sequence of dispatches, written once. A sequence is generic over
//! an `Executor`: the device's (`gpu::GpuExecutor`, which records into a command encoder) or
//! the CPU mirror's (`cpu::CpuExecutor`, which runs each stage's mirror at once). Both run the
//! same dispatches in the same order with the same group counts, taken from the WGSL
//! (`shaders::stage_shape`). A readback that decides later work (`Executor::read`) is an
//! explicit split point: the device submits what it recorded and waits.
//!
//! docs/architecture.md §3 lists the sequences and their split points.

use bytemuck::Pod;

use crate::bins::PhotonBins;
use crate::em::{
    EmConfig, EmStats, FitShape, GatherSetup, LobeMap, dispatch_ranges, iterations_per_dispatch,
    workgroup_size,
};
use crate::error::{Error, Result};
use crate::grid::SplatGrid;
use crate::grid::check_cell_len;
use crate::photons::{
    PhotonConfig, PhotonMap, PhotonStats, StoreAction, StorePlanner, first_capacity,
};
use crate::shaders::Stage;
use crate::shaders::stage_shape;
use crate::shared::bins::list_count;
use crate::shared::dispatch::groups_for;
use crate::shared::lobes::{
    EM_COVER_APPLY, EM_DEFER_FIT, EM_GROUPS, EM_SHARE, EM_SHARE_COPY, EM_SMOOTH_APPLY,
};
use crate::timing::ms_since;
use crate::tone::{ToneConfig, reduce_levels};
use crate::types::{
    BinParams, Camera, DepositParams, DirectParams, DistanceParams, EmParams, Emitter,
    GatherParams, GridParams, Lobe, PathParams, Photon, PhotonViewParams, ScanParams, Splat,
    SplatLight, TemporalParams, TileParams, TraceCounters,
};

/// Where a sequence runs: buffers, uniforms, dispatches by stage name, copies and readbacks.
pub trait Executor {
    type Buffer: Clone;
    /// A zeroed buffer of `bytes` bytes (at least one 4-byte word).
    fn zeroed(&mut self, label: &'static str, bytes: u64) -> Result<Self::Buffer>;
    /// A buffer holding `data` (one zeroed element when it is empty).
    fn upload<T: Pod>(&mut self, label: &'static str, data: &[T]) -> Result<Self::Buffer>;
    /// A uniform holding `value`.
    fn uniform<T: Pod>(&mut self, label: &'static str, value: &T) -> Result<Self::Buffer>;
    /// One dispatch of `stage` over `groups` workgroups, `bindings` in binding order.
    fn dispatch(&mut self, stage: Stage, bindings: &[&Self::Buffer], groups: u32) -> Result<()>;
    /// `dispatch` of a tracing stage, whose bind group 1 is the scene's geometry (splats and
    /// grid) that the executor was made with.
    fn dispatch_traced(
        &mut self,
        stage: Stage,
        bindings: &[&Self::Buffer],
        groups: u32,
    ) -> Result<()>;
    /// `dispatch` of the stage's variant with `defines` and pipeline-overridable `constants`
    /// (the mirrors read the same settings from the stage's parameters).
    fn dispatch_variant(
        &mut self,
        stage: Stage,
        defines: &[&'static str],
        constants: &[(&'static str, f64)],
        bindings: &[&Self::Buffer],
        groups: u32,
    ) -> Result<()>;
    /// Copies `bytes` bytes between two buffers.
    fn copy(
        &mut self,
        src: &Self::Buffer,
        src_offset: u64,
        dst: &Self::Buffer,
        dst_offset: u64,
        bytes: u64,
    ) -> Result<()>;
    /// A split point: what is recorded runs, then the first `count` values of `buffer` come
    /// back.
    fn read<T: Pod>(&mut self, buffer: &Self::Buffer, count: usize) -> Result<Vec<T>>;
    /// A split point with nothing read: what is recorded runs, and is done when this returns
    /// (a stage's time ends here).
    fn finish(&mut self) -> Result<()>;
}

/// Workgroups of `stage` that cover `n` values (its WGSL's workgroup size × items).
pub fn groups(stage: Stage, n: u32) -> Result<u32> {
    Ok(groups_for(n, stage_shape(stage)?.per_group(stage)?))
}

/// Exclusive scan of the first `len` values of `values` in place: `scan_reduce` writes one sum
/// per block, the block sums are scanned recursively, and `scan_apply` finishes each block.
pub fn exclusive_scan<E: Executor>(ex: &mut E, values: &E::Buffer, len: u32) -> Result<()> {
    let blocks = groups(Stage::ScanReduce, len)?;
    let params = ScanParams {
        len,
        ..Default::default()
    };
    let params = ex.uniform("scan params", &params)?;
    if blocks <= 1 {
        let zero = ex.upload("scan zero offset", &[0u32])?;
        return ex.dispatch(Stage::ScanApply, &[&params, values, &zero], blocks);
    }
    let block_sums = ex.zeroed("scan block sums", blocks as u64 * 4)?;
    ex.dispatch(Stage::ScanReduce, &[&params, values, &block_sums], blocks)?;
    exclusive_scan(ex, &block_sums, blocks)?;
    ex.dispatch(Stage::ScanApply, &[&params, values, &block_sums], blocks)
}

/// A tone-mapped image where it was made.
pub struct Toned<B> {
    /// RGBA8 sRGB, one u32 per pixel.
    pub rgba: B,
    /// (Σ log(ε + Y), count) over the finite pixels.
    pub log_sum: B,
}

/// Tone mapping of `pixels` HDR pixels (`vec4<f32>` each): `tonemap_reduce` level by level
/// down to one (Σ log, count), then `tonemap_apply` per pixel.
pub fn tone_map<E: Executor>(
    ex: &mut E,
    hdr: &E::Buffer,
    pixels: u32,
    cfg: &ToneConfig,
) -> Result<Toned<E::Buffer>> {
    cfg.validate()?;
    let sums_in = log_sum(ex, hdr, pixels, cfg)?;
    let rgba = ex.zeroed("tone-mapped image", pixels.max(1) as u64 * 4)?;
    let params = ex.uniform("tone params", &cfg.params(pixels, 0))?;
    let bindings = [&params, hdr, &sums_in, &rgba];
    ex.dispatch(
        Stage::TonemapApply,
        &bindings,
        groups(Stage::TonemapApply, pixels)?,
    )?;
    Ok(Toned {
        rgba,
        log_sum: sums_in,
    })
}

/// The log-average's sum of `pixels` HDR pixels, (Σ log(ε + Y), count) over the finite ones, in
/// a buffer of one `vec2<f32>`: `tonemap_reduce` level by level down to one.
pub fn log_sum<E: Executor>(
    ex: &mut E,
    hdr: &E::Buffer,
    pixels: u32,
    cfg: &ToneConfig,
) -> Result<E::Buffer> {
    let block = stage_shape(Stage::TonemapReduce)?.per_group(Stage::TonemapReduce)?;
    let mut sums_in = ex.zeroed("tone sums", 8)?;
    for (level, &count) in reduce_levels(pixels, block).iter().enumerate() {
        let blocks = groups_for(count, block).max(1);
        let sums_out = ex.zeroed("tone sums", blocks as u64 * 8)?;
        let params = ex.uniform("tone params", &cfg.params(count, level as u32))?;
        let bindings = [&params, hdr, &sums_in, &sums_out];
        ex.dispatch(Stage::TonemapReduce, &bindings, blocks)?;
        sums_in = sums_out;
    }
    Ok(sums_in)
}

/// The moving frames' history buffers of one frame: the resolved image (w: the frames it
/// holds) and the surface each pixel kept.
pub struct TemporalHistory<'a, B> {
    pub image: &'a B,
    pub surface: &'a B,
}

/// Temporal anti-aliasing of a moving frame (`temporal`): `hdr` and its `surface`, drawn with
/// `cam`, blended into `last` (drawn with `prev`), resolved into `next`, whose image is then
/// copied into `hdr`. The frame's log-average (`log_sum`) sets the scale of the pass's weights.
#[allow(clippy::too_many_arguments)]
pub fn temporal<E: Executor>(
    ex: &mut E,
    cam: &Camera,
    prev: &Camera,
    params: &TemporalParams,
    hdr: &E::Buffer,
    surface: &E::Buffer,
    last: TemporalHistory<E::Buffer>,
    next: TemporalHistory<E::Buffer>,
) -> Result<()> {
    let pixels = params.width * params.height;
    let cam_buf = ex.uniform("camera", cam)?;
    let prev_buf = ex.uniform("last camera", prev)?;
    let params_buf = ex.uniform("temporal params", params)?;
    let frame_log_sum = log_sum(ex, hdr, pixels, &ToneConfig::default())?;
    let bindings = [
        &cam_buf,
        &prev_buf,
        &params_buf,
        hdr,
        surface,
        last.image,
        last.surface,
        next.image,
        next.surface,
        &frame_log_sum,
    ];
    ex.dispatch(Stage::Temporal, &bindings, groups(Stage::Temporal, pixels)?)?;
    ex.copy(next.image, 0, hdr, 0, pixels as u64 * 16)
}

/// A splat grid where it was built.
pub struct BuiltGrid<B> {
    /// The grid's settings, with the entry count the build found.
    pub params: GridParams,
    pub params_buf: B,
    /// `cell_count + 1` offsets into `cell_splats`.
    pub cell_start: B,
    pub cell_splats: B,
    /// Distance field for empty-space skipping (see `SplatGrid::cell_dist`).
    pub cell_dist: B,
}

impl<B> BuiltGrid<B> {
    /// The grid in host memory.
    pub fn read_back<E: Executor<Buffer = B>>(&self, ex: &mut E) -> Result<SplatGrid> {
        let cells = self.params.cell_count as usize;
        Ok(SplatGrid {
            params: self.params,
            cell_start: ex.read(&self.cell_start, cells + 1)?,
            cell_splats: ex.read(&self.cell_splats, self.params.entry_count as usize)?,
            cell_dist: ex.read(&self.cell_dist, cells)?,
        })
    }
}

/// The grid build: count → exclusive scan → (split: the entry total sizes the list, the
/// longest cell is checked) → scatter → rank → the distance field's passes x, y, z → the
/// listed cells' facing cones.
pub fn build_grid<E: Executor>(
    ex: &mut E,
    params: &GridParams,
    splats: &E::Buffer,
) -> Result<BuiltGrid<E::Buffer>> {
    let params_buf = ex.uniform("grid params", params)?;
    let cells = params.cell_count as u64;
    let cell_start = ex.zeroed("cell start", (cells + 1) * 4)?;
    let max_cell_len = ex.zeroed("grid max cell length", 4)?;
    let splat_groups = groups(Stage::GridCount, params.splat_count)?;
    let bindings = [&params_buf, splats, &cell_start, &max_cell_len];
    ex.dispatch(Stage::GridCount, &bindings, splat_groups)?;
    exclusive_scan(ex, &cell_start, params.cell_count + 1)?;
    // stats = [entry total (last scan value), longest cell list]
    let stats = ex.zeroed("grid stats", 8)?;
    ex.copy(&cell_start, cells * 4, &stats, 0, 4)?;
    ex.copy(&max_cell_len, 0, &stats, 4, 4)?;
    let (entries, max_cell_len) = match ex.read::<u32>(&stats, 2)?[..] {
        [e, m] => (e, m),
        _ => return Err(Error::Gpu("grid stats readback was short".into())),
    };
    check_cell_len(max_cell_len)?;

    let params = GridParams {
        entry_count: entries,
        ..*params
    };
    let params_buf = ex.uniform("grid params", &params)?;
    let bytes = entries as u64 * 4;
    let cursor = ex.zeroed("cell cursor", cells * 4)?;
    let scratch_splats = ex.zeroed("scratch splats", bytes)?;
    let scratch_cells = ex.zeroed("scratch cells", bytes)?;
    let cell_splats = ex.zeroed("cell splats", bytes)?;
    let bindings = [
        &params_buf,
        splats,
        &cell_start,
        &cursor,
        &scratch_splats,
        &scratch_cells,
    ];
    ex.dispatch(
        Stage::GridScatter,
        &bindings,
        groups(Stage::GridScatter, params.splat_count)?,
    )?;
    let bindings = [
        &params_buf,
        &cell_start,
        &scratch_splats,
        &scratch_cells,
        &cell_splats,
    ];
    ex.dispatch(
        Stage::GridRank,
        &bindings,
        groups(Stage::GridRank, entries)?,
    )?;
    let cell_dist = distance_field(ex, &params_buf, &params, &cell_start)?;
    let bindings = [&params_buf, splats, &cell_start, &cell_splats, &cell_dist];
    ex.dispatch(
        Stage::GridCone,
        &bindings,
        groups(Stage::GridCone, params.cell_count)?,
    )?;
    Ok(BuiltGrid {
        params,
        params_buf,
        cell_start,
        cell_splats,
        cell_dist,
    })
}

/// Passes x, y, z of `grid_distance`, ping-ponging between two buffers; returns the field.
fn distance_field<E: Executor>(
    ex: &mut E,
    grid: &E::Buffer,
    params: &GridParams,
    cell_start: &E::Buffer,
) -> Result<E::Buffer> {
    let bytes = params.cell_count as u64 * 4;
    let a = ex.zeroed("cell distance", bytes)?;
    let b = ex.zeroed("cell distance scratch", bytes)?;
    let groups = groups(Stage::GridDistance, params.cell_count)?;
    let passes: [(u32, &E::Buffer, &E::Buffer); 3] =
        [(0, cell_start, &a), (1, &a, &b), (2, &b, &a)];
    for (axis, src, dst) in passes {
        let pass = DistanceParams {
            axis,
            ..Default::default()
        };
        let pass = ex.uniform("distance pass", &pass)?;
        ex.dispatch(
            Stage::GridDistance,
            &[&pass, grid, cell_start, src, dst],
            groups,
        )?;
    }
    Ok(a)
}

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
/// photons and binned as photons are, for `em_share`.
pub struct Deposits<B> {
    pub params: DepositParams,
    pub params_buf: B,
    /// The records binned: key (splat, 0), their photons' mean position, total power.
    pub bins: Bins<B>,
    /// Per splat: its photons' spread (the radius of a uniform disk as spread) and count.
    pub spread: B,
}

/// Photon deposits of the stored photons in `pages` (a buffer and its photon count each),
/// with at most `range` splats' deposits in one buffer: per range of splats, `em_deposit` per
/// photon page → `em_deposit_list` → (split: the ranges' record counts) → `bin_photons` of
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
                Stage::EmDeposit,
                &bindings,
                groups(Stage::EmDeposit, photons)?,
            )?;
        }
        let uniform = ex.uniform("deposit range params", &in_range)?;
        let records = (count as u64).min(stored).max(1);
        let list = ex.zeroed("deposit list", records * size_of::<Photon>() as u64)?;
        let listed = ex.zeroed("deposits listed", 4)?;
        let bindings = [&uniform, splats, &deposits, &list, &spread, &listed];
        ex.dispatch(
            Stage::EmDepositList,
            &bindings,
            groups(Stage::EmDepositList, count)?,
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

/// What `em_share` reads besides the binned records (`FitInput`'s bins are then the
/// deposits' bins).
pub struct DepositInput<'a, B> {
    /// `DepositParams::reach`: `em_select` lists the splats with deposits within it.
    pub reach: f32,
    pub params: &'a B,
    pub keys: &'a B,
    pub spread: &'a B,
}

/// Where `em_smooth` finds a splat's neighbours: the binned deposits' records (their
/// parameters, the bins' parameters, list starts and keys) and the splats.
pub struct Records<'a, B> {
    pub deposit_params: &'a B,
    pub bin_params: &'a B,
    pub splats: &'a B,
    pub cell_start: &'a B,
    pub keys: &'a B,
}

/// What the lobe fit reads of the binned photons.
pub struct FitInput<'a, B> {
    pub bin_params: &'a B,
    pub cell_start: &'a B,
    pub geom: &'a B,
    pub power: &'a B,
    /// The splats and their materials.
    pub splats: &'a B,
    pub materials: &'a B,
    pub splat_count: u32,
    /// Final gathering for the fitted splats' lobes, with `EmConfig::gather` rays a side; the
    /// executor then traces the scene's splats.
    pub gathering: Option<Gathering<'a, B>>,
    /// The bins hold deposits, not photons: every splat's irradiance comes from `em_share`
    /// (which needs final gathering: the deposits carry no photon directions to fit).
    pub deposits: Option<DepositInput<'a, B>>,
    /// Shared fits: only the groups' leaders are fitted, from their members' rays.
    pub groups: Option<GroupInput<'a, B>>,
    /// Shared coverage: `em_coverage` measures once a group (else once a splat).
    pub cover: Option<CoverInput<'a, B>>,
}

/// The coverage groups in the executor's memory (`fit_groups::CoverGroups::words`).
pub struct CoverInput<'a, B> {
    pub words: &'a B,
    pub groups: u32,
}

/// The shared fits' groups in the executor's memory (`fit_groups::FitGroups::words`), with
/// where their starts and members lie in it.
pub struct GroupInput<'a, B> {
    pub words: &'a B,
    pub starts_at: u32,
    pub members_at: u32,
}

/// What final gathering needs besides the photons: its setup (`em::GatherSetup`), with the
/// setup's lights where the executor holds them.
pub struct Gathering<'a, B> {
    pub setup: &'a GatherSetup<'a>,
    pub lights: &'a B,
    /// The splats on the host, whose order in space the direct bake takes them in
    /// (`grid::splat_order`, made only where final gathering runs).
    pub splats: &'a [Splat],
    /// The most bytes of samples one batch of splats holds (the rays of the fit list are
    /// cast and fitted a batch at a time).
    pub batch_bytes: u64,
}

/// The lobe fit where it ran: `cfg.lobes` slots a splat (dense, unpacked) and each splat's
/// light, with the counts the selection found.
pub struct Fit<B> {
    pub lobes: B,
    pub light: B,
    /// Splats on the fit list: those fitted, and those not fitted with too many candidates
    /// for one invocation.
    pub listed: u32,
    /// Splats on the gather list (`em_gather`).
    pub gathered: u32,
    pub fitted: u32,
    pub max_candidates: u32,
    pub dispatches: u32,
    /// Wall time of the passes: `em_select` with its readback, `em_gather`, `em_fit`, and
    /// with final gathering the direct bake and `final_gather` (their `em_fit` in `fit_ms`).
    pub select_ms: f64,
    pub gather_ms: f64,
    pub fit_ms: f64,
    pub final_gather_ms: f64,
    /// The direct bake's part of `final_gather_ms`.
    pub direct_bake_ms: f64,
    /// With final gathering, the direct bake its rays read: every splat's, of the setup's
    /// lights, the same as the frames bake (`bake_direct`), so they may take it.
    pub direct: Option<Direct<B>>,
    /// `em_smooth`'s counts (`smooth_light`; zeros where it did not run).
    pub smoothed: [u32; 4],
}

impl<B> Fit<B> {
    /// The fit's figures, `ms` its wall time (`photons` is summed when its lobes are read).
    pub fn stats(&self, ms: f64) -> EmStats {
        EmStats {
            listed: self.listed + self.gathered,
            fitted: self.fitted,
            max_candidates: self.max_candidates,
            photons: 0,
            dispatches: self.dispatches,
            ms,
            select_ms: self.select_ms,
            gather_ms: self.gather_ms,
            fit_ms: self.fit_ms,
            final_gather_ms: self.final_gather_ms,
            direct_bake_ms: self.direct_bake_ms,
            rays: 0,
            served: 0,
            coverages: 0,
            smoothed: self.smoothed,
        }
    }

    /// The fit of `splat_count` splats, `per_splat` lobe slots each, in host memory with its
    /// lobes packed (`LobeMap::pack`); with nothing fitted no lobe is read.
    pub fn read_back<E: Executor<Buffer = B>>(
        &self,
        ex: &mut E,
        per_splat: u32,
        splat_count: u32,
        stats: EmStats,
    ) -> Result<LobeMap> {
        let dense = match self.fitted {
            0 => Vec::new(),
            n => ex.read::<Lobe>(&self.lobes, n as usize * per_splat as usize)?,
        };
        let light = ex.read::<SplatLight>(&self.light, splat_count as usize)?;
        let mut map = LobeMap::pack(per_splat, &dense, light, stats);
        map.stats.photons = map.fitted().map(|l| l.photons as u64).sum();
        Ok(map)
    }
}

/// The lobe fit: `em_select` lists the splats with photons near them, in two lists → (split:
/// the lists' lengths and the most candidates a fit-list splat has, which sizes the
/// dispatches on a loop-limited device) → `em_gather`, one invocation per splat of the gather
/// list (irradiance alone) → `em_fit`, one workgroup per splat of the fit list, in one
/// dispatch or in several that hand the mixture over through the lobe buffer. With final
/// gathering (`cfg.gather` > 0), that `em_fit` gives the fitted splats only their irradiance,
/// then `direct_bake` → `final_gather` from each fitted splat → `em_fit` over those samples.
/// With deposits (`input.deposits`, final gathering only), the bins hold the deposits:
/// `em_share` gives every splat its irradiance in place of `em_gather` and the photon
/// `em_fit`. Wherever the scene's geometry is given (`input.gathering`), `em_coverage` divides
/// every splat's irradiance by the share of its gather disk its surface covers before final
/// gathering, whether or not anything is fitted.
pub fn fit_lobes<E: Executor>(
    ex: &mut E,
    input: &FitInput<E::Buffer>,
    cfg: &EmConfig,
    shape: FitShape,
) -> Result<Fit<E::Buffer>> {
    cfg.validate()?;
    if input.deposits.is_some() && cfg.gather == 0 {
        return Err(Error::Invalid(
            "deposits carry no photon directions: the photon fit (gather 0) needs the \
             photons' estimate"
                .into(),
        ));
    }
    let t = std::time::Instant::now();
    let splat_count = input.splat_count;
    let n = splat_count as u64;
    let light = ex.zeroed("splat light", n.max(1) * 32)?;
    let fit_list = ex.zeroed("fit list", n.max(1) * 8)?;
    let gather_list = ex.zeroed("gather list", n.max(1) * 4)?;
    let counters = ex.zeroed("em counters", 16)?;
    // Without shared fits a word stands in for the groups (no stage reads it).
    let no_groups = ex.zeroed("no fit groups", 4)?;
    let fit_groups = input.groups.as_ref().map_or(&no_groups, |g| g.words);
    let mut select_params = cfg.params(splat_count, 0, shape);
    if let Some(d) = &input.deposits {
        select_params.radius = d.reach;
        select_params.flags |= EM_SHARE;
    }
    if input.groups.is_some() {
        select_params.flags |= EM_GROUPS;
    }
    let select = ex.uniform("em select params", &select_params)?;
    let bindings = [
        &select,
        input.bin_params,
        input.splats,
        input.materials,
        input.cell_start,
        &fit_list,
        &counters,
        &gather_list,
        fit_groups,
    ];
    ex.dispatch(
        Stage::EmSelect,
        &bindings,
        groups(Stage::EmSelect, splat_count)?,
    )?;
    let (listed, max_candidates, fitted, gathered) = match ex.read::<u32>(&counters, 4)?[..] {
        [a, b, c, d] => (a, b, c, d),
        _ => return Err(Error::Gpu("em counters readback was short".into())),
    };
    let select_ms = ms_since(t);
    // The passes over every splat (deposits, coverage, smoothing) leave the photon fit's lobes
    // as they are.
    let every_splat = cfg.params(splat_count, splat_count, shape);
    match &input.deposits {
        // Every splat's irradiance from the deposits around it, summed once a coverage group,
        // at its leader, then copied to the members.
        Some(d) => {
            let deposits = SharedDeposits {
                deposit_params: d.params,
                bin_params: input.bin_params,
                splats: input.splats,
                materials: input.materials,
                cell_start: input.cell_start,
                keys: d.keys,
                geom: input.geom,
                power: input.power,
                spread: d.spread,
            };
            share_light(
                ex,
                &every_splat,
                &deposits,
                (&light, &counters),
                input.cover.as_ref(),
            )?;
        }
        None => {
            let gather = ex.uniform(
                "em gather params",
                &cfg.params(splat_count, gathered, shape),
            )?;
            let bindings = [
                &gather,
                input.bin_params,
                input.splats,
                &gather_list,
                input.cell_start,
                input.geom,
                input.power,
                &light,
            ];
            ex.dispatch(
                Stage::EmGather,
                &bindings,
                groups(Stage::EmGather, gathered)?,
            )?;
        }
    }
    // A split point of its own, so that the gather's time and the fit's are told apart (one
    // more submission, well under a millisecond); em_share counts the splats it lit that are
    // not fitted.
    let gathered = match (&input.deposits, &ex.read::<u32>(&counters, 4)?[..]) {
        (Some(_), &[.., lit]) => lit,
        _ => gathered,
    };
    let gather_ms = ms_since(t) - select_ms;
    // Lobes for the fitted splats alone, at the slots em_select gave them.
    let lobes = ex.zeroed("lobes", (fitted as u64 * cfg.lobes as u64).max(1) * 32)?;
    let gathering = match (&input.gathering, cfg.gather) {
        (_, 0) => None,
        (Some(g), _) if fitted > 0 => Some(g),
        (Some(_), _) => None,
        (None, _) => {
            return Err(Error::Internal(
                "final gathering needs the scene's lights and geometry".into(),
            ));
        }
    };
    let mut params = cfg.params(splat_count, listed, shape);
    if gathering.is_some() {
        params.flags |= EM_DEFER_FIT;
    }
    let fit_input = EmFitInput {
        input,
        fit_list: &fit_list,
        candidates: [input.geom, input.power],
        lobes: &lobes,
        light: &light,
    };
    // With deposits em_share gave every splat its irradiance; no pass over photons is left.
    let mut dispatches = match input.deposits {
        Some(_) => 0,
        None => em_fit(ex, cfg, shape, &params, max_candidates, &fit_input)?,
    };
    // The photons' estimate where the gather disk leaves the surface, on every path that has
    // the scene's geometry: before final gathering's rays read it, and where no fit follows
    // (an all-diffuse scene fits nothing, yet its edges darkened as the glossy scene's did).
    if input.gathering.is_some() {
        cover_light(ex, &every_splat, &light, input.cover.as_ref())?;
    }
    // The deposits' estimate widened where the light is smooth, before the rays read it.
    let mut smoothed = [0; 4];
    if let (Some(d), true) = (&input.deposits, cfg.smooth > 0.0) {
        let records = Records {
            deposit_params: d.params,
            bin_params: input.bin_params,
            splats: input.splats,
            cell_start: input.cell_start,
            keys: d.keys,
        };
        smoothed = smooth_light(ex, &every_splat, &records, &light, input.cover.as_ref())?;
    }
    ex.read::<u32>(&counters, 1)?;
    let mut fit_ms = ms_since(t) - select_ms - gather_ms;
    let mut final_gather_ms = 0.0;
    let mut direct_bake_ms = 0.0;
    let mut direct = None;
    if let Some(g) = gathering {
        let refit = Refit {
            fit_input,
            counters: &counters,
            listed,
            groups: fit_groups,
        };
        let rays = fit_to_rays(ex, cfg, shape, g, &refit)?;
        let (more, gather_rays_ms, refit_ms) = (rays.dispatches, rays.rays_ms, rays.fit_ms);
        direct = Some(rays.direct);
        direct_bake_ms = rays.direct_ms;
        dispatches += more;
        final_gather_ms = gather_rays_ms;
        fit_ms += refit_ms;
    }
    Ok(Fit {
        lobes,
        light,
        listed,
        gathered,
        fitted,
        max_candidates,
        dispatches,
        select_ms,
        gather_ms,
        fit_ms,
        final_gather_ms,
        direct_bake_ms,
        direct,
        smoothed,
    })
}

/// What `em_share` reads: the binned deposits (their parameters, the bins' parameters, list
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

/// `em_share`: each of `params.splat_count` splats' photon irradiance from the deposits around
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
    for (p, invocations) in group_passes(params, count, EM_SHARE_COPY) {
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
        let groups = groups(Stage::EmShare, invocations)?;
        ex.dispatch(Stage::EmShare, &bindings, groups)?;
    }
    Ok(())
}

/// `em_coverage`: each of `params.splat_count` splats' photon irradiance in `light` divided by
/// the share of its gather disk (radius and slab from `params`) that its surface covers,
/// measured once a group of `cover` (once a splat without); a splat whose lobes the photon fit
/// wrote keeps its light (the lobes carry their own). The executor must trace the scene's
/// geometry.
pub fn cover_light<E: Executor>(
    ex: &mut E,
    params: &EmParams,
    light: &E::Buffer,
    cover: Option<&CoverInput<'_, E::Buffer>>,
) -> Result<()> {
    let mut own = None;
    let (words, count) = group_words(ex, cover, params.splat_count, &mut own)?;
    let shares = ex.zeroed("coverage shares", count.max(1) as u64 * 4)?;
    for (p, invocations) in group_passes(params, count, EM_COVER_APPLY) {
        let uniform = ex.uniform("em coverage params", &p)?;
        let bindings = [&uniform, light, words, &shares];
        let groups = groups(Stage::EmCoverage, invocations)?;
        ex.dispatch_traced(Stage::EmCoverage, &bindings, groups)?;
    }
    Ok(())
}

/// A stage's two passes over coverage groups, each pass's uniform and invocations: the first
/// once a group (`groups` of them, at the leaders, `second` unset), the second once a splat
/// (`second` set).
fn group_passes(params: &EmParams, groups: u32, second: u32) -> [(EmParams, u32); 2] {
    let first = EmParams {
        active_count: groups,
        flags: params.flags & !second,
        ..*params
    };
    let every = EmParams {
        flags: params.flags | second,
        ..*params
    };
    [(first, groups), (every, params.splat_count)]
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

/// `em_smooth` (design §6, "Smoothing"): each splat's photon irradiance, the least noisy of
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
    for (p, invocations) in group_passes(params, count, EM_SMOOTH_APPLY) {
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
        let groups = groups(Stage::EmSmooth, invocations)?;
        ex.dispatch(Stage::EmSmooth, &bindings, groups)?;
    }
    match ex.read::<u32>(&counters, 4)?[..] {
        [a, b, c, d] => Ok([a, b, c, d]),
        _ => Err(Error::Gpu("smoothing counters readback was short".into())),
    }
}

/// What `fit_to_rays` takes of the photon fit: its `em_fit` buffers, its counters (read back
/// to split the passes' times) and the fit list's length.
struct Refit<'a, B> {
    fit_input: EmFitInput<'a, B>,
    counters: &'a B,
    listed: u32,
    /// The shared fits' groups (a word where there are none).
    groups: &'a B,
}

/// What `fit_to_rays` did: the `em_fit` dispatches, the milliseconds of the rays (with the
/// direct bake), of their fit and of the direct bake alone, and the direct bake.
struct Rays<B> {
    dispatches: u32,
    rays_ms: f64,
    fit_ms: f64,
    direct_ms: f64,
    direct: Direct<B>,
}

/// Final gathering and the fit to it (design §6), after the photon fit gave every splat its
/// irradiance: the direct bake, then per batch of the fit list `final_gather` and `em_fit` over
/// its samples.
fn fit_to_rays<E: Executor>(
    ex: &mut E,
    cfg: &EmConfig,
    shape: FitShape,
    g: &Gathering<E::Buffer>,
    refit: &Refit<E::Buffer>,
) -> Result<Rays<E::Buffer>> {
    let (input, light, counters, listed) = (
        refit.fit_input.input,
        refit.fit_input.light,
        refit.counters,
        refit.listed,
    );
    let n = input.splat_count as u64;
    let t = std::time::Instant::now();
    let order = ex.upload("direct order", &crate::grid::splat_order(g.splats))?;
    let direct = bake_direct(ex, g.lights, &order, &g.setup.direct)?;
    // A readback waits for the bake, so that its time is told apart: it grows with every
    // splat, where the rays and their fit grow with the fits.
    ex.read::<u32>(counters, 1)?;
    let direct_ms = ms_since(t);
    // The rays read the photons' irradiance where they meet a splat, also a glossy one that
    // an earlier batch has refitted: a copy keeps the result the same for any batch size.
    let photon_light = ex.zeroed("photon light", n.max(1) * 32)?;
    ex.copy(light, 0, &photon_light, 0, n * 32)?;
    let rays = cfg.gather * cfg.gather;
    let per_entry = rays as u64 * 16;
    let batch = (g.batch_bytes / per_entry).clamp(1, listed.max(1) as u64) as u32;
    let samples = ex.zeroed("gather samples", batch as u64 * per_entry)?;
    ex.read::<u32>(counters, 1)?;
    let mut rays_ms = ms_since(t);
    let mut fit_ms = 0.0;
    let mut dispatches = 0;
    // The samples stand in for the photons' power; their geometry is not read, and one
    // record stands in for it (no pages to bind).
    let no_geometry = ex.zeroed("no photon geometry", 64)?;
    let fit_input = EmFitInput {
        candidates: [&no_geometry, &samples],
        ..refit.fit_input
    };
    for first in (0..listed).step_by(batch as usize) {
        let t = std::time::Instant::now();
        let count = batch.min(listed - first);
        let (group_starts, group_members) = input
            .groups
            .as_ref()
            .map_or((0, 0), |g| (g.starts_at, g.members_at));
        let gather = GatherParams {
            splat_count: count,
            samples: cfg.gather,
            seed: g.setup.seed,
            shadow_bias: g.setup.shadow_bias,
            first,
            light_count: g.setup.direct.light_count,
            group_starts,
            group_members,
        };
        let baked = (&photon_light, &direct.direct);
        final_gather(
            ex,
            &gather,
            (fit_input.fit_list, refit.groups),
            baked,
            &samples,
            (input.materials, g.lights),
        )?;
        ex.read::<u32>(counters, 1)?;
        rays_ms += ms_since(t);
        let t = std::time::Instant::now();
        let params = EmParams {
            gathered: rays,
            inv_area: std::f32::consts::PI / rays as f32,
            list_first: first,
            ..cfg.params(input.splat_count, first + count, shape)
        };
        dispatches += em_fit(ex, cfg, shape, &params, rays, &fit_input)?;
        ex.read::<u32>(counters, 1)?;
        fit_ms += ms_since(t);
    }
    Ok(Rays {
        dispatches,
        rays_ms,
        fit_ms,
        direct_ms,
        direct,
    })
}

/// The buffers of `em_fit`'s dispatches.
struct EmFitInput<'a, B> {
    input: &'a FitInput<'a, B>,
    fit_list: &'a B,
    /// Bound as the binned photons' geometry and power.
    candidates: [&'a B; 2],
    lobes: &'a B,
    light: &'a B,
}

/// `em_fit` over the fit list with the uniform `params`, its iterations split over as many
/// dispatches as `max_candidates` a splat need on this device; returns how many.
fn em_fit<E: Executor>(
    ex: &mut E,
    cfg: &EmConfig,
    shape: FitShape,
    params: &EmParams,
    max_candidates: u32,
    b: &EmFitInput<E::Buffer>,
) -> Result<u32> {
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
    let mut dispatches = 0;
    for (begin, end) in dispatch_ranges(cfg.iterations, chunk) {
        let params = EmParams {
            iteration_begin: begin,
            iteration_end: end,
            ..*params
        };
        let uniform = ex.uniform("em params", &params)?;
        let bindings = [
            &uniform,
            b.input.bin_params,
            b.input.splats,
            b.fit_list,
            b.input.cell_start,
            b.candidates[0],
            b.candidates[1],
            b.lobes,
            b.light,
        ];
        ex.dispatch_variant(
            Stage::EmFit,
            defines,
            &constants,
            &bindings,
            params.active_count,
        )?;
        dispatches += 1;
    }
    Ok(dispatches)
}

/// The photon view of `cam` (`width × height` from `cam.size`): `photon_view` once per photon
/// page (a buffer and its photon count) into fixed-point sums with integer atomics, then
/// `photon_resolve` into an HDR image (`vec4<f32>` per pixel, rows from the top).
pub fn photon_image<E: Executor>(
    ex: &mut E,
    materials: &E::Buffer,
    pages: &[(&E::Buffer, u32)],
    cam: &Camera,
    scale: f32,
) -> Result<E::Buffer> {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let pixels = width * height;
    let sums = ex.zeroed("photon view sums", pixels.max(1) as u64 * 12)?;
    let cam_buf = ex.uniform("camera", cam)?;
    for &(page, count) in pages.iter().filter(|p| p.1 > 0) {
        let params = PhotonViewParams {
            count,
            width,
            height,
            scale,
        };
        let params_buf = ex.uniform("photon view params", &params)?;
        let bindings = [&params_buf, &cam_buf, materials, page, &sums];
        ex.dispatch_traced(
            Stage::PhotonView,
            &bindings,
            groups(Stage::PhotonView, count)?,
        )?;
    }
    let hdr = ex.zeroed("photon view", pixels.max(1) as u64 * 16)?;
    let params = PhotonViewParams {
        count: pixels,
        width,
        height,
        scale,
    };
    let params = ex.uniform("photon resolve params", &params)?;
    let bindings = [&params, &sums, &hdr];
    ex.dispatch(
        Stage::PhotonResolve,
        &bindings,
        groups(Stage::PhotonResolve, pixels)?,
    )?;
    Ok(hdr)
}

const PHOTON_BYTES: u64 = size_of::<Photon>() as u64;

/// One photon store buffer and how many photons it holds.
pub struct Page<B> {
    pub buffer: B,
    pub capacity: u64,
    pub count: u64,
}

/// Stored photons where they were traced: the pages in order, and the pass's figures.
pub struct Traced<B> {
    pub pages: Vec<Page<B>>,
    pub stats: PhotonStats,
}

impl<B> Traced<B> {
    /// All stored photons in host memory, sorted by `Photon::key`.
    pub fn read_back<E: Executor<Buffer = B>>(&self, ex: &mut E) -> Result<PhotonMap> {
        let mut photons = Vec::with_capacity(self.stats.stored as usize);
        for page in &self.pages {
            photons.extend(ex.read::<Photon>(&page.buffer, page.count as usize)?);
        }
        let mut map = PhotonMap {
            photons,
            stats: self.stats.clone(),
        };
        map.sort();
        Ok(map)
    }
}

/// The photon pass: batches of `photon_trace` appending to a store of pages of at most
/// `max_page` photons. Each batch ends in a split point, the counters read back: on overflow
/// (the counter counts every store attempt, so it tells how much room the batch needed) the
/// page grows, or a new page starts at `max_page`, and the batch runs again; nothing is
/// written out of bounds and nothing is dropped. Before each batch the `StorePlanner` makes
/// room for what the batch will likely store, so reruns are rare. `progress` hears (paths
/// done, total).
pub fn trace_photons<E: Executor>(
    ex: &mut E,
    emitters: &[Emitter],
    materials: &E::Buffer,
    cfg: &PhotonConfig,
    max_page: u64,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Traced<E::Buffer>> {
    cfg.validate()?;
    let t = std::time::Instant::now();
    let emitter_buf = ex.upload("emitters", emitters)?;
    let mut planner = StorePlanner::new(max_page, cfg.photons);
    let mut pages = Vec::new();
    let mut page = new_page(ex, first_capacity(cfg, max_page))?;
    let mut stats = PhotonStats::default();
    let mut batch = cfg.batch;
    let mut done = 0u64;
    while done < cfg.photons {
        let paths = (cfg.photons - done).min(batch as u64) as u32;
        let action = planner.before(page.count, page.capacity, paths, done);
        apply(ex, action, &mut pages, &mut page)?;
        let before = page.count as u32;
        let params = ex.uniform("trace params", &cfg.params(emitters, done as u32, paths))?;
        let start = TraceCounters {
            stored: before,
            capacity: page.capacity as u32,
            ..Default::default()
        };
        let counters_buf = ex.upload("trace counters", &[start])?;
        let bindings = [
            &params,
            &emitter_buf,
            materials,
            &page.buffer,
            &counters_buf,
        ];
        ex.dispatch_traced(
            Stage::PhotonTrace,
            &bindings,
            groups(Stage::PhotonTrace, paths)?,
        )?;
        let counters = ex
            .read::<TraceCounters>(&counters_buf, 1)?
            .pop()
            .ok_or_else(|| Error::Gpu("trace counters readback was short".into()))?;
        if counters.overflow == 0 {
            page.count = counters.stored as u64;
            stats.add_batch(paths, before, &counters);
            planner.record(paths, (counters.stored - before) as u64);
            done += paths as u64;
            progress(done, cfg.photons);
            continue;
        }
        stats.reruns += 1;
        let need = (counters.stored - before) as u64;
        match planner.after_overflow(page.count, page.capacity, need, paths, done) {
            StoreAction::HalveBatch if paths > 1 => batch = paths / 2,
            StoreAction::HalveBatch => {
                return Err(Error::DeviceLimit(format!(
                    "one photon path stores more photons than the largest store page holds \
                     ({max_page})"
                )));
            }
            action => apply(ex, action, &mut pages, &mut page)?,
        }
    }
    if page.count > 0 || pages.is_empty() {
        pages.push(page);
    }
    stats.pages = pages.len() as u32;
    stats.trace_ms = ms_since(t);
    Ok(Traced { pages, stats })
}

fn new_page<E: Executor>(ex: &mut E, capacity: u64) -> Result<Page<E::Buffer>> {
    Ok(Page {
        buffer: ex.zeroed("photons", capacity * PHOTON_BYTES)?,
        capacity,
        count: 0,
    })
}

/// Makes the room `action` asks for: a larger page holding the photons so far, or a new one.
fn apply<E: Executor>(
    ex: &mut E,
    action: StoreAction,
    pages: &mut Vec<Page<E::Buffer>>,
    page: &mut Page<E::Buffer>,
) -> Result<()> {
    match action {
        StoreAction::Keep | StoreAction::HalveBatch => {}
        StoreAction::Grow(capacity) => {
            let grown = new_page(ex, capacity)?;
            ex.copy(&page.buffer, 0, &grown.buffer, 0, page.count * PHOTON_BYTES)?;
            *page = Page {
                count: page.count,
                ..grown
            };
        }
        StoreAction::NewPage(capacity) => {
            let full = std::mem::replace(page, new_page(ex, capacity)?);
            pages.push(full);
        }
    }
    Ok(())
}

/// The direct bake where it was made: per splat its shadowed irradiance (`[E, 0]`), and per
/// splat and light the light's visibility (`direct_bake.wgsl`).
pub struct Direct<B> {
    pub direct: B,
    pub visibility: B,
}

impl<B> Direct<B> {
    /// Both in host memory.
    pub fn read_back<E: Executor<Buffer = B>>(
        &self,
        ex: &mut E,
        params: &DirectParams,
    ) -> Result<DirectMap> {
        let n = params.splat_count as usize;
        Ok(DirectMap {
            direct: ex.read(&self.direct, n)?,
            visibility: ex.read(&self.visibility, n * params.light_count as usize)?,
        })
    }
}

/// The direct bake in host memory: per splat `[E, 0]`, its shadowed irradiance from every
/// light, and per splat and light (`splat * lights + light`) the light's visibility.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DirectMap {
    pub direct: Vec<[f32; 4]>,
    pub visibility: Vec<f32>,
}

/// Bakes the direct light of `lights` (`params.light_count` of them) into every splat of the
/// executor's geometry: one `direct_bake` dispatch over the splats, taken in `order`
/// (`grid::splat_order`).
pub fn bake_direct<E: Executor>(
    ex: &mut E,
    lights: &E::Buffer,
    order: &E::Buffer,
    params: &DirectParams,
) -> Result<Direct<E::Buffer>> {
    let n = params.splat_count as u64;
    let direct = ex.zeroed("direct light", n.max(1) * 16)?;
    let visibility = ex.zeroed(
        "light visibility",
        (n * params.light_count as u64).max(1) * 4,
    )?;
    let uniform = ex.uniform("direct params", params)?;
    let bindings = [&uniform, lights, &direct, &visibility, order];
    let groups = groups(Stage::DirectBake, params.splat_count)?;
    ex.dispatch_traced(Stage::DirectBake, &bindings, groups)?;
    Ok(Direct { direct, visibility })
}

/// Final gathering (`final_gather.wgsl`): `samples²` rays from each fitted splat of the fit
/// list `list`'s entries `first..first + splat_count` (`params`) over its hemisphere (with
/// shared fits, from its group's members in turn, as `groups` lists them), with the
/// radiance each brings back from the surfaces' baked light (`light`: their photon irradiance;
/// `direct`: the direct bake), their `materials` and the scene's `lights` (a ray that meets an
/// area light first brings none), into `samples`: `[radiance, direction bits]`, `samples²` an
/// entry from the batch's first.
pub fn final_gather<E: Executor>(
    ex: &mut E,
    params: &GatherParams,
    (list, fit_groups): (&E::Buffer, &E::Buffer),
    (light, direct): (&E::Buffer, &E::Buffer),
    samples: &E::Buffer,
    (materials, lights): (&E::Buffer, &E::Buffer),
) -> Result<()> {
    let per_splat = (params.samples * params.samples) as u64;
    let rays = params.splat_count as u64 * per_splat;
    let count = u32::try_from(rays).map_err(|_| {
        Error::DeviceLimit(format!(
            "final gathering: {rays} rays are more than one dispatch holds"
        ))
    })?;
    let uniform = ex.uniform("gather params", params)?;
    let bindings = [
        &uniform, list, light, direct, samples, materials, lights, fit_groups,
    ];
    ex.dispatch_traced(
        Stage::FinalGather,
        &bindings,
        groups(Stage::FinalGather, count)?,
    )
}

pub use crate::shared::splat::TILE;

/// Each screen tile's splats, in splat-index order, where they were binned.
pub struct TileLists<B> {
    /// The tiling, with the entry count the binning found.
    pub params: TileParams,
    /// `tiles + 1` list starts (the scanned counts).
    pub start: B,
    /// The lists, one after another.
    pub splats: B,
    /// The longest list.
    pub longest: u32,
}

/// Bins the splats into the screen tiles of `cam` (bound as `cam_buf`): `splat_tile_count`,
/// the exclusive scan, then a split point for the entry total (it sizes the lists),
/// `splat_tile_scatter`, and `grid_rank` to put each list in splat-index order.
pub fn bin_splat_tiles<E: Executor>(
    ex: &mut E,
    cam: &Camera,
    cam_buf: &E::Buffer,
    splats: &E::Buffer,
    splat_count: u32,
) -> Result<TileLists<E::Buffer>> {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let mut params = TileParams {
        tiles_x: width.div_ceil(TILE),
        tiles_y: height.div_ceil(TILE),
        splat_count,
        entry_count: 0,
    };
    let tiles = params.tiles_x * params.tiles_y;
    let uniform = ex.uniform("tile params", &params)?;
    let start = ex.zeroed("tile starts", (tiles as u64 + 1) * 4)?;
    let per_splat = groups(Stage::SplatTileCount, splat_count)?;
    ex.dispatch(
        Stage::SplatTileCount,
        &[cam_buf, &uniform, splats, &start],
        per_splat,
    )?;
    exclusive_scan(ex, &start, tiles + 1)?;
    let starts = ex.read::<u32>(&start, tiles as usize + 1)?;
    params.entry_count = starts[tiles as usize];
    let longest = starts.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
    // grid_rank's loop, and the splatter's, walk a whole list per invocation.
    if longest > crate::grid::MAX_CELL_LEN {
        return Err(Error::Invalid(format!(
            "{longest} splats cover one {TILE}×{TILE}-pixel tile (at most {}): the compute \
             splatter cannot draw this view; use --splatter raster",
            crate::grid::MAX_CELL_LEN
        )));
    }
    let entries = params.entry_count.max(1) as u64 * 4;
    let uniform = ex.uniform("tile params", &params)?;
    let cursor = ex.zeroed("tile cursors", tiles.max(1) as u64 * 4)?;
    let scratch_splats = ex.zeroed("tile scratch splats", entries)?;
    let scratch_tiles = ex.zeroed("tile scratch tiles", entries)?;
    let bindings = [
        cam_buf,
        &uniform,
        splats,
        &start,
        &cursor,
        &scratch_splats,
        &scratch_tiles,
    ];
    ex.dispatch(Stage::SplatTileScatter, &bindings, per_splat)?;
    let rank = GridParams {
        entry_count: params.entry_count,
        ..Default::default()
    };
    let rank = ex.uniform("tile rank params", &rank)?;
    let lists = ex.zeroed("tile lists", entries)?;
    let bindings = [&rank, &start, &scratch_splats, &scratch_tiles, &lists];
    let groups = groups(Stage::GridRank, params.entry_count)?;
    ex.dispatch(Stage::GridRank, &bindings, groups)?;
    Ok(TileLists {
        params,
        start,
        splats: lists,
        longest,
    })
}

/// Adds one path-traced sample per pixel (`params.sample`) to the running mean in `hdr`
/// (`path_trace`, one invocation per pixel).
pub fn path_sample<E: Executor>(
    ex: &mut E,
    params: &PathParams,
    cam: &E::Buffer,
    materials: &E::Buffer,
    lights: &E::Buffer,
    hdr: &E::Buffer,
) -> Result<()> {
    let uniform = ex.uniform("path params", params)?;
    let bindings = [&uniform, cam, materials, lights, hdr];
    let pixels = params.width * params.height;
    ex.dispatch_traced(
        Stage::PathTrace,
        &bindings,
        groups(Stage::PathTrace, pixels)?,
    )
}
